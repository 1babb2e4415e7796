//! Textures, vertex colours and alpha cut-outs in the kernels (glsl/textures.glsl), against
//! analytic images computed here on the CPU with an independent sampler, and between
//! estimators. Lavapipe, validation on.
//!
//! The analytic scenes: a camera looking straight down at a textured diffuse quad that
//! fills its view exactly (texture coordinates (0, 0) at the image's top-left corner,
//! u along x, v along y, so that a 4 x 4 texture covers 6 x 6 pixels per texel of the
//! 24 x 24 frame), under a uniform white sky, with paths of at most 2 segments: a point of
//! the quad reflects its albedo times the sky's radiance, so each pixel's expectation is
//! the texture (times the vertex colour) averaged over the pixel — computed here by
//! supersampling the pixel with this file's own sampler (sRGB decode, wrap modes,
//! bilinear filtering). Per-pixel z-tests as in tests/render_bidir.rs (ALPHA per
//! comparison, Šidák-corrected).

mod common;

use std::sync::Arc;

use common::scenes::{camera, scene};
use common::{render_stats, with_gpu};
use glam::{Vec2, Vec3, Vec4};
use vkvcm::gpu::Gpu;
use vkvcm::image::Image;
use vkvcm::render::{self, Algorithm, Budget, RenderOutput, RenderSettings};
use vkvcm::scene::{
    AlphaMode, Filter, Light, Material, Scene, TextureImage, TextureRef, Triangle, VertexAttributes, Wrap,
};
use vkvcm_tools::stats::{one_sample_test, welch_test, PixelStats};

const ALPHA: f64 = 1e-3;
const W: u32 = 24;
const H: u32 = 24;
/// Camera height over the quad y = 0, and the quad's half size: exactly the view's
/// footprint for a 45 degree field of view.
const CAM_H: f32 = 3.0;

fn half_size() -> f32 {
    CAM_H * (22.5f32).to_radians().tan()
}

/// A 4 x 4 RGBA8 image whose texels all differ (so that a flip or transpose shows), with
/// alpha 0 on the texels where i + j is odd (the cut-out pattern).
fn test_image() -> TextureImage {
    let texels = (0..16)
        .map(|k| {
            let (i, j) = (k % 4, k / 4);
            [
                (40 + 50 * i) as u8,
                (30 + 60 * j) as u8,
                (220 - 40 * i - 10 * j) as u8,
                if (i + j) % 2 == 1 { 0 } else { 255 },
            ]
        })
        .collect();
    TextureImage { name: "test".into(), width: 4, height: 4, texels }
}

fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

fn texel(img: &TextureImage, i: i32, j: i32) -> Vec4 {
    let t = img.texels[(j * img.width as i32 + i) as usize];
    let c = |b: u8| b as f32 / 255.0;
    Vec4::new(srgb_to_linear(c(t[0])), srgb_to_linear(c(t[1])), srgb_to_linear(c(t[2])), c(t[3]))
}

fn wrap(i: i32, n: i32, w: Wrap) -> i32 {
    match w {
        Wrap::Repeat => i.rem_euclid(n),
        Wrap::ClampToEdge => i.clamp(0, n - 1),
        Wrap::MirroredRepeat => {
            let m = i.rem_euclid(2 * n);
            if m < n {
                m
            } else {
                2 * n - 1 - m
            }
        }
    }
}

/// The reference sampler: glTF's conventions, written independently of the GLSL.
fn sample(img: &TextureImage, t: &TextureRef, uv: Vec2) -> Vec4 {
    let [r0, r1] = t.transform;
    let st = Vec2::new(r0[0] * uv.x + r0[1] * uv.y + r0[2], r1[0] * uv.x + r1[1] * uv.y + r1[2]);
    let (w, h) = (img.width as i32, img.height as i32);
    let x = st * Vec2::new(w as f32, h as f32);
    let at = |i: i32, j: i32| texel(img, wrap(i, w, t.wrap_s), wrap(j, h, t.wrap_t));
    match t.filter {
        Filter::Nearest => at(x.x.floor() as i32, x.y.floor() as i32),
        Filter::Linear => {
            let y = x - Vec2::splat(0.5);
            let (i, j) = (y.x.floor() as i32, y.y.floor() as i32);
            let f = y - Vec2::new(i as f32, j as f32);
            let top = at(i, j).lerp(at(i + 1, j), f.x);
            let bottom = at(i, j + 1).lerp(at(i + 1, j + 1), f.x);
            top.lerp(bottom, f.y)
        }
    }
}

/// The quad y = 0 filling the view, with texture coordinates `uv_of(u, v)` at its
/// corners (u, v in {0, 1}: the image's corners) and vertex colours `color_of(u, v)`.
fn quad(material: u32, uv_of: &dyn Fn(f32, f32) -> Vec2, color_of: Option<&dyn Fn(f32, f32) -> Vec4>) -> Vec<Triangle> {
    let s = half_size();
    // Image x is world +x, image y (down) world +z (camera up = -z).
    let corner = |u: f32, v: f32| Vec3::new(-s + 2.0 * s * u, 0.0, -s + 2.0 * s * v);
    let tri = |c: [(f32, f32); 3]| Triangle {
        p: c.map(|(u, v)| corner(u, v)),
        n: None,
        material,
        attributes: Some(Box::new(VertexAttributes {
            uv: [Some(c.map(|(u, v)| uv_of(u, v))), None],
            color: color_of.map(|f| c.map(|(u, v)| f(u, v))),
            tangent: None,
        })),
    };
    // Both counter-clockwise seen from above (+y), the camera's side.
    vec![tri([(0.0, 0.0), (0.0, 1.0), (1.0, 1.0)]), tri([(0.0, 0.0), (1.0, 1.0), (1.0, 0.0)])]
}

