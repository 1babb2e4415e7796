//! Environment maps: equirectangular (latitude-longitude) radiance images lighting the
//! scene from infinity ([`super::Light::Environment`]). Read from Radiance `.hdr` (the
//! `image` crate) or OpenEXR (the `exr` crate), recognised by their first bytes. The
//! mapping of texels to directions is Mitsuba 3's (docs/environment.md).

use std::fmt;
use std::path::Path;
use std::sync::Arc;

use anyhow::{anyhow, bail, Context, Result};
use glam::Vec3;

/// An environment map lighting the scene from infinity: radiance `scale * map(d)` along
/// world direction `d`, the map turned about +Y by `rotation_deg` (right-handed: +X
/// turns towards -Z for 90 degrees), as Mitsuba 3's `envmap` with
/// `to_world = rotate([0, 1, 0], rotation_deg)`.
#[derive(Clone, Debug, PartialEq)]
pub struct EnvironmentLight {
    pub map: Arc<EnvironmentMap>,
    pub scale: Vec3,
    pub rotation_deg: f32,
}

/// The largest width or height accepted (a 16k x 8k map is 1.5 GiB as float32 RGBA).
pub const MAX_ENVIRONMENT_SIZE: u32 = 16384;

/// A linear-RGB lat-long image; row 0 is the zenith (+Y), column 0 looks along -Z.
#[derive(Clone, PartialEq)]
pub struct EnvironmentMap {
    /// Where it came from (a file name or `data:` URI prefix), for messages.
    pub source: String,
    pub width: u32,
    pub height: u32,
    /// Row-major radiance, rows top (zenith) to bottom (nadir); non-negative and finite.
    pub texels: Vec<[f32; 3]>,
}

impl fmt::Debug for EnvironmentMap {
    /// The size and a CRC-32 of the texels (it is part of `Scene::fingerprint`), not the
    /// texels themselves.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut h = crc32fast::Hasher::new();
        h.update(bytemuck::cast_slice(&self.texels));
        write!(f, "EnvironmentMap({:?}, {}x{}, crc {:08x})", self.source, self.width, self.height, h.finalize())
    }
}

impl EnvironmentMap {
    /// A map from texels (row-major, `width * height` of them). At least 2 x 3 texels (a
    /// column to interpolate with and a row between the poles); radiance must be finite,
    /// negative values are clamped to 0 (some HDR tools write tiny negative noise).
    pub fn new(source: &str, width: u32, height: u32, mut texels: Vec<[f32; 3]>) -> Result<EnvironmentMap> {
        if width < 2 || height < 3 {
            bail!("environment map {source}: {width}x{height} is too small (at least 2x3 texels)");
        }
        if width > MAX_ENVIRONMENT_SIZE || height > MAX_ENVIRONMENT_SIZE {
            bail!("environment map {source}: {width}x{height} is larger than {MAX_ENVIRONMENT_SIZE} texels on a side");
        }
        if texels.len() != width as usize * height as usize {
            bail!("environment map {source}: {} texels for {width}x{height}", texels.len());
        }
        if let Some(i) = texels.iter().position(|t| t.iter().any(|c| !c.is_finite())) {
            bail!(
                "environment map {source}: texel ({}, {}) is not finite ({:?})",
                i as u32 % width,
                i as u32 / width,
                texels[i]
            );
        }
        for t in &mut texels {
            for c in t.iter_mut() {
                *c = c.max(0.0);
            }
        }
        Ok(EnvironmentMap { source: source.to_string(), width, height, texels })
    }

    /// Reads a `.hdr` or `.exr` file.
    pub fn load(path: &Path) -> Result<EnvironmentMap> {
        let bytes = std::fs::read(path).with_context(|| format!("cannot read environment map {}", path.display()))?;
        Self::decode(&bytes, &path.display().to_string())
    }

    /// Decodes the bytes of a Radiance HDR or OpenEXR file (by its magic number).
    pub fn decode(bytes: &[u8], source: &str) -> Result<EnvironmentMap> {
        if bytes.starts_with(b"#?") {
            let img = image::load_from_memory_with_format(bytes, image::ImageFormat::Hdr)
                .map_err(|e| anyhow!("environment map {source}: not a readable Radiance HDR file: {e}"))?
                .into_rgb32f();
            let (w, h) = img.dimensions();
            let texels = img.pixels().map(|p| p.0).collect();
            Self::new(source, w, h, texels)
        } else if bytes.starts_with(&[0x76, 0x2f, 0x31, 0x01]) {
            let (img, _, _) = crate::image::decode_exr_channels(bytes, source)
                .map_err(|e| anyhow!("environment map {source}: {e:#}"))?;
            Self::new(source, img.width, img.height, img.data)
        } else {
            bail!("environment map {source}: neither a Radiance HDR (.hdr) nor an OpenEXR (.exr) file")
        }
    }

    /// A constant map (for tests: it must light a scene exactly as a constant background).
    pub fn constant(width: u32, height: u32, radiance: [f32; 3]) -> EnvironmentMap {
        EnvironmentMap {
            source: "constant".into(),
            width,
            height,
            texels: vec![radiance; width as usize * height as usize],
        }
    }

    pub fn texel(&self, x: u32, y: u32) -> [f32; 3] {
        self.texels[(y * self.width + x) as usize]
    }
}

/// Rec. 709 luminance, the weight importance sampling gives a texel.
pub fn luminance(c: [f32; 3]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}
