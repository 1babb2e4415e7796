//! What a render reports while it runs ([`Progress`]) and what it produced
//! ([`RenderOutput`]).

use super::atomics::SplatAtomics;
use super::film::FilmSums;
use super::reads;
use super::shard::IterationSet;
use crate::gpu::Profile;

/// Progress of a running render.
#[derive(Clone, Debug)]
pub struct Progress {
    pub iterations: u64,
    pub seconds: f64,
    /// Fraction done in [0, 1].
    pub fraction: f64,
    /// Something the batch changed that a user should hear of (the light-vertex store
    /// grew and iterations were rendered again).
    pub note: Option<String>,
}

/// What a render produced.
pub struct RenderOutput {
    pub width: u32,
    pub height: u32,
    /// Mean linear RGB per pixel, row 0 at the top.
    pub pixels: Vec<[f32; 3]>,
    /// Per-pixel sums of the iterations' values and of their squares: the mean is
    /// `sum / iterations`, the variance of one iteration's value follows from both.
    pub sum: Vec<[f64; 3]>,
    pub sum_sq: Vec<[f64; 3]>,
    /// The film's exact fixed-point sums (`sum` and `sum_sq` are these as float64).
    pub sums: FilmSums,
    /// The global indices of its iterations (src/render/shard.rs).
    pub held: IterationSet,
    pub iterations: u64,
    pub seconds: f64,
    /// Samples that were NaN, infinite or negative (rejected, never added).
    pub rejected_samples: u64,
    /// Light-tracing splats rejected because they could overflow the fixed-point sum.
    pub overflow_splats: u64,
    /// Samples rejected because they are above the film's range (2^32, glsl/film.glsl).
    pub overflow_samples: u64,
    pub profile: Profile,
    /// Paths per kernel invocation the render ran with ([`regen`]).
    pub paths_per_invocation: u32,
    /// How its kernels read their read-only buffers ([`reads`]).
    pub reads: reads::Reads,
    /// How its splats were summed (src/render/atomics.rs).
    pub atomics: SplatAtomics,
    /// True when stopped early by the cancel flag.
    pub interrupted: bool,
    /// The AOV layers asked for (`--aov`).
    pub aov: Option<super::aov::AovImage>,
}
