//! Environment maps (glsl/environment.glsl, src/render/environment.rs) in every
//! estimator. Lavapipe, validation on.
//!
//! * Furnace: a diffuse sphere of albedo a under a constant map of radiance L reflects
//!   exactly a L (it is convex: every bounce leaves to the sky); every estimator, per-pixel
//!   one-sample test against that value.
//! * Unbiased importance sampling: on a smooth, strongly non-uniform map, path tracing
//!   with next-event estimation (which samples the map) against BSDF sampling alone,
//!   bidirectional path tracing and VCM against path tracing (all pixels: every estimator
//!   here samples every path, as the sky can be hit), light tracing on the pixels whose
//!   primary hits are diffuse. Per-pixel Welch tests as in tests/render_bidir.rs.
//! * Sampling matters: under a map that is black but for one small bright patch, the
//!   importance-sampled estimator's error at equal iterations is far below BSDF
//!   sampling's (the ratio is printed; assert at least 4x, measured 13.8x).
//! * The same map as a constant background: a constant map renders the constant
//!   background's image (pt, bpt, vcm; per pixel and on the image mean), though next-event
//!   estimation samples the two differently (the map by its distribution, the constant
//!   background by |cos| about the normal: glsl/lights.glsl). Sabotage caught: the constant
//!   background's hit taking the direct pdf 1 / (4 pi) while next-event estimation samples
//!   by cosine. (That its specialised kernels equal the generic ones is checked with the
//!   other scenes in tests/render_features.rs.)
//! * The constant sky through specular surfaces: with a glass sphere, pt (whose sky
//!   samples pass glass and mirrors as paths of their own) against pt without next-event
//!   estimation and bpt, per pixel and on the image mean.
//!
//! Statistics: each render's iterations are independent samples; ALPHA = 1e-3 per
//! comparison after Šidák correction over pixels and channels (tools/src/stats.rs).

mod common;

use std::sync::Arc;

use common::scenes::{environment_scene, smooth_sky};
use common::{render_stats, with_gpu, TestRender, IMAGE_MEAN_BLOCKS};
use glam::Vec3;
use vkvcm::gpu::Gpu;
use vkvcm::image::Image;
use vkvcm::render::{self, Algorithm, Budget, RenderOutput, RenderSettings};
use vkvcm::scene::{Camera, EnvironmentLight, EnvironmentMap, Light, LoadReport, Material, Scene, Sphere};
use vkvcm_tools::stats::{image_mean_test, one_sample_test, sidak, welch_test, MeanEstimate, PixelStats};

const ALPHA: f64 = 1e-3;
const W: u32 = 24;
const H: u32 = 24;

fn render_with(gpu: &Arc<Gpu>, scene: &Scene, s: &RenderSettings) -> RenderOutput {
    let out = render::render(gpu, scene, s, None, &mut |_| {}).unwrap();
    assert_eq!(out.rejected_samples, 0, "{} {:?}: rejected samples", scene.name, s.algorithm);
    assert_eq!(out.overflow_splats, 0, "{} {:?}: overflowing splats", scene.name, s.algorithm);
    out
}

fn settings(algo: Algorithm, iterations: u64, seed: u32) -> RenderSettings {
    let mut s = RenderSettings::new(algo, W, H, Budget::Iterations(iterations));
    s.frame.seed = seed;
    s
}

fn stats(gpu: &Arc<Gpu>, scene: &Scene, algo: Algorithm, iterations: u64) -> PixelStats {
    render_stats(&render_with(gpu, scene, &settings(algo, iterations, 101 + algo as u32)), None)
}

fn environment(map: EnvironmentMap) -> Light {
    Light::Environment(EnvironmentLight { map: Arc::new(map), scale: Vec3::ONE, rotation_deg: 0.0 })
}

