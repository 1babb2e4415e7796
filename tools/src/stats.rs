//! Per-pixel hypothesis tests between renders, after Mitsuba 3's `test_renders`.
//!
//! Given K independent renders of estimator A (different seeds) and K' of estimator B, each
//! pixel and **each channel** (R, G, B separately, so a colour error that keeps luminance
//! still shows) gets the sample mean and the unbiased sample variance, and the statistic
//!
//! ```text
//! t = (mean_A - mean_B) / sqrt(var_A / K + var_B / K')
//! ```
//!
//! **Small K.** With K of 4 to 8 the variances are themselves noisy, so `t` is not normal,
//! and comparing it with a normal quantile at a Šidák-corrected level (~1e-6) fails good
//! renders most of the time (t with 3 degrees of freedom exceeds 4.65 about 2% of the time,
//! not 3e-6). Welch–Satterthwaite degrees of freedom fix the bulk of the distribution but
//! not its far tail: measured over 2000 trials of 32x32 images at alpha = 0.01, K = 4 with
//! 10x the standard deviation of K' = 8 failed 60% of same-distribution trials. So the test
//! uses the conservative degrees of freedom `df = min(K, K') - 1` (Hsu; shown conservative
//! for every variance ratio by Mickey & Brown, 1966), computes the exact two-sided p-value
//! of Student's t with `df`, and reports it as the equivalent normal score
//! `z = sign(t) * Phi^-1(1 - p/2)`. A test fails when `|z|` exceeds the two-sided normal
//! quantile of the per-test significance, exactly as a z-test would; as K grows, `z` tends
//! to `t`. The price is power: at 3e-6 per test a bias must exceed ~88 standard errors to
//! show with K = 4, ~13 with K = 8, ~7 with K = 16, ~5 with K = 64. For sensitive tests,
//! use more renders, [`Image::downsample`] them (fewer tests, less noise per pixel), or
//! build [`PixelStats::from_sums`] from per-iteration moments (each iteration with fresh
//! random numbers is an independent sample, so `count` is the iteration count).
//!
//! Significance: `alpha` is for the whole image. Šidák's correction over the N pixels
//! gives `alpha_per_pixel = 1 - (1 - alpha)^(1/N)`, and again over the three channels of a
//! pixel `alpha_per_test = 1 - (1 - alpha_per_pixel)^(1/3)`, i.e. Šidák over all 3N tests
//! (exact for independent tests, conservative for the correlated channels of a pixel).
//!
//! Special cases: a test whose two means agree to 1e-6 relative passes (differences below
//! f32 accumulation precision are not bias); when the combined standard error is below
//! [`EXACT_RELATIVE`] (1e-5) of the mean (two exact values, which two renderers' f32
//! arithmetic may round differently by tens of ulps; vkvcm's film adds its 2^-32 rounding
//! bound to such a pixel's variance) the test passes up to that relative difference, and
//! with both variances zero any larger difference fails with `z = ±inf`;
//! a NaN or infinite mean or
//! variance fails the pixel and is counted in [`ZTest::non_finite`]. The one-sample test
//! against a known image (zero variance) has `df = K - 1`, which is exact.
//!
//! Caveat for render tests: the test assumes each render's pixel value is roughly normal
//! across seeds. Use enough samples per pixel per render that fireflies are not the whole
//! story, or downsample.

use anyhow::{anyhow, bail, Result};
use std::fmt;
use std::path::{Path, PathBuf};
use vkvcm::image::{error_ramp, false_color_error, write_exr, write_png, Image};

/// Relative difference of two means below which a test passes regardless of variance.
pub const EQUAL_RELATIVE: f64 = 1e-6;

/// Relative difference below which two means pass whose combined standard error is below
/// the same fraction of the mean (exact values: e.g. a constant background seen through a
/// mirror, with no random decision on the way). Another renderer's f32 arithmetic was seen 2.3e-6 away from vkvcm's
/// on such pixels (Mitsuba 3, tests/render_environment.rs: 0.8999979 against 0.9).
pub const EXACT_RELATIVE: f64 = 1e-5;

/// Per-pixel, per-channel sample statistics of `count` independent observations.
#[derive(Clone, Debug, PartialEq)]
pub struct PixelStats {
    pub width: u32,
    pub height: u32,
    /// Number of independent observations (renders) behind each pixel.
    pub count: usize,
    /// Sample mean per pixel and channel.
    pub mean: Vec<[f64; 3]>,
    /// Unbiased sample variance of one observation (divides by `count - 1`).
    pub variance: Vec<[f64; 3]>,
}

