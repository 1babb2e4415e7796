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