/// One diffuse sphere of radius 1, seen whole from 3 radii (45 degree field of view).
fn furnace_scene(albedo: f32, light: Light) -> Scene {
    Scene {
        name: "environment_furnace".into(),
        triangles: vec![],
        meshes: vec![],
        instances: vec![],
        spheres: vec![Sphere { center: Vec3::ZERO, radius: 1.0, material: 0 }],
        materials: vec![Material { name: "furnace".into(), diffuse: Vec3::splat(albedo), ..Default::default() }],
        lights: vec![light],
        camera: Camera::looking_at(Vec3::new(0.3, 0.5, 3.0), Vec3::ZERO, Vec3::Y, 45f32.to_radians()).unwrap(),
        report: LoadReport::default(),
        images: vec![],
    }
}

#[test]
fn furnace_every_estimator() {
    let (albedo, radiance) = (0.6f32, 0.8f32);
    let scene = furnace_scene(albedo, environment(EnvironmentMap::constant(16, 8, [radiance; 3])));
    // The pixels entirely on the sphere (the others mix sky and sphere by coverage).
    let on_sphere = hit_mask(&scene, |_| true);
    let expected = Image {
        width: W,
        height: H,
        data: on_sphere.iter().map(|&m| if m { [albedo * radiance; 3] } else { [0.0; 3] }).collect(),
    };
    assert!(on_sphere.iter().filter(|m| **m).count() > 150);
    with_gpu(|gpu| {
        for algo in vkvcm::render::settings::ALGORITHMS {
            if algo == Algorithm::El {
                continue;
            }
            // Light tracing reaches a pixel only through its splats, photon mapping through
            // the photons near it (correlated between neighbouring pixels: at 256
            // iterations ppm's sphere mean spread 0.474-0.484 over seeds): more iterations.
            let iterations = if matches!(algo, Algorithm::Lt | Algorithm::Ppm | Algorithm::Bpm) { 1024 } else { 256 };
            let mut s = settings(algo, iterations, 101 + algo as u32);
            // Merging: a radius of 0.1 scene radii (the default, 0.003, leaves most pixels
            // without a photon at these sample counts). On a sphere of radius R the surface
            // inside a ball of radius r <= 2R has area exactly pi r^2 (Archimedes), so the
            // density estimate of uniform irradiance has no bias from the radius.
            s.radius_factor = 0.1;
            let out = render_with(gpu, &scene, &s);
            let st = render_stats(&out, Some(&on_sphere));
            one_sample_test(&st, &expected, ALPHA).unwrap().assert_passed(&format!("env_furnace_{}", algo.name()));
            // Also the mean over the sphere's pixels, which a per-pixel test with a noisy
            // variance estimate could let through: within 2%.
            let n = on_sphere.iter().filter(|m| **m).count() as f64;
            let mean = st.mean.iter().map(|c| c[1]).sum::<f64>() / n;
            let want = (albedo * radiance) as f64;
            assert!((mean - want).abs() < 0.02 * want, "{}: furnace mean {mean}, expected {want}", algo.name());
        }
    });
}

#[test]
fn constant_map_renders_the_constant_background() {
    let c = Vec3::new(0.5, 0.7, 0.9);
    let mut as_map = environment_scene(EnvironmentMap::constant(8, 5, c.to_array()), 0.0);
    as_map.name = "constant_map".into();
    let mut as_background = as_map.clone();
    as_background.lights = vec![Light::Background { radiance: c }];
    let algos = [Algorithm::Pt, Algorithm::Bpt, Algorithm::Vcm];
    with_gpu(|gpu| {
        let run = |scene: &Scene, algo, seed| {
            let r = TestRender::new(algo, W, H, 512).seed(seed).independent();
            let (out, blocks) = r.blocks(gpu, scene, IMAGE_MEAN_BLOCKS);
            (render_stats(&out, None), MeanEstimate::of_blocks(&blocks).unwrap())
        };
        for (i, algo) in algos.into_iter().enumerate() {
            let (a, a_mean) = run(&as_map, algo, 101 + i as u32);
            let (b, b_mean) = run(&as_background, algo, 7 + i as u32);
            welch_test(&a, &b, ALPHA).unwrap().assert_passed(&format!("env_constant_{}", algo.name()));
            let m = image_mean_test(a_mean, b_mean);
            eprintln!("{}: constant map vs constant background: {m}", algo.name());
            assert!(m.p >= sidak(ALPHA, algos.len()), "{}: constant map vs constant background: {m}", algo.name());
        }
    });
}

