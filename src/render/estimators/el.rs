//! Eye light (`el`): |cos| between the shading normal and the view ray at the first hit,
//! times the surface's tint (base-colour texture and vertex colour, docs/textures.md), a
//! preview and not a radiance estimate (SmallVCM's EyeLight, which has no textures). One pass: the camera
//! kernel glsl/el.comp, one ray per pixel.

use anyhow::Result;

use super::{Algorithm, Build, Estimator, EstimatorInfo, Techniques};
use crate::gpu::{Batch, Buffer};
use crate::render::gpu_types::GpuPush;
use crate::render::passes::camera_subpaths::CameraSubpaths;
use crate::render::passes::PassInfo;

pub const INFO: EstimatorInfo = EstimatorInfo {
    algorithm: Algorithm::El,
    name: "el",
    description: "Eye light: |cos| at the first hit, times its texture (a preview, not radiance).",
    techniques: Techniques::NONE,
    radiance: false,
    consistent_only: false,
    default_connect: None,
    regenerates_paths: false,
    default_sampler: None,
    build,
};

struct EyeLight {
    camera: CameraSubpaths,
}

fn build(b: &Build) -> Result<Box<dyn Estimator>> {
    Ok(Box::new(EyeLight { camera: CameraSubpaths::eye_light(&b.passes())? }))
}

impl Estimator for EyeLight {
    fn record(&self, batch: &mut Batch, iteration: u32) -> Result<()> {
        self.camera.record(batch, &GpuPush::simple(iteration, self.camera.pixels()))
    }

    fn passes(&self) -> Vec<PassInfo> {
        vec![self.camera.info()]
    }

    fn buffers(&self) -> Vec<&Buffer> {
        Vec::new()
    }
}
