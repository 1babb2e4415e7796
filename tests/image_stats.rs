//! Statistics for render tests: distribution functions against reference values (computed
//! with mpmath at 40 digits), Šidák correction, and the per-pixel Welch test's false-failure
//! rate and power on synthetic renders drawn from known normal distributions.

#![allow(clippy::excessive_precision)] // reference values quoted as computed

use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use vkvcm::image::{read_exr, Image};
use vkvcm_tools::stats::{
    dump_on_failure, image_mean_test, inverse_normal_cdf, normal_sf, one_sample_test, sidak, student_t_two_sided_p,
    welch_test, z_test, z_test_analytic, MeanEstimate, PixelStats,
};

fn rel_err(got: f64, want: f64) -> f64 {
    ((got - want) / want).abs()
}

#[test]
fn inverse_normal_cdf_known_quantiles() {
    let cases = [
        (0.5, 0.0f64),
        (0.6, 0.253_347_103_135_799_8),
        (0.975, 1.959_963_984_540_054_2),
        (1.0 - 1e-6, 4.753_424_308_822_899),
        (1e-10, -6.361_340_902_404_056),
        (1e-100, -21.273_453_560_965_324),
        (1e-300, -37.047_096_299_361_2),
    ];
    for (p, want) in cases {
        let got = inverse_normal_cdf(p);
        let tol = if want == 0.0 { 1e-15 } else { 1e-9 * want.abs() };
        assert!((got - want).abs() <= tol, "q({p:e}) = {got}, want {want}");
    }
    assert!((inverse_normal_cdf(0.975) - 1.959964).abs() < 1e-6);
    assert!((inverse_normal_cdf(1.0 - 1e-6) - 4.753424).abs() < 1e-6);
    assert_eq!(inverse_normal_cdf(0.0), f64::NEG_INFINITY);
    assert_eq!(inverse_normal_cdf(1.0), f64::INFINITY);
    assert!(
        inverse_normal_cdf(-0.1).is_nan() && inverse_normal_cdf(1.5).is_nan() && inverse_normal_cdf(f64::NAN).is_nan()
    );
    // Symmetry across all three branches of AS 241.
    for p in [0.3, 0.07, 1e-3, 1e-8] {
        assert!((inverse_normal_cdf(p) + inverse_normal_cdf(1.0 - p)).abs() < 1e-8, "asymmetric at {p}");
    }
}

#[test]
fn normal_sf_known_values_and_inverse() {
    let cases = [
        (1.0, 0.158_655_253_931_457_05),
        (5.0, 2.866_515_718_791_939e-7),
        (10.0, 7.619_853_024_160_526e-24),
        (30.0, 4.906_713_927_148_187e-198),
    ];
    for (z, want) in cases {
        let got = normal_sf(z);
        assert!(rel_err(got, want) < 1e-12, "sf({z}) = {got:e}, want {want:e}");
    }
    assert!((normal_sf(0.0) - 0.5).abs() < 1e-15);
    assert!((normal_sf(-1.0) - (1.0 - 0.158_655_253_931_457_05)).abs() < 1e-15);
    // The quantile inverts the tail over 1e-300..0.5.
    let mut z = 0.01;
    while z < 37.0 {
        let back = -inverse_normal_cdf(normal_sf(z));
        assert!(rel_err(back, z) < 1e-10, "q(1 - sf({z})) = {back}");
        z *= 1.1;
    }
}

