//! PLACEHOLDER written by the render engineer so the crate compiles while the GPU hash
//! grid is being written: same public API as agreed; replace this file entirely.

use std::sync::Arc;

use anyhow::{bail, Result};

use crate::gpu::{Batch, Buffer, Gpu};

pub struct HashGrid {
    pub cell_start: Buffer,
    pub cell_indices: Buffer,
    num_buckets: u32,
}

impl HashGrid {
    pub fn new(
        gpu: &Arc<Gpu>,
        _lv_a: &Buffer,
        _lv_count: &Buffer,
        light_paths: u32,
        slots: u32,
        num_buckets: u32,
    ) -> Result<HashGrid> {
        Ok(HashGrid {
            cell_start: gpu.buffer_zeroed::<u32>("grid_start", num_buckets as usize + 1)?,
            cell_indices: gpu.buffer_zeroed::<u32>("grid_indices", (light_paths * slots) as usize)?,
            num_buckets,
        })
    }

    pub fn record_build(&self, _batch: &mut Batch, _radius: f32, _origin: [f32; 3]) -> Result<()> {
        bail!("the GPU hash grid is not built yet (placeholder)")
    }

    pub fn num_buckets(&self) -> u32 {
        self.num_buckets
    }
}
