//! Path tracing against analytic answers and against itself with another sampling
//! strategy (issue: path tracing). All on lavapipe with validation on.
//!
//! Statistics: K independent renders (different seeds) give a per-pixel mean and
//! variance; pixels are tested with a two-sided z-test whose per-pixel level is
//! Šidák-corrected so that the whole image has false-failure probability `ALPHA`.

mod common;

use common::scenes::*;
use common::with_gpu;
use glam::Vec3;
use vkvcm::image::Image;
use vkvcm::render::{self, Algorithm, Budget, RenderSettings};
use vkvcm::scene::{Light, Material, Scene};
use vkvcm_tools::stats::{z_test, z_test_analytic};

/// Whole-image false-failure probability of each statistical test.
const ALPHA: f64 = 1e-3;

fn render_runs(gpu: &std::sync::Arc<vkvcm::gpu::Gpu>, scene: &Scene, s: &RenderSettings, runs: u32) -> Vec<Image> {
    (0..runs)
        .map(|k| {
            let mut s = s.clone();
            s.frame.seed = 1000 + 7919 * k;
            let out = render::render(gpu, scene, &s, None, &mut |_| {}).unwrap();
            assert_eq!(out.rejected_samples, 0, "rejected samples in {}", scene.name);
            Image { width: out.width, height: out.height, data: out.pixels }
        })
        .collect()
}

/// A closed box, every wall Lambertian with albedo `a` and emitting `le`; the camera is
/// inside. Radiance everywhere is le * sum_{k=0}^{K-1} a^k for paths of at most K
/// segments (each bounce adds one segment, the first segment sees le directly).
#[test]
fn white_furnace_matches_analytic_radiance() {
    let a = 0.7f32;
    let le = 0.5f32;
    let max_len = 6u32;
    let mat =
        Material { name: "furnace".into(), diffuse: Vec3::splat(a), emission: Vec3::splat(le), ..Default::default() };
    let tris = inward_box(1.0, 0);
    let lights = area_lights(&tris, std::slice::from_ref(&mat));
    let cam = camera(Vec3::new(0.1, -0.2, 0.05), Vec3::new(0.3, 1.0, 0.2), Vec3::Z, 70.0);
    let scene = scene("furnace", tris, vec![mat], lights, cam);
    let expected = le * (0..max_len).map(|k| a.powi(k as i32)).sum::<f32>();
    with_gpu(|gpu| {
        let mut s = RenderSettings::new(Algorithm::Pt, 16, 16, Budget::Iterations(16));
        s.frame.max_path_length = max_len;
        let runs = render_runs(gpu, &scene, &s, 4);
        let reference = Image { width: 16, height: 16, data: vec![[expected; 3]; 256] };
        let t = z_test_analytic(&runs, &reference, ALPHA);
        assert!(t.passed(), "furnace: expected {expected}: {t}");
        // Energy: the mean over the image is close to the analytic value too.
        let mean = runs.iter().map(|i| i.mean()[0]).sum::<f64>() / runs.len() as f64;
        assert!((mean - expected as f64).abs() < 0.02 * expected as f64, "mean {mean} vs {expected}");
    });
}

/// A Lambertian plane (albedo rho) under a point light of intensity I at height h, seen
/// from above. Each pixel's expected value is the pixel-area average of
/// rho/pi * I cos(theta) / d^2, integrated here on the CPU with 16x16 sub-samples.
#[test]
fn point_light_on_plane_matches_analytic_irradiance() {
    let rho = 0.6f32;
    let intensity = 3.0f32;
    let light_pos = Vec3::new(0.3, 0.2, 1.0);
    let mat = Material { name: "plane".into(), diffuse: Vec3::splat(rho), ..Default::default() };
    let s = 4.0f32;
    let plane = vec![
        vkvcm::scene::Triangle {
            p: [Vec3::new(-s, -s, 0.), Vec3::new(s, -s, 0.), Vec3::new(s, s, 0.)],
            n: None,
            material: 0,
            attributes: None,
        },
        vkvcm::scene::Triangle {
            p: [Vec3::new(-s, -s, 0.), Vec3::new(s, s, 0.), Vec3::new(-s, s, 0.)],
            n: None,
            material: 0,
            attributes: None,
        },
    ];
    let cam_pos = Vec3::new(0.0, 0.0, 2.0);
    let cam = camera(cam_pos, -Vec3::Z, Vec3::Y, 60.0);
    let lights = vec![Light::Point { position: light_pos, intensity: Vec3::splat(intensity) }];
    let scene = scene("plane", plane, vec![mat], lights, cam.clone());
    let (w, h) = (24u32, 24u32);
    // CPU expectation, with the same camera model as glsl/scene.glsl.
    let expected = pixel_means(&cam, w, h, |d| {
        let t = -cam_pos.z / d.z;
        let x = cam_pos + t * d;
        let l = light_pos - x;
        let cos = l.z / l.length();
        (rho / std::f32::consts::PI * intensity * cos / l.length_squared()) as f64
    });
    with_gpu(|gpu| {
        let s = RenderSettings::new(Algorithm::Pt, w, h, Budget::Iterations(8));
        let runs = render_runs(gpu, &scene, &s, 4);
        let t = z_test_analytic(&runs, &Image { width: w, height: h, data: expected.clone() }, ALPHA);
        assert!(t.passed(), "point light on plane: {t}");
    });
}