impl PixelStats {
    /// Mean and unbiased variance (two-pass, in f64) of at least two same-size images.
    pub fn from_images(images: &[Image]) -> Result<Self> {
        if images.len() < 2 {
            bail!("need at least 2 independent images to estimate a variance, got {}", images.len());
        }
        let first = &images[0];
        for (k, img) in images.iter().enumerate() {
            if !img.same_size(first) || img.data.len() != first.data.len() {
                bail!("image {k} is {}x{}, image 0 is {}x{}", img.width, img.height, first.width, first.height);
            }
        }
        let n = first.data.len();
        let mut mean = vec![[0.0f64; 3]; n];
        for img in images {
            for (m, p) in mean.iter_mut().zip(&img.data) {
                for c in 0..3 {
                    m[c] += p[c] as f64;
                }
            }
        }
        let k = images.len() as f64;
        for m in &mut mean {
            *m = m.map(|v| v / k);
        }
        let mut variance = vec![[0.0f64; 3]; n];
        for img in images {
            for ((v, m), p) in variance.iter_mut().zip(&mean).zip(&img.data) {
                for c in 0..3 {
                    let d = p[c] as f64 - m[c];
                    v[c] += d * d;
                }
            }
        }
        for v in &mut variance {
            *v = v.map(|s| s / (k - 1.0));
        }
        Ok(Self { width: first.width, height: first.height, count: images.len(), mean, variance })
    }

    /// Statistics from per-pixel sums of `count` independent observations and of their
    /// squares (e.g. a film that accumulates each iteration's value and its square).
    /// `variance = (sum_sq - sum^2 / count) / (count - 1)`, clamped at 0; accumulate in f64
    /// (or exact integers) so the difference does not cancel away.
    pub fn from_sums(width: u32, height: u32, count: usize, sum: &[[f64; 3]], sum_sq: &[[f64; 3]]) -> Result<Self> {
        let n = width as usize * height as usize;
        if sum.len() != n || sum_sq.len() != n {
            bail!("sums have {} and {} pixels, expected {width}x{height}", sum.len(), sum_sq.len());
        }
        if count < 2 {
            bail!("need at least 2 observations per pixel to estimate a variance, got {count}");
        }
        let k = count as f64;
        let mean = sum.iter().map(|s| s.map(|v| v / k)).collect();
        let variance = sum
            .iter()
            .zip(sum_sq)
            .map(|(s, q)| [0, 1, 2].map(|c| ((q[c] - s[c] * s[c] / k) / (k - 1.0)).max(0.0)))
            .collect();
        Ok(Self { width, height, count, mean, variance })
    }

    /// The mean as an image.
    pub fn mean_image(&self) -> Image {
        Image { width: self.width, height: self.height, data: self.mean.iter().map(|m| m.map(|v| v as f32)).collect() }
    }

    /// The standard error of the mean, sqrt(variance / count), as an image.
    pub fn std_error_image(&self) -> Image {
        let k = self.count as f64;
        let data = self.variance.iter().map(|v| v.map(|s| (s / k).sqrt() as f32)).collect();
        Image { width: self.width, height: self.height, data }
    }

    /// Each pixel of `keep` with, per channel, the mean of the variances of the pixels of
    /// `keep` in its 3 x 3 neighbourhood (itself included); the others unchanged. For an
    /// estimator whose variance comes from rare events (a sharp metal's samples lost below
    /// the horizon, about 1 in 400), a pixel's own sample variance is near 0 whenever none
    /// of its samples had one, though its mean is right; where neighbouring pixels draw
    /// from nearly the same distribution, their pooled variance is the better estimate.
    pub fn with_pooled_variance(&self, keep: &[bool]) -> Self {
        let (w, h) = (self.width as i64, self.height as i64);
        let mut out = self.clone();
        for i in 0..self.variance.len() {
            if !keep[i] {
                continue;
            }
            let (x, y) = (i as i64 % w, i as i64 / w);
            let (mut sum, mut n) = ([0.0f64; 3], 0usize);
            for (nx, ny) in (-1..=1).flat_map(|dy| (-1..=1).map(move |dx| (x + dx, y + dy))) {
                let j = (ny * w + nx) as usize;
                if nx >= 0 && ny >= 0 && nx < w && ny < h && keep[j] {
                    for (s, v) in sum.iter_mut().zip(self.variance[j]) {
                        *s += v;
                    }
                    n += 1;
                }
            }
            out.variance[i] = sum.map(|s| s / n as f64);
        }
        out
    }

