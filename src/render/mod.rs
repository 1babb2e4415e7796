//! Estimators: each is a sequence of kernel dispatches per iteration over shared buffers
//! (../shared/DESIGN.md). One iteration = one sample per pixel.

pub mod bench;
pub mod bidir;
pub mod converge;
pub mod features;
pub mod film;
pub mod gpu_types;
pub mod hash_grid;
pub mod pt;
pub mod radius;
pub mod reads;
pub mod regen;
pub mod resources;
pub mod saved;
pub mod scene_gpu;

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

use anyhow::{bail, Context, Result};

use crate::gpu::{Batch, Gpu, Kernel, Profile};
use crate::scene::Scene;
pub use film::Film;
pub use scene_gpu::{FrameSettings, SceneGpu};

/// The estimators vkvcm implements.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Algorithm {
    /// Eye light: |cos| at the first hit (a preview, not radiance).
    El,
    /// Path tracing with next-event estimation and MIS.
    Pt,
    /// Light tracing: light subpaths connected to the camera.
    Lt,
    /// Bidirectional path tracing (vertex connection), SmallVCM's MIS.
    Bpt,
    /// Progressive photon mapping: merging at the first non-specular camera vertex.
    Ppm,
    /// Bidirectional photon mapping: merging at every camera vertex, with MIS.
    Bpm,
    /// Vertex connection and merging: all of the above, with MIS.
    Vcm,
}

impl Algorithm {
    pub fn name(self) -> &'static str {
        match self {
            Algorithm::El => "el",
            Algorithm::Pt => "pt",
            Algorithm::Lt => "lt",
            Algorithm::Bpt => "bpt",
            Algorithm::Ppm => "ppm",
            Algorithm::Bpm => "bpm",
            Algorithm::Vcm => "vcm",
        }
    }
}

/// When a render stops.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Budget {
    Iterations(u64),
    /// Wall-clock seconds (at least one iteration runs).
    Seconds(f64),
}

#[derive(Clone, Debug)]
pub struct RenderSettings {
    pub algorithm: Algorithm,
    pub frame: FrameSettings,
    pub budget: Budget,
    /// Path tracing only: `false` disables next-event estimation (BSDF sampling only).
    pub nee: bool,
    /// Initial merge radius as a fraction of the scene's bounding-sphere radius.
    pub radius_factor: f32,
    /// Radius reduction exponent alpha of r_i = r_0 (i+1)^((alpha-1)/2).
    pub alpha: f32,
    /// Kernels with every scene feature compiled in, instead of only the scene's
    /// (src/render/features.rs); the image agrees within float rounding.
    pub generic: bool,
    /// Count the rays traced (`Profile::rays`; a few atomics per invocation).
    pub count_rays: bool,
    /// bpt and vcm: where vertex connections go (SmallVCM's matching light subpath or a
    /// light-vertex cache); must be `Path` for the other estimators.
    pub connect: bidir::Connect,
    /// Paths per kernel invocation (path regeneration, [`regen`]); `None` chooses by
    /// device ([`regen::auto`]). The image does not depend on it.
    pub paths_per_invocation: Option<u32>,
    /// How the kernels read their read-only buffers ([`reads`]); `None` chooses by device
    /// ([`reads::Reads::auto`]). The image does not depend on it.
    pub reads: Option<reads::Reads>,
}

impl RenderSettings {
    pub fn new(algorithm: Algorithm, width: u32, height: u32, budget: Budget) -> Self {
        RenderSettings {
            algorithm,
            frame: FrameSettings { width, height, seed: 1234, max_path_length: 10, min_path_length: 0 },
            budget,
            nee: true,
            radius_factor: radius::DEFAULT_RADIUS_FACTOR,
            alpha: radius::DEFAULT_ALPHA,
            generic: false,
            count_rays: false,
            connect: bidir::Connect::default_for(algorithm),
            paths_per_invocation: None,
            reads: None,
        }
    }
}

/// Progress of a running render.
#[derive(Clone, Debug)]
pub struct Progress {
    pub iterations: u64,
    pub seconds: f64,
    /// Fraction done in [0, 1].
    pub fraction: f64,
}

/// What a render produced.
pub struct RenderOutput {
    pub width: u32,
    pub height: u32,
    /// Mean linear RGB per pixel, row 0 at the top.
    pub pixels: Vec<[f32; 3]>,
    /// Per-pixel sums of the iterations' values and of their squares: the mean is
    /// `sum / iterations`, the variance of one iteration's value follows from both.
    pub sum: Vec<[f64; 3]>,
    pub sum_sq: Vec<[f64; 3]>,
    pub iterations: u64,
    pub seconds: f64,
    /// Samples that were NaN, infinite or negative (rejected, never added).
    pub rejected_samples: u64,
    /// Light-tracing splats rejected because they could overflow the fixed-point sum.
    pub overflow_splats: u64,
    pub profile: Profile,
    /// Paths per kernel invocation the render ran with ([`regen`]).
    pub paths_per_invocation: u32,
    /// How its kernels read their read-only buffers ([`reads`]).
    pub reads: reads::Reads,
    /// True when stopped early by the cancel flag.
    pub interrupted: bool,
}

