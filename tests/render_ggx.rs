//! The GGX microfacet lobe (glsl/bsdf.glsl): its sampling pdf against its evaluation
//! (PT with NEE vs BSDF sampling only), its reverse pdfs (BPT vs PT) and its energy
//! (furnace). Lavapipe, validation on.
//!
//! Statistics as in tests/render_bidir.rs: one render per estimator, K = iterations
//! independent samples per pixel, per-pixel Welch test, Šidák-corrected so that each
//! comparison has false-failure probability ALPHA. The scene's light is large
//! (3 x 3 at height 1.5 over the floor) so that BSDF-sampled hits of it are not rare
//! events for the roughness 0.3 and 0.7 lobes.

mod common;

use common::ggx::*;
use common::scenes::*;
use common::{assert_estimators_agree, image_mean, render_checked, render_stats, with_gpu, TestRender};
use glam::Vec3;
use vkvcm::render::{Algorithm, Budget, RenderSettings};
use vkvcm::scene::{Light, Material, Scene, Sphere};
use vkvcm_tools::stats::welch_test;

const ALPHA: f64 = 1e-3;
const W: u32 = 24;
const H: u32 = 24;

/// `algo` for `iterations` at W x H, paths of at most 4 segments.
fn run(algo: Algorithm, iterations: u64) -> TestRender {
    TestRender::new(algo, W, H, iterations).max_path_length(4)
}

/// Left half: pure GGX metal, roughness 0.3 (alpha 0.09), coloured F0. Right half:
/// roughness 0.7 (alpha 0.49) GGX with F0 0.04 over a diffuse base behind a dielectric
/// interface (the importer's dielectric mapping), so component selection and the diffuse
/// lobe's Fresnel weight are exercised too.
fn ggx_floor() -> Scene {
    let metal =
        Material { name: "ggx_metal".into(), glossy: Vec3::new(0.9, 0.7, 0.5), roughness: 0.3, ..Default::default() };
    let plastic = Material {
        name: "ggx_plastic".into(),
        diffuse: Vec3::new(0.2, 0.5, 0.3),
        glossy: Vec3::splat(0.04),
        roughness: 0.7,
        diffuse_fresnel_f0: 0.04,
        ..Default::default()
    };
    glossy_floor_scene(metal, plastic)
}

/// NEE + MIS uses bsdf_eval's f and pdf_fwd for light samples and bsdf_sample's
/// weight for BSDF hits; BSDF sampling only uses bsdf_sample alone. They agree only if
/// the sampled density is the pdf that bsdf_eval reports (a missing Jacobian fails).
#[test]
fn ggx_nee_and_bsdf_sampling_agree() {
    let scene = ggx_floor();
    with_gpu(|gpu| {
        let a = run(Algorithm::Pt, 1024).seed(11).stats(gpu, &scene);
        let b = run(Algorithm::Pt, 4096).seed(12).nee(false).stats(gpu, &scene);
        assert!(image_mean(&a) > 0.05, "the scene rendered (almost) black");
        let t = welch_test(&a, &b, ALPHA).unwrap();
        assert!(t.passed(), "GGX floor: PT NEE vs PT BSDF sampling only: {t}");
    });
}

/// The diffuse lobe under a dielectric interface is sampled by cos (1 - E(cos)), not by the
/// cosine (glsl/bsdf.glsl, sample_coupled_diffuse): pt with and without NEE, bpt and light
/// tracing agree per pixel and on the image mean on an interface of F0 0.04, roughness 0.3
/// (left: 1 - E from 0.55 at grazing angles to 0.96) and one of F0 0.5, roughness 0.5
/// (right, 0.40 to 0.54; KHR_materials_specular allows it). 8192 iterations: the pdf
/// reported at 0.9 times the density fails (t -36 on the image mean), cosine samples with
/// this pdf too (t 5.1). Smoother interfaces would vary 1 - E more, but light tracing's
/// samples of their highlights are too heavy-tailed for the per-pixel test (roughness 0.2
/// failed it with the cosine's sampling too).
#[test]
fn coupled_diffuse_sampling_agrees_with_its_pdf() {
    let plastic = |name: &str, roughness: f32, f0: f32| Material {
        name: name.into(),
        diffuse: Vec3::new(0.6, 0.5, 0.4),
        glossy: Vec3::splat(f0),
        roughness,
        diffuse_fresnel_f0: f0,
        ..Default::default()
    };
    let scene = glossy_floor_scene(plastic("smooth", 0.3, 0.04), plastic("rough_bright_coat", 0.5, 0.5));
    with_gpu(|gpu| assert_estimators_agree(gpu, &scene, W, H, 4, 8192));
}

