//! `vkvcm reference` (a reference render with its own error estimate) and `vkvcm converge`
//! (error-vs-time curves of estimators against a reference: CSV and a log-log PNG).

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use clap::Args;

use super::render::{check_writable, install_interrupt};
use vkvcm::gpu::Gpu;
use vkvcm::image::{self, plot, Image};
use vkvcm::render::converge::Variant;
use vkvcm::render::converge::{self as conv, ReferenceError};
use vkvcm::render::reference::{self, Reference};
use vkvcm::render::saved::{Provenance, ShardOf};
use vkvcm::render::shard::Shard;
use vkvcm::render::{Algorithm, Budget, RenderSettings};
use vkvcm::scene::{self, Light, Scene};

#[derive(Args)]
pub struct ReferenceArgs {
    /// A glTF file (.gltf/.glb) or a built-in scene: gbs_s, glm_c, gbs_p, gbs_b.
    pub scene: String,
    /// Output EXR. Default: <scene>_reference.exr.
    #[arg(long, short = 'o', value_parser = super::parse_exr_path)]
    pub output: Option<PathBuf>,
    /// Estimator. Use an unbiased one (bpt, pt). vcm, ppm and bpm are only consistent:
    /// their merging bias shrinks with time but is there at any finite time, and the
    /// error estimate from two halves cannot see it (both halves share it).
    #[arg(long, short = 'a', value_enum, default_value = "bpt")]
    pub algo: Algorithm,
    /// Total render seconds (both halves together).
    #[arg(long, short = 't', conflicts_with = "iterations")]
    pub time: Option<f64>,
    /// Total iterations (both halves together; at least 2). Default: 256.
    #[arg(long, short = 'i')]
    pub iterations: Option<u64>,
    #[arg(long, default_value_t = 256)]
    pub width: u32,
    #[arg(long, default_value_t = 256)]
    pub height: u32,
    /// Seed of the first half; the second half uses seed + 1.
    #[arg(long, default_value_t = 1234)]
    pub seed: u32,
    /// Longest path, in segments.
    #[arg(long, default_value_t = 10)]
    pub max_path_length: u32,
    /// How next-event estimation and light subpaths pick a light (`render
    /// --light-selection`): the image's expectation is the same either way, its noise not.
    #[arg(long, value_enum, default_value_t = vkvcm::render::DEFAULT_LIGHT_SELECTION)]
    pub light_selection: vkvcm::render::LightSelection,
    /// Also write a tone-mapped sRGB PNG of the reference.
    #[arg(long, conflicts_with = "shard")]
    pub png: Option<PathBuf>,
    /// Render shard K of N (K from 0 to N-1) of both halves: of each half's I/2
    /// iterations (--iterations I), the global iterations K*I/2/N to (K+1)*I/2/N - 1.
    /// Writes a shard file (default <scene>_reference.K.exr); `vkvcm merge` of all N
    /// writes the reference this command writes without --shard (docs/distributed.md).
    #[arg(long, value_name = "K/N", value_parser = super::shard::parse_shard, conflicts_with = "time")]
    pub shard: Option<Shard>,
    #[command(flatten)]
    pub gpu: super::GpuArgs,
    #[command(flatten)]
    pub env: super::EnvArgs,
}

