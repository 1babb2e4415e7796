//! Partial transmission (glsl/bsdf.glsl, "Partial transmission"; `Material::transmissive`):
//! glTF's KHR_materials_transmission with transmissionFactor below 1, or with metallic,
//! is glass of weight w beside the metallic/roughness lobes of weight 1 - w.
//!
//! - Linearity: where every path meets the surface once, the image is linear in the BSDF,
//!   so a partially transmissive surface must render as w x (its glass alone) + (1 - w) x
//!   (its lobes alone), per pixel. The two parts are validated on their own elsewhere
//!   (glass and rough glass against Mitsuba in tests/render_environment.rs, the lobes in
//!   tests/render_ggx.rs and tests/render_textures.rs), so this ties the mixture's
//!   weights, component probabilities and pdfs to independently checked images.
//! - The estimators agree (BPT and LT against PT) in a closed scene where light meets the
//!   lobes from inside the glass too, with shading normals: the forward and reverse pdfs
//!   and the adjoint form of the mixture.
//! - A white furnace: no pixel returns more than the uniform sky gives.
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
use vkvcm::render::{self, Algorithm, Budget, RenderSettings};
use vkvcm::scene::{EnvironmentLight, Light, Material, Scene, Sphere, Triangle, GLTF_DIELECTRIC_F0};
use vkvcm_tools::stats::{welch_test, PixelStats};

const ALPHA: f64 = 1e-3;
const W: u32 = 24;
const H: u32 = 24;
const IOR: f32 = 1.5;

fn render(
    gpu: &Arc<Gpu>,
    scene: &Scene,
    algo: Algorithm,
    iterations: u64,
    seed: u32,
    max_len: u32,
) -> render::RenderOutput {
    let mut s = RenderSettings::new(algo, W, H, Budget::Iterations(iterations));
    s.frame.seed = seed;
    s.frame.max_path_length = max_len;
    render_checked(gpu, scene, &s)
}

/// glTF's transmissive material (`Material::transmissive`, as the importer makes it).
fn transmissive(name: &str, base: Vec3, metallic: f32, roughness: f32, transmission: f32) -> Material {
    let f0 = Vec3::splat(GLTF_DIELECTRIC_F0);
    Material { name: name.into(), ..Material::transmissive(base, metallic, roughness, transmission, IOR, f0) }
}

/// A 2 x 2 quad tilted 30 degrees towards the camera, alone under a non-uniform sky
/// (`smooth_sky`): every camera path meets it at most once (a refracted ray leaves for
/// the sky), so the image is linear in its BSDF. With `shading_normals` its vertex
/// normals are tilted up to 25 degrees off the facet.
fn quad_scene(material: Material, shading_normals: bool) -> Scene {
    let (s, c) = (30f32.to_radians().sin(), 30f32.to_radians().cos());
    let p = |x: f32, y: f32| Vec3::new(x, y * c, -y * s);
    let triangles = vec![
        Triangle { p: [p(-1.0, -1.0), p(1.0, -1.0), p(1.0, 1.0)], n: None, material: 0, attributes: None },
        Triangle { p: [p(-1.0, -1.0), p(1.0, 1.0), p(-1.0, 1.0)], n: None, material: 0, attributes: None },
    ];
    let light = Light::Environment(EnvironmentLight {
        map: Arc::new(smooth_sky(64, 32)),
        scale: Vec3::ONE,
        rotation_deg: 30.0,
    });
    let cam = camera(Vec3::new(0.0, -1.0, 3.0), Vec3::new(0.0, 1.0, -3.0), Vec3::Y, 45.0);
    let mut sc = scene(&format!("quad {}", material.name), triangles, vec![material], vec![light], cam);
    if shading_normals {
        tilt_shading_normals(&mut sc, 25.0, 7);
    }
    sc
}

/// w a + (1 - w) b of two renders of K samples each: its mean and the variance that gives
/// its squared standard error when divided by K.
fn mix(a: &PixelStats, b: &PixelStats, w: f64) -> PixelStats {
    assert_eq!(a.count, b.count);
    let mut m = a.clone();
    for i in 0..m.mean.len() {
        for c in 0..3 {
            m.mean[i][c] = w * a.mean[i][c] + (1.0 - w) * b.mean[i][c];
            m.variance[i][c] = w * w * a.variance[i][c] + (1.0 - w) * (1.0 - w) * b.variance[i][c];
        }
    }
    m
}