    fn check(&self, what: &str) -> Result<()> {
        if self.count < 2 {
            bail!("{what}: need at least 2 observations per pixel, got {}", self.count);
        }
        let n = self.width as usize * self.height as usize;
        if n == 0 || self.mean.len() != n || self.variance.len() != n {
            bail!("{what}: statistics do not match a non-empty {}x{} image", self.width, self.height);
        }
        Ok(())
    }
}

/// Values of the test with the largest |z|.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TestValues {
    pub mean_a: f64,
    pub mean_b: f64,
    /// Standard errors of the two means (0 for an exact expected image).
    pub std_err_a: f64,
    pub std_err_b: f64,
    /// The t statistic and its (conservative) degrees of freedom; NaN df when the means
    /// were equal within [`EQUAL_RELATIVE`] (or [`EXACT_RELATIVE`] with a standard error
    /// below it) or both variances were zero.
    pub t: f64,
    pub df: f64,
}

/// Result of a per-pixel test; see the module documentation.
#[derive(Clone, Debug)]
pub struct ZTest {
    pub width: u32,
    pub height: u32,
    /// Pixels tested (N), all of the image.
    pub pixels: usize,
    /// Pixels with at least one failing channel (non-finite pixels included).
    pub failed: usize,
    /// Pixels with a NaN or infinite mean or variance in A or B.
    pub non_finite: usize,
    /// Renders behind A and B (B's is 0 for an exact expected image).
    pub count_a: usize,
    pub count_b: usize,
    /// Overall significance.
    pub alpha: f64,
    /// Šidák per-pixel significance 1 - (1 - alpha)^(1/N).
    pub alpha_per_pixel: f64,
    /// Šidák per-channel significance 1 - (1 - alpha_per_pixel)^(1/3).
    pub alpha_per_test: f64,
    /// Two-sided normal quantile of `alpha_per_test`: a test fails when |z| exceeds it.
    pub z_threshold: f64,
    /// Signed normal-equivalent score of the worst test (largest |z| among finite pixels).
    pub worst_z: f64,
    pub worst_pixel: (u32, u32),
    /// Channel of the worst test: 0 = R, 1 = G, 2 = B.
    pub worst_channel: usize,
    pub worst: TestValues,
    /// First pixel (row-major) with a non-finite value, if any.
    pub first_non_finite: Option<(u32, u32)>,
    /// Mean of A, mean of B (or the expected image), and the signed z of every test
    /// (NaN where non-finite): for [`ZTest::dump`].
    pub mean_a: Image,
    pub mean_b: Image,
    pub z: Image,
}

impl ZTest {
    /// True when no pixel failed.
    pub fn passed(&self) -> bool {
        self.failed == 0
    }

    /// Fraction of pixels that failed.
    pub fn fraction_failed(&self) -> f64 {
        self.failed as f64 / self.pixels.max(1) as f64
    }

    /// Writes `mean.exr` (A), `ref.exr` (B), `error.exr` (|A - B|), `z.exr` (|z| per channel),
    /// `error.png` (false colour) and `z.png` (|z| / threshold on the ramp: red = failed)
    /// into `target/test-failures/<name>/` (see [`failure_dir`]); returns that directory.
    pub fn dump(&self, name: &str) -> Result<PathBuf> {
        let error = Image {
            width: self.width,
            height: self.height,
            data: self
                .mean_a
                .data
                .iter()
                .zip(&self.mean_b.data)
                .map(|(a, b)| [0, 1, 2].map(|c| (a[c] - b[c]).abs()))
                .collect(),
        };
        let abs_z = self.z.map(|z| z.map(f32::abs));
        let dir = dump_on_failure(
            &failure_dir(),
            name,
            &[("mean", &self.mean_a), ("ref", &self.mean_b), ("error", &error), ("z", &abs_z)],
        )?;
        write_png(&dir.join("error.png"), &false_color_error(&self.mean_a, &self.mean_b), 1.0)?;
        let thr = self.z_threshold as f32;
        let z_ramp = abs_z.map(|z| {
            let worst =
                z.iter().copied().fold(0.0f32, |m, v| if v.is_nan() || m.is_nan() { f32::NAN } else { m.max(v) });
            error_ramp(if worst.is_nan() { f32::NAN } else { worst / thr })
        });
        write_png(&dir.join("z.png"), &z_ramp, 1.0)?;
        Ok(dir)
    }

    /// Panics with the report (and the directory of [`ZTest::dump`]'s images) unless the
    /// test passed.
    #[track_caller]
    pub fn assert_passed(&self, name: &str) {
        if !self.passed() {
            match self.dump(name) {
                Ok(dir) => panic!("{name}: {self}\nimages: {}", dir.display()),
                Err(e) => panic!("{name}: {self}\n(could not write images: {e:#})"),
            }
        }
    }
}