/// BPT's connections to light vertices and its MIS weights use pdf_rev of the GGX lobe
/// on both subpaths; it must agree with PT (which samples every path here: the light
/// can be hit).
#[test]
fn ggx_bpt_matches_pt() {
    let scene = ggx_floor();
    with_gpu(|gpu| {
        let pt = run(Algorithm::Pt, 16384).seed(21).stats(gpu, &scene);
        let bpt = run(Algorithm::Bpt, 8192).seed(22).stats(gpu, &scene);
        let t = welch_test(&pt, &bpt, ALPHA).unwrap();
        assert!(t.passed(), "GGX floor: PT vs BPT: {t}");
    });
}

/// src/render/ggx_albedo.rs is the quadrature of tests/common/ggx.rs (committed within its
/// 5-decimal rounding; VKVCM_WRITE_GGX_TABLE=1 rewrites it, checked from the next build),
/// converged (128 against 256
/// cells: 3e-5), its averages are the exact integrals of the interpolated table, and its
/// smooth limit is Schlick's F with E_avg = F0 + (1 - F0) / 21 (analytic). Between rows
/// and columns the bilinear interpolation stays within 2e-3 of the quadrature at cosines
/// above 0.2 (measured 8e-4) and within 1e-3 cosine-weighted (measured 3e-4): what a
/// white dielectric may miss of 1 in `gltf_material_never_reflects_more_than_it_receives`.
/// Below 0.2 the masking of smooth lobes falls faster than the cells (1.4% at cosine 0.013,
/// roughness 0.05).
#[test]
fn albedo_table_is_the_quadrature() {
    let table = ggx_albedo_table(256);
    if std::env::var_os("VKVCM_WRITE_GGX_TABLE").is_some() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/src/render/ggx_albedo.rs");
        std::fs::write(path, ggx_albedo_table_source(&table)).unwrap();
    }
    let (committed, averages) = committed_ggx_albedo_table();
    assert_eq!(committed.len(), table.len());
    for (k, (c, t)) in committed.iter().zip(&table).enumerate() {
        for i in 0..2 {
            assert!((c[i] - t[i]).abs() <= 1e-5 + 1e-7, "entry {k}.{i}: committed {}, quadrature {}", c[i], t[i]);
        }
    }
    for (j, (c, t)) in averages.iter().zip(&ggx_albedo_averages(&committed)).enumerate() {
        for i in 0..2 {
            assert!((c[i] - t[i]).abs() <= 1e-5 + 1e-7, "average {j}.{i}: committed {}, integral {}", c[i], t[i]);
        }
    }
    let coarse = ggx_albedo_table(128);
    let worst =
        coarse.iter().zip(&table).flat_map(|(a, b)| [(a[0] - b[0]).abs(), (a[1] - b[1]).abs()]).fold(0.0, f64::max);
    eprintln!("quadrature 128 vs 256 cells: {worst:.2e}");
    assert!(worst < 1e-4, "the quadrature has not converged: {worst}");
    // The smooth limit (width MIN_GGX_ALPHA, cosines above the masking's last 2%).
    for (i, &[a, b]) in committed.iter().enumerate().take(N_MU).skip(5) {
        let mu = table_cosine(i);
        let s = (1.0 - mu).powi(5);
        assert!((a - (1.0 - s)).abs() < 2e-3 && (b - s).abs() < 2e-3, "mu {mu}: (A, B) ({a}, {b}), Schlick {s}");
    }
    let [aa, ab] = averages[0];
    assert!((aa - 20.0 / 21.0).abs() < 3e-3 && (ab - 1.0 / 21.0).abs() < 3e-3, "smooth averages ({aa}, {ab})");
    // The interpolation between the table's rows and columns, at cell centres, for E at F0
    // 0.04 (glTF's dielectric) and 1: the largest error above cosine 0.2, and the
    // cosine-weighted mean error per roughness (what a diffuse lobe's integral sees).
    let (mut worst, mut worst_mean) = ((0.0f64, 0.0, 0.0), 0.0f64);
    for j in 0..N_R - 1 {
        let mut mean = [0.0f64; 2];
        for i in 0..N_MU - 1 {
            let x = (i as f64 + 0.5) / (N_MU - 1) as f64;
            let r = (j as f64 + 0.5) / (N_R - 1) as f64;
            let (mu, alpha) = (x * x, (r * r).max(MIN_GGX_ALPHA));
            let q = ggx_albedo_terms(mu, alpha, 256);
            let t = table_lookup(&committed, mu, alpha);
            for (k, f0) in [0.04, 1.0].into_iter().enumerate() {
                let err = f0 * (q[0] - t[0]) + q[1] - t[1];
                // 2 mu dmu = 4 x^3 dx.
                mean[k] += err * 4.0 * x.powi(3) / (N_MU - 1) as f64;
                if mu > 0.2 && err.abs() > worst.0 {
                    worst = (err.abs(), mu, r);
                }
            }
        }
        worst_mean = worst_mean.max(mean[0].abs()).max(mean[1].abs());
    }
    eprintln!(
        "interpolation: worst {:.2e} at mu {:.4}, roughness {:.3}; cosine-weighted mean {worst_mean:.2e}",
        worst.0, worst.1, worst.2
    );
    assert!(worst.0 < 2e-3 && worst_mean < 1e-3, "the table's interpolation is off by {worst:?}, {worst_mean}");
}

