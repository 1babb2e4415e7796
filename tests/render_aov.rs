//! AOVs (`--aov`, src/render/aov.rs, glsl/aov.glsl) against analytic values, per pixel,
//! on lavapipe with validation on.
//!
//! * A flat diffuse wall of known colour seen head-on, its shading normal tilted to a
//!   known direction: every sample of every pixel sees the wall, so the albedo is the
//!   wall's colour and the normal the tilted one (to float rounding), the position lies on
//!   the wall's plane at the pixel centre's point (to the jitter's mean: the pixel samples
//!   are uniform in the pixel and the map from raster to plane is affine), and the depth
//!   is the distance to it.
//! * A mirror at 45 degrees filling the view, reflecting a diffuse wall of another colour:
//!   the albedo is the wall's times the mirror's colour, the normal the wall's (facing the
//!   reflected rays), while depth and position are the mirror's (the first hit). el, which
//!   traces no further than the first hit, reports the mirror itself there.
//!
//! The estimators that trace camera paths are checked (el, pt, bpt, ppm, vcm; bpm's camera
//! kernel is vcm's without connections); lt is refused. Sabotage tried: aov_surface not
//! skipping delta surfaces (the mirror case fails: the mirror's colour), the normal taken
//! from the geometric normal (the tilted wall fails), no sample counted (albedo 0).

mod common;

use std::sync::Arc;

use common::scenes::{camera, scene};
use common::with_gpu;
use glam::Vec3;
use vkvcm::gpu::Gpu;
use vkvcm::render::aov::{AovImage, AovSet};
use vkvcm::render::{self, Algorithm, Budget, RenderSettings};
use vkvcm::scene::{Light, Material, Scene, Triangle};

const W: u32 = 16;
const H: u32 = 12;
const YFOV_DEG: f32 = 40.0;
const ITERATIONS: u64 = 16;
/// The wall's distance from the camera (flat-wall case).
const D: f32 = 3.0;
const WALL: Vec3 = Vec3::new(0.6, 0.5, 0.4);

fn quad(a: Vec3, b: Vec3, c: Vec3, d: Vec3, material: u32) -> Vec<Triangle> {
    vec![
        Triangle { p: [a, b, c], n: None, material, attributes: None },
        Triangle { p: [a, c, d], n: None, material, attributes: None },
    ]
}

/// A point light behind the camera, so that the scenes are lit (the AOVs do not depend on it).
fn lamp() -> Light {
    Light::Point { position: Vec3::new(0.0, 0.5, 1.0), intensity: Vec3::splat(5.0) }
}

/// The wall z = -D (normal +z, towards the camera), much larger than the view, with
/// shading normal `n`; the camera at the origin looks down -z.
fn wall_scene(n: Vec3) -> Scene {
    let m = Material { name: "wall".into(), diffuse: WALL, ..Default::default() };
    let s = 100.0;
    let mut tris = quad(Vec3::new(-s, -s, -D), Vec3::new(s, -s, -D), Vec3::new(s, s, -D), Vec3::new(-s, s, -D), 0);
    for t in &mut tris {
        t.n = Some([n; 3]);
    }
    let cam = camera(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, YFOV_DEG);
    scene("aov_wall", tris, vec![m], vec![lamp()], cam)
}

const MIRROR_COLOUR: Vec3 = Vec3::new(0.9, 0.8, 0.7);
const BEHIND: Vec3 = Vec3::new(0.2, 0.7, 0.3);

/// A mirror through (0, 0, -2) with normal (1, 0, 1)/sqrt 2 fills the view and reflects
/// the camera's rays towards +x, onto a diffuse wall x = 6 facing -x.
fn mirror_scene(mirror: Vec3) -> Scene {
    let mirror_m = Material { name: "mirror".into(), mirror, ..Default::default() };
    let wall_m = Material { name: "behind".into(), diffuse: BEHIND, ..Default::default() };
    let s = 50.0;
    // Spanned by (1, 0, -1)/sqrt 2 and +y; counter-clockwise seen from the normal's side.
    let c = Vec3::new(0.0, 0.0, -2.0);
    let u = Vec3::new(1.0, 0.0, -1.0).normalize() * s;
    let v = Vec3::Y * s;
    let mut tris = quad(c - u - v, c + u - v, c + u + v, c - u + v, 0);
    let n = (tris[0].p[1] - tris[0].p[0]).cross(tris[0].p[2] - tris[0].p[0]);
    assert!(n.dot(Vec3::new(1.0, 0.0, 1.0)) > 0.0, "the mirror faces the camera");
    let x = 6.0;
    tris.extend(quad(Vec3::new(x, -s, -s), Vec3::new(x, -s, s), Vec3::new(x, s, s), Vec3::new(x, s, -s), 1));
    let cam = camera(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, YFOV_DEG);
    scene("aov_mirror", tris, vec![mirror_m, wall_m], vec![lamp()], cam)
}

