//! AOVs (`--aov`): per-pixel albedo, shading normal, depth and position beside the image,
//! with Intel Open Image Denoise's conventions for the albedo and normal, summed on the
//! GPU by the camera kernels (glsl/aov.glsl) from the camera subpaths they trace anyway.
//! The kernels are compiled with them only when asked ([`AovKernel`]), so a render
//! without AOVs runs the same code as before.
//!
//! Per pixel three vec4 of float32 sums (no compensation: a layer is a guide, not a
//! measurement): (albedo, samples), (normal, first hits), (position, depth).

use std::str::FromStr;
use std::sync::Arc;

use anyhow::{bail, Context, Result};

use super::sizes::BufferSize;
use super::variants::kernel_switches;
use crate::gpu::{Bind, Buffer, Gpu};
use crate::image::{ExtraChannel, Samples};

kernel_switches! {
    /// What the camera kernels (pt.comp, camera_subpath.comp, el.comp) are compiled with.
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    pub struct AovKernel {
        /// Sum the AOVs into the binding `aov` (glsl/aov.glsl).
        pub aov: bool,
    }
}

/// vec4 sums per pixel in the `aov` buffer.
pub const AOV_VEC4_PER_PIXEL: u64 = 3;

/// The EXR channel names of each layer (OpenEXR's conventions, which tev and denoisers read).
pub const ALBEDO_CHANNELS: [&str; 3] = ["albedo.R", "albedo.G", "albedo.B"];
pub const NORMAL_CHANNELS: [&str; 3] = ["N.X", "N.Y", "N.Z"];
pub const DEPTH_CHANNEL: &str = "Z";
pub const POSITION_CHANNELS: [&str; 3] = ["P.X", "P.Y", "P.Z"];

/// Which AOV layers a render writes (`--aov albedo,normal,depth,position`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AovSet {
    pub albedo: bool,
    pub normal: bool,
    pub depth: bool,
    pub position: bool,
}

impl AovSet {
    /// Every layer.
    pub const ALL: AovSet = AovSet { albedo: true, normal: true, depth: true, position: true };
    /// The names `--aov` takes.
    pub const NAMES: [&'static str; 4] = ["albedo", "normal", "depth", "position"];

    /// True when any layer is asked for (the kernels then sum them all).
    pub fn any(&self) -> bool {
        self.albedo || self.normal || self.depth || self.position
    }

    /// The names of the layers asked for, comma-separated.
    pub fn names(&self) -> String {
        let on = [self.albedo, self.normal, self.depth, self.position];
        let names: Vec<&str> = Self::NAMES.iter().zip(on).filter(|(_, on)| *on).map(|(n, _)| *n).collect();
        names.join(",")
    }
}

impl FromStr for AovSet {
    type Err = anyhow::Error;

    /// A comma-separated list of `albedo`, `normal`, `depth`, `position`, or `all`.
    fn from_str(s: &str) -> Result<AovSet> {
        let mut set = AovSet::default();
        for name in s.split(',').map(str::trim) {
            match name {
                "albedo" => set.albedo = true,
                "normal" => set.normal = true,
                "depth" => set.depth = true,
                "position" => set.position = true,
                "all" => set = AovSet::ALL,
                other => bail!("unknown AOV {other:?}: expected a list of albedo, normal, depth, position, or all"),
            }
        }
        Ok(set)
    }
}

/// The size of the `aov` buffer of a `pixels`-pixel frame.
pub fn plan(pixels: u64) -> BufferSize {
    BufferSize::new("aov", pixels.saturating_mul(16 * AOV_VEC4_PER_PIXEL))
}

/// The AOV sums on the GPU.
pub struct Aovs {
    pub set: AovSet,
    pub sums: Buffer,
    /// The scene's origin in the file's coordinates (`LoadReport::origin`): the kernels see
    /// camera-relative positions.
    pub origin: [f64; 3],
}

impl Aovs {
    pub fn new(gpu: &Arc<Gpu>, set: AovSet, size: &BufferSize, origin: [f64; 3]) -> Result<Aovs> {
        Ok(Aovs { set, sums: size.zeroed(gpu)?, origin })
    }

    pub fn bind(&self) -> Bind<'_> {
        Bind::own(&self.sums)
    }