#[derive(Args)]
pub struct ConvergeArgs {
    /// The scene of the reference: a glTF file or a built-in name.
    pub scene: String,
    /// Reference EXR (from `vkvcm reference`; any EXR of the same size works, without a
    /// noise floor unless it carries vkvcm:reference_rmse), or the shards of a reference
    /// (`reference --shard`), merged in memory as `vkvcm merge` would.
    #[arg(long, short = 'r', required = true, num_args = 1.., value_name = "REFERENCE.exr")]
    pub reference: Vec<PathBuf>,
    /// Estimators, comma-separated, each `algo` or, for bpt and vcm, `algo:path` /
    /// `algo:cache:N` (the connection strategy, `render --connect`); then `:independent`
    /// / `:sobol` for a sampler other than the default (`render --sampler`); `@N` after a
    /// light-subpath estimator sets N light subpaths per iteration (`render
    /// --light-paths`), e.g. vcm,vcm:independent,vcm@65536. Rows and plot series carry
    /// these names.
    #[arg(long, value_delimiter = ',', default_value = "pt,bpt,vcm", value_parser = Variant::parse)]
    pub algos: Vec<Variant>,
    /// Render seconds per estimator (read-backs and error measurement not counted).
    #[arg(long, short = 't', default_value_t = 10.0)]
    pub time: f64,
    /// Checkpoints per estimator at T/2^(K-1), ..., T/2, T.
    #[arg(long, short = 'k', default_value_t = 6)]
    pub checkpoints: usize,
    /// Write the rows as CSV here (default: print them to stdout).
    #[arg(long)]
    pub csv: Option<PathBuf>,
    /// Write a log-log plot of RMSE vs. seconds (PNG).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Image size (default: the reference's; any other size is refused).
    #[arg(long)]
    pub width: Option<u32>,
    #[arg(long)]
    pub height: Option<u32>,
    /// Seed of the measured renders (keep it different from the reference's).
    #[arg(long, default_value_t = 4321)]
    pub seed: u32,
    /// Longest path, in segments (default: the reference's vkvcm:max_path_length, else 10).
    #[arg(long)]
    pub max_path_length: Option<u32>,
    /// How every estimator picks a light (`render --light-selection`); to compare the two
    /// rules at equal time, run converge once with each.
    #[arg(long, value_enum, default_value_t = vkvcm::render::DEFAULT_LIGHT_SELECTION)]
    pub light_selection: vkvcm::render::LightSelection,
    /// Measure only block K of N (K from 0 to N-1) of --algos' estimators, e.g. one
    /// array task each: the rows of all N, given to --rows, are the whole run's.
    #[arg(long, value_name = "K/N", value_parser = super::shard::parse_shard)]
    pub shard: Option<Shard>,
    /// Render nothing: read the CSV rows of the --shard runs (every estimator of --algos
    /// in exactly one file) and write them, and --plot, as one run of all would.
    #[arg(long, num_args = 1.., value_name = "ROWS.csv", conflicts_with = "shard")]
    pub rows: Option<Vec<PathBuf>>,
    #[command(flatten)]
    pub gpu: super::GpuArgs,
    /// The environment map of the reference, if it had one.
    #[command(flatten)]
    pub env: super::EnvArgs,
}

/// Names of the materials and lights that make SDS paths (light -> specular -> diffuse
/// -> specular -> eye) unreachable for pt, lt and bpt: a delta light (point, spot, sun)
/// and a specular surface. `None` when the scene has no such pair.
fn sds_hazard(scene: &Scene) -> Option<&'static str> {
    let delta = scene.lights.iter().find_map(|l| match l {
        Light::Point { .. } => Some("a point light"),
        Light::Spot { .. } => Some("a spot light"),
        Light::Directional { .. } => Some("a directional light"),
        _ => None,
    })?;
    let specular = scene.materials.iter().any(|m| m.ior >= 0.0 || m.mirror.max_element() > 0.0);
    specular.then_some(delta)
}

/// The scene of `reference` and `converge`; a failure exits 3, as render's.
fn load_scene(name: &str, env: &super::EnvArgs) -> Result<Scene> {
    use super::exit::{Class, ClassifyExt};
    env.load_options(None).and_then(|o| scene::load_named_with(name, &o)).class(Class::Scene)
}

fn meta_value<'a>(meta: &'a [(String, String)], key: &str) -> Option<&'a str> {
    meta.iter().find(|(k, _)| k == key).map(|(_, v)| v.as_str())
}