/// pt's next-event sample of a constant sky passes specular surfaces as a path of its own
/// (glsl/pt.comp, SKY_THROUGH_SPECULAR), weighed 1 / (1 + pick) as the continuation that
/// finds the sky through them: the environment scene with its diffuse sphere made smooth
/// glass under the constant background, pt against pt without next-event estimation and
/// against bpt (whose sky samples are shadow rays), per pixel and on the image mean.
#[test]
fn constant_sky_through_specular_surfaces() {
    let c = Vec3::new(0.5, 0.7, 0.9);
    let mut scene = environment_scene(EnvironmentMap::constant(8, 5, c.to_array()), 0.0);
    scene.name = "sky_through_glass".into();
    scene.lights = vec![Light::Background { radiance: c }];
    scene.materials[1] = Material { name: "glass".into(), mirror: Vec3::ONE, ior: 1.5, ..Default::default() };
    with_gpu(|gpu| {
        let run = |r: TestRender| {
            let (out, blocks) = r.independent().max_path_length(8).blocks(gpu, &scene, IMAGE_MEAN_BLOCKS);
            (render_stats(&out, None), MeanEstimate::of_blocks(&blocks).unwrap())
        };
        let (pt, pt_mean) = run(TestRender::new(Algorithm::Pt, W, H, 2048).seed(31));
        let (bsdf_only, bsdf_only_mean) = run(TestRender::new(Algorithm::Pt, W, H, 2048).seed(32).nee(false));
        welch_test(&pt, &bsdf_only, ALPHA).unwrap().assert_passed("sky_through_glass_pt_vs_pt_without_nee");
        let (bpt, bpt_mean) = run(TestRender::new(Algorithm::Bpt, W, H, 1024).seed(33));
        welch_test(&pt, &bpt, ALPHA).unwrap().assert_passed("sky_through_glass_pt_vs_bpt");
        for (what, other_mean) in [("pt without NEE", bsdf_only_mean), ("bpt", bpt_mean)] {
            let m = image_mean_test(pt_mean, other_mean);
            eprintln!("sky through glass: pt vs {what}: {m}");
            assert!(m.p >= sidak(ALPHA, 2), "sky through glass: pt vs {what}: {m}");
        }
    });
}

fn hit_mask(scene: &Scene, keep: impl Fn(&Material) -> bool) -> Vec<bool> {
    common::primary_hit_mask(scene, W, H, keep)
}

#[test]
fn importance_sampling_is_unbiased() {
    let scene = environment_scene(smooth_sky(32, 17), 25.0);
    with_gpu(|gpu| {
        let pt = stats(gpu, &scene, Algorithm::Pt, 2048);
        let mut bsdf_only = settings(Algorithm::Pt, 4096, 5);
        bsdf_only.nee = false;
        let pt_bsdf = render_stats(&render_with(gpu, &scene, &bsdf_only), None);
        welch_test(&pt, &pt_bsdf, ALPHA).unwrap().assert_passed("env_pt_nee_vs_bsdf");
        for algo in [Algorithm::Bpt, Algorithm::Vcm] {
            let other = stats(gpu, &scene, algo, 1024);
            welch_test(&pt, &other, ALPHA).unwrap().assert_passed(&format!("env_pt_vs_{}", algo.name()));
        }
        let mask = hit_mask(&scene, |m| m.mirror == Vec3::ZERO);
        assert!(mask.iter().filter(|m| **m).count() > 100, "too few diffuse pixels to compare");
        let lt = render_stats(&render_with(gpu, &scene, &settings(Algorithm::Lt, 4096, 9)), Some(&mask));
        let bpt = render_stats(&render_with(gpu, &scene, &settings(Algorithm::Bpt, 1024, 11)), Some(&mask));
        welch_test(&lt, &bpt, ALPHA).unwrap().assert_passed("env_lt_vs_bpt");
    });
}

