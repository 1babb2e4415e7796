//! Tone-mapped 8-bit sRGB PNG output (previews, not data: use EXR for numbers).

use super::atomic::write_atomic;
use super::Image;
use ::image::ImageEncoder;
use anyhow::{anyhow, bail, Result};
use std::path::Path;

/// The sRGB opto-electronic transfer function (IEC 61966-2-1) of a linear value in [0, 1].
#[inline]
pub fn linear_to_srgb(v: f32) -> f32 {
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// Tone maps one linear RGB value to 8-bit sRGB: multiply by `exposure`, clamp to [0, 1],
/// apply the sRGB OETF, round to nearest. No other operator (no Reinhard, no filmic):
/// values above 1 / `exposure` saturate. NaN maps to 0.
#[inline]
pub fn tonemap_srgb8(c: [f32; 3], exposure: f32) -> [u8; 3] {
    c.map(|v| {
        let v = v * exposure;
        let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
        (linear_to_srgb(v) * 255.0 + 0.5) as u8
    })
}

/// Writes `img` as an 8-bit sRGB PNG through [`tonemap_srgb8`]. `exposure` is a linear
/// scale factor (1.0 = as is; `2f32.powf(stops)` for photographic stops). The output is
/// deterministic and the write is atomic (temporary file + rename); errors name `path`.
pub fn write_png(path: &Path, img: &Image, exposure: f32) -> Result<()> {
    if img.width == 0 || img.height == 0 {
        bail!("cannot write PNG {}: image is empty ({}x{})", path.display(), img.width, img.height);
    }
    if img.data.len() != img.width as usize * img.height as usize {
        bail!("cannot write PNG {}: image data does not match {}x{}", path.display(), img.width, img.height);
    }
    let mut rgb = Vec::with_capacity(img.data.len() * 3);
    for &p in &img.data {
        rgb.extend_from_slice(&tonemap_srgb8(p, exposure));
    }
    let mut bytes = Vec::new();
    ::image::codecs::png::PngEncoder::new(&mut bytes)
        .write_image(&rgb, img.width, img.height, ::image::ExtendedColorType::Rgb8)
        .map_err(|e| anyhow!("cannot write PNG {}: {e}", path.display()))?;
    write_atomic(path, "PNG", |w| Ok(w.write_all(&bytes)?))
}
