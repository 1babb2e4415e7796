//! The merge of a split render's shards (`vkvcm merge`, docs/distributed.md): their
//! films' fixed-point sums added, which gives the bits of the whole render on one device
//! (src/render/film.rs), after checking that the files are shards of one render.

use std::path::{Path, PathBuf};

use super::film::{FilmSums, Rejected};
use super::saved::{HalfB, SavedRender};
use super::shard::IterationSet;

/// Attributes that differ between shards of one render; every other `vkvcm:*` attribute
/// must be equal.
const PER_FILE: [&str; 11] = [
    "iterations",
    "iteration_set",
    "seconds",
    "device",
    "rejected_samples",
    "overflow_splats",
    "overflow_samples",
    "shard",
    "reference_rmse",
    "reference_rel_mse",
    "missing",
];

/// Why files were not merged: the message names the file(s).
#[derive(Debug, thiserror::Error)]
#[error("{message}")]
pub struct Refusal {
    /// True when the files are of different scenes (the rest are usage errors).
    pub scene: bool,
    pub message: String,
}

fn refuse(message: String) -> Refusal {
    Refusal { scene: false, message }
}

/// The merged render.
pub struct Merged {
    pub width: u32,
    pub height: u32,
    pub sums: FilmSums,
    /// Shards of a reference (src/render/reference.rs): the second half's sums, of the
    /// same iterations `held`.
    pub half_b: Option<HalfB>,
    pub held: IterationSet,
    /// The split render's iterations.
    pub total: u64,
    pub rejected: Rejected,
    /// The shards' render seconds in all.
    pub seconds: f64,
    /// The attributes to write (those of the shards, with the merged counts).
    pub metadata: Vec<(String, String)>,
}

impl Merged {
    pub fn iterations(&self) -> u64 {
        self.held.len()
    }

    /// The iterations of the split render that no file held.
    pub fn missing(&self) -> IterationSet {
        self.held.missing(self.total)
    }
}

/// Merges `files` (path, contents), refusing files of different renders, a shard given
/// twice, files that are not shards, and (unless `partial`) missing shards or shards
/// that do not hold all their iterations.
pub fn merge(files: &[(PathBuf, SavedRender)], partial: bool) -> std::result::Result<Merged, Refusal> {
    let Some((p0, first)) = files.first() else { return Err(refuse("no files to merge".into())) };
    let shard_of = |p: &PathBuf, s: &SavedRender| {
        if !s.exact {
            return Err(refuse(format!(
                "{}: a float32 film of an older vkvcm, whose sums cannot be merged exactly",
                p.display()
            )));
        }
        s.shard.ok_or_else(|| refuse(format!("{} is not a shard (it was rendered without --shard K/N)", p.display())))
    };
    let sh0 = shard_of(p0, first)?;
    let mut held = IterationSet::new();
    let mut sums = FilmSums::zero(first.sums.pixels());
    let mut half_b = first.half_b.as_ref().map(|h| HalfB { seed: h.seed, sums: FilmSums::zero(h.sums.pixels()) });
    let mut rejected = Rejected::default();
    let mut seconds = 0.0;
    let mut devices: Vec<String> = Vec::new();
    let mut seen: Vec<Option<&PathBuf>> = vec![None; sh0.shard.count as usize];
    for (p, s) in files {
        let sh = shard_of(p, s)?;
        if s.half_b.is_some() != first.half_b.is_some() {
            let kind = |r: &SavedRender| match r.half_b {
                Some(_) => "a reference (`vkvcm reference --shard`, two halves)",
                None => "a render (`vkvcm render --shard`)",
            };
            return Err(refuse(format!(
                "{} is a shard of {}, {} of {}: they cannot be merged",
                p.display(),
                kind(s),
                p0.display(),
                kind(first)
            )));
        }
        check_same(p0, first, p, s)?;
        if sh.shard.count != sh0.shard.count || sh.total != sh0.total {
            return Err(refuse(format!(
                "{} is shard {} of a render of {} iterations, {} shard {} of {}: different shard counts or splits",
                p.display(),
                sh.shard,
                sh.total,
                p0.display(),
                sh0.shard,
                sh0.total
            )));
        }
        let slot = &mut seen[sh.shard.index as usize];
        if let Some(other) = slot {
            return Err(refuse(format!("{} and {} are both shard {}", other.display(), p.display(), sh.shard)));
        }
        *slot = Some(p);
        let range = sh.shard.range(sh.total);
        if s.held != IterationSet::of(range.clone()) && !partial {
            return Err(refuse(format!(
                "{}: shard {} holds iterations {} of its {}-{}: unfinished (use --partial to merge it anyway)",
                p.display(),
                sh.shard,
                s.held,
                range.start,
                range.end - 1
            )));
        }
        held.union(&s.held).map_err(|e| refuse(format!("{}: {e:#} it and an earlier file", p.display())))?;
        sums.add(&s.sums).map_err(|e| refuse(format!("{}: {e:#}", p.display())))?;
        if let (Some(total), Some(b)) = (&mut half_b, &s.half_b) {
            total.sums.add(&b.sums).map_err(|e| refuse(format!("{}: {e:#}", p.display())))?;
        }
        rejected = rejected + s.rejected;
        seconds += s.seconds;
        let device = attribute(s, "device").unwrap_or_default().to_string();
        if !devices.contains(&device) {
            devices.push(device);
        }
    }
    let missing: Vec<String> =
        seen.iter().enumerate().filter(|(_, p)| p.is_none()).map(|(k, _)| format!("{k}/{}", sh0.shard.count)).collect();
    if !missing.is_empty() && !partial {
        return Err(refuse(format!(
            "shard(s) {} of the render of {} are missing (use --partial to merge the others)",
            missing.join(", "),
            p0.display()
        )));
    }
    let merged = Merged {
        width: first.width,
        height: first.height,
        sums,
        half_b,
        total: sh0.total,
        rejected,
        seconds,
        metadata: Vec::new(),
        held,
    };
    let metadata = merged_metadata(first, &merged, &devices);
    Ok(Merged { metadata, ..merged })
}