/// A closed box whose walls emit Le and reflect with a GGX lobe of F0 = 1 only. With
/// directional albedos E(mu) in [e_min, e_max] (CPU quadrature of the same formulas),
/// the radiance with at most K segments lies between Le sum_{k<K} e_min^k and
/// Le sum_{k<K} e_max^k <= Le K: the lobe never reflects more than it receives.
#[test]
fn ggx_furnace_conserves_energy() {
    let le = 0.5f64;
    let k_max = 5u32;
    with_gpu(|gpu| {
        for roughness in [0.2f32, 0.5, 0.9] {
            let a = (roughness as f64).powi(2);
            let albedos: Vec<f64> = (1..=16).map(|i| ggx_albedo(i as f64 / 16.0, a, 2000, 400)).collect();
            for (i, e) in albedos.iter().enumerate() {
                assert!(*e <= 1.0 + 1e-3, "roughness {roughness}: albedo {e} > 1 at mu = {}", (i + 1) as f64 / 16.0);
            }
            // Grazing directions (mu < 1/16) lose the most; the box's corners see them.
            let e_min = ggx_albedo(0.02, a, 2000, 400).min(albedos.iter().cloned().fold(1.0, f64::min));
            let e_max = albedos.iter().cloned().fold(0.0, f64::max);
            let series = |e: f64| le * (0..k_max).map(|k| e.powi(k as i32)).sum::<f64>();
            let (lo, hi) = (series(e_min), series(e_max));

            let mat = Material {
                name: "ggx_furnace".into(),
                glossy: Vec3::ONE,
                roughness,
                emission: Vec3::splat(le as f32),
                ..Default::default()
            };
            let tris = inward_box(1.0, 0);
            let lights = area_lights(&tris, std::slice::from_ref(&mat));
            let cam = camera(Vec3::new(0.1, -0.2, 0.05), Vec3::new(0.3, 1.0, 0.2), Vec3::Z, 70.0);
            let scene = scene("ggx_furnace", tris, vec![mat], lights, cam);
            let mut s = RenderSettings::new(Algorithm::Pt, 16, 16, Budget::Iterations(256));
            s.frame.max_path_length = k_max;
            s.frame.seed = 31;
            let st = render_stats(&render_checked(gpu, &scene, &s), None);
            let n = st.mean.len() as f64;
            let mean = st.mean.iter().map(|c| c[0]).sum::<f64>() / n;
            let se = (st.variance.iter().map(|v| v[0]).sum::<f64>() / (n * n * st.count as f64)).sqrt();
            assert!(
                mean <= hi + 4.0 * se + 1e-4 && mean >= lo - 4.0 * se - 1e-4,
                "roughness {roughness}: furnace mean {mean} +- {se} outside [{lo}, {hi}] (albedo {e_min}..{e_max}, \
                 Le K = {})",
                le * k_max as f64
            );
        }
    });
}