enum Estimator {
    Pt(pt::PathTracer),
    Bidir(Box<bidir::Bidir>),
    El(Kernel, u32),
}

impl Estimator {
    fn record(&self, batch: &mut Batch, iteration: u32) -> Result<()> {
        match self {
            Estimator::Pt(p) => p.record(batch, iteration),
            Estimator::Bidir(b) => b.record(batch, iteration),
            Estimator::El(k, pixels) => {
                let push = gpu_types::GpuPush::simple(iteration, *pixels);
                batch.dispatch(k, crate::gpu::groups_2d(*pixels, 64), bytemuck::bytes_of(&push))
            }
        }
    }
}

/// Checks the settings, and that every buffer of the render fits the device
/// ([`resources::check`]), before anything is allocated.
fn check_frame(gpu: &Gpu, scene: &Scene, s: &RenderSettings) -> Result<()> {
    if s.frame.max_path_length == 0 {
        bail!("max path length must be at least 1");
    }
    // Light vertices keep their path length in 8 bits (glsl/vcm.glsl) and store at most
    // max_path_length - 1 of them per subpath.
    if s.frame.max_path_length > 256 && !matches!(s.algorithm, Algorithm::El | Algorithm::Pt) {
        bail!("max path length {} is more than the light-vertex store's 256", s.frame.max_path_length);
    }
    if s.connect != bidir::Connect::Path && !matches!(s.algorithm, Algorithm::Bpt | Algorithm::Vcm) {
        bail!(
            "connections to a light-vertex cache ({}) need an estimator that connects vertices (bpt, vcm), not {}",
            s.connect.name(),
            s.algorithm.name()
        );
    }
    if s.connect == bidir::Connect::Cache(0) {
        bail!("the light-vertex cache needs at least 1 connection per camera vertex");
    }
    if s.paths_per_invocation == Some(0) {
        bail!("paths per invocation must be at least 1");
    }
    if let Budget::Iterations(0) = s.budget {
        bail!("iterations must be at least 1");
    }
    resources::check(gpu, scene, s)
}

/// Renders `scene`. `progress` is called after every batch of iterations; `cancel`
/// stops the render after the current batch (the image so far is returned).
pub fn render(
    gpu: &Arc<Gpu>,
    scene: &Scene,
    settings: &RenderSettings,
    cancel: Option<&AtomicBool>,
    progress: &mut dyn FnMut(&Progress),
) -> Result<RenderOutput> {
    let mut r = Renderer::new(gpu, scene, settings)?;
    r.run(settings.budget, cancel, progress)?;
    r.output()
}

/// A render in progress: the pipelines, scene buffers and film of one scene and setting,
/// kept between calls to [`Renderer::run`] so that a render can be continued, sampled at
/// checkpoints (`vkvcm converge`) or resumed from saved sums.
pub struct Renderer {
    settings: RenderSettings,
    // Field order is drop order: the estimator's kernels before the buffers they bind.
    est: Estimator,
    film: Film,
    _scene_gpu: SceneGpu,
    features: features::FeatureSet,
    /// Paths per kernel invocation (path regeneration, [`regen`]).
    paths_per_invocation: u32,
    batch: Batch,
    profile: Profile,
    /// Iterations accumulated in the film (including resumed ones).
    done: u64,
    /// Iterations per submit, adapted to about a quarter second and kept between runs.
    per_batch: u64,
    /// Rejected samples and overflowing splats of a resumed render (the film counts anew).
    prior_rejected: (u64, u64),
    /// Wall-clock seconds spent in `run` (plus those of a resumed render).
    seconds: f64,
    interrupted: bool,
}