/// The partially transmissive quad against w x the glass quad + (1 - w) x the lobes
/// quad, per pixel (PT). Cases: smooth glass beside GGX lobes of the smallest width
/// (glTF roughness 0), rough glass with a partly metallic lobe set, and the same with
/// shading normals. Sabotages caught: the interface weight left off the sampled mirror and
/// refraction, and the lobes' weight left off bsdf_eval.
#[test]
fn partial_transmission_is_the_mix_of_glass_and_lobes() {
    let base = Vec3::new(0.9, 0.6, 0.3);
    // (glTF roughness, transmission, metallic, shading normals)
    let cases = [(0.0, 0.5, 0.0, false), (0.4, 0.7, 0.3, false), (0.4, 0.7, 0.3, true)];
    with_gpu(|gpu| {
        for (i, (roughness, transmission, metallic, shading_normals)) in cases.into_iter().enumerate() {
            let partial = transmissive("partial", base, metallic, roughness, transmission);
            let w = partial.glass_weight as f64;
            assert!(w > 0.2 && w < 0.8, "glass weight {w}");
            let glass = transmissive("glass", base, 0.0, roughness, 1.0);
            let lobes_metallic = metallic / (1.0 - partial.glass_weight);
            // The lobes alone (metallic below 1, so no mirror stands in for a smooth metal).
            assert!(lobes_metallic < 1.0);
            let lobes =
                Material { name: "lobes".into(), ..Material::metallic_roughness(base, lobes_metallic, roughness) };
            let seed = 100 + 10 * i as u32;
            let st = |m: Material, seed: u32| {
                render_stats(&render(gpu, &quad_scene(m, shading_normals), Algorithm::Pt, 1024, seed, 4), None)
            };
            let p = st(partial, seed);
            let g = st(glass, seed + 1);
            let l = st(lobes, seed + 2);
            let m = mix(&g, &l, w);
            eprintln!(
                "roughness {roughness}, transmission {transmission}, metallic {metallic}, shading normals \
                 {shading_normals}: image mean partial {:.5}, mix {:.5} (glass {:.5}, lobes {:.5})",
                image_mean(&p),
                image_mean(&m),
                image_mean(&g),
                image_mean(&l)
            );
            assert!((image_mean(&g) - image_mean(&l)).abs() > 0.02, "the parts must differ to test the weights");
            let t = welch_test(&p, &m, ALPHA).unwrap();
            assert!(t.passed(), "case {i}: partial vs w glass + (1 - w) lobes: {t}");
        }
    });
}

/// glossy_floor_scene (diffuse floor, large area light) with a partially transmissive
/// coarse sphere mesh with its shading normals (rough glass, transmission 0.6, metallic
/// 0.2: w = 0.48) and an analytic sphere of smooth glass (IOR 1.5) beside rough lobes
/// (glass weight 0.5; not a glTF material, whose lobes share the glass's roughness, but
/// the same kernel paths with lobes that connections can reach), holding a small light:
/// light subpaths start inside it and meet its lobes from inside.
fn partial_scene() -> Scene {
    let left = Material { name: "floor_left".into(), diffuse: Vec3::new(0.6, 0.5, 0.4), ..Default::default() };
    let right = Material { name: "floor_right".into(), diffuse: Vec3::new(0.3, 0.5, 0.6), ..Default::default() };
    let mut s = glossy_floor_scene(left, right);
    let a = s.materials.len() as u32;
    s.materials.push(transmissive("rough_partial", Vec3::new(0.9, 0.7, 0.5), 0.2, 0.5, 0.6));
    let mut smooth = transmissive("smooth_partial", Vec3::new(0.6, 0.8, 0.9), 0.0, 0.5, 0.5);
    smooth.dielectric_roughness = 0.0;
    s.materials.push(smooth);
    s.triangles.extend(smooth_sphere_mesh(Vec3::new(0.8, 0.4, 0.55), 0.55, 6, 10, a));
    s.spheres.push(Sphere { center: Vec3::new(-0.8, 0.2, 0.5), radius: 0.5, material: a + 1 });
    add_filament(&mut s, Vec3::new(-0.8, 0.2, 0.5), 4.0);
    s.name = "partial transmission".into();
    s
}

