//! The clear coat (KHR_materials_clearcoat, glsl/lobes/clearcoat.glsl):
//! f = (1 - c(v)) f_base + c(v) f_coat with c(v) = clearcoat x F_coat(|n.v|).
//!
//! - The coat alone (over a black base) on a sphere under a uniform white sky, paths of 2
//!   segments: a pixel sees c(mu) E(mu), E the directional albedo of the F = 1 GGX lobe by
//!   CPU quadrature (the same independent formulas as tests/render_ggx.rs), averaged over
//!   the pixel's footprint: a per-pixel one-sample z-test against that.
//! - A white furnace: coated white materials (dielectric, metal, mirror) never return
//!   more than they receive; the loss is stated.
//! - The estimators agree: PT with and without NEE (sampling against evaluation), BPT and
//!   LT against PT on a closed scene (reverse pdfs, the adjoint: the blend uses the
//!   viewer's direction, wi on light subpaths).
//!
//! Statistics as in tests/render_ggx.rs: K = iterations independent samples per pixel,
//! per-pixel tests Šidák-corrected so that each comparison has false-failure probability
//! ALPHA. Lavapipe, validation on.

mod common;

use common::ggx::ggx_albedo;
use common::scenes::*;
use common::{image_mean, with_gpu, TestRender};
use glam::Vec3;
use vkvcm::render::Algorithm;
use vkvcm::scene::{Light, Material, Scene, Sphere};
use vkvcm_tools::stats::one_sample_test;

const ALPHA: f64 = 1e-3;
const W: u32 = 20;
const H: u32 = 20;
/// The texel of the texture tests: R 64 (coat factor), G 204 (coat roughness).
const TEXEL: [u8; 4] = [64, 204, 0, 255];

fn coated(name: &str, base: Material, clearcoat: f32, roughness: f32) -> Material {
    Material { name: name.into(), clearcoat, clearcoat_roughness: roughness, ..base }
}

/// A unit sphere of `mat` at the origin under a uniform white sky, seen from +z.
fn sphere_scene(mat: Material) -> Scene {
    let cam = camera(Vec3::new(0.0, 0.0, 3.2), Vec3::new(0.0, 0.0, -1.0), Vec3::Y, 45.0);
    let mut sc = scene("coat sphere", vec![], vec![mat], vec![Light::Background { radiance: Vec3::ONE }], cam);
    sc.spheres = vec![Sphere { center: Vec3::ZERO, radius: 1.0, material: 0 }];
    sc
}

fn schlick(f0: f64, c: f64) -> f64 {
    f0 + (1.0 - f0) * (1.0 - c).powi(5)
}

