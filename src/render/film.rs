//! The film: per-pixel sums of each iteration's value and of its square, kept on the GPU
//! across iterations as 128-bit fixed-point integers (glsl/film.glsl), and counters of
//! rejected (NaN/Inf/negative) samples, overflowing splats and overflowing samples.
//!
//! Integer sums do not depend on the order in which iterations are added: the sums of
//! disjoint sets of iterations add up ([`FilmSums::add`]) to the bits of one render of
//! all of them, which shards and several devices rely on (src/render/shard.rs).

use std::sync::Arc;

use anyhow::{bail, Result};

use super::addresses::FrameAddresses;
use super::sizes::{Access, BufferSize};
use crate::gpu::{Bind, Buffer, Gpu};

/// Per-pixel RGB sums.
pub type PixelSums = Vec<[f64; 3]>;

/// uvec4 entries per pixel in `Film::accum` (FILM_UVEC4_PER_PIXEL, glsl/film.glsl): the
/// sums of R, G, B, then of their squares.
pub const FILM_UVEC4_PER_PIXEL: usize = 6;
/// Bits after the fixed-point sums' binary point (FILM_SCALE = 2^32, glsl/film.glsl).
pub const FILM_FRACTION_BITS: i32 = 32;
/// u32 counters in `film_stats`.
const STATS_WORDS: usize = 8;

/// The film's sums read back: per pixel and channel, the 128-bit fixed-point sums (units
/// of 2^-[`FILM_FRACTION_BITS`]) of the iterations' values and of their squares.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FilmSums {
    pub sum: Vec<[u128; 3]>,
    pub sum_sq: Vec<[u128; 3]>,
}

impl FilmSums {
    pub fn zero(pixels: usize) -> FilmSums {
        FilmSums { sum: vec![[0; 3]; pixels], sum_sq: vec![[0; 3]; pixels] }
    }

    pub fn pixels(&self) -> usize {
        self.sum.len()
    }

    /// Adds `other`'s sums (another set of iterations of the same render): exact, so the
    /// order of adds does not matter. Fails on a different size or a sum that would pass
    /// 2^128 (impossible for at most 2^32 iterations in all: glsl/film.glsl).
    pub fn add(&mut self, other: &FilmSums) -> Result<()> {
        if other.pixels() != self.pixels() {
            bail!("films of {} and {} pixels cannot be added", self.pixels(), other.pixels());
        }
        let add = |a: &mut [[u128; 3]], b: &[[u128; 3]]| -> Result<()> {
            for (p, q) in a.iter_mut().zip(b) {
                for c in 0..3 {
                    p[c] = p[c].checked_add(q[c]).ok_or_else(|| anyhow::anyhow!("a film sum passes 2^128"))?;
                }
            }
            Ok(())
        };
        add(&mut self.sum, &other.sum)?;
        add(&mut self.sum_sq, &other.sum_sq)
    }

    /// A fixed-point sum as a float64 (rounded to nearest).
    pub fn real(q: u128) -> f64 {
        q as f64 * (-FILM_FRACTION_BITS as f64).exp2()
    }

    /// The nearest fixed-point sum to `v` (saved renders of the float32 film).
    pub fn fixed(v: f64) -> u128 {
        (v.max(0.0) * (FILM_FRACTION_BITS as f64).exp2()).round() as u128
    }

    /// The sums as float64 (value, square).
    pub fn reals(&self) -> (PixelSums, PixelSums) {
        let f = |v: &[[u128; 3]]| v.iter().map(|p| p.map(Self::real)).collect();
        (f(&self.sum), f(&self.sum_sq))
    }

    /// The mean image of `iterations` iterations: each sum / iterations, in float64, then
    /// rounded to float32 (on the host: the same bits wherever the sums were made).
    pub fn mean(&self, iterations: u64) -> Vec<[f32; 3]> {
        let k = 1.0 / iterations.max(1) as f64;
        self.sum.iter().map(|p| p.map(|q| (Self::real(q) * k) as f32)).collect()
    }

    /// The 128-bit words of a sum, least significant first (the GPU's and the EXR's layout).
    pub fn words(q: u128) -> [u32; 4] {
        std::array::from_fn(|i| (q >> (32 * i)) as u32)
    }

