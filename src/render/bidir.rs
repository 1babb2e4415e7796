//! The light-subpath estimators: light tracing (`lt`) and bidirectional path tracing
//! (`bpt`). Per iteration: glsl/light_subpath.comp (one invocation per light subpath),
//! then glsl/camera_subpath.comp (one per pixel; it also takes the splats into the film)
//! or, for `lt`, glsl/accumulate.comp.
//!
//! Light vertices use SmallVCM's layout: the camera subpath of pixel p connects to the
//! vertices of light subpath p, which live in fixed slots (see glsl/vcm.glsl).

use std::sync::Arc;

use anyhow::{bail, Result};

use super::film::Film;
use super::gpu_types::GpuPush;
use super::scene_gpu::{define_refs, SceneGpu};
use crate::gpu::{groups_for, Batch, Buffer, Gpu, Kernel};

/// Which light-subpath estimator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BidirMode {
    LightTracing,
    Bpt,
}

pub struct Bidir {
    light: Kernel,
    resolve: Kernel,
    pixels: u32,
    light_paths: u32,
    // Owned so they outlive the kernels' descriptor sets.
    _buffers: Vec<Buffer>,
}

/// Bytes of one light-vertex half (lv_a or lv_b) per vertex.
const LV_HALF_BYTES: u64 = 32;

impl Bidir {
    pub fn new(gpu: &Arc<Gpu>, scene: &SceneGpu, film: &Film, mode: BidirMode, max_path_length: u32) -> Result<Bidir> {
        let pixels = film.width * film.height;
        let light_paths = pixels;
        let store = mode == BidirMode::Bpt;
        let slots = max_path_length.saturating_sub(1).max(1) as u64;
        let lv_vertices = if store { light_paths as u64 * slots } else { 1 };
        let max = gpu.limits.max_storage_buffer_range as u64;
        if lv_vertices * LV_HALF_BYTES > max {
            bail!(
                "the light-vertex store needs 2 x {} bytes ({} light subpaths x {} vertices) but this device binds at most {} bytes per buffer; lower the resolution or --max-path-length",
                lv_vertices * LV_HALF_BYTES,
                light_paths,
                slots,
                max
            );
        }
        let buffers = vec![
            gpu.buffer_zeroed::<u64>("splat", 3 * pixels as usize)?,
            gpu.buffer_zeroed::<[f32; 4]>("light_vertices_a", 2 * lv_vertices as usize)?,
            gpu.buffer_zeroed::<[f32; 4]>("light_vertices_b", 2 * lv_vertices as usize)?,
            gpu.buffer_zeroed::<u32>("light_vertex_counts", if store { light_paths as usize } else { 1 })?,
        ];
        let mut bind = scene.bindings(&[&film.accum, &film.stats]);
        bind.extend(buffers.iter());
        let mut defines = scene.defines.clone();
        let lt = mode == BidirMode::LightTracing;
        defines.push(("STORE_VERTICES".into(), (store as u32).to_string()));
        defines.push(("LIGHT_TRACE_ONLY".into(), (lt as u32).to_string()));
        let light = gpu.kernel("light_subpath.comp", &define_refs(&defines), &bind)?;
        let resolve = if lt {
            gpu.kernel("accumulate.comp", &define_refs(&scene.defines), &bind)?
        } else {
            let mut d = scene.defines.clone();
            d.push(("USE_VC".into(), "1".into()));
            gpu.kernel("camera_subpath.comp", &define_refs(&d), &bind)?
        };
        Ok(Bidir { light, resolve, pixels, light_paths, _buffers: buffers })
    }

    pub fn record(&self, batch: &mut Batch, iteration: u32) -> Result<()> {
        let mut push = GpuPush { iteration, count: self.light_paths, light_paths: self.light_paths, ..Default::default() };
        batch.dispatch(&self.light, [groups_for(self.light_paths, 64), 1, 1], bytemuck::bytes_of(&push))?;
        push.count = self.pixels;
        batch.dispatch(&self.resolve, [groups_for(self.pixels, 64), 1, 1], bytemuck::bytes_of(&push))
    }
}
