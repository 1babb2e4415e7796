//! Smooth shading in every estimator (glsl/bsdf.glsl: interpolated vertex normals with
//! Veach's adjoint correction on light subpaths, thesis ch. 5.3). Lavapipe, validation on.
//!
//! The scene: a diffuse floor and a GGX floor under a large area light, a diffuse + GGX
//! back wall, with shading normals tilted up to 25 degrees off the wall's and the light's
//! triangles and by 30 degrees, all the same way, off the floor's, and a
//! coarse smooth-shaded sphere mesh (6 x 10 quads, so its shading normals differ from its
//! facets by up to 15 degrees). Path tracing shades with the shading normals directly;
//! light tracing, BPT, BPM and VCM reach the same paths from the light, where the
//! shading-normal BSDF is not symmetric: without the adjoint correction they converge to
//! another image (checked by sabotage: with `shading_correction` returning 1, PT vs BPT
//! fails on 193 of the 576 pixels; without merge_eval's shading factor BPM's image mean is
//! 7% too bright, t = 12). So agreement between them tests the correction.
//!
//! Statistics as in tests/render_bidir.rs: per-pixel Welch tests with the iterations of one
//! render as independent samples, Šidák-corrected to false-failure probability ALPHA per
//! comparison; the merging estimators by the paired image-mean test of
//! tests/render_vcm.rs (a small bias spreads over the whole image).

mod common;

use std::sync::Arc;

use common::scenes::{glossy_floor_scene, smooth_sphere_mesh, tilt_shading_normals};
use common::{render_stats, with_gpu};
use glam::Vec3;
use vkvcm::gpu::Gpu;
use vkvcm::render::{self, Algorithm, Budget, RenderSettings};
use vkvcm::scene::{Material, Scene};
use vkvcm_tools::stats::{welch_test, PixelStats};

const ALPHA: f64 = 1e-3;
const W: u32 = 24;
const H: u32 = 24;
const RADIUS: f32 = 0.01;
const SEEDS: u32 = 8;

fn smooth_scene() -> Scene {
    let floor = Material { name: "floor".into(), diffuse: Vec3::new(0.6, 0.5, 0.4), ..Default::default() };
    let plastic = Material {
        name: "plastic".into(),
        diffuse: Vec3::new(0.3, 0.4, 0.5),
        glossy: Vec3::splat(0.2),
        roughness: 0.4,
        ..Default::default()
    };
    let mut s = glossy_floor_scene(floor, plastic);
    tilt_shading_normals(&mut s, 25.0, 99);
    // The floor (its first four triangles, z = 0) shades with one normal tilted 30 degrees
    // towards +x: a shading cosine systematically unlike the geometric one, so that
    // every cosine the estimators take at the floor matters to the image mean.
    let tilted = Vec3::new(0.5, 0.0, 0.75f32.sqrt());
    for t in &mut s.triangles[..4] {
        assert_eq!(t.p.map(|p| p.z), [0.0; 3], "the floor comes first");
        t.n = Some([tilted; 3]);
    }
    let ball = s.materials.len() as u32;
    s.materials.push(Material { name: "ball".into(), diffuse: Vec3::new(0.7, 0.7, 0.6), ..Default::default() });
    s.triangles.extend(smooth_sphere_mesh(Vec3::new(0.3, 0.6, 0.5), 0.5, 6, 10, ball));
    s.name = "smooth".into();
    s
}

fn render_one(gpu: &Arc<Gpu>, scene: &Scene, algo: Algorithm, iterations: u64, seed: u32) -> render::RenderOutput {
    render_with_radius(gpu, scene, algo, iterations, seed, 0.01)
}