fn render_aov(gpu: &Arc<Gpu>, scene: &Scene, algo: Algorithm) -> AovImage {
    let mut s = RenderSettings::new(algo, W, H, Budget::Iterations(ITERATIONS));
    s.aov = AovSet::ALL;
    let out = render::render(gpu, scene, &s, None, &mut |_| {}).unwrap();
    assert_eq!(out.iterations, ITERATIONS);
    out.aov.expect("the AOVs asked for")
}

/// The estimators that trace camera paths, with a radius for the merging ones.
/// (bpm's camera kernel merges as vcm's does, without connections: left out for time.)
const ESTIMATORS: [Algorithm; 5] = [Algorithm::El, Algorithm::Pt, Algorithm::Bpt, Algorithm::Ppm, Algorithm::Vcm];

/// The point of the plane z = `-depth` seen through pixel (x, y)'s centre.
fn pixel_centre_on_plane(x: u32, y: u32, depth: f32) -> Vec3 {
    let f = 0.5 * H as f32 / (0.5 * YFOV_DEG.to_radians()).tan();
    let d = Vec3::new(x as f32 + 0.5 - 0.5 * W as f32, 0.5 * H as f32 - (y as f32 + 0.5), -f);
    d * (depth / f)
}

fn assert_close(what: &str, pixel: (u32, u32), got: Vec3, want: Vec3, tol: f32) {
    assert!(
        (got - want).abs().max_element() <= tol,
        "{what} at pixel {pixel:?}: got {got}, expected {want} (tolerance {tol})"
    );
}

#[test]
fn flat_wall_albedo_normal_depth_position() {
    // A shading normal 30 degrees off the wall's, so that a geometric normal would fail.
    let n = Vec3::new(0.5, 0.0, 0.75f32.sqrt());
    let scene = wall_scene(n);
    // Half a pixel's footprint on the wall: the mean of 16 uniform jitters is within it.
    let pixel_on_wall = D / (0.5 * H as f32 / (0.5 * YFOV_DEG.to_radians()).tan());
    with_gpu(|gpu| {
        for algo in ESTIMATORS {
            let img = render_aov(gpu, &scene, algo);
            for y in 0..H {
                for x in 0..W {
                    let i = (y * W + x) as usize;
                    let what = |w: &str| format!("{} {w}", algo.name());
                    assert_close(&what("albedo"), (x, y), Vec3::from(img.albedo[i]), WALL, 1e-5);
                    assert_close(&what("normal"), (x, y), Vec3::from(img.normal[i]), n, 1e-5);
                    let p = Vec3::from(img.position[i]);
                    assert_close(&what("position"), (x, y), p, pixel_centre_on_plane(x, y, D), 0.5 * pixel_on_wall);
                    assert!((p.z + D).abs() < 1e-4, "{} position at ({x}, {y}) off the wall: {p}", algo.name());
                    // The mean distance is within the pixel's spread of distances of |p|.
                    let z = img.depth[i];
                    assert!(
                        (z - p.length()).abs() < 1e-3 * D,
                        "{} depth at ({x}, {y}): {z}, |P| = {}",
                        algo.name(),
                        p.length()
                    );
                }
            }
        }
    });
}

