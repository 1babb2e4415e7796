//! The `vkvcm` command line: parse, call the library, report.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;

use anyhow::{bail, Context, Result};
use clap::{Args, Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};

use vkvcm::gpu::{self, Gpu, GpuOptions};
use vkvcm::image::{self, Image};
use vkvcm::render::{self, Algorithm, Budget, Progress, RenderSettings};
use vkvcm::scene::{self, LoadOptions};

#[derive(Parser)]
#[command(name = "vkvcm", version, about = "Light transport in Vulkan compute shaders: pt, lt, bpt, ppm, bpm, vcm")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// List Vulkan devices and the features vkvcm needs.
    Devices,
    /// Render a scene to an EXR (and optionally a PNG).
    Render(RenderArgs),
    /// Benchmarks (results for docs/performance.md).
    #[command(subcommand)]
    Bench(BenchCommand),
}

#[derive(Subcommand)]
enum BenchCommand {
    /// Samples/s per wall second and per CPU-second, and GPU ms per kernel, for scenes x
    /// estimators at a fixed iteration count (after one warm-up iteration each).
    Render(BenchRenderArgs),
    /// BVH build time and closest-hit / any-hit rays per second (camera and random rays)
    /// on the generated traversal scenes: cornell (~4k triangles + spheres), spheres and
    /// displaced (1M triangles each); see docs/bvh.md.
    Traverse(BenchTraverseArgs),
    /// Error at equal time: each estimator renders for --seconds of wall-clock time, and
    /// its RMSE, relative MSE and mean bias against a long reference render are reported
    /// (the reference's own remaining noise is printed with it).
    EqualTime(BenchEqualTimeArgs),
}

#[derive(Args)]
struct BenchEqualTimeArgs {
    #[arg(long, value_delimiter = ',', default_value = "gbs_s,glm_c,gbs_p,gbs_b")]
    scenes: Vec<String>,
    #[arg(long, value_delimiter = ',', default_value = "pt,lt,bpt,ppm,bpm,vcm")]
    algos: Vec<Algorithm>,
    #[arg(long, default_value_t = 128)]
    size: u32,
    /// Wall-clock seconds per estimator.
    #[arg(long, default_value_t = 5.0)]
    seconds: f64,
    /// Estimator of the reference (vcm samples every path of the reference scenes,
    /// including the SDS paths bpt and pt miss).
    #[arg(long, value_enum, default_value = "vcm")]
    reference_algo: Algorithm,
    #[arg(long, default_value_t = 2048)]
    reference_iterations: u64,
    #[arg(long)]
    json: Option<PathBuf>,
    #[arg(long)]
    device: Option<String>,
}

#[derive(Args)]
struct BenchTraverseArgs {
    /// Scenes: cornell, spheres, displaced (comma-separated).
    #[arg(long, value_delimiter = ',', default_value = "cornell,spheres,displaced")]
    scenes: Vec<String>,
    /// Rays per ray set.
    #[arg(long, default_value_t = 1 << 20)]
    rays: u32,
    #[arg(long)]
    device: Option<String>,
}

#[derive(Args)]
struct BenchRenderArgs {
    /// Scenes (built-in names or glTF paths), comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "gbs_s,glm_c,gbs_p,gbs_b")]
    scenes: Vec<String>,
    /// Estimators, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "pt,lt,bpt,ppm,bpm,vcm")]
    algos: Vec<Algorithm>,
    /// Image width and height.
    #[arg(long, default_value_t = 256)]
    size: u32,
    #[arg(long, default_value_t = 8)]
    iterations: u64,
    /// Also write the results as JSON.
    #[arg(long)]
    json: Option<PathBuf>,
    #[arg(long)]
    device: Option<String>,
}

