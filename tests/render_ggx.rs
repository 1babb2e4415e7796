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

use std::sync::Arc;

use common::scenes::*;
use common::{render_stats, with_gpu};
use glam::Vec3;
use vkvcm::gpu::Gpu;
use vkvcm::image::stats::{welch_test, PixelStats};
use vkvcm::render::{self, Algorithm, Budget, RenderSettings};
use vkvcm::scene::{Material, Scene};

const ALPHA: f64 = 1e-3;
const W: u32 = 24;
const H: u32 = 24;

fn render_one(gpu: &Arc<Gpu>, scene: &Scene, s: &RenderSettings) -> render::RenderOutput {
    let out = render::render(gpu, scene, s, None, &mut |_| {}).unwrap();
    assert_eq!(out.rejected_samples, 0, "{} {:?}: rejected samples", scene.name, s.algorithm);
    assert_eq!(out.overflow_splats, 0, "{} {:?}: overflowing splats", scene.name, s.algorithm);
    out
}

fn stats(gpu: &Arc<Gpu>, scene: &Scene, algo: Algorithm, nee: bool, iterations: u64, seed: u32) -> PixelStats {
    let mut s = RenderSettings::new(algo, W, H, Budget::Iterations(iterations));
    s.frame.seed = seed;
    s.frame.max_path_length = 4;
    s.nee = nee;
    render_stats(&render_one(gpu, scene, &s), None)
}

/// Left half: pure GGX metal, roughness 0.3 (alpha 0.09), coloured F0. Right half:
/// roughness 0.7 (alpha 0.49) GGX with F0 0.04 over a diffuse base (the importer's
/// dielectric mapping), so component selection is exercised too.
fn ggx_floor() -> Scene {
    let metal =
        Material { name: "ggx_metal".into(), glossy: Vec3::new(0.9, 0.7, 0.5), roughness: 0.3, ..Default::default() };
    let plastic = Material {
        name: "ggx_plastic".into(),
        diffuse: Vec3::new(0.2, 0.5, 0.3),
        glossy: Vec3::splat(0.04),
        roughness: 0.7,
        ..Default::default()
    };
    glossy_floor_scene(metal, plastic)
}

fn image_mean(s: &PixelStats) -> f64 {
    s.mean.iter().map(|c| c[0] + c[1] + c[2]).sum::<f64>() / (3 * s.mean.len()) as f64
}

/// NEE + MIS uses bsdf_eval's f and pdf_fwd for light samples and bsdf_sample's
/// weight for BSDF hits; BSDF sampling only uses bsdf_sample alone. They agree only if
/// the sampled density is the pdf that bsdf_eval reports (a missing Jacobian fails).
#[test]
fn ggx_nee_and_bsdf_sampling_agree() {
    let scene = ggx_floor();
    with_gpu(|gpu| {
        let a = stats(gpu, &scene, Algorithm::Pt, true, 1024, 11);
        let b = stats(gpu, &scene, Algorithm::Pt, false, 4096, 12);
        assert!(image_mean(&a) > 0.05, "the scene rendered (almost) black");
        let t = welch_test(&a, &b, ALPHA).unwrap();
        assert!(t.passed(), "GGX floor: PT NEE vs PT BSDF sampling only: {t}");
    });
}

/// BPT's connections to light vertices and its MIS weights use pdf_rev of the GGX lobe
/// on both subpaths; it must agree with PT (which samples every path here: the light
/// can be hit).
#[test]
fn ggx_bpt_matches_pt() {
    let scene = ggx_floor();
    with_gpu(|gpu| {
        let pt = stats(gpu, &scene, Algorithm::Pt, true, 16384, 21);
        let bpt = stats(gpu, &scene, Algorithm::Bpt, true, 8192, 22);
        let t = welch_test(&pt, &bpt, ALPHA).unwrap();
        assert!(t.passed(), "GGX floor: PT vs BPT: {t}");
    });
}

// ---- CPU model of the GGX lobe (the formulas of glsl/bsdf.glsl) for the energy test.

fn ggx_d(ch: f64, a: f64) -> f64 {
    let a2 = a * a;
    let t = ch * ch * (a2 - 1.0) + 1.0;
    a2 / (std::f64::consts::PI * t * t)
}

fn ggx_lambda(c: f64, a: f64) -> f64 {
    let tan2 = (1.0 - c * c).max(0.0) / (c * c);
    0.5 * ((1.0 + a * a * tan2).sqrt() - 1.0)
}

/// Directional albedo of the F0 = 1 GGX lobe at cos(theta_o) = `mu`: the integral of
/// f cos(theta_i) over the hemisphere, by a midpoint rule over the half-vector
/// (importance-free, so it checks the normalisation of D independently of sampling):
/// f cos_i dw_i = D G2 / (4 cos_o) * 4 (wo.h) ... / (4 wo.h) dw_h, i.e.
/// integrand in h: D(h) G2 / (4 cos_o) * 4 (wo.h) with dw_i = 4 (wo.h) dw_h.
fn ggx_albedo(mu: f64, a: f64) -> f64 {
    let wo = [(1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu];
    let (nt, np) = (2000, 400);
    let mut sum = 0.0;
    for i in 0..nt {
        // theta_h in [0, pi/2); substitute theta_h = atan(a tan(s)) to resolve narrow lobes.
        let s = (i as f64 + 0.5) / nt as f64 * std::f64::consts::FRAC_PI_2;
        let th = (a * s.tan()).atan();
        let dth_ds = a / (s.cos().powi(2) + a * a * s.sin().powi(2));
        let (st, ct) = (th.sin(), th.cos());
        for j in 0..np {
            let phi = (j as f64 + 0.5) / np as f64 * 2.0 * std::f64::consts::PI;
            let h = [st * phi.cos(), st * phi.sin(), ct];
            let oh = wo[0] * h[0] + wo[2] * h[2];
            if oh <= 0.0 {
                continue;
            }
            let ci = 2.0 * oh * h[2] - wo[2];
            if ci <= 0.0 {
                continue;
            }
            let g2 = 1.0 / (1.0 + ggx_lambda(mu, a) + ggx_lambda(ci, a));
            let f_cos_jac = ggx_d(ct, a) * g2 / (4.0 * mu * ci) * ci * 4.0 * oh;
            let dw = st * dth_ds * (std::f64::consts::FRAC_PI_2 / nt as f64) * (2.0 * std::f64::consts::PI / np as f64);
            sum += f_cos_jac * dw;
        }
    }
    sum
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
            let albedos: Vec<f64> = (1..=16).map(|i| ggx_albedo(i as f64 / 16.0, a)).collect();
            for (i, e) in albedos.iter().enumerate() {
                assert!(*e <= 1.0 + 1e-3, "roughness {roughness}: albedo {e} > 1 at mu = {}", (i + 1) as f64 / 16.0);
            }
            // Grazing directions (mu < 1/16) lose the most; the box's corners see them.
            let e_min = ggx_albedo(0.02, a).min(albedos.iter().cloned().fold(1.0, f64::min));
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
            let st = render_stats(&render_one(gpu, &scene, &s), None);
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