/// Relative MSE of `a` against `reference`, over pixels and channels.
fn rel_mse(a: &PixelStats, reference: &PixelStats) -> f64 {
    let mut sum = 0.0;
    for (x, r) in a.mean.iter().zip(&reference.mean) {
        for c in 0..3 {
            sum += (x[c] - r[c]).powi(2) / (r[c] * r[c] + 1e-2);
        }
    }
    sum / (3 * a.mean.len()) as f64
}

#[test]
fn importance_sampling_finds_a_small_bright_patch() {
    // 64 x 33 texels, black but for 2 x 2 texels (about 6 x 11 degrees) of radiance 200,
    // 50 degrees above the horizon.
    let (w, h) = (64u32, 33u32);
    let mut texels = vec![[0.0f32; 3]; (w * h) as usize];
    for (i, j) in [(20, 8), (21, 8), (20, 9), (21, 9)] {
        texels[(j * w + i) as usize] = [200.0, 180.0, 150.0];
    }
    let map = EnvironmentMap::new("patch", w, h, texels).unwrap();
    let scene = environment_scene(map, 0.0);
    with_gpu(|gpu| {
        let reference = render_stats(&render_with(gpu, &scene, &settings(Algorithm::Pt, 4096, 1)), None);
        let sampled = render_stats(&render_with(gpu, &scene, &settings(Algorithm::Pt, 64, 2)), None);
        let mut s = settings(Algorithm::Pt, 64, 2);
        s.nee = false;
        let bsdf = render_stats(&render_with(gpu, &scene, &s), None);
        let (e_is, e_bsdf) = (rel_mse(&sampled, &reference), rel_mse(&bsdf, &reference));
        eprintln!(
            "64 iterations, relMSE against a 4096-iteration reference: map sampling {e_is:.3e}, BSDF sampling \
             {e_bsdf:.3e}, ratio {:.1}",
            e_bsdf / e_is
        );
        assert!(e_bsdf > 4.0 * e_is, "map sampling relMSE {e_is:.3e} is not far below BSDF sampling's {e_bsdf:.3e}");
    });
}

