//! `vkvcm-bench ...`: render throughput, BVH traversal and equal-time error (results for
//! docs/performance.md and docs/bvh.md).

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;

use anyhow::{bail, Context, Result};
use clap::{Args, Parser};

use vkvcm::gpu::{Gpu, GpuArgs};
use vkvcm::image::write_json;
use vkvcm::render::{self, Algorithm};
use vkvcm::scene;

fn main() -> ExitCode {
    match BenchCommand::parse().run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

#[derive(Parser)]
#[command(name = "vkvcm-bench", version, about = "Benchmarks of vkvcm (results for docs/performance.md)")]
pub enum BenchCommand {
    /// Samples/s per wall second and per CPU-second, and GPU ms per kernel, for scenes x
    /// estimators at a fixed iteration count (after one warm-up iteration each).
    Render(BenchRenderArgs),
    /// BVH build time and closest-hit / any-hit rays per second (camera and random rays)
    /// on the generated traversal scenes: cornell (~4k triangles + spheres), spheres and
    /// displaced (1M triangles each); see docs/bvh.md.
    Traverse(BenchTraverseArgs),
    /// BVH build time per million triangles for each thread count, on generated meshes of
    /// 1M and 4M triangles (spheres, displaced, spheres-4m, displaced-4m) or loaded scenes
    /// (built-in names, glTF paths); checks that every thread count builds the same BVH.
    /// CPU only; see docs/bvh.md.
    BvhBuild(BenchBvhBuildArgs),
    /// Error at equal time: each estimator renders for --seconds of wall-clock time, and
    /// its RMSE, relative MSE and mean bias against a long reference render are reported
    /// (the reference's own remaining noise is printed with it).
    EqualTime(BenchEqualTimeArgs),
    /// Scene-specialised against generic kernels (`render --generic`): the four reference
    /// scenes x pt, lt, bpt, ppm, bpm, vcm at 128x128, 8 rounds of 4 timed iterations per
    /// variant, the variants alternating, the renderers built in one order for the first
    /// half of the rounds and in the other for the second; GPU ms per iteration,
    /// samples/s, rays/s, ms per stage, and the speedup (docs/performance.md).
    Suite(BenchSuiteArgs),
}

#[derive(Args)]
pub struct BenchSuiteArgs {
    /// Scenes (the suite: all four reference scenes).
    #[arg(long, value_delimiter = ',', default_value = "gbs_s,glm_c,gbs_p,gbs_b")]
    pub scenes: Vec<String>,
    /// Estimators (the suite: all but el).
    #[arg(long, value_delimiter = ',', default_value = "pt,lt,bpt,ppm,bpm,vcm")]
    pub algos: Vec<Algorithm>,
    #[arg(long, default_value_t = vkvcm_tools::bench::render::SUITE_SIZE)]
    pub size: u32,
    /// Rounds; each runs both variants, alternating which goes first (the renderers are
    /// rebuilt in the other order after half of them).
    #[arg(long, default_value_t = vkvcm_tools::bench::render::SUITE_ROUNDS)]
    pub rounds: u32,
    /// Timed iterations per variant and round.
    #[arg(long, default_value_t = vkvcm_tools::bench::render::SUITE_ITERATIONS_PER_ROUND)]
    pub iterations: u64,
    #[arg(long)]
    pub json: Option<PathBuf>,
    #[command(flatten)]
    pub gpu: GpuArgs,
}

#[derive(Args)]
pub struct BenchEqualTimeArgs {
    #[arg(long, value_delimiter = ',', default_value = "gbs_s,glm_c,gbs_p,gbs_b")]
    pub scenes: Vec<String>,
    /// Estimators, each `algo` or, for bpt and vcm, `algo:path` / `algo:cache:N` (the
    /// connection strategy, `render --connect`), e.g. bpt:path,bpt:cache:1; then
    /// `:independent` / `:sobol` for a sampler other than the default (`render
    /// --sampler`), e.g. pt:independent, vcm:path:independent; `@N` after a
    /// light-subpath estimator sets N light subpaths per iteration (`render
    /// --light-paths`), e.g. vcm@16384.
    #[arg(long, value_delimiter = ',', default_value = "pt,lt,bpt,ppm,bpm,vcm", value_parser = vkvcm::render::converge::Variant::parse)]
    pub algos: Vec<vkvcm::render::converge::Variant>,
    #[arg(long, default_value_t = 128)]
    pub size: u32,
    /// Wall-clock seconds per estimator and round.
    #[arg(long, default_value_t = 5.0)]
    pub seconds: f64,
    /// Rounds: each renders every estimator once (seed 4321 + round), starting one
    /// further along the list each round; the table shows the means over the rounds.
    #[arg(long, default_value_t = 1)]
    pub rounds: u32,
    /// Estimator of the reference (vcm samples every path of the reference scenes,
    /// including the SDS paths bpt and pt miss).
    #[arg(long, value_enum, default_value = "vcm")]
    pub reference_algo: Algorithm,
    #[arg(long, default_value_t = 2048)]
    pub reference_iterations: u64,
    #[arg(long)]
    pub json: Option<PathBuf>,
    #[command(flatten)]
    pub gpu: GpuArgs,
}

#[derive(Args)]
pub struct BenchTraverseArgs {
    /// Scenes: cornell, spheres, displaced (comma-separated).
    #[arg(long, value_delimiter = ',', default_value = "cornell,spheres,displaced")]
    pub scenes: Vec<String>,
    /// Rays per ray set.
    #[arg(long, default_value_t = 1 << 20)]
    pub rays: u32,
    /// When the BVH build makes a node of few primitives a leaf (docs/bvh.md, "Build").
    #[arg(long, value_enum, default_value = "auto")]
    pub leaf_rule: vkvcm::bvh::LeafRule,
    #[command(flatten)]
    pub gpu: GpuArgs,
}

#[derive(Args)]
pub struct BenchBvhBuildArgs {
    /// Generated meshes (spheres, displaced, spheres-4m, displaced-4m), built-in scene
    /// names or glTF paths, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "spheres,displaced,spheres-4m,displaced-4m")]
    pub scenes: Vec<String>,
    /// Builder thread counts to time, comma-separated (0 = all cores).
    #[arg(long, value_delimiter = ',', default_value = "1,0")]
    pub threads: Vec<usize>,
    /// Builds per scene and thread count; the median counts.
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..))]
    pub rounds: u32,
    /// When the build makes a node of few primitives a leaf (docs/bvh.md, "Build").
    #[arg(long, value_enum, default_value = "auto")]
    pub leaf_rule: vkvcm::bvh::LeafRule,
    /// Also write the results as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Also write each scene's triangles to DIR/SCENE.f32 (9 little-endian f32 per
    /// triangle: the three vertices), for scripts/embree_build.py to build the same mesh
    /// with Embree.
    #[arg(long, value_name = "DIR")]
    pub export_triangles: Option<PathBuf>,
}

