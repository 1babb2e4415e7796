//! Renders saved as EXR files that can be resumed and merged: the mean in R, G, B, the
//! per-pixel second moment (sum of squares / iterations) in `moment2.R/G/B` (float32, for
//! other tools), the film's exact fixed-point sums as uint32 channels (`film.sum.R.0` ..
//! `film.sum.B.3`, `film.sq.R.0` .. `film.sq.B.3`: word 0 the least significant of each
//! 128-bit sum, src/render/film.rs), and as `vkvcm:*` string attributes every setting that
//! shapes the image, the iterations (`iterations`, and their global indices in
//! `iteration_set`), the seconds, the rejected samples, and a shard's `shard` (K/N) and
//! `shard_of` (the split render's iterations). A shard of a reference
//! (src/render/reference.rs) adds `seed_b` and its second half's sums in the `half_b.` layer.
//!
//! The sums are stored exactly, so a resumed render or a merge of shards is bit for bit
//! the uninterrupted render (tests/render_resume.rs, tests/shards.rs). Files of the
//! float32 film (`vkvcm-render-1`) are still resumed, from their float32 moments: that
//! resumption is close (2^-24 relative), not exact.

use std::path::Path;

use anyhow::{anyhow, bail, Result};

use super::film::{FilmSums, Rejected};
use super::output::RenderOutput;
use super::settings::{Algorithm, RenderSettings};
use super::shard::{IterationSet, Shard};
use crate::image::{self, ExrCompression, Image, Samples};
use crate::scene::Scene;

/// Names of the second-moment channels, for R, G, B.
pub const MOMENT2_CHANNELS: [&str; 3] = ["moment2.R", "moment2.G", "moment2.B"];
/// Value of `vkvcm:format` in resumable files.
pub const FORMAT: &str = "vkvcm-render-2";
/// The format of the float32 film, still resumed (not merged).
const FORMAT_FLOAT_FILM: &str = "vkvcm-render-1";

/// The layer of a reference shard's second half (`half_b.film.sum.R.0`, ...:
/// src/render/reference.rs); the film of an ordinary render is in no layer (`""`).
pub const HALF_B_LAYER: &str = "half_b.";

/// The uint32 channel of word `w` (0: least significant) of channel `c` (0..3: R, G, B)
/// of the film's sums (`square`: of the sums of squares) in `layer`.
pub fn sum_channel(layer: &str, square: bool, c: usize, w: usize) -> String {
    format!("{layer}film.{}.{}.{w}", if square { "sq" } else { "sum" }, ["R", "G", "B"][c])
}

/// The uint32 channels of `sums`' words in `layer`.
pub fn sum_channels(layer: &str, sums: &FilmSums) -> Vec<image::ExtraChannel> {
    let mut channels = Vec::with_capacity(24);
    for (square, sums) in [(false, &sums.sum), (true, &sums.sum_sq)] {
        for c in 0..3 {
            for w in 0..4 {
                let words = sums.iter().map(|p| FilmSums::words(p[c])[w]).collect();
                channels.push((sum_channel(layer, square, c, w), Samples::U32(words)));
            }
        }
    }
    channels
}

/// Which shard of which render a file holds (`--shard`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ShardOf {
    pub shard: Shard,
    /// The iterations of the whole render that is split.
    pub total: u64,
}

/// Where a render came from, besides its settings.
#[derive(Clone, Debug)]
pub struct Provenance {
    /// `Scene::name`.
    pub scene: String,
    /// The camera asked for (`--camera`), or `"default"`.
    pub camera: String,
    /// The device's name (informational; a render may resume on another device).
    pub device: String,
    /// [`Scene::fingerprint`]: a resumed render must have the same.
    pub scene_fingerprint: String,
    /// `--shard`: which part of which render this is.
    pub shard: Option<ShardOf>,
}

impl Provenance {
    pub fn new(scene: &Scene, camera: &str, device: &str) -> Provenance {
        Provenance {
            scene: scene.name.clone(),
            camera: camera.to_string(),
            device: device.to_string(),
            scene_fingerprint: scene.fingerprint(),
            shard: None,
        }
    }
}