fn attribute<'a>(s: &'a SavedRender, key: &str) -> Option<&'a str> {
    s.metadata.iter().find(|(k, _)| k.strip_prefix("vkvcm:") == Some(key)).map(|(_, v)| v.as_str())
}

/// Refuses `s` (at `p`) unless it is of the same render as `first` (at `p0`), naming
/// the first attribute that differs.
fn check_same(p0: &Path, first: &SavedRender, p: &Path, s: &SavedRender) -> std::result::Result<(), Refusal> {
    let (a, b) = (p0.display(), p.display());
    for key in ["scene", "scene_fingerprint"] {
        if attribute(first, key) != attribute(s, key) {
            let message = format!(
                "{b} is of another scene than {a} ({key} {} vs {})",
                attribute(s, key).unwrap_or("(none)"),
                attribute(first, key).unwrap_or("(none)")
            );
            return Err(Refusal { scene: true, message });
        }
    }
    if (s.width, s.height) != (first.width, first.height) {
        return Err(refuse(format!("{b} is {}x{}, {a} {}x{}", s.width, s.height, first.width, first.height)));
    }
    if s.algorithm != first.algorithm {
        return Err(refuse(format!(
            "{b} was rendered with --algo {}, {a} with --algo {}",
            s.algorithm, first.algorithm
        )));
    }
    if s.seed != first.seed {
        return Err(refuse(format!("{b} was rendered with --seed {}, {a} with --seed {}", s.seed, first.seed)));
    }
    let shared = |r: &SavedRender| -> Vec<(String, String)> {
        r.metadata
            .iter()
            .filter(|(k, _)| !PER_FILE.iter().any(|p| k.strip_prefix("vkvcm:") == Some(p)))
            .cloned()
            .collect()
    };
    let (x, y) = (shared(first), shared(s));
    let keys: std::collections::BTreeSet<&String> = x.iter().chain(&y).map(|(k, _)| k).collect();
    for k in keys {
        let get = |v: &[(String, String)]| v.iter().find(|(kk, _)| kk == k).map(|(_, v)| v.clone());
        let (va, vb) = (get(&x), get(&y));
        if va != vb {
            let show = |v: Option<String>| v.unwrap_or_else(|| "(absent)".into());
            return Err(refuse(format!(
                "{b} and {a} are not shards of one render: {k} is {} in {b}, {} in {a}",
                show(vb),
                show(va)
            )));
        }
    }
    Ok(())
}

/// The merged file's attributes: the shards' shared ones, and its own counts.
fn merged_metadata(first: &SavedRender, m: &Merged, devices: &[String]) -> Vec<(String, String)> {
    let mut meta: Vec<(String, String)> = first
        .metadata
        .iter()
        .filter(|(k, _)| !PER_FILE.iter().any(|p| k.strip_prefix("vkvcm:") == Some(p)) && k != "vkvcm:shard_of")
        .cloned()
        .collect();
    let kv = |k: &str, v: String| (format!("vkvcm:{k}"), v);
    meta.extend([
        kv("iterations", m.iterations().to_string()),
        kv("iteration_set", m.held.to_string()),
        kv("seconds", format!("{:.3}", m.seconds)),
        kv("device", devices.join(", ")),
        kv("rejected_samples", m.rejected.samples.to_string()),
        kv("overflow_splats", m.rejected.overflow_splats.to_string()),
        kv("overflow_samples", m.rejected.overflow_samples.to_string()),
    ]);
    if !m.missing().is_empty() {
        meta.push(kv("missing", m.missing().to_string()));
    }
    meta
}