fn open_gpu(args: &super::GpuArgs) -> Result<std::sync::Arc<Gpu>> {
    let gpu = super::open_device(args)?;
    eprintln!("device: {} ({})", gpu.info.name, gpu.info.driver);
    Ok(gpu)
}

/// Fails when the device's validation layer reported anything (VKVCM_VALIDATION=1).
fn check_validation(gpu: std::sync::Arc<Gpu>) -> Result<()> {
    let msgs = gpu.validation_messages();
    drop(gpu);
    if !msgs.list().is_empty() {
        bail!("{} Vulkan validation message(s) (printed above)", msgs.list().len());
    }
    Ok(())
}

/// `--shard`: which shard of which split (each half's iterations) it renders.
fn reference_shard(a: &ReferenceArgs) -> Result<Option<ShardOf>> {
    let Some(shard) = a.shard else { return Ok(None) };
    let Some(total) = a.iterations else {
        bail!("--shard {shard} needs --iterations: the shards of a reference split a fixed number of iterations");
    };
    let per_half = total / 2;
    if per_half < shard.count as u64 {
        bail!(
            "--shard {shard}: --iterations {total} gives each half {per_half} iteration(s), fewer than {} shards",
            shard.count
        );
    }
    Ok(Some(ShardOf { shard, total: per_half }))
}

/// Warns about what the two halves' error estimate cannot see; refuses previews.
fn check_reference_estimator(a: &ReferenceArgs, scene: &Scene) -> Result<()> {
    let info = a.algo.info();
    match (info.radiance, info.consistent_only) {
        (false, _) => bail!("--algo {} is a preview, not radiance: use bpt or pt", info.name),
        (true, true) => eprintln!(
            "warning: {} is consistent but biased at any finite time (merging); the reference's error \
             estimate from two halves does not include that bias",
            a.algo.name()
        ),
        (true, false) => {
            if let Some(light) = sds_hazard(scene) {
                eprintln!(
                    "warning: {} has {light} and specular surfaces: {} cannot sample SDS paths \
                     (light -> specular -> diffuse -> specular -> eye, e.g. caustics seen through glass), \
                     so this reference lacks them; --algo vcm samples them but is only consistent",
                    scene.name,
                    a.algo.name()
                );
            }
        }
    }
    Ok(())
}

/// What `vkvcm reference` (and `vkvcm merge` of reference shards) prints about the
/// reference written to `output`.
pub(super) fn report_reference(output: &Path, r: &Reference) {
    println!(
        "reference {}: {} x {} iterations ({:.1} s) at {}x{}, seeds {} and {}",
        output.display(),
        r.algorithm.name(),
        r.iterations,
        r.seconds,
        r.image.width,
        r.image.height,
        r.seeds[0],
        r.seeds[1]
    );
    println!("its own error estimate, from the two halves: rmse {:.6e}, rel_mse {:.6e}", r.rmse, r.rel_mse);
    println!("(RMS standard error from the per-pixel variance: {:.6e})", r.stderr_rms);
    if r.rejected_samples > 0 {
        eprintln!("warning: {} sample(s) were NaN, infinite or negative and were rejected", r.rejected_samples);
    }
}

