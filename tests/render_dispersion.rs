//! KHR_materials_dispersion (glsl/lobes/dispersion.glsl): glass whose IOR depends on the
//! colour channel, rendered by subpaths that each choose one channel at their first
//! dispersive vertex. Checked per channel against the same scene without dispersion at
//! that channel's IOR (the independent reference: plain glass, which the rest of the suite
//! checks against Mitsuba), for PT, VCM and BPT; the estimators against each other on rough
//! dispersive glass (connections and merges at dispersive vertices of other channels); a
//! white furnace per channel; and the feature switch. Lavapipe, validation on.
//!
//! Statistics: per-pixel Welch tests at ALPHA, Šidák-corrected over the image (tests/common).

mod common;

use common::scenes::*;
use common::{image_mean, render_stats, with_gpu, TestRender};
use glam::Vec3;
use vkvcm::render::Algorithm;
use vkvcm::scene::{Light, Material, Scene, Sphere, Triangle};
use vkvcm_tools::stats::{welch_test, PixelStats};

const ALPHA: f64 = 1e-3;

/// Glass of IOR `ior` (green's), KHR_materials_dispersion `dispersion` and glTF roughness
/// `roughness`, as the importer makes it.
fn glass(ior: f32, dispersion: f32, roughness: f32) -> Material {
    Material {
        name: format!("glass {ior} d {dispersion} r {roughness}"),
        mirror: Vec3::ONE,
        ior,
        dielectric_roughness: roughness,
        dispersion,
        ..Default::default()
    }
}

/// A glass sphere (radius 0.5, a sphere primitive) of material `glass` just above a floor
/// of light and dark stripes 0.25 wide, before a striped back wall, under a square area
/// light: the camera sees the stripes refracted through the sphere, and the sphere's
/// caustic on the floor (light subpaths through the glass: light vertices that carry a
/// channel). Open: paths that leave it end.
fn striped_scene(glass: Material) -> Scene {
    let lamp = Material { name: "lamp".into(), emission: Vec3::splat(6.0), ..Default::default() };
    let light = Material { name: "light stripe".into(), diffuse: Vec3::new(0.85, 0.8, 0.75), ..Default::default() };
    let dark = Material { name: "dark stripe".into(), diffuse: Vec3::new(0.1, 0.12, 0.15), ..Default::default() };
    let quad = |a: Vec3, b: Vec3, c: Vec3, d: Vec3, material: u32| {
        [
            Triangle { p: [a, b, c], n: None, material, attributes: None },
            Triangle { p: [a, c, d], n: None, material, attributes: None },
        ]
    };
    let v = Vec3::new;
    let mut tris = Vec::new();
    for i in 0..16 {
        let (x0, x1) = (-2.0 + 0.25 * i as f32, -1.75 + 0.25 * i as f32);
        let m = 1 + (i % 2) as u32;
        tris.extend(quad(v(x0, -2.0, 0.0), v(x1, -2.0, 0.0), v(x1, 1.2, 0.0), v(x0, 1.2, 0.0), m));
        tris.extend(quad(v(x0, 1.2, 0.0), v(x1, 1.2, 0.0), v(x1, 1.2, 2.5), v(x0, 1.2, 2.5), 3 - m));
    }
    // The lamp: normal -z (counter-clockwise seen from below).
    tris.extend(quad(v(-0.8, -0.6, 2.4), v(-0.8, 1.0, 2.4), v(0.8, 1.0, 2.4), v(0.8, -0.6, 2.4), 0));
    let materials = vec![lamp, light, dark, glass];
    let lights = area_lights(&tris, &materials);
    let cam = camera(v(0.0, -2.2, 1.3), v(0.0, 2.4, -0.85), Vec3::Z, 38.0);
    let mut s = scene("dispersion stripes", tris, materials, lights, cam);
    s.spheres.push(Sphere { center: v(0.0, 0.2, 0.55), radius: 0.5, material: 3 });
    s
}

/// Channel `k` of `stats[k]` for each k: the reference image made of the three renders
/// without dispersion.
fn per_channel(stats: [&PixelStats; 3]) -> PixelStats {
    let mut out = stats[0].clone();
    for i in 0..out.mean.len() {
        for (k, st) in stats.iter().enumerate() {
            out.mean[i][k] = st.mean[i][k];
            out.variance[i][k] = st.variance[i][k];
        }
    }
    out
}

