//! `vkvcm render`.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;

use anyhow::{bail, Context, Result};
use clap::Args;

use super::progress::Reporter;
use vkvcm::gpu::{Gpu, GpuOptions};
use vkvcm::image::{self, Image};
use vkvcm::render::{self, Algorithm, Budget, Progress, RenderSettings};
use vkvcm::scene::{self, LoadOptions};

#[derive(Args)]
pub struct RenderArgs {
    /// A glTF file (.gltf/.glb) or a built-in scene: gbs_s (default), glm_c, gbs_p, gbs_b.
    pub scene: Option<String>,
    /// Estimator.
    #[arg(long, short = 'a', value_enum, default_value = "vcm")]
    pub algo: Algorithm,
    /// Iterations (one sample per pixel each).
    #[arg(long, short = 'i', conflicts_with = "time")]
    pub iterations: Option<u64>,
    /// Render for this many wall-clock seconds instead of a fixed iteration count.
    #[arg(long, short = 't')]
    pub time: Option<f64>,
    #[arg(long, default_value_t = 512)]
    pub width: u32,
    #[arg(long, default_value_t = 512)]
    pub height: u32,
    #[arg(long, default_value_t = 1234)]
    pub seed: u32,
    /// Longest path, in segments.
    #[arg(long, default_value_t = 10)]
    pub max_path_length: u32,
    /// Initial merge radius as a fraction of the scene's bounding-sphere radius.
    #[arg(long, default_value_t = vkvcm::render::radius::DEFAULT_RADIUS_FACTOR)]
    pub radius_factor: f32,
    /// Radius reduction: r_i = r_0 (i+1)^((alpha-1)/2).
    #[arg(long, default_value_t = vkvcm::render::radius::DEFAULT_ALPHA)]
    pub alpha: f32,
    /// Camera to use, by node or camera name (default: the first one).
    #[arg(long)]
    pub camera: Option<String>,
    /// Output EXR (linear float32). Default: <scene>_<algo>.exr.
    #[arg(long, short = 'o')]
    pub output: Option<PathBuf>,
    /// Also write a tone-mapped sRGB PNG.
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// Exposure scale for the PNG.
    #[arg(long, default_value_t = 1.0)]
    pub exposure: f32,
    /// Print per-kernel GPU time.
    #[arg(long)]
    pub profile: bool,
    /// Vulkan device: index or name substring (see `vkvcm devices`).
    #[arg(long)]
    pub device: Option<String>,
}

/// Ctrl-C once: finish the current batch and write what was rendered. Twice: abort.
pub fn install_interrupt() -> Arc<AtomicBool> {
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

pub fn render_cmd(a: RenderArgs) -> Result<()> {
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
pub fn check_writable(path: &std::path::Path) -> Result<()> {
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
