//! Renders saved as EXR files that can be resumed: the mean in R, G, B, the per-pixel
//! second moment (sum of squares / iterations) in `moment2.R/G/B`, and as `vkvcm:*` string
//! attributes every setting that shapes the image plus the iteration count and seconds.
//!
//! Precision: both are stored as float32. The film itself keeps float32 Kahan sums, and
//! the mean and second moment are the sums divided by the iteration count, so storing
//! them rounds each value once more by at most 2^-24 relative (6e-8): a resumed render
//! differs from an uninterrupted one by about that much (tests/render_resume.rs), far
//! below any Monte Carlo noise. The variance M2 - mean^2 loses precision where it is tiny
//! next to mean^2, as it already does in the float32 film.

use std::path::Path;

use anyhow::{anyhow, bail, Result};

use super::output::RenderOutput;
use super::settings::{Algorithm, RenderSettings};
use crate::image::{self, ExrCompression, Image};
use crate::scene::Scene;

/// Names of the second-moment channels, for R, G, B.
pub const MOMENT2_CHANNELS: [&str; 3] = ["moment2.R", "moment2.G", "moment2.B"];
/// Value of `vkvcm:format` in resumable files.
pub const FORMAT: &str = "vkvcm-render-1";

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
}

impl Provenance {
    pub fn new(scene: &Scene, camera: &str, device: &str) -> Provenance {
        Provenance {
            scene: scene.name.clone(),
            camera: camera.to_string(),
            device: device.to_string(),
            scene_fingerprint: scene.fingerprint(),
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
    pub seconds: f64,
    pub rejected_samples: u64,
    pub overflow_splats: u64,
    /// Per-pixel sums of the iterations' values and of their squares.
    pub sum: Vec<[f64; 3]>,
    pub sum_sq: Vec<[f64; 3]>,
}

/// The `vkvcm:*` attributes of a render.
pub fn render_metadata(out: &RenderOutput, s: &RenderSettings, p: &Provenance) -> Vec<(String, String)> {
    let kv = |k: &str, v: String| (format!("vkvcm:{k}"), v);
    vec![
        kv("format", FORMAT.to_string()),
        kv("scene", p.scene.clone()),
        kv("scene_fingerprint", p.scene_fingerprint.clone()),
        kv("camera", p.camera.clone()),
        kv("estimator", s.algorithm.name().to_string()),
        kv("iterations", out.iterations.to_string()),
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
    ]
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
    let img = Image { width: out.width, height: out.height, data: out.pixels.clone() };
    let k = 1.0 / out.iterations.max(1) as f64;
    let extra: Vec<image::ExtraChannel> = MOMENT2_CHANNELS
        .iter()
        .enumerate()
        .map(|(c, name)| (name.to_string(), out.sum_sq.iter().map(|q| (q[c] * k) as f32).collect()))
        .chain(out.aov.iter().flat_map(|a| a.channels()))
        .collect();
    image::write_exr_channels(path, &img, &extra, &meta, ExrCompression::Zip)
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
    if format != FORMAT {
        bail!("{shown}: vkvcm:format is {format:?}, this version resumes {FORMAT:?}");
    }
    let mut m2 = Vec::new();
    for name in MOMENT2_CHANNELS {
        match extra.iter().find(|(n, _)| n == name) {
            Some((_, d)) => m2.push(d),
            None => bail!("{shown} has no {name} channel: cannot resume it"),
        }
    }
    let iterations: u64 = parse(&shown, "iterations", get("iterations")?)?;
    if iterations == 0 {
        bail!("{shown}: vkvcm:iterations is 0, nothing to resume");
    }
    let n = iterations as f64;
    let sum = img.data.iter().map(|p| p.map(|v| v as f64 * n)).collect();
    let sum_sq = (0..img.data.len()).map(|i| [0, 1, 2].map(|c| m2[c][i] as f64 * n)).collect();
    let seconds: f64 = parse(&shown, "seconds", get("seconds")?)?;
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
        seconds: if seconds.is_finite() && seconds >= 0.0 { seconds } else { 0.0 },
        rejected_samples: parse(&shown, "rejected_samples", get("rejected_samples")?)?,
        overflow_splats: parse(&shown, "overflow_splats", get("overflow_splats")?)?,
        sum,
        sum_sq,
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
        Ok(())
    }

    /// The estimator, if it is one this version knows.
    pub fn algorithm(&self) -> Option<Algorithm> {
        <Algorithm as clap::ValueEnum>::from_str(&self.algorithm, true).ok()
    }
}
