//! Rendering: a scene, a film and an estimator's passes, run iteration by iteration
//! (docs/architecture.md). One iteration = one sample per pixel.
//!
//! * [`settings`]: what a render is asked for; [`estimators`]: the registry and one module
//!   per estimator; [`passes`]: the passes they are made of; [`plan`]: every buffer's
//!   size, checked before allocation; [`variants`]: what each kernel is compiled with;
//!   [`scene_gpu`], [`film`]: the buffers every pass binds.
//! * [`Renderer`] runs a render in batches of iterations and reads the film back.

pub mod addresses;
pub mod albedo_tables;
pub mod aov;
pub mod atomics;
pub mod converge;
pub mod devices;
pub mod environment;
pub mod estimators;
pub mod features;
pub mod film;
pub mod ggx_albedo;
pub mod gpu_types;
pub mod light_selection;
pub mod light_tree;
pub mod light_vertex_store;
pub mod merge;
pub mod output;
pub mod passes;
pub mod plan;
pub mod radius;
pub mod reads;
pub mod reference;
pub mod regen;
pub mod saved;
pub mod scene_gpu;
pub mod settings;
pub mod shard;
pub mod sheen_albedo;
pub mod sizes;
pub mod techniques;
pub mod variants;

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

use anyhow::{bail, Context, Result};

use crate::gpu::{Batch, Gpu, Profile};
use crate::scene::Scene;
pub use estimators::{BatchEnd, Estimator};
pub use film::Film;
use light_vertex_store::LightVertexSizing;
pub use light_vertex_store::StoreUse;
pub use output::{Progress, RenderOutput};
pub use scene_gpu::SceneGpu;
pub use settings::{
    Algorithm, Budget, Connect, FrameSettings, LightSelection, RenderSettings, Sampler, DEFAULT_CACHE_CONNECTIONS,
    DEFAULT_LIGHT_SELECTION,
};

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
    est: Box<dyn Estimator>,
    film: Film,
    scene_gpu: SceneGpu,
    plan: plan::FramePlan,
    batch: Batch,
    gpu: Arc<Gpu>,
    profile: Profile,
    /// Iterations accumulated in the film (including resumed ones): `held.len()`.
    done: u64,
    /// The global indices of the iterations in the film (src/render/shard.rs).
    held: shard::IterationSet,
    /// The global index of the next iteration to render.
    next: u64,
    /// Iterations per submit, adapted to about a quarter second and kept between runs.
    per_batch: u64,
    /// What a resumed render rejected (the film counts anew).
    prior_rejected: film::Rejected,
    /// Wall-clock seconds spent in `run` (plus those of a resumed render).
    seconds: f64,
    interrupted: bool,
}

impl Renderer {
    /// Checks the settings and the plan of sizes against the device, uploads the scene
    /// and builds the estimator's passes; `settings.budget` is only checked here (each
    /// [`Renderer::run`] call takes its own budget).
    pub fn new(gpu: &Arc<Gpu>, scene: &Scene, settings: &RenderSettings) -> Result<Renderer> {
        let frame = &settings.frame;
        let plan = Self::plan_for(gpu, scene, settings)?;
        let features = features::FeatureSet::new(scene, settings.generic).with_count_rays(settings.count_rays);
        // The plan's reads, which it checked (it reads from storage what exceeds a texel limit).
        let reads = plan.reads;
        let atomics = atomics::SplatAtomics::resolve(gpu, settings.atomics)?;
        let scene_gpu = SceneGpu::with_features(gpu, scene, frame, &features, reads, atomics, plan.scene.chunk_bytes)?;
        let mut film = Film::new(gpu, &plan.film)?;
        if let Some(size) = &plan.film.aov {
            film.aov = Some(aov::Aovs::new(gpu, settings.aov, size, scene.report.origin)?);
        }
        let est = settings.algorithm.build(&estimators::Build {
            gpu,
            scene: &scene_gpu,
            film: &film,
            settings,
            plan: &plan,
        })?;
        // Every kernel of the render exists now: keep their pipelines for later processes
        // even if this one does not end normally.
        gpu.save_pipeline_cache();
        let mut batch = gpu.batch()?;
        let budget =
            settings.submission_budget_ms.or_else(|| crate::gpu::default_submission_budget_ms(gpu.info.device_type));
        batch.set_budget(budget);
        Ok(Renderer {
            settings: settings.clone(),
            est,
            film,
            scene_gpu,
            plan,
            batch,
            gpu: gpu.clone(),
            profile: Profile::default(),
            done: 0,
            held: shard::IterationSet::new(),
            next: 0,
            per_batch: 1,
            prior_rejected: film::Rejected::default(),
            seconds: 0.0,
            interrupted: false,
        })
    }

    /// The plan of sizes of a render of `scene` with `settings` on `gpu`, checked against
    /// the device: what [`Renderer::new`] allocates, refused before anything is.
    pub fn plan_for(gpu: &Gpu, scene: &Scene, settings: &RenderSettings) -> Result<plan::FramePlan> {
        let plan = Self::plan_sizes(gpu, scene, settings)?;
        let (frame, info) = (&settings.frame, settings.algorithm.info());
        plan.check(gpu, &format!("a {}x{} {} render", frame.width, frame.height, info.name))?;
        Ok(plan)
    }