/// Two triangles over the rectangle [u0, u1] x [v0, v1] of the parameter plane that
/// `corner` maps into the world (affinely), with texture coordinates (u, v) at each point
/// when `uv`. Their geometric normal is d corner / du x d corner / dv.
fn rect(
    corner: &dyn Fn(f32, f32) -> Vec3,
    (u0, u1): (f32, f32),
    (v0, v1): (f32, f32),
    material: u32,
    uv: bool,
) -> Vec<Triangle> {
    let tri = |c: [(f32, f32); 3]| Triangle {
        p: c.map(|(u, v)| corner(u, v)),
        n: None,
        material,
        attributes: uv.then(|| {
            Box::new(VertexAttributes { uv: [Some(c.map(|(u, v)| Vec2::new(u, v))), None], color: None, tangent: None })
        }),
    };
    vec![tri([(u0, v0), (u1, v0), (u1, v1)]), tri([(u0, v0), (u1, v1), (u0, v1)])]
}

/// Image 0 with repeat wrapping on TEXCOORD_0, untransformed, filtered by `filter`.
fn repeat_texture(filter: Filter) -> TextureRef {
    TextureRef {
        image: 0,
        wrap_s: Wrap::Repeat,
        wrap_t: Wrap::Repeat,
        filter,
        tex_coord: 0,
        transform: TextureRef::IDENTITY,
    }
}

fn top_camera() -> vkvcm::scene::Camera {
    camera(Vec3::new(0.0, CAM_H, 0.0), Vec3::NEG_Y, Vec3::NEG_Z, 45.0)
}

fn textured_scene(
    texture: TextureRef,
    uv_of: &dyn Fn(f32, f32) -> Vec2,
    color_of: Option<&dyn Fn(f32, f32) -> Vec4>,
) -> Scene {
    let mat = Material {
        name: "textured".into(),
        diffuse: Vec3::ONE,
        base_color_texture: Some(texture),
        ..Default::default()
    };
    let sky = Light::Background { radiance: Vec3::ONE };
    let mut s = scene("textured quad", quad(0, uv_of, color_of), vec![mat], vec![sky], top_camera());
    s.images = vec![test_image()];
    s
}

/// The image whose pixels average `f` over 16 x 16 points of the pixel, at image
/// coordinates (u, v) = (x / W, y / H).
fn pixel_averages(f: &dyn Fn(f32, f32) -> Vec3) -> Image {
    let n = 16;
    let mut out = Image::filled(W, H, [0.0; 3]);
    for py in 0..H {
        for px in 0..W {
            let mut sum = Vec3::ZERO;
            for k in 0..n * n {
                let u = (px as f32 + ((k % n) as f32 + 0.5) / n as f32) / W as f32;
                let v = (py as f32 + ((k / n) as f32 + 0.5) / n as f32) / H as f32;
                sum += f(u, v);
            }
            out.data[(py * W + px) as usize] = (sum / (n * n) as f32).to_array();
        }
    }
    out
}

/// Each pixel's expectation: the tint (texture at `t_uv`, times the vertex colour).
fn expected_image(scene: &Scene, color_of: Option<&dyn Fn(f32, f32) -> Vec4>) -> Image {
    let t = scene.materials[0].base_color_texture.as_ref().unwrap();
    let img = &scene.images[0];
    pixel_averages(&|u, v| (sample(img, t, t_uv(u, v)) * color_of.map_or(Vec4::ONE, |f| f(u, v))).truncate())
}

/// The texture coordinates of the image point (u, v) in these tests: [-0.5, 1.5]^2, so
/// that the wrap modes matter.
fn t_uv(u: f32, v: f32) -> Vec2 {
    Vec2::new(2.0 * u - 0.5, 2.0 * v - 0.5)
}

fn render_with(gpu: &Arc<Gpu>, scene: &Scene, algo: Algorithm, iterations: u64) -> RenderOutput {
    let mut s = RenderSettings::new(algo, W, H, Budget::Iterations(iterations));
    s.frame.max_path_length = 2;
    s.frame.seed = 9 + algo as u32;
    let out = render::render(gpu, scene, &s, None, &mut |_| {}).unwrap();
    assert_eq!(out.rejected_samples, 0, "{algo:?}: rejected samples");
    out
}