/// A Lambertian plane (albedo rho) under a large one-sided square area light of radiance
/// le at height 0.3, paths of two segments (direct light only). Each pixel's expected value
/// is the pixel-area average of rho/pi * E, E from Lambert's formula for a polygon, E =
/// le/2 sum_i acos(u_i.u_(i+1)) n.normalize(u_i x u_(i+1)) (u_i the unit vectors to the
/// corners), integrated here on the CPU with 16x16 sub-samples. The camera, under the
/// light, sees the plane below the light's edge, where the light is large, near and
/// grazing: next-event estimation samples its triangles by solid angle there, and the MIS
/// weight of an emitter hit takes that pdf from the previous vertex (glsl/lights.glsl).
#[test]
fn large_area_light_on_plane_matches_analytic_irradiance() {
    let rho = 0.6f32;
    let le = 1.5f32;
    let v = Vec3::new;
    let height = 0.3f32;
    // Counter-clockwise seen from below: the light's normal is -z.
    let corners = [v(-0.2, -1.0, height), v(-0.2, 1.0, height), v(1.8, 1.0, height), v(1.8, -1.0, height)];
    let plane = Material { name: "plane".into(), diffuse: Vec3::splat(rho), ..Default::default() };
    let lamp = Material { name: "lamp".into(), emission: Vec3::splat(le), ..Default::default() };
    let tri = |p: [Vec3; 3], material: u32| vkvcm::scene::Triangle { p, n: None, material, attributes: None };
    let s = 4.0f32;
    let tris = vec![
        tri([v(-s, -s, 0.), v(s, -s, 0.), v(s, s, 0.)], 0),
        tri([v(-s, -s, 0.), v(s, s, 0.), v(-s, s, 0.)], 0),
        tri([corners[0], corners[1], corners[2]], 1),
        tri([corners[0], corners[2], corners[3]], 1),
    ];
    let materials = vec![plane, lamp];
    let lights = area_lights(&tris, &materials);
    let cam_pos = v(0.0, 0.0, 0.25);
    let cam = camera(cam_pos, -Vec3::Z, Vec3::Y, 90.0);
    let scene = scene("large_light", tris, materials, lights, cam.clone());
    let (w, h) = (24u32, 24u32);
    // CPU expectation, with the same camera model as glsl/scene.glsl.
    let expected = pixel_means(&cam, w, h, |d| {
        let x = (cam_pos + (-cam_pos.z / d.z) * d).as_dvec3();
        let u: Vec<_> = corners.iter().map(|c| (c.as_dvec3() - x).normalize()).collect();
        let e: f64 = (0..4)
            .map(|i| {
                let (a, b) = (u[i], u[(i + 1) % 4]);
                a.dot(b).clamp(-1.0, 1.0).acos() * a.cross(b).normalize().z
            })
            .sum::<f64>()
            .abs()
            * 0.5
            * le as f64;
        rho as f64 / std::f64::consts::PI * e
    });
    with_gpu(|gpu| {
        let mut s = RenderSettings::new(Algorithm::Pt, w, h, Budget::Iterations(64));
        s.frame.max_path_length = 2;
        // 16 runs: the per-pixel test is a t-test on the runs, and with 6 (5 degrees of
        // freedom) a 4% bias of every pixel stayed below the threshold.
        let runs = render_runs(gpu, &scene, &s, 16);
        let t = z_test_analytic(&runs, &Image { width: w, height: h, data: expected.clone() }, ALPHA);
        assert!(t.passed(), "large area light on plane: {t}");
        // The image mean within 1%: the quadrature of the expectation and the noise of the
        // mean are each below 0.1% (measured -0.03%).
        let mean = runs.iter().map(|i| i.mean()[0]).sum::<f64>() / runs.len() as f64;
        let want = expected.iter().map(|p| p[0] as f64).sum::<f64>() / expected.len() as f64;
        assert!((mean / want - 1.0).abs() < 0.01, "image mean {mean} vs analytic {want}");
    });
}

