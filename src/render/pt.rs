//! Path tracing (`pt`): one kernel, `paths_per_invocation` pixel samples per invocation
//! (glsl/pt.comp, src/render/regen.rs).

use std::sync::Arc;

use anyhow::Result;

use super::film::Film;
use super::gpu_types::GpuPush;
use super::regen;
use super::scene_gpu::{define_refs, SceneGpu};
use crate::gpu::{groups_2d, Batch, Gpu, Kernel};

pub struct PathTracer {
    kernel: Kernel,
    pixels: u32,
    /// Paths per invocation (src/render/regen.rs).
    paths_per_invocation: u32,
}

impl PathTracer {
    /// `nee: false` builds the BSDF-sampling-only variant (a test reference).
    pub fn new(
        gpu: &Arc<Gpu>,
        scene: &SceneGpu,
        film: &Film,
        nee: bool,
        paths_per_invocation: u32,
    ) -> Result<PathTracer> {
        let mut defines = scene.defines.clone();
        defines.push(("NEE".into(), if nee { "1" } else { "0" }.into()));
        let kernel =
            gpu.kernel_with("pt.comp", &define_refs(&defines), &scene.bindings(&[&film.accum, &film.stats]))?;
        Ok(PathTracer { kernel, pixels: film.width * film.height, paths_per_invocation })
    }

    pub fn record(&self, batch: &mut Batch, iteration: u32) -> Result<()> {
        let k = self.paths_per_invocation;
        let push = GpuPush { paths_per_invocation: k, ..GpuPush::simple(iteration, self.pixels) };
        batch.dispatch(&self.kernel, groups_2d(regen::invocations(self.pixels, k), 64), bytemuck::bytes_of(&push))
    }
}