/// The glTF metallic/roughness material (`Material::metallic_roughness`, white base) on a
/// sphere under a uniform white environment, with paths of at most 2 segments: a pixel on
/// the sphere (convex, so no interreflection) sees the material's directional albedo at
/// its view direction, the environment's pixels see 1. For every roughness and metallic
/// value no pixel may exceed 1 (one-sided per-pixel test: mean <= 1 + z se with the
/// Šidák-corrected z, plus the table's error bound below where a diffuse lobe is), and a
/// white dielectric (metallic 0, glTF's F0) of any roughness
/// reflects exactly what it receives: its GGX lobe reflects E(cos_o) and the diffuse lobe
/// under the interface 1 - E(cos_o) (glsl/bsdf.glsl, diffuse_fresnel_weight), so every
/// pixel is 1 (two-sided per-pixel test, within z se plus the table's E's difference from
/// the lobe's albedo, `table_error_bound`, 3e-5 to 7e-4: since the diffuse lobe is sampled by
/// its weight, its samples all weigh the same and the pixels' standard errors are that
/// small; pixels that see the sphere at grazing angles, below cosine 0.2, are left out,
/// where the table is coarser). BPT must agree with PT per pixel (the layered lobe's
/// pdfs in both directions). Sabotage: with glTF's `fresnel_mix` weighting (1 - F(wo.h))
/// a roughness-0.3 dielectric pixel reflects 1.126 +- 0.026, without any weighting (a
/// plain sum of the lobes) a smooth one 1.102 +- 0.021: both fail the bound; with
/// Schlick's F(cos) in place of E (the coupling before) the roughness-1 one is too dark.
/// The two coloured-F0 cases (KHR_materials_specular, _ior) fail it when the diffuse
/// interface takes F0's smallest component instead of its largest (1.30 +- 0.06 in red).
#[test]
fn gltf_material_never_reflects_more_than_it_receives() {
    let (w, h) = (24u32, 24u32);
    with_gpu(|gpu| {
        let gltf_f0 = Vec3::splat(0.04);
        // The last two: a coloured dielectric F0 (KHR_materials_specular / _ior), whose
        // diffuse interface takes its largest component.
        let coloured = Vec3::new(0.16, 0.04, 0.0);
        for (metallic, roughness, f0) in [
            (0.0f32, 0.0f32, gltf_f0),
            (0.0, 0.3, gltf_f0),
            (0.0, 1.0, gltf_f0),
            (0.5, 0.5, gltf_f0),
            (1.0, 0.3, gltf_f0),
            (1.0, 1.0, gltf_f0),
            (0.0, 0.0, coloured),
            (0.0, 0.3, coloured),
        ] {
            let mut mat = Material::metallic_roughness_with_f0(Vec3::ONE, metallic, roughness, f0);
            mat.name = format!("white m {metallic} r {roughness} f0 {f0}");
            let cam = camera(Vec3::new(0.0, 0.0, 3.2), Vec3::new(0.0, 0.0, -1.0), Vec3::Y, 45.0);
            let mut sc = scene("gltf furnace", vec![], vec![mat], vec![Light::Background { radiance: Vec3::ONE }], cam);
            sc.spheres = vec![Sphere { center: Vec3::ZERO, radius: 1.0, material: 0 }];
            let render = |algo: Algorithm, iterations: u64| {
                let mut s = RenderSettings::new(algo, w, h, Budget::Iterations(iterations));
                s.frame.max_path_length = 2;
                s.frame.seed = 41 + algo as u32;
                render_checked(gpu, &sc, &s)
            };
            let run = |algo: Algorithm, iterations: u64| render_stats(&render(algo, iterations), None);
            let pt_out = render(Algorithm::Pt, 512);
            let pt = render_stats(&pt_out, None);
            let label = format!("metallic {metallic}, roughness {roughness}, F0 {f0}");
            let z = vkvcm_tools::stats::inverse_normal_cdf(1.0 - vkvcm_tools::stats::sidak(ALPHA, 3 * pt.mean.len()));
            // Where a diffuse lobe is, the table's E(cos_o) weighs it and the GGX lobe's
            // samples find its own albedo: a pixel may exceed 1 by their difference.
            let delta = if metallic < 1.0 { table_error_bound(f0.max_element() as f64, roughness as f64) } else { 0.0 };
            let mut worst = 0.0f64;
            for (m, v) in pt.mean.iter().zip(&pt.variance) {
                for c in 0..3 {
                    let se = (v[c] / pt.count as f64).sqrt();
                    worst = worst.max(m[c]);
                    assert!(
                        m[c] <= 1.0 + z * se + delta + 1e-6,
                        "{label}: a pixel reflects {} +- {se} > 1 (table's error bound {delta:.1e})",
                        m[c]
                    );
                }
            }
            eprintln!(
                "{label}: brightest pixel {worst:.4}, image mean {:.4}, table's error bound {delta:.1e}",
                image_mean(&pt)
            );
            if metallic == 0.0 && f0 == gltf_f0 {
                let mask = not_grazing_mask(&sc.camera, w, h, 0.2);
                let kept = mask.iter().filter(|&&m| m).count();
                assert!(kept > (w * h / 2) as usize, "mask keeps {kept} pixels");
                // And no less than 1 by more than that difference.
                for ((m, v), _) in pt.mean.iter().zip(&pt.variance).zip(&mask).filter(|(_, &keep)| keep) {
                    for c in 0..3 {
                        let se = (v[c] / pt.count as f64).sqrt();
                        assert!(
                            (m[c] - 1.0).abs() <= z * se + delta,
                            "{label}: a white dielectric must reflect everything: a pixel reflects {} +- {se} \
                             (table's error bound {delta:.1e})",
                            m[c]
                        );
                    }
                }
            }
            let t = welch_test(&run(Algorithm::Bpt, 256), &pt, ALPHA).unwrap();
            assert!(t.passed(), "{label}: BPT vs PT: {t}");
        }
    });
}