/// Nearest and linear filtering with each wrap mode, a texture transform, and vertex
/// colours (varying across the quad: red 1, green = u, blue 1, linear in u so that the
/// interpolation over the two triangles is exact): pt and bpt per pixel against the CPU
/// image. Sabotaged (sRGB decode left out; v flipped; mirrored repeat as repeat) it
/// fails.
#[test]
fn textured_quad_matches_the_cpu_sampler() {
    let scale_offset = [[0.5, 0.0, 0.25], [0.0, 2.0, -0.5]];
    type Case = (&'static str, Wrap, Wrap, Filter, [[f32; 3]; 2]);
    let cases: [Case; 4] = [
        ("nearest, repeat", Wrap::Repeat, Wrap::Repeat, Filter::Nearest, TextureRef::IDENTITY),
        ("linear, clamp / mirrored", Wrap::ClampToEdge, Wrap::MirroredRepeat, Filter::Linear, TextureRef::IDENTITY),
        ("linear, mirrored / repeat", Wrap::MirroredRepeat, Wrap::Repeat, Filter::Linear, TextureRef::IDENTITY),
        ("nearest, transformed", Wrap::Repeat, Wrap::MirroredRepeat, Filter::Nearest, scale_offset),
    ];
    let green_ramp = |u: f32, _v: f32| Vec4::new(1.0, u, 1.0, 1.0);
    with_gpu(|gpu| {
        for (label, wrap_s, wrap_t, filter, transform) in cases {
            let t = TextureRef { image: 0, wrap_s, wrap_t, filter, tex_coord: 0, transform };
            for colours in [false, true] {
                let color_of: Option<&dyn Fn(f32, f32) -> Vec4> = if colours { Some(&green_ramp) } else { None };
                let sc = textured_scene(t.clone(), &t_uv, color_of);
                let expected = expected_image(&sc, color_of);
                for (algo, iterations) in [(Algorithm::Pt, 256), (Algorithm::Bpt, 128)] {
                    let st = render_stats(&render_with(gpu, &sc, algo, iterations), None);
                    let name = format!("{label}{}, {algo:?}", if colours { ", vertex colours" } else { "" });
                    let r = one_sample_test(&st, &expected, ALPHA).unwrap();
                    assert!(r.passed(), "{name}: {r}");
                }
            }
        }
    });
}

/// TEXCOORD_1: a texture that names the second set reads it (the first set is a
/// constant, wrong on purpose): the image is the first set's image of the same
/// coordinates.
#[test]
fn second_texture_coordinate_set() {
    let t = |tex_coord| TextureRef { tex_coord, ..repeat_texture(Filter::Nearest) };
    let identity = |u: f32, v: f32| Vec2::new(u, v);
    let reference = textured_scene(t(0), &identity, None);
    let mut sc = textured_scene(t(1), &identity, None);
    for tri in &mut sc.triangles {
        let a = tri.attributes.as_mut().unwrap();
        a.uv[1] = a.uv[0];
        a.uv[0] = Some([Vec2::new(0.9, 0.1); 3]);
    }
    with_gpu(|gpu| {
        let st = render_stats(&render_with(gpu, &sc, Algorithm::Pt, 128), None);
        let r = one_sample_test(&st, &expected_image_for_uvs(&reference), ALPHA).unwrap();
        assert!(r.passed(), "TEXCOORD_1: {r}");
    });
}

/// A texture on a coordinate set the triangles lack is not applied: the image is the
/// untextured quad's, pixel for pixel (same seed; the kernels differ only in compiled-in
/// texture code, bit-identical on lavapipe, 1e-5 allowed for rounding). Reading the other
/// set instead would show the texture.
#[test]
fn texture_on_a_missing_coordinate_set_is_not_applied() {
    let t = TextureRef { tex_coord: 1, ..repeat_texture(Filter::Nearest) };
    let identity = |u: f32, v: f32| Vec2::new(u, v);
    let sc = textured_scene(t, &identity, None);
    assert!(sc.triangles.iter().all(|t| t.attributes.as_ref().unwrap().uv[1].is_none()));
    let mut plain = sc.clone();
    plain.materials[0].base_color_texture = None;
    with_gpu(|gpu| {
        let a = render_with(gpu, &sc, Algorithm::Pt, 16);
        let b = render_with(gpu, &plain, Algorithm::Pt, 16);
        let worst = a
            .pixels
            .iter()
            .flatten()
            .zip(b.pixels.iter().flatten())
            .map(|(x, y)| (x - y).abs() / x.abs().max(y.abs()).max(1e-6))
            .fold(0.0f32, f32::max);
        assert!(worst <= 1e-5, "differs from the untextured quad by {worst}");
    });
}

/// The expected image of a quad whose TEXCOORD_0 at the image corners is the quad's own
/// (bilinear in the image, as the quad's two triangles interpolate it).
fn expected_image_for_uvs(scene: &Scene) -> Image {
    let a = scene.triangles[0].attributes.as_ref().unwrap().uv[0].unwrap();
    let b = scene.triangles[1].attributes.as_ref().unwrap().uv[0].unwrap();
    // Corners: (0,0) = a[0], (0,1) = a[1], (1,1) = a[2], (1,0) = b[2]; the coordinates
    // here are affine in the image, so the corners define them.
    let (c00, c01, c11, c10) = (a[0], a[1], a[2], b[2]);
    assert!((c00 + c11 - c01 - c10).length() < 1e-6, "the test's coordinates are affine");
    let t = scene.materials[0].base_color_texture.as_ref().unwrap();
    let img = &scene.images[0];
    pixel_averages(&|u, v| sample(img, t, c00 + (c10 - c00) * u + (c01 - c00) * v).truncate())
}

/// An alphaMode MASK quad (the test image's alpha: 0 on half of its texels, in a
/// checkerboard) over a grey diffuse floor 0.002 below it, under the white sky. The
/// cut-outs are holes for every ray: camera rays see the floor through them, and the
/// floor is lit through them. So pt (shadow rays: any-hit traversal) and bpt and lt (light
/// subpaths through the holes, connections) agree per pixel; and the quad's opaque
/// texels, whose upper hemisphere is all sky, show exactly their texture colour.
/// Sabotaged (the alpha test only in closest-hit traversal, not in shadow rays; or no
/// alpha test at all) it fails.
#[test]
fn alpha_cutouts_are_holes_for_every_ray() {
    let t = repeat_texture(Filter::Nearest);
    let mut sc = textured_scene(t, &|u, v| Vec2::new(u, v), None);
    sc.materials[0].alpha_mode = AlphaMode::Mask { cutoff: 0.5 };
    // The floor: larger than the view, 0.002 below, grey, flat.
    let f = 3.0 * half_size();
    let y = -0.002;
    let floor_mat = sc.materials.len() as u32;
    sc.materials.push(Material { name: "floor".into(), diffuse: Vec3::splat(0.5), ..Default::default() });
    let c = |x: f32, z: f32| Vec3::new(x, y, z);
    sc.triangles.push(Triangle { p: [c(-f, -f), c(-f, f), c(f, f)], n: None, material: floor_mat, attributes: None });
    sc.triangles.push(Triangle { p: [c(-f, -f), c(f, f), c(f, -f)], n: None, material: floor_mat, attributes: None });
    let img = test_image();
    // Pixels (6 x 6 per texel) wholly inside an opaque texel, away from its edges.
    let opaque: Vec<bool> = (0..W * H)
        .map(|i| {
            let (x, y) = (i % W, i / W);
            let (ti, tj) = (x / 6, y / 6);
            img.texels[(tj * 4 + ti) as usize][3] == 255
        })
        .collect();
    with_gpu(|gpu| {
        let pt_out = render_with(gpu, &sc, Algorithm::Pt, 512);
        let pt = render_stats(&pt_out, None);
        // Opaque texels: the texture's colour (the whole upper hemisphere is sky).
        let mut expected = Image::filled(W, H, [0.0; 3]);
        for (i, e) in expected.data.iter_mut().enumerate() {
            if opaque[i] {
                let (x, y) = (i as u32 % W, i as u32 / W);
                *e = texel(&img, (x / 6) as i32, (y / 6) as i32).truncate().to_array();
            }
        }
        let on_quad = render_stats(&pt_out, Some(&opaque));
        let r = one_sample_test(&on_quad, &expected, ALPHA).unwrap();
        assert!(r.passed(), "opaque texels: {r}");
        // Holes: the grey floor (lit through the hole: at most its albedo 0.5 within five
        // standard errors, not black), not the texture's colour there (whose channels
        // differ by 0.1 or more; the floor's are equal).
        for (i, (m, v)) in pt.mean.iter().zip(&pt.variance).enumerate() {
            if !opaque[i] {
                let se = (v[1] / pt.count as f64).sqrt();
                let grey = (m[0] - m[1]).abs() < 0.05 && (m[1] - m[2]).abs() < 0.05;
                assert!(
                    grey && m[1] > 0.05 && m[1] < 0.5 + 5.0 * se,
                    "pixel {i} in a hole: {m:?} +- {se} (the grey floor)"
                );
            }
        }
        let mut s = RenderSettings::new(Algorithm::Pt, W, H, Budget::Iterations(1));
        s.frame.max_path_length = 4;
        let run = |algo: Algorithm, iterations: u64| {
            let mut s = s.clone();
            s.algorithm = algo;
            s.budget = Budget::Iterations(iterations);
            s.frame.seed = 77 + algo as u32;
            render_stats(&render::render(gpu, &sc, &s, None, &mut |_| {}).unwrap(), None)
        };
        let pt4 = run(Algorithm::Pt, 2048);
        let bpt4 = run(Algorithm::Bpt, 1024);
        let r = welch_test(&pt4, &bpt4, ALPHA).unwrap();
        assert!(r.passed(), "cut-outs: PT vs BPT: {r}");
        // Every pixel sees a diffuse surface (the quad or, through a hole, the floor), so
        // light tracing reaches all of them.
        let lt4 = render_stats(
            &{
                let mut s = s.clone();
                s.algorithm = Algorithm::Lt;
                s.budget = Budget::Iterations(4096);
                s.frame.seed = 5;
                render::render(gpu, &sc, &s, None, &mut |_| {}).unwrap()
            },
            None,
        );
        let r = welch_test(&lt4, &bpt4, ALPHA).unwrap();
        assert!(r.passed(), "cut-outs: LT vs BPT: {r}");
    });
}

/// alphaMode BLEND is stochastic transparency: a ray meets the surface with probability
/// alpha and passes straight through otherwise (glsl/textures.glsl, `alpha_visible`).
/// * A black quad of alpha 0.3 filling the view under the white sky: every pixel's
///   expectation is exactly 0.7 (the sky through the quad), for pt, bpt and vcm
///   (one-sample test per pixel).
/// * A grey quad of alpha 0.4 over a grey floor 0.002 below it: the floor is lit through
///   the quad and seen through it, the quad lit by the sky and by the floor through
///   itself; pt (shadow rays: the any-hit traversal), bpt and lt (light subpaths through
///   the quad, connections) agree per pixel.
///
/// Sabotaged, it fails: BLEND decided as MASK with cutoff 0.5; the random number hashing
/// neither the barycentrics nor the distance (one decision per triangle). (Hashing the
/// barycentrics without the distance still passes: on triangles they differ per ray; the
/// distance is there for spheres, whose barycentrics are 0.)
#[test]
fn alpha_blend_is_stochastic_transparency() {
    let black =
        Material { name: "black, blended".into(), alpha: 0.3, alpha_mode: AlphaMode::Blend, ..Default::default() };
    let uv = |u: f32, v: f32| Vec2::new(u, v);
    let sky = Light::Background { radiance: Vec3::ONE };
    let over_sky = scene("blended quad", quad(0, &uv, None), vec![black], vec![sky.clone()], top_camera());
    let grey = Material {
        name: "grey, blended".into(),
        diffuse: Vec3::splat(0.8),
        alpha: 0.4,
        alpha_mode: AlphaMode::Blend,
        ..Default::default()
    };
    let mut over_floor = scene("blended quad", quad(0, &uv, None), vec![grey], vec![sky], top_camera());
    let f = 3.0 * half_size();
    let y = -0.002;
    over_floor.materials.push(Material { name: "floor".into(), diffuse: Vec3::splat(0.5), ..Default::default() });
    let c = |x: f32, z: f32| Vec3::new(x, y, z);
    for p in [[c(-f, -f), c(-f, f), c(f, f)], [c(-f, -f), c(f, f), c(f, -f)]] {
        over_floor.triangles.push(Triangle { p, n: None, material: 1, attributes: None });
    }
    with_gpu(|gpu| {
        let expected = Image::filled(W, H, [0.7; 3]);
        for (algo, iterations) in [(Algorithm::Pt, 512), (Algorithm::Bpt, 256), (Algorithm::Vcm, 256)] {
            let out = render_stats(&render_with(gpu, &over_sky, algo, iterations), None);
            let r = one_sample_test(&out, &expected, ALPHA).unwrap();
            assert!(r.passed(), "{algo:?}, black quad of alpha 0.3 over the sky: {r}");
        }
        let run = |algo: Algorithm, iterations: u64| {
            let mut s = RenderSettings::new(algo, W, H, Budget::Iterations(iterations));
            s.frame.max_path_length = 4;
            s.frame.seed = 91 + algo as u32;
            render_stats(&render::render(gpu, &over_floor, &s, None, &mut |_| {}).unwrap(), None)
        };
        let pt = run(Algorithm::Pt, 2048);
        let bpt = run(Algorithm::Bpt, 1024);
        let r = welch_test(&pt, &bpt, ALPHA).unwrap();
        assert!(r.passed(), "blended quad over a floor: PT vs BPT: {r}");
        let lt = run(Algorithm::Lt, 4096);
        let r = welch_test(&lt, &bpt, ALPHA).unwrap();
        assert!(r.passed(), "blended quad over a floor: LT vs BPT: {r}");
    });
}

/// Against Mitsuba 3 (scripts/texture_reference.py: tests/env/textured_scene.gltf for
/// vkvcm, tests/env/mitsuba_textured_{mean,var}.exr, 16 renders of 256 spp): a bilinear,
/// repeating checker on the ground and a nearest, clamped cut-out quad, under the sky
/// map, 24 segments. The materials are made Lambertian (the texture kept), as the
/// script's Mitsuba scene describes them. pt and vcm per pixel.
#[test]
fn textured_and_masked_scene_matches_mitsuba() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/env");
    let mut scene = vkvcm::scene::load_with(&dir.join("textured_scene.gltf"), &Default::default()).unwrap();
    assert_eq!(scene.images.len(), 2);
    for m in &mut scene.materials {
        assert!(m.base_color_texture.is_some(), "{}: no texture", m.name);
        m.diffuse = Vec3::ONE;
        m.glossy = Vec3::ZERO;
        m.glossy_untinted = 0.0;
        m.diffuse_fresnel_f0 = 0.0;
    }
    assert!(matches!(scene.materials[1].alpha_mode, AlphaMode::Mask { .. }));
    with_gpu(|gpu| {
        common::assert_matches_mitsuba(
            gpu,
            &scene,
            "mitsuba_textured",
            24,
            &[(Algorithm::Pt, 2048), (Algorithm::Vcm, 256)],
        )
    });
}

