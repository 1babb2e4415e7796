//! The light-subpath estimators (lt, bpt, ppm, bpm, vcm): one pass sequence, with the
//! passes and kernel switches each estimator's [`Techniques`] turn on. Per iteration, as
//! SmallVCM's VertexCM::RunIteration:
//!
//! 1. light subpaths (src/render/passes/light_subpaths.rs, glsl/light_subpath.comp): N_L
//!    of them (one per pixel, SmallVCM's choice, unless `--light-paths`), traced in
//!    chunks, their vertices compacted into the light-vertex store
//!    (src/render/light_vertex_store.rs) and/or connected to the camera;
//! 2. grid build (passes/hash_grid.rs), when merging: the hash grid over the stored
//!    vertices for this iteration's radius;
//! 3. camera subpaths (passes/camera_subpaths.rs, glsl/camera_subpath.comp), one per
//!    pixel, with the connections (to light subpath p = this pixel, or with
//!    `--connect cache` to vertices drawn from the whole store) and merges the techniques
//!    ask for; it adds each pixel's value and splats to the film; or, for lt (no camera
//!    pass), accumulate (passes/accumulate.rs): splats to the film.
//!
//! The MIS factors of an iteration (eta = pi r^2 N_L, glsl/subpath.glsl) follow from the
//! techniques: connections weigh against merges only when both are on. After each batch
//! the estimator checks its light-vertex store and grows it when an iteration did not fit
//! ([`Estimator::finish_batch`]).

use anyhow::{Context, Result};

use super::{BatchEnd, Build, Estimator, Techniques};
use crate::gpu::{Batch, Buffer};
use crate::render::gpu_types::GpuPush;
use crate::render::light_vertex_store::{LightVertexStore, StoreCounters, StoreUse};
use crate::render::passes::accumulate::Accumulate;
use crate::render::passes::camera_subpaths::{CameraKernel, CameraSubpaths};
use crate::render::passes::hash_grid::HashGrid;
use crate::render::passes::light_subpaths::{LightKernel, LightSubpaths};
use crate::render::passes::PassInfo;
use crate::render::plan::FramePlan;
use crate::render::radius::RadiusSchedule;
use crate::render::settings::Sampler;

/// Builds the light-subpath estimator of `b`'s settings with its registry techniques
/// (src/render/settings.rs: LT, BPT, PPM, BPM, VCM).
pub fn build(b: &Build) -> Result<Box<dyn Estimator>> {
    let techniques = b.settings.algorithm.info().techniques;
    let s = b.scene.params.scene_sphere;
    Ok(Box::new(LightSubpathEstimator {
        techniques,
        radius: RadiusSchedule::new(b.settings.radius_factor, s[3], b.settings.alpha),
        grid_origin: [s[0] - s[3], s[1] - s[3], s[2] - s[3]],
        pixels: b.plan.pixels,
        light_paths: b.plan.light_paths,
        paths_per_invocation: b.plan.paths_per_invocation,
        passes: Some(Passes::new(b, techniques)?),
        plan: b.plan.clone(),
        store_counters: StoreCounters::default(),
    }))
}

/// A light-subpath estimator built for one render.
pub struct LightSubpathEstimator {
    techniques: Techniques,
    radius: RadiusSchedule,
    grid_origin: [f32; 3],
    pixels: u32,
    light_paths: u32,
    paths_per_invocation: u32,
    /// None only while the light-vertex store is being grown.
    passes: Option<Passes>,
    /// The plan its passes were built from (the store's capacity grows).
    plan: FramePlan,
    store_counters: StoreCounters,
}

/// The pass that takes the splats (and, with a camera pass, the camera subpaths' values)
/// into the film.
enum FilmPass {
    Camera(CameraSubpaths),
    Accumulate(Accumulate),
}

/// The passes and the light-vertex store they share.
struct Passes {
    // Field order is drop order: each pass's kernels before the buffers they bind.
    film_pass: FilmPass,
    light: LightSubpaths,
    grid: Option<HashGrid>,
    store: LightVertexStore,
}

