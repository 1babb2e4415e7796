//! The accumulate pass of estimators without a camera pass (light tracing): adds each
//! pixel's splat sum of the iteration to the film and zeroes it (glsl/accumulate.comp).

use anyhow::Result;

use super::{PassContext, PassInfo};
use crate::gpu::{Batch, Bind, Kernel};
use crate::render::gpu_types::GpuPush;
use crate::render::light_vertex_store::LightVertexStore;
use crate::render::variants::workgroup_defines;

/// The name profiles report.
pub const NAME: &str = "accumulate";

pub struct Accumulate {
    kernel: Kernel,
    pixels: u32,
}

impl Accumulate {
    pub fn new(b: &PassContext, store: &LightVertexStore) -> Result<Accumulate> {
        let mut binds: Vec<Bind> = b.film.binds().to_vec();
        binds.push(Bind::own(&store.splat));
        let defines = b.scene.variant.film_defines().with(&workgroup_defines());
        let kernel = b.gpu.kernel("accumulate.comp", &defines.pairs(), &binds)?;
        Ok(Accumulate { kernel, pixels: b.pixels })
    }

    /// One pixel per invocation.
    pub fn record(&self, batch: &mut Batch, push: &GpuPush) -> Result<()> {
        batch.begin_pass(NAME);
        batch.dispatch(&self.kernel, self.kernel.groups_for(self.pixels), bytemuck::bytes_of(push))
    }

    pub fn info(&self) -> PassInfo {
        PassInfo { name: NAME, detail: "accumulate.comp: splats -> film".into() }
    }
}