/// Against Mitsuba 3 (scripts/texture_reference.py --normal-map: tests/env/
/// normal_map_scene.gltf for vkvcm, tests/env/mitsuba_normal_map_{mean,var}.exr, 16
/// renders of 256 spp): the grey Lambertian ground with a 4 x 4 tangent-space normal map
/// (tilts of 0 to 40 degrees in eight directions, nearest, repeating) under the sky map,
/// 24 segments; Mitsuba's `normalmap` BSDF around its `diffuse`. The material is made
/// Lambertian (the normal map kept), as the script's Mitsuba scene describes it. pt and
/// vcm per pixel: vcm's light subpaths reach the camera through the ground's adjoint
/// shading-normal correction. With the generated tangents' bitangent reversed (MikkTSpace
/// given glTF's v unflipped, src/scene/gltf_import/tangents.rs) pt fails on 344 of 2304
/// pixels.
#[test]
fn normal_mapped_ground_matches_mitsuba() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/env");
    let mut scene = vkvcm::scene::load_with(&dir.join("normal_map_scene.gltf"), &Default::default()).unwrap();
    assert_eq!(scene.materials.len(), 1);
    for m in &mut scene.materials {
        assert!(m.normal_texture.is_some(), "{}: no normal map", m.name);
        m.diffuse = Vec3::splat(0.8);
        m.glossy = Vec3::ZERO;
        m.glossy_untinted = 0.0;
        m.diffuse_fresnel_f0 = 0.0;
    }
    assert!(vkvcm::render::features::FeatureSet::new(&scene, false).normal_maps);
    with_gpu(|gpu| {
        common::assert_matches_mitsuba(
            gpu,
            &scene,
            "mitsuba_normal_map",
            24,
            &[(Algorithm::Pt, 1024), (Algorithm::Vcm, 256)],
        )
    });
}