    /// The plan of sizes [`Renderer::plan_for`] checks, before that check: what
    /// `vkvcm info` shows of a frame that may not fit the device.
    pub fn plan_sizes(gpu: &Gpu, scene: &Scene, settings: &RenderSettings) -> Result<plan::FramePlan> {
        let info = settings.algorithm.info();
        let frame = &settings.frame;
        settings.check()?;
        let pixels = frame.width.saturating_mul(frame.height);
        let k = regen::resolve(gpu, info.regenerates_paths, settings.paths_per_invocation, pixels);
        let features = features::FeatureSet::new(scene, settings.generic);
        let reads = reads::Reads::resolve(gpu, settings.reads)?;
        let device_addresses = gpu.has(crate::gpu::BUFFER_DEVICE_ADDRESS);
        // A scratch half is bound (at most one binding) where the device has no addresses.
        let scratch_limit = if device_addresses { u64::MAX } else { gpu.limits.max_storage_buffer_range as u64 };
        let light_sizing = LightVertexSizing {
            scratch_limit,
            chunk_paths: settings.light_chunk_paths,
            capacity: settings.light_vertex_capacity,
        };
        let light_k = |chunk: u32| regen::resolve(gpu, info.regenerates_paths, settings.paths_per_invocation, chunk);
        let mut plan = plan::FramePlan::new(
            scene,
            settings,
            info.techniques,
            k,
            &features,
            reads,
            device_addresses,
            light_sizing,
            light_k,
        )?;
        plan.reads_chosen = settings.reads.is_none();
        let limits = sizes::SizeLimits::of(gpu);
        plan.scene.chunk_if_over_binding(&limits, device_addresses);
        plan.read_from_storage_where_over(scene, &limits);
        plan.fit_light_vertex_capacity(&limits);
        Ok(plan)
    }

    /// Keep every timed dispatch from now on, for [`Renderer::take_dispatches`].
    pub fn trace_dispatches(&mut self) {
        self.profile.dispatches = Some(Vec::new());
    }

    /// The dispatches kept since [`Renderer::trace_dispatches`] (and the last take).
    pub fn take_dispatches(&mut self) -> Vec<crate::gpu::DispatchEvent> {
        self.profile.dispatches.as_mut().map(std::mem::take).unwrap_or_default()
    }

    /// Iterations accumulated so far.
    pub fn iterations(&self) -> u64 {
        self.done
    }

    /// Wall-clock seconds rendered so far.
    pub fn seconds(&self) -> f64 {
        self.seconds
    }

    /// Queue submissions so far: one per batch of iterations, more where the submission
    /// budget split them (src/gpu/batch.rs).
    pub fn submissions(&self) -> u64 {
        self.batch.submissions()
    }

    /// Whether a submission budget is in force ([`RenderSettings::submission_budget_ms`]; it
    /// needs timestamp queries).
    pub fn has_submission_budget(&self) -> bool {
        self.batch.has_budget()
    }

    /// Paths per kernel invocation (path regeneration, [`regen`]).
    pub fn paths_per_invocation(&self) -> u32 {
        self.plan.paths_per_invocation
    }

    /// How the kernels read their read-only buffers ([`reads`]).
    pub fn reads(&self) -> reads::Reads {
        self.scene_gpu.reads()
    }

    /// How the camera kernel first reads the light-vertex store and the hash grid (a store
    /// grown past a texel limit is read from storage, when the reads were chosen).
    pub fn store_reads(&self) -> reads::Reads {
        self.plan.store_reads
    }

    /// How splats are summed (src/render/atomics.rs).
    pub fn atomics(&self) -> atomics::SplatAtomics {
        self.scene_gpu.variant.atomics
    }

    /// The scene features the kernels were compiled with.
    pub fn features(&self) -> &features::FeatureSet {
        &self.scene_gpu.variant.features
    }

    /// The passes of an iteration.
    pub fn passes(&self) -> Vec<passes::PassInfo> {
        self.est.passes()
    }

    /// How the light-vertex store was used so far (None: the estimator stores no light
    /// vertices).
    pub fn light_vertex_store_use(&self) -> Option<StoreUse> {
        self.est.light_vertex_store_use()
    }

    /// What the kernels were compiled with and the passes of an iteration
    /// (`vkvcm render --verbose`).
    pub fn describe(&self) -> String {
        let info = self.settings.algorithm.info();
        let mut s = format!("estimator {}: {}\n{}\n", info.name, info.description, self.features());
        if info.default_connect.is_some() {
            let c = match self.settings.connect {
                Connect::Path => "to the vertices of light subpath p = this pixel (--connect path)".to_string(),
                Connect::Cache(n) => {
                    format!("to {n} light vertex(es) per camera vertex drawn from all light subpaths (--connect cache)")
                }
            };
            s += &format!("  vertex connections: {c}\n");
        }
        s += "  passes per iteration:\n";
        for p in self.passes() {
            s += &format!("    {}: {}\n", p.name, p.detail);
        }
        let defines: Vec<String> =
            self.scene_gpu.variant.defines().list().iter().map(|(k, v)| format!("{k}={v}")).collect();
        s + &format!("  scene defines of every kernel: {}", defines.join(" "))
    }