/// The GPU's env_sample and env_eval (glsl/tests/env_sample.comp) on the textured sky,
/// turned by 70 degrees:
/// * the sampled directions, binned at 4 x 4 bins per sampling cell in the map's (u, v),
///   follow the pdf (each bin's count within 5 standard deviations of its expectation:
///   the draws are stratified, so the binomial deviation is an upper bound);
/// * a direction's sampled pdf equals env_eval's along it;
/// * the solid-angle pdf integrates to 1 and the estimate of the map's power through
///   sampling equals the one through uniform directions (each within 4 standard errors).
#[test]
fn gpu_sampling_follows_the_pdf() {
    use vkvcm::gpu::{groups_2d, Bind};
    use vkvcm::render::environment::EnvironmentTables;
    use vkvcm::render::gpu_types::GpuPush;
    use vkvcm::render::reads::Reads;
    use vkvcm::render::{FrameSettings, SceneGpu};
    let (w, h) = (16u32, 9u32);
    let map = smooth_sky(w, h);
    let tables = EnvironmentTables::new(&map);
    let rotation = 70f32;
    let scene = environment_scene(map, rotation);
    let n = 512u32;
    let count = n * n;
    let out: Vec<[f32; 4]> = with_gpu(|gpu| {
        let frame = FrameSettings {
            width: 4,
            height: 4,
            seed: 3,
            max_path_length: 4,
            min_path_length: 0,
            light_selection: vkvcm::render::DEFAULT_LIGHT_SELECTION,
        };
        let sg = SceneGpu::new(gpu, &scene, &frame, Reads::resolve(gpu, None).unwrap()).unwrap();
        let results = gpu.buffer_zeroed::<[f32; 4]>("env_results", 4 * count as usize).unwrap();
        let mut binds = sg.binds();
        binds.push(Bind::own(&results));
        let kernel = gpu.kernel("tests/env_sample.comp", &sg.variant.defines().pairs(), &binds).unwrap();
        let push = GpuPush { count, light_paths: n, ..Default::default() };
        let mut batch = gpu.batch().unwrap();
        batch.dispatch(&kernel, groups_2d(count, 64), bytemuck::bytes_of(&push)).unwrap();
        batch.submit_wait(None).unwrap();
        results.read::<[f32; 4]>().unwrap()
    });
    let (sin, cos) = rotation.to_radians().sin_cos();
    let to_uv = |d: [f32; 3]| {
        // World -> map frame (the inverse rotation about +Y), then Mitsuba's lat-long.
        let (x, y, z) = (cos * d[0] - sin * d[2], d[1], sin * d[0] + cos * d[2]);
        let u = (x.atan2(-z) / (2.0 * std::f32::consts::PI)).rem_euclid(1.0);
        (u, y.clamp(-1.0, 1.0).acos() / std::f32::consts::PI)
    };
    let sub = 4u32;
    let (bins_u, bins_v) = (w * sub, (h - 1) * sub);
    let mut hist = vec![0u32; (bins_u * bins_v) as usize];
    let (mut power_sampled, mut power_sampled_sq) = (0.0f64, 0.0f64);
    let (mut pdf_sum, mut pdf_sum_sq, mut power_uniform, mut power_uniform_sq) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for k in 0..count as usize {
        let [dx, dy, dz, pdf] = out[4 * k];
        let [lr, lg, lb, pdf_eval] = out[4 * k + 1];
        assert!(pdf > 0.0, "draw {k}: no direction (pdf {pdf})");
        assert_eq!(pdf, pdf_eval, "draw {k}: sampled pdf differs from env_eval's");
        let (u, v) = to_uv([dx, dy, dz]);
        // Bins are aligned with the cells: cell i starts at u = (i + 1/2) / W.
        let gx = (u * w as f32 - 0.5).rem_euclid(w as f32);
        let bu = ((gx * sub as f32) as u32).min(bins_u - 1);
        let bv = ((v * (h - 1) as f32 * sub as f32) as u32).min(bins_v - 1);
        hist[(bv * bins_u + bu) as usize] += 1;
        // The map's power (luminance integrated over directions) two ways.
        let lum = |r: f32, g: f32, b: f32| 0.2126 * r as f64 + 0.7152 * g as f64 + 0.0722 * b as f64;
        let x = lum(lr, lg, lb) / pdf as f64;
        power_sampled += x;
        power_sampled_sq += x * x;
        let [_, _, _, uniform_pdf] = out[4 * k + 2];
        let [ur, ug, ub, _] = out[4 * k + 3];
        let four_pi = 4.0 * std::f64::consts::PI;
        let x = uniform_pdf as f64 * four_pi;
        pdf_sum += x;
        pdf_sum_sq += x * x;
        let x = lum(ur, ug, ub) * four_pi;
        power_uniform += x;
        power_uniform_sq += x * x;
    }
    let total = count as f64;
    let cell_area = 1.0 / (w as f64 * (h - 1) as f64);
    for bv in 0..bins_v {
        for bu in 0..bins_u {
            let p = tables.pdf_uv(w, bu / sub, bv / sub) as f64 * cell_area / (sub * sub) as f64;
            let expected = p * total;
            let got = hist[(bv * bins_u + bu) as usize] as f64;
            let sd = (expected * (1.0 - p)).sqrt().max(1.0);
            assert!(
                (got - expected).abs() <= 5.0 * sd,
                "bin ({bu}, {bv}) of cell ({}, {}): {got} draws, expected {expected:.1}",
                bu / sub,
                bv / sub
            );
        }
    }
    let mean_sd = |s: f64, s2: f64| (s / total, ((s2 / total - (s / total).powi(2)) / total).sqrt());
    let (pdf_mean, pdf_se) = mean_sd(pdf_sum, pdf_sum_sq);
    assert!((pdf_mean - 1.0).abs() < 4.0 * pdf_se, "pdf integrates to {pdf_mean} +- {pdf_se}");
    let (pu, pu_se) = mean_sd(power_uniform, power_uniform_sq);
    let (ps, ps_se) = mean_sd(power_sampled, power_sampled_sq);
    assert!(
        (pu - ps).abs() < 4.0 * (pu_se * pu_se + ps_se * ps_se).sqrt(),
        "power through uniform directions {pu} +- {pu_se}, through sampling {ps} +- {ps_se}"
    );
}

