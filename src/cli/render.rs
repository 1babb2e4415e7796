//! `vkvcm render`.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::Instant;

use anyhow::{anyhow, bail, Context, Result};
use clap::Args;

use super::exit::{Class, ClassifyExt};
use super::progress::Reporter;
use vkvcm::gpu::Gpu;
use vkvcm::image::{self, Image};
use vkvcm::render::{self, saved, Algorithm, Budget, Connect, Progress, RenderOutput, RenderSettings, Renderer};
use vkvcm::scene;

#[derive(Args)]
pub struct RenderArgs {
    #[command(flatten)]
    pub scene: super::scene_args::SceneArgs,
    /// Estimator.
    #[arg(long, short = 'a', value_enum, default_value = "vcm")]
    pub algo: Algorithm,
    /// Iterations (one sample per pixel each). With --resume: the total, counting the
    /// resumed ones.
    #[arg(long, short = 'i', conflicts_with = "time")]
    pub iterations: Option<u64>,
    /// Render for this many wall-clock seconds instead of a fixed iteration count (with
    /// --resume: this many more seconds).
    #[arg(long, short = 't')]
    pub time: Option<f64>,
    /// The frame's size, from --width/--height and the camera (`SceneArgs::frame_size`).
    #[arg(skip)]
    pub width: u32,
    #[arg(skip)]
    pub height: u32,
    #[arg(long, default_value_t = 1234)]
    pub seed: u32,
    /// Longest path, in segments.
    #[arg(long, default_value_t = 10)]
    pub max_path_length: u32,
    /// How next-event estimation and light subpaths pick a light: `power`, in proportion
    /// to each light's emitted power (pbrt-v4's rule), `uniform`, 1 / #lights
    /// (SmallVCM's), or `tree`, next-event estimation picking emissive triangles by a light
    /// tree that weighs them at the shading point (for many emissive triangles).
    /// Unbiased either way; docs/performance.md measures the difference.
    #[arg(long, value_enum, default_value_t = vkvcm::render::DEFAULT_LIGHT_SELECTION)]
    pub light_selection: vkvcm::render::LightSelection,
    /// Where the camera paths' random numbers come from: `sobol`, Owen-scrambled Sobol
    /// points that stratify each pixel's samples across iterations (the default of every
    /// estimator with camera paths: all but lt and el), or `independent` pseudo-random
    /// numbers. Light subpaths always draw independent numbers. Unbiased either way;
    /// docs/estimators.md, "Samplers".
    #[arg(long, value_enum)]
    pub sampler: Option<vkvcm::render::Sampler>,
    /// Initial merge radius as a fraction of the scene's bounding-sphere radius.
    #[arg(long, default_value_t = vkvcm::render::radius::DEFAULT_RADIUS_FACTOR)]
    pub radius_factor: f32,
    /// Radius reduction: r_i = r_0 (i+1)^((alpha-1)/2).
    #[arg(long, default_value_t = vkvcm::render::radius::DEFAULT_ALPHA)]
    pub alpha: f32,
    /// bpt, vcm: where a camera vertex's vertex connections go. `path`: every stored
    /// vertex of light subpath p = this pixel (SmallVCM); `cache`: --cache-connections
    /// vertices drawn uniformly from all light subpaths' vertices (light-vertex cache,
    /// Davidovic et al. 2014). Default: cache (measured better at equal time for bpt
    /// and vcm, docs/estimators.md).
    #[arg(long, value_enum)]
    pub connect: Option<ConnectKind>,
    /// Light subpaths per iteration, N_L, for lt, bpt, ppm, bpm and vcm (default: one per
    /// pixel, SmallVCM's choice). Merging's normalisation and MIS follow it; fewer light
    /// paths make an iteration cheaper and smaller in memory, and a large frame fit. At
    /// equal time, fewer help vcm where connections carry the light and hurt it where
    /// merging does (caustics): docs/estimators.md.
    #[arg(long, value_name = "N")]
    pub light_paths: Option<u32>,
    /// With --connect cache: light vertices connected to per camera vertex.
    #[arg(long, default_value_t = vkvcm::render::DEFAULT_CACHE_CONNECTIONS)]
    pub cache_connections: u32,
    /// Output EXR (linear float32, with the second moment and settings to resume it).
    /// Default: <scene>_<algo>.exr.
    #[arg(long, short = 'o', value_parser = super::parse_exr_path)]
    pub output: Option<PathBuf>,
    /// Also write a tone-mapped sRGB PNG (at the end).
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// Exposure scale for the PNG.
    #[arg(long, default_value_t = 1.0)]
    pub exposure: f32,
    /// Write the output EXR every SECONDS of rendering (atomically, with its iteration count).
    #[arg(long, value_name = "SECONDS")]
    pub checkpoint_every: Option<f64>,
    /// Continue the render saved in the output EXR (or in EXR, written to the output) with
    /// the same settings. A missing output EXR starts a new render.
    #[arg(long, value_name = "EXR", num_args = 0..=1)]
    pub resume: Option<Option<PathBuf>>,
    /// Print GPU time per stage and kernel per iteration, and rays traced per second (the
    /// kernels then count rays).
    #[arg(long)]
    pub profile: bool,
    /// Write the --profile report as JSON to FILE (implies counting rays).
    #[arg(long, value_name = "FILE")]
    pub profile_json: Option<PathBuf>,
    /// Write a trace of the render to FILE in the Chrome trace-event format (Perfetto,
    /// chrome://tracing): host phases on a CPU track, every timed dispatch with its pass,
    /// kernel, iteration and workgroups on a GPU track.
    #[arg(long, value_name = "FILE")]
    pub profile_trace: Option<PathBuf>,
    /// Compile every scene feature into the kernels instead of only the scene's (for
    /// comparison: the image agrees within float rounding).
    #[arg(long)]
    pub generic: bool,
    /// Paths each kernel invocation traces one after another (path regeneration; the image
    /// does not depend on it). Default: chosen for the device (256 at most on a CPU device
    /// such as lavapipe, 1 on a GPU; docs/performance.md).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub paths_per_invocation: Option<u32>,
    /// How the kernels read the buffers they only read (scene, light vertices, hash grid):
    /// as storage buffers or as uniform texel buffers (the image does not depend on it).
    /// Default: chosen for the device (texel on a CPU device such as lavapipe, where it
    /// is faster; storage on a GPU; docs/performance.md).
    #[arg(long, value_enum)]
    pub reads: Option<render::reads::Reads>,
    /// How light-tracing splats are summed: 64-bit atomics, or 32-bit atomic pairs with
    /// carry for devices without 64-bit atomics (the image does not depend on it).
    /// Default: 64 where the device has 64-bit buffer atomics (docs/devices.md).
    #[arg(long, value_enum)]
    pub atomics: Option<render::atomics::SplatAtomics>,
    /// Measure the image against this reference EXR (same size) as `vkvcm diff` does: RMSE
    /// and relative MSE on each progress line (of the last image read back) and, at the
    /// end, printed and stored in the output EXR's attributes.
    #[arg(long, value_name = "EXR")]
    pub reference: Option<PathBuf>,
    /// Print the feature set the kernels are compiled with and the buffers allocated.
    #[arg(long, conflicts_with = "quiet")]
    pub verbose: bool,
    /// Print no progress and no summary: only warnings and errors (the exit code says how
    /// it ended: README.md).
    #[arg(long, short = 'q')]
    pub quiet: bool,
    #[command(flatten)]
    pub extras: super::extras::ExtrasArgs,
    #[command(flatten)]
    pub gpu: super::GpuArgs,
    #[command(flatten)]
    pub shards: super::shard::ShardArgs,
    #[command(flatten)]
    pub submission: super::submission::SubmissionArgs,
}