/// Path tracing with next-event estimation + MIS and with BSDF sampling only are two
/// different estimators of the same image: per-pixel z-test on scenes whose lights can
/// be hit (area light, background).
///
/// BSDF sampling alone reaches glm_c's small light rarely (from the glossy floor only
/// through its 12.5% diffuse lobe: about one hit per thousand samples), and a z-test
/// needs each run's sample variance to be meaningful, i.e. many hits per pixel and run.
/// So the BSDF-only side gets 64x the samples (seen failing at 4x: all runs 0 at a
/// pixel whose long-run value is 0.03).
#[test]
fn nee_and_bsdf_sampling_agree_on_reference_scenes() {
    with_gpu(|gpu| {
        for (name, iters) in [("glm_c", 128), ("gbs_b", 32)] {
            let scene = vkvcm::scene::load_named(name).unwrap();
            let mut s = RenderSettings::new(Algorithm::Pt, 16, 16, Budget::Iterations(iters));
            let a = render_runs(gpu, &scene, &s, 6);
            s.nee = false;
            s.budget = Budget::Iterations(iters * 64);
            let b = render_runs(gpu, &scene, &s, 6);
            let t = z_test(&a, &b, ALPHA);
            assert!(t.passed(), "{name}: NEE vs BSDF sampling: {t}");
        }
    });
}

/// The four reference scenes render with no NaN/Inf/negative sample, a plausible
/// (non-black, finite) image, and no validation message.
#[test]
fn reference_scenes_render_clean() {
    with_gpu(|gpu| {
        for name in vkvcm::scene::BUILTIN_SCENES {
            let scene = vkvcm::scene::load_named(name).unwrap();
            for algo in [Algorithm::Pt, Algorithm::El] {
                let s = RenderSettings::new(algo, 32, 32, Budget::Iterations(2));
                let out = render::render(gpu, &scene, &s, None, &mut |_| {}).unwrap();
                assert_eq!(out.rejected_samples, 0, "{name}/{algo:?}");
                assert!(out.pixels.iter().flatten().all(|v| v.is_finite() && *v >= 0.0));
                let mean: f32 = out.pixels.iter().map(|p| p[0] + p[1] + p[2]).sum::<f32>();
                assert!(mean > 0.0, "{name}/{algo:?} rendered black");
            }
        }
    });
}

/// Same scene, seed, settings and device give bit-identical images; another seed does not.
#[test]
fn renders_are_deterministic() {
    with_gpu(|gpu| {
        let scene = vkvcm::scene::load_named("gbs_s").unwrap();
        let s = RenderSettings::new(Algorithm::Pt, 32, 32, Budget::Iterations(3));
        let a = render::render(gpu, &scene, &s, None, &mut |_| {}).unwrap().pixels;
        let b = render::render(gpu, &scene, &s, None, &mut |_| {}).unwrap().pixels;
        let bits = |v: &Vec<[f32; 3]>| v.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&a), bits(&b));
        let mut s2 = s.clone();
        s2.frame.seed += 1;
        let c = render::render(gpu, &scene, &s2, None, &mut |_| {}).unwrap().pixels;
        assert_ne!(bits(&a), bits(&c));
    });
}

/// Each pixel's mean of `value(d)` over a 16 x 16 grid of its camera directions d (the
/// camera model of glsl/scene.glsl), as an RGB image's texels.
fn pixel_means(cam: &vkvcm::scene::Camera, w: u32, h: u32, value: impl Fn(Vec3) -> f64) -> Vec<[f32; 3]> {
    let right = cam.forward.cross(cam.up).normalize();
    let up = right.cross(cam.forward);
    let dist = h as f32 / (2.0 * (0.5 * cam.yfov).tan());
    let sub = 16;
    let mut out = vec![[0f32; 3]; (w * h) as usize];
    for py in 0..h {
        for px in 0..w {
            let mut acc = 0.0f64;
            for sy in 0..sub {
                for sx in 0..sub {
                    let rx = px as f32 + (sx as f32 + 0.5) / sub as f32;
                    let ry = py as f32 + (sy as f32 + 0.5) / sub as f32;
                    acc += value(
                        (cam.forward * dist + right * (rx - 0.5 * w as f32) + up * (0.5 * h as f32 - ry)).normalize(),
                    );
                }
            }
            out[(py * w + px) as usize] = [(acc / (sub * sub) as f64) as f32; 3];
        }
    }
    out
}
