//! The anisotropic GGX lobe (KHR_materials_anisotropy, glsl/lobes/anisotropy.glsl):
//! alpha_t = mix(alpha, 1, strength^2) along the anisotropy direction, alpha_b = alpha
//! across it, the direction rotated in the tangent frame of the vertex tangents.
//!
//! - A floor of two anisotropic white metals under a lamp (tests/env/anisotropy_scene.gltf:
//!   one with its own TANGENT and a rotation, one with tangents generated from its texture
//!   coordinates, a rotation and an anisotropyTexture), paths of 2 segments, per pixel
//!   against a reference drawn with Mitsuba 3's anisotropic GGX distribution
//!   (scripts/anisotropy_reference.py: its D, G1 and visible-normal sampler), PT, BPT and
//!   VCM.
//! - The same scene with longer paths: PT with NEE, PT without, BPT and LT agree per pixel
//!   (bsdf_eval's forward pdf is the density bsdf_sample draws; the reverse pdfs; light
//!   subpaths, which evaluate f with wo and wi swapped: the lobe is symmetric).
//! - A white furnace: the floor under a uniform sky of radiance 1, 2 segments, so a pixel
//!   sees the lobe's directional albedo: no pixel exceeds 1, and the half of strength 0
//!   (with the anisotropic kernels) is the isotropic lobe's albedo by quadrature.
//!
//! Statistics as in tests/render_sheen.rs: per-pixel tests Šidák-corrected so that each
//! comparison has false-failure probability ALPHA. Lavapipe, validation on.

mod common;

use common::ggx::ggx_albedo;
use common::{assert_matches_mitsuba, image_mean, with_gpu, TestRender};
use glam::Vec3;
use vkvcm::render::Algorithm;
use vkvcm::scene::{Light, Scene};
use vkvcm_tools::stats::one_sample_test;

const ALPHA: f64 = 1e-3;
/// scripts/anisotropy_reference.py's SIZE and CAMERA.
const SIZE: u32 = 20;

/// tests/env/anisotropy_scene.gltf with the camera of scripts/anisotropy_reference.py and
/// no light but the file's lamp (whatever default environment the importer adds is
/// dropped: the reference has none).
fn floor_scene() -> Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/env/anisotropy_scene.gltf");
    let mut sc = vkvcm::scene::load_with(&path, &Default::default()).unwrap();
    sc.lights.retain(|l| !l.is_environment());
    let (from, to) = (Vec3::new(0.0, 2.0, 2.5), Vec3::new(0.0, 0.0, 0.5));
    sc.camera = common::scenes::camera(from, to - from, Vec3::Y, 40.0);
    sc
}

/// The importer made both floors anisotropic with tangents (the left from its TANGENT, the
/// right generated), and the kernels have the lobe.
#[test]
fn anisotropic_metal_matches_mitsuba_microfacets() {
    let sc = floor_scene();
    let aniso: Vec<_> = sc.materials.iter().filter(|m| m.has_anisotropy()).collect();
    assert_eq!(aniso.len(), 2, "both floors anisotropic");
    assert!(aniso[1].anisotropy_texture.is_some());
    let tangents = sc.triangles.iter().filter(|t| t.attributes.as_ref().is_some_and(|a| a.tangent.is_some())).count();
    assert_eq!(tangents, 4, "both floors' triangles have tangents");
    assert!(vkvcm::render::features::FeatureSet::new(&sc, false).anisotropy);
    with_gpu(|gpu| {
        assert_matches_mitsuba(
            gpu,
            &sc,
            "mitsuba_anisotropy",
            2,
            &[(Algorithm::Pt, 4096), (Algorithm::Bpt, 2048), (Algorithm::Vcm, 1024)],
        )
    });
}

/// PT with NEE against PT without, BPT and LT on the floor scene with 4 segments (the lamp's
/// own dielectric GGX lobe adds interreflections): per pixel, and their image means (a
/// two-sided z-test, Šidák-corrected over the three comparisons), which sees a bias of a
/// percent or two that the per-pixel test has no power for (a forward pdf with Lambda(wi)
/// in place of Lambda(wo): PT 1.342, PT without NEE 1.358, LT 1.382).
#[test]
fn anisotropic_estimators_agree() {
    let sc = floor_scene();
    with_gpu(|gpu| common::assert_estimators_agree(gpu, &sc, SIZE, SIZE, 4, 2048));
}