/// BPT against PT per pixel everywhere; LT against PT where the camera sees no glass (LT
/// cannot reach the camera through smooth glass, and through rough glass its estimate is
/// a sum of rare large connections: tests/render_rough_glass.rs). VCM's merges read the
/// same bsdf_eval as BPT's connections, and its image is biased by the merge radius, so
/// it is left to tests/render_features.rs (specialised = generic on such a scene).
#[test]
fn partial_transmission_bpt_and_lt_match_pt() {
    with_gpu(|gpu| {
        let scene = partial_scene();
        let no_glass = common::primary_hit_mask(&scene, W, H, |m| !m.is_dielectric());
        let kept = no_glass.iter().filter(|&&k| k).count();
        assert!(kept > (W * H / 2) as usize && kept < (W * H) as usize, "the mask keeps {kept} pixels");
        let pt_out = render(gpu, &scene, Algorithm::Pt, 8192, 31, 6);
        for (algo, iterations) in [(Algorithm::Bpt, 4096), (Algorithm::Lt, 8192)] {
            let mask = (algo == Algorithm::Lt).then_some(no_glass.as_slice());
            let pt = &render_stats(&pt_out, mask);
            let other = render_stats(&render(gpu, &scene, algo, iterations, 32, 6), mask);
            eprintln!("image mean PT {:.5}, {} {:.5}", image_mean(pt), algo.name(), image_mean(&other));
            assert!(image_mean(pt) > 0.05, "the scene rendered (almost) black");
            let t = welch_test(pt, &other, ALPHA).unwrap();
            assert!(t.passed(), "PT vs {}: {t}", algo.name());
        }
    });
}

/// A white furnace: a sphere of white partially transmissive material (radius 1) under a
/// uniform white sky of radiance 1, PT with paths of up to 24 segments. Each part of the
/// mixture returns at most what it receives (the glass exactly that, the lobes less: single
/// scattering GGX), so no pixel may exceed 1 (one-sided per-pixel test at the
/// Šidák-corrected z), for glTF roughness 0 and 0.5, transmission 0.5 and 0.9, metallic 0
/// and 0.5. The image's mean must also reach a floor: at roughness 0 the lobes (GGX of
/// width 1e-3 and the Fresnel-weighted diffuse) lose almost nothing and the image returns
/// 0.991-0.992 of 1 (measured; what is lost is mostly paths longer than 24 segments); at
/// roughness 0.5 both parts lose what single scattering misses (measured 0.925 and
/// 0.889). The floors sit 1-4% below; the lobes left unevaluated from inside the glass (the
/// sign that turns their normal, sabotaged) gave 0.883, 0.850, 0.823 and 0.885.
#[test]
fn partial_transmission_furnace() {
    with_gpu(|gpu| {
        // (roughness, transmission, metallic, the floor of the image's mean)
        for (roughness, transmission, metallic, floor) in
            [(0.0, 0.5, 0.0, 0.98), (0.5, 0.5, 0.0, 0.9), (0.5, 0.9, 0.5, 0.86), (0.0, 0.9, 0.5, 0.98)]
        {
            let mat = transmissive("white", Vec3::ONE, metallic, roughness, transmission);
            let cam = camera(Vec3::new(0.0, 0.0, 3.2), Vec3::new(0.0, 0.0, -1.0), Vec3::Y, 45.0);
            let mut sc = scene("furnace", vec![], vec![mat], vec![Light::Background { radiance: Vec3::ONE }], cam);
            sc.spheres = vec![Sphere { center: Vec3::ZERO, radius: 1.0, material: 0 }];
            let st = render_stats(&render(gpu, &sc, Algorithm::Pt, 512, 41, 24), None);
            let what = format!("roughness {roughness}, transmission {transmission}, metallic {metallic}");
            let worst = common::assert_no_pixel_above_one(&st, None, &what);
            let least = st.mean.iter().flatten().fold(f64::INFINITY, |a, &b| a.min(b));
            // The image's mean (the channels of a pixel are not independent: their sum's
            // variance is at most 3 times the sum of theirs, Cauchy-Schwarz).
            let n = 3.0 * st.mean.len() as f64;
            let mean = st.mean.iter().flatten().sum::<f64>() / n;
            let se = st.variance.iter().map(|v| 3.0 * (v[0] + v[1] + v[2]) / st.count as f64).sum::<f64>().sqrt() / n;
            eprintln!("{what}: pixels from {least:.4} to {worst:.4}, image mean {mean:.5} +- {se:.5}");
            assert!(mean <= 1.0 + 4.0 * se, "the image's mean {mean} +- {se} exceeds 1");
            assert!(mean >= floor, "the image's mean {mean} +- {se} is below {floor}: energy lost");
        }
    });
}
