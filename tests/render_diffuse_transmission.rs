//! KHR_materials_diffuse_transmission (glsl/lobes/diffuse_transmission.glsl): the
//! transmission per pixel against its analytic value through a sheet lit from behind (path
//! tracing, and light tracing, which evaluates the BSDF with its arguments swapped: the
//! reciprocity check), a white furnace, and the estimators' agreement on a closed scene
//! with a sheet between the lamp and the floor.
mod common;

use std::sync::Arc;

use common::ggx::GgxAlbedo;
use common::scenes::*;
use common::{image_mean, with_gpu, TestRender};
use glam::Vec3;
use vkvcm::render::Algorithm;
use vkvcm::scene::{DiffuseTransmission, EnvironmentLight, EnvironmentMap, Light, Material, Scene, Triangle};
use vkvcm_tools::stats::PixelStats;

/// Family-wise false-alarm rate of each image comparison (Šidák-corrected per pixel).
const W: u32 = 20;
const H: u32 = 20;

fn transmitting(name: &str, base: Material, factor: f32, color: Vec3, metallic: f32) -> Material {
    let dt = DiffuseTransmission { factor, color, metallic, texture: None, color_texture: None };
    Material { name: name.into(), diffuse_transmission: Some(Box::new(dt)), ..base }
}

/// Rows of the sky maps; row j is at polar angle pi j / (ROWS - 1) from +y, so row 16 is
/// the horizon.
const ROWS: u32 = 33;

/// Radiance 1 down to one row above the horizon, 0 from the horizon down, bilinear
/// between (glsl/environment.glsl): the lower hemisphere is exactly dark.
fn upper_sky() -> EnvironmentMap {
    let texels = (0..ROWS).flat_map(|j| (0..8).map(move |_| [if j < ROWS / 2 { 1.0f32 } else { 0.0 }; 3])).collect();
    EnvironmentMap::new("upper sky", 8, ROWS, texels).unwrap()
}

/// upper_sky's radiance at polar angle theta (from +y).
fn upper_sky_radiance(theta: f64) -> f64 {
    let row = theta / std::f64::consts::PI * (ROWS - 1) as f64;
    let h = (ROWS / 2) as f64;
    (h - row).clamp(0.0, 1.0)
}

fn uniform_sky() -> EnvironmentMap {
    EnvironmentMap::new("uniform sky", 8, ROWS, vec![[1.0; 3]; 8 * ROWS as usize]).unwrap()
}

/// Two sheets in the plane y = 0 (x in [-1.1, -0.1] and [0.1, 1.1], z in [-0.5, 0.5]),
/// materials 0 and 1, under the sky `map`; the camera looks up at their undersides from
/// (0, -2.5, 0) and sees nothing else but the sky above. With `texel`, the sheets have
/// texture coordinates and image 0 is that one texel (RGBA).
fn sheet_scene(map: EnvironmentMap, left: Material, right: Material, texel: Option<[u8; 4]>) -> Scene {
    let v = Vec3::new;
    let quad = |x0: f32, x1: f32, material: u32| {
        let (a, b, c, d) = (v(x0, 0.0, -0.5), v(x1, 0.0, -0.5), v(x1, 0.0, 0.5), v(x0, 0.0, 0.5));
        [
            Triangle { p: [a, b, c], n: None, material, attributes: None },
            Triangle { p: [a, c, d], n: None, material, attributes: None },
        ]
    };
    let mut tris = quad(-1.1, -0.1, 0).to_vec();
    tris.extend(quad(0.1, 1.1, 1));
    let light = Light::Environment(EnvironmentLight { map: Arc::new(map), scale: Vec3::ONE, rotation_deg: 0.0 });
    let cam = camera(v(0.0, -2.5, 0.0), Vec3::Y, Vec3::Z, 60.0);
    let mut sc = scene("diffuse transmission sheets", tris, vec![left, right], vec![light], cam);
    if let Some(texel) = texel {
        for tri in &mut sc.triangles {
            tri.attributes = Some(Box::new(vkvcm::scene::VertexAttributes {
                uv: [Some([glam::Vec2::ZERO, glam::Vec2::X, glam::Vec2::Y]), None],
                color: None,
                tangent: None,
            }));
        }
        sc.images = vec![vkvcm::scene::TextureImage { name: "dt".into(), width: 1, height: 1, texels: vec![texel] }];
    }
    sc
}