/// The floor under a uniform sky of radiance 1 (the lamp's emission off), 2 segments: a
/// pixel sees the directional albedo of the floor at its view direction. No pixel may
/// exceed 1 (one-sided, Šidák-corrected z); the right floor made isotropic (strength 0,
/// the kernels still anisotropic) is the isotropic lobe's albedo at its roughness 0.2 by
/// quadrature (tests/common/ggx.rs), per pixel, and bit for bit the same as with kernels
/// compiled without the anisotropy (both floors of strength 0).
#[test]
fn anisotropic_furnace() {
    let mut sc = floor_scene();
    let lamp = sc.materials.iter().position(|m| m.emission != Vec3::ZERO).unwrap();
    sc.materials[lamp].emission = Vec3::ZERO;
    sc.lights = vec![Light::Background { radiance: Vec3::ONE }];
    // The lamp would shadow the sky: move it below the floor, out of sight.
    for t in sc.triangles.iter_mut().filter(|t| t.material as usize == lamp) {
        for p in &mut t.p {
            p.y = -5.0;
        }
    }
    let right = sc.materials.iter().position(|m| m.anisotropy_texture.is_some()).unwrap();
    sc.materials[right].anisotropy_strength = 0.0;
    let a = (sc.materials[right].roughness as f64).powi(2);
    with_gpu(|gpu| {
        let st =
            TestRender::new(Algorithm::Pt, SIZE, SIZE, 1024).seed(91).max_path_length(2).independent().stats(gpu, &sc);
        let worst = common::assert_no_pixel_above_one(&st, None, "anisotropic furnace");
        eprintln!("furnace: brightest pixel {worst:.4}, image mean {:.5}", image_mean(&st));
        // The isotropic half: each pixel's albedo at its view cosine, averaged over an 8 x 8
        // grid of its footprint; pixels whose footprint straddles x = 0 are left out.
        let cam = &sc.camera;
        let plane = 0.5 * SIZE as f32 / (0.5 * cam.yfov).tan();
        let r = cam.forward.cross(cam.up).normalize();
        let u = r.cross(cam.forward);
        let mut expected = vkvcm::image::Image::filled(SIZE, SIZE, [0.0; 3]);
        let mut masked = st.clone();
        let (mut left_sum, mut left_n) = (0.0, 0);
        for i in 0..(SIZE * SIZE) as usize {
            let (x, y) = ((i as u32 % SIZE) as f32, (i as u32 / SIZE) as f32);
            let hits: Vec<(f32, f64)> = (0..64)
                .map(|k| {
                    let (px, py) = (x + ((k % 8) as f32 + 0.5) / 8.0, y + ((k / 8) as f32 + 0.5) / 8.0);
                    let d =
                        (cam.forward * plane + r * (px - 0.5 * SIZE as f32) + u * (0.5 * SIZE as f32 - py)).normalize();
                    let p = cam.position + d * (-cam.position.y / d.y);
                    (p.x, -d.y as f64)
                })
                .collect();
            if hits.iter().all(|h| h.0 > 0.0) {
                let e = hits.iter().map(|h| ggx_albedo(h.1, a, 400, 200)).sum::<f64>() / 64.0;
                expected.data[i] = [e as f32; 3];
            } else {
                if hits.iter().all(|h| h.0 < 0.0) {
                    left_sum += st.mean[i][1];
                    left_n += 1;
                }
                masked.mean[i] = [0.0; 3];
                masked.variance[i] = [0.0; 3];
            }
        }
        eprintln!("furnace: anisotropic half's mean albedo {:.5}", left_sum / left_n as f64);
        // Pooled variances: about 1 in 400 of the lobe's samples is lost below the horizon,
        // and a pixel none of whose samples was has a sample variance near 0.
        let keep: Vec<bool> = expected.data.iter().map(|e| *e != [0.0; 3]).collect();
        let t = one_sample_test(&masked.with_pooled_variance(&keep), &expected, ALPHA).unwrap();
        assert!(t.passed(), "strength 0 vs the isotropic lobe's albedo: {t}");
        // Both floors of strength 0: the kernels lack HAS_ANISOTROPY, and the isotropic
        // half's pixels are the same bit for bit (same seed, same isotropic code).
        for m in &mut sc.materials {
            m.anisotropy_strength = 0.0;
        }
        assert!(!vkvcm::render::features::FeatureSet::new(&sc, false).anisotropy);
        let iso =
            TestRender::new(Algorithm::Pt, SIZE, SIZE, 1024).seed(91).max_path_length(2).independent().stats(gpu, &sc);
        let same = (0..st.mean.len()).filter(|&i| masked.mean[i] != [0.0; 3]).all(|i| st.mean[i] == iso.mean[i]);
        let n = masked.mean.iter().filter(|m| **m != [0.0; 3]).count();
        assert!(n > 50 && same, "strength 0 with and without HAS_ANISOTROPY differ ({n} pixels compared)");
    });
}