/// A render read back from an EXR written by [`write_render_exr`].
#[derive(Clone, Debug)]
pub struct SavedRender {
    pub scene: String,
    /// [`Scene::fingerprint`]; `None` in files written before it was recorded.
    pub scene_fingerprint: Option<String>,
    pub camera: String,
    pub algorithm: String,
    pub seed: u32,
    pub width: u32,
    pub height: u32,
    pub max_path_length: u32,
    pub min_path_length: u32,
    /// `LightSelection::name` (renders saved before the option: "uniform").
    pub light_selection: String,
    pub nee: bool,
    /// `Sampler::name` (renders saved before the option: "independent").
    pub sampler: String,
    pub radius_factor: f32,
    pub alpha: f32,
    /// bpt, vcm: `Connect::name` (renders saved before the option: "path").
    pub connect: String,
    /// Light subpaths per iteration (renders saved before the option: one per pixel).
    pub light_paths: u32,
    pub iterations: u64,
    /// The global indices of its iterations (`0..iterations` in files without them).
    pub held: IterationSet,
    /// `--shard` renders: which shard of which render.
    pub shard: Option<ShardOf>,
    pub seconds: f64,
    pub rejected: Rejected,
    /// The film's sums.
    pub sums: FilmSums,
    /// A shard of a reference (`reference --shard`): its second half, of the same
    /// iterations (`held`) as the film above, which is the first.
    pub half_b: Option<HalfB>,
    /// False for files of the float32 film, whose sums are rounded: resumed, never merged.
    pub exact: bool,
    /// Every `vkvcm:*` attribute, for merges to compare.
    pub metadata: Vec<(String, String)>,
}

/// The second half of a reference shard (src/render/reference.rs).
#[derive(Clone, Debug)]
pub struct HalfB {
    /// `vkvcm:seed_b`.
    pub seed: u32,
    pub sums: FilmSums,
}

/// The `vkvcm:*` attributes of a render.
pub fn render_metadata(out: &RenderOutput, s: &RenderSettings, p: &Provenance) -> Vec<(String, String)> {
    let kv = |k: &str, v: String| (format!("vkvcm:{k}"), v);
    let mut meta = vec![
        kv("format", FORMAT.to_string()),
        kv("scene", p.scene.clone()),
        kv("scene_fingerprint", p.scene_fingerprint.clone()),
        kv("camera", p.camera.clone()),
        kv("estimator", s.algorithm.name().to_string()),
        kv("iterations", out.iterations.to_string()),
        kv("iteration_set", out.held.to_string()),
        kv("seconds", format!("{:.3}", out.seconds)),
        kv("seed", s.frame.seed.to_string()),
        kv("max_path_length", s.frame.max_path_length.to_string()),
        kv("min_path_length", s.frame.min_path_length.to_string()),
        kv("light_selection", s.frame.light_selection.name().to_string()),
        kv("nee", s.nee.to_string()),
        kv("sampler", s.sampler().name().to_string()),
        // Rust prints the shortest string that parses back to the same f32.
        kv("radius_factor", s.radius_factor.to_string()),
        kv("alpha", s.alpha.to_string()),
        kv("connect", s.connect.name()),
        kv("light_paths", s.light_paths().to_string()),
        kv("device", p.device.clone()),
        kv("rejected_samples", out.rejected_samples.to_string()),
        kv("overflow_splats", out.overflow_splats.to_string()),
        kv("overflow_samples", out.overflow_samples.to_string()),
    ];
    if let Some(sh) = p.shard {
        meta.push(kv("shard", sh.shard.to_string()));
        meta.push(kv("shard_of", sh.total.to_string()));
    }
    meta
}

/// Writes `out` (atomically) with everything [`read_render_exr`] needs to resume it.
pub fn write_render_exr(path: &Path, out: &RenderOutput, s: &RenderSettings, p: &Provenance) -> Result<()> {
    write_render_exr_with(path, out, s, p, &[])
}

/// [`write_render_exr`] with more attributes (`render --reference`'s errors).
pub fn write_render_exr_with(
    path: &Path,
    out: &RenderOutput,
    s: &RenderSettings,
    p: &Provenance,
    more: &[(String, String)],
) -> Result<()> {
    let mut meta = render_metadata(out, s, p);
    if s.aov.any() {
        meta.push(("vkvcm:aov".into(), s.aov.names()));
    }
    meta.extend_from_slice(more);
    let aovs = out.aov.iter().flat_map(|a| a.channels()).collect();
    write_sums_exr(path, out.width, out.height, &out.sums, out.iterations, &meta, aovs)
}

/// Writes (atomically) a render of `iterations` iterations from its film's sums: the mean
/// and second moment computed from them on the host, the sums' words, and `meta`. The
/// channels are a function of the sums and the count alone: merged shards and one render
/// give the same bits. `more_channels` (the AOV layers) are written beside them.
pub fn write_sums_exr(
    path: &Path,
    width: u32,
    height: u32,
    sums: &FilmSums,
    iterations: u64,
    meta: &[(String, String)],
    more_channels: Vec<image::ExtraChannel>,
) -> Result<()> {
    let img = Image { width, height, data: sums.mean(iterations) };
    let k = 1.0 / iterations.max(1) as f64;
    let mut extra: Vec<image::ExtraChannel> = MOMENT2_CHANNELS
        .iter()
        .enumerate()
        .map(|(c, name)| {
            (name.to_string(), Samples::F32(sums.sum_sq.iter().map(|q| (FilmSums::real(q[c]) * k) as f32).collect()))
        })
        .chain(more_channels)
        .collect();
    extra.extend(sum_channels("", sums));
    image::write_exr_channels(path, &img, &extra, meta, ExrCompression::Zip)
}

