//! `vkvcm bench render`: a fixed suite (scenes x estimators, fixed iterations) measuring
//! samples per wall second and per CPU-second of the whole process (user + sys from
//! getrusage; on lavapipe the GPU work is CPU work of this process), and GPU
//! time per kernel stage. The first iteration of each render is not timed (it pays the
//! driver's shader compilation).

use std::sync::Arc;
use std::time::Instant;

use anyhow::Result;
use serde::Serialize;

use super::{render, Algorithm, Budget, RenderSettings};
use crate::gpu::{Gpu, KernelTime};
use crate::scene::Scene;

#[derive(Clone, Debug, Serialize)]
pub struct BenchRow {
    pub scene: String,
    pub algorithm: String,
    pub width: u32,
    pub height: u32,
    pub iterations: u64,
    pub wall_seconds: f64,
    /// CPU-seconds (user + sys) of this process during the timed render, if known.
    pub cpu_seconds: Option<f64>,
    pub samples_per_second: f64,
    pub samples_per_cpu_second: Option<f64>,
    /// GPU time per kernel over the timed iterations.
    pub kernels: Vec<KernelTime>,
}

/// User + system CPU time of this process in seconds (getrusage), `None` if unavailable.
pub fn process_cpu_seconds() -> Option<f64> {
    // SAFETY: rusage is plain old data; all-zero is a valid value.
    let mut u: libc::rusage = unsafe { std::mem::zeroed() };
    // SAFETY: `u` is a valid rusage to fill.
    if unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut u) } != 0 {
        return None;
    }
    let t = |tv: libc::timeval| tv.tv_sec as f64 + tv.tv_usec as f64 * 1e-6;
    Some(t(u.ru_utime) + t(u.ru_stime))
}

/// Renders `scene` with `algo` for 1 warm-up iteration, then `iterations` timed ones.
pub fn bench_one(
    gpu: &Arc<Gpu>,
    scene: &Scene,
    algo: Algorithm,
    width: u32,
    height: u32,
    iterations: u64,
) -> Result<BenchRow> {
    let warm = RenderSettings::new(algo, width, height, Budget::Iterations(1));
    render(gpu, scene, &warm, None, &mut |_| {})?;
    let s = RenderSettings::new(algo, width, height, Budget::Iterations(iterations));
    let cpu0 = process_cpu_seconds();
    let t0 = Instant::now();
    let out = render(gpu, scene, &s, None, &mut |_| {})?;
    let wall = t0.elapsed().as_secs_f64();
    let cpu = match (cpu0, process_cpu_seconds()) {
        (Some(a), Some(b)) => Some(b - a),
        _ => None,
    };
    let samples = (width as u64 * height as u64 * out.iterations) as f64;
    Ok(BenchRow {
        scene: scene.name.clone(),
        algorithm: algo.name().to_string(),
        width,
        height,
        iterations: out.iterations,
        wall_seconds: wall,
        cpu_seconds: cpu,
        samples_per_second: samples / wall,
        samples_per_cpu_second: cpu.filter(|&c| c > 0.0).map(|c| samples / c),
        kernels: out.profile.kernels,
    })
}

/// A markdown table of the rows.
pub fn table(rows: &[BenchRow]) -> String {
    let mut s = String::from(
        "| scene | algo | size | iterations | wall s | CPU s | samples/s | samples/CPU-s | GPU ms per iteration by kernel |\n|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let kernels: Vec<String> =
            r.kernels.iter().map(|k| format!("{} {:.2}", k.kernel, k.total_ms / r.iterations.max(1) as f64)).collect();
        s += &format!(
            "| {} | {} | {}x{} | {} | {:.2} | {} | {:.0} | {} | {} |\n",
            r.scene,
            r.algorithm,
            r.width,
            r.height,
            r.iterations,
            r.wall_seconds,
            r.cpu_seconds.map(|c| format!("{c:.2}")).unwrap_or_else(|| "-".into()),
            r.samples_per_second,
            r.samples_per_cpu_second.map(|c| format!("{c:.0}")).unwrap_or_else(|| "-".into()),
            kernels.join(", ")
        );
    }
    s
}

/// One estimator's error after a fixed wall-clock budget.
#[derive(Clone, Debug, Serialize)]
pub struct EqualTimeRow {
    pub scene: String,
    pub algorithm: String,
    pub seconds: f64,
    pub iterations: u64,
    pub rmse: f64,
    pub rel_mse: f64,
    pub mean_abs_bias: f64,
}

/// A long render used as the reference, with an estimate of its own remaining noise:
/// the RMS over pixels and channels of the standard error of its per-pixel mean.
pub struct Reference {
    pub image: crate::image::Image,
    pub algorithm: Algorithm,
    pub iterations: u64,
    pub noise_rms: f64,
}

/// `iterations` in all, in two independent halves ([`super::converge::render_reference`]).
pub fn reference(gpu: &Arc<Gpu>, scene: &Scene, algo: Algorithm, size: u32, iterations: u64) -> Result<Reference> {
    let s = RenderSettings::new(algo, size, size, Budget::Iterations(iterations));
    let r = super::converge::render_reference(gpu, scene, &s, None, &mut |_, _| {})?;
    Ok(Reference { image: r.image, algorithm: algo, iterations: r.iterations, noise_rms: r.stderr_rms })
}

/// Renders with `algo` for `seconds` of render time (its first iteration, which pays the
/// driver's compilation, is discarded) and measures the error against the reference.
pub fn equal_time(
    gpu: &Arc<Gpu>,
    scene: &Scene,
    algo: Algorithm,
    seconds: f64,
    reference: &Reference,
) -> Result<EqualTimeRow> {
    let (w, h) = (reference.image.width, reference.image.height);
    let mut s = RenderSettings::new(algo, w, h, Budget::Seconds(seconds));
    // A different seed from the reference's, so the errors are independent.
    s.frame.seed = 4321;
    let target = super::converge::Target {
        image: &reference.image,
        error: super::converge::ReferenceError { rmse: Some(reference.noise_rms), rel_mse: None },
    };
    let rows = super::converge::converge_one(gpu, scene, &s, &target, &[seconds], None, &mut |_| {})?;
    let row = rows.last().ok_or_else(|| anyhow::anyhow!("equal-time render of {} measured nothing", algo.name()))?;
    Ok(EqualTimeRow {
        scene: scene.name.clone(),
        algorithm: algo.name().to_string(),
        seconds: row.seconds,
        iterations: row.iterations,
        rmse: row.rmse,
        rel_mse: row.rel_mse,
        mean_abs_bias: row.mean_abs_bias,
    })
}

/// A markdown table of equal-time rows.
pub fn equal_time_table(rows: &[EqualTimeRow]) -> String {
    let mut s = String::from(
        "| scene | algo | seconds | iterations | RMSE | relMSE | mean bias |\n|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        s += &format!(
            "| {} | {} | {:.1} | {} | {:.5} | {:.5} | {:.5} |\n",
            r.scene, r.algorithm, r.seconds, r.iterations, r.rmse, r.rel_mse, r.mean_abs_bias
        );
    }
    s
}