/// A normal map bends the shading normal, for every estimator: the quad with a constant
/// normal map (34 degrees off its normal, between its tangent +x and bitangent -z)
/// renders as the same quad with that bent normal as its vertex normals (per pixel, pt
/// and bpt against pt), and unlike the flat quad. Lit by a low sun and a dim sky, so that
/// the normal's tilt shows. Sabotaged (the bitangent's sign flipped; the map ignored) it
/// fails.
#[test]
fn normal_map_bends_the_shading_normal_in_every_estimator() {
    let tn = Vec3::new(0.4, 0.4, 0.68f32.sqrt());
    let enc = |c: f32| ((c * 0.5 + 0.5) * 255.0).round() as u8;
    let texel = [enc(tn.x), enc(tn.y), enc(tn.z), 255];
    // What the kernels decode; the frame: T = +x (u along x), N = +y (the quad's normal),
    // B = cross(N, T) = -z.
    let d = texel.map(|b| b as f32 / 255.0 * 2.0 - 1.0);
    let bent = (Vec3::X * d[0] + Vec3::NEG_Z * d[1] + Vec3::Y * d[2]).normalize();
    let map = repeat_texture(Filter::Linear);
    let lights = vec![
        Light::Directional { direction: Vec3::new(1.0, -0.6, 0.2).normalize(), irradiance: Vec3::splat(2.0) },
        Light::Background { radiance: Vec3::splat(0.2) },
    ];
    let make = |normal_map: bool, normals: bool| {
        let mat = Material {
            name: "bumpy".into(),
            diffuse: Vec3::splat(0.8),
            normal_texture: normal_map.then(|| map.clone()),
            ..Default::default()
        };
        let mut tris = quad(0, &|u, v| Vec2::new(u, v), None);
        for t in &mut tris {
            if normal_map {
                t.attributes.as_mut().unwrap().tangent = Some([Vec4::new(1.0, 0.0, 0.0, 1.0); 3]);
            } else {
                t.attributes = None;
            }
            if normals {
                t.n = Some([bent; 3]);
            }
        }
        let mut s = scene("normal map", tris, vec![mat], lights.clone(), top_camera());
        s.images = vec![TextureImage { name: "normals".into(), width: 2, height: 2, texels: vec![texel; 4] }];
        s
    };
    let (mapped, explicit, flat) = (make(true, false), make(false, true), make(false, false));
    assert!(vkvcm::render::features::FeatureSet::new(&mapped, false).normal_maps);
    with_gpu(|gpu| {
        let reference = render_stats(&render_with(gpu, &explicit, Algorithm::Pt, 256), None);
        for (algo, iterations) in [(Algorithm::Pt, 256), (Algorithm::Bpt, 256)] {
            let st = render_stats(&render_with(gpu, &mapped, algo, iterations), None);
            let r = welch_test(&st, &reference, ALPHA).unwrap();
            assert!(r.passed(), "{algo:?} with the normal map vs vertex normals: {r}");
        }
        let st = render_stats(&render_with(gpu, &flat, Algorithm::Pt, 256), None);
        assert!(!welch_test(&st, &reference, ALPHA).unwrap().passed(), "the flat quad renders as the bent one");
    });
}

