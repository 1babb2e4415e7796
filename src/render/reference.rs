//! A reference render with its own error estimate (`vkvcm reference`): two independent
//! halves of equally many iterations, seeds S and S + 1, whose mean is the reference.
//!
//! The error estimate follows the usual split-sample trick: if `a` and `b` are independent
//! unbiased renders with the same variance, `(a - b) / 2` has the variance of `(a + b) / 2`
//! around its expectation, so RMS((a - b) / 2) estimates the RMS error of their average.
//! It sees noise only: a bias both halves share (VCM's merging at finite time, paths
//! neither half can sample) stays invisible.
//!
//! A reference splits into shards like a render (`reference --shard K/N`,
//! docs/distributed.md): shard K renders the same global iterations of both halves, and
//! its file holds both halves' film sums ([`write_shard`]). `vkvcm merge` adds the shards'
//! sums half by half ([`from_merged`]); the reference is a function of the two halves'
//! sums alone ([`HalfSums::reference`]), so the merge writes the bits one machine writes.

use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use anyhow::{anyhow, bail, Result};

use super::converge::warm_renderer;
use super::film::FilmSums;
use super::merge::Merged;
use super::saved::{self, Provenance, ShardOf};
use super::{Algorithm, Budget, Progress, RenderOutput, RenderSettings, Renderer};
use crate::gpu::Gpu;
use crate::image::{compare, Image};
use crate::scene::Scene;

/// A reference image with its own error estimate.
#[derive(Clone, Debug)]
pub struct Reference {
    /// The average of the two halves.
    pub image: Image,
    pub algorithm: Algorithm,
    /// Iterations in all (both halves; each has half).
    pub iterations: u64,
    /// Render seconds in all.
    pub seconds: f64,
    /// Seeds of the two halves.
    pub seeds: [u32; 2],
    /// RMS over pixels and channels of (a - b) / 2: an estimate of the RMS error of `image`.
    pub rmse: f64,
    /// mean(((a - b) / 2)^2 / (image^2 + 1e-2)): the same for the relative MSE
    /// ([`crate::image::REL_MSE_EPSILON`]).
    pub rel_mse: f64,
    /// RMS over pixels and channels of the standard error of the per-pixel mean, from the
    /// per-iteration variance of both halves: a second estimate of the same quantity.
    pub stderr_rms: f64,
    /// Samples rejected as NaN, infinite or negative, both halves.
    pub rejected_samples: u64,
}

/// The settings a reference's EXR records besides estimator and seeds (`vkvcm:KEY`,
/// written as `vkvcm render` writes them: a shard's file holds the same strings).
pub const SETTINGS_KEYS: [&str; 5] = ["max_path_length", "light_selection", "sampler", "radius_factor", "alpha"];

/// [`SETTINGS_KEYS`] of `s`, as `(vkvcm:KEY, value)`.
pub fn settings_metadata(s: &RenderSettings) -> Vec<(String, String)> {
    let values = [
        s.frame.max_path_length.to_string(),
        s.frame.light_selection.name().to_string(),
        s.sampler().name().to_string(),
        s.radius_factor.to_string(),
        s.alpha.to_string(),
    ];
    SETTINGS_KEYS.iter().zip(values).map(|(k, v)| (format!("vkvcm:{k}"), v)).collect()
}

impl Reference {
    /// EXR metadata (`vkvcm:*`) describing the reference and its error estimate;
    /// `settings` is [`settings_metadata`].
    pub fn metadata(&self, scene: &str, settings: &[(String, String)]) -> Vec<(String, String)> {
        let kv = |k: &str, v: String| (format!("vkvcm:{k}"), v);
        let mut meta = vec![
            kv("scene", scene.to_string()),
            kv("estimator", self.algorithm.name().to_string()),
            kv("iterations", self.iterations.to_string()),
            kv("seconds", format!("{:.3}", self.seconds)),
            kv("seed", self.seeds[0].to_string()),
            kv("seed_b", self.seeds[1].to_string()),
        ];
        meta.extend_from_slice(settings);
        meta.extend([
            kv("rejected_samples", self.rejected_samples.to_string()),
            kv("reference_rmse", format!("{:e}", self.rmse)),
            kv("reference_rel_mse", format!("{:e}", self.rel_mse)),
            kv("reference_stderr_rms", format!("{:e}", self.stderr_rms)),
        ]);
        meta
    }
}