    pub fn from_words(w: [u32; 4]) -> u128 {
        w.iter().rev().fold(0u128, |acc, &x| (acc << 32) | x as u128)
    }
}

/// The film's sizes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FilmPlan {
    pub width: u32,
    pub height: u32,
    /// [`FILM_UVEC4_PER_PIXEL`] uvec4 per pixel.
    pub sums: BufferSize,
    /// [`STATS_WORDS`] u32 counters.
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
            sums: BufferSize::new("film", px.saturating_mul(16 * FILM_UVEC4_PER_PIXEL as u64)).reached(access),
            stats: BufferSize::new("film_stats", 4 * STATS_WORDS as u64),
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
    /// Six uvec4 per pixel: the fixed-point sums of R, G, B and of their squares.
    pub accum: Buffer,
    /// `[0]`: rejected samples; `[1]`: splats rejected for overflow; `[2..3]`: traced rays
    /// (low, high word) when profiling (`COUNT_RAYS`, glsl/scene.glsl); `[4]`: samples
    /// rejected for overflow (at or above 2^32).
    pub stats: Buffer,
    /// The device addresses of the frame's large buffers: the film's own, and those the
    /// passes register (src/render/addresses.rs).
    pub addresses: FrameAddresses,
    /// The AOV sums, when asked for (set by the renderer, which knows the scene's origin).
    pub aov: Option<super::aov::Aovs>,
}

/// Counters of samples the film did not add.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Rejected {
    /// NaN, infinite or negative samples.
    pub samples: u64,
    /// Light-tracing splats over SPLAT_MAX.
    pub overflow_splats: u64,
    /// Samples at or above the film's range (2^32).
    pub overflow_samples: u64,
}

impl std::ops::Add for Rejected {
    type Output = Rejected;
    fn add(self, o: Rejected) -> Rejected {
        Rejected {
            samples: self.samples + o.samples,
            overflow_splats: self.overflow_splats + o.overflow_splats,
            overflow_samples: self.overflow_samples + o.overflow_samples,
        }
    }
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

    /// The film's sums (row 0 at the top).
    pub fn sums(&self) -> Result<FilmSums> {
        let raw: Vec<[u32; 4]> = self.accum.read()?;
        let n = raw.len() / FILM_UVEC4_PER_PIXEL;
        let mut s = FilmSums::zero(n);
        for (p, words) in raw.chunks_exact(FILM_UVEC4_PER_PIXEL).enumerate() {
            for c in 0..3 {
                s.sum[p][c] = FilmSums::from_words(words[c]);
                s.sum_sq[p][c] = FilmSums::from_words(words[3 + c]);
            }
        }
        Ok(s)
    }

    /// Replaces the sums (lengths must match the film). The counters are not touched.
    pub fn load_sums(&self, sums: &FilmSums) -> Result<()> {
        let n = self.width as usize * self.height as usize;
        if sums.pixels() != n || sums.sum_sq.len() != n {
            bail!("saved sums have {} pixels but the film has {n}", sums.pixels());
        }
        let mut raw = Vec::with_capacity(FILM_UVEC4_PER_PIXEL * n);
        for (s, q) in sums.sum.iter().zip(&sums.sum_sq) {
            raw.extend(s.iter().chain(q).map(|&v| FilmSums::words(v)));
        }
        self.accum.write(&raw)
    }

    /// What the film rejected so far.
    pub fn rejected(&self) -> Result<Rejected> {
        let s = self.stats.read::<u32>()?;
        Ok(Rejected { samples: s[0] as u64, overflow_splats: s[1] as u64, overflow_samples: s[4] as u64 })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn words_round_trip() {
        for q in [0u128, 1, u32::MAX as u128 + 5, u128::MAX, 0x0123_4567_89ab_cdef_fedc_ba98_7654_3210] {
            assert_eq!(FilmSums::from_words(FilmSums::words(q)), q);
        }
        assert_eq!(FilmSums::words(1 << 32), [0, 1, 0, 0]);
    }

    #[test]
    fn fixed_and_real_agree() {
        assert_eq!(FilmSums::fixed(1.0), 1 << 32);
        assert_eq!(FilmSums::real(3 << 31), 1.5);
    }
}
