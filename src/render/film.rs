//! The film: per-pixel sums of each iteration's value and of its square, kept on the GPU
//! across iterations (Kahan-compensated float32, see glsl/film.glsl), and counters of
//! rejected (NaN/Inf/negative) samples and overflowing splats.

use std::sync::Arc;

use anyhow::{bail, Result};

use crate::gpu::{Buffer, Gpu};

/// Per-pixel RGB sums.
pub type PixelSums = Vec<[f64; 3]>;

/// vec4 entries per pixel in `Film::accum`.
pub const FILM_VEC4_PER_PIXEL: usize = 4;

pub struct Film {
    pub width: u32,
    pub height: u32,
    /// Four vec4 per pixel: sum, its Kahan compensation, sum of squares, its compensation.
    pub accum: Buffer,
    /// `[0]`: rejected samples; `[1]`: splats rejected for overflow.
    pub stats: Buffer,
}

impl Film {
    pub fn new(gpu: &Arc<Gpu>, width: u32, height: u32) -> Result<Film> {
        let n = width as usize * height as usize;
        Ok(Film {
            width,
            height,
            accum: gpu.buffer_zeroed::<[f32; 4]>("film", FILM_VEC4_PER_PIXEL * n)?,
            stats: gpu.buffer_zeroed::<u32>("film_stats", 4)?,
        })
    }

    /// Per-pixel sums of the iterations' values and of their squares (linear RGB, row 0
    /// at the top).
    pub fn sums(&self) -> Result<(PixelSums, PixelSums)> {
        let raw: Vec<[f32; 4]> = self.accum.read()?;
        let rgb = |v: [f32; 4]| [v[0] as f64, v[1] as f64, v[2] as f64];
        let sum = raw.chunks_exact(FILM_VEC4_PER_PIXEL).map(|p| rgb(p[0])).collect();
        let sum_sq = raw.chunks_exact(FILM_VEC4_PER_PIXEL).map(|p| rgb(p[2])).collect();
        Ok((sum, sum_sq))
    }

    /// Replaces the sums (Kahan compensations reset to zero); lengths must match the film.
    pub fn load_sums(&self, sum: &[[f64; 3]], sum_sq: &[[f64; 3]]) -> Result<()> {
        let n = self.width as usize * self.height as usize;
        if sum.len() != n || sum_sq.len() != n {
            bail!("saved sums have {} and {} pixels but the film has {n}", sum.len(), sum_sq.len());
        }
        let v = |p: [f64; 3]| [p[0] as f32, p[1] as f32, p[2] as f32, 0.0];
        let mut raw = Vec::with_capacity(FILM_VEC4_PER_PIXEL * n);
        for (s, q) in sum.iter().zip(sum_sq) {
            raw.extend_from_slice(&[v(*s), [0.0; 4], v(*q), [0.0; 4]]);
        }
        self.accum.write(&raw)
    }

    /// Samples rejected so far because they were NaN, infinite or negative, and splats
    /// rejected because they could overflow the fixed-point sum.
    pub fn rejected(&self) -> Result<(u64, u64)> {
        let s = self.stats.read::<u32>()?;
        Ok((s[0] as u64, s[1] as u64))
    }
}