/// The film's sums from a file's channels: exactly from the uint32 words in `layer`
/// (format 2), or rounded from the float32 mean and second moment (format 1). Errors name
/// what is missing.
fn saved_sums(
    shown: &std::path::Display,
    layer: &str,
    img: &Image,
    extra: &[image::ExtraChannel],
    exact: bool,
    iterations: u64,
) -> Result<FilmSums> {
    let channel = |name: &str| -> Result<&Samples> {
        extra.iter().find(|(n, _)| n == name).map(|(_, d)| d).ok_or_else(|| {
            anyhow!("{shown} has no {name} channel: truncated, or not a render that vkvcm can resume or merge")
        })
    };
    let n = img.data.len();
    let mut sums = FilmSums::zero(n);
    if exact {
        for (square, out) in [(false, &mut sums.sum), (true, &mut sums.sum_sq)] {
            for c in 0..3 {
                for w in 0..4 {
                    let name = sum_channel(layer, square, c, w);
                    let Samples::U32(words) = channel(&name)? else {
                        bail!("{shown}: channel {name} is not uint32");
                    };
                    for (p, &x) in out.iter_mut().zip(words) {
                        p[c] |= (x as u128) << (32 * w);
                    }
                }
            }
        }
        return Ok(sums);
    }
    let m2: Vec<Vec<f32>> =
        MOMENT2_CHANNELS.iter().map(|name| channel(name).map(Samples::to_f32)).collect::<Result<_>>()?;
    let k = iterations as f64;
    for (i, p) in img.data.iter().enumerate() {
        sums.sum[i] = p.map(|v| FilmSums::fixed(v as f64 * k));
        sums.sum_sq[i] = [0, 1, 2].map(|c| FilmSums::fixed(m2[c][i] as f64 * k));
    }
    Ok(sums)
}

/// Reads a render written by [`write_render_exr`]. Errors name the file and what is
/// missing or malformed.
pub fn read_render_exr(path: &Path) -> Result<SavedRender> {
    let shown = path.display();
    let (img, extra, meta) = image::read_exr_channels(path)?;
    let get = |key: &str| -> Result<&str> {
        meta.iter()
            .find(|(k, _)| k.strip_prefix("vkvcm:") == Some(key))
            .map(|(_, v)| v.as_str())
            .ok_or_else(|| anyhow!("{shown} has no vkvcm:{key} attribute: not a resumable vkvcm render"))
    };
    fn parse<T: std::str::FromStr>(shown: &std::path::Display, key: &str, v: &str) -> Result<T> {
        v.trim().parse().map_err(|_| anyhow!("{shown}: attribute vkvcm:{key} = {v:?} is malformed"))
    }
    let format = get("format")?;
    if format != FORMAT && format != FORMAT_FLOAT_FILM {
        bail!("{shown}: vkvcm:format is {format:?}, this version reads {FORMAT:?}");
    }
    let exact = format == FORMAT;
    let iterations: u64 = parse(&shown, "iterations", get("iterations")?)?;
    if iterations == 0 {
        bail!("{shown}: vkvcm:iterations is 0, nothing to resume");
    }
    let held = match get("iteration_set") {
        Ok(v) => IterationSet::parse(v).map_err(|e| anyhow!("{shown}: vkvcm:iteration_set: {e}"))?,
        Err(_) => IterationSet::of(0..iterations),
    };
    if held.len() != iterations {
        bail!(
            "{shown}: vkvcm:iteration_set {held} holds {} iterations, vkvcm:iterations says {iterations}",
            held.len()
        );
    }
    let shard = match get("shard") {
        Ok(v) => Some(ShardOf {
            shard: Shard::parse(v).map_err(|e| anyhow!("{shown}: vkvcm:shard: {e}"))?,
            total: parse(&shown, "shard_of", get("shard_of")?)?,
        }),
        Err(_) => None,
    };
    let sums = saved_sums(&shown, "", &img, &extra, exact, iterations)?;
    let half_b = match get("seed_b") {
        Ok(v) if exact => Some(HalfB {
            seed: parse(&shown, "seed_b", v)?,
            sums: saved_sums(&shown, HALF_B_LAYER, &img, &extra, exact, iterations)?,
        }),
        _ => None,
    };
    let seconds: f64 = parse(&shown, "seconds", get("seconds")?)?;
    let rejected = Rejected {
        samples: parse(&shown, "rejected_samples", get("rejected_samples")?)?,
        overflow_splats: parse(&shown, "overflow_splats", get("overflow_splats")?)?,
        overflow_samples: match get("overflow_samples") {
            Ok(v) => parse(&shown, "overflow_samples", v)?,
            Err(_) => 0,
        },
    };
    Ok(SavedRender {
        scene: get("scene")?.to_string(),
        scene_fingerprint: get("scene_fingerprint").ok().map(str::to_string),
        camera: get("camera")?.to_string(),
        algorithm: get("estimator")?.to_string(),
        seed: parse(&shown, "seed", get("seed")?)?,
        width: img.width,
        height: img.height,
        max_path_length: parse(&shown, "max_path_length", get("max_path_length")?)?,
        min_path_length: parse(&shown, "min_path_length", get("min_path_length")?)?,
        // Renders saved before --light-selection existed picked lights uniformly.
        light_selection: get("light_selection").unwrap_or("uniform").to_string(),
        nee: parse(&shown, "nee", get("nee")?)?,
        // Renders saved before --sampler existed drew independent random numbers.
        sampler: get("sampler").unwrap_or("independent").to_string(),
        radius_factor: parse(&shown, "radius_factor", get("radius_factor")?)?,
        alpha: parse(&shown, "alpha", get("alpha")?)?,
        // Renders saved before --connect existed connected to the matching light subpath.
        connect: get("connect").unwrap_or("path").to_string(),
        // Renders saved before --light-paths existed traced one light subpath per pixel.
        light_paths: match get("light_paths") {
            Ok(v) => parse(&shown, "light_paths", v)?,
            Err(_) => img.width.saturating_mul(img.height),
        },
        iterations,
        held,
        shard,
        seconds: if seconds.is_finite() && seconds >= 0.0 { seconds } else { 0.0 },
        rejected,
        sums,
        half_b,
        exact,
        metadata: meta.iter().filter(|(k, _)| k.starts_with("vkvcm:")).cloned().collect(),
    })
}

