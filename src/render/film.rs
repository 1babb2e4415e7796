//! The film: per-pixel sums of each iteration's value and of its square, kept on the GPU
//! across iterations (Kahan-compensated float32, see glsl/film.glsl), and counters of
//! rejected (NaN/Inf/negative) samples and overflowing splats.

use std::sync::Arc;

use anyhow::{bail, Result};

use super::addresses::FrameAddresses;
use super::sizes::{Access, BufferSize};
use crate::gpu::{Bind, Buffer, Gpu};

/// Per-pixel RGB sums.
pub type PixelSums = Vec<[f64; 3]>;

/// vec4 entries per pixel in `Film::accum`.
pub const FILM_VEC4_PER_PIXEL: usize = 4;

/// The film's sizes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FilmPlan {
    pub width: u32,
    pub height: u32,
    /// [`FILM_VEC4_PER_PIXEL`] vec4 per pixel.
    pub sums: BufferSize,
    /// Four u32 counters.
    pub stats: BufferSize,
    /// The AOV sums (`--aov`, src/render/aov.rs).
    pub aov: Option<BufferSize>,
}

impl FilmPlan {
    /// The film of a `width` x `height` frame, its sums reached as `access`.
    pub fn new(width: u32, height: u32, access: Access) -> FilmPlan {
        let px = width as u64 * height as u64;
        FilmPlan {
            width,
            height,
            sums: BufferSize::new("film", px.saturating_mul(16 * FILM_VEC4_PER_PIXEL as u64)).reached(access),
            stats: BufferSize::new("film_stats", 16),
            aov: None,
        }
    }

    /// This film with the AOV sums when `on`.
    pub fn with_aov(self, on: bool) -> FilmPlan {
        let aov = on.then(|| super::aov::plan(self.width as u64 * self.height as u64));
        FilmPlan { aov, ..self }
    }

    pub fn buffers(&self) -> Vec<BufferSize> {
        [self.sums, self.stats].into_iter().chain(self.aov).collect()
    }
}

pub struct Film {
    pub width: u32,
    pub height: u32,
    /// Four vec4 per pixel: sum, its Kahan compensation, sum of squares, its compensation.
    pub accum: Buffer,
    /// `[0]`: rejected samples; `[1]`: splats rejected for overflow; `[2..3]`: traced rays
    /// (low, high word) when profiling (`COUNT_RAYS`, glsl/scene.glsl).
    pub stats: Buffer,
    /// The device addresses of the frame's large buffers: the film's own, and those the
    /// passes register (src/render/addresses.rs).
    pub addresses: FrameAddresses,
    /// The AOV sums, when asked for (set by the renderer, which knows the scene's origin).
    pub aov: Option<super::aov::Aovs>,
}

impl Film {
    pub fn new(gpu: &Arc<Gpu>, plan: &FilmPlan) -> Result<Film> {
        let accum = plan.sums.zeroed(gpu)?;
        let addresses = FrameAddresses::new(gpu)?;
        addresses.set(|a| &mut a.film, &accum)?;
        Ok(Film { width: plan.width, height: plan.height, accum, stats: plan.stats.zeroed(gpu)?, addresses, aov: None })
    }

    /// The bindings `film` (bound without device addresses), `film_stats` and
    /// `frame_addresses` (glsl/film.glsl).
    pub fn binds(&self) -> [Bind<'_>; 3] {
        [Bind::own(&self.accum), Bind::own_u32(&self.stats), self.addresses.bind()]
    }

    /// Per-pixel sums of the iterations' values and of their squares (linear RGB, row 0
    /// at the top), each the float32 Kahan sum minus its compensation, in float64.
    pub fn sums(&self) -> Result<(PixelSums, PixelSums)> {
        let raw: Vec<[f32; 4]> = self.accum.read()?;
        // film_kahan_add keeps comp = (t - sum) - y, the amount t overshoots: true = t - comp.
        let rgb = |t: [f32; 4], c: [f32; 4]| std::array::from_fn(|i| t[i] as f64 - c[i] as f64);
        let sum = raw.chunks_exact(FILM_VEC4_PER_PIXEL).map(|p| rgb(p[0], p[1])).collect();
        let sum_sq = raw.chunks_exact(FILM_VEC4_PER_PIXEL).map(|p| rgb(p[2], p[3])).collect();
        Ok((sum, sum_sq))
    }

    /// Replaces the sums, each split into a float32 sum and the Kahan compensation that
    /// holds its rounding error (so [`Film::sums`] returns them to about 2^-48 relative);
    /// lengths must match the film. The rejected-sample counters are not touched.
    pub fn load_sums(&self, sum: &[[f64; 3]], sum_sq: &[[f64; 3]]) -> Result<()> {
        let n = self.width as usize * self.height as usize;
        if sum.len() != n || sum_sq.len() != n {
            bail!("saved sums have {} and {} pixels but the film has {n}", sum.len(), sum_sq.len());
        }
        let split = |p: [f64; 3]| {
            let t = p.map(|v| v as f32);
            let c: [f32; 3] = std::array::from_fn(|i| (t[i] as f64 - p[i]) as f32);
            ([t[0], t[1], t[2], 0.0], [c[0], c[1], c[2], 0.0])
        };
        let mut raw = Vec::with_capacity(FILM_VEC4_PER_PIXEL * n);
        for (s, q) in sum.iter().zip(sum_sq) {
            let (st, sc) = split(*s);
            let (qt, qc) = split(*q);
            raw.extend_from_slice(&[st, sc, qt, qc]);
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
