//! Bidirectional path tracing with connections to a light-vertex cache (`--connect cache`,
//! src/render/passes/light_subpaths.rs and glsl/camera_subpath.comp, `Connect::Cache`; Davidovic et al. 2014) against independent
//! estimators, and its determinism. Lavapipe, validation on.
//!
//! What is compared (the reasons are those of tests/render_bidir.rs):
//! * against PT where PT samples every path: glm_c without its mirror sphere, and gbs_b;
//! * against BPT with SmallVCM's connections (`--connect path`, itself checked against PT
//!   and LT in tests/render_bidir.rs) on all four reference scenes: both sample the same
//!   paths with the same MIS weights, so their expectations are equal pixel by pixel.
//!
//! Statistics as in tests/render_bidir.rs: per-pixel Welch test (t converted to z),
//! Sidak-corrected so that each comparison fails falsely with probability ALPHA = 1e-3
//! (the same significance as the other bidirectional tests). A bias confined to no pixel
//! in particular (a wrong global weight, a skewed draw) shows in the whole-image mean
//! first, so each comparison also tests the mean luminance of the two images: z from the
//! per-pixel variances (pixels are independent), |z| < 3.29 (two-sided 1e-3).
//!
//! Counts: 24x24 pixels (N_L = 576 light subpaths per iteration) like the other bidir
//! tests; PT needs 16384 iterations there (rare glossy highlights, see render_bidir.rs),
//! BPT 2048.
//!
//! Sabotage checks (done by hand, not kept): dropping the weight M / (N_L n_c) of the
//! cache connections, or drawing a light subpath uniformly and then one of its vertices
//! uniformly while keeping that weight (drawing vertices non-uniformly), or dropping the
//! path-length checks of the cache draws, makes these tests fail (numbers in
//! docs/estimators.md).

mod common;

use std::sync::Arc;

use common::{render_stats, with_gpu};
use vkvcm::gpu::Gpu;
use vkvcm::render::Connect;
use vkvcm::render::{self, Algorithm, Budget, RenderOutput, RenderSettings};
use vkvcm::scene::Scene;
use vkvcm_tools::stats::{welch_test, PixelStats};

const ALPHA: f64 = 1e-3;
/// Two-sided normal quantile of ALPHA, for the whole-image mean.
const Z_MEAN: f64 = 3.29;
const W: u32 = 24;
const H: u32 = 24;

fn render_one(
    gpu: &Arc<Gpu>,
    scene: &Scene,
    algo: Algorithm,
    connect: Connect,
    iterations: u64,
    seed: u32,
) -> RenderOutput {
    let mut s = RenderSettings::new(algo, W, H, Budget::Iterations(iterations));
    s.frame.seed = seed;
    s.connect = connect;
    let out = render::render(gpu, scene, &s, None, &mut |_| {}).unwrap();
    assert_eq!(out.rejected_samples, 0, "{} {algo:?} {connect:?}: rejected samples", scene.name);
    assert_eq!(out.overflow_splats, 0, "{} {algo:?} {connect:?}: overflowing splats", scene.name);
    out
}

/// Whole-image mean luminance and its standard error.
fn mean_and_se(s: &PixelStats) -> (f64, f64) {
    let lum = |c: [f64; 3]| 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
    let n = s.mean.len() as f64;
    let mean = s.mean.iter().map(|&c| lum(c)).sum::<f64>() / n;
    // Per-pixel luminance variance bounded by treating channels as fully correlated.
    let var = s.variance.iter().map(|&v| lum(v.map(|x| x.sqrt())).powi(2)).sum::<f64>() / (n * n);
    (mean, (var / s.count as f64).sqrt())
}

/// Per-pixel Welch test and whole-image mean test of `a` against `b`.
fn assert_agree(what: &str, a: &PixelStats, b: &PixelStats) {
    let t = welch_test(a, b, ALPHA).unwrap();
    let ((ma, sa), (mb, sb)) = (mean_and_se(a), mean_and_se(b));
    let z = (ma - mb) / (sa * sa + sb * sb).sqrt();
    println!("{what}: {t}; mean luminance {ma:.5} +- {sa:.5} vs {mb:.5} +- {sb:.5}, z = {z:.2}");
    assert!(t.passed(), "{what}: {t}");
    assert!(z.abs() < Z_MEAN, "{what}: mean luminance {ma:.5} +- {sa:.5} vs {mb:.5} +- {sb:.5}, z = {z:.2}");
}

fn cache(n: u32) -> Connect {
    Connect::Cache(n)
}