/// `--connect`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ConnectKind {
    Path,
    Cache,
}

/// The connection strategy `--connect` / `--cache-connections` ask for with `algo`.
pub fn connect_setting(algo: Algorithm, kind: Option<ConnectKind>, cache_connections: u32) -> Result<Connect> {
    if cache_connections == 0 {
        bail!("--cache-connections 0: must be at least 1");
    }
    let requested = kind.map(|k| match k {
        ConnectKind::Path => Connect::Path,
        ConnectKind::Cache => Connect::Cache(cache_connections),
    });
    algo.info().connect(requested).map_err(|e| anyhow!("--connect: {e}"))
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

/// Without --checkpoint-every, the film is copied to the host (what a device loss can
/// still write) after slices of `SNAPSHOT_COST_FACTOR` times the last copy's duration,
/// at most `MAX_SNAPSHOT_SECONDS`: at most ~4% of the time goes to copies, and a small
/// film is copied after every batch.
const SNAPSHOT_COST_FACTOR: f64 = 25.0;
const MAX_SNAPSHOT_SECONDS: f64 = 5.0;

/// What --verbose says of the scene's size: triangles placed, stored and instanced.
fn scene_summary(scene: &vkvcm::scene::Scene) -> String {
    let placed = scene.placed_triangles();
    let mut s = format!("scene {}: {placed} triangles", scene.name);
    if !scene.instances.is_empty() {
        s += &format!(
            " ({} stored: {} world-space, {} shared mesh(es) placed by {} instances; --flatten-instances stores each placement)",
            scene.triangles.len(),
            scene.world_triangles().len(),
            scene.meshes.len(),
            scene.instances.len()
        );
    }
    s + &format!(", {} sphere(s), {} light(s)", scene.spheres.len(), scene.lights.len())
}

/// What --verbose says of the light-vertex store after a render: how full it got.
fn store_use_line(u: &render::StoreUse) -> String {
    let per_path = u.most_vertices as f64 / u.light_paths.max(1) as f64;
    let mut s = format!(
        "light-vertex store: at most {} vertices in an iteration ({per_path:.2} per light subpath, of {} slots), capacity {}",
        u.most_vertices, u.slots_per_path, u.capacity
    );
    if u.grown > 0 {
        s += &format!("; grown {} time(s), {} iteration(s) rendered again", u.grown, u.iterations_redone);
    }
    s
}

/// What --verbose says of the kernel cache: where it is, and how the kernels were built.
fn kernel_cache_line(gpu: &Gpu) -> String {
    let c = gpu.shader_counts();
    match gpu.kernel_cache_dir() {
        Some(dir) => format!(
            "kernel cache {}: {} kernel(s) compiled, {} read from the cache; pipeline cache: {} bytes read",
            dir.display(),
            c.compiled,
            c.from_disk,
            gpu.pipeline_cache_loaded_bytes()
        ),
        None => format!("kernel cache: off; {} kernel(s) compiled", c.compiled),
    }
}

/// Checks the arguments that need no scene or device; errors name the option.
fn check_args(a: &RenderArgs) -> Result<()> {
    if a.iterations == Some(0) {
        bail!("--iterations 0: at least one iteration is needed");
    }
    if let Some(t) = a.time {
        if !(t > 0.0 && t.is_finite()) {
            bail!("--time {t}: must be a positive number of seconds");
        }
    }
    if let Some(c) = a.checkpoint_every {
        if !(c > 0.0 && c.is_finite()) {
            bail!("--checkpoint-every {c}: must be a positive number of seconds");
        }
    }
    if a.max_path_length == 0 {
        bail!("--max-path-length 0: must be at least 1");
    }
    if !(a.radius_factor > 0.0 && a.radius_factor.is_finite()) {
        bail!("--radius-factor {}: must be a positive number", a.radius_factor);
    }
    if !(a.alpha > 0.0 && a.alpha <= 1.0) {
        bail!("--alpha {}: must be in (0, 1]", a.alpha);
    }
    a.scene.check()?;
    if !(a.exposure > 0.0 && a.exposure.is_finite()) {
        bail!("--exposure {}: must be a positive number", a.exposure);
    }
    Ok(())
}

/// Renders; `Some(Class::Interrupted)` when SIGINT or SIGTERM stopped it (what was
/// rendered is written).
pub fn render_cmd(mut a: RenderArgs) -> Result<Option<Class>> {
    check_args(&a).class(Class::Usage)?;
    if let Some(p) = &a.profile_trace {
        check_writable(p).context("--profile-trace")?;
        super::trace::start();
    }
    let scene = {
        let _p = super::trace::phase("scene load");
        load_scene(&a).class(Class::Scene)?
    };
    (a.width, a.height) = a.scene.frame_size(&scene);
    let output = a.output.clone().unwrap_or_else(|| PathBuf::from(format!("{}_{}.exr", scene.name, a.algo.name())));
    check_writable(&output).context("--output")?;
    if let Some(p) = &a.png {
        check_writable(p).context("--png")?;
    }
    let mut settings = render_settings(&a).class(Class::Usage)?;
    let shard = a.shards.apply(a.iterations, &mut settings).class(Class::Usage)?;
    let reference = read_reference(&a).class(Class::Usage)?;
    if let Some(p) = &a.profile_json {
        check_writable(p).context("--profile-json")?;
    }
    let camera = a.scene.camera.clone().unwrap_or_else(|| "default".into());
    let mut provenance = saved::Provenance { shard, ..saved::Provenance::new(&scene, &camera, "") };
    let saved = read_resumed(&a, &output, &settings, &provenance).class(Class::Usage)?;
    if let (Some(s), Budget::Iterations(n)) = (&saved, settings.budget) {
        if s.iterations >= n {
            say(
                &a,
                &format!(
                    "{} already has {} iterations (asked for {n} in total): nothing to do",
                    output.display(),
                    s.iterations
                ),
            );
            return Ok(None);
        }
    }

    if let Some(list) = &a.shards.devices {
        let cancel = install_interrupt();
        let o = super::shard::DevicesOutput {
            path: &output,
            png: a.png.as_deref(),
            exposure: a.exposure,
            quiet: a.quiet,
            cancel: &cancel,
        };
        return super::shard::render_on_devices(list, &a.gpu.options(), &scene, &settings, &mut provenance, &o);
    }
    let gpu = {
        let _p = super::trace::phase("device open");
        super::open_device(&a.gpu)?
    };
    say(&a, &format!("device: {} ({})", gpu.info.name, gpu.info.driver));
    provenance.device = gpu.info.name.clone();
    let mut r = {
        let mut p = super::trace::phase("prepare: BVH build, upload, kernels");
        let r = prepare_renderer(&a, &gpu, &scene, &settings)?;
        let c = gpu.shader_counts();
        p.arg("kernels compiled", c.compiled.into());
        p.arg("kernels from the cache", c.from_disk.into());
        r
    };
    if a.profile_trace.is_some() {
        r.trace_dispatches();
    }
    if let (None, Some(sh)) = (&saved, shard) {
        r.start_at(sh.shard.range(sh.total).start);
    }
    if let Some(s) = &saved {
        r.resume_saved(s)?;
        say(&a, &format!("resuming {} at iteration {} ({:.1} s rendered)", output.display(), s.iterations, s.seconds));
    }
    let display = a.extras.start_display(&output, a.width, a.height).class(Class::Usage)?;
    let file = OutputFile {
        path: &output,
        settings: &settings,
        provenance: &provenance,
        reference: reference.as_ref(),
        display: display.as_ref(),
    };
    let on_disk = saved.as_ref().map_or(0, |s| s.iterations);
    let out = render_slices(&a, &mut r, &scene.name, &file, on_disk)?;
    if out.iterations == 0 {
        eprintln!("interrupted before the first iteration finished: nothing written");
        return Ok(Some(Class::Interrupted));
    }
    write_outputs(&a, &r, &scene, &file, &out, saved.as_ref())?;
    if let Some(d) = display {
        d.finish(&out.pixels);
    }
    if let Some(p) = &a.profile_trace {
        super::trace::write(p).context("--profile-trace")?;
        say(&a, &format!("wrote {}", p.display()));
    }
    drop(r);
    let msgs = gpu.validation_messages();
    drop(gpu);
    if !msgs.list().is_empty() {
        bail!("{} Vulkan validation message(s) (printed above)", msgs.list().len());
    }
    Ok(out.interrupted.then_some(Class::Interrupted))
}

/// An informational line on stderr, left out with --quiet.
fn say(a: &RenderArgs, line: &str) {
    if !a.quiet {
        eprintln!("{line}");
    }
}

/// The scene with the view and environment options applied; prints the loader's warnings.
fn load_scene(a: &RenderArgs) -> Result<scene::Scene> {
    let scene = a.scene.load()?;
    for w in &scene.report.warnings {
        eprintln!("warning: {w}");
    }
    if let Some(n) = &scene.report.lighting_note {
        eprintln!("note: {n}");
    }
    if scene.report.degenerate_triangles > 0 {
        eprintln!("warning: skipped {} degenerate triangle(s)", scene.report.degenerate_triangles);
    }
    Ok(scene)
}

/// The render settings the arguments ask for.
fn render_settings(a: &RenderArgs) -> Result<RenderSettings> {
    let budget = match (a.iterations, a.time) {
        (_, Some(t)) => Budget::Seconds(t),
        (Some(n), None) => Budget::Iterations(n),
        (None, None) => Budget::Iterations(16),
    };
    let mut settings = RenderSettings::new(a.algo, a.width, a.height, budget);
    settings.frame.seed = a.seed;
    settings.frame.max_path_length = a.max_path_length;
    settings.frame.light_selection = a.light_selection;
    settings.sampler = a.sampler;
    settings.radius_factor = a.radius_factor;
    settings.alpha = a.alpha;
    settings.generic = a.generic;
    settings.paths_per_invocation = a.paths_per_invocation;
    settings.reads = a.reads;
    settings.atomics = a.atomics;
    settings.connect = connect_setting(a.algo, a.connect, a.cache_connections)?;
    settings.light_paths = a.light_paths;
    settings.count_rays = a.profile || a.profile_json.is_some();
    a.submission.apply(&mut settings);
    settings.aov = a.extras.aov_set();
    // Settings an estimator refuses are a usage error, found before the device opens.
    settings.check()?;
    Ok(settings)
}

/// With --resume, the saved render to continue, checked against `settings` before the
/// GPU opens; none when --resume is absent or its default file does not exist yet.
fn read_resumed(
    a: &RenderArgs,
    output: &Path,
    settings: &RenderSettings,
    provenance: &saved::Provenance,
) -> Result<Option<saved::SavedRender>> {
    let Some(from) = &a.resume else { return Ok(None) };
    let path = from.as_deref().unwrap_or(output);
    if from.is_none() && !path.exists() {
        eprintln!("note: {} does not exist yet: starting a new render", path.display());
        return Ok(None);
    }
    let s = saved::read_render_exr(path).context("--resume")?;
    s.check_matches(settings, provenance).with_context(|| format!("cannot resume {}", path.display()))?;
    Ok(Some(s))
}

/// The renderer, after checking that the frame fits the device (the error names the
/// options that size it); with --verbose, prints what it chose.
fn prepare_renderer(
    a: &RenderArgs,
    gpu: &Arc<Gpu>,
    scene: &scene::Scene,
    settings: &RenderSettings,
) -> Result<Renderer> {
    Renderer::plan_for(gpu, scene, settings)
        .map_err(|e| {
            let mpl = if a.algo.info().techniques.light_subpaths {
                format!(" --max-path-length {}", a.max_path_length)
            } else {
                String::new()
            };
            anyhow!("--width {} --height {}{mpl}: {e:#}", a.width, a.height)
        })
        .class(Class::Memory)?;
    let r = super::exit::memory_if_out_of_memory(
        Renderer::new(gpu, scene, settings).with_context(|| format!("preparing {} with {}", scene.name, a.algo.name())),
    )?;
    if a.verbose {
        eprintln!("{}", scene_summary(scene));
        eprintln!("{}", r.describe());
        let how = if a.paths_per_invocation.is_some() { "--paths-per-invocation" } else { "chosen for the device" };
        eprintln!("paths per invocation: {} ({how})", r.paths_per_invocation());
        let how = if a.reads.is_some() { "--reads" } else { "chosen for the device" };
        eprintln!("read-only buffers read as: {} buffers ({how})", r.reads().name());
        if r.store_reads() != r.reads() {
            eprintln!(
                "light-vertex store and hash grid read as: {} buffers (over the texel limit)",
                r.store_reads().name()
            );
        }
        let how = if a.atomics.is_some() { "--atomics" } else { "chosen for the device" };
        eprintln!("splats summed with {}-bit atomics ({how})", r.atomics().name());
        eprint!("{}", render::features::buffer_table(&r.buffers()));
        eprintln!("{}", kernel_cache_line(gpu));
    }
    Ok(r)
}

/// Where a render is written, and what the file records with it.
struct OutputFile<'a> {
    path: &'a Path,
    settings: &'a RenderSettings,
    provenance: &'a saved::Provenance,
    /// --reference: the image the render is measured against.
    reference: Option<&'a Image>,
    /// --display: where images read back during the render are shown.
    display: Option<&'a super::display::Display>,
}

