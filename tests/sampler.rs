//! The camera paths' quasi-random numbers (glsl/common.glsl, `sobol2` / `sobol1`;
//! glsl/path_sampler.glsl; `--sampler sobol`):
//! each dimension of each pixel's sequence is an Owen-scrambled Sobol sequence, so its
//! first 2^k points are a (0, k, 2)-net (2-D: every box [a 2^-i, (a+1) 2^-i) x
//! [b 2^-(k-i), (b+1) 2^-(k-i)) holds exactly one point) and the 1-D points fall one in
//! each interval of width 2^-k; different dimensions and pixels are scrambled
//! independently. Exact checks of the net properties, read back from the GPU; the
//! independence checks are statistical with stated tolerances. Then pt, bpt and vcm with
//! the sampler against the same estimator with independent numbers: the same image
//! (unbiased), with less error.

mod common;

use common::{image_mean, render_checked, render_stats, run_test_kernel, with_gpu};
use vkvcm::image::stats::welch_test;
use vkvcm::render::{Algorithm, Budget, RenderSettings, Sampler};

/// (x, y, z) in 24-bit fixed point for each (key, dim, index): sobol2's point and
/// sobol1's value.
fn points(requests: &[[u32; 4]]) -> Vec<[u32; 4]> {
    with_gpu(|gpu| run_test_kernel(gpu, "tests/sobol.comp", requests))
}

const KEYS: [u32; 3] = [1, 0xdead_beef, 2_891_336_453];
const DIMS: [u32; 3] = [0, 3, 41];

fn sequence(key: u32, dim: u32, indices: std::ops::Range<u32>) -> Vec<[u32; 4]> {
    points(&indices.map(|i| [key, dim, i, 0]).collect::<Vec<_>>())
}

/// Whether `pts` (2^k points, 24-bit coordinates) put exactly one point in every
/// elementary box of area 2^-k.
fn is_net(pts: &[(u32, u32)], k: u32) -> bool {
    (0..=k).all(|i| {
        let mut seen = vec![false; 1 << k];
        pts.iter().all(|&(x, y)| {
            let cell = ((x >> (24 - i)) << (k - i)) | (y >> (24 - (k - i)));
            !std::mem::replace(&mut seen[cell as usize], true)
        })
    })
}

#[test]
fn every_dimension_is_a_net_in_two_and_one_dimensions() {
    for key in KEYS {
        for dim in DIMS {
            let p = sequence(key, dim, 0..2048);
            for k in 1..=10 {
                let n = 1usize << k;
                let xy: Vec<(u32, u32)> = p[..n].iter().map(|q| (q[0], q[1])).collect();
                assert!(is_net(&xy, k), "key {key:#x} dim {dim}: the first {n} 2-D points are not a (0,{k},2)-net");
                let mut strata: Vec<u32> = p[..n].iter().map(|q| q[2] >> (24 - k)).collect();
                strata.sort_unstable();
                strata.dedup();
                assert_eq!(strata.len(), n, "key {key:#x} dim {dim}: the first {n} 1-D points share an interval");
            }
            // An aligned later block of 2^10 points is a net too (what iterations
            // 1024..2047 of a render draw).
            let xy: Vec<(u32, u32)> = p[1024..].iter().map(|q| (q[0], q[1])).collect();
            assert!(is_net(&xy, 10), "key {key:#x} dim {dim}: points 1024..2047 are not a net");
        }
    }
}

fn correlation(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let cov: f64 = a.iter().zip(b).map(|(x, y)| (x - ma) * (y - mb)).sum();
    let va: f64 = a.iter().map(|x| (x - ma) * (x - ma)).sum();
    let vb: f64 = b.iter().map(|y| (y - mb) * (y - mb)).sum();
    cov / (va * vb).sqrt()
}