#[test]
fn student_t_p_values() {
    // Two-sided p-values from mpmath (betainc at 40 digits).
    let cases = [
        (2.0, 5.0, 0.101_939_478_829_858_36),
        (10.0, 3.0, 0.002_128_399_058_414_150_1),
        (6.0, 14.0, 3.254_775_878_249_242_4e-5),
        (30.0, 7.5, 4.374_733_410_169_642_1e-9),
        (50.0, 4.0, 9.574_453_656_969_698_4e-7),
        (1.5, 100.0, 0.136_765_058_124_688_86),
        (8.0, 1000.0, 3.426_661_482_391_474_4e-15),
        (0.3, 2.5, 0.787_342_371_495_197_21),
        (5.0, 200_000.0, 5.737_864_916_784_278_6e-7),
    ];
    for (t, df, want) in cases {
        let got = student_t_two_sided_p(t, df);
        assert!(rel_err(got, want) < 1e-9, "p(t={t}, df={df}) = {got:e}, want {want:e}");
        assert_eq!(student_t_two_sided_p(-t, df), got);
    }
    // Closed forms far into the tail: df = 1 (Cauchy) and df = 2.
    for t in [0.5f64, 3.0, 1e3, 1e6] {
        let cauchy = 2.0 / std::f64::consts::PI * (1.0 / t).atan();
        assert!(rel_err(student_t_two_sided_p(t, 1.0), cauchy) < 1e-11, "df=1, t={t}");
        let two = 1.0 - t / (2.0 + t * t).sqrt();
        let two_stable = 2.0 / ((2.0 + t * t).sqrt() * ((2.0 + t * t).sqrt() + t));
        assert!(rel_err(student_t_two_sided_p(t, 2.0), two_stable) < 1e-11, "df=2, t={t}");
        assert!((two - two_stable).abs() < 1e-9);
    }
    // Large df tends to the normal tail.
    assert!(rel_err(student_t_two_sided_p(5.0, 1e9), 2.0 * 2.866_515_718_791_939e-7) < 1e-6);
    assert!(rel_err(student_t_two_sided_p(5.0, f64::INFINITY), 2.0 * 2.866_515_718_791_939e-7) < 1e-12);
    assert_eq!(student_t_two_sided_p(0.0, 3.0), 1.0);
    assert_eq!(student_t_two_sided_p(f64::INFINITY, 3.0), 0.0);
    assert!(student_t_two_sided_p(1.0, 0.0).is_nan() && student_t_two_sided_p(f64::NAN, 3.0).is_nan());
}

#[test]
fn sidak_correction() {
    assert!((sidak(0.01, 1) - 0.01).abs() < 1e-17);
    let n = 1_000_000;
    let s = sidak(0.01, n);
    assert!((1.0 - (1.0 - s).powf(n as f64) - 0.01).abs() < 1e-9, "{s}");
    // Slightly above Bonferroni: -ln(1 - alpha) / n.
    assert!(s > 0.01 / n as f64 && s < 1.01 * 0.01 / n as f64);
}

// ---- synthetic renders ----

struct Normal(Pcg64);
impl Normal {
    fn new(seed: u64) -> Self {
        Normal(Pcg64::seed_from_u64(seed))
    }
    /// Box–Muller.
    fn sample(&mut self) -> f64 {
        let u1: f64 = 1.0 - self.0.random::<f64>();
        let u2: f64 = self.0.random::<f64>();
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }
}

/// A smooth "scene": per-pixel expected value of each channel.
fn truth(w: u32, h: u32) -> Image {
    Image::from_fn(w, h, |x, y| {
        let (u, v) = (x as f32 / w as f32, y as f32 / h as f32);
        [0.2 + u, 0.5 + 0.3 * v, 0.05 + 0.5 * u * v]
    })
}

/// `k` renders of `mean` with per-pixel noise of standard deviation `rel_sigma * mean + 0.01`.
fn renders(rng: &mut Normal, mean: &Image, k: usize, rel_sigma: f32) -> Vec<Image> {
    (0..k).map(|_| mean.map(|m| m.map(|v| v + (rel_sigma * v + 0.01) * rng.sample() as f32))).collect()
}

#[test]
fn two_sample_false_failure_rate_is_below_three_percent() {
    // Same distribution for A and B, different K and different noise levels (Welch's case).
    let reference = truth(32, 32);
    let trials = 200;
    let mut failures = 0;
    let mut worst = 0.0f64;
    for trial in 0..trials {
        let mut rng = Normal::new(1000 + trial);
        let a = renders(&mut rng, &reference, 6, 0.10);
        let b = renders(&mut rng, &reference, 8, 0.04);
        let test = z_test(&a, &b, 0.01);
        worst = worst.max(test.worst_z.abs());
        if !test.passed() {
            failures += 1;
            eprintln!("trial {trial}: {test}");
        }
    }
    eprintln!("{failures} of {trials} trials failed; largest |z| {worst:.2}");
    assert!(failures * 100 <= 3 * trials as usize, "{failures} of {trials} trials failed at alpha = 0.01");
}

#[test]
fn one_sample_false_failure_rate_is_below_three_percent() {
    let reference = truth(32, 32);
    let trials = 200;
    let mut failures = 0;
    for trial in 0..trials {
        let mut rng = Normal::new(5000 + trial);
        let a = renders(&mut rng, &reference, 5, 0.10);
        let test = z_test_analytic(&a, &reference, 0.01);
        if !test.passed() {
            failures += 1;
            eprintln!("trial {trial}: {test}");
        }
    }
    eprintln!("{failures} of {trials} trials failed");
    assert!(failures * 100 <= 3 * trials as usize, "{failures} of {trials} trials failed at alpha = 0.01");
}