impl fmt::Display for ZTest {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        const CH: [&str; 3] = ["R", "G", "B"];
        write!(
            f,
            "z-test {}: {} of {} pixels failed (alpha {}, Šidák per pixel {:.3e}, per channel {:.3e}, |z| threshold {:.3})",
            if self.passed() { "passed" } else { "FAILED" },
            self.failed,
            self.pixels,
            self.alpha,
            self.alpha_per_pixel,
            self.alpha_per_test,
            self.z_threshold
        )?;
        if self.non_finite > 0 {
            let (x, y) = self.first_non_finite.unwrap_or_default();
            write!(f, "; {} pixels have NaN/Inf values, first at ({x}, {y})", self.non_finite)?;
        }
        let w = &self.worst;
        let (x, y) = self.worst_pixel;
        write!(
            f,
            "; worst pixel ({x}, {y}) channel {}: z = {:.3} (t = {:.3}, df = {:.1}), A = {:.6e} ± {:.3e} (K = {}), ",
            CH[self.worst_channel], self.worst_z, w.t, w.df, w.mean_a, w.std_err_a, self.count_a
        )?;
        if self.count_b == 0 {
            write!(f, "expected = {:.6e}", w.mean_b)
        } else {
            write!(f, "B = {:.6e} ± {:.3e} (K = {})", w.mean_b, w.std_err_b, self.count_b)
        }
    }
}

/// Two-sample test of every pixel and channel, A's renders against B's (unequal variances,
/// conservative degrees of freedom); see the module docs.
/// Panics (with the reason) on fewer than 2 images per side, different sizes, or an
/// `alpha` outside (0, 1); [`welch_test`] returns those as errors.
pub fn z_test(a: &[Image], b: &[Image], alpha: f64) -> ZTest {
    let run = || -> Result<ZTest> { welch_test(&PixelStats::from_images(a)?, &PixelStats::from_images(b)?, alpha) };
    run().unwrap_or_else(|e| panic!("z_test: {e:#}"))
}

/// One-sample test of A's renders against a known image (zero variance, e.g. an analytic
/// solution): `t = (mean_A - expected) / sqrt(var_A / K)` with K - 1 degrees of freedom.
/// Panics like [`z_test`]; [`one_sample_test`] returns errors.
pub fn z_test_analytic(a: &[Image], expected: &Image, alpha: f64) -> ZTest {
    let run = || -> Result<ZTest> { one_sample_test(&PixelStats::from_images(a)?, expected, alpha) };
    run().unwrap_or_else(|e| panic!("z_test_analytic: {e:#}"))
}

/// [`z_test`] on precomputed statistics (e.g. from a film that keeps per-pixel moments).
pub fn welch_test(a: &PixelStats, b: &PixelStats, alpha: f64) -> Result<ZTest> {
    a.check("welch_test A")?;
    b.check("welch_test B")?;
    if a.width != b.width || a.height != b.height {
        bail!("welch_test: A is {}x{}, B is {}x{}", a.width, a.height, b.width, b.height);
    }
    let (ka, kb) = (a.count as f64, b.count as f64);
    run_tests(a.width, a.height, alpha, a.count, b.count, |i, c| {
        (
            Side { mean: a.mean[i][c], se2: a.variance[i][c] / ka, dof: ka - 1.0 },
            Side { mean: b.mean[i][c], se2: b.variance[i][c] / kb, dof: kb - 1.0 },
        )
    })
}

/// An image mean (every pixel and channel) with its standard error and the number of
/// independent observations its error is estimated from (for the degrees of freedom).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeanEstimate {
    pub mean: f64,
    pub std_error: f64,
    pub samples: usize,
}

impl MeanEstimate {
    /// From the image means of independent blocks of a render's iterations (at least 2):
    /// their spread is the error whatever correlates the render's pixels (light tracing's
    /// and merging's splats).
    pub fn of_blocks(block_means: &[f64]) -> Result<MeanEstimate> {
        if block_means.len() < 2 {
            bail!("an image mean's error needs at least 2 blocks, got {}", block_means.len());
        }
        let b = block_means.len() as f64;
        let mean = block_means.iter().sum::<f64>() / b;
        let var_mean = block_means.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / ((b - 1.0) * b);
        Ok(MeanEstimate { mean, std_error: var_mean.sqrt(), samples: block_means.len() })
    }