/// glTF emissiveTexture: a textured area light (emission 3 x the 4 x 4 test texture,
/// nearest filtering) 0.4 over a diffuse floor, the camera above at an angle (it sees
/// the floor and the light's unlit back), against the same light split into its 16
/// texels, each two triangles of constant emission (the texel's sRGB-decoded colour
/// times 3): an independent construction of the same radiance. Paths of at most 2
/// segments, so the floor's light is direct: pt's next-event estimation and its
/// BSDF-sampled hits of the light (weighted by MIS), light tracing's emission and bpt's
/// and vcm's connections each read the texture at their own point of the light. Every
/// estimator of the textured light agrees per pixel with pt of the split one; the light
/// without its texture (radiance 3 everywhere) does not. Sabotaged (the texture's u and v
/// swapped in emission_tint; the tint left out of light_emit) it fails.
#[test]
fn emissive_texture_modulates_area_lights_in_every_estimator() {
    let img = test_image();
    let strength = 3.0;
    let floor_mat = Material { name: "floor".into(), diffuse: Vec3::splat(0.8), ..Default::default() };
    let floor = {
        let corner = |u: f32, v: f32| Vec3::new(-1.5 + 3.0 * u, 0.0, -1.5 + 3.0 * v);
        let tri = |c: [(f32, f32); 3]| Triangle { p: c.map(|(u, v)| corner(u, v)), material: 0, ..Default::default() };
        vec![tri([(0.0, 0.0), (0.0, 1.0), (1.0, 1.0)]), tri([(0.0, 0.0), (1.0, 1.0), (1.0, 0.0)])]
    };
    // The light's rectangle [u0, u1] x [v0, v1] of texture space at height 0.4, facing
    // down (geometric normal -y), texture coordinates (u, v) at its point (u, v).
    let light_corner = |u: f32, v: f32| Vec3::new(-0.5 + u, 0.4, -0.5 + v);
    let light_quad = |u0: f32, u1: f32, v0: f32, v1: f32, material: u32, uv: bool| {
        rect(&light_corner, (u0, u1), (v0, v1), material, uv)
    };
    let cam = camera(Vec3::new(0.0, 2.5, 2.5), Vec3::new(0.0, -1.0, -1.0), Vec3::Y, 50.0);
    let textured = |with_texture: bool| {
        let emitter = Material {
            name: "emitter".into(),
            emission: Vec3::splat(strength),
            emissive_texture: with_texture.then_some(repeat_texture(Filter::Nearest)),
            ..Default::default()
        };
        let mut tris = floor.clone();
        tris.extend(light_quad(0.0, 1.0, 0.0, 1.0, 1, true));
        let mats = vec![floor_mat.clone(), emitter];
        let lights = common::scenes::area_lights(&tris, &mats);
        let mut s = scene("emissive texture", tris, mats, lights, cam.clone());
        s.images = vec![img.clone()];
        s
    };
    let split = {
        let mut tris = floor.clone();
        let mut mats = vec![floor_mat.clone()];
        for j in 0..4 {
            for i in 0..4 {
                let c = texel(&img, i, j).truncate() * strength;
                mats.push(Material { name: format!("texel {i} {j}"), emission: c, ..Default::default() });
                let (u0, v0) = (i as f32 / 4.0, j as f32 / 4.0);
                tris.extend(light_quad(u0, u0 + 0.25, v0, v0 + 0.25, mats.len() as u32 - 1, false));
            }
        }
        let lights = common::scenes::area_lights(&tris, &mats);
        scene("emissive texels", tris, mats, lights, cam.clone())
    };
    let (with, without) = (textured(true), textured(false));
    assert!(vkvcm::render::features::FeatureSet::new(&with, false).emissive_textures);
    with_gpu(|gpu| {
        let reference = render_stats(&render_with(gpu, &split, Algorithm::Pt, 512), None);
        for (algo, iterations) in [
            (Algorithm::Pt, 256),
            // Light tracing reaches the dim pixels at the floor's far edge rarely (a
            // pixel's few splats underestimate its variance at 256 iterations: the split
            // light fails there too), so it runs longer.
            (Algorithm::Lt, 2048),
            (Algorithm::Bpt, 256),
            (Algorithm::Vcm, 256),
        ] {
            let st = render_stats(&render_with(gpu, &with, algo, iterations), None);
            let r = welch_test(&st, &reference, ALPHA).unwrap();
            assert!(r.passed(), "{algo:?}: textured light vs its texels: {r}");
        }
        let st = render_stats(&render_with(gpu, &without, Algorithm::Pt, 256), None);
        assert!(
            !welch_test(&st, &reference, ALPHA).unwrap().passed(),
            "the untextured light renders as the textured one"
        );
    });
}

/// A 4 x 4 metallic-roughness image (linear values): G (roughness) 90, 145, 200 or 255
/// and B (metallic) 0, 30, 60 or 90, every pair once (so that a flip or transpose shows),
/// and R, which glTF leaves unused, different again.
fn metallic_roughness_image() -> TextureImage {
    let texels = (0..16)
        .map(|k| {
            let (i, j) = (k % 4, k / 4);
            [(255 - 16 * k) as u8, (90 + 55 * ((i + 2 * j) % 4)) as u8, (30 * ((3 * i + j) % 4)) as u8, 255]
        })
        .collect();
    TextureImage { name: "metallic-roughness".into(), width: 4, height: 4, texels }
}

