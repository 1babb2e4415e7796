//! `vkvcm-bench render`: a fixed suite (scenes x estimators, fixed iterations) measuring
//! samples per wall second and per CPU-second of the whole process (user + sys from
//! getrusage; on lavapipe the GPU work is CPU work of this process), and GPU
//! time per kernel stage. Each row first renders one untimed warm-up iteration (it pays
//! the driver's shader compilation), then times only the iterations of its render: not
//! the render's set-up (the scene's upload and BVH build, the kernels' creation).

use std::sync::Arc;
use std::time::Instant;

use anyhow::Result;
use serde::Serialize;

use vkvcm::gpu::{Gpu, KernelTime};
use vkvcm::render::converge::Variant;
use vkvcm::render::{render, Algorithm, Budget, RenderSettings, Renderer};
use vkvcm::scene::Scene;

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
    /// Paths per kernel invocation (path regeneration, src/render/regen.rs).
    pub paths_per_invocation: u32,
    /// How the kernels read their read-only buffers (src/render/reads.rs).
    pub reads: String,
    /// GPU time per kernel over the timed iterations.
    pub kernels: Vec<KernelTime>,
    /// Runs this row summarises ([`median_of_rounds`]; 1 for a single run).
    pub rounds: u32,
    /// Smallest and largest samples per CPU-second over those runs.
    pub samples_per_cpu_second_range: Option<[f64; 2]>,
}