pub fn reference_cmd(a: ReferenceArgs) -> Result<()> {
    use super::exit::{Class, ClassifyExt};
    a.env.check()?;
    let shard = reference_shard(&a).class(Class::Usage)?;
    let scene = load_scene(&a.scene, &a.env)?;
    let output = a.output.clone().unwrap_or_else(|| match shard {
        Some(sh) => PathBuf::from(format!("{}_reference.{}.exr", scene.name, sh.shard.index)),
        None => PathBuf::from(format!("{}_reference.exr", scene.name)),
    });
    check_writable(&output)?;
    if let Some(p) = &a.png {
        check_writable(p)?;
    }
    let budget = match (a.iterations, a.time) {
        (_, Some(t)) if !(t > 0.0 && t.is_finite()) => bail!("--time must be a positive number of seconds"),
        (_, Some(t)) => Budget::Seconds(t),
        (Some(n), None) if n < 2 => bail!("--iterations must be at least 2 (one per half)"),
        (Some(n), None) => Budget::Iterations(n),
        (None, None) => Budget::Iterations(256),
    };
    check_reference_estimator(&a, &scene)?;
    let mut settings = RenderSettings::new(a.algo, a.width, a.height, budget);
    settings.frame.seed = a.seed;
    settings.frame.max_path_length = a.max_path_length;
    settings.frame.light_selection = a.light_selection;

    let gpu = open_gpu(&a.gpu)?;
    let mut last = -1.0;
    let halves = reference::render_halves(&gpu, &scene, &settings, shard, None, &mut |half, p| {
        if p.seconds - last >= 5.0 || p.fraction >= 1.0 {
            last = p.seconds;
            eprintln!("half {}: {:5.1}% {} it, {:.1} s", half + 1, 100.0 * p.fraction, p.iterations, p.seconds);
        }
        if p.fraction >= 1.0 {
            last = -1.0;
        }
    })
    .with_context(|| format!("rendering the reference of {} with {}", scene.name, a.algo.name()))?;
    if let Some(sh) = shard {
        let provenance = Provenance { shard, ..Provenance::new(&scene, "default", &gpu.info.name) };
        reference::write_shard(&output, &halves, &settings, &provenance)?;
        println!(
            "reference shard {} of {}: iterations {} of each half ({} in all, {:.1} s), seeds {} and {}",
            sh.shard,
            output.display(),
            halves.a.held,
            2 * halves.a.iterations,
            halves.a.seconds + halves.b.seconds,
            halves.seeds[0],
            halves.seeds[1]
        );
        return check_validation(gpu);
    }
    let r = halves.into_reference(a.algo)?;
    image::write_exr(&output, &r.image, &r.metadata(&scene.name, &reference::settings_metadata(&settings)))?;
    report_reference(&output, &r);
    if let Some(p) = &a.png {
        image::write_png(p, &r.image, 1.0)?;
        eprintln!("wrote {}", p.display());
    }
    check_validation(gpu)
}

/// Writes `text` to `path` atomically (temporary file + rename), with the permissions the
/// umask gives an ordinary file (a bare temporary file would be 0600).
fn write_text(path: &Path, text: &str) -> Result<()> {
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let mut b = tempfile::Builder::new();
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        b.permissions(std::fs::Permissions::from_mode(0o666));
    }
    let mut f = b.tempfile_in(dir).with_context(|| format!("cannot write {}", path.display()))?;
    std::io::Write::write_all(&mut f, text.as_bytes()).with_context(|| format!("cannot write {}", path.display()))?;
    f.persist(path).with_context(|| format!("cannot write {}", path.display()))?;
    Ok(())
}

/// The reference image and its attributes: one EXR, or the shards of a reference (or of
/// a render, without a noise floor) merged in memory with `vkvcm merge`'s checks.
fn load_reference(paths: &[PathBuf]) -> Result<(Image, Vec<(String, String)>)> {
    if let [p] = paths {
        let (img, meta) = image::read_exr(p)?;
        if meta_value(&meta, "vkvcm:shard").is_none() {
            return Ok((img, meta));
        }
    }
    let hint = "converge takes complete sets only: `vkvcm merge --partial` merges what there is";
    let m = super::shard::merge_files(paths, false, hint).context("--reference")?;
    if m.half_b.is_some() {
        let (r, meta) = reference::from_merged(m)?;
        return Ok((r.image, meta));
    }
    let img = Image { width: m.width, height: m.height, data: m.sums.mean(m.iterations()) };
    Ok((img, m.metadata))
}