/// The seeds of the two halves of a reference of seed `seed`.
pub fn seeds(seed: u32) -> [u32; 2] {
    [seed, seed.wrapping_add(1)]
}

/// The film sums of both halves over the same number of iterations each.
pub struct HalfSums {
    pub width: u32,
    pub height: u32,
    pub a: FilmSums,
    pub b: FilmSums,
    /// Iterations of each half.
    pub per_half: u64,
}

impl HalfSums {
    /// The reference these halves make: a function of the sums and counts alone (the
    /// rest is copied into it), so one machine and a merge of shards give the same bits.
    pub fn reference(&self, algorithm: Algorithm, seeds: [u32; 2], seconds: f64, rejected: u64) -> Result<Reference> {
        let mean = |s: &FilmSums| Image { width: self.width, height: self.height, data: s.mean(self.per_half) };
        let halves = [mean(&self.a), mean(&self.b)];
        let image = Image::average(&halves)?;
        // a - (a + b) / 2 = (a - b) / 2, and `compare` divides by the second image's square.
        let m = compare(&halves[0], &image)?;
        let n = 2.0 * self.per_half as f64;
        let mut acc = 0.0;
        for i in 0..self.a.pixels() {
            for c in 0..3 {
                let s = FilmSums::real(self.a.sum[i][c]) + FilmSums::real(self.b.sum[i][c]);
                let q = FilmSums::real(self.a.sum_sq[i][c]) + FilmSums::real(self.b.sum_sq[i][c]);
                let mean = s / n;
                let var = ((q / n - mean * mean) * n / (n - 1.0).max(1.0)).max(0.0);
                acc += var / n;
            }
        }
        let stderr_rms = (acc / (3 * self.a.pixels()).max(1) as f64).sqrt();
        Ok(Reference {
            image,
            algorithm,
            iterations: 2 * self.per_half,
            seconds,
            seeds,
            rmse: m.rmse,
            rel_mse: m.rel_mse,
            stderr_rms,
            rejected_samples: rejected,
        })
    }
}

/// Both halves as rendered: A with seed `seeds[0]`, B with `seeds[1]`, over the same
/// global iterations.
pub struct Halves {
    pub a: RenderOutput,
    pub b: RenderOutput,
    pub seeds: [u32; 2],
}

impl Halves {
    pub fn into_reference(self, algorithm: Algorithm) -> Result<Reference> {
        let seconds = self.a.seconds + self.b.seconds;
        let rejected = self.a.rejected_samples + self.b.rejected_samples;
        let (width, height, per_half) = (self.a.width, self.a.height, self.a.iterations);
        let sums = HalfSums { width, height, per_half, a: self.a.sums, b: self.b.sums };
        sums.reference(algorithm, self.seeds, seconds, rejected)
    }
}

/// Renders both halves of the reference of `settings` (whose budget is the total: an
/// iteration budget of at least 2, or seconds), or with `shard` (which splits each
/// half's `shard.total` iterations) that shard of both. Half A gets half the budget and
/// half B exactly as many iterations as A got, so their average is the pooled mean.
pub fn render_halves(
    gpu: &Arc<Gpu>,
    scene: &Scene,
    settings: &RenderSettings,
    shard: Option<ShardOf>,
    cancel: Option<&AtomicBool>,
    progress: &mut dyn FnMut(usize, &Progress),
) -> Result<Halves> {
    let (half_budget, first) = match (settings.budget, shard) {
        (Budget::Iterations(_), Some(sh)) => {
            let r = sh.shard.range(sh.total);
            (Budget::Iterations(r.end - r.start), r.start)
        }
        (Budget::Seconds(_), Some(sh)) => bail!("shard {} of a reference needs an iteration budget", sh.shard),
        (Budget::Iterations(n), None) if n < 2 => bail!("a reference needs at least 2 iterations (one per half)"),
        (Budget::Iterations(n), None) => (Budget::Iterations(n / 2), 0),
        (Budget::Seconds(t), None) if !(t > 0.0 && t.is_finite()) => bail!("the reference time must be positive"),
        (Budget::Seconds(t), None) => (Budget::Seconds(t / 2.0), 0),
    };
    let seeds = seeds(settings.frame.seed);
    // A time budget starts warm (the first iteration pays the driver's compilation); an
    // iteration budget renders only its own iterations, whose rejected samples a merge
    // of shards adds up.
    let renderer = |s: &RenderSettings| -> Result<Renderer> {
        let mut r = match half_budget {
            Budget::Seconds(_) => warm_renderer(gpu, scene, s)?,
            Budget::Iterations(_) => Renderer::new(gpu, scene, s)?,
        };
        r.start_at(first);
        Ok(r)
    };
    let mut sa = settings.clone();
    sa.budget = half_budget;
    let mut ra = renderer(&sa)?;
    ra.run(half_budget, cancel, &mut |p| progress(0, p))?;
    let a = ra.output()?;
    drop(ra);
    let mut sb = sa.clone();
    sb.frame.seed = seeds[1];
    sb.budget = Budget::Iterations(a.iterations);
    let mut rb = renderer(&sb)?;
    rb.run(sb.budget, cancel, &mut |p| progress(1, p))?;
    let b = rb.output()?;
    drop(rb);
    if b.held != a.held {
        bail!("reference interrupted: the second half has {} of {} iterations", b.iterations, a.iterations);
    }
    Ok(Halves { a, b, seeds })
}