/// Rows of `rounds` repeats of the same list of runs (`runs[r][i]`: run i of round r),
/// summarised per run: the round with the median samples per CPU-second (the lower
/// middle one for an even count; wall-clock samples/s when CPU time is unknown), with the
/// range of that figure over the rounds.
pub fn median_of_rounds(runs: &[Vec<BenchRow>]) -> Vec<BenchRow> {
    let Some(first) = runs.first() else { return Vec::new() };
    (0..first.len())
        .map(|i| {
            let mut rows: Vec<&BenchRow> = runs.iter().filter_map(|r| r.get(i)).collect();
            let key = |r: &BenchRow| r.samples_per_cpu_second.unwrap_or(r.samples_per_second);
            rows.sort_by(|a, b| key(a).total_cmp(&key(b)));
            let mut row = rows[(rows.len() - 1) / 2].clone();
            row.rounds = rows.len() as u32;
            let cpu: Vec<f64> = rows.iter().filter_map(|r| r.samples_per_cpu_second).collect();
            row.samples_per_cpu_second_range = (cpu.len() == rows.len())
                .then(|| [cpu.iter().copied().fold(f64::INFINITY, f64::min), cpu.iter().copied().fold(0.0, f64::max)]);
            row
        })
        .collect()
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

/// Settings of `bench render` that override the device's defaults (`None`: the default).
#[derive(Clone, Copy, Debug, Default)]
pub struct Overrides {
    /// Paths per kernel invocation (src/render/regen.rs).
    pub paths_per_invocation: Option<u32>,
    /// How the kernels read their read-only buffers (src/render/reads.rs).
    pub reads: Option<vkvcm::render::reads::Reads>,
    /// How splats are summed (src/render/atomics.rs).
    pub atomics: Option<vkvcm::render::atomics::SplatAtomics>,
    /// How lights are picked (src/render/light_selection.rs).
    pub light_selection: Option<vkvcm::render::LightSelection>,
}

/// Renders `scene` with `variant` for 1 warm-up iteration, then `iterations` timed ones,
/// with `overrides` of the device's defaults. The timed render's set-up (uploading the
/// scene, building its BVH, creating the kernels) happens before its clock starts: the
/// row is the cost of the iterations, which a render's length multiplies (set-up and
/// start-up are measured apart: docs/performance.md, "Scene size" and "Start-up").
pub fn bench_one(
    gpu: &Arc<Gpu>,
    scene: &Scene,
    variant: Variant,
    (width, height): (u32, u32),
    iterations: u64,
    overrides: Overrides,
) -> Result<BenchRow> {
    let mut warm = variant.settings(width, height, Budget::Iterations(1));
    warm.paths_per_invocation = overrides.paths_per_invocation;
    warm.reads = overrides.reads;
    warm.atomics = overrides.atomics;
    if let Some(l) = overrides.light_selection {
        warm.frame.light_selection = l;
    }
    render(gpu, scene, &warm, None, &mut |_| {})?;
    let s = RenderSettings { budget: Budget::Iterations(iterations), ..warm };
    let mut renderer = Renderer::new(gpu, scene, &s)?;
    let cpu0 = process_cpu_seconds();
    let t0 = Instant::now();
    renderer.run(s.budget, None, &mut |_| {})?;
    let wall = t0.elapsed().as_secs_f64();
    let cpu = match (cpu0, process_cpu_seconds()) {
        (Some(a), Some(b)) => Some(b - a),
        _ => None,
    };
    let out = renderer.output()?;
    let samples = (width as u64 * height as u64 * out.iterations) as f64;
    Ok(BenchRow {
        scene: scene.name.clone(),
        algorithm: variant.name(),
        width,
        height,
        iterations: out.iterations,
        wall_seconds: wall,
        cpu_seconds: cpu,
        samples_per_second: samples / wall,
        samples_per_cpu_second: cpu.filter(|&c| c > 0.0).map(|c| samples / c),
        paths_per_invocation: out.paths_per_invocation,
        reads: out.reads.name().to_string(),
        kernels: out.profile.kernels,
        rounds: 1,
        samples_per_cpu_second_range: None,
    })
}

/// A markdown table of the rows.
pub fn table(rows: &[BenchRow]) -> String {
    let mut s = String::from(
        "| scene | algo | size | iterations | wall s | CPU s | samples/s | samples/CPU-s | GPU ms per iteration by kernel | paths per invocation | reads | samples/CPU-s range (rounds) |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let kernels: Vec<String> =
            r.kernels.iter().map(|k| format!("{} {:.2}", k.kernel, k.total_ms / r.iterations.max(1) as f64)).collect();
        s += &format!(
            "| {} | {} | {}x{} | {} | {:.2} | {} | {:.0} | {} | {} | {} | {} | {} |\n",
            r.scene,
            r.algorithm,
            r.width,
            r.height,
            r.iterations,
            r.wall_seconds,
            r.cpu_seconds.map(|c| format!("{c:.2}")).unwrap_or_else(|| "-".into()),
            r.samples_per_second,
            r.samples_per_cpu_second.map(|c| format!("{c:.0}")).unwrap_or_else(|| "-".into()),
            kernels.join(", "),
            r.paths_per_invocation,
            r.reads,
            match r.samples_per_cpu_second_range {
                Some([lo, hi]) if r.rounds > 1 => format!("{lo:.0}-{hi:.0} ({})", r.rounds),
                _ => format!("- ({})", r.rounds),
            }
        );
    }
    s
}

/// One estimator's error after a fixed wall-clock budget (averaged over rounds).
#[derive(Clone, Debug, Serialize)]
pub struct EqualTimeRow {
    pub scene: String,
    /// [`Variant::name`].
    pub algorithm: String,
    /// Renders (rounds) averaged; each ran for the budget with its own seed.
    pub rounds: u32,
    /// Render seconds and iterations per round (mean).
    pub seconds: f64,
    pub iterations: f64,
    /// Pixel samples per render second over all rounds.
    pub samples_per_second: f64,
    /// Means over the rounds.
    pub rmse: f64,
    pub rel_mse: f64,
    pub mean_abs_bias: f64,
    /// Smallest and largest RMSE of a round.
    pub rmse_min: f64,
    pub rmse_max: f64,
    /// The variance of one iteration's image, independent of the time budget and of the
    /// machine's load: (RMSE^2 - reference noise^2) x iterations, mean over the rounds
    /// (the reference noise is the RMS standard error it prints).
    pub variance_per_iteration: f64,
}

/// A long render used as the reference, with an estimate of its own remaining noise:
/// the RMS over pixels and channels of the standard error of its per-pixel mean.
pub struct Reference {
    pub image: vkvcm::image::Image,
    pub algorithm: Algorithm,
    pub iterations: u64,
    pub noise_rms: f64,
}

/// `iterations` in all, in two independent halves ([`vkvcm::render::reference::render_reference`]).
pub fn reference(gpu: &Arc<Gpu>, scene: &Scene, algo: Algorithm, size: u32, iterations: u64) -> Result<Reference> {
    let s = RenderSettings::new(algo, size, size, Budget::Iterations(iterations));
    let r = vkvcm::render::reference::render_reference(gpu, scene, &s, None, &mut |_, _| {})?;
    Ok(Reference { image: r.image, algorithm: algo, iterations: r.iterations, noise_rms: r.stderr_rms })
}

/// Renders `variant` for `seconds` of render time with `seed` (its first iteration, which
/// pays the driver's compilation, is discarded) and measures the error against the
/// reference: a row of one round.
pub fn equal_time(
    gpu: &Arc<Gpu>,
    scene: &Scene,
    variant: Variant,
    seconds: f64,
    seed: u32,
    reference: &Reference,
) -> Result<EqualTimeRow> {
    let (w, h) = (reference.image.width, reference.image.height);
    let mut s = variant.settings(w, h, Budget::Seconds(seconds));
    s.frame.seed = seed;
    let target = vkvcm::render::converge::Target {
        image: &reference.image,
        error: vkvcm::render::converge::ReferenceError { rmse: Some(reference.noise_rms), rel_mse: None },
    };
    let rows = vkvcm::render::converge::converge_one(gpu, scene, &s, &target, &[seconds], None, &mut |_| {})?;
    let row = rows.last().ok_or_else(|| anyhow::anyhow!("equal-time render of {} measured nothing", variant.name()))?;
    Ok(EqualTimeRow {
        scene: scene.name.clone(),
        algorithm: variant.name(),
        rounds: 1,
        seconds: row.seconds,
        iterations: row.iterations as f64,
        samples_per_second: (w as f64 * h as f64 * row.iterations as f64) / row.seconds.max(1e-9),
        rmse: row.rmse,
        rel_mse: row.rel_mse,
        mean_abs_bias: row.mean_abs_bias,
        rmse_min: row.rmse,
        rmse_max: row.rmse,
        variance_per_iteration: (row.rmse * row.rmse - reference.noise_rms * reference.noise_rms).max(0.0)
            * row.iterations as f64,
    })
}

/// [`equal_time`] for every variant in `rounds` rounds, interleaved: each round runs all
/// variants back to back, starting one further along the list each round (so a change of
/// load on the machine affects all alike), round r with seed `EQUAL_TIME_SEED + r` (never
/// the reference's). One row per variant, averaged over the rounds.
pub fn equal_time_rounds(
    gpu: &Arc<Gpu>,
    scene: &Scene,
    variants: &[Variant],
    seconds: f64,
    rounds: u32,
    reference: &Reference,
    log: &mut dyn FnMut(&EqualTimeRow),
) -> Result<Vec<EqualTimeRow>> {
    let n = variants.len();
    let mut per: Vec<Vec<EqualTimeRow>> = vec![Vec::new(); n];
    for round in 0..rounds {
        for k in 0..n {
            let v = (k + round as usize) % n;
            let row = equal_time(gpu, scene, variants[v], seconds, EQUAL_TIME_SEED + round, reference)?;
            log(&row);
            per[v].push(row);
        }
    }
    Ok(per.into_iter().filter_map(|rows| average(&rows)).collect())
}

/// First seed of the equal-time renders; the reference uses 1234 and 1235.
pub const EQUAL_TIME_SEED: u32 = 4321;

fn average(rows: &[EqualTimeRow]) -> Option<EqualTimeRow> {
    let first = rows.first()?;
    let k = rows.len() as f64;
    let mean = |f: &dyn Fn(&EqualTimeRow) -> f64| rows.iter().map(f).sum::<f64>() / k;
    let pixels_per_iteration = first.samples_per_second * first.seconds / first.iterations.max(1.0);
    let seconds: f64 = rows.iter().map(|r| r.seconds).sum();
    let iterations: f64 = rows.iter().map(|r| r.iterations).sum();
    Some(EqualTimeRow {
        scene: first.scene.clone(),
        algorithm: first.algorithm.clone(),
        rounds: rows.len() as u32,
        seconds: seconds / k,
        iterations: iterations / k,
        samples_per_second: pixels_per_iteration * iterations / seconds.max(1e-9),
        rmse: mean(&|r| r.rmse),
        rel_mse: mean(&|r| r.rel_mse),
        mean_abs_bias: mean(&|r| r.mean_abs_bias),
        rmse_min: rows.iter().map(|r| r.rmse).fold(f64::INFINITY, f64::min),
        rmse_max: rows.iter().map(|r| r.rmse).fold(0.0, f64::max),
        variance_per_iteration: mean(&|r| r.variance_per_iteration),
    })
}

/// A markdown table of equal-time rows.
pub fn equal_time_table(rows: &[EqualTimeRow]) -> String {
    let mut s = String::from(
        "| scene | algo | rounds | seconds | iterations | samples/s | RMSE (min-max) | relMSE | mean bias | var/it |\n|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        s += &format!(
            "| {} | {} | {} | {:.1} | {:.0} | {:.0} | {:.5} ({:.5}-{:.5}) | {:.5} | {:.5} | {:.4} |\n",
            r.scene,
            r.algorithm,
            r.rounds,
            r.seconds,
            r.iterations,
            r.samples_per_second,
            r.rmse,
            r.rmse_min,
            r.rmse_max,
            r.rel_mse,
            r.mean_abs_bias,
            r.variance_per_iteration
        );
    }
    s
}