    /// `(name, bytes)` of every buffer the render allocated.
    pub fn buffers(&self) -> Vec<(String, u64)> {
        let mut b: Vec<&crate::gpu::Buffer> = self.scene_gpu.buffers.iter().chain(&self.scene_gpu.chunks).collect();
        b.extend([&self.film.accum, &self.film.stats]);
        b.extend(self.film.aov.as_ref().map(|a| &a.sums));
        b.extend(self.est.buffers());
        b.iter().map(|b| (b.name().to_string(), b.size())).collect()
    }

    /// The settings this renderer was built with.
    pub fn settings(&self) -> &RenderSettings {
        &self.settings
    }

    /// Replaces the film with saved sums of the iterations `held`; the next iteration is
    /// the one after the last held, continuing the same random sequences and radius
    /// schedule, so resuming gives the bits an uninterrupted render would.
    pub fn resume(&mut self, sums: &film::FilmSums, held: &shard::IterationSet, seconds: f64) -> Result<()> {
        self.film.load_sums(sums)?;
        self.done = held.len();
        self.held = held.clone();
        self.next = held.end();
        self.seconds = seconds;
        Ok(())
    }

    /// Continues a render saved by [`saved::write_render_exr`]; the caller has checked
    /// [`saved::SavedRender::check_matches`].
    pub fn resume_saved(&mut self, saved: &saved::SavedRender) -> Result<()> {
        self.resume(&saved.sums, &saved.held, saved.seconds)?;
        self.prior_rejected = saved.rejected;
        Ok(())
    }

    /// Renders from the global iteration `index` on (a shard's first, or where a device
    /// took its next block of iterations: src/render/shard.rs); the film keeps what it holds.
    pub fn start_at(&mut self, index: u64) {
        self.next = index;
    }

    /// The global indices of the iterations in the film.
    pub fn held(&self) -> &shard::IterationSet {
        &self.held
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
            let first = self.next;
            if first + n > u32::MAX as u64 {
                bail!("more than {} iterations: the iteration index would wrap", u32::MAX);
            }
            let t0 = Instant::now();
            let name = self.settings.algorithm.name();
            let what = || {
                let last = first + n - 1;
                let range = if n == 1 { format!("iteration {first}") } else { format!("iterations {first}-{last}") };
                format!("{range} of {name}")
            };
            for i in 0..n {
                self.batch.set_iteration(first + i);
                self.est.record(&mut self.batch, (first + i) as u32).with_context(what)?;
            }
            self.batch.submit_wait(Some(&mut self.profile)).with_context(what)?;
            // An estimator may leave iterations out of the film (the light-vertex store's
            // overflow): they are rendered again in the next batch.
            let b = estimators::Build {
                gpu: &self.gpu,
                scene: &self.scene_gpu,
                film: &self.film,
                settings: &self.settings,
                plan: &self.plan,
            };
            let BatchEnd { accepted, note } = self.est.finish_batch(&b, first, n).with_context(what)?;
            done += accepted;
            self.done += accepted;
            self.held.insert(first..first + accepted).with_context(|| format!("{} already in the film", what()))?;
            self.next += accepted;
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
            progress(&Progress { iterations: self.done, seconds: self.seconds, fraction, note });
        }
        Ok(())
    }

    /// The image so far (reads the film back; the render can continue afterwards).
    pub fn output(&self) -> Result<RenderOutput> {
        let sums = self.film.sums().context("reading the film back")?;
        let (sum, sum_sq) = sums.reals();
        let pixels = sums.mean(self.done);
        let rejected = self.film.rejected().context("reading the film's counters back")? + self.prior_rejected;
        let mut profile = self.profile.clone();
        if self.settings.count_rays {
            // glsl/scene.glsl COUNT_RAYS_FLUSH: a 64-bit count in film_stats[2..4].
            let s = self.film.stats.read::<u32>().context("reading the ray count back")?;
            profile.rays = Some(s[2] as u64 | (s[3] as u64) << 32);
        }
        let aov = self.film.aov.as_ref().map(|a| a.read()).transpose()?;
        Ok(RenderOutput {
            aov,
            width: self.settings.frame.width,
            height: self.settings.frame.height,
            pixels,
            sum,
            sum_sq,
            sums,
            held: self.held.clone(),
            iterations: self.done,
            seconds: self.seconds,
            rejected_samples: rejected.samples,
            overflow_splats: rejected.overflow_splats,
            overflow_samples: rejected.overflow_samples,
            profile,
            paths_per_invocation: self.plan.paths_per_invocation,
            reads: self.scene_gpu.reads(),
            atomics: self.scene_gpu.variant.atomics,
            interrupted: self.interrupted,
        })
    }
}