/// glTF's metallicRoughnessTexture (glTF 2.0 section 3.9.2: roughness = roughnessFactor
/// x G, metallic = metallicFactor x B, linear texels) in every estimator. A floor (z = 0,
/// |x|, |y| <= 1.5) whose metallic and roughness come from a 4 x 4 texture and whose base
/// colour from the test image (sRGB), both nearest-filtered and repeated twice over it
/// by a texture transform, lit by a spot light from above whose cone misses the grey wall
/// behind the floor: the wall is lit only by the floor (paths of at most 3 segments). It
/// is compared with the same floor split into its 8 x 8 texel squares, each of the
/// constant material `Material::metallic_roughness(base x texel colour, metallic x B,
/// roughness x G)`: an independent construction of the same material field. pt reads the
/// texture at camera vertices, lt at the floor's light vertices it connects to the
/// camera, bpt and vcm also at the floor's stored light vertices they connect to the
/// wall's camera vertices (the spot is a point: the wall's light comes through next-event
/// estimation at the floor, these connections, or light tracing). Each estimator of the
/// textured floor agrees per pixel with bpt of the split floor (the generic kernels equal
/// the specialised ones on a metallic-roughness-textured scene: tests/render_features.rs);
/// the floor with the constant factors alone (the texture dropped) does not.
/// The texels make the floor far less metallic than its factors, so that the factors
/// alone reflect much less light onto the wall. The wall stands 0.3 off the floor: in a
/// corner light tracing's camera connections are heavy-tailed and its per-pixel variance
/// underestimated (lt failed against pt there even for a split floor).
///
/// Sabotaged, it fails (pixels failed of 576, worst |t| against a threshold near 5):
/// * roughness read from R instead of G: every estimator (126-138 pixels, |t| 50-112);
/// * the texels sRGB-decoded: every estimator (124-140 pixels, |t| 47-78);
/// * the light vertices' metallic and roughness not loaded (glsl/light_vertex_store.glsl, lv_load: the
///   factors alone at stored light vertices): bpt (138 pixels, |z| 16.5) and vcm (136,
///   17.1); pt and lt, which store none, pass;
/// * bsdf_sample's GGX width the material's, not the point's (its pdf no longer the one
///   bsdf_eval reports): only lt, barely (5 pixels, |z| 5.6). Here only light subpaths
///   scatter off the floor into paths that reach the camera; pt's continuations from it
///   find no light within 3 segments.
#[test]
fn metallic_roughness_texture_varies_the_lobes_in_every_estimator() {
    let base = Vec3::new(0.95, 0.85, 0.75);
    let (metallic, roughness) = (0.8, 0.9);
    let f0 = Vec3::splat(vkvcm::scene::GLTF_DIELECTRIC_F0);
    // Both textures twice over the floor: uv' = 2 uv.
    let texture = |image: u32| TextureRef {
        image,
        transform: [[2.0, 0.0, 0.0], [0.0, 2.0, 0.0]],
        ..repeat_texture(Filter::Nearest)
    };
    let (mr_img, colour_img) = (metallic_roughness_image(), test_image());
    // The floor's point (u, v) in [0, 1]^2 (its texture coordinates).
    let floor_corner = |u: f32, v: f32| Vec3::new(-1.5 + 3.0 * u, -1.5 + 3.0 * v, 0.0);
    // The grey wall (material 0) y = 1.5, 0.3 <= z <= 2.3, and the spot at height 2.2
    // pointing down, whose 30 degree cone lights only the floor (the wall is 39 degrees
    // off its axis or more); the camera sees the floor and the wall.
    let wall = Material { name: "wall".into(), diffuse: Vec3::splat(0.8), ..Default::default() };
    let wall_corner = |u: f32, v: f32| Vec3::new(-1.5 + 3.0 * u, 1.5, 0.3 + 2.0 * v);
    let spot = Light::Spot {
        position: Vec3::new(0.0, -0.3, 2.2),
        direction: Vec3::NEG_Z,
        intensity: Vec3::splat(10.0),
        cos_inner: 25f32.to_radians().cos(),
        cos_outer: 30f32.to_radians().cos(),
    };
    let cam = camera(Vec3::new(0.0, -3.2, 2.6), Vec3::new(0.0, 3.4, -2.1), Vec3::Z, 50.0);
    let make = |floor: Vec<Triangle>, materials: Vec<Material>| {
        let mut tris = rect(&wall_corner, (0.0, 1.0), (0.0, 1.0), 0, false);
        tris.extend(floor);
        let mut s = scene("metallic-roughness floor", tris, materials, vec![spot.clone()], cam.clone());
        s.images = vec![mr_img.clone(), colour_img.clone()];
        s
    };
    let textured = |with_texture: bool| {
        let mut floor = Material {
            name: "textured floor".into(),
            base_color_texture: Some(texture(1)),
            ..Material::metallic_roughness_textured(base, metallic, roughness, f0, texture(0))
        };
        if !with_texture {
            floor.metallic_roughness_texture = None;
        }
        make(rect(&floor_corner, (0.0, 1.0), (0.0, 1.0), 1, true), vec![wall.clone(), floor])
    };
    let split = {
        let mut materials = vec![wall.clone()];
        // Texel (i, j) of both images: the texel colour tints the base colour (it
        // multiplies the diffuse lobe and the metal's part of the GGX F0: the material of
        // the tinted base, as the dielectric F0 is grey), G and B scale the factors.
        for j in 0..4 {
            for i in 0..4 {
                let mr = mr_img.texels[j * 4 + i].map(|b| b as f32 / 255.0);
                let colour = texel(&colour_img, i as i32, j as i32).truncate();
                let mut m = Material::metallic_roughness(base * colour, metallic * mr[2], roughness * mr[1]);
                m.name = format!("texel {i} {j}");
                materials.push(m);
            }
        }
        // The floor's 8 x 8 squares (a texel each), material texel (i % 4, j % 4).
        let mut floor = Vec::new();
        for jj in 0..8 {
            for ii in 0..8 {
                let material = 1 + ((jj % 4) * 4 + ii % 4) as u32;
                let (u0, v0) = (ii as f32 / 8.0, jj as f32 / 8.0);
                floor.extend(rect(&floor_corner, (u0, u0 + 0.125), (v0, v0 + 0.125), material, false));
            }
        }
        make(floor, materials)
    };
    let (with, without) = (textured(true), textured(false));
    assert!(vkvcm::render::features::FeatureSet::new(&with, false).metallic_roughness_textures);
    assert!(!vkvcm::render::features::FeatureSet::new(&split, false).metallic_roughness_textures);
    // Pixels wholly on the floor or the wall: where a surface's edge crosses a pixel, few
    // of its samples see the dim wall, and their mean is too skewed for the z-test.
    let covered = common::primary_hit_mask(&split, W, H, |_| true);
    let run = |gpu: &Arc<Gpu>, scene: &Scene, algo: Algorithm, iterations: u64| {
        let mut s = RenderSettings::new(algo, W, H, Budget::Iterations(iterations));
        s.frame.max_path_length = 3;
        s.frame.seed = 31 + algo as u32;
        let out = render::render(gpu, scene, &s, None, &mut |_| {}).unwrap();
        assert_eq!(out.rejected_samples, 0, "{algo:?}: rejected samples");
        render_stats(&out, Some(&covered))
    };
    with_gpu(|gpu| {
        let reference = run(gpu, &split, Algorithm::Bpt, 4096);
        for (algo, iterations) in
            [(Algorithm::Pt, 2048), (Algorithm::Lt, 4096), (Algorithm::Bpt, 1024), (Algorithm::Vcm, 1024)]
        {
            let st = run(gpu, &with, algo, iterations);
            let r = welch_test(&st, &reference, ALPHA).unwrap();
            assert!(r.passed(), "{algo:?}: metallic-roughness texture vs its texels: {r}");
        }
        let st = run(gpu, &without, Algorithm::Pt, 512);
        assert!(
            !welch_test(&st, &reference, ALPHA).unwrap().passed(),
            "the floor without its metallic-roughness texture renders as the textured one"
        );
    });
}