// ---- `vkvcm-bench suite`: specialised against generic kernels (src/render/features.rs).

/// The fixed suite of `vkvcm-bench suite` (docs/performance.md): the four reference
/// scenes x six estimators at 128x128, 8 rounds of 4 timed iterations per variant.
pub const SUITE_SCENES: [&str; 4] = ["gbs_s", "glm_c", "gbs_p", "gbs_b"];
pub const SUITE_ALGOS: [Algorithm; 6] =
    [Algorithm::Pt, Algorithm::Lt, Algorithm::Bpt, Algorithm::Ppm, Algorithm::Bpm, Algorithm::Vcm];
pub const SUITE_SIZE: u32 = 128;
pub const SUITE_ROUNDS: u32 = 8;
pub const SUITE_ITERATIONS_PER_ROUND: u64 = 4;

/// One kernel variant's measurements over all rounds.
#[derive(Clone, Debug, Serialize)]
pub struct VariantStats {
    /// GPU ms per iteration (all stages): the median over the rounds.
    pub gpu_ms_per_iteration: f64,
    /// Wall-clock ms per iteration over all rounds (includes submission and waiting).
    pub wall_ms_per_iteration: f64,
    /// Samples per second of GPU time (median round).
    pub samples_per_second: f64,
    /// Rays per second of GPU time over all rounds.
    pub rays_per_second: f64,
    pub rays_per_iteration: f64,
    /// GPU ms per iteration of each stage over all rounds.
    pub stages: Vec<vkvcm::gpu::StageTime>,
}

