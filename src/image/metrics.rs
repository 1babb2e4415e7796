//! Error metrics against a reference image, and a false-colour error image.

use super::{luminance, Image};
use anyhow::{bail, Result};
use std::fmt;

/// The epsilon of [`Metrics::rel_mse`]: `(a - b)^2 / (b^2 + REL_MSE_EPSILON)`. It keeps
/// black reference pixels from dominating (an error of 0.1 on black counts as 1.0).
pub const REL_MSE_EPSILON: f64 = 1e-2;

/// Errors of an image against a reference, over all pixels and the three channels
/// (accumulated in f64). A NaN or infinite value in either image makes every field
/// non-finite rather than being skipped.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Metrics {
    /// sqrt(mean((a - b)^2)).
    pub rmse: f64,
    /// mean((a - b)^2 / (b^2 + 1e-2)), b the reference ([`REL_MSE_EPSILON`]).
    pub rel_mse: f64,
    /// |mean(a - b)|: the signed error averaged over the image; noise cancels, bias does not.
    pub mean_abs_bias: f64,
    /// max |a - b|.
    pub max_abs: f64,
}

impl fmt::Display for Metrics {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "rmse {:.6e}, relMSE {:.6e}, |bias| {:.6e}, max |err| {:.6e}",
            self.rmse, self.rel_mse, self.mean_abs_bias, self.max_abs
        )
    }
}

/// Computes [`Metrics`] of `a` against `reference`. Errors if the sizes differ or the
/// images are empty.
pub fn compare(a: &Image, reference: &Image) -> Result<Metrics> {
    if !a.same_size(reference) {
        bail!(
            "cannot compare a {}x{} image with a {}x{} reference",
            a.width,
            a.height,
            reference.width,
            reference.height
        );
    }
    if a.data.is_empty() || a.data.len() != reference.data.len() {
        bail!("cannot compare empty or malformed images ({}x{})", a.width, a.height);
    }
    let (mut se, mut rel, mut sum, mut max) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for (p, q) in a.data.iter().zip(&reference.data) {
        for c in 0..3 {
            let (x, r) = (p[c] as f64, q[c] as f64);
            let d = x - r;
            se += d * d;
            rel += d * d / (r * r + REL_MSE_EPSILON);
            sum += d;
            let ad = d.abs();
            if ad.is_nan() || max.is_nan() {
                max = f64::NAN;
            } else if ad > max {
                max = ad;
            }
        }
    }
    let n = (a.data.len() * 3) as f64;
    Ok(Metrics { rmse: (se / n).sqrt(), rel_mse: rel / n, mean_abs_bias: (sum / n).abs(), max_abs: max })
}

/// The colour ramp of [`false_color_error`] at `t` (clamped to [0, 1]): black, blue, cyan,
/// green, yellow, red. The stops are sRGB display colours converted to linear, so a PNG
/// written with exposure 1 shows exactly these colours. NaN gives magenta.
pub fn error_ramp(t: f32) -> [f32; 3] {
    const STOPS: [[f32; 3]; 6] =
        [[0.0, 0.0, 0.0], [0.1, 0.1, 0.8], [0.0, 0.7, 0.9], [0.2, 0.9, 0.2], [1.0, 0.9, 0.0], [1.0, 0.1, 0.0]];
    if t.is_nan() {
        return [1.0, 0.0, 1.0];
    }
    let s = t.clamp(0.0, 1.0) * (STOPS.len() - 1) as f32;
    let i = (s.floor() as usize).min(STOPS.len() - 2);
    let f = s - i as f32;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    [0, 1, 2].map(|c| srgb_to_linear(a[c] + (b[c] - a[c]) * f))
}

fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// Per-pixel error luminance `luminance(|a - b|)` (channel-wise absolute difference, so
/// colour errors show too), divided by the 99th percentile of that error over the image
/// (or by its maximum when the percentile is 0) and mapped through [`error_ramp`]. The
/// robust scale keeps a few fireflies from turning everything else black. Non-finite
/// errors are magenta. Panics if the sizes differ (call [`compare`] first).
pub fn false_color_error(a: &Image, b: &Image) -> Image {
    let err = error_luminance(a, b);
    let mut finite: Vec<f32> = err.iter().copied().filter(|e| e.is_finite()).collect();
    let scale = if finite.is_empty() {
        0.0
    } else {
        let k = ((finite.len() - 1) as f64 * 0.99).round() as usize;
        let (_, p99, _) = finite.select_nth_unstable_by(k, |x, y| x.total_cmp(y));
        let p99 = *p99;
        if p99 > 0.0 {
            p99
        } else {
            finite.iter().copied().fold(0.0, f32::max)
        }
    };
    ramp_image(a, &err, scale)
}

/// Like [`false_color_error`] with a fixed scale: an error luminance of `scale` (or more)
/// maps to the top of the ramp. Panics if the sizes differ.
pub fn false_color_error_scaled(a: &Image, b: &Image, scale: f32) -> Image {
    let err = error_luminance(a, b);
    ramp_image(a, &err, scale)
}

fn error_luminance(a: &Image, b: &Image) -> Vec<f32> {
    assert!(
        a.same_size(b) && a.data.len() == b.data.len(),
        "false-colour error of a {}x{} image against a {}x{} image",
        a.width,
        a.height,
        b.width,
        b.height
    );
    a.data.iter().zip(&b.data).map(|(p, q)| luminance([0, 1, 2].map(|c| (p[c] - q[c]).abs()))).collect()
}

fn ramp_image(a: &Image, err: &[f32], scale: f32) -> Image {
    let data = err
        .iter()
        .map(|&e| {
            if !e.is_finite() {
                error_ramp(f32::NAN)
            } else if scale > 0.0 {
                error_ramp(e / scale)
            } else {
                error_ramp(0.0)
            }
        })
        .collect();
    Image { width: a.width, height: a.height, data }
}