    /// From per-pixel statistics whose pixels are independent (one path tracer's renders),
    /// each pixel's channels taken as fully correlated.
    pub fn of_independent_pixels(st: &PixelStats) -> Result<MeanEstimate> {
        st.check("an image mean's statistics")?;
        let n = st.mean.len() as f64;
        let mean = st.mean.iter().flatten().sum::<f64>() / (3.0 * n);
        let channel_sd = |v: &[f64; 3]| v.iter().map(|x| x.sqrt()).sum::<f64>() / 3.0;
        let var_mean = st.variance.iter().map(|v| channel_sd(v).powi(2)).sum::<f64>() / (n * n * st.count as f64);
        Ok(MeanEstimate { mean, std_error: var_mean.sqrt(), samples: st.count })
    }
}

/// Two image means compared by [`image_mean_test`].
#[derive(Clone, Copy, Debug)]
pub struct ImageMeanTest {
    pub a: MeanEstimate,
    pub b: MeanEstimate,
    pub t: f64,
    pub df: f64,
    /// Two-sided p-value of `t` with `df` degrees of freedom.
    pub p: f64,
}

impl fmt::Display for ImageMeanTest {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "image means {:.5} +- {:.5} and {:.5} +- {:.5}: t {:.2} ({} df), p {:.2e}",
            self.a.mean, self.a.std_error, self.b.mean, self.b.std_error, self.t, self.df, self.p
        )
    }
}

/// Welch's t of two image means with the conservative min(samples) - 1 degrees of freedom
/// (the module docs), two-sided.
pub fn image_mean_test(a: MeanEstimate, b: MeanEstimate) -> ImageMeanTest {
    let se = a.std_error.hypot(b.std_error);
    let t = if a.mean == b.mean { 0.0 } else { (a.mean - b.mean) / se };
    let df = (a.samples.min(b.samples).max(2) - 1) as f64;
    ImageMeanTest { a, b, t, df, p: student_t_two_sided_p(t, df) }
}

/// [`z_test_analytic`] on precomputed statistics.
pub fn one_sample_test(a: &PixelStats, expected: &Image, alpha: f64) -> Result<ZTest> {
    a.check("one_sample_test")?;
    if a.width != expected.width || a.height != expected.height || expected.data.len() != a.mean.len() {
        bail!(
            "one_sample_test: A is {}x{}, expected image is {}x{}",
            a.width,
            a.height,
            expected.width,
            expected.height
        );
    }
    let ka = a.count as f64;
    run_tests(a.width, a.height, alpha, a.count, 0, |i, c| {
        (
            Side { mean: a.mean[i][c], se2: a.variance[i][c] / ka, dof: ka - 1.0 },
            Side { mean: expected.data[i][c] as f64, se2: 0.0, dof: f64::INFINITY },
        )
    })
}

/// One side of a test: a mean, its squared standard error and the degrees of freedom of
/// that error estimate (infinite when exact).
#[derive(Clone, Copy)]
struct Side {
    mean: f64,
    se2: f64,
    dof: f64,
}

/// Outcome of one test: normal-equivalent z (NaN when non-finite), t and df.
fn test_one(a: Side, b: Side) -> (f64, f64, f64) {
    if !(a.mean.is_finite() && b.mean.is_finite() && a.se2.is_finite() && b.se2.is_finite()) {
        return (f64::NAN, f64::NAN, f64::NAN);
    }
    let diff = a.mean - b.mean;
    if diff.abs() <= EQUAL_RELATIVE * a.mean.abs().max(b.mean.abs()) {
        return (0.0, 0.0, f64::NAN);
    }
    let se2 = a.se2 + b.se2;
    let resolution = EXACT_RELATIVE * a.mean.abs().max(b.mean.abs());
    if se2 <= resolution * resolution && diff.abs() <= resolution {
        return (0.0, 0.0, f64::NAN);
    }
    if se2 <= 0.0 {
        let inf = f64::INFINITY.copysign(diff);
        return (inf, inf, f64::NAN);
    }
    let t = diff / se2.sqrt();
    // Conservative degrees of freedom: the smaller of the two sides that carry variance.
    let df = match (a.se2 > 0.0, b.se2 > 0.0) {
        (true, true) => a.dof.min(b.dof),
        (true, false) => a.dof,
        _ => b.dof,
    };
    let p = student_t_two_sided_p(t, df);
    let z = (-inverse_normal_cdf(0.5 * p)).copysign(t);
    (z, t, df)
}