impl OutputFile<'_> {
    fn write(&self, out: &RenderOutput) -> Result<()> {
        let more = match self.error(out)? {
            Some(m) => vec![
                ("vkvcm:reference_rmse".to_string(), m.rmse.to_string()),
                ("vkvcm:reference_rel_mse".to_string(), m.rel_mse.to_string()),
            ],
            None => Vec::new(),
        };
        saved::write_render_exr_with(self.path, out, self.settings, self.provenance, &more)
    }

    /// The error of `out` against --reference, measured as `vkvcm diff` does.
    fn error(&self, out: &RenderOutput) -> Result<Option<image::Metrics>> {
        let Some(reference) = self.reference else { return Ok(None) };
        let img = Image { width: out.width, height: out.height, data: out.pixels.clone() };
        image::compare(&img, reference).context("--reference").map(Some)
    }
}

/// --reference, read and checked against the frame's size before anything renders.
fn read_reference(a: &RenderArgs) -> Result<Option<Image>> {
    let Some(p) = &a.reference else { return Ok(None) };
    let (img, _) = image::read_exr(p).context("--reference")?;
    if (img.width, img.height) != (a.width, a.height) {
        bail!(
            "--reference {}: the reference is {}x{}, the render --width {} --height {}",
            p.display(),
            img.width,
            img.height,
            a.width,
            a.height
        );
    }
    Ok(Some(img))
}