/// One scene and estimator, specialised and generic.
#[derive(Clone, Debug, Serialize)]
pub struct SuiteRow {
    pub scene: String,
    pub algorithm: String,
    pub size: u32,
    /// Timed iterations per variant (rounds x iterations per round).
    pub iterations: u64,
    pub specialised: VariantStats,
    pub generic: VariantStats,
    /// Generic over specialised GPU time per iteration, the median over the rounds of
    /// each round's ratio (the two variants of a round ran back to back, under the same
    /// load): > 1 means the specialised kernels are faster.
    pub speedup: f64,
    /// The smallest and largest ratio of a round: the spread the machine's load caused.
    pub speedup_min: f64,
    pub speedup_max: f64,
    /// What the specialised kernels left out (the feature set's compiled-out list).
    pub compiled_out: Vec<String>,
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        0.0
    } else if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

fn variant_stats(total: &vkvcm::gpu::Profile, round_ms: &mut [f64], pixels: f64) -> VariantStats {
    let it = total.iterations.max(1) as f64;
    let med = median(round_ms);
    let rays = total.rays.unwrap_or(0) as f64;
    VariantStats {
        gpu_ms_per_iteration: med,
        wall_ms_per_iteration: 1e3 * total.wall_seconds / it,
        samples_per_second: pixels / (med * 1e-3).max(1e-12),
        rays_per_second: rays / (total.total_ms() * 1e-3).max(1e-12),
        rays_per_iteration: rays / it,
        stages: total.stages(),
    }
}