/// Shifts an 8x8 block at (8, 8) of every render in `imgs` by `shift` in all channels.
fn shift_block(imgs: &mut [Image], shift: impl Fn(u32, u32, usize) -> f32) {
    for img in imgs {
        for y in 8..16 {
            for x in 8..16 {
                let mut p = img.get(x, y);
                for (c, v) in p.iter_mut().enumerate() {
                    *v += shift(x, y, c);
                }
                img.set(x, y, p);
            }
        }
    }
}

/// Standard error of mean_A - mean_B at pixel (x, y), channel c, for the noise of `renders`.
#[allow(clippy::too_many_arguments)]
fn se_diff(reference: &Image, x: u32, y: u32, c: usize, ka: usize, sa: f32, kb: usize, sb: f32) -> f32 {
    let m = reference.get(x, y)[c];
    let (da, db) = (sa * m + 0.01, sb * m + 0.01);
    (da * da / ka as f32 + db * db / kb as f32).sqrt()
}

#[test]
fn welch_detects_a_biased_block() {
    let reference = truth(32, 32);
    for trial in 0..20 {
        let mut rng = Normal::new(9000 + trial);
        let mut a = renders(&mut rng, &reference, 8, 0.10);
        let b = renders(&mut rng, &reference, 8, 0.04);
        // With K = 8 (df = 7) the t quantile at the Šidák level (3.3e-6 per test) is 13.2, far
        // wider than the normal 4.65, so a per-pixel shift must be large to show.
        shift_block(&mut a, |x, y, c| 20.0 * se_diff(&reference, x, y, c, 8, 0.10, 8, 0.04));
        let test = z_test(&a, &b, 0.01);
        assert!(!test.passed(), "trial {trial}: a 20-sigma bias went unnoticed: {test}");
        let (x, y) = test.worst_pixel;
        assert!((8..16).contains(&x) && (8..16).contains(&y), "worst pixel outside the block: {test}");
        assert!(test.failed <= 64, "pixels outside the block failed: {test}");
        assert!(test.worst_z > 0.0, "A is brighter, z must be positive: {test}");
    }
    // More renders per side: the statistic approaches a normal z, so 7 standard errors show.
    let mut rng = Normal::new(77);
    let mut a = renders(&mut rng, &reference, 64, 0.10);
    let b = renders(&mut rng, &reference, 64, 0.04);
    shift_block(&mut a, |x, y, c| -7.0 * se_diff(&reference, x, y, c, 64, 0.10, 64, 0.04));
    let test = z_test(&a, &b, 0.01);
    assert!(!test.passed() && test.worst_z < 0.0, "{test}");
    assert!(test.failed >= 5, "a 7-sigma shift with K = 64 should fail several of 64 pixels: {test}");
}

#[test]
fn stats_from_sums_match_and_give_power() {
    let reference = truth(16, 16);
    let mut rng = Normal::new(12);
    let imgs = renders(&mut rng, &reference, 5, 0.1);
    let mut sum = vec![[0.0f64; 3]; 256];
    let mut sum_sq = vec![[0.0f64; 3]; 256];
    for img in &imgs {
        for (i, p) in img.data.iter().enumerate() {
            for c in 0..3 {
                sum[i][c] += p[c] as f64;
                sum_sq[i][c] += p[c] as f64 * p[c] as f64;
            }
        }
    }
    let a = PixelStats::from_sums(16, 16, 5, &sum, &sum_sq).unwrap();
    let b = PixelStats::from_images(&imgs).unwrap();
    for i in 0..256 {
        for c in 0..3 {
            assert!((a.mean[i][c] - b.mean[i][c]).abs() < 1e-12);
            assert!((a.variance[i][c] - b.variance[i][c]).abs() < 1e-9 * b.variance[i][c].max(1e-6));
        }
    }
    assert!(PixelStats::from_sums(16, 16, 1, &sum, &sum_sq).is_err());
    assert!(PixelStats::from_sums(16, 15, 5, &sum, &sum_sq).is_err());

    // Per-iteration moments: 1000 observations, so the test is practically a z-test and a
    // 6-standard-error shift shows (threshold 4.36 at 16x16; t = 6 with df = 999 is z = 5.95).
    let (k, sigma) = (1000usize, 0.1f64);
    let stats = |shift: f64| PixelStats {
        width: 16,
        height: 16,
        count: k,
        mean: reference.data.iter().map(|m| m.map(|v| v as f64 + shift)).collect(),
        variance: vec![[sigma * sigma; 3]; 256],
    };
    let se = (2.0 * sigma * sigma / k as f64).sqrt();
    let t = welch_test(&stats(6.0 * se), &stats(0.0), 0.01).unwrap();
    assert!(!t.passed() && (t.worst_z - 6.0).abs() < 0.1 && t.z_threshold < 4.5, "{t}");
    assert!(welch_test(&stats(3.0 * se), &stats(0.0), 0.01).unwrap().passed());
}