/// Against Mitsuba 3 (scripts/env_reference.py: the same scene written as
/// tests/env/env_scene.gltf for vkvcm and rendered by Mitsuba's `path` integrator as
/// tests/env/mitsuba_{mean,var}.exr, 16 independent renders of 256 spp): the glTF with its
/// VKVCM_environment (tests/env/sky.hdr turned 30 degrees) renders the same image, per
/// pixel (Welch test with the reference's 16 renders as its samples), in pt and vcm.
#[test]
fn environment_map_matches_mitsuba() {
    matches_mitsuba("env_scene.gltf", "mitsuba");
}

/// The same scene with the diffuse sphere as a coarse smooth-shaded mesh (6 x 10 quads
/// with the sphere's normals at the vertices: `env_reference.py --smooth`, tests/env/
/// smooth_scene.gltf and mitsuba_smooth_{mean,var}.exr): vkvcm's shading normals
/// (docs/numerics.md) against Mitsuba's, per pixel, in pt and in vcm (whose light
/// subpaths use the adjoint correction).
#[test]
fn smooth_shaded_mesh_matches_mitsuba() {
    matches_mitsuba("smooth_scene.gltf", "mitsuba_smooth");
}

/// The same scene with the mirror sphere made of smooth glass of IOR 1.5
/// (`env_reference.py --glass`, tests/env/glass_scene.gltf and
/// mitsuba_glass_{mean,var}.exr, Mitsuba's `dielectric`): vkvcm's dielectric (exact
/// Fresnel, refraction both ways, and in vcm light subpaths through the glass and
/// merging of the caustic it throws on the ground) against Mitsuba's, per pixel. vcm
/// takes 1024 iterations here, not 256: the pixels that see the sun spot of sky.hdr
/// through the glass are rare events for every estimator (a camera ray refracts
/// deterministically; only its position in the pixel decides whether it reaches the 3°
/// sun), and at 256 iterations vcm's own variance estimate there was too small: one such
/// pixel at z = -6.8 (0.148 +- 0.0006 against Mitsuba's 0.161), where 1024 iterations
/// give 0.166 with either merge radius (0.003 and 0.0005 of the scene), so no merging
/// bias.
///
/// Sabotage (done by hand, not kept): the glTF's IOR 1.5 changed to 1.4 fails it.
#[test]
fn glass_sphere_matches_mitsuba() {
    matches_mitsuba_with("glass_scene.gltf", "mitsuba_glass", &[(Algorithm::Pt, 2048), (Algorithm::Vcm, 1024)]);
}