#[derive(Args)]
pub struct BenchRenderArgs {
    /// Scenes (built-in names or glTF paths), comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "gbs_s,glm_c,gbs_p,gbs_b")]
    pub scenes: Vec<String>,
    /// Estimators, comma-separated, each `algo` or, for bpt and vcm, `algo:path` /
    /// `algo:cache:N` (the connection strategy, `render --connect`), e.g. bpt:path; then
    /// `:independent` / `:sobol` for a sampler other than the default (`render
    /// --sampler`), e.g. vcm:independent; `@N` after a light-subpath estimator sets N
    /// light subpaths per iteration (`render --light-paths`), e.g. vcm@16384.
    #[arg(long, value_delimiter = ',', default_value = "pt,lt,bpt,ppm,bpm,vcm", value_parser = vkvcm::render::converge::Variant::parse)]
    pub algos: Vec<vkvcm::render::converge::Variant>,
    /// Image width and height.
    #[arg(long, default_value_t = 256)]
    pub size: u32,
    #[arg(long, default_value_t = 8)]
    pub iterations: u64,
    /// Repeat the whole list this many times (each round runs every scene and estimator
    /// once, so a drift of the machine's speed spreads over all rows); each row is the
    /// round with the median samples per CPU-second, with the range over the rounds.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    pub rounds: u32,
    /// Paths per kernel invocation (`render --paths-per-invocation`; default: chosen for
    /// the device).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub paths_per_invocation: Option<u32>,
    /// How the kernels read their read-only buffers (`render --reads`; default: chosen
    /// for the device).
    #[arg(long, value_enum)]
    pub reads: Option<render::reads::Reads>,
    /// How splats are summed (`render --atomics`; default: chosen for the device).
    #[arg(long, value_enum)]
    pub atomics: Option<render::atomics::SplatAtomics>,
    /// How lights are picked (`render --light-selection`; default: power).
    #[arg(long, value_enum)]
    pub light_selection: Option<render::LightSelection>,
    /// Also write the results as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
    #[command(flatten)]
    pub gpu: GpuArgs,
}