    /// The layers asked for, read back and averaged.
    pub fn read(&self) -> Result<AovImage> {
        let raw: Vec<[f32; 4]> = self.sums.read().context("reading the AOVs back")?;
        Ok(AovImage::from_sums(self.set, &raw, self.origin))
    }
}

/// AOV layers, per pixel, row 0 at the top.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AovImage {
    pub set: AovSet,
    /// Mean over the pixel's samples of the first non-specular hit's albedo times the
    /// specular throughput before it (0 where a sample found none).
    pub albedo: Vec<[f32; 3]>,
    /// Mean over the pixel's samples of the first non-specular hit's shading normal,
    /// world space, not renormalised (0 where a sample found none).
    pub normal: Vec<[f32; 3]>,
    /// Mean distance from the camera to the first hit over the samples that hit
    /// (+infinity where none did).
    pub depth: Vec<f32>,
    /// Mean first-hit position in the file's world coordinates over the samples that hit
    /// (0 where none did).
    pub position: Vec<[f32; 3]>,
}

impl AovImage {
    /// Averages the kernels' sums (three vec4 per pixel, glsl/aov.glsl).
    pub fn from_sums(set: AovSet, raw: &[[f32; 4]], origin: [f64; 3]) -> AovImage {
        let mut img = AovImage { set, ..Default::default() };
        for p in raw.chunks_exact(AOV_VEC4_PER_PIXEL as usize) {
            let (samples, hits) = (p[0][3] as f64, p[1][3] as f64);
            let per_sample = |v: f32| if samples > 0.0 { (v as f64 / samples) as f32 } else { 0.0 };
            img.albedo.push([0, 1, 2].map(|c| per_sample(p[0][c])));
            img.normal.push([0, 1, 2].map(|c| per_sample(p[1][c])));
            if hits > 0.0 {
                img.position.push([0, 1, 2].map(|c| (p[2][c] as f64 / hits + origin[c]) as f32));
                img.depth.push((p[2][3] as f64 / hits) as f32);
            } else {
                img.position.push([0.0; 3]);
                img.depth.push(f32::INFINITY);
            }
        }
        img
    }

    /// The layers asked for as EXR channels.
    pub fn channels(&self) -> Vec<ExtraChannel> {
        let mut out = Vec::new();
        let mut rgb = |names: [&str; 3], v: &[[f32; 3]]| {
            for (c, name) in names.iter().enumerate() {
                out.push((name.to_string(), Samples::F32(v.iter().map(|p| p[c]).collect())));
            }
        };
        if self.set.albedo {
            rgb(ALBEDO_CHANNELS, &self.albedo);
        }
        if self.set.normal {
            rgb(NORMAL_CHANNELS, &self.normal);
        }
        if self.set.position {
            rgb(POSITION_CHANNELS, &self.position);
        }
        if self.set.depth {
            out.push((DEPTH_CHANNEL.to_string(), Samples::F32(self.depth.clone())));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_lists() {
        let s: AovSet = "albedo,normal".parse().unwrap();
        assert_eq!(s, AovSet { albedo: true, normal: true, ..Default::default() });
        assert_eq!("all".parse::<AovSet>().unwrap(), AovSet::ALL);
        assert_eq!(AovSet::ALL.names(), "albedo,normal,depth,position");
        assert!("albedo,colour".parse::<AovSet>().is_err());
    }

    #[test]
    fn averages_sums() {
        // Two samples, one hit at depth 3 and camera-relative position (1, 2, 3).
        let raw = [[0.8, 0.4, 0.2, 2.0], [0.0, 0.0, 1.0, 1.0], [1.0, 2.0, 3.0, 3.0]];
        let img = AovImage::from_sums(AovSet::ALL, &raw, [10.0, 0.0, 0.0]);
        assert_eq!(img.albedo, vec![[0.4, 0.2, 0.1]]);
        assert_eq!(img.normal, vec![[0.0, 0.0, 0.5]]);
        assert_eq!(img.depth, vec![3.0]);
        assert_eq!(img.position, vec![[11.0, 2.0, 3.0]]);
        let names: Vec<String> = img.channels().into_iter().map(|c| c.0).collect();
        assert_eq!(names, ["albedo.R", "albedo.G", "albedo.B", "N.X", "N.Y", "N.Z", "P.X", "P.Y", "P.Z", "Z"]);
    }
}