fn run_tests(
    width: u32,
    height: u32,
    alpha: f64,
    count_a: usize,
    count_b: usize,
    side: impl Fn(usize, usize) -> (Side, Side),
) -> Result<ZTest> {
    if !(alpha > 0.0 && alpha < 1.0) {
        bail!("significance alpha must be in (0, 1), got {alpha}");
    }
    let n = width as usize * height as usize;
    let alpha_per_pixel = sidak(alpha, n);
    let alpha_per_test = sidak(alpha_per_pixel, 3);
    let z_threshold = -inverse_normal_cdf(0.5 * alpha_per_test);

    let mut mean_a = Image::new(width, height);
    let mut mean_b = Image::new(width, height);
    let mut z_img = Image::new(width, height);
    let (mut failed, mut non_finite) = (0usize, 0usize);
    let mut first_non_finite = None;
    let mut worst = (0.0f64, 0usize, 0usize, TestValues::default());
    for i in 0..n {
        let (x, y) = ((i % width as usize) as u32, (i / width as usize) as u32);
        let (mut fail, mut bad) = (false, false);
        for c in 0..3 {
            let (a, b) = side(i, c);
            let (z, t, df) = test_one(a, b);
            mean_a.data[i][c] = a.mean as f32;
            mean_b.data[i][c] = b.mean as f32;
            z_img.data[i][c] = z as f32;
            if z.is_nan() {
                bad = true;
                continue;
            }
            fail |= z.abs() > z_threshold;
            if z.abs() > worst.0.abs() {
                let values = TestValues {
                    mean_a: a.mean,
                    mean_b: b.mean,
                    std_err_a: a.se2.sqrt(),
                    std_err_b: b.se2.sqrt(),
                    t,
                    df,
                };
                worst = (z, i, c, values);
            }
        }
        if bad {
            non_finite += 1;
            first_non_finite.get_or_insert((x, y));
        }
        if fail || bad {
            failed += 1;
        }
    }
    let w = width.max(1) as usize;
    Ok(ZTest {
        width,
        height,
        pixels: n,
        failed,
        non_finite,
        count_a,
        count_b,
        alpha,
        alpha_per_pixel,
        alpha_per_test,
        z_threshold,
        worst_z: worst.0,
        worst_pixel: ((worst.1 % w) as u32, (worst.1 / w) as u32),
        worst_channel: worst.2,
        worst: worst.3,
        first_non_finite,
        mean_a,
        mean_b,
        z: z_img,
    })
}

/// Šidák's per-test significance for `n` independent tests at overall significance
/// `alpha`: 1 - (1 - alpha)^(1/n), computed without cancellation.
pub fn sidak(alpha: f64, n: usize) -> f64 {
    -(f64::ln_1p(-alpha) / n.max(1) as f64).exp_m1()
}

/// Quantile function (inverse CDF) of the standard normal distribution: Wichura's
/// algorithm AS 241 (PPND16, Applied Statistics 37(3), 1988), about 1e-16 relative
/// accuracy. Returns -inf at 0, +inf at 1 and NaN outside [0, 1].
#[allow(clippy::excessive_precision)] // the published coefficients, verbatim
pub fn inverse_normal_cdf(p: f64) -> f64 {
    if p.is_nan() || !(0.0..=1.0).contains(&p) {
        return f64::NAN;
    }
    if p == 0.0 {
        return f64::NEG_INFINITY;
    }
    if p == 1.0 {
        return f64::INFINITY;
    }
    fn poly(c: &[f64; 8], x: f64) -> f64 {
        c.iter().rev().fold(0.0, |acc, &k| acc * x + k)
    }
    const A: [f64; 8] = [
        3.387_132_872_796_366_608,
        1.331_416_678_917_843_774_5e2,
        1.971_590_950_306_551_442_7e3,
        1.373_169_376_550_946_112_5e4,
        4.592_195_393_154_987_145_7e4,
        6.726_577_092_700_870_085_3e4,
        3.343_057_558_358_812_810_5e4,
        2.509_080_928_730_122_672_7e3,
    ];
    const B: [f64; 8] = [
        1.0,
        4.231_333_070_160_091_125_2e1,
        6.871_870_074_920_579_083e2,
        5.394_196_021_424_751_107_7e3,
        2.121_379_430_158_659_586_7e4,
        3.930_789_580_009_271_061e4,
        2.872_908_573_572_194_267_4e4,
        5.226_495_278_852_854_561e3,
    ];
    const C: [f64; 8] = [
        1.423_437_110_749_683_577_34,
        4.630_337_846_156_545_295_9,
        5.769_497_221_460_691_405_5,
        3.647_848_324_763_204_605_04,
        1.270_458_252_452_368_382_58,
        2.417_807_251_774_506_117_7e-1,
        2.272_384_498_926_918_458_33e-2,
        7.745_450_142_783_414_076_4e-4,
    ];
    const D: [f64; 8] = [
        1.0,
        2.053_191_626_637_758_821_87,
        1.676_384_830_183_803_849_4,
        6.897_673_349_851_000_045_5e-1,
        1.481_039_764_274_800_745_9e-1,
        1.519_866_656_361_645_719_66e-2,
        5.475_938_084_995_344_946e-4,
        1.050_750_071_644_416_843_24e-9,
    ];
    const E: [f64; 8] = [
        6.657_904_643_501_103_777_2,
        5.463_784_911_164_114_369_9,
        1.784_826_539_917_291_335_8,
        2.965_605_718_285_048_912_3e-1,
        2.653_218_952_657_612_309_3e-2,
        1.242_660_947_388_078_438_6e-3,
        2.711_555_568_743_487_578_15e-5,
        2.010_334_399_292_288_132_65e-7,
    ];
    const F: [f64; 8] = [
        1.0,
        5.998_322_065_558_879_376_9e-1,
        1.369_298_809_227_358_053_1e-1,
        1.487_536_129_085_061_485_25e-2,
        7.868_691_311_456_132_591e-4,
        1.846_318_317_510_054_681_8e-5,
        1.421_511_758_316_445_888_7e-7,
        2.044_263_103_389_939_785_64e-15,
    ];
    let q = p - 0.5;
    if q.abs() <= 0.425 {
        let r = 0.180625 - q * q;
        return q * poly(&A, r) / poly(&B, r);
    }
    let tail = if q < 0.0 { p } else { 1.0 - p };
    let r = (-tail.ln()).sqrt();
    let x = if r <= 5.0 {
        let r = r - 1.6;
        poly(&C, r) / poly(&D, r)
    } else {
        let r = r - 5.0;
        poly(&E, r) / poly(&F, r)
    };
    if q < 0.0 {
        -x
    } else {
        x
    }
}