/// The same sphere made of rough glass (`env_reference.py --rough-glass`,
/// tests/env/rough_glass_scene.gltf and mitsuba_rough_glass_{mean,var}.exr): a glTF
/// material with KHR_materials_transmission, KHR_materials_ior 1.5 and roughnessFactor
/// 0.3, which the importer maps to vkvcm's rough dielectric of GGX alpha 0.09
/// (glsl/bsdf.glsl), against Mitsuba's `roughdielectric` (ggx, alpha 0.09), the same
/// BSDF (Walter et al. 2007), per pixel: in pt (NEE into the glass, MIS with its pdfs),
/// bpt (connections through it both ways, its reverse pdfs) and vcm (merging on it too).
#[test]
fn rough_glass_sphere_matches_mitsuba() {
    matches_mitsuba_with(
        "rough_glass_scene.gltf",
        "mitsuba_rough_glass",
        &[(Algorithm::Pt, 2048), (Algorithm::Bpt, 512), (Algorithm::Vcm, 512)],
    );
}

/// The glass sphere tinted and absorbing (`env_reference.py --volume` / `--rough-volume`,
/// tests/env/{volume,rough_volume}_scene.gltf, mitsuba_{volume,rough_volume}_{mean,var}.exr):
/// glTF materials with KHR_materials_transmission, a tinting baseColorFactor and
/// KHR_materials_volume, smooth and of roughness 0.3, which vkvcm renders with tinted
/// transmission and Beer-Lambert absorption inside the sphere (glsl/medium.glsl), against
/// Mitsuba's `dielectric` / `roughdielectric` with that specular_transmittance around a
/// `homogeneous` medium of albedo 0 (integrator `volpath`), per pixel: camera subpaths
/// through the medium, light subpaths through it, connections and merges on the rough
/// sphere (pt, bpt, vcm); the smooth sphere with vcm.
#[test]
fn absorbing_glass_spheres_match_mitsuba() {
    matches_mitsuba_with(
        "rough_volume_scene.gltf",
        "mitsuba_rough_volume",
        &[(Algorithm::Pt, 512), (Algorithm::Bpt, 256), (Algorithm::Vcm, 256)],
    );
    // The smooth sphere's caustics on the ground are rare large pt samples at any
    // affordable count (pt's camera paths through smooth glass are checked analytically:
    // tests/render_volume.rs); vcm merges them.
    matches_mitsuba_with("volume_scene.gltf", "mitsuba_volume", &[(Algorithm::Vcm, 256)]);
}

/// Renders tests/env/`gltf` and compares it with the reference `reference_stem`_{mean,var}.exr.
fn matches_mitsuba(gltf: &str, reference_stem: &str) {
    matches_mitsuba_with(gltf, reference_stem, &[(Algorithm::Pt, 2048), (Algorithm::Vcm, 256)]);
}

/// [`matches_mitsuba`] with these estimators and iterations.
fn matches_mitsuba_with(gltf: &str, reference_stem: &str, estimators: &[(Algorithm, u64)]) {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/env");
    let scene = vkvcm::scene::load_with(&dir.join(gltf), &Default::default()).unwrap();
    with_gpu(|gpu| common::assert_matches_mitsuba(gpu, &scene, reference_stem, 8, estimators));
}

/// Luminance of the irradiance on a surface facing +Y, by the midpoint rule on a grid 4
/// times finer than the texels in (u, v) (independent of the generator's own quadrature,
/// which takes each texel once at its centre), the map's nearest texel at each point.
fn irradiance_from_above(m: &EnvironmentMap) -> f64 {
    const SUB: u32 = 4;
    let (nu, nv) = (m.width * SUB, (m.height - 1) * SUB);
    let (du, dv) = (std::f64::consts::TAU / nu as f64, std::f64::consts::PI / nv as f64);
    let mut sum = 0.0;
    for b in 0..nv / 2 {
        let theta = (b as f64 + 0.5) * dv;
        let j = ((b as f64 + 0.5) / SUB as f64).round() as u32;
        for a in 0..nu {
            let t = m.texel(a / SUB, j);
            let lum = (0.2126 * t[0] + 0.7152 * t[1] + 0.0722 * t[2]) as f64;
            sum += lum * theta.cos() * theta.sin() * du * dv;
        }
    }
    sum
}

