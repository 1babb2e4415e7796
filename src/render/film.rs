//! The film: per-pixel sums kept on the GPU across iterations (Kahan-compensated
//! float32, see glsl/film.glsl) and a counter of rejected (NaN/Inf/negative) samples.

use std::sync::Arc;

use anyhow::Result;

use crate::gpu::{Buffer, Gpu};

pub struct Film {
    pub width: u32,
    pub height: u32,
    /// Two vec4 per pixel: sum and Kahan compensation.
    pub accum: Buffer,
    /// `[0]`: rejected samples.
    pub stats: Buffer,
}

impl Film {
    pub fn new(gpu: &Arc<Gpu>, width: u32, height: u32) -> Result<Film> {
        let n = width as usize * height as usize;
        Ok(Film {
            width,
            height,
            accum: gpu.buffer_zeroed::<[f32; 4]>("film", 2 * n)?,
            stats: gpu.buffer_zeroed::<u32>("film_stats", 4)?,
        })
    }

    /// The mean image after `iterations` iterations (linear RGB, row 0 at the top).
    pub fn mean(&self, iterations: u64) -> Result<Vec<[f32; 3]>> {
        let raw: Vec<[f32; 4]> = self.accum.read()?;
        let k = 1.0 / iterations.max(1) as f64;
        Ok(raw
            .chunks_exact(2)
            .map(|p| [(p[0][0] as f64 * k) as f32, (p[0][1] as f64 * k) as f32, (p[0][2] as f64 * k) as f32])
            .collect())
    }

    /// Samples rejected so far because they were NaN, infinite or negative.
    pub fn rejected(&self) -> Result<u64> {
        Ok(self.stats.read::<u32>()?[0] as u64)
    }
}