impl Renderer {
    /// Uploads the scene and builds the estimator's kernels; `settings.budget` is only
    /// checked here (each [`Renderer::run`] call takes its own budget).
    pub fn new(gpu: &Arc<Gpu>, scene: &Scene, settings: &RenderSettings) -> Result<Renderer> {
        check_frame(gpu, scene, settings)?;
        let frame = &settings.frame;
        let features = features::FeatureSet::new(scene, settings.algorithm, settings.generic)
            .with_count_rays(settings.count_rays)
            .with_connect(settings.connect);
        let reads = reads::Reads::resolve(gpu, settings.reads);
        let scene_gpu = SceneGpu::with_features(gpu, scene, frame, &features, reads)?;
        let film = Film::new(gpu, frame.width, frame.height)?;
        let pixels = frame.width * frame.height;
        let k = regen::resolve(gpu, settings.algorithm, settings.paths_per_invocation, pixels);
        let est = match settings.algorithm {
            Algorithm::Pt => Estimator::Pt(pt::PathTracer::new(gpu, &scene_gpu, &film, settings.nee, k)?),
            Algorithm::Lt | Algorithm::Bpt | Algorithm::Ppm | Algorithm::Bpm | Algorithm::Vcm => {
                let mode = match settings.algorithm {
                    Algorithm::Lt => bidir::BidirMode::LightTracing,
                    Algorithm::Bpt => bidir::BidirMode::Bpt,
                    Algorithm::Ppm => bidir::BidirMode::Ppm,
                    Algorithm::Bpm => bidir::BidirMode::Bpm,
                    _ => bidir::BidirMode::Vcm,
                };
                let schedule = radius::RadiusSchedule::new(
                    settings.radius_factor,
                    scene_gpu.params.scene_sphere[3],
                    settings.alpha,
                );
                let config = bidir::BidirConfig {
                    mode,
                    max_path_length: frame.max_path_length,
                    radius: schedule,
                    connect: settings.connect,
                    paths_per_invocation: k,
                };
                Estimator::Bidir(Box::new(bidir::Bidir::new(gpu, &scene_gpu, &film, config)?))
            }
            Algorithm::El => {
                let defines = scene_gpu::define_refs(&scene_gpu.defines);
                let k = gpu.kernel_with("el.comp", &defines, &scene_gpu.bindings(&[&film.accum, &film.stats]))?;
                Estimator::El(k, pixels)
            }
        };
        Ok(Renderer {
            settings: settings.clone(),
            paths_per_invocation: k,
            est,
            film,
            _scene_gpu: scene_gpu,
            features,
            batch: gpu.batch()?,
            profile: Profile::default(),
            done: 0,
            per_batch: 1,
            prior_rejected: (0, 0),
            seconds: 0.0,
            interrupted: false,
        })
    }

    /// Iterations accumulated so far.
    pub fn iterations(&self) -> u64 {
        self.done
    }

    /// Wall-clock seconds rendered so far.
    pub fn seconds(&self) -> f64 {
        self.seconds
    }

    /// Paths per kernel invocation (path regeneration, [`regen`]).
    pub fn paths_per_invocation(&self) -> u32 {
        self.paths_per_invocation
    }

    /// How the kernels read their read-only buffers ([`reads`]).
    pub fn reads(&self) -> reads::Reads {
        self._scene_gpu.reads
    }

    /// What the kernels were compiled with.
    pub fn features(&self) -> &features::FeatureSet {
        &self.features
    }

    /// `(name, bytes)` of every buffer the render allocated.
    pub fn buffers(&self) -> Vec<(String, u64)> {
        let mut b: Vec<&crate::gpu::Buffer> = self._scene_gpu.buffers.iter().collect();
        b.extend([&self.film.accum, &self.film.stats]);
        if let Estimator::Bidir(bd) = &self.est {
            b.extend(bd.buffers());
        }
        b.iter().map(|b| (b.name().to_string(), b.size())).collect()
    }

    /// The settings this renderer was built with.
    pub fn settings(&self) -> &RenderSettings {
        &self.settings
    }

    /// Replaces the film with saved per-pixel sums of `iterations` iterations (see
    /// [`RenderOutput::sum`]); the next iteration continues the same random sequences and
    /// radius schedule, so resuming gives the image an uninterrupted render would.
    pub fn resume(&mut self, sum: &[[f64; 3]], sum_sq: &[[f64; 3]], iterations: u64, seconds: f64) -> Result<()> {
        self.film.load_sums(sum, sum_sq)?;
        self.done = iterations;
        self.seconds = seconds;
        Ok(())
    }

    /// Continues a render saved by [`saved::write_render_exr`]; the caller has checked
    /// [`saved::SavedRender::check_matches`].
    pub fn resume_saved(&mut self, saved: &saved::SavedRender) -> Result<()> {
        self.resume(&saved.sum, &saved.sum_sq, saved.iterations, saved.seconds)?;
        self.prior_rejected = (saved.rejected_samples, saved.overflow_splats);
        Ok(())
    }

    /// Renders more iterations until `budget` (counted from this call) is spent or
    /// `cancel` is set. `progress` is called after every batch.
    pub fn run(
        &mut self,
        budget: Budget,
        cancel: Option<&AtomicBool>,
        progress: &mut dyn FnMut(&Progress),
    ) -> Result<()> {
        self.run_slice(budget, None, cancel, progress)
    }