/// The dispersive glass against plain glass per channel: `algo` renders the striped scene
/// with a sphere of glass `dispersive` (with `bulb` a small lamp inside it), and the same scene three times without dispersion
/// at IOR n_R, n_G, n_B (the same roughness); channel k of the first must match channel k
/// of render k per pixel. The references must tell n_R from n_B (the dispersive render's
/// R against B's reference fails), so that swapping the IORs, or flipping the spread,
/// would fail.
fn assert_channels_match_plain_glass(
    gpu: &std::sync::Arc<vkvcm::gpu::Gpu>,
    algo: Algorithm,
    iterations: u64,
    dispersive: Material,
    bulb: bool,
) {
    let (w, h) = (16, 16);
    let run = |m: Material, seed| {
        let mut s = striped_scene(m);
        if bulb {
            add_filament(&mut s, Vec3::new(0.25, 0.2, 0.55), 20.0);
        }
        TestRender::new(algo, w, h, iterations).seed(seed).max_path_length(8).independent().stats(gpu, &s)
    };
    let (iors, roughness) = (dispersive.dispersion_iors(), dispersive.dielectric_roughness);
    let disp = run(dispersive, 91);
    let refs: Vec<PixelStats> = (0..3).map(|k| run(glass(iors[k], 0.0, roughness), 92 + k as u32)).collect();
    assert!(image_mean(&disp) > 0.02, "{algo:?}: the scene rendered (almost) black");
    let t = welch_test(&disp, &per_channel([&refs[0], &refs[1], &refs[2]]), ALPHA).unwrap();
    eprintln!("{algo:?}: dispersive vs plain glass per channel: {t}");
    assert!(t.passed(), "{algo:?}: dispersive vs plain glass per channel: {t}");
    let swapped = welch_test(&disp, &per_channel([&refs[2], &refs[1], &refs[0]]), ALPHA).unwrap();
    eprintln!("{algo:?}: with R's and B's IORs swapped: {swapped}");
    assert!(!swapped.passed(), "{algo:?}: the scene does not tell n_R from n_B: {swapped}");
}

/// PT and VCM (connections and merges: the caustic's light vertices carry their channel)
/// per channel against plain glass: a smooth sphere of IOR 1.5 and dispersion 8 (IORs 1.4,
/// 1.5, 1.6). BPT on a rough (0.3) sphere of dispersion 24 (IORs 1.2, 1.5, 1.8) with a
/// small lamp inside (a frosted bulb): the floor around it is lit mostly by connections to
/// light vertices on the glass itself, evaluated with their subpath's channel.
#[test]
fn dispersion_matches_plain_glass_per_channel() {
    with_gpu(|gpu| {
        let smooth = glass(1.5, 8.0, 0.0);
        let iors = smooth.dispersion_iors();
        assert!((iors - Vec3::new(1.4, 1.5, 1.6)).abs().max_element() < 1e-6, "{iors}");
        assert_channels_match_plain_glass(gpu, Algorithm::Pt, 512, smooth.clone(), false);
        assert_channels_match_plain_glass(gpu, Algorithm::Vcm, 256, smooth, false);
        assert_channels_match_plain_glass(gpu, Algorithm::Bpt, 256, glass(1.5, 24.0, 0.3), true);
    });
}

/// The estimators agree per pixel on a rough (0.3) dispersive glass sphere in the striped
/// scene: PT with NEE against PT without it, BPT, VCM and light tracing. NEE, connections
/// and merges happen at dispersive vertices, with camera and light vertices of different
/// channels. Light tracing sees the sphere's own pixels through a rough lens (a narrow
/// transmission lobe towards the camera): its estimate there is too heavy-tailed for 512
/// iterations (so it is with dispersion 0: tried), so it is compared off them, where it
/// still meets the dispersed caustic on the floor (light vertices after the glass, their
/// throughput carrying their channel).
#[test]
fn dispersion_estimators_agree() {
    with_gpu(|gpu| {
        let (w, h) = (16, 16);
        let s = striped_scene(glass(1.5, 8.0, 0.3));
        let not_glass = common::primary_hit_mask(&s, w, h, |m| !m.is_dielectric());
        let run = |algo, iterations, seed| {
            TestRender::new(algo, w, h, iterations).seed(seed).max_path_length(6).independent().output(gpu, &s)
        };
        let pt_out = run(Algorithm::Pt, 512, 101);
        let pt = render_stats(&pt_out, None);
        assert!(image_mean(&pt) > 0.02, "the scene rendered (almost) black");
        let lt = render_stats(&run(Algorithm::Lt, 512, 104), Some(&not_glass));
        for (what, a, b) in [
            (
                "PT without NEE",
                pt.clone(),
                render_stats(
                    &{
                        let r = TestRender::new(Algorithm::Pt, w, h, 512).seed(102).max_path_length(6).independent();
                        r.nee(false).output(gpu, &s)
                    },
                    None,
                ),
            ),
            ("BPT", pt.clone(), render_stats(&run(Algorithm::Bpt, 256, 103), None)),
            ("VCM", pt.clone(), render_stats(&run(Algorithm::Vcm, 256, 105), None)),
            ("LT (off the sphere)", render_stats(&pt_out, Some(&not_glass)), lt),
        ] {
            let t = welch_test(&a, &b, ALPHA).unwrap();
            eprintln!("{}: PT vs {what}: {t}", s.name);
            assert!(t.passed(), "{}: PT vs {what}: {t}", s.name);
        }
    });
}