/// Renders the budget in slices of --checkpoint-every seconds (or see
/// SNAPSHOT_COST_FACTOR), reading the film back after each: the checkpoint to write, and
/// what a device loss can still write. `on_disk`: iterations already in the output file.
/// On a failure, the last film read back is written when it adds iterations.
fn render_slices(
    a: &RenderArgs,
    r: &mut Renderer,
    scene_name: &str,
    file: &OutputFile,
    mut on_disk: u64,
) -> Result<RenderOutput> {
    let budget = file.settings.budget;
    let cancel = install_interrupt();
    let pixels = (a.width as u64 * a.height as u64) as f64;
    let mut reporter = Reporter::new(budget, r.iterations(), r.seconds(), a.quiet);
    let mut slice = a.checkpoint_every.unwrap_or(0.0);
    let start = Instant::now();
    let mut last: Option<RenderOutput> = None;
    let _render = super::trace::phase("render");
    let failure = loop {
        let slice_budget = match budget {
            Budget::Iterations(n) => Budget::Iterations(n.saturating_sub(r.iterations())),
            Budget::Seconds(t) => Budget::Seconds(t - start.elapsed().as_secs_f64()),
        };
        let finished = match slice_budget {
            Budget::Iterations(n) => n == 0,
            Budget::Seconds(t) => t <= 0.0 && r.iterations() > 0,
        };
        if finished || cancel.load(Ordering::SeqCst) {
            break None;
        }
        let mut on_progress = |p: &Progress| {
            if let Some(n) = &p.note {
                reporter.note(n);
            }
            reporter.update(p, pixels)
        };
        if let Err(e) = r.run_slice(slice_budget, Some(slice), Some(&cancel), &mut on_progress) {
            break Some(e);
        }
        let t0 = Instant::now();
        super::trace::dispatches(&r.take_dispatches());
        let readback = super::trace::phase("readback");
        let output = r.output();
        drop(readback);
        match output {
            Ok(out) => {
                if a.checkpoint_every.is_some() {
                    match file.write(&out) {
                        Ok(()) => {
                            on_disk = out.iterations;
                            let path = file.path.display();
                            reporter.note(&format!("checkpoint: {} iterations in {path}", out.iterations))
                        }
                        Err(e) => reporter.note(&format!("warning: checkpoint not written: {e:#}")),
                    }
                } else {
                    slice = (SNAPSHOT_COST_FACTOR * t0.elapsed().as_secs_f64()).min(MAX_SNAPSHOT_SECONDS);
                }
                if let Ok(Some(m)) = file.error(&out) {
                    reporter.set_error(&format!(
                        "rmse {:.4e}, rel_mse {:.4e} (at {} it)",
                        m.rmse, m.rel_mse, out.iterations
                    ));
                }
                if let Some(d) = file.display {
                    d.offer(&out.pixels);
                }
                last = Some(out);
            }
            Err(e) => break Some(e),
        }
    };
    super::trace::dispatches(&r.take_dispatches());
    let out = match failure {
        // A signal between slices leaves the renderer's flag unset: the render was
        // interrupted all the same (exit code 130).
        None => r
            .output()
            .map(|o| RenderOutput { interrupted: o.interrupted || cancel.load(Ordering::SeqCst), ..o })
            .with_context(|| format!("rendering {scene_name} with {}", a.algo.name())),
        Some(e) => Err(e.context(format!("rendering {scene_name}"))),
    };
    reporter.finish();
    if out.is_err() {
        write_last_completed(file, last, on_disk)?;
    }
    out
}