/// Renders `scene` with `algo` with specialised and with generic kernels (both counting
/// rays), after one untimed warm-up iteration each (the driver compiles there), in
/// `rounds` rounds of `per_round` iterations that alternate which variant runs first, so
/// that a change of load on the machine affects both alike. The renderers are built
/// twice, in both orders: the first half of the rounds with the specialised one built
/// first, the second half with the generic one built first. On lavapipe the renderer
/// built first ran 2-5% slower than the second with identical kernels (an A/A test of
/// bpm on gbs_s at 256x256, docs/performance.md), a bias that the two orders cancel in
/// the median ratio.
pub fn suite_row(
    gpu: &Arc<Gpu>,
    scene: &Scene,
    algo: Algorithm,
    size: u32,
    rounds: u32,
    per_round: u64,
) -> Result<SuiteRow> {
    let make = |generic: bool| -> Result<vkvcm::render::Renderer> {
        let mut s = RenderSettings::new(algo, size, size, Budget::Iterations(per_round));
        s.generic = generic;
        s.count_rays = true;
        let mut r = vkvcm::render::Renderer::new(gpu, scene, &s)?;
        r.run(Budget::Iterations(1), None, &mut |_| {})?;
        Ok(r)
    };
    // Index 0: specialised, 1: generic; built in `first_generic` order.
    let build = |first_generic: bool| -> Result<[vkvcm::render::Renderer; 2]> {
        Ok(if first_generic {
            let g = make(true)?;
            [make(false)?, g]
        } else {
            let sp = make(false)?;
            [sp, make(true)?]
        })
    };
    let mut renderers = build(false)?;
    let compiled_out = {
        let f = renderers[0].features();
        let all = [
            ("diffuse", f.diffuse),
            ("phong", f.phong),
            ("ggx", f.ggx),
            ("mirror", f.mirror),
            ("dielectric", f.dielectric),
            ("area", f.area_lights),
            ("point", f.point_lights),
            ("spot", f.spot_lights),
            ("directional", f.directional_lights),
            ("background", f.background),
            ("environment map", f.environment_map),
            ("spheres", f.spheres),
            ("shading normals", f.shading_normals),
        ];
        all.iter().filter(|(_, on)| !on).map(|(n, _)| n.to_string()).collect()
    };
    let mut totals = [vkvcm::gpu::Profile::default(), vkvcm::gpu::Profile::default()];
    let mut round_ms: [Vec<f64>; 2] = [Vec::new(), Vec::new()];
    for round in 0..rounds {
        if round == rounds / 2 && round > 0 {
            drop(renderers);
            renderers = build(true)?;
        }
        let order = if round % 2 == 0 { [0, 1] } else { [1, 0] };
        for v in order {
            let r = &mut renderers[v];
            let before = r.output()?.profile;
            r.run(Budget::Iterations(per_round), None, &mut |_| {})?;
            let delta = r.output()?.profile.since(&before);
            round_ms[v].push(delta.total_ms() / delta.iterations.max(1) as f64);
            totals[v].absorb(&delta);
        }
    }
    let mut ratios: Vec<f64> = round_ms[1].iter().zip(&round_ms[0]).map(|(g, s)| g / s.max(1e-12)).collect();
    let speedup = median(&mut ratios);
    let pixels = size as f64 * size as f64;
    let specialised = variant_stats(&totals[0], &mut round_ms[0], pixels);
    let generic = variant_stats(&totals[1], &mut round_ms[1], pixels);
    Ok(SuiteRow {
        scene: scene.name.clone(),
        algorithm: algo.name().to_string(),
        size,
        iterations: totals[0].iterations,
        speedup,
        speedup_min: ratios.first().copied().unwrap_or(0.0),
        speedup_max: ratios.last().copied().unwrap_or(0.0),
        specialised,
        generic,
        compiled_out,
    })
}