/// Upper tail P(Z > z) of the standard normal distribution, accurate in the far tail
/// (through the regularized incomplete gamma function: erfc(x) = Q(1/2, x^2)).
pub fn normal_sf(z: f64) -> f64 {
    if z.is_nan() {
        return f64::NAN;
    }
    if z < 0.0 {
        return 1.0 - normal_sf(-z);
    }
    let x = 0.5 * z * z;
    0.5 * gamma_q_half(x)
}

/// Two-sided p-value P(|T| >= |t|) of Student's t distribution with `df` (> 0, may be
/// fractional or infinite) degrees of freedom: I_{df/(df+t^2)}(df/2, 1/2), evaluated by the
/// continued fraction on the side that keeps the tail accurate. NaN for invalid input.
pub fn student_t_two_sided_p(t: f64, df: f64) -> f64 {
    if t.is_nan() || df.is_nan() || df <= 0.0 {
        return f64::NAN;
    }
    let t = t.abs();
    if t == f64::INFINITY {
        return 0.0;
    }
    if df > 1e7 {
        return (2.0 * normal_sf(t)).min(1.0);
    }
    let u = t * t / df;
    // x = df / (df + t^2) = 1 / (1 + u), y = 1 - x = u / (1 + u)
    let x = 1.0 / (1.0 + u);
    let y = u / (1.0 + u);
    let ln_x = -u.ln_1p();
    let ln_y = u.ln() - u.ln_1p();
    inc_beta(0.5 * df, 0.5, x, y, ln_x, ln_y)
}