/// The coat over a black base (zero lobes: the base is invalid, the coat drawn alone) on
/// a sphere under a uniform sky of radiance 1: each pixel is the mean over its footprint
/// (an 8 x 8 grid) of clearcoat F_coat(mu) E(mu), tested per pixel (one-sample z) where the
/// pixel's 64 points all see the sphere at mu >= 0.15 or all miss it (then 1). E is
/// tabulated at 65 cosines and interpolated linearly (its error, below 1e-3 of E, is far
/// below a pixel's standard error). Clearcoat 0.8, roughness 0.3 and 0.7. Sabotages: the
/// Fresnel taken at |n.wi| (the light's side) in place of the viewer's, and the coat's
/// alpha taken as the roughness itself, each fail it.
#[test]
fn coat_alone_matches_quadrature() {
    with_gpu(|gpu| {
        for roughness in [0.3f32, 0.7] {
            let a = (roughness as f64).powi(2);
            let table: Vec<f64> = (0..=64).map(|i| ggx_albedo((i as f64 / 64.0).max(1e-3), a, 600, 160)).collect();
            let albedo = |mu: f64| {
                let t = mu.clamp(0.0, 1.0) * 64.0;
                let i = (t.floor() as usize).min(63);
                table[i] + (table[i + 1] - table[i]) * (t - i as f64)
            };
            let sc = sphere_scene(coated("black coated", Material::default(), 0.8, roughness));
            // Per pixel: the expected value, or None where the pixel is left out.
            let pixel = |i: u32| -> Option<f32> {
                let (x, y) = ((i % W) as f32, (i / W) as f32);
                let hits: Vec<Option<f64>> = (0..64)
                    .map(|k| {
                        unit_sphere_hit_cos(
                            &sc.camera,
                            W,
                            H,
                            x + ((k % 8) as f32 + 0.5) / 8.0,
                            y + ((k / 8) as f32 + 0.5) / 8.0,
                        )
                    })
                    .collect();
                if hits.iter().all(Option::is_none) {
                    Some(1.0)
                } else if hits.iter().all(|h| h.is_some_and(|c| c >= 0.15)) {
                    let c = hits.iter().flatten();
                    Some((c.map(|&mu| 0.8 * schlick(0.04, mu) * albedo(mu)).sum::<f64>() / 64.0) as f32)
                } else {
                    None
                }
            };
            let values: Vec<Option<f32>> = (0..W * H).map(pixel).collect();
            let mask: Vec<bool> = values.iter().map(Option::is_some).collect();
            let mut expected = vkvcm::image::Image::filled(W, H, [0.0; 3]);
            for (e, v) in expected.data.iter_mut().zip(&values) {
                *e = [v.unwrap_or(0.0); 3];
            }
            let st = TestRender::new(Algorithm::Pt, W, H, 1024).seed(51).max_path_length(2).stats(gpu, &sc);
            let masked = {
                let mut m = st.clone();
                for (i, _) in mask.iter().enumerate().filter(|(_, keep)| !**keep) {
                    m.mean[i] = [0.0; 3];
                    m.variance[i] = [0.0; 3];
                }
                m
            };
            eprintln!("roughness {roughness}: image mean {:.5}", image_mean(&st));
            let t = one_sample_test(&masked, &expected, ALPHA).unwrap();
            assert!(t.passed(), "roughness {roughness}: the coat alone vs quadrature: {t}");
        }
    });
}

/// White furnace: coated white spheres (glTF white dielectric of roughness 0 and 0.5,
/// white metal of roughness 0.3, white mirror, i.e. smooth metal) under a uniform white
/// sky, PT with paths of 2 segments (a convex sphere: each pixel is the material's
/// directional albedo). No pixel may exceed 1 (one-sided per-pixel test at the
/// Šidák-corrected z). The floors: the image's mean measured 0.9xx (see the messages);
/// what is lost is the coat's single-scattering GGX loss and the base's own.
#[test]
fn clearcoat_furnace() {
    with_gpu(|gpu| {
        for (label, base, coat_roughness, floor) in [
            ("white dielectric r 0", Material::metallic_roughness(Vec3::ONE, 0.0, 0.0), 0.0f32, 0.97),
            ("white dielectric r 0.5", Material::metallic_roughness(Vec3::ONE, 0.0, 0.5), 0.5, 0.9),
            ("white metal r 0.3", Material::metallic_roughness(Vec3::ONE, 1.0, 0.3), 0.3, 0.9),
            ("white mirror", Material::metallic_roughness(Vec3::ONE, 1.0, 0.0), 0.2, 0.97),
        ] {
            let sc = sphere_scene(coated(label, base, 1.0, coat_roughness));
            let st = TestRender::new(Algorithm::Pt, W, H, 512).seed(61).max_path_length(2).stats(gpu, &sc);
            let worst = common::assert_no_pixel_above_one(&st, None, label);
            let mean = image_mean(&st);
            eprintln!("{label}, coat roughness {coat_roughness}: brightest pixel {worst:.4}, image mean {mean:.5}");
            assert!(mean >= floor, "{label}: the image's mean {mean} is below {floor}: energy lost");
        }
    });
}