/// Renders the reference of `settings` on one device ([`render_halves`] without a shard).
pub fn render_reference(
    gpu: &Arc<Gpu>,
    scene: &Scene,
    settings: &RenderSettings,
    cancel: Option<&AtomicBool>,
    progress: &mut dyn FnMut(usize, &Progress),
) -> Result<Reference> {
    render_halves(gpu, scene, settings, None, cancel, progress)?.into_reference(settings.algorithm)
}

/// Writes (atomically) a shard of a reference: a render file of half A (its settings,
/// `vkvcm:seed`, `vkvcm:shard` and `vkvcm:shard_of`, which count each half's iterations)
/// with `vkvcm:seed_b` and half B's sums in the `half_b.` layer; its seconds and
/// rejected samples are both halves'.
pub fn write_shard(path: &Path, h: &Halves, s: &RenderSettings, p: &Provenance) -> Result<()> {
    let mut meta = saved::render_metadata(&h.a, s, p);
    let (a, b) = (&h.a, &h.b);
    let totals = [
        ("seconds", format!("{:.3}", a.seconds + b.seconds)),
        ("rejected_samples", (a.rejected_samples + b.rejected_samples).to_string()),
        ("overflow_splats", (a.overflow_splats + b.overflow_splats).to_string()),
        ("overflow_samples", (a.overflow_samples + b.overflow_samples).to_string()),
    ];
    for (k, v) in totals {
        let key = format!("vkvcm:{k}");
        meta.iter_mut().filter(|(m, _)| *m == key).for_each(|e| e.1 = v.clone());
    }
    meta.push(("vkvcm:seed_b".into(), h.seeds[1].to_string()));
    let half_b = saved::sum_channels(saved::HALF_B_LAYER, &b.sums);
    saved::write_sums_exr(path, a.width, a.height, &a.sums, a.iterations, &meta, half_b)
}

/// The reference of merged reference shards, and its attributes (those `vkvcm reference`
/// writes, and `vkvcm:missing` when shards were missing).
pub fn from_merged(m: Merged) -> Result<(Reference, Vec<(String, String)>)> {
    let get = |k: &str| {
        m.metadata
            .iter()
            .find(|(key, _)| key.strip_prefix("vkvcm:") == Some(k))
            .map(|(_, v)| v.clone())
            .ok_or_else(|| anyhow!("the shards have no vkvcm:{k} attribute"))
    };
    let name = get("estimator")?;
    let algorithm = Algorithm::from_name(&name).ok_or_else(|| anyhow!("unknown estimator {name:?}"))?;
    let seed: u32 = get("seed")?.parse().map_err(|_| anyhow!("malformed vkvcm:seed"))?;
    let settings: Vec<(String, String)> =
        SETTINGS_KEYS.iter().map(|k| Ok((format!("vkvcm:{k}"), get(k)?))).collect::<Result<_>>()?;
    let scene = get("scene")?;
    let (missing, per_half, seconds, rejected) = (m.missing(), m.iterations(), m.seconds, m.rejected.samples);
    let Some(half_b) = m.half_b else { bail!("not the shards of a reference") };
    let seeds = [seed, half_b.seed];
    let sums = HalfSums { width: m.width, height: m.height, a: m.sums, b: half_b.sums, per_half };
    let r = sums.reference(algorithm, seeds, seconds, rejected)?;
    let mut meta = r.metadata(&scene, &settings);
    if !missing.is_empty() {
        meta.push(("vkvcm:missing".into(), missing.to_string()));
    }
    Ok((r, meta))
}
