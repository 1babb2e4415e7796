//! One-sided surfaces (glTF `doubleSided: false`, `Material::one_sided`): the camera does
//! not see their back side, it sees what lies behind it (glsl/scene.glsl,
//! `trace_camera_segment`, `visible_to_camera`), while light meets both sides of every
//! surface. Lavapipe, validation on.
//!
//! * An analytic case: a one-sided quad seen from behind against a white sky is not there
//!   (every pixel is the sky's radiance, exactly), a two-sided one is.
//! * Agreement: in a scene where the camera looks through the back of a one-sided quad at
//!   the floor the quad shadows, and through the back of a one-sided area light, light
//!   tracing (whose vertices reach the camera by connections traced from the camera), BPT
//!   and VCM must agree with PT per pixel (Welch tests, Šidák-corrected to a false-failure
//!   probability ALPHA per comparison, as in tests/render_ggx.rs).

mod common;

use std::sync::Arc;

use common::scenes::*;
use common::{render_checked, render_stats, with_gpu};
use glam::Vec3;
use vkvcm::gpu::Gpu;
use vkvcm::render::{self, Algorithm, Budget, RenderSettings};
use vkvcm::scene::{Light, Material, Scene, Triangle};
use vkvcm_tools::stats::{welch_test, PixelStats};

const ALPHA: f64 = 1e-3;
const W: u32 = 24;
const H: u32 = 24;

fn render(gpu: &Arc<Gpu>, scene: &Scene, algo: Algorithm, iterations: u64) -> render::RenderOutput {
    let mut s = RenderSettings::new(algo, W, H, Budget::Iterations(iterations));
    s.frame.max_path_length = 5;
    render_checked(gpu, scene, &s)
}

fn quad(a: Vec3, b: Vec3, c: Vec3, d: Vec3, material: u32) -> [Triangle; 2] {
    [
        Triangle { p: [a, b, c], n: None, material, attributes: None },
        Triangle { p: [a, c, d], n: None, material, attributes: None },
    ]
}

/// A diffuse quad facing away from the camera, filling the middle of the view, under a
/// white sky of radiance 1 and nothing else.
fn quad_against_the_sky(one_sided: bool) -> Scene {
    let v = Vec3::new;
    // Winding normal +y: away from the camera at y = -3.
    let tris = quad(v(-1., 0., -1.), v(-1., 0., 1.), v(1., 0., 1.), v(1., 0., -1.), 0).to_vec();
    assert!((tris[0].p[1] - tris[0].p[0]).cross(tris[0].p[2] - tris[0].p[0]).y > 0.0);
    let grey = Material { name: "grey".into(), diffuse: Vec3::splat(0.7), one_sided, ..Default::default() };
    let sky = Light::Background { radiance: Vec3::ONE };
    scene("quad_against_the_sky", tris, vec![grey], vec![sky], camera(v(0., -3., 0.), Vec3::Y, Vec3::Z, 40.0))
}

/// The sky through the back of a one-sided quad is exactly the sky (a camera ray that
/// passes the quad meets nothing else); with a two-sided quad the middle pixels see the
/// quad's diffuse back instead, lit by the sky (radiance 0.7), and `el` sees it too.
#[test]
fn a_one_sided_quad_seen_from_behind_is_not_there() {
    with_gpu(|gpu| {
        let centre = ((H / 2) * W + W / 2) as usize;
        for one_sided in [true, false] {
            let scene = quad_against_the_sky(one_sided);
            let out = render(gpu, &scene, Algorithm::Pt, 8);
            let mean = |i: usize| out.sum[i][1] / out.iterations as f64;
            if one_sided {
                for i in 0..(W * H) as usize {
                    assert_eq!(mean(i), 1.0, "pixel {i}: the sky through a one-sided quad's back");
                }
            } else {
                assert!(mean(centre) < 0.95, "the middle pixel sees the two-sided quad: {}", mean(centre));
            }
            let el = render(gpu, &scene, Algorithm::El, 1);
            let seen = el.sum[centre][1];
            assert_eq!(seen > 0.0, !one_sided, "el, one-sided {one_sided}: the middle pixel shows {seen}");
        }
    });
}

/// z-up: a two-sided diffuse floor z = 0; above it a one-sided diffuse quad at z = 1 whose
/// front faces down, shadowing the floor from a one-sided area light at z = 2.5 that
/// faces down too. The camera is above both and sees their back sides: with
/// `one_sided` it sees through both, onto the floor and the quad's shadow (lit only by
/// light the floor and the quad's front reflect); light still meets both sides of the
/// quad, so the shadow is there either way.
fn shadowing_quad_scene(one_sided: bool) -> Scene {
    let v = Vec3::new;
    let mut tris = Vec::new();
    tris.extend(quad(v(-3., -3., 0.), v(3., -3., 0.), v(3., 3., 0.), v(-3., 3., 0.), 0)); // normal +z
    tris.extend(quad(v(-1., -1., 1.), v(-1., 1., 1.), v(1., 1., 1.), v(1., -1., 1.), 1)); // normal -z
    tris.extend(quad(v(-0.6, -0.6, 2.5), v(-0.6, 0.6, 2.5), v(0.6, 0.6, 2.5), v(0.6, -0.6, 2.5), 2)); // normal -z
    let materials = vec![
        Material { name: "floor".into(), diffuse: Vec3::new(0.6, 0.55, 0.5), ..Default::default() },
        Material { name: "shade".into(), diffuse: Vec3::splat(0.8), one_sided, ..Default::default() },
        Material { name: "lamp".into(), emission: Vec3::splat(6.0), one_sided, ..Default::default() },
    ];
    let lights = area_lights(&tris, &materials);
    let cam = camera(v(0., -2.5, 4.5), v(0., 2.5, -4.2), Vec3::Z, 55.0);
    scene("shadowing_quad", tris, materials, lights, cam)
}

fn middle_mean(s: &PixelStats) -> f64 {
    let mut sum = 0.0;
    let mut n = 0;
    for y in H / 3..2 * H / 3 {
        for x in W / 3..2 * W / 3 {
            sum += s.mean[(y * W + x) as usize][1];
            n += 1;
        }
    }
    sum / n as f64
}

#[test]
fn light_tracing_bpt_and_vcm_agree_with_pt_through_one_sided_backs() {
    with_gpu(|gpu| {
        let scene = shadowing_quad_scene(true);
        let pt = render_stats(&render(gpu, &scene, Algorithm::Pt, 256), None);
        for (algo, iterations) in [(Algorithm::Lt, 256), (Algorithm::Bpt, 128), (Algorithm::Vcm, 128)] {
            let other = render_stats(&render(gpu, &scene, algo, iterations), None);
            let t = welch_test(&pt, &other, ALPHA).unwrap();
            assert!(t.passed(), "PT vs {}: {t}", algo.name());
        }
        // Not a vacuous agreement: two-sided, the middle of the view is the quad's top and
        // the lamp's black back, instead of the floor in the shadow.
        let two_sided = render_stats(&render(gpu, &shadowing_quad_scene(false), Algorithm::Pt, 64), None);
        let (a, b) = (middle_mean(&pt), middle_mean(&two_sided));
        eprintln!("middle of the view (green): one-sided {a:.4}, two-sided {b:.4}");
        assert!((a - b).abs() > 0.2 * a.max(b), "one-sided {a} vs two-sided {b}: the rule changed nothing");
    });
}