#[test]
fn one_sample_detects_bias_and_colour_errors() {
    let reference = truth(32, 32);
    let mut rng = Normal::new(31);
    let mut a = renders(&mut rng, &reference, 16, 0.05);
    // Swap red and blue in the block: luminance-preserving-ish colour error, tested per channel.
    for img in &mut a {
        for y in 8..16 {
            for x in 8..16 {
                let p = img.get(x, y);
                img.set(x, y, [p[2], p[1], p[0]]);
            }
        }
    }
    let test = z_test_analytic(&a, &reference, 0.01);
    assert!(!test.passed(), "{test}");
    assert!(test.worst_channel == 0 || test.worst_channel == 2, "{test}");
    assert_eq!(test.count_b, 0);
    assert!(test.to_string().contains("expected ="), "{test}");
}

#[test]
fn zero_variance_pixels() {
    let white = Image::filled(4, 4, [1.0, 0.5, 0.0]);
    let same = vec![white.clone(), white.clone(), white.clone()];
    let t = z_test(&same, &same, 0.01);
    assert!(t.passed(), "{t}");
    assert_eq!(t.worst_z, 0.0);

    // Equal within 1e-6 relative passes (EQUAL_RELATIVE, whatever the variances).
    let mut close = white.clone();
    close.set(1, 2, [1.0 + 5e-7, 0.5, 0.0]);
    assert!(z_test(&same, &[close.clone(), close.clone()], 0.01).passed());
    // With no variance on either side (two exact values, e.g. from two renderers'
    // different f32 arithmetic) up to 1e-5 relative passes, and no further.
    let mut rounded = white.clone();
    rounded.set(1, 2, [1.0 - 5e-6, 0.5, 0.0]);
    assert!(z_test(&same, &[rounded.clone(), rounded.clone()], 0.01).passed());
    let mut beyond = white.clone();
    beyond.set(1, 2, [1.0 - 2e-5, 0.5, 0.0]);
    assert!(!z_test(&same, &[beyond.clone(), beyond.clone()], 0.01).passed());
    // The same when one side carries only a rounding-sized variance (vkvcm's film adds its
    // 2^-32 bound; seen: 0.9 +- 3.4e-7 against Mitsuba's exact 0.8999979), and no further.
    let film_like = |value: f64| {
        let k = 2048usize;
        let sum = vec![[value * k as f64; 3]; 16];
        let sum_sq = vec![[(value * value + 2f64.powi(-32)) * k as f64; 3]; 16];
        PixelStats::from_sums(4, 4, k, &sum, &sum_sq).unwrap()
    };
    let exact = |value: f64| {
        let sum = vec![[value * 16.0; 3]; 16];
        let sum_sq = vec![[value * value * 16.0; 3]; 16];
        PixelStats::from_sums(4, 4, 16, &sum, &sum_sq).unwrap()
    };
    assert!(welch_test(&film_like(0.9), &exact(0.8999979), 0.01).unwrap().passed());
    assert!(!welch_test(&film_like(0.9), &exact(0.89998), 0.01).unwrap().passed());
    let mut off = white.clone();
    off.set(1, 2, [1.0, 0.5 + 1e-3, 0.0]);
    let t = z_test(&same, &[off.clone(), off.clone()], 0.01);
    assert!(!t.passed());
    assert_eq!(t.failed, 1);
    assert_eq!(t.worst_pixel, (1, 2));
    assert_eq!(t.worst_channel, 1);
    assert_eq!(t.worst_z, f64::NEG_INFINITY);
    let msg = t.to_string();
    assert!(msg.contains("(1, 2)") && msg.contains("FAILED") && msg.contains("channel G"), "{msg}");

    // Analytic: exact match passes, a different expected value fails.
    assert!(z_test_analytic(&same, &white, 0.01).passed());
    assert!(!z_test_analytic(&same, &off, 0.01).passed());
}

