//! Eye light (`el`): |cos| between the shading normal and the view ray at the first hit,
//! times the surface's tint (base-colour texture and vertex colour, docs/textures.md), a
//! preview and not a radiance estimate (SmallVCM's EyeLight, which has no textures). One pass: the camera
//! kernel glsl/el.comp, one ray per pixel.

use anyhow::Result;

use super::{Build, Estimator};
use crate::gpu::{Batch, Buffer};
use crate::render::gpu_types::GpuPush;
use crate::render::passes::camera_subpaths::CameraSubpaths;
use crate::render::passes::PassInfo;

struct EyeLight {
    camera: CameraSubpaths,
}

pub fn build(b: &Build) -> Result<Box<dyn Estimator>> {
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