/// The built-in studio and sky (src/scene/default_environments.rs): deterministic, finite,
/// not negative, normalised so that a white surface facing up has radiance 1 (irradiance
/// pi, within 2% by an independent integration), the sky's brightest texel within a
/// degree of the sun asked for, and parameters outside Preetham's fits refused.
#[test]
fn built_in_environments_are_deterministic_and_normalised() {
    use vkvcm::scene::default_environments::{sky, studio, SkyParameters};
    let p = SkyParameters { sun_azimuth_deg: -60.0, sun_elevation_deg: 30.0, turbidity: 4.0 };
    for (name, make) in [
        ("studio", Box::new(|| studio(256, 128).unwrap()) as Box<dyn Fn() -> EnvironmentMap>),
        ("sky", Box::new(move || sky(512, 256, &p).unwrap())),
    ] {
        let (a, b) = (make(), make());
        assert!(a == b, "{name}: two maps differ");
        assert!(a.texels.iter().flatten().all(|c| c.is_finite() && *c >= 0.0), "{name}");
        let e = irradiance_from_above(&a);
        assert!((e / std::f64::consts::PI - 1.0).abs() < 0.02, "{name}: irradiance from above {e}, not pi");
    }
    let m = sky(512, 256, &p).unwrap();
    let brightest = (0..m.texels.len()).max_by(|&x, &y| m.texels[x][1].total_cmp(&m.texels[y][1])).unwrap() as u32;
    let (u, v) = ((brightest % m.width) as f32 + 0.5, (brightest / m.width) as f32);
    let (theta, phi) = (v / (m.height - 1) as f32 * std::f32::consts::PI, u / m.width as f32 * std::f32::consts::TAU);
    let d = Vec3::new(theta.sin() * phi.sin(), theta.cos(), -theta.sin() * phi.cos());
    let (az, el) = ((-60f32).to_radians(), 30f32.to_radians());
    let sun = Vec3::new(el.cos() * az.sin(), el.sin(), el.cos() * az.cos());
    assert!(d.dot(sun).acos().to_degrees() < 1.0, "brightest texel along {d}, sun along {sun}");
    for bad in [
        SkyParameters { turbidity: 1.0, ..p },
        SkyParameters { sun_elevation_deg: 0.0, ..p },
        SkyParameters { sun_elevation_deg: 91.0, ..p },
    ] {
        assert!(sky(64, 32, &bad).is_err(), "{bad:?}");
    }
}

/// The studio and the sky are sampled as their radiance says: path tracing with
/// next-event estimation (which draws directions from the map's distribution) against
/// BSDF sampling alone, per pixel (Welch), on the environment test scene. Small maps (the
/// sky's sun then spans a few degrees), so that BSDF sampling finds it often enough to
/// have a usable variance.
#[test]
fn built_in_environments_are_importance_sampled_without_bias() {
    use vkvcm::scene::default_environments::{sky, studio, SkyParameters};
    let maps = [("studio", studio(64, 32).unwrap()), ("sky", sky(32, 16, &SkyParameters::default()).unwrap())];
    with_gpu(|gpu| {
        for (name, map) in maps {
            let scene = environment_scene(map, 10.0);
            let pt = stats(gpu, &scene, Algorithm::Pt, 1024);
            let mut bsdf_only = settings(Algorithm::Pt, 4096, 5);
            bsdf_only.nee = false;
            let pt_bsdf = render_stats(&render_with(gpu, &scene, &bsdf_only), None);
            welch_test(&pt, &pt_bsdf, ALPHA).unwrap().assert_passed(&format!("env_{name}_nee_vs_bsdf"));
        }
    });
}