#[test]
fn non_finite_pixels_fail() {
    let reference = truth(8, 8);
    let mut rng = Normal::new(3);
    let mut a = renders(&mut rng, &reference, 4, 0.1);
    let b = renders(&mut rng, &reference, 4, 0.1);
    a[2].set(5, 6, [f32::NAN, 0.0, 0.0]);
    a[1].set(2, 3, [0.0, f32::INFINITY, 0.0]);
    let t = z_test(&a, &b, 0.01);
    assert!(!t.passed());
    assert_eq!(t.non_finite, 2);
    assert_eq!(t.failed, 2, "{t}");
    assert_eq!(t.first_non_finite, Some((2, 3)));
    assert!(t.to_string().contains("NaN/Inf"), "{t}");
}

#[test]
fn thresholds_and_fields() {
    let reference = truth(16, 8);
    let mut rng = Normal::new(4);
    let a = renders(&mut rng, &reference, 4, 0.1);
    let b = renders(&mut rng, &reference, 5, 0.1);
    let t = z_test(&a, &b, 0.01);
    assert_eq!((t.pixels, t.count_a, t.count_b), (128, 4, 5));
    assert!((t.alpha_per_pixel - sidak(0.01, 128)).abs() < 1e-18);
    assert!((t.alpha_per_test - sidak(sidak(0.01, 128), 3)).abs() < 1e-18);
    assert!((t.z_threshold + inverse_normal_cdf(t.alpha_per_test / 2.0)).abs() < 1e-12);
    assert_eq!(t.worst.df, 3.0, "conservative df = min(K_A, K_B) - 1: {t}");
    // The stats API gives the same answer and the mean image is the average.
    let (sa, sb) = (PixelStats::from_images(&a).unwrap(), PixelStats::from_images(&b).unwrap());
    let t2 = welch_test(&sa, &sb, 0.01).unwrap();
    assert_eq!((t2.failed, t2.worst_z, t2.worst_pixel), (t.failed, t.worst_z, t.worst_pixel));
    assert_eq!(sa.mean_image(), Image::average(&a).unwrap());
    let se = sa.std_error_image();
    assert!(se.data.iter().all(|p| p.iter().all(|v| *v > 0.0)));
    assert!(one_sample_test(&sa, &reference, 0.01).is_ok());
    // Errors rather than panics in the Result API.
    assert!(PixelStats::from_images(&a[..1]).is_err());
    assert!(welch_test(&sa, &PixelStats::from_images(&renders(&mut rng, &truth(4, 4), 3, 0.1)).unwrap(), 0.01).is_err());
    assert!(welch_test(&sa, &sb, 0.0).is_err() && welch_test(&sa, &sb, 1.0).is_err());
}

#[test]
#[should_panic(expected = "at least 2")]
fn z_test_panics_on_a_single_render() {
    let img = truth(4, 4);
    z_test(std::slice::from_ref(&img), &[img.clone(), img.clone()], 0.01);
}

#[test]
fn dumps_images_for_debugging() {
    let dir = tempfile::tempdir().unwrap();
    let a = truth(8, 4);
    let b = Image::filled(8, 4, [0.5; 3]);
    let out = dump_on_failure(dir.path(), "pt/vs bpt", &[("mean", &a), ("ref", &b)]).unwrap();
    assert_eq!(out, dir.path().join("pt_vs bpt"));
    let (back, meta) = read_exr(&out.join("mean.exr")).unwrap();
    assert_eq!(back, a);
    assert_eq!(meta, vec![("vkvcm:test".to_string(), "pt/vs bpt".to_string())]);
    assert!(out.join("ref.exr").is_file());

    // ZTest::dump writes the full set under target/test-failures/<name>/.
    let mut rng = Normal::new(8);
    let ra = renders(&mut rng, &a, 3, 0.001);
    let rb = renders(&mut rng, &b, 3, 0.001);
    let t = z_test(&ra, &rb, 0.01);
    assert!(!t.passed());
    let name = "image_stats_dump_selftest";
    let out = t.dump(name).unwrap();
    assert!(out.ends_with(format!("test-failures/{name}")), "{}", out.display());
    for f in ["mean.exr", "ref.exr", "error.exr", "z.exr", "error.png", "z.png"] {
        assert!(out.join(f).is_file(), "{f} missing in {}", out.display());
    }
    let (z, _) = read_exr(&out.join("z.exr")).unwrap();
    assert_eq!(z.data.len(), 32);
    std::fs::remove_dir_all(&out).unwrap();

    let caught = std::panic::catch_unwind(|| t.assert_passed("image_stats_assert_selftest"));
    let msg = *caught.unwrap_err().downcast::<String>().unwrap();
    assert!(msg.contains("FAILED") && msg.contains("test-failures"), "{msg}");
    let _ = std::fs::remove_dir_all(vkvcm_tools::stats::failure_dir().join("image_stats_assert_selftest"));
}

