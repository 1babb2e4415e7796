//! The pass sequence of the light-subpath estimators (lt, bpt, ppm, bpm, vcm), with the
//! passes each [`Techniques`] turns on. Per iteration:
//!
//! 1. light subpaths (src/render/passes/light_subpaths.rs): N_L of them (one per pixel,
//!    SmallVCM's choice, unless `--light-paths`), traced in chunks, their vertices
//!    compacted into the light-vertex store and/or connected to the camera;
//! 2. grid build (passes/hash_grid.rs), when merging: the hash grid over the stored
//!    vertices for this iteration's radius;
//! 3. camera subpaths (passes/camera_subpaths.rs), one per pixel, with the connections
//!    (to light subpath p = this pixel, or with `--connect cache` to vertices drawn from
//!    the whole store) and merges the techniques ask for; it adds each pixel's value and
//!    splats to the film; or, for lt (no camera pass), accumulate (passes/accumulate.rs):
//!    splats to the film.
//!
//! The MIS factors of an iteration (docs/smallvcm.md, eta = pi r^2 N_L) follow from the
//! techniques: connections weigh against merges only when both are on.

use anyhow::Result;

use super::{Build, Estimator, Techniques};
use crate::gpu::{Batch, Buffer};
use crate::render::gpu_types::GpuPush;
use crate::render::passes::accumulate::Accumulate;
use crate::render::passes::camera_subpaths::{CameraKernel, CameraSubpaths};
use crate::render::passes::hash_grid::HashGrid;
use crate::render::passes::light_subpaths::{LightKernel, LightSubpaths, LightVertexStore, StoreStatus};
use crate::render::passes::PassInfo;
use crate::render::radius::RadiusSchedule;
use crate::render::settings::Sampler;

/// The pass that takes the splats (and, with a camera pass, the camera subpaths' values)
/// into the film.
enum FilmPass {
    Camera(CameraSubpaths),
    Accumulate(Accumulate),
}

/// Builds the light-subpath estimator of `b`'s settings, with its registry techniques
/// (the `build` of lt, bpt, ppm, bpm and vcm).
pub fn build(b: &Build) -> Result<Box<dyn Estimator>> {
    Ok(Box::new(LightSubpathEstimator::new(b, b.settings.algorithm.info().techniques)?))
}

/// A light-subpath estimator built for one render.
pub struct LightSubpathEstimator {
    techniques: Techniques,
    radius: RadiusSchedule,
    grid_origin: [f32; 3],
    pixels: u32,
    light_paths: u32,
    paths_per_invocation: u32,
    // Field order is drop order: each pass's kernels before the buffers they bind.
    film_pass: FilmPass,
    light: LightSubpaths,
    grid: Option<HashGrid>,
    store: LightVertexStore,
}

impl LightSubpathEstimator {
    /// The passes of `techniques` for the render `b`; the buffers are the plan's.
    pub fn new(b: &Build, techniques: Techniques) -> Result<LightSubpathEstimator> {
        let lv = b.plan.light_vertices.as_ref().expect("a light-subpath estimator's plan has a light-vertex store");
        let store = LightVertexStore::new(b.gpu, lv, &b.film.addresses)?;
        let grid = match &b.plan.grid {
            Some(g) => Some(HashGrid::with_plan(b.gpu, &store.vertices_a, &store.offsets, g, &b.film.addresses)?),
            None => None,
        };
        let pass = b.passes();
        let connect = b.settings.connect;
        let sobol = b.settings.sampler() == Sampler::Sobol;
        let light = LightSubpaths::new(&pass, &store, lv, LightKernel::new(techniques))?;
        let film_pass = if techniques.light_trace_only {
            FilmPass::Accumulate(Accumulate::new(&pass, &store)?)
        } else {
            let camera_kernel = CameraKernel::new(techniques, connect, b.scene.reads(), sobol);
            FilmPass::Camera(CameraSubpaths::bidirectional(&pass, &store, grid.as_ref(), camera_kernel)?)
        };
        let s = b.scene.params.scene_sphere;
        Ok(LightSubpathEstimator {
            techniques,
            radius: RadiusSchedule::new(b.settings.radius_factor, s[3], b.settings.alpha),
            grid_origin: [s[0] - s[3], s[1] - s[3], s[2] - s[3]],
            pixels: b.plan.pixels,
            light_paths: b.plan.light_paths,
            paths_per_invocation: b.plan.paths_per_invocation,
            film_pass,
            light,
            grid,
            store,
        })
    }
}

impl Estimator for LightSubpathEstimator {
    fn record(&self, batch: &mut Batch, iteration: u32) -> Result<()> {
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
            grid_buckets: self.grid.as_ref().map_or(0, |g| g.num_buckets()),
            paths_per_invocation: self.paths_per_invocation,
            first_path: 0,
        };
        self.light.record(batch, &push)?;
        if let Some(g) = &self.grid {
            g.record_build(batch, radius, self.grid_origin)?;
        }
        push.count = self.pixels;
        match &self.film_pass {
            FilmPass::Camera(c) => c.record(batch, &push),
            FilmPass::Accumulate(a) => a.record(batch, &push),
        }
    }

    fn passes(&self) -> Vec<PassInfo> {
        let mut v = vec![self.light.info()];
        if let Some(g) = &self.grid {
            v.push(g.info());
        }
        v.push(match &self.film_pass {
            FilmPass::Camera(c) => c.info(),
            FilmPass::Accumulate(a) => a.info(),
        });
        v
    }

    fn buffers(&self) -> Vec<&Buffer> {
        let mut b = self.store.buffers();
        if let Some(g) = &self.grid {
            b.extend(g.buffers());
        }
        b.extend(self.light.buffers());
        b
    }

    fn light_vertex_store(&self) -> Result<Option<StoreStatus>> {
        if !self.techniques.store_vertices {
            return Ok(None);
        }
        Ok(Some(self.store.status()?))
    }
}