/// After a failure (the device may be gone): writes `last`, the last host copy of the
/// film, if it adds iterations to the `on_disk` ones, and says what the file holds.
fn write_last_completed(file: &OutputFile, last: Option<RenderOutput>, on_disk: u64) -> Result<()> {
    let path = file.path.display();
    match last {
        Some(l) if l.iterations > on_disk => {
            file.write(&l)?;
            eprintln!("wrote the last completed {} iterations ({:.1} s) to {path}", l.iterations, l.seconds);
        }
        _ if on_disk > 0 => eprintln!("{path} holds the last completed {on_disk} iterations"),
        _ => eprintln!("no completed iterations to write; {path} is unchanged"),
    }
    Ok(())
}

/// Writes the finished render (EXR, and the PNG and profile JSON when asked) and prints
/// its summary.
fn write_outputs(
    a: &RenderArgs,
    r: &Renderer,
    scene: &scene::Scene,
    file: &OutputFile,
    out: &RenderOutput,
    saved: Option<&saved::SavedRender>,
) -> Result<()> {
    {
        let _p = super::trace::phase("write EXR");
        file.write(out)?;
    }
    let pixels = (a.width as u64 * a.height as u64) as f64;
    let new_seconds = out.seconds - saved.map_or(0.0, |s| s.seconds);
    let new_iterations = out.iterations - saved.map_or(0, |s| s.iterations);
    say(
        a,
        &format!(
            "{} iterations in {:.2} s ({:.0} samples/s){}; wrote {}",
            out.iterations,
            out.seconds,
            new_iterations as f64 * pixels / new_seconds.max(1e-9),
            if out.interrupted { " (interrupted)" } else { "" },
            file.path.display()
        ),
    );
    if let Some(m) = file.error(out)? {
        say(a, &format!("against the reference: rmse {:.6e}, rel_mse {:.6e}", m.rmse, m.rel_mse));
    }
    if out.rejected_samples > 0 {
        eprintln!("warning: {} sample(s) were NaN, infinite or negative and were rejected", out.rejected_samples);
    }
    if let (true, Some(u)) = (a.verbose, r.light_vertex_store_use()) {
        eprintln!("{}", store_use_line(&u));
    }
    if a.verbose {
        let budget = if r.has_submission_budget() { "within the submission budget" } else { "no submission budget" };
        eprintln!("{} queue submission(s), {budget}", r.submissions());
    }
    if let Some(p) = &a.png {
        let img = Image { width: out.width, height: out.height, data: out.pixels.clone() };
        image::write_png(p, &img, a.exposure)?;
        say(a, &format!("wrote {}", p.display()));
    }
    if a.profile {
        eprint!("{}", out.profile.report());
    }
    if let Some(p) = &a.profile_json {
        let mut report = vkvcm::gpu::ProfileReport::new(&out.profile, &scene.name, a.algo.name(), a.width, a.height);
        report.paths_per_invocation = Some(r.paths_per_invocation());
        report.reads = Some(r.reads().name().to_string());
        super::write_json(p, &report).context("--profile-json")?;
        say(a, &format!("wrote {}", p.display()));
    }
    Ok(())
}

/// Fails early, with the path in the message, when an output cannot be created.
pub fn check_writable(path: &std::path::Path) -> Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    if path.is_dir() {
        bail!("cannot write {}: it is a directory", path.display());
    }
    if !dir.is_dir() {
        if dir.exists() {
            bail!("cannot write {}: {} is not a directory", path.display(), dir.display());
        }
        bail!("cannot write {}: directory {} does not exist", path.display(), dir.display());
    }
    tempfile::NamedTempFile::new_in(&dir)
        .map(drop)
        .with_context(|| format!("cannot write {}: directory {} is not writable", path.display(), dir.display()))
}