/// glossy_floor_scene with coated floors: left a red dielectric (glTF roughness 0.6) under
/// a coat of roughness 0.4, factor 1, right a gold metal of roughness 0.5 under a
/// half coat of roughness 0.3. PT with NEE against PT without (bsdf_eval's pdf is the
/// density bsdf_sample draws), BPT and LT against PT (reverse pdfs; the adjoint blend on
/// light subpaths). Sabotages: the coat's probability left out of the reverse pdf, and
/// the blend taken at wo on light subpaths, each fail it.
#[test]
fn clearcoat_estimators_agree() {
    let left = coated("coated_red", Material::metallic_roughness(Vec3::new(0.8, 0.2, 0.1), 0.0, 0.6), 1.0, 0.4);
    let right = coated("coated_gold", Material::metallic_roughness(Vec3::new(0.9, 0.7, 0.3), 1.0, 0.5), 0.5, 0.3);
    let sc = glossy_floor_scene(left, right);
    with_gpu(|gpu| common::assert_estimators_agree(gpu, &sc, W, H, 4, 2048));
}

/// clearcoatTexture (R) and clearcoatRoughnessTexture (G) multiply the factors per point:
/// floors coated with factor 1 and roughness 0.5 under a texel (R, G) = (64, 204) / 255
/// must render as floors coated with factor 64/255 and roughness 0.5 x 204/255 = 0.4
/// without textures (PT, per pixel), and BPT on the textured floors must agree with PT
/// (light vertices carry the point's coat). Sabotage: the texel's G read as the factor
/// fails it (93 pixels); the coat left out of the stored light vertex (read back as 1) is
/// not caught (BPT's connections to stored vertices carry too little of the coat here).
#[test]
fn clearcoat_textures_scale_the_factors() {
    let base = |c: Vec3, m: f32| Material::metallic_roughness(c, m, 0.6);
    let t = nearest_texture(0);
    let textured = |name: &str, b: Material| Material {
        clearcoat_texture: Some(t.clone()),
        clearcoat_roughness_texture: Some(t.clone()),
        ..coated(name, b, 1.0, 0.5)
    };
    let red = Vec3::new(0.8, 0.2, 0.1);
    let gold = Vec3::new(0.9, 0.7, 0.3);
    let tex = textured_floor_scene(textured("red", base(red, 0.0)), textured("gold", base(gold, 1.0)), TEXEL);
    let (f, r) = (64.0 / 255.0, 0.5 * 204.0 / 255.0);
    let plain = textured_floor_scene(coated("red", base(red, 0.0), f, r), coated("gold", base(gold, 1.0), f, r), TEXEL);
    with_gpu(|gpu| common::assert_textures_match_factors(gpu, &tex, &plain, W, H));
}

/// The feature set compiles the coat in only where a primitive's material has one, and its
/// textures only where they apply (a generic-vs-specialised render of a coated scene was
/// left out: compiling the generic kernels took 71 s of CPU here; tests/render_features.rs
/// compares them on the reference scenes).
#[test]
fn coat_features() {
    use vkvcm::render::features::FeatureSet;
    let plain = glossy_floor_scene(Material::metallic_roughness(Vec3::ONE, 0.0, 0.5), Material::default());
    let f = FeatureSet::new(&plain, false);
    assert!(!f.clearcoat && !f.clearcoat_textures, "{f}");
    let coat = |name: &str| coated(name, Material::metallic_roughness(Vec3::new(0.8, 0.2, 0.1), 0.0, 0.6), 0.9, 0.3);
    let f = FeatureSet::new(&glossy_floor_scene(coat("a"), coat("b")), false);
    assert!(f.clearcoat && !f.clearcoat_textures && f.to_string().contains("clear coat"), "{f}");
    let t = nearest_texture(0);
    let sc = textured_floor_scene(Material { clearcoat_texture: Some(t), ..coat("textured") }, coat("b"), TEXEL);
    let f = FeatureSet::new(&sc, false);
    assert!(f.clearcoat && f.clearcoat_textures, "{f}");
}