#[derive(Args)]
struct RenderArgs {
    /// A glTF file (.gltf/.glb) or a built-in scene: gbs_s (default), glm_c, gbs_p, gbs_b.
    scene: Option<String>,
    /// Estimator.
    #[arg(long, short = 'a', value_enum, default_value = "vcm")]
    algo: Algorithm,
    /// Iterations (one sample per pixel each).
    #[arg(long, short = 'i', conflicts_with = "time")]
    iterations: Option<u64>,
    /// Render for this many wall-clock seconds instead of a fixed iteration count.
    #[arg(long, short = 't')]
    time: Option<f64>,
    #[arg(long, default_value_t = 512)]
    width: u32,
    #[arg(long, default_value_t = 512)]
    height: u32,
    #[arg(long, default_value_t = 1234)]
    seed: u32,
    /// Longest path, in segments.
    #[arg(long, default_value_t = 10)]
    max_path_length: u32,
    /// Initial merge radius as a fraction of the scene's bounding-sphere radius.
    #[arg(long, default_value_t = vkvcm::render::radius::DEFAULT_RADIUS_FACTOR)]
    radius_factor: f32,
    /// Radius reduction: r_i = r_0 (i+1)^((alpha-1)/2).
    #[arg(long, default_value_t = vkvcm::render::radius::DEFAULT_ALPHA)]
    alpha: f32,
    /// Camera to use, by node or camera name (default: the first one).
    #[arg(long)]
    camera: Option<String>,
    /// Output EXR (linear float32). Default: <scene>_<algo>.exr.
    #[arg(long, short = 'o')]
    output: Option<PathBuf>,
    /// Also write a tone-mapped sRGB PNG.
    #[arg(long)]
    png: Option<PathBuf>,
    /// Exposure scale for the PNG.
    #[arg(long, default_value_t = 1.0)]
    exposure: f32,
    /// Print per-kernel GPU time.
    #[arg(long)]
    profile: bool,
    /// Vulkan device: index or name substring (see `vkvcm devices`).
    #[arg(long)]
    device: Option<String>,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Devices => devices(),
        Command::Render(args) => render_cmd(args),
        Command::Bench(BenchCommand::Render(args)) => bench_render(args),
        Command::Bench(BenchCommand::Traverse(args)) => bench_traverse(args),
        Command::Bench(BenchCommand::EqualTime(args)) => bench_equal_time(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn devices() -> Result<()> {
    let list = gpu::list_devices()?;
    if list.is_empty() {
        bail!("no Vulkan device found");
    }
    for d in &list {
        println!("{}: {} ({}), driver {}, Vulkan {}", d.index, d.name, d.type_name(), d.driver, d.api_version);
        for f in &d.features {
            let mark = if f.present { "yes" } else { "NO " };
            let req = if f.required { "required" } else { "optional" };
            println!("    {mark} {} ({req})", f.name);
        }
    }
    Ok(())
}

/// Opens the device for a benchmark and prints which one it is (results name it).
fn open_bench_gpu(device: Option<String>) -> Result<Arc<Gpu>> {
    let gpu = Gpu::new(&GpuOptions::from_env(device))?;
    println!("device: {} ({}), Vulkan {}", gpu.info.name, gpu.info.driver, gpu.info.api_version);
    Ok(gpu)
}

fn bench_traverse(a: BenchTraverseArgs) -> Result<()> {
    let gpu = open_bench_gpu(a.device.clone())?;
    let opts = vkvcm::bvh::bench::TraverseBenchOptions { rays: a.rays.max(1), ..Default::default() };
    for name in &a.scenes {
        let scene = vkvcm::bvh::bench::bench_scene(name)
            .with_context(|| format!("unknown traversal scene {name:?} (cornell, spheres, displaced)"))?;
        let report = vkvcm::bvh::bench::bench_traverse(&gpu, &scene, &opts)?;
        println!("{report}");
    }
    Ok(())
}

fn bench_equal_time(a: BenchEqualTimeArgs) -> Result<()> {
    if a.size == 0 || a.seconds.is_nan() || a.seconds <= 0.0 || a.reference_iterations < 2 {
        bail!("--size and --seconds must be positive and --reference-iterations at least 2");
    }
    let gpu = open_bench_gpu(a.device.clone())?;
    let mut rows = Vec::new();
    for name in &a.scenes {
        let scene = scene::load_named(name)?;
        eprintln!("{name}: reference, {} x {} iterations ...", a.reference_algo.name(), a.reference_iterations);
        let r = render::bench::reference(&gpu, &scene, a.reference_algo, a.size, a.reference_iterations)?;
        println!(
            "{name}: reference {} x {} iterations at {}x{}, its own noise (RMS standard error) {:.5}",
            r.algorithm.name(),
            r.iterations,
            a.size,
            a.size,
            r.noise_rms
        );
        for &algo in &a.algos {
            let row = render::bench::equal_time(&gpu, &scene, algo, a.seconds, &r)?;
            eprintln!("{name} {}: RMSE {:.5}", row.algorithm, row.rmse);
            rows.push(row);
        }
    }
    print!("{}", render::bench::equal_time_table(&rows));
    if let Some(p) = &a.json {
        write_json(p, &rows)?;
    }
    Ok(())
}

/// Writes `value` as pretty JSON, atomically.
fn write_json<T: serde::Serialize>(p: &std::path::Path, value: &T) -> Result<()> {
    let text = serde_json::to_string_pretty(value)?;
    let dir = p.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(std::path::Path::new("."));
    let mut f = tempfile::NamedTempFile::new_in(dir).with_context(|| format!("cannot write {}", p.display()))?;
    std::io::Write::write_all(&mut f, text.as_bytes())?;
    f.persist(p).with_context(|| format!("cannot write {}", p.display()))?;
    Ok(())
}

fn bench_render(a: BenchRenderArgs) -> Result<()> {
    if a.size == 0 || a.iterations == 0 {
        bail!("--size and --iterations must be at least 1");
    }
    let gpu = open_bench_gpu(a.device.clone())?;
    let mut rows = Vec::new();
    for name in &a.scenes {
        let scene = scene::load_named(name)?;
        for &algo in &a.algos {
            let row = render::bench::bench_one(&gpu, &scene, algo, a.size, a.size, a.iterations)
                .with_context(|| format!("benchmarking {} on {name}", algo.name()))?;
            eprintln!("{} {}: {:.0} samples/s", row.scene, row.algorithm, row.samples_per_second);
            rows.push(row);
        }
    }
    print!("{}", render::bench::table(&rows));
    if let Some(p) = &a.json {
        write_json(p, &rows)?;
    }
    Ok(())
}

/// Ctrl-C once: finish the current batch and write what was rendered. Twice: abort.
fn install_interrupt() -> Arc<AtomicBool> {
    let flag = Arc::new(AtomicBool::new(false));
    let count = Arc::new(AtomicUsize::new(0));
    let f = flag.clone();
    let _ = ctrlc::set_handler(move || {
        if count.fetch_add(1, Ordering::SeqCst) >= 1 {
            eprintln!("\ninterrupted twice: aborting without writing");
            std::process::exit(130);
        }
        eprintln!("\ninterrupt: finishing the current iterations and writing the image (Ctrl-C again aborts)");
        f.store(true, Ordering::SeqCst);
    });
    flag
}

fn render_cmd(a: RenderArgs) -> Result<()> {
    let scene_name = a.scene.clone().unwrap_or_else(|| "default".into());
    let scene = scene::load_named_with(&scene_name, &LoadOptions { camera: a.camera.clone() })?;
    for w in &scene.report.warnings {
        eprintln!("warning: {w}");
    }
    if scene.report.degenerate_triangles > 0 {
        eprintln!("warning: skipped {} degenerate triangle(s)", scene.report.degenerate_triangles);
    }
    let output = a.output.clone().unwrap_or_else(|| PathBuf::from(format!("{}_{}.exr", scene.name, a.algo.name())));
    check_writable(&output)?;
    if let Some(p) = &a.png {
        check_writable(p)?;
    }
    let budget = match (a.iterations, a.time) {
        (_, Some(t)) if !(t > 0.0 && t.is_finite()) => bail!("--time must be a positive number of seconds"),
        (_, Some(t)) => Budget::Seconds(t),
        (Some(n), None) => Budget::Iterations(n),
        (None, None) => Budget::Iterations(16),
    };
    let mut settings = RenderSettings::new(a.algo, a.width, a.height, budget);
    settings.frame.seed = a.seed;
    settings.frame.max_path_length = a.max_path_length;
    if !(a.radius_factor > 0.0 && a.radius_factor.is_finite()) {
        bail!("--radius-factor must be a positive number");
    }
    if !(a.alpha > 0.0 && a.alpha <= 1.0) {
        bail!("--alpha must be in (0, 1]");
    }
    settings.radius_factor = a.radius_factor;
    settings.alpha = a.alpha;

    let gpu = Gpu::new(&GpuOptions::from_env(a.device.clone()))?;
    eprintln!("device: {} ({})", gpu.info.name, gpu.info.driver);
    let cancel = install_interrupt();
    let pixels = (a.width as u64 * a.height as u64) as f64;
    let mut reporter = Reporter::new(budget);
    let out = render::render(&gpu, &scene, &settings, Some(&cancel), &mut |p: &Progress| reporter.update(p, pixels))
        .with_context(|| format!("rendering {} with {}", scene.name, a.algo.name()))?;
    reporter.finish();

    let img = Image { width: out.width, height: out.height, data: out.pixels.clone() };
    let meta = vec![
        ("vkvcm:scene".to_string(), scene.name.clone()),
        ("vkvcm:estimator".to_string(), a.algo.name().to_string()),
        ("vkvcm:iterations".to_string(), out.iterations.to_string()),
        ("vkvcm:seconds".to_string(), format!("{:.3}", out.seconds)),
        ("vkvcm:seed".to_string(), a.seed.to_string()),
        ("vkvcm:max_path_length".to_string(), a.max_path_length.to_string()),
        ("vkvcm:radius_factor".to_string(), a.radius_factor.to_string()),
        ("vkvcm:alpha".to_string(), a.alpha.to_string()),
        ("vkvcm:device".to_string(), gpu.info.name.clone()),
        ("vkvcm:rejected_samples".to_string(), out.rejected_samples.to_string()),
    ];
    image::write_exr(&output, &img, &meta)?;
    eprintln!(
        "{} iterations in {:.2} s ({:.0} samples/s){}; wrote {}",
        out.iterations,
        out.seconds,
        out.iterations as f64 * pixels / out.seconds.max(1e-9),
        if out.interrupted { " (interrupted)" } else { "" },
        output.display()
    );
    if out.rejected_samples > 0 {
        eprintln!("warning: {} sample(s) were NaN, infinite or negative and were rejected", out.rejected_samples);
    }
    if let Some(p) = &a.png {
        image::write_png(p, &img, a.exposure)?;
        eprintln!("wrote {}", p.display());
    }
    if a.profile {
        eprint!("{}", out.profile.table());
    }
    let msgs = gpu.validation_messages();
    drop(gpu);
    if !msgs.list().is_empty() {
        bail!("{} Vulkan validation message(s) (printed above)", msgs.list().len());
    }
    Ok(())
}

/// Fails early, with the path in the message, when an output cannot be created.
fn check_writable(path: &std::path::Path) -> Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    if !dir.is_dir() {
        bail!("cannot write {}: directory {} does not exist", path.display(), dir.display());
    }
    tempfile::NamedTempFile::new_in(&dir)
        .map(drop)
        .with_context(|| format!("cannot write {}: directory {} is not writable", path.display(), dir.display()))
}

/// A progress bar on a terminal, plain lines otherwise.
struct Reporter {
    bar: Option<ProgressBar>,
    last_line: f64,
}

impl Reporter {
    fn new(budget: Budget) -> Self {
        let bar = std::io::stderr().is_terminal().then(|| {
            let total = match budget {
                Budget::Iterations(n) => n,
                Budget::Seconds(_) => 1000,
            };
            let b = ProgressBar::new(total);
            b.set_style(
                ProgressStyle::with_template("{bar:40} {msg} [{elapsed_precise} < {eta_precise}]")
                    .unwrap_or_else(|_| ProgressStyle::default_bar()),
            );
            b
        });
        Reporter { bar, last_line: -1.0 }
    }

    fn update(&mut self, p: &Progress, pixels: f64) {
        let rate = p.iterations as f64 * pixels / p.seconds.max(1e-9);
        let msg = format!("{} it, {:.2} Msamples/s", p.iterations, rate * 1e-6);
        match &self.bar {
            Some(b) => {
                let len = b.length().unwrap_or(1);
                b.set_position((p.fraction * len as f64).round() as u64);
                b.set_message(msg);
            }
            None => {
                if p.seconds - self.last_line >= 5.0 || p.fraction >= 1.0 {
                    self.last_line = p.seconds;
                    eprintln!("progress: {:5.1}% {msg}, {:.1} s", 100.0 * p.fraction, p.seconds);
                }
            }
        }
    }

    fn finish(&self) {
        if let Some(b) = &self.bar {
            b.finish_and_clear();
        }
    }
}
