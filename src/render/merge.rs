//! The merge of a split render's shards (`vkvcm merge`, docs/distributed.md): their
//! films' fixed-point sums added, which gives the bits of the whole render on one device
//! (src/render/film.rs), after checking that the files are shards of one render.

use std::path::{Path, PathBuf};

use super::film::{FilmSums, Rejected};
use super::saved::{HalfB, SavedRender, ShardOf};
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
    /// True when the files are a consistent but incomplete set (a partial merge takes them).
    pub incomplete: bool,
    pub message: String,
}

fn refuse(message: String) -> Refusal {
    Refusal { scene: false, incomplete: false, message }
}

fn incomplete(message: String) -> Refusal {
    Refusal { scene: false, incomplete: true, message }
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

/// A merge in progress: shards are added one at a time, so that it holds the running sums
/// and one shard's, however many shards there are.
pub struct Merger {
    p0: PathBuf,
    /// The first file without its sums: what every other file must match.
    first: SavedRender,
    sh0: ShardOf,
    partial: bool,
    sums: FilmSums,
    half_b: Option<HalfB>,
    held: IterationSet,
    rejected: Rejected,
    seconds: f64,
    devices: Vec<String>,
    seen: Vec<Option<PathBuf>>,
}

fn shard_of(p: &Path, s: &SavedRender) -> std::result::Result<ShardOf, Refusal> {
    if !s.exact {
        return Err(refuse(format!(
            "{}: a float32 film of an older vkvcm, whose sums cannot be merged exactly",
            p.display()
        )));
    }
    s.shard.ok_or_else(|| refuse(format!("{} is not a shard (it was rendered without --shard K/N)", p.display())))
}

impl Merger {
    /// A merge that starts with `first` (whose sums it takes over). With `partial`,
    /// missing shards and shards that do not hold all their iterations are merged too.
    pub fn new(p0: PathBuf, mut first: SavedRender, partial: bool) -> std::result::Result<Merger, Refusal> {
        let sh0 = shard_of(&p0, &first)?;
        let empty = || FilmSums::zero(0);
        let sums = std::mem::replace(&mut first.sums, empty());
        let half_b =
            first.half_b.as_mut().map(|h| HalfB { seed: h.seed, sums: std::mem::replace(&mut h.sums, empty()) });
        let mut m = Merger {
            p0: p0.clone(),
            sh0,
            partial,
            sums,
            half_b,
            held: IterationSet::new(),
            rejected: Rejected::default(),
            seconds: 0.0,
            devices: Vec::new(),
            seen: vec![None; sh0.shard.count as usize],
            first: first.clone(),
        };
        m.note(&p0, &first)?;
        Ok(m)
    }

    /// Adds the shard `s` read from `p`, refusing it (naming the file) when it is not a
    /// shard of the same render as the first, is given twice, or is unfinished.
    pub fn add(&mut self, p: &Path, s: &SavedRender) -> std::result::Result<(), Refusal> {
        self.note(p, s)?;
        self.sums.add(&s.sums).map_err(|e| refuse(format!("{}: {e:#}", p.display())))?;
        if let (Some(total), Some(b)) = (&mut self.half_b, &s.half_b) {
            total.sums.add(&b.sums).map_err(|e| refuse(format!("{}: {e:#}", p.display())))?;
        }
        Ok(())
    }

    /// Checks `s` against the first file and counts all of it but its sums.
    fn note(&mut self, p: &Path, s: &SavedRender) -> std::result::Result<(), Refusal> {
        let (p0, first, sh0) = (&self.p0, &self.first, self.sh0);
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
        let slot = &mut self.seen[sh.shard.index as usize];
        if let Some(other) = slot {
            return Err(refuse(format!("{} and {} are both shard {}", other.display(), p.display(), sh.shard)));
        }
        *slot = Some(p.to_path_buf());
        let range = sh.shard.range(sh.total);
        if s.held != IterationSet::of(range.clone()) && !self.partial {
            return Err(incomplete(format!(
                "{}: shard {} holds iterations {} of its {}-{}: unfinished",
                p.display(),
                sh.shard,
                s.held,
                range.start,
                range.end - 1
            )));
        }
        self.held.union(&s.held).map_err(|e| refuse(format!("{}: {e:#} it and an earlier file", p.display())))?;
        self.rejected = self.rejected + s.rejected;
        self.seconds += s.seconds;
        let device = attribute(s, "device").unwrap_or_default().to_string();
        if !self.devices.contains(&device) {
            self.devices.push(device);
        }
        Ok(())
    }

    /// The merged render; refuses (unless partial) when shards are missing.
    pub fn finish(self) -> std::result::Result<Merged, Refusal> {
        let count = self.sh0.shard.count;
        let missing: Vec<String> =
            self.seen.iter().enumerate().filter(|(_, p)| p.is_none()).map(|(k, _)| format!("{k}/{count}")).collect();
        if !missing.is_empty() && !self.partial {
            return Err(incomplete(format!(
                "shard(s) {} of the render of {} are missing",
                missing.join(", "),
                self.p0.display()
            )));
        }
        let merged = Merged {
            width: self.first.width,
            height: self.first.height,
            sums: self.sums,
            half_b: self.half_b,
            total: self.sh0.total,
            rejected: self.rejected,
            seconds: self.seconds,
            metadata: Vec::new(),
            held: self.held,
        };
        let metadata = merged_metadata(&self.first, &merged, &self.devices);
        Ok(Merged { metadata, ..merged })
    }
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
            return Err(Refusal { scene: true, incomplete: false, message });
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