/// The estimators this run measures: --algos, or its block --shard.
fn shard_algos(a: &ConvergeArgs) -> Result<Vec<Variant>> {
    let Some(sh) = a.shard else { return Ok(a.algos.clone()) };
    if sh.count as usize > a.algos.len() {
        bail!("--shard {sh}: {} estimator(s) in --algos, fewer than {} shards", a.algos.len(), sh.count);
    }
    let r = sh.range(a.algos.len() as u64);
    Ok(a.algos[r.start as usize..r.end as usize].to_vec())
}

/// The rows of `files` (CSV of --shard runs), in the order of `algos`: every estimator
/// in exactly one file, and no other.
fn read_rows(files: &[PathBuf], algos: &[Variant]) -> Result<Vec<conv::ConvergeRow>> {
    let mut found: Vec<(PathBuf, Vec<conv::ConvergeRow>)> = Vec::new();
    for p in files {
        let text = std::fs::read_to_string(p).with_context(|| format!("cannot read --rows {}", p.display()))?;
        let rows = conv::read_csv(&text).with_context(|| format!("--rows {}", p.display()))?;
        for r in &rows {
            if !algos.iter().any(|v| v.name() == r.estimator) {
                bail!("--rows {}: estimator {} is not in --algos", p.display(), r.estimator);
            }
            if let Some((q, _)) = found.iter().find(|(q, rs)| q != p && rs.iter().any(|x| x.estimator == r.estimator)) {
                bail!("--rows: {} and {} both hold estimator {}", q.display(), p.display(), r.estimator);
            }
        }
        found.push((p.clone(), rows));
    }
    let all: Vec<conv::ConvergeRow> = found.into_iter().flat_map(|(_, rows)| rows).collect();
    let mut rows = Vec::with_capacity(all.len());
    for v in algos {
        let before = rows.len();
        rows.extend(all.iter().filter(|r| r.estimator == v.name()).cloned());
        if rows.len() == before {
            bail!("--rows: no file holds estimator {} of --algos", v.name());
        }
    }
    Ok(rows)
}