/// ln Γ(x) for x > 0 (Lanczos, g = 7, 9 terms; ~1e-15 relative).
#[allow(clippy::excessive_precision)]
fn ln_gamma(x: f64) -> f64 {
    const G: f64 = 7.0;
    const C: [f64; 9] = [
        0.999_999_999_999_809_93,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_13,
        -176.615_029_162_140_59,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_571_6e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        // Γ(x) = Γ(x + 1) / x keeps the series in its accurate range.
        return ln_gamma(x + 1.0) - x.ln();
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + G + 0.5;
    for (i, &c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Regularized incomplete beta I_x(a, b), given x, y = 1 - x and their logarithms.
fn inc_beta(a: f64, b: f64, x: f64, y: f64, ln_x: f64, ln_y: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    if y <= 0.0 {
        return 1.0;
    }
    let ln_front = a * ln_x + b * ln_y - (ln_gamma(a) + ln_gamma(b) - ln_gamma(a + b));
    if x < (a + 1.0) / (a + b + 2.0) {
        (ln_front.exp() * beta_cf(a, b, x) / a).clamp(0.0, 1.0)
    } else {
        (1.0 - ln_front.exp() * beta_cf(b, a, y) / b).clamp(0.0, 1.0)
    }
}

/// Continued fraction of the incomplete beta function (modified Lentz).
fn beta_cf(a: f64, b: f64, x: f64) -> f64 {
    const TINY: f64 = 1e-300;
    const EPS: f64 = 1e-15;
    let fix = |v: f64| if v.abs() < TINY { TINY } else { v };
    let (qab, qap, qam) = (a + b, a + 1.0, a - 1.0);
    let mut c = 1.0;
    let mut d = 1.0 / fix(1.0 - qab * x / qap);
    let mut h = d;
    for m in 1..100_000 {
        let m = m as f64;
        let m2 = 2.0 * m;
        let aa = m * (b - m) * x / ((qam + m2) * (a + m2));
        d = 1.0 / fix(1.0 + aa * d);
        c = fix(1.0 + aa / c);
        h *= d * c;
        let aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
        d = 1.0 / fix(1.0 + aa * d);
        c = fix(1.0 + aa / c);
        let del = d * c;
        h *= del;
        if (del - 1.0).abs() < EPS {
            break;
        }
    }
    h
}

/// Regularized upper incomplete gamma Q(1/2, x) = erfc(sqrt(x)).
fn gamma_q_half(x: f64) -> f64 {
    const A: f64 = 0.5;
    const EPS: f64 = 1e-16;
    const TINY: f64 = 1e-300;
    if x <= 0.0 {
        return 1.0;
    }
    let ln_gamma_a = 0.5 * std::f64::consts::PI.ln();
    let front = (-x + A * x.ln() - ln_gamma_a).exp();
    if x < A + 1.0 {
        // Series for P, then Q = 1 - P (P is not tiny here, so no precision is lost).
        let (mut ap, mut del, mut sum) = (A, 1.0 / A, 1.0 / A);
        for _ in 0..1000 {
            ap += 1.0;
            del *= x / ap;
            sum += del;
            if del.abs() < sum.abs() * EPS {
                break;
            }
        }
        1.0 - sum * front
    } else {
        // Continued fraction for Q (modified Lentz).
        let mut b = x + 1.0 - A;
        let mut c = 1.0 / TINY;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..1000 {
            let an = -(i as f64) * (i as f64 - A);
            b += 2.0;
            d = an * d + b;
            if d.abs() < TINY {
                d = TINY;
            }
            c = b + an / c;
            if c.abs() < TINY {
                c = TINY;
            }
            d = 1.0 / d;
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() < EPS {
                break;
            }
        }
        front * h
    }
}

/// `target/test-failures`: under `$CARGO_TARGET_DIR` when set, else this crate's `target/`.
pub fn failure_dir() -> PathBuf {
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("target"));
    target.join("test-failures")
}

/// Writes each `(label, image)` as `<dir>/<name>/<label>.exr` (creating the directories)
/// and returns `<dir>/<name>`. Path separators in `name` and labels become `_`.
pub fn dump_on_failure(dir: &Path, name: &str, images: &[(&str, &Image)]) -> Result<PathBuf> {
    let clean = |s: &str| s.replace(['/', '\\'], "_");
    let out = dir.join(clean(name));
    std::fs::create_dir_all(&out).map_err(|e| anyhow!("cannot create {}: {e}", out.display()))?;
    let meta = [("vkvcm:test".to_string(), name.to_string())];
    for (label, img) in images {
        write_exr(&out.join(format!("{}.exr", clean(label))), img, &meta)?;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pooled_variance_averages_kept_neighbours() {
        let st = PixelStats {
            width: 3,
            height: 2,
            count: 4,
            mean: vec![[0.0; 3]; 6],
            variance: [0.0, 9.0, 3.0, 6.0, 100.0, 0.0].map(|v| [v; 3]).to_vec(),
        };
        let keep = [true, true, true, true, false, true];
        let p = st.with_pooled_variance(&keep);
        // Pixel 0: itself, 1, 3 (4 is left out); pixel 5: 1, 2, 5; pixel 4 unchanged.
        assert_eq!(p.variance[0][0], 5.0);
        assert_eq!(p.variance[5][1], 4.0);
        assert_eq!(p.variance[4][2], 100.0);
    }

    #[test]
    fn ln_gamma_known_values() {
        let cases = [
            (0.5, 0.572_364_942_924_700_1),
            (1.0, 0.0),
            (2.0, 0.0),
            (10.0, 12.801_827_480_081_469),
            (0.1, 2.252_712_651_734_206),
            (1000.5, 5_908.674_175_848_677),
        ];
        for (x, expected) in cases {
            let got = ln_gamma(x);
            assert!((got - expected).abs() <= 1e-13 * expected.abs().max(1.0), "lnΓ({x}) = {got}, want {expected}");
        }
    }
}