#[test]
fn bpt_cache_matches_pt_where_pt_is_complete() {
    with_gpu(|gpu| {
        for name in ["glm_c", "gbs_b"] {
            let mut scene = vkvcm::scene::load_named(name).unwrap();
            if name == "glm_c" {
                scene.spheres.clear();
            }
            let pt = render_stats(&render_one(gpu, &scene, Algorithm::Pt, Connect::Path, 16384, 31), None);
            let bpt = render_stats(&render_one(gpu, &scene, Algorithm::Bpt, cache(1), 2048, 32), None);
            assert_agree(&format!("{name}: PT vs BPT with the cache (1 connection)"), &pt, &bpt);
        }
    });
}

#[test]
fn bpt_cache_matches_bpt_path_on_all_reference_scenes() {
    with_gpu(|gpu| {
        for name in vkvcm::scene::BUILTIN_SCENES {
            let scene = vkvcm::scene::load_named(name).unwrap();
            let path = render_stats(&render_one(gpu, &scene, Algorithm::Bpt, Connect::Path, 2048, 41), None);
            // 3 connections: also covers the loop over n_c > 1 draws.
            let c = render_stats(&render_one(gpu, &scene, Algorithm::Bpt, cache(3), 2048, 42), None);
            assert_agree(&format!("{name}: BPT path vs BPT cache (3 connections)"), &path, &c);
        }
    });
}

/// Path-length limits: with min = max = 3 segments only paths of exactly 3 segments count,
/// so the cache must skip the vertices that make longer or shorter paths (and a camera
/// vertex too deep for any connection draws nothing). Compared with `path`, which skips
/// them by its own loop. gbs_b (background light, diffuse box): light subpaths have
/// several vertices and camera subpaths several bounces, so both limits bind. 1024
/// iterations, as many as vcm_cache_matches_vcm_path.
#[test]
fn bpt_cache_respects_path_length_limits() {
    with_gpu(|gpu| {
        let scene = vkvcm::scene::load_named("gbs_b").unwrap();
        let run = |connect: Connect, seed: u32| {
            let mut s = RenderSettings::new(Algorithm::Bpt, W, H, Budget::Iterations(1024));
            s.frame.seed = seed;
            s.frame.max_path_length = 3;
            s.frame.min_path_length = 3;
            s.connect = connect;
            render_stats(&render::render(gpu, &scene, &s, None, &mut |_| {}).unwrap(), None)
        };
        let path = run(Connect::Path, 61);
        let c = run(cache(2), 62);
        assert_agree("gbs_b, paths of exactly 3 segments: BPT path vs BPT cache (2 connections)", &path, &c);
    });
}

/// vcm shares the connection code: the cache variant agrees with SmallVCM's layout (both
/// merge with the same radius schedule, so their expectations, merging bias included,
/// are equal).
#[test]
fn vcm_cache_matches_vcm_path() {
    with_gpu(|gpu| {
        let scene = vkvcm::scene::load_named("gbs_s").unwrap();
        let path = render_stats(&render_one(gpu, &scene, Algorithm::Vcm, Connect::Path, 1024, 51), None);
        let c = render_stats(&render_one(gpu, &scene, Algorithm::Vcm, cache(1), 1024, 52), None);
        assert_agree("gbs_s: VCM path vs VCM cache (1 connection)", &path, &c);
    });
}

/// Same seed, same image, bit for bit: the prefix sum is a fixed-order scan and the draws
/// come from each pixel's random sequence. Another seed differs (the control).
#[test]
fn bpt_cache_is_deterministic() {
    with_gpu(|gpu| {
        let scene = vkvcm::scene::load_named("gbs_s").unwrap();
        let a = render_one(gpu, &scene, Algorithm::Bpt, cache(2), 8, 7);
        let b = render_one(gpu, &scene, Algorithm::Bpt, cache(2), 8, 7);
        assert!(a.sum == b.sum && a.sum_sq == b.sum_sq, "two renders with seed 7 differ");
        let c = render_one(gpu, &scene, Algorithm::Bpt, cache(2), 8, 8);
        assert!(a.sum != c.sum, "seeds 7 and 8 gave the same image");
    });
}

/// The cache is only for estimators that connect vertices.
#[test]
fn cache_is_refused_without_connections() {
    with_gpu(|gpu| {
        let scene = vkvcm::scene::load_named("gbs_s").unwrap();
        for algo in [Algorithm::Pt, Algorithm::Lt, Algorithm::Bpm] {
            let mut s = RenderSettings::new(algo, W, H, Budget::Iterations(1));
            s.connect = cache(1);
            let e = render::render(gpu, &scene, &s, None, &mut |_| {}).err().expect("cache accepted");
            assert!(format!("{e:#}").contains("light-vertex cache"), "{algo:?}: {e:#}");
        }
    });
}