/// Calibration (run with `--ignored --nocapture`): false-failure rate of the Welch test
/// over many trials for several sample sizes and noise ratios.
#[test]
#[ignore]
fn calibration_false_failure_rates() {
    let reference = truth(32, 32);
    let trials = 2000;
    let configs = [
        (6, 0.10, 8, 0.04),
        (4, 0.1, 4, 0.1),
        (8, 0.1, 8, 0.1),
        (4, 0.2, 8, 0.02),
        (8, 0.2, 4, 0.02),
        (8, 0.2, 8, 0.02),
    ];
    for (ka, sa, kb, sb) in configs {
        let mut failures = 0;
        for trial in 0..trials {
            let mut rng = Normal::new(100_000 + trial);
            let a = renders(&mut rng, &reference, ka, sa);
            let b = renders(&mut rng, &reference, kb, sb);
            if !z_test(&a, &b, 0.01).passed() {
                failures += 1;
            }
        }
        eprintln!(
            "K_A={ka} sigma_A={sa} K_B={kb} sigma_B={sb}: {failures} of {trials} failed ({:.2}%)",
            100.0 * failures as f64 / trials as f64
        );
    }
    // One-sample test against the exact image: df = K - 1 is exact, so the rate should be
    // close to alpha itself (Šidák is exact for independent tests).
    for k in [3, 4, 8] {
        let mut failures = 0;
        for trial in 0..trials {
            let mut rng = Normal::new(200_000 + trial);
            if !z_test_analytic(&renders(&mut rng, &reference, k, 0.1), &reference, 0.01).passed() {
                failures += 1;
            }
        }
        eprintln!("one-sample K={k}: {failures} of {trials} failed ({:.2}%)", 100.0 * failures as f64 / trials as f64);
    }
}

/// The image-mean test (assert_matches_mitsuba's): 16 block means against a reference of
/// 16 renders of 16x16 pixels. Without a bias it fails at most ~alpha of the time (2000
/// trials at alpha 0.01: below 2%, a binomial tail of 3.2 standard deviations above 1%);
/// a bias of 8 standard errors fails nearly always (t threshold 4.07 with 15 df at 1e-3:
/// over 90% of trials).
#[test]
fn image_mean_test_false_failures_and_power() {
    let mut rng = Normal::new(31);
    let (truth, block_sd, pixel_sd, k) = (0.5f64, 0.02f64, 0.3f64, 16usize);
    let n = 256.0;
    let ref_se = pixel_sd / (n * k as f64).sqrt();
    let se = (block_sd * block_sd / 16.0 + ref_se * ref_se).sqrt();
    let mut trial = |bias: f64| {
        let blocks: Vec<f64> = (0..16).map(|_| truth + bias * se + block_sd * rng.sample()).collect();
        let ref_mean = truth + ref_se * rng.sample();
        let reference = PixelStats {
            width: 16,
            height: 16,
            count: k,
            mean: vec![[ref_mean; 3]; 256],
            variance: vec![[pixel_sd * pixel_sd; 3]; 256],
        };
        image_mean_test(
            MeanEstimate::of_blocks(&blocks).unwrap(),
            MeanEstimate::of_independent_pixels(&reference).unwrap(),
        )
    };
    let false_failures = (0..2000).filter(|_| trial(0.0).p < 0.01).count();
    assert!(false_failures < 40, "{false_failures} of 2000 unbiased trials failed at 0.01");
    let detected = (0..200).filter(|_| trial(8.0).p < 1e-3).count();
    assert!(detected > 180, "a bias of 8 standard errors failed only {detected} of 200 trials at 1e-3");
    let one = trial(0.0);
    assert_eq!(one.df, 15.0);
    assert!((one.b.std_error - ref_se).abs() < 1e-12, "{one}");
    assert!(MeanEstimate::of_blocks(&[0.5]).is_err(), "one block has no spread");
}