/// A white furnace: a rough (0.3) dispersive glass sphere under a uniform white background
/// of radiance 1 returns no more than 1 in any pixel and channel; what it loses is the
/// single-scattering microfacets' loss of plain rough glass at each channel's IOR (channel
/// k against the plain furnace at n_k per pixel; about 5% at IOR 1.5 in Mitsuba 3,
/// tests/render_rough_glass.rs).
#[test]
fn dispersion_furnace() {
    with_gpu(|gpu| {
        let cam = camera(Vec3::new(0.0, 0.0, 3.2), Vec3::new(0.0, 0.0, -1.0), Vec3::Y, 30.0);
        let furnace = |m: Material, seed| {
            let mut s = scene("dispersion furnace", vec![], vec![m], vec![], cam.clone());
            s.lights = vec![Light::Background { radiance: Vec3::ONE }];
            s.spheres = vec![Sphere { center: Vec3::ZERO, radius: 1.0, material: 0 }];
            TestRender::new(Algorithm::Pt, 16, 16, 256).seed(seed).max_path_length(24).independent().stats(gpu, &s)
        };
        let dispersive = glass(1.5, 8.0, 0.3);
        let iors = dispersive.dispersion_iors();
        let st = furnace(dispersive, 111);
        let brightest = common::assert_no_pixel_above_one(&st, None, "dispersive furnace");
        let refs: Vec<PixelStats> = (0..3).map(|k| furnace(glass(iors[k], 0.0, 0.3), 112 + k as u32)).collect();
        let t = welch_test(&st, &per_channel([&refs[0], &refs[1], &refs[2]]), ALPHA).unwrap();
        let channel_mean = |st: &PixelStats, k: usize| st.mean.iter().map(|m| m[k]).sum::<f64>() / st.mean.len() as f64;
        let ref_brightest = (0..3).map(|k| refs[k].mean.iter().map(|m| m[k]).fold(0.0, f64::max)).fold(0.0, f64::max);
        eprintln!(
            "dispersive furnace: brightest pixel {brightest:.4} (plain glass's {ref_brightest:.4}); image means R, G, B {:.4} {:.4} {:.4} (plain glass at n_k: \
             {:.4} {:.4} {:.4}; 1 is lossless); per channel: {t}",
            channel_mean(&st, 0),
            channel_mean(&st, 1),
            channel_mean(&st, 2),
            channel_mean(&refs[0], 0),
            channel_mean(&refs[1], 1),
            channel_mean(&refs[2], 2)
        );
        assert!(t.passed(), "dispersive furnace vs plain glass per channel: {t}");
    });
}

/// HAS_DISPERSION is compiled in only where some glass disperses: not for dispersion 0, nor
/// for a dispersion on an opaque material; where it is, light vertices have a slot more.
#[test]
fn dispersion_features() {
    use vkvcm::render::features::FeatureSet;
    use vkvcm::render::light_vertex_store::light_vertex_b_bytes;
    let plain = FeatureSet::new(&striped_scene(glass(1.5, 0.0, 0.0)), false);
    let defined = |f: &FeatureSet| f.defines().pairs().iter().any(|(k, v)| *k == "HAS_DISPERSION" && *v == "1");
    assert!(!plain.dispersion && !defined(&plain), "{plain}");
    let opaque = Material { diffuse: Vec3::ONE, dispersion: 1.0, ..Default::default() };
    let f = FeatureSet::new(&striped_scene(opaque), false);
    assert!(!f.dispersion, "{f}");
    let f = FeatureSet::new(&striped_scene(glass(1.5, 0.5, 0.0)), false);
    assert!(f.dispersion && defined(&f) && f.to_string().contains("dispersion"), "{f}");
    assert_eq!(light_vertex_b_bytes(&f), light_vertex_b_bytes(&plain) + 16);
}
