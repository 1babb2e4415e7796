//! How light-tracing splats are summed (`--atomics`): the splat sums are exact 64-bit
//! fixed-point integers either way (glsl/film.glsl), so the image does not depend on it
//! (tests/render_atomics.rs).
//!
//! * [`SplatAtomics::Bits64`]: one 64-bit atomic add per channel (`shaderInt64`,
//!   `shaderBufferInt64Atomics`).
//! * [`SplatAtomics::Bits32`]: the same 64-bit sum carried in two 32-bit words per
//!   channel: an atomic add to the low word, whose returned old value tells whether it
//!   wrapped, then an atomic add of the high part and the carry to the high word. Every
//!   add contributes exactly its value mod 2^64 whatever the order, so the sum is the same
//!   as the 64-bit one. Reading it back converts the two words to the nearest float as a
//!   64-bit conversion would (`u64_words_to_float` in glsl/common.glsl), so the image is bit-identical. For
//!   devices without 64-bit atomics (MoltenVK, most Android GPUs, SwiftShader:
//!   docs/devices.md).
//!
//! Both reject a splat above `SPLAT_MAX` = 2^27 (counted in `overflow_splats`), so a
//! pixel's sum of one iteration overflows only past 2^13 such splats.

use anyhow::{bail, Result};

use crate::gpu::{Gpu, SHADER_INT64_ATOMICS};

/// How splats are summed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum SplatAtomics {
    /// 64-bit atomic adds.
    #[value(name = "64")]
    Bits64,
    /// Pairs of 32-bit atomic adds with carry.
    #[value(name = "32")]
    Bits32,
}

impl SplatAtomics {
    pub fn name(self) -> &'static str {
        match self {
            SplatAtomics::Bits64 => "64",
            SplatAtomics::Bits32 => "32",
        }
    }

    /// `requested` (`--atomics`), or else 64-bit atomics where the device has them.
    pub fn resolve(gpu: &Gpu, requested: Option<SplatAtomics>) -> Result<SplatAtomics> {
        let has64 = gpu.has(SHADER_INT64_ATOMICS);
        match requested {
            Some(SplatAtomics::Bits64) if !has64 => bail!(
                "--atomics 64: device {:?} has no 64-bit buffer atomics ({SHADER_INT64_ATOMICS}); use --atomics 32",
                gpu.info.name
            ),
            Some(a) => Ok(a),
            None if has64 => Ok(SplatAtomics::Bits64),
            None => Ok(SplatAtomics::Bits32),
        }
    }
}