/// `m` with both its diffuse-transmission textures (image 0).
fn textured(mut m: Material) -> Material {
    let dt = m.diffuse_transmission.as_mut().unwrap();
    dt.texture = Some(nearest_texture(0));
    dt.color_texture = Some(nearest_texture(0));
    m
}

/// The linear value of an sRGB byte.
fn srgb(c: u8) -> f32 {
    let c = c as f32 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// What a camera ray through image point (x, y) sees: the sky (None), or the sheet it
/// hits (0 or 1) and the cosine there.
fn hit(cam: &vkvcm::scene::Camera, x: f32, y: f32) -> Option<(usize, f64)> {
    let plane = 0.5 * H as f32 / (0.5 * cam.yfov).tan();
    let right = cam.forward.cross(cam.up).normalize();
    let up = right.cross(cam.forward);
    let d = (cam.forward * plane + right * (x - 0.5 * W as f32) + up * (0.5 * H as f32 - y)).normalize();
    let p = cam.position + d * (-cam.position.y / d.y);
    if p.z.abs() > 0.5 {
        return None;
    }
    let sheet = match p.x {
        x if (-1.1..=-0.1).contains(&x) => 0,
        x if (0.1..=1.1).contains(&x) => 1,
        _ => return None,
    };
    Some((sheet, d.y as f64))
}

/// Whether pixel `i` sees a sheet at its centre.
fn hit_any(sc: &Scene, i: usize) -> bool {
    hit(&sc.camera, (i as u32 % W) as f32 + 0.5, (i as u32 / W) as f32 + 0.5).is_some()
}

/// The expected image: sky pixels 1 (the camera sees only the upper sky), pixels on sheet
/// k the mean of `value(k, cos)` over 8 x 8 points, pixels on an edge None (not tested).
fn expected_image(sc: &Scene, value: &dyn Fn(usize, f64) -> Vec3) -> Vec<Option<[f32; 3]>> {
    let pixel = |i: u32| -> Option<[f32; 3]> {
        let (x, y) = ((i % W) as f32, (i / W) as f32);
        let hits: Vec<_> = (0..64)
            .map(|k| hit(&sc.camera, x + ((k % 8) as f32 + 0.5) / 8.0, y + ((k / 8) as f32 + 0.5) / 8.0))
            .collect();
        match hits[0] {
            None if hits.iter().all(Option::is_none) => Some([1.0; 3]),
            Some((k, _)) if hits.iter().all(|h| h.is_some_and(|h| h.0 == k)) => {
                let sum: Vec3 = hits.iter().flatten().map(|&(k, c)| value(k, c)).sum();
                Some((sum / 64.0).to_array())
            }
            _ => None,
        }
    };
    (0..W * H).map(pixel).collect()
}

fn test_against(st: &PixelStats, values: &[Option<[f32; 3]>], what: &str) {
    common::assert_matches_values(st, values, what);
    // The pixels' sum against the expected sum: the per-pixel test misses a bias of a few
    // per cent that every pixel shares. Pixels are independent estimates, so the sum's
    // variance is the sum of theirs; |z| < 4.5 (two-sided 7e-6 per channel).
    for c in 0..3 {
        let (mut diff, mut var) = (0.0, 0.0);
        for (i, v) in values.iter().enumerate() {
            if let Some(v) = v {
                diff += st.mean[i][c] - v[c] as f64;
                var += st.variance[i][c] / st.count as f64;
            }
        }
        let z = diff / var.sqrt().max(1e-12);
        eprintln!("{what}: channel {c}, pooled z {z:.2}");
        assert!(z.abs() < 4.5, "{what}: channel {c}: the tested pixels' sum is off by {diff:.4} (z = {z:.2})");
    }
}

/// int_0^1 w(mu) L(acos mu) 2 mu dmu by the midpoint rule, L the upper sky's radiance.
fn sky_integral(w: &dyn Fn(f64) -> f64) -> f64 {
    let n = 20000;
    (0..n)
        .map(|k| {
            let mu = (k as f64 + 0.5) / n as f64;
            w(mu) * upper_sky_radiance(mu.acos()) * 2.0 * mu
        })
        .sum::<f64>()
        / n as f64
}

/// The sheets lit from behind: the upper sky lights their tops, their undersides see a
/// black lower hemisphere, so a pixel on a sheet sees only the transmission:
/// - left, Lambert (no interface) base (0.8, 0.3, 0.2), factor 0.6, colour
///   (0.3, 0.9, 0.5): f_t = t c / pi, the pixel t c I, I = int L(mu) 2 mu dmu (the sky's
///   ramp at the horizon makes I < 1);
/// - right, glTF's dielectric (F0 0.04, roughness 0.5) of base (0.2, 0.5, 0.8) and
///   metallic 0.3, factor 1 and colour 1 times its textures' texel (188, 137, 99, 153):
///   t = 153/255 (A, linear), c the RGB decoded from sRGB; f_t = t c (1 - m) (1 - E(mu_o))
///   (1 - E(mu_i)) / (pi (1 - E_avg)), the pixel t c (1 - m) (1 - E(mu_o)) int (1 - E(mu))
///   L(mu) 2 mu dmu / (1 - E_avg), E the interface's GGX albedo (F0 0.04, width 0.25) and
///   E_avg its cosine-weighted average, both from src/render/ggx_albedo.rs's table
///   (tests/common/ggx.rs, GgxAlbedo).
///
/// Path tracing (with NEE) and light tracing, each per pixel against these values. Light
/// tracing starts at the sky and evaluates the BSDF with the light's direction as the
/// fixed one, so its agreement is the reciprocity check. Then a white furnace under a
/// uniform sky: the Lambert sheet (base and colour white, factor 0.4) returns exactly 1
/// per pixel (reflected 0.6 + transmitted 0.4); the glTF one (white, metallic 0,
/// roughness 0.5, factor 0.4 from its texture, white) returns 1 as well: its diffuse
/// component (reflected and transmitted) 1 - E(mu_o), its GGX lobe E(mu_o) (pooled z over
/// its pixels). Sabotages: see the commit message.
#[test]
fn diffuse_transmission_matches_analytic_and_furnace() {
    let lambert = |c: Vec3| Material { diffuse: c, ..Default::default() };
    let (lc, t_l) = (Vec3::new(0.3, 0.9, 0.5), 0.6f32);
    // The right sheet's factor 1 and colour 1 times its textures' texel.
    let texel = [188u8, 137, 99, 153];
    let (rc, t_r, m_r) = (Vec3::new(srgb(texel[0]), srgb(texel[1]), srgb(texel[2])), texel[3] as f32 / 255.0, 0.3f32);
    let left = transmitting("lambert", lambert(Vec3::new(0.8, 0.3, 0.2)), t_l, lc, 0.0);
    let gltf = Material::metallic_roughness(Vec3::new(0.2, 0.5, 0.8), m_r, 0.5);
    let right = textured(transmitting("gltf", gltf, 1.0, Vec3::ONE, m_r));
    let sc = sheet_scene(upper_sky(), left, right, Some(texel));
    // The glTF sheet's interface: F0 0.04, width roughness^2.
    let (interface, alpha) = (GgxAlbedo::committed(), 0.25);
    let e = |mu: f64| interface.albedo(0.04, mu, alpha);
    let i_lambert = sky_integral(&|_| 1.0);
    let i_gltf = sky_integral(&|mu| 1.0 - e(mu)) / (1.0 - interface.average(0.04, alpha));
    eprintln!("sky integrals: Lambert {i_lambert:.5}, under the interface {i_gltf:.5}");
    let value = |k: usize, mu_o: f64| match k {
        0 => lc * (t_l * i_lambert as f32),
        _ => rc * (t_r * (1.0 - m_r) * ((1.0 - e(mu_o)) * i_gltf) as f32),
    };
    let white = Vec3::ONE;
    // The glTF sheet's factor 0.4 = 102/255 from its texture.
    let furnace = sheet_scene(
        uniform_sky(),
        transmitting("white lambert", lambert(white), 0.4, white, 0.0),
        textured(transmitting("white gltf", Material::metallic_roughness(white, 0.0, 0.5), 1.0, white, 0.0)),
        Some([255, 255, 255, 102]),
    );
    with_gpu(|gpu| {
        let expected = expected_image(&sc, &value);
        // Light tracing does not see the sky itself (no light path ends at the camera
        // through the sky): only its sheet pixels are tested.
        let sheets: Vec<_> = expected.iter().enumerate().map(|(i, v)| v.filter(|_| hit_any(&sc, i))).collect();
        for (what, algo, seed, expected) in
            [("PT", Algorithm::Pt, 11u32, &expected), ("LT", Algorithm::Lt, 12, &sheets)]
        {
            let st = TestRender::new(algo, W, H, 512).seed(seed).max_path_length(2).stats(gpu, &sc);
            eprintln!("sheets lit from behind, {what}: image mean {:.5}", image_mean(&st));
            test_against(&st, expected, &format!("{what} vs the analytic transmission"));
        }
        let st = TestRender::new(Algorithm::Pt, W, H, 512).seed(13).max_path_length(2).stats(gpu, &furnace);
        let lambert_one = |k: usize, _: f64| if k == 0 { Vec3::ONE } else { Vec3::ZERO };
        let mut ones = expected_image(&furnace, &lambert_one);
        // The glTF sheet's pixels: their sum, its variance, their number (channel R).
        let mut gltf = (0.0, 0.0, 0);
        for (i, v) in ones.iter_mut().enumerate() {
            if v.is_some_and(|v| v[0] == 0.0) {
                *v = None;
                gltf = (gltf.0 + st.mean[i][0], gltf.1 + st.variance[i][0] / st.count as f64, gltf.2 + 1);
            }
        }
        test_against(&st, &ones, "white furnace, Lambert sheet");
        common::assert_no_pixel_above_one(&st, None, "furnace");
        let z_gltf = (gltf.0 - gltf.2 as f64) / gltf.1.sqrt();
        eprintln!(
            "white furnace: glTF sheet's mean {:.5} over {} pixels (z {z_gltf:.2} against 1)",
            gltf.0 / gltf.2 as f64,
            gltf.2
        );
        // The pooled test's 4.5.
        assert!(z_gltf.abs() < 4.5, "furnace: the glTF sheet returns {} on average", gltf.0 / gltf.2 as f64);
    });
}

/// A closed scene whose floor is lit through sheets: glossy_floor_scene (lamp above, a
/// back wall) with diffuse grey floors and, between the lamp and the floor at height 0.7,
/// two transmitting sheets: left glTF's red dielectric (roughness 0.6) transmitting 0.7 of
/// green under a clear coat of factor 1 (the coat on both sides), right a Lambert yellow
/// transmitting red under a sheen (0.5 white, roughness 0.4), its factor and colour
/// varied by a texture (texel (230, 120, 60, 128)), tilted shading normals on both. PT with NEE against PT without (bsdf_eval's pdf is the density
/// bsdf_sample draws, transmissions included), BPT and LT against PT (reverse pdfs, light
/// subpaths crossing the sheets, the layers' adjoint).
#[test]
fn diffuse_transmission_estimators_agree() {
    let grey = Material { name: "floor".into(), diffuse: Vec3::splat(0.5), ..Default::default() };
    let mut sc = glossy_floor_scene(grey.clone(), grey);
    let left = Material {
        clearcoat: 1.0,
        clearcoat_roughness: 0.3,
        ..transmitting(
            "coated",
            Material::metallic_roughness(Vec3::new(0.8, 0.2, 0.1), 0.0, 0.6),
            0.7,
            Vec3::new(0.2, 0.9, 0.3),
            0.0,
        )
    };
    let mut right = Material {
        sheen_color: Vec3::splat(0.5),
        sheen_roughness: 0.4,
        ..transmitting(
            "sheened",
            Material { diffuse: Vec3::new(0.7, 0.7, 0.1), ..Default::default() },
            0.5,
            Vec3::new(0.9, 0.2, 0.1),
            0.0,
        )
    };
    // The right sheet's factor and colour vary by a texture (one texel): BPT's stored
    // light vertices must carry the point's multipliers.
    let dt = right.diffuse_transmission.as_mut().unwrap();
    dt.factor = 1.0;
    dt.texture = Some(nearest_texture(0));
    dt.color_texture = Some(nearest_texture(0));
    sc.images =
        vec![vkvcm::scene::TextureImage { name: "dt".into(), width: 1, height: 1, texels: vec![[230, 120, 60, 128]] }];
    let first = sc.materials.len() as u32;
    sc.materials.extend([left, right]);
    let v = Vec3::new;
    let quad = |a: Vec3, b: Vec3, c: Vec3, d: Vec3, material: u32| {
        [
            Triangle { p: [a, b, c], n: None, material, attributes: None },
            Triangle { p: [a, c, d], n: None, material, attributes: None },
        ]
    };
    let mut sheets = quad(v(-1.2, -0.6, 0.7), v(0.0, -0.6, 0.7), v(0.0, 1.8, 0.7), v(-1.2, 1.8, 0.7), first).to_vec();
    sheets.extend(quad(v(0.0, -0.6, 0.7), v(1.2, -0.6, 0.7), v(1.2, 1.8, 0.7), v(0.0, 1.8, 0.7), first + 1));
    // The lights index triangles: the sheets go after them.
    for tri in &mut sheets {
        tri.attributes = Some(Box::new(vkvcm::scene::VertexAttributes {
            uv: [Some([glam::Vec2::ZERO, glam::Vec2::X, glam::Vec2::Y]), None],
            color: None,
            tangent: None,
        }));
    }
    sc.triangles.extend(sheets);
    tilt_shading_normals(&mut sc, 20.0, 7);
    with_gpu(|gpu| common::assert_estimators_agree(gpu, &sc, W, H, 5, 4096));
}

/// The feature set compiles the diffuse transmission in only where a used opaque
/// material transmits, and its textures only with texture coordinates.
#[test]
fn diffuse_transmission_features() {
    use vkvcm::render::features::FeatureSet;
    let plain = Material { diffuse: Vec3::ONE, ..Default::default() };
    let f = FeatureSet::new(&sheet_scene(uniform_sky(), plain.clone(), plain.clone(), None), false);
    assert!(!f.diffuse_transmission, "{f}");
    let dt = transmitting("dt", plain.clone(), 0.5, Vec3::ONE, 0.0);
    // A factor of 0, or a dielectric, transmits nothing diffusely.
    let none = transmitting("none", plain.clone(), 0.0, Vec3::ONE, 0.0);
    let glass = Material { ior: 1.5, ..dt.clone() };
    let f = FeatureSet::new(&sheet_scene(uniform_sky(), none, glass, None), false);
    assert!(!f.diffuse_transmission, "{f}");
    let f = FeatureSet::new(&sheet_scene(uniform_sky(), dt.clone(), plain.clone(), None), false);
    assert!(f.diffuse_transmission && !f.diffuse_transmission_textures, "{f}");
    assert!(f.to_string().contains("diffuse transmission"), "{f}");
    let f = FeatureSet::new(&sheet_scene(uniform_sky(), textured(dt.clone()), plain.clone(), None), false);
    assert!(f.diffuse_transmission && !f.diffuse_transmission_textures, "without coordinates: {f}");
    let f = FeatureSet::new(&sheet_scene(uniform_sky(), textured(dt), plain, Some([0; 4])), false);
    assert!(f.diffuse_transmission && f.diffuse_transmission_textures, "{f}");
}