/// A markdown table of suite rows: per variant GPU ms per iteration, samples/s, rays/s,
/// and the specialised stages' ms per iteration.
pub fn suite_table(rows: &[SuiteRow]) -> String {
    let mut s = String::from(
        "| scene | algo | spec. ms/it | generic ms/it | speedup (range) | spec. Msamples/s | generic Msamples/s | spec. Mrays/s | generic Mrays/s | rays/it | spec. stages ms/it (light, grid, camera, accumulate) |\n\
         |---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let stage = |name: &str| {
            r.specialised
                .stages
                .iter()
                .find(|s| s.stage == name)
                .map(|s| format!("{:.2}", s.ms_per_iteration))
                .unwrap_or_else(|| "-".into())
        };
        s += &format!(
            "| {} | {} | {:.2} | {:.2} | {:.3} ({:.2}-{:.2}) | {:.3} | {:.3} | {:.2} | {:.2} | {:.0} | {} / {} / {} / {} |\n",
            r.scene,
            r.algorithm,
            r.specialised.gpu_ms_per_iteration,
            r.generic.gpu_ms_per_iteration,
            r.speedup,
            r.speedup_min,
            r.speedup_max,
            r.specialised.samples_per_second * 1e-6,
            r.generic.samples_per_second * 1e-6,
            r.specialised.rays_per_second * 1e-6,
            r.generic.rays_per_second * 1e-6,
            r.specialised.rays_per_iteration,
            stage("light subpaths"),
            stage("grid build"),
            stage("camera subpaths"),
            stage("accumulate"),
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(name: &str, per_cpu: f64) -> BenchRow {
        BenchRow {
            scene: "s".into(),
            algorithm: name.into(),
            width: 1,
            height: 1,
            iterations: 1,
            wall_seconds: 1.0,
            cpu_seconds: Some(1.0),
            samples_per_second: 1.0,
            samples_per_cpu_second: Some(per_cpu),
            paths_per_invocation: 1,
            reads: "storage".into(),
            kernels: Vec::new(),
            rounds: 1,
            samples_per_cpu_second_range: None,
        }
    }

    #[test]
    fn median_of_rounds_takes_each_rows_median_round_and_range() {
        let runs = vec![
            vec![row("pt", 5.0), row("lt", 10.0)],
            vec![row("pt", 1.0), row("lt", 30.0)],
            vec![row("pt", 3.0), row("lt", 20.0)],
        ];
        let m = median_of_rounds(&runs);
        assert_eq!(m.len(), 2);
        assert_eq!((m[0].algorithm.as_str(), m[0].samples_per_cpu_second), ("pt", Some(3.0)));
        assert_eq!(m[0].samples_per_cpu_second_range, Some([1.0, 5.0]));
        assert_eq!((m[1].samples_per_cpu_second, m[1].rounds), (Some(20.0), 3));
        assert_eq!(m[1].samples_per_cpu_second_range, Some([10.0, 30.0]));
        // An even count takes the lower middle round.
        assert_eq!(median_of_rounds(&runs[..2])[0].samples_per_cpu_second, Some(1.0));
        assert!(median_of_rounds(&[]).is_empty());
    }
}
