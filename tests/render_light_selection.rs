//! Light selection (src/render/light_selection.rs, glsl/lights.glsl `pick_light`,
//! `light_pick_prob`): picking lights by power instead of uniformly changes which light
//! next-event estimation and light subpaths use, and every estimator's MIS weights must
//! follow the same probabilities, so the image must not change. A scene with six lights of
//! very different power (two large area-light triangles, the two triangles of a small
//! bright emitter, a point light and a dim constant background): PT, BPT and LT picking
//! by power against PT picking uniformly, per pixel. (tests/mis_weights.rs checks that
//! the weights of every technique of a path sum to 1 with the power-based probabilities.)
//!
//! Statistics as in tests/render_ggx.rs: K = iterations independent samples per pixel,
//! per-pixel Welch test, Šidák-corrected so that each comparison has false-failure
//! probability ALPHA. Lavapipe, validation on.

mod common;

use std::sync::Arc;

use common::scenes::*;
use common::{image_mean, render_checked, render_stats, with_gpu};
use glam::Vec3;
use vkvcm::gpu::Gpu;
use vkvcm::render::light_selection::LightDistribution;
use vkvcm::render::{self, Algorithm, Budget, LightSelection, RenderSettings};
use vkvcm::scene::{Light, Material, Scene};
use vkvcm_tools::stats::{welch_test, PixelStats};

const ALPHA: f64 = 1e-3;
const W: u32 = 24;
const H: u32 = 24;

fn render(
    gpu: &Arc<Gpu>,
    scene: &Scene,
    algo: Algorithm,
    selection: LightSelection,
    iterations: u64,
    seed: u32,
) -> render::RenderOutput {
    let mut s = RenderSettings::new(algo, W, H, Budget::Iterations(iterations));
    s.frame.seed = seed;
    s.frame.max_path_length = 5;
    s.frame.light_selection = selection;
    render_checked(gpu, scene, &s)
}

/// The mean over pixels of the per-sample variance (all channels).
fn mean_variance(s: &PixelStats) -> f64 {
    s.variance.iter().map(|v| v[0] + v[1] + v[2]).sum::<f64>() / (3 * s.variance.len()) as f64
}

/// glossy_floor_scene (its large area light: two triangles of power pi 4.5 2 = 28 each)
/// with a small bright emitter facing the camera (two triangles of power pi 0.045 40 =
/// 5.7 each), a point light (power 4 pi times its intensity's luminance 0.46: 5.7) and a
/// dim constant background (power 4 pi pi r^2 times its luminance 0.024: about 19 for the
/// scene's bounding radius r = 4.5).
fn many_lights_scene() -> Scene {
    let left = Material { name: "floor_left".into(), diffuse: Vec3::new(0.6, 0.5, 0.4), ..Default::default() };
    let right = Material {
        name: "floor_right".into(),
        diffuse: Vec3::new(0.3, 0.5, 0.6),
        glossy: Vec3::splat(0.3),
        roughness: 0.4,
        ..Default::default()
    };
    let mut s = glossy_floor_scene(left, right);
    add_filament(&mut s, Vec3::new(-0.8, 0.6, 0.4), 40.0);
    s.lights.push(Light::Point { position: Vec3::new(1.2, 0.5, 0.8), intensity: Vec3::new(0.5, 0.45, 0.4) });
    s.lights.push(Light::Background { radiance: Vec3::new(0.02, 0.025, 0.03) });
    s.name = "many lights".into();
    s
}

/// The lights' pick probabilities by power differ by more than a factor 3 (else the test
/// would not exercise anything), and the table draws them as the kernels divide by them.
#[test]
fn power_selection_table_of_the_test_scene() {
    let scene = many_lights_scene();
    assert_eq!(scene.lights.len(), 6);
    let d = LightDistribution::new(&scene, LightSelection::Power);
    let (lo, hi) = d.prob.iter().fold((1.0f32, 0.0f32), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    eprintln!("pick probabilities by power: {:?}", d.prob);
    assert!(lo > 0.0 && hi > 3.0 * lo, "probabilities {:?}", d.prob);
    assert!((d.prob.iter().sum::<f32>() - 1.0).abs() < 1e-5);
    assert_eq!(LightDistribution::new(&scene, LightSelection::Uniform), LightDistribution::uniform(6));
}

/// PT, BPT and LT picking lights by power against PT picking them uniformly, per pixel.
/// LT is compared where the camera sees a surface (it cannot reach the camera along a
/// ray that escapes to the background). Sabotage caught: the kernels dividing by
/// 1 / #lights while picking by power.
#[test]
fn power_selection_matches_uniform_selection() {
    with_gpu(|gpu| {
        let scene = many_lights_scene();
        let surfaces = common::primary_hit_mask(&scene, W, H, |_| true);
        let kept = surfaces.iter().filter(|&&k| k).count();
        assert!(kept > (W * H / 2) as usize, "the mask keeps {kept} pixels");
        let uniform_out = render(gpu, &scene, Algorithm::Pt, LightSelection::Uniform, 4096, 51);
        let uniform = render_stats(&uniform_out, None);
        assert!(image_mean(&uniform) > 0.05, "the scene rendered (almost) black");
        for (algo, iterations) in [(Algorithm::Pt, 4096), (Algorithm::Bpt, 2048), (Algorithm::Lt, 8192)] {
            let mask = (algo == Algorithm::Lt).then_some(surfaces.as_slice());
            let reference = &render_stats(&uniform_out, mask);
            let power = render_stats(&render(gpu, &scene, algo, LightSelection::Power, iterations, 52), mask);
            eprintln!(
                "{}: image mean PT uniform {:.5}, {} power {:.5}; mean per-sample variance {:.4e} (PT uniform {:.4e})",
                algo.name(),
                image_mean(reference),
                algo.name(),
                image_mean(&power),
                mean_variance(&power),
                mean_variance(reference)
            );
            let t = welch_test(reference, &power, ALPHA).unwrap();
            assert!(t.passed(), "PT uniform vs {} power: {t}", algo.name());
        }
    });
}
