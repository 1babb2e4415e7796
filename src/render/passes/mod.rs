//! The passes an iteration is made of, shared by the estimators (src/render/estimators/).
//! Each pass owns its kernels, records its dispatches under its `NAME` (the name
//! `--profile` reports, `Batch::begin_pass`), and allocates its buffers from the frame's
//! plan of sizes (src/render/plan.rs), whose part it defines next to its code.
//!
//! | pass | module | kernels |
//! |---|---|---|
//! | light subpaths | [`light_subpaths`] | light_subpath.comp, exclusive_scan.comp, light_vertex_compact.comp |
//! | grid build | [`hash_grid`] | hash_grid_count.comp, exclusive_scan.comp, hash_grid_scatter.comp, hash_grid_sort.comp |
//! | camera subpaths | [`camera_subpaths`] | camera_subpath.comp, pt.comp or el.comp |
//! | accumulate | [`accumulate`] | accumulate.comp |
//!
//! [`exclusive_scan`] is a building block of two of them.

pub mod accumulate;
pub mod camera_subpaths;
pub mod exclusive_scan;
pub mod hash_grid;
pub mod light_subpaths;

use std::sync::Arc;

use super::film::Film;
use super::scene_gpu::SceneGpu;
use crate::gpu::Gpu;

/// What the passes of a render are built from: the device, the scene and film they
/// bind, and the counts of the frame's plan (src/render/plan.rs).
pub struct PassContext<'a> {
    pub gpu: &'a Arc<Gpu>,
    pub scene: &'a SceneGpu,
    pub film: &'a Film,
    pub pixels: u32,
    /// Light subpaths per iteration (N_L).
    pub light_paths: u32,
    /// Paths per invocation of the kernels that regenerate paths (src/render/regen.rs).
    pub paths_per_invocation: u32,
}

/// A pass as `vkvcm render --verbose` describes it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PassInfo {
    /// The name profiles report.
    pub name: &'static str,
    /// What it does in this render.
    pub detail: String,
}
