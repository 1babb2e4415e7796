//! Path tracing (`pt`): BSDF sampling with next-event estimation, combined by the
//! balance heuristic (`--nee false`: BSDF sampling only, a test reference). One pass: the
//! camera kernel glsl/pt.comp, `paths_per_invocation` pixel samples per invocation (path
//! regeneration, src/render/regen.rs).

use anyhow::Result;

use super::{Build, Estimator};
use crate::gpu::{Batch, Buffer};
use crate::render::gpu_types::GpuPush;
use crate::render::passes::camera_subpaths::CameraSubpaths;
use crate::render::passes::camera_subpaths::PtKernel;
use crate::render::passes::PassInfo;
use crate::render::settings::Sampler;

struct PathTracer {
    camera: CameraSubpaths,
    paths_per_invocation: u32,
}

pub fn build(b: &Build) -> Result<Box<dyn Estimator>> {
    let camera = CameraSubpaths::path_tracer(
        &b.passes(),
        PtKernel { nee: b.settings.nee, sobol: b.settings.sampler() == Sampler::Sobol },
    )?;
    Ok(Box::new(PathTracer { camera, paths_per_invocation: b.plan.paths_per_invocation }))
}

impl Estimator for PathTracer {
    fn record(&self, batch: &mut Batch, iteration: u32) -> Result<()> {
        let push = GpuPush {
            paths_per_invocation: self.paths_per_invocation,
            ..GpuPush::simple(iteration, self.camera.pixels())
        };
        self.camera.record(batch, &push)
    }

    fn passes(&self) -> Vec<PassInfo> {
        vec![self.camera.info()]
    }

    fn buffers(&self) -> Vec<&Buffer> {
        Vec::new()
    }
}
