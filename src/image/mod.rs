//! Image output (EXR, PNG) and error metrics.
//!
//! - [`Image`]: linear RGB, `f32` per channel, row 0 at the top, row-major.
//! - [`write_exr`] / [`read_exr`]: linear float32 EXR with `vkvcm:*` string metadata; the
//!   writer is byte-deterministic (same image + metadata -> same bytes) and atomic.
//! - [`write_png`]: tone-mapped 8-bit sRGB preview (exposure scale, clamp, sRGB OETF), atomic.
//! - [`compare`] / [`Metrics`] and [`false_color_error`]: error against a reference.
//!
//! Every file is written to a temporary file in the target directory and renamed over the
//! destination, so a crash never leaves a truncated file where a good one was.

mod atomic;
mod exr_io;
mod metrics;
pub mod plot;
mod png_io;

pub use exr_io::{
    decode_exr_channels, read_exr, read_exr_channels, write_exr, write_exr_channels, write_exr_with, ExrCompression,
    ExtraChannel, Samples,
};
pub use metrics::{compare, error_ramp, false_color_error, false_color_error_scaled, Metrics, REL_MSE_EPSILON};
pub use png_io::{linear_to_srgb, tonemap_srgb8, write_png};

use anyhow::{bail, Result};

/// Rec. 709 / sRGB-primaries luminance of a linear RGB value.
#[inline]
pub fn luminance(c: [f32; 3]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

/// A linear RGB image: `data[y * width + x]`, row 0 is the top row.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub data: Vec<[f32; 3]>,
}

impl Image {
    /// A black image.
    pub fn new(width: u32, height: u32) -> Self {
        Self::filled(width, height, [0.0; 3])
    }

    /// An image with every pixel set to `value`.
    pub fn filled(width: u32, height: u32, value: [f32; 3]) -> Self {
        Self { width, height, data: vec![value; width as usize * height as usize] }
    }

    /// An image with pixel (x, y) set to `f(x, y)`, evaluated in row-major order.
    pub fn from_fn(width: u32, height: u32, mut f: impl FnMut(u32, u32) -> [f32; 3]) -> Self {
        let mut data = Vec::with_capacity(width as usize * height as usize);
        for y in 0..height {
            for x in 0..width {
                data.push(f(x, y));
            }
        }
        Self { width, height, data }
    }

    /// Wraps existing pixel data; errors if `data.len() != width * height`.
    pub fn from_data(width: u32, height: u32, data: Vec<[f32; 3]>) -> Result<Self> {
        let expected = width as usize * height as usize;
        if data.len() != expected {
            bail!("image data has {} pixels, expected {width}x{height} = {expected}", data.len());
        }
        Ok(Self { width, height, data })
    }

    /// Number of pixels (`width * height`).
    pub fn pixel_count(&self) -> usize {
        self.data.len()
    }

    /// Index of pixel (x, y) in `data`. Panics when out of bounds.
    #[inline]
    pub fn index(&self, x: u32, y: u32) -> usize {
        assert!(x < self.width && y < self.height, "pixel ({x}, {y}) outside a {}x{} image", self.width, self.height);
        y as usize * self.width as usize + x as usize
    }

    /// Pixel (x, y). Panics when out of bounds.
    #[inline]
    pub fn get(&self, x: u32, y: u32) -> [f32; 3] {
        self.data[self.index(x, y)]
    }

    /// Sets pixel (x, y). Panics when out of bounds.
    #[inline]
    pub fn set(&mut self, x: u32, y: u32, value: [f32; 3]) {
        let i = self.index(x, y);
        self.data[i] = value;
    }

    /// True when both images have the same width and height.
    pub fn same_size(&self, other: &Image) -> bool {
        self.width == other.width && self.height == other.height
    }

    /// Mean of each channel over all pixels (accumulated in f64). Zero for an empty image.
    pub fn mean(&self) -> [f64; 3] {
        let mut sum = [0.0f64; 3];
        for p in &self.data {
            for c in 0..3 {
                sum[c] += p[c] as f64;
            }
        }
        let n = self.data.len().max(1) as f64;
        sum.map(|s| s / n)
    }

    /// Mean luminance over all pixels.
    pub fn mean_luminance(&self) -> f64 {
        let m = self.mean();
        0.2126 * m[0] + 0.7152 * m[1] + 0.0722 * m[2]
    }

    /// Number of pixels with at least one NaN or infinite channel.
    pub fn non_finite_count(&self) -> usize {
        self.data.iter().filter(|p| !p.iter().all(|v| v.is_finite())).count()
    }

    /// Applies `f` to every pixel.
    pub fn map(&self, mut f: impl FnMut([f32; 3]) -> [f32; 3]) -> Image {
        Image { width: self.width, height: self.height, data: self.data.iter().map(|&p| f(p)).collect() }
    }

    /// Multiplies every channel by `s`.
    pub fn scale(&mut self, s: f32) {
        for p in &mut self.data {
            *p = p.map(|v| v * s);
        }
    }

    /// Per-pixel mean of several images of the same size (accumulated in f64).
    pub fn average(images: &[Image]) -> Result<Image> {
        let Some(first) = images.first() else { bail!("cannot average an empty list of images") };
        let mut sum = vec![[0.0f64; 3]; first.data.len()];
        for (k, img) in images.iter().enumerate() {
            if !img.same_size(first) {
                bail!("image {k} is {}x{}, image 0 is {}x{}", img.width, img.height, first.width, first.height);
            }
            for (s, p) in sum.iter_mut().zip(&img.data) {
                for c in 0..3 {
                    s[c] += p[c] as f64;
                }
            }
        }
        let inv = 1.0 / images.len() as f64;
        let data = sum.into_iter().map(|s| s.map(|v| (v * inv) as f32)).collect();
        Ok(Image { width: first.width, height: first.height, data })
    }

    /// Box-filters `factor` x `factor` blocks into one pixel. A partial block at the right or
    /// bottom edge (when the size is not a multiple of `factor`) is dropped. Useful in render
    /// tests: averaging blocks lowers the per-pixel noise and the number of tests.
    pub fn downsample(&self, factor: u32) -> Image {
        assert!(factor >= 1, "downsample factor must be at least 1");
        let (w, h) = (self.width / factor, self.height / factor);
        let inv = 1.0 / (factor as f64 * factor as f64);
        Image::from_fn(w, h, |x, y| {
            let mut s = [0.0f64; 3];
            for dy in 0..factor {
                for dx in 0..factor {
                    let p = self.get(x * factor + dx, y * factor + dy);
                    for c in 0..3 {
                        s[c] += p[c] as f64;
                    }
                }
            }
            s.map(|v| (v * inv) as f32)
        })
    }

    /// The `w` x `h` sub-image whose top-left pixel is (x, y). Panics when it does not fit.
    pub fn crop(&self, x: u32, y: u32, w: u32, h: u32) -> Image {
        assert!(
            x as u64 + w as u64 <= self.width as u64 && y as u64 + h as u64 <= self.height as u64,
            "crop {w}x{h} at ({x}, {y}) does not fit a {}x{} image",
            self.width,
            self.height
        );
        Image::from_fn(w, h, |i, j| self.get(x + i, y + j))
    }
}

/// Writes `value` as pretty JSON, atomically (a complete file or none).
pub fn write_json<T: serde::Serialize>(path: &std::path::Path, value: &T) -> anyhow::Result<()> {
    let text = serde_json::to_string_pretty(value)?;
    atomic::write_atomic(path, "JSON", |w| Ok(w.write_all(text.as_bytes())?))
}