impl SavedRender {
    /// Fails, naming the first setting that differs (as the command-line option), unless
    /// continuing this render with `s` for the scene and camera of `p` reproduces an
    /// uninterrupted render.
    pub fn check_matches(&self, s: &RenderSettings, p: &Provenance) -> Result<()> {
        let diff = |what: &str, saved: String, now: String| -> Result<()> {
            if saved != now {
                bail!("it was rendered with {what} {saved}, this run asks for {what} {now}");
            }
            Ok(())
        };
        if self.half_b.is_some() {
            bail!("it is a shard of a reference (two halves, `vkvcm reference --shard`), not of a render");
        }
        diff("scene", self.scene.clone(), p.scene.clone())?;
        if let Some(f) = &self.scene_fingerprint {
            if *f != p.scene_fingerprint {
                bail!(
                    "scene {} has changed since it was rendered (scene fingerprint {f}, now {})",
                    p.scene,
                    p.scene_fingerprint
                );
            }
        }
        diff("--camera", self.camera.clone(), p.camera.clone())?;
        diff("--algo", self.algorithm.clone(), s.algorithm.name().to_string())?;
        diff("--width", self.width.to_string(), s.frame.width.to_string())?;
        diff("--height", self.height.to_string(), s.frame.height.to_string())?;
        diff("--seed", self.seed.to_string(), s.frame.seed.to_string())?;
        diff("--max-path-length", self.max_path_length.to_string(), s.frame.max_path_length.to_string())?;
        diff("min path length", self.min_path_length.to_string(), s.frame.min_path_length.to_string())?;
        diff("--light-selection", self.light_selection.clone(), s.frame.light_selection.name().to_string())?;
        diff("next-event estimation", self.nee.to_string(), s.nee.to_string())?;
        diff("--sampler", self.sampler.clone(), s.sampler().name().to_string())?;
        diff("--radius-factor", self.radius_factor.to_string(), s.radius_factor.to_string())?;
        diff("--alpha", self.alpha.to_string(), s.alpha.to_string())?;
        diff("--connect", self.connect.clone(), s.connect.name())?;
        diff("--light-paths", self.light_paths.to_string(), s.light_paths().to_string())?;
        let shard = |sh: Option<ShardOf>| sh.map_or("(none)".to_string(), |x| format!("{} of {}", x.shard, x.total));
        diff("--shard", shard(self.shard), shard(p.shard))?;
        // A render continues after its last iteration: the film must hold every one
        // before it (a partial merge does not).
        let first = p.shard.map_or(0, |x| x.shard.range(x.total).start);
        if self.held != IterationSet::of(first..self.held.end()) {
            bail!("it holds iterations {} with gaps (a partial merge?): it cannot be continued", self.held);
        }
        if !self.exact && self.shard.is_some() {
            bail!("it holds a float32 film of an older vkvcm");
        }
        Ok(())
    }

    /// The estimator, if it is one this version knows.
    pub fn algorithm(&self) -> Option<Algorithm> {
        <Algorithm as clap::ValueEnum>::from_str(&self.algorithm, true).ok()
    }
}