    /// [`Renderer::run`] that also returns after the batch that passes `slice_seconds`
    /// of wall-clock time (checkpoints: call it again to continue; 0 returns after one
    /// batch, whose size does not depend on the slice). Errors say which
    /// iterations of which estimator failed; the film then holds an unknown state, but
    /// every earlier [`Renderer::output`] stays valid.
    pub fn run_slice(
        &mut self,
        budget: Budget,
        slice_seconds: Option<f64>,
        cancel: Option<&AtomicBool>,
        progress: &mut dyn FnMut(&Progress),
    ) -> Result<()> {
        let start = Instant::now();
        let mut done: u64 = 0;
        // Aim for batches of about a quarter second: few submits, responsive progress.
        const TARGET_BATCH_SECONDS: f64 = 0.25;
        // Seconds this call may run: the budget's or the slice's, whichever is shorter.
        // Only the budget shortens batches; a slice ends after the batch that passes it.
        let budget_seconds = match budget {
            Budget::Seconds(t) => Some(t),
            Budget::Iterations(_) => None,
        };
        let limit = match (budget_seconds, slice_seconds) {
            (Some(t), Some(s)) => Some(t.min(s)),
            (t, s) => t.or(s),
        };
        loop {
            let remaining = match budget {
                Budget::Iterations(n) => n.saturating_sub(done),
                Budget::Seconds(_) => self.per_batch,
            };
            if remaining == 0 || (done > 0 && limit.is_some_and(|t| start.elapsed().as_secs_f64() >= t)) {
                break;
            }
            if cancel.is_some_and(|c| c.load(Ordering::Relaxed)) {
                self.interrupted = true;
                break;
            }
            let n = remaining.min(self.per_batch);
            let first = self.done;
            if first + n > u32::MAX as u64 {
                bail!("more than {} iterations: the iteration index would wrap", u32::MAX);
            }
            let t0 = Instant::now();
            let what = || {
                let last = first + n - 1;
                let range = if n == 1 { format!("iteration {first}") } else { format!("iterations {first}-{last}") };
                format!("{range} of {}", self.settings.algorithm.name())
            };
            for i in 0..n {
                self.est.record(&mut self.batch, (first + i) as u32).with_context(what)?;
            }
            self.batch.submit_wait(Some(&mut self.profile)).with_context(what)?;
            done += n;
            self.done += n;
            let dt = t0.elapsed().as_secs_f64().max(1e-6);
            self.seconds += dt;
            self.profile.add_iterations(n, dt);
            let per_iter = dt / n as f64;
            self.per_batch = ((TARGET_BATCH_SECONDS / per_iter) as u64).clamp(1, 256);
            if let Some(t) = budget_seconds {
                let left = t - start.elapsed().as_secs_f64();
                self.per_batch = self.per_batch.min(((left / per_iter).ceil() as u64).max(1));
            }
            let seconds = start.elapsed().as_secs_f64();
            let fraction = match budget {
                Budget::Iterations(n) => done as f64 / n as f64,
                Budget::Seconds(t) => (seconds / t).min(1.0),
            };
            progress(&Progress { iterations: self.done, seconds: self.seconds, fraction });
        }
        Ok(())
    }

    /// The image so far (reads the film back; the render can continue afterwards).
    pub fn output(&self) -> Result<RenderOutput> {
        let (sum, sum_sq) = self.film.sums().context("reading the film back")?;
        let k = 1.0 / self.done.max(1) as f64;
        let pixels = sum.iter().map(|p| p.map(|v| (v * k) as f32)).collect();
        let (rejected, overflow) = self.film.rejected().context("reading the film's counters back")?;
        let (rejected_samples, overflow_splats) = (rejected + self.prior_rejected.0, overflow + self.prior_rejected.1);
        let mut profile = self.profile.clone();
        if self.settings.count_rays {
            // glsl/scene.glsl COUNT_RAYS_FLUSH: a 64-bit count in film_stats[2..4].
            let s = self.film.stats.read::<u32>().context("reading the ray count back")?;
            profile.rays = Some(s[2] as u64 | (s[3] as u64) << 32);
        }
        Ok(RenderOutput {
            width: self.settings.frame.width,
            height: self.settings.frame.height,
            pixels,
            sum,
            sum_sq,
            iterations: self.done,
            seconds: self.seconds,
            rejected_samples,
            overflow_splats,
            profile,
            paths_per_invocation: self.paths_per_invocation,
            reads: self._scene_gpu.reads,
            interrupted: self.interrupted,
        })
    }
}