/// Fails early, before a long benchmark, when `path` cannot be written.
fn check_writable(path: &Path) -> Result<()> {
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    tempfile::NamedTempFile::new_in(dir).map(drop).with_context(|| format!("cannot write {}", path.display()))
}

impl BenchCommand {
    pub fn run(self) -> Result<()> {
        match self {
            BenchCommand::Render(a) => bench_render(a),
            BenchCommand::Traverse(a) => bench_traverse(a),
            BenchCommand::BvhBuild(a) => bench_bvh_build(a),
            BenchCommand::EqualTime(a) => bench_equal_time(a),
            BenchCommand::Suite(a) => bench_suite(a),
        }
    }
}

/// Opens the device for a benchmark and prints which one it is (results name it).
fn open_bench_gpu(args: &GpuArgs) -> Result<Arc<Gpu>> {
    let gpu = Gpu::new(&args.options())?;
    println!("device: {} ({}), Vulkan {}", gpu.info.name, gpu.info.driver, gpu.info.api_version);
    Ok(gpu)
}

fn bench_traverse(a: BenchTraverseArgs) -> Result<()> {
    let gpu = open_bench_gpu(&a.gpu)?;
    let build = vkvcm::bvh::BuildOptions { leaf_rule: a.leaf_rule, ..Default::default() };
    let opts = vkvcm_tools::bench::traverse::TraverseBenchOptions { rays: a.rays.max(1), build, ..Default::default() };
    for name in &a.scenes {
        let scene = vkvcm_tools::bench::traverse::bench_scene(name)
            .with_context(|| format!("unknown traversal scene {name:?} (cornell, spheres, displaced)"))?;
        let report = vkvcm_tools::bench::traverse::bench_traverse(&gpu, &scene, &opts)?;
        println!("{report}");
    }
    Ok(())
}

fn bench_bvh_build(a: BenchBvhBuildArgs) -> Result<()> {
    if let Some(p) = &a.json {
        check_writable(p).context("--json")?;
    }
    println!("BVH build on {} cores available", std::thread::available_parallelism().map_or(1, |n| n.get()));
    let mut rows = Vec::new();
    for name in &a.scenes {
        let scene = vkvcm_tools::bench::build::build_scene(name)?;
        if let Some(dir) = &a.export_triangles {
            let path = vkvcm_tools::bench::build::export_triangles(&scene, dir)?;
            println!("{name}: triangles written to {}", path.display());
        }
        for row in vkvcm_tools::bench::build::bench_build(&scene, &a.threads, a.rounds, a.leaf_rule)? {
            println!("{row}");
            rows.push(row);
        }
    }
    if let Some(p) = &a.json {
        write_json(p, &rows)?;
    }
    Ok(())
}