impl Passes {
    /// The passes of `techniques` for the render `b`; the buffers are `b.plan`'s.
    fn new(b: &Build, techniques: Techniques) -> Result<Passes> {
        let lv = b.plan.light_vertices.as_ref().expect("a light-subpath estimator's plan has a light-vertex store");
        let store = LightVertexStore::new(b.gpu, lv, &b.film.addresses)?;
        let grid = match &b.plan.grid {
            Some(g) => Some(HashGrid::with_plan(b.gpu, &store.vertices_a, &store.offsets, g, &b.film.addresses)?),
            None => None,
        };
        let pass = b.passes();
        let light = LightSubpaths::new(&pass, &store, lv, LightKernel::new(techniques))?;
        let film_pass = if techniques.light_trace_only {
            FilmPass::Accumulate(Accumulate::new(&pass, &store)?)
        } else {
            let sobol = b.settings.sampler() == Sampler::Sobol;
            let camera_kernel = CameraKernel::new(techniques, b.settings.connect, b.plan.store_reads, sobol);
            FilmPass::Camera(CameraSubpaths::bidirectional(&pass, &store, grid.as_ref(), camera_kernel)?)
        };
        Ok(Passes { film_pass, light, grid, store })
    }
}

impl LightSubpathEstimator {
    fn passes_built(&self) -> &Passes {
        self.passes.as_ref().expect("the passes are rebuilt before the estimator is used again")
    }

    /// Rebuilds the passes with a light-vertex store for iterations that store `needed`
    /// vertices (and a margin), after checking the grown plan against the device. The old
    /// store is freed first.
    fn grow_light_vertex_store(&mut self, b: &Build, needed: u64) -> Result<String> {
        let f = &b.settings.frame;
        let what = format!(
            "a {}x{} {} render whose iterations store up to {needed} light vertices ({} light subpaths)",
            f.width,
            f.height,
            b.settings.algorithm.name(),
            self.light_paths
        );
        let plan = self.plan.grown(b.gpu, needed, &what)?;
        self.passes = None;
        let passes = Passes::new(&Build { plan: &plan, ..*b }, self.techniques);
        self.passes = Some(passes.context("growing the light-vertex store")?);
        self.plan = plan;
        let capacity = self.plan.light_vertices.as_ref().map_or(0, |lv| lv.capacity);
        Ok(format!("light-vertex store grown to {capacity} vertices (an iteration stored {needed})"))
    }
}

impl Estimator for LightSubpathEstimator {
    fn record(&self, batch: &mut Batch, iteration: u32) -> Result<()> {
        let passes = self.passes_built();
        let i = iteration as u64;
        let t = self.techniques;
        let (mis_vm, mis_vc) = self.radius.mis_factors(i, self.light_paths, t.vertex_connection, t.vertex_merging);
        let radius = self.radius.radius(i);
        let mut push = GpuPush {
            iteration,
            count: self.light_paths,
            mis_vm,
            mis_vc,
            radius,
            light_paths: self.light_paths,
            grid_buckets: passes.grid.as_ref().map_or(0, |g| g.num_buckets()),
            paths_per_invocation: self.paths_per_invocation,
            first_path: 0,
        };
        passes.light.record(batch, &push)?;
        if let Some(g) = &passes.grid {
            g.record_build(batch, radius, self.grid_origin)?;
        }
        push.count = self.pixels;
        match &passes.film_pass {
            FilmPass::Camera(c) => c.record(batch, &push),
            FilmPass::Accumulate(a) => a.record(batch, &push),
        }
    }

    fn passes(&self) -> Vec<PassInfo> {
        let passes = self.passes_built();
        let mut v = vec![passes.light.info()];
        if let Some(g) = &passes.grid {
            v.push(g.info());
        }
        v.push(match &passes.film_pass {
            FilmPass::Camera(c) => c.info(),
            FilmPass::Accumulate(a) => a.info(),
        });
        v
    }

    fn buffers(&self) -> Vec<&Buffer> {
        let passes = self.passes_built();
        let mut b = passes.store.buffers();
        if let Some(g) = &passes.grid {
            b.extend(g.buffers());
        }
        b.extend(passes.light.buffers());
        b
    }

    fn finish_batch(&mut self, b: &Build, first: u64, n: u64) -> Result<BatchEnd> {
        if !self.techniques.store_vertices {
            return Ok(BatchEnd { accepted: n, note: None });
        }
        let status = self.passes_built().store.status()?;
        let (accepted, overflow) = self.store_counters.after_batch(status, first, n);
        let Some(needed) = overflow else {
            return Ok(BatchEnd { accepted, note: None });
        };
        let grown = self.grow_light_vertex_store(b, needed)?;
        let note = format!("{grown}; iterations {}-{} rendered again", first + accepted, first + n - 1);
        Ok(BatchEnd { accepted, note: Some(note) })
    }

    fn light_vertex_store_use(&self) -> Option<StoreUse> {
        let lv = self.plan.light_vertices.as_ref().filter(|lv| lv.store_vertices)?;
        Some(self.store_counters.store_use(lv))
    }
}