#[test]
fn mirror_passes_to_the_wall_behind() {
    let white = mirror_scene(Vec3::ONE);
    let tinted = mirror_scene(MIRROR_COLOUR);
    let mirror_n = Vec3::new(1.0, 0.0, 1.0).normalize();
    with_gpu(|gpu| {
        // pt's throughput through a mirror is the mirror's colour exactly (no roulette at
        // the first vertices); the other estimators' roulette on light vertices' albedo
        // makes it exact only for a white mirror.
        let mut cases: Vec<(Algorithm, &Scene, Vec3)> = vec![(Algorithm::Pt, &tinted, MIRROR_COLOUR * BEHIND)];
        cases.extend(ESTIMATORS.iter().filter(|a| **a != Algorithm::El).map(|a| (*a, &white, BEHIND)));
        for (algo, scene, albedo) in cases {
            let img = render_aov(gpu, scene, algo);
            for y in 0..H {
                for x in 0..W {
                    let i = (y * W + x) as usize;
                    let what = |w: &str| format!("{} {w}", algo.name());
                    assert_close(&what("albedo"), (x, y), Vec3::from(img.albedo[i]), albedo, 1e-5);
                    assert_close(&what("normal"), (x, y), Vec3::from(img.normal[i]), Vec3::NEG_X, 1e-5);
                    // Depth and position: the mirror's (the first hit).
                    let p = Vec3::from(img.position[i]);
                    assert!((p - Vec3::new(0.0, 0.0, -2.0)).dot(mirror_n).abs() < 1e-4, "{} P = {p}", algo.name());
                    assert!(
                        (img.depth[i] - p.length()).abs() < 1e-2,
                        "{} depth {} |P| {}",
                        algo.name(),
                        img.depth[i],
                        p.length()
                    );
                }
            }
        }
        // el stops at the first hit: the mirror's colour and normal.
        let img = render_aov(gpu, &tinted, Algorithm::El);
        for i in 0..(W * H) as usize {
            assert_close("el albedo", (i as u32 % W, i as u32 / W), Vec3::from(img.albedo[i]), MIRROR_COLOUR, 1e-5);
            assert_close("el normal", (i as u32 % W, i as u32 / W), Vec3::from(img.normal[i]), mirror_n, 1e-5);
        }
    });
}

#[test]
fn lt_is_refused() {
    let mut s = RenderSettings::new(Algorithm::Lt, W, H, Budget::Iterations(1));
    s.aov = AovSet { albedo: true, ..Default::default() };
    let e = s.check().unwrap_err().to_string();
    assert!(e.contains("--aov") && e.contains("lt"), "{e}");
}

/// The layers are written into the render's EXR under the names tev and denoisers read,
/// and only those asked for; read back with the `exr` crate.
#[test]
fn exr_layer_names() {
    let scene = wall_scene(Vec3::Z);
    let dir = tempfile::tempdir().unwrap();
    with_gpu(|gpu| {
        let mut s = RenderSettings::new(Algorithm::Pt, W, H, Budget::Iterations(2));
        s.aov = "albedo,normal,depth".parse().unwrap();
        let out = render::render(gpu, &scene, &s, None, &mut |_| {}).unwrap();
        let path = dir.path().join("aov.exr");
        let p = render::saved::Provenance::new(&scene, "default", "test");
        render::saved::write_render_exr(&path, &out, &s, &p).unwrap();
        let img = exr::prelude::read_all_flat_layers_from_file(&path).unwrap();
        let layer = &img.layer_data[0];
        let names: Vec<String> = layer.channel_data.list.iter().map(|c| c.name.to_string()).collect();
        for want in ["R", "G", "B", "albedo.R", "albedo.G", "albedo.B", "N.X", "N.Y", "N.Z", "Z"] {
            assert!(names.iter().any(|n| n == want), "channel {want} missing from {names:?}");
        }
        assert!(!names.iter().any(|n| n.starts_with("P.")), "position was not asked for: {names:?}");
        // The values are those the render returned.
        let aov = out.aov.unwrap();
        let channel = |name: &str| -> Vec<f32> {
            let c = layer.channel_data.list.iter().find(|c| c.name.to_string() == name).unwrap();
            c.sample_data.values_as_f32().collect()
        };
        assert_eq!(channel("albedo.G"), aov.albedo.iter().map(|a| a[1]).collect::<Vec<_>>());
        assert_eq!(channel("N.Z"), aov.normal.iter().map(|n| n[2]).collect::<Vec<_>>());
        assert_eq!(channel("Z"), aov.depth);
        // The settings record which layers were asked for.
        let (_, _, meta) = vkvcm::image::read_exr_channels(&path).unwrap();
        assert!(meta.iter().any(|(k, v)| k == "vkvcm:aov" && v == "albedo,normal,depth"), "{meta:?}");
    });
}