fn render_with_radius(
    gpu: &Arc<Gpu>,
    scene: &Scene,
    algo: Algorithm,
    iterations: u64,
    seed: u32,
    radius_factor: f32,
) -> render::RenderOutput {
    let mut s = RenderSettings::new(algo, W, H, Budget::Iterations(iterations));
    s.frame.seed = seed;
    s.frame.max_path_length = 6;
    s.radius_factor = radius_factor;
    let out = render::render(gpu, scene, &s, None, &mut |_| {}).unwrap();
    assert_eq!(out.rejected_samples, 0, "{algo:?}: rejected samples");
    assert_eq!(out.overflow_splats, 0, "{algo:?}: overflowing splats");
    out
}

fn stats(gpu: &Arc<Gpu>, scene: &Scene, algo: Algorithm, iterations: u64) -> PixelStats {
    render_stats(&render_one(gpu, scene, algo, iterations, 17 + algo as u32), None)
}

#[test]
fn smooth_shading_agrees_between_camera_and_light_subpaths() {
    let scene = smooth_scene();
    let features = vkvcm::render::features::FeatureSet::new(&scene, false);
    assert!(features.shading_normals, "the scene's normals must reach the kernels");
    with_gpu(|gpu| {
        let bpt = stats(gpu, &scene, Algorithm::Bpt, 2048);
        for (algo, iterations) in [(Algorithm::Pt, 8192), (Algorithm::Lt, 8192)] {
            let other = stats(gpu, &scene, algo, iterations);
            let t = welch_test(&other, &bpt, ALPHA).unwrap();
            assert!(t.passed(), "{algo:?} vs BPT with shading normals: {t}");
        }
    });
}

/// BPM and VCM against BPT, image means over 8 seeds, paired (the same seed shares its
/// light and camera subpaths): df = 7, two-sided p >= 1e-3, i.e. |t| < 5.41. The merge
/// radius is small (1% of the scene), so the kernel-estimation bias is below what this
/// resolves (as in tests/render_vcm.rs). 192 iterations per render: without the
/// shading-normal factor of merge_eval (sabotage), BPM is 2% too bright, t = 4.3 at 64
/// iterations, which this test must resolve.
#[test]
fn smooth_shading_merging_estimators_match_bpt() {
    let scene = smooth_scene();
    with_gpu(|gpu| {
        let image_mean = |algo: Algorithm, seed: u32| -> f64 {
            let out = render_with_radius(gpu, &scene, algo, 64, seed, RADIUS);
            out.pixels.iter().map(|p| (p[0] + p[1] + p[2]) as f64).sum::<f64>() / out.pixels.len() as f64
        };
        let seeds: Vec<u32> = (0..SEEDS).map(|k| 11 + 1000 * k).collect();
        let bpt: Vec<f64> = seeds.iter().map(|&k| image_mean(Algorithm::Bpt, k)).collect();
        for algo in [Algorithm::Vcm, Algorithm::Bpm] {
            let d: Vec<f64> = seeds.iter().zip(&bpt).map(|(&k, b)| image_mean(algo, k) - b).collect();
            let n = d.len() as f64;
            let m = d.iter().sum::<f64>() / n;
            let se = (d.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt();
            let t = m / se;
            eprintln!("smooth: {algo:?} - BPT = {m:.6} +- {se:.6}: t = {t:.2}");
            assert!(t.abs() < 5.41, "{algo:?} image mean differs from BPT's by {m} +- {se} (t = {t})");
        }
    });
}

/// Shading normals change the image (the sphere's facets disappear): the kernels do read
/// them. That a scene without them renders the same with the code that handles them
/// compiled in is render_features' generic-equals-specialised check.
#[test]
fn shading_normals_change_the_image() {
    let smooth = smooth_scene();
    let mut flat = smooth.clone();
    for t in &mut flat.triangles {
        t.n = None;
    }
    with_gpu(|gpu| {
        for algo in [Algorithm::Pt, Algorithm::Bpt, Algorithm::Vcm] {
            let a = stats(gpu, &smooth, algo, 512);
            let b = stats(gpu, &flat, algo, 512);
            let t = welch_test(&a, &b, ALPHA).unwrap();
            assert!(!t.passed(), "{algo:?}: the smooth and the flat scene render the same image: {t}");
        }
    });
}