/// z-up: a grey floor z = 0 lit only by a 1 x 1 emitting quad at z = 1 facing down whose
/// material is `lamp`; the camera looks down at both from the side.
fn floor_under_a_lamp(lamp: Material) -> Scene {
    let v = Vec3::new;
    let quad = |a: Vec3, b: Vec3, c: Vec3, d: Vec3, material: u32| {
        [[a, b, c], [a, c, d]].map(|p| Triangle { p, n: None, material, attributes: None })
    };
    let mut tris = Vec::new();
    tris.extend(quad(v(-2., -2., 0.), v(2., -2., 0.), v(2., 2., 0.), v(-2., 2., 0.), 0));
    tris.extend(quad(v(-0.5, -0.5, 1.), v(-0.5, 0.5, 1.), v(0.5, 0.5, 1.), v(0.5, -0.5, 1.), 1)); // normal -z
    let floor = Material { name: "floor".into(), diffuse: Vec3::splat(0.5), ..Default::default() };
    let materials = vec![floor, lamp];
    let lights = common::scenes::area_lights(&tris, &materials);
    scene("floor under a lamp", tris, materials, lights, camera(v(0., -3., 2.5), v(0., 3., -2.2), Vec3::Z, 50.0))
}

/// The means of `n` x `n` blocks of pixels, each block's value per iteration the mean of
/// its pixels' (independent paths, so its variance is the sum of theirs over n^4).
fn blocks(s: &PixelStats, n: u32) -> PixelStats {
    let (w, h) = (s.width / n, s.height / n);
    let mut mean = vec![[0.0; 3]; (w * h) as usize];
    let mut variance = vec![[0.0; 3]; (w * h) as usize];
    let k = (n * n) as f64;
    for y in 0..h * n {
        for x in 0..w * n {
            let (i, b) = ((y * s.width + x) as usize, ((y / n) * w + x / n) as usize);
            for c in 0..3 {
                mean[b][c] += s.mean[i][c] / k;
                variance[b][c] += s.variance[i][c] / (k * k);
            }
        }
    }
    PixelStats { width: w, height: h, count: s.count, mean, variance }
}

/// An emitting cut-out or blended surface emits where it is there: next-event
/// estimation's light samples and light subpaths' starting points are weighted by its
/// presence (glsl/textures.glsl, `emitter_presence`), as paths that hit it are by the
/// traversal's alpha test.
/// * A lamp cut away entirely (MASK, alpha 0.3 < cutoff 0.5) lights nothing: every pixel
///   of pt, lt and bpt is exactly 0 (without the presence weight next-event estimation
///   and light subpaths would light the floor).
/// * A blended lamp of alpha 0.4: pt with next-event estimation (presence-weighted light
///   samples) against pt without (only hits of the lamp, which the stochastic alpha test
///   thins), and lt and bpt against pt, per pixel.
#[test]
fn emitting_cut_outs_and_blended_lamps_emit_where_they_are() {
    let lamp = |alpha: f32, alpha_mode: AlphaMode| Material {
        name: "lamp".into(),
        emission: Vec3::splat(4.0),
        alpha,
        alpha_mode,
        ..Default::default()
    };
    let run = |gpu: &Arc<Gpu>, scene: &Scene, algo: Algorithm, nee: bool, iterations: u64| {
        let mut s = RenderSettings::new(algo, W, H, Budget::Iterations(iterations));
        s.frame.max_path_length = 4;
        s.frame.seed = 17 + algo as u32;
        s.nee = nee;
        render::render(gpu, scene, &s, None, &mut |_| {}).unwrap()
    };
    with_gpu(|gpu| {
        let cut_away = floor_under_a_lamp(lamp(0.3, AlphaMode::Mask { cutoff: 0.5 }));
        for algo in [Algorithm::Pt, Algorithm::Lt, Algorithm::Bpt] {
            let out = run(gpu, &cut_away, algo, true, 16);
            let lit = out.sum.iter().filter(|p| p.iter().any(|&c| c != 0.0)).count();
            assert_eq!(lit, 0, "{}: {lit} pixels lit by a lamp that is cut away", algo.name());
        }
        let blended = floor_under_a_lamp(lamp(0.4, AlphaMode::Blend));
        let pt = render_stats(&run(gpu, &blended, Algorithm::Pt, true, 1024), None);
        for (algo, nee, iterations) in
            [(Algorithm::Pt, false, 4096), (Algorithm::Lt, true, 2048), (Algorithm::Bpt, true, 1024)]
        {
            let other = render_stats(&run(gpu, &blended, algo, nee, iterations), None);
            // Without next-event estimation the far floor (the image's top rows) sees the
            // lamp edge-on: about 0.5 hits expected per pixel in 4096 samples, so a pixel
            // with none has variance 0 and fails against the estimate that samples the
            // lamp (seen: 2.5e-4 +- 4e-5 against 0). That comparison is made on 4x4
            // blocks of pixels, each with about 16x the hits.
            let (a, b) = if nee { (pt.clone(), other) } else { (blocks(&pt, 4), blocks(&other, 4)) };
            let r = welch_test(&a, &b, ALPHA).unwrap();
            assert!(r.passed(), "blended lamp: PT vs {} (nee {nee}): {r}", algo.name());
        }
    });
}