fn bench_equal_time(a: BenchEqualTimeArgs) -> Result<()> {
    if a.size == 0 || a.seconds.is_nan() || a.seconds <= 0.0 || a.reference_iterations < 2 || a.rounds == 0 {
        bail!("--size, --seconds and --rounds must be positive and --reference-iterations at least 2");
    }
    let gpu = open_bench_gpu(&a.gpu)?;
    let mut rows = Vec::new();
    for name in &a.scenes {
        let scene = scene::load_named(name)?;
        eprintln!("{name}: reference, {} x {} iterations ...", a.reference_algo.name(), a.reference_iterations);
        let r = vkvcm_tools::bench::render::reference(&gpu, &scene, a.reference_algo, a.size, a.reference_iterations)?;
        println!(
            "{name}: reference {} x {} iterations at {}x{}, its own noise (RMS standard error) {:.5}",
            r.algorithm.name(),
            r.iterations,
            a.size,
            a.size,
            r.noise_rms
        );
        let mut log = |row: &vkvcm_tools::bench::render::EqualTimeRow| {
            eprintln!("{name} {}: RMSE {:.5}, {} iterations", row.algorithm, row.rmse, row.iterations)
        };
        rows.extend(vkvcm_tools::bench::render::equal_time_rounds(
            &gpu, &scene, &a.algos, a.seconds, a.rounds, &r, &mut log,
        )?);
    }
    print!("{}", vkvcm_tools::bench::render::equal_time_table(&rows));
    if let Some(p) = &a.json {
        write_json(p, &rows)?;
    }
    Ok(())
}

fn bench_suite(a: BenchSuiteArgs) -> Result<()> {
    if a.size == 0 || a.iterations == 0 || a.rounds == 0 {
        bail!("--size, --rounds and --iterations must be at least 1");
    }
    if let Some(p) = &a.json {
        check_writable(p).context("--json")?;
    }
    let gpu = open_bench_gpu(&a.gpu)?;
    let mut rows = Vec::new();
    for name in &a.scenes {
        let scene = scene::load_named(name)?;
        for &algo in &a.algos {
            let row = vkvcm_tools::bench::render::suite_row(&gpu, &scene, algo, a.size, a.rounds, a.iterations)
                .with_context(|| format!("benchmarking {} on {name}", algo.name()))?;
            eprintln!(
                "{} {}: specialised {:.2} ms/it, generic {:.2} ms/it, speedup {:.3} ({:.2}-{:.2})",
                row.scene,
                row.algorithm,
                row.specialised.gpu_ms_per_iteration,
                row.generic.gpu_ms_per_iteration,
                row.speedup,
                row.speedup_min,
                row.speedup_max
            );
            rows.push(row);
        }
    }
    print!("{}", vkvcm_tools::bench::render::suite_table(&rows));
    if let Some(p) = &a.json {
        write_json(p, &rows)?;
    }
    Ok(())
}

fn bench_render(a: BenchRenderArgs) -> Result<()> {
    if a.size == 0 || a.iterations == 0 {
        bail!("--size and --iterations must be at least 1");
    }
    let gpu = open_bench_gpu(&a.gpu)?;
    let scenes = a.scenes.iter().map(|n| Ok((n, scene::load_named(n)?))).collect::<Result<Vec<_>>>()?;
    let overrides = vkvcm_tools::bench::render::Overrides {
        paths_per_invocation: a.paths_per_invocation,
        reads: a.reads,
        atomics: a.atomics,
        light_selection: a.light_selection,
    };
    let mut runs = Vec::new();
    for round in 1..=a.rounds {
        let mut rows = Vec::new();
        for (name, scene) in &scenes {
            for &variant in &a.algos {
                let size = (a.size, a.size);
                let row = vkvcm_tools::bench::render::bench_one(&gpu, scene, variant, size, a.iterations, overrides)
                    .with_context(|| format!("benchmarking {} on {name}", variant.name()))?;
                let cpu = row.samples_per_cpu_second.map_or("-".into(), |c| format!("{c:.0}"));
                eprintln!(
                    "round {round}/{}: {} {}: {:.0} samples/s, {cpu} samples/CPU-s",
                    a.rounds, row.scene, row.algorithm, row.samples_per_second
                );
                rows.push(row);
            }
        }
        runs.push(rows);
    }
    let rows = vkvcm_tools::bench::render::median_of_rounds(&runs);
    print!("{}", vkvcm_tools::bench::render::table(&rows));
    if let Some(p) = &a.json {
        write_json(p, &rows)?;
    }
    Ok(())
}