pub fn converge_cmd(a: ConvergeArgs) -> Result<()> {
    use super::exit::{Class, ClassifyExt};
    let times = conv::checkpoint_times(a.time, a.checkpoints).context("--time / --checkpoints")?;
    if a.algos.is_empty() {
        bail!("--algos: name at least one estimator");
    }
    if let Some(p) = a.algos.iter().find(|v| !v.algorithm.info().radiance) {
        bail!("--algos: {} is a preview, not radiance; it has no error to measure", p.name());
    }
    let algos = shard_algos(&a).class(Class::Usage)?;
    let (reference, meta) = load_reference(&a.reference)?;
    let shown = a.reference.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", ");
    let (w, h) = (a.width.unwrap_or(reference.width), a.height.unwrap_or(reference.height));
    if (w, h) != (reference.width, reference.height) {
        bail!(
            "the reference {shown} is {}x{} but the render would be {w}x{h}: render at the reference's size \
             (leave out --width/--height) or make a reference of this size",
            reference.width,
            reference.height
        );
    }
    if reference.non_finite_count() > 0 {
        bail!("the reference {shown} has {} non-finite pixel(s)", reference.non_finite_count());
    }
    for p in [&a.csv, &a.plot].into_iter().flatten() {
        check_writable(p)?;
    }
    a.env.check()?;
    let scene = load_scene(&a.scene, &a.env)?;
    if let Some(s) = meta_value(&meta, "vkvcm:scene").filter(|s| *s != scene.name) {
        eprintln!("warning: the reference {shown} was rendered from scene {s}, not {}", scene.name);
    }
    for key in ["vkvcm:seed", "vkvcm:seed_b"] {
        if meta_value(&meta, key) == Some(a.seed.to_string().as_str()) {
            eprintln!("warning: --seed {} is the reference's own seed: the errors are not independent", a.seed);
        }
    }
    let ref_max_len = meta_value(&meta, "vkvcm:max_path_length").and_then(|v| v.parse::<u32>().ok());
    let max_path_length = a.max_path_length.or(ref_max_len).unwrap_or(10);
    if ref_max_len.is_some_and(|m| m != max_path_length) {
        eprintln!(
            "warning: the reference was rendered with max path length {ref_max_len:?}, these with {max_path_length}"
        );
    }
    let ref_err = ReferenceError::from_metadata(&meta);
    let ref_algo = meta_value(&meta, "vkvcm:estimator").unwrap_or("unknown estimator").to_string();
    match ref_err.rmse {
        Some(e) => eprintln!("reference {shown}: {ref_algo}, its own RMSE estimate {e:.4e}"),
        None => eprintln!("reference {shown}: no vkvcm:reference_rmse, so no noise floor"),
    }

    let target = conv::Target { image: &reference, error: ref_err };
    let measured = match &a.rows {
        Some(files) => (read_rows(files, &algos).class(Class::Usage)?, None),
        None => {
            let settings = |v: &Variant| {
                let mut s = v.settings(w, h, Budget::Seconds(a.time));
                s.frame.seed = a.seed;
                s.frame.max_path_length = max_path_length;
                s.frame.light_selection = a.light_selection;
                s
            };
            let gpu = open_gpu(&a.gpu)?;
            (measure(&gpu, &scene, &algos, &settings, &target, &times)?, Some(gpu))
        }
    };
    let (rows, gpu) = measured;
    let text = conv::csv_string(&rows)?;
    match &a.csv {
        Some(p) => {
            write_text(p, &text)?;
            eprintln!("wrote {}", p.display());
        }
        None => print!("{text}"),
    }
    if let Some(p) = &a.plot {
        let series = algos
            .iter()
            .map(|v| plot::Series {
                name: v.name(),
                points: rows.iter().filter(|r| r.estimator == v.name()).map(|r| (r.seconds, r.rmse)).collect(),
            })
            .filter(|s| !s.points.is_empty())
            .collect();
        let plot = plot::LogLogPlot {
            title: format!("{} {w}x{h}: error vs. render time", scene.name),
            x_label: "render seconds".into(),
            y_label: "RMSE".into(),
            series,
            floor: ref_err.rmse.map(|e| (e, format!("reference ({ref_algo}) own RMSE"))),
            width: 900,
            height: 600,
        };
        plot::write_loglog_png(p, &plot)?;
        eprintln!("wrote {}", p.display());
    }
    gpu.map_or(Ok(()), check_validation)
}

/// Each estimator of `algos` rendered and measured at `times` (stops with the rows so
/// far on Ctrl-C).
fn measure(
    gpu: &std::sync::Arc<Gpu>,
    scene: &Scene,
    algos: &[Variant],
    settings: &dyn Fn(&Variant) -> RenderSettings,
    target: &conv::Target,
    times: &[f64],
) -> Result<Vec<conv::ConvergeRow>> {
    let cancel = install_interrupt();
    let mut rows = Vec::new();
    for variant in algos {
        let name = variant.name();
        let r = conv::converge_one(gpu, scene, &settings(variant), target, times, Some(&cancel), &mut |c| {
            let r = c.row;
            eprintln!(
                "{name:>4} {}/{}: {:6} it {:8.2} s  RMSE {:.4e}  relMSE {:.4e}  |bias| {:.3e}",
                r.checkpoint, c.of, r.iterations, r.seconds, r.rmse, r.rel_mse, r.mean_abs_bias
            );
        })
        .with_context(|| format!("rendering {} with {name}", scene.name))?;
        rows.extend(r.into_iter().map(|row| conv::ConvergeRow { estimator: name.clone(), ..row }));
        if cancel.load(std::sync::atomic::Ordering::Relaxed) {
            eprintln!("interrupted: writing the rows so far");
            break;
        }
    }
    Ok(rows)
}