/// Different dimensions of one pixel, and one dimension of different pixels, are
/// scrambled independently: over 1024 points the correlation of any two of their
/// coordinates is that of independent uniforms, whose standard deviation is
/// 1/sqrt(1024) = 0.031; the tolerance 0.16 is five of them. Without the padding
/// (every dimension the same Sobol points) the correlation would be 1.
#[test]
fn dimensions_and_pixels_are_decorrelated() {
    let n = 1024;
    let unit = |v: u32| v as f64 / 16_777_216.0;
    let coords = |key: u32, dim: u32| -> Vec<Vec<f64>> {
        let p = sequence(key, dim, 0..n);
        (0..3).map(|c| p.iter().map(|q| unit(q[c])).collect()).collect()
    };
    let base = coords(KEYS[0], 0);
    let others = [
        ("dimension 1", coords(KEYS[0], 1)),
        ("dimension 2", coords(KEYS[0], 2)),
        ("another pixel", coords(KEYS[1], 0)),
    ];
    for (what, other) in &others {
        for (i, a) in base.iter().enumerate() {
            for (j, b) in other.iter().enumerate() {
                let r = correlation(a, b);
                assert!(r.abs() < 0.16, "{what}: coordinate {i} against {j}: correlation {r:.3}");
            }
        }
    }
    // Within one dimension, x, y and the 1-D value are scrambled independently too.
    for (i, j) in [(0, 1), (0, 2), (1, 2)] {
        let r = correlation(&base[i], &base[j]);
        assert!(r.abs() < 0.16, "coordinates {i} and {j} of one dimension: correlation {r:.3}");
    }
}

/// Renders of gbs_b (glossy floor, mirror and glass spheres under a constant background:
/// next-event estimation and BSDF sampling of the background, which the stratification
/// helps most) with each sampler, 48x48, 256 iterations, two seeds each.
///
/// Unbiased: every pixel agrees with the independent sampler's by a Welch test at false-
/// failure probability 1e-3 per comparison (Sidak-corrected over pixels). The Sobol side's
/// per-pixel variance comes from iterations that are stratified, not independent: it
/// overstates the error where a pixel's integrand is smooth, and may understate it
/// where a feature covers less than 1/256 of a pixel's samples; gbs_b at 48x48 has none
/// that the test meets. The image means and the spread do not rely on it.
/// vcm's merging is biased, but by the radius only, which does not depend on the sampler:
/// both renders estimate the same value.
///
/// Less error: the mean squared difference between the two seeds' images estimates twice
/// a render's error variance; the test asks Sobol's to be below `max_ratio` times
/// independent's. A sampler whose points are not stratified across iterations (a random
/// sample index per iteration) gives 1.0 and fails it.
fn sobol_is_unbiased_with_less_error(algorithm: Algorithm, max_ratio: f64) {
    let scene = vkvcm::scene::load_named("gbs_b").unwrap();
    let name = algorithm.name();
    let (outs, stats) = with_gpu(|gpu| {
        let mut outs = Vec::new();
        for sampler in [Sampler::Sobol, Sampler::Independent] {
            for seed in [1, 2] {
                let mut s = RenderSettings::new(algorithm, 48, 48, Budget::Iterations(256));
                s.sampler = Some(sampler);
                s.frame.seed = seed;
                outs.push(render_checked(gpu, &scene, &s));
            }
        }
        let stats: Vec<_> = outs.iter().map(|o| render_stats(o, None)).collect();
        (outs, stats)
    });
    let t = welch_test(&stats[0], &stats[2], 1e-3).unwrap();
    assert!(t.passed(), "{name}, sobol against independent: {t}");
    let (ms, mi) = (image_mean(&stats[0]), image_mean(&stats[2]));
    assert!((ms / mi - 1.0).abs() < 0.01, "{name}, image means: sobol {ms}, independent {mi}");
    let spread = |a: &vkvcm::render::RenderOutput, b: &vkvcm::render::RenderOutput| -> f64 {
        let n = a.pixels.len() as f64;
        a.pixels
            .iter()
            .zip(&b.pixels)
            .map(|(p, q)| (0..3).map(|c| (p[c] - q[c]) as f64).map(|d| d * d).sum::<f64>())
            .sum::<f64>()
            / n
    };
    let ratio = spread(&outs[0], &outs[1]) / spread(&outs[2], &outs[3]);
    eprintln!("{name}: sobol's squared error over independent's {ratio:.3}");
    assert!(ratio < max_ratio, "{name}: sobol's squared error over independent's: {ratio:.3}");
}

/// pt: Sobol's squared error over independent's was 0.55-0.57 on gbs_b in
/// docs/performance.md's measurements (128x128, 64 and 512 iterations, relMSE against a
/// reference), 0.44 in this test.
#[test]
fn sobol_pt_is_unbiased_with_less_error() {
    sobol_is_unbiased_with_less_error(Algorithm::Pt, 0.8);
}

#[test]
fn sobol_bpt_is_unbiased_with_less_error() {
    sobol_is_unbiased_with_less_error(Algorithm::Bpt, 0.8);
}

#[test]
fn sobol_vcm_is_unbiased_with_less_error() {
    sobol_is_unbiased_with_less_error(Algorithm::Vcm, 0.8);
}