/// The largest difference between the albedo table's E (glsl/bsdf.glsl ggx_albedo, F0 `f0`)
/// and the GGX lobe's own at cosines 0.2-1 of roughness `roughness`: the quadrature with
/// 256 x 256 cells against the table, plus the quadrature's own error (256 against 128
/// cells), on 161 cosines (0.005 apart; the table's rows are 0.03-0.06 apart there).
fn table_error_bound(f0: f64, roughness: f64) -> f64 {
    let (table, _) = committed_ggx_albedo_table();
    let alpha = (roughness * roughness).max(MIN_GGX_ALPHA);
    let e = |t: [f64; 2]| f0 * t[0] + t[1];
    (0..=160)
        .map(|i| {
            let mu = 0.2 + 0.005 * i as f64;
            let fine = e(ggx_albedo_terms(mu, alpha, 256));
            (fine - e(table_lookup(&table, mu, alpha))).abs() + (fine - e(ggx_albedo_terms(mu, alpha, 128))).abs()
        })
        .fold(0.0, f64::max)
}

/// Pixels of a `w` x `h` frame of `cam` whose four corners either all miss the unit sphere
/// at the origin or all hit it at |cos(view ray, normal)| >= `min_cos`.
fn not_grazing_mask(cam: &vkvcm::scene::Camera, w: u32, h: u32, min_cos: f32) -> Vec<bool> {
    let plane = 0.5 * h as f32 / (0.5 * cam.yfov).tan();
    let right = cam.forward.cross(cam.up).normalize();
    let up = right.cross(cam.forward);
    // None: the ray misses; Some(cos) at the hit.
    let corner = |x: f32, y: f32| -> Option<f32> {
        let d = (cam.forward * plane + right * (x - 0.5 * w as f32) + up * (0.5 * h as f32 - y)).normalize();
        let b = cam.position.dot(d);
        let disc = b * b - (cam.position.length_squared() - 1.0);
        (disc >= 0.0).then(|| {
            let p = cam.position + d * (-b - disc.sqrt());
            -d.dot(p.normalize())
        })
    };
    (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f32, (i / w) as f32);
            let c = [corner(x, y), corner(x + 1.0, y), corner(x, y + 1.0), corner(x + 1.0, y + 1.0)];
            c.iter().all(|c| c.is_none()) || c.iter().all(|c| c.is_some_and(|v| v >= min_cos))
        })
        .collect()
}
