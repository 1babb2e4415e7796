//! The four reference scenes (scenes/*.gltf) against the numbers of docs/smallvcm.md 2-3.

use glam::Vec3;
use std::f32::consts::PI;
use vkvcm::scene::{self, Light, Material, Scene};

/// glTF y-up -> SmallVCM z-up: (X, Y, Z) -> (X, -Z, Y).
fn zup(v: Vec3) -> Vec3 {
    Vec3::new(v.x, -v.z, v.y)
}

fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
    (a - b).abs().max_element() <= tol
}

fn assert_close(a: Vec3, b: Vec3, tol: f32, what: &str) {
    assert!(close(a, b, tol), "{what}: {a} != {b} (tol {tol})");
}

/// Loads a built-in scene in the file's coordinates (the importer re-centres on the camera).
fn load(name: &str) -> Scene {
    let mut s = scene::load_named(name).unwrap_or_else(|e| panic!("{name}: {e:#}"));
    s.translate(glam::DVec3::from_array(s.report.origin).as_vec3());
    assert!(s.report.warnings.is_empty(), "{name}: {:?}", s.report.warnings);
    assert_eq!(s.report.degenerate_triangles, 0);
    s
}

const CB_MIN: Vec3 = Vec3::new(-1.27029, -1.25549, -1.28002);
const CB_MAX: Vec3 = Vec3::new(1.28975, 1.30455, 1.28002);

fn v(x: f32) -> Vec3 {
    Vec3::splat(x)
}

fn expected_materials() -> Vec<(Vec3, Vec3, f32, Vec3, f32)> {
    // (diffuse, phong, exponent, mirror, ior) of docs/smallvcm.md 2.4
    let z = Vec3::ZERO;
    vec![
        (z, z, 1.0, z, -1.0),
        (z, z, 1.0, z, -1.0),
        (v(0.1), v(0.7), 90.0, z, -1.0),
        (Vec3::new(0.156863, 0.803922, 0.172549), z, 1.0, z, -1.0),
        (Vec3::new(0.803922, 0.152941, 0.152941), z, 1.0, z, -1.0),
        (v(0.803922), z, 1.0, z, -1.0),
        (z, z, 1.0, v(1.0), -1.0),
        (z, z, 1.0, v(1.0), 1.6),
        (Vec3::new(0.156863, 0.172549, 0.803922), z, 1.0, z, -1.0),
    ]
}

fn check_materials(s: &Scene, emitting: bool) {
    let exp = expected_materials();
    assert_eq!(s.materials.len(), exp.len(), "{}", s.name);
    for (i, (m, e)) in s.materials.iter().zip(&exp).enumerate() {
        let Material { diffuse, phong, phong_exponent, mirror, ior, emission, .. } = m.clone();
        assert_eq!(diffuse, e.0, "{} material {i} diffuse", s.name);
        assert_eq!(phong, e.1, "{} material {i} phong", s.name);
        if phong != Vec3::ZERO {
            assert_eq!(phong_exponent, e.2, "{} material {i} exponent", s.name);
        }
        assert_eq!(mirror, e.3, "{} material {i} mirror", s.name);
        assert_eq!(ior, e.4, "{} material {i} ior", s.name);
        let want_emission = if emitting && i < 2 { v(25.033298) } else { Vec3::ZERO };
        assert_close(emission, want_emission, 1e-5, &format!("{} material {i} emission", s.name));
    }
}

fn check_box(s: &Scene, light_box: bool) {
    let n_tris = if light_box { 20 } else { 10 };
    assert_eq!(s.triangles.len(), n_tris, "{}", s.name);
    // Bounding box of the triangles, back in z-up, equals the Cornell box corners.
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for t in &s.triangles {
        for p in t.p {
            lo = lo.min(zup(p));
            hi = hi.max(zup(p));
        }
    }
    assert_close(lo, CB_MIN, 1e-5, "bbox min");
    assert_close(hi, CB_MAX, 1e-5, "bbox max");
    let (c, r) = s.bounding_sphere();
    assert!((r - 2.21706).abs() <= 1e-5, "{}: bounding radius {r}", s.name);
    assert_close(zup(c), Vec3::new(0.00973, 0.02453, 0.0), 1e-5, "bounding centre");
    let (blo, bhi) = s.bounds();
    assert_close(zup(blo).min(zup(bhi)), CB_MIN, 1e-5, "bounds()");

    // Materials per face and orientation: Cornell faces look into the box, light-box sides
    // look out of the light box, its bottom looks down.
    let centre = (CB_MIN + CB_MAX) * 0.5;
    let mut faces = std::collections::BTreeMap::new();
    for t in &s.triangles {
        let p = t.p.map(zup);
        let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize();
        let g = (p[0] + p[1] + p[2]) / 3.0;
        let in_light_box = p.iter().all(|q| q.x.abs() <= 0.25 + 1e-6 && q.y.abs() <= 0.25 + 1e-6 && q.z >= 1.26);
        if in_light_box {
            if p.iter().all(|q| (q.z - 1.26002).abs() < 1e-6) {
                assert_close(n, Vec3::NEG_Z, 1e-6, "light-box bottom faces down");
                *faces.entry("lb_bottom").or_insert(0) += 1;
            } else {
                let out = g - Vec3::new(0.0, 0.0, g.z);
                assert!(n.dot(out) > 0.0 && n.z.abs() < 1e-6, "light-box side faces out: {n}");
                assert_eq!(t.material, 5, "light-box sides are white");
                *faces.entry("lb_side").or_insert(0) += 1;
            }
            continue;
        }
        assert!(n.dot(centre - g) > 0.0, "{}: wall normal {n} at {g} does not face into the box", s.name);
        let (face, mat) = if p.iter().all(|q| (q.z - CB_MIN.z).abs() < 1e-6) {
            ("floor", 2)
        } else if p.iter().all(|q| (q.z - CB_MAX.z).abs() < 1e-6) {
            ("ceiling", 5)
        } else if p.iter().all(|q| (q.y - CB_MAX.y).abs() < 1e-6) {
            ("back", 8)
        } else if p.iter().all(|q| (q.x - CB_MIN.x).abs() < 1e-6) {
            ("left", 3)
        } else if p.iter().all(|q| (q.x - CB_MAX.x).abs() < 1e-6) {
            ("right", 4)
        } else {
            panic!("{}: triangle {p:?} is on no Cornell face", s.name)
        };
        assert_eq!(t.material, mat, "{}: {face} material", s.name);
        assert!(t.n.is_none());
        *faces.entry(face).or_insert(0) += 1;
    }
    for f in ["floor", "ceiling", "back", "left", "right"] {
        assert_eq!(faces.get(f), Some(&2), "{}: face {f} (no front wall)", s.name);
    }
    if light_box {
        assert_eq!(faces.get("lb_side"), Some(&8));
        assert_eq!(faces.get("lb_bottom"), Some(&2));
    } else {
        assert_eq!(faces.get("lb_side"), None);
    }
}

fn check_small_spheres(s: &Scene) {
    assert_eq!(s.spheres.len(), 2, "{}", s.name);
    assert_close(zup(s.spheres[0].center), Vec3::new(-0.538850, 0.024530, -0.780020), 1e-5, "mirror sphere");
    assert_eq!(s.spheres[0].radius, 0.5);
    assert_eq!(s.spheres[0].material, 6);
    assert_close(zup(s.spheres[1].center), Vec3::new(0.558310, 0.024530, -0.780020), 1e-5, "glass sphere");
    assert_eq!(s.spheres[1].radius, 0.5);
    assert_eq!(s.spheres[1].material, 7);
}

fn check_camera(s: &Scene) {
    let c = &s.camera;
    assert_close(zup(c.position), Vec3::new(-0.0439815, -4.12529, 0.222539), 1e-6, "camera position");
    assert_close(zup(c.forward), Vec3::new(0.00688625, 0.998505, -0.0542161), 1e-5, "camera forward");
    assert_close(zup(c.up), Vec3::new(3.73896e-4, 0.0542148, 0.998529), 1e-5, "camera up");
    assert!((c.forward.length() - 1.0).abs() < 1e-6 && c.forward.dot(c.up).abs() < 1e-6);
    assert!((c.yfov - PI / 4.0).abs() < 1e-7, "yfov {}", c.yfov);
}

#[test]
fn scene0_gbs_s_sun() {
    for name in ["gbs_s", "default", "0"] {
        let s = load(name);
        assert_eq!(s.name, "gbs_s");
        check_box(&s, true);
        check_small_spheres(&s);
        check_materials(&s, false);
        check_camera(&s);
        assert_eq!(s.lights.len(), 1);
        let Light::Directional { direction, irradiance } = s.lights[0] else { panic!("{:?}", s.lights) };
        assert_close(irradiance, Vec3::new(10.0, 4.0, 0.0), 1e-6, "sun irradiance");
        assert_close(zup(direction), Vec3::new(-0.485071, 0.727607, -0.485071), 1e-5, "sun direction");
    }
}

#[test]
fn scene1_glm_c_area() {
    let s = load("glm_c");
    check_box(&s, true);
    check_materials(&s, true);
    check_camera(&s);
    assert_eq!(s.spheres.len(), 1);
    assert_close(zup(s.spheres[0].center), Vec3::new(0.009730, 0.024530, -0.480020), 1e-5, "large sphere");
    assert_eq!(s.spheres[0].radius, 0.8);
    assert_eq!(s.spheres[0].material, 6);
    assert_eq!(s.lights.len(), 2);
    let mut area = 0.0;
    let mut power = Vec3::ZERO;
    for (k, l) in s.lights.iter().enumerate() {
        let Light::Area { triangle, radiance } = *l else { panic!("{l:?}") };
        let t = &s.triangles[triangle as usize];
        assert_eq!(t.material, k as u32, "light k uses material k");
        let n = (t.p[1] - t.p[0]).cross(t.p[2] - t.p[0]);
        assert_close(zup(n.normalize()), Vec3::NEG_Z, 1e-6, "emitter faces down");
        assert!(t.p.iter().all(|p| (zup(*p).z - 1.26002).abs() < 1e-6));
        let a = 0.5 * n.length();
        assert!((a - 0.125).abs() < 1e-6, "triangle area {a}");
        area += a;
        power += PI * radiance * a;
        assert_close(radiance, v(25.033299), 1e-5, "radiance");
    }
    assert!((area - 0.25).abs() < 1e-6);
    assert_close(power, v(19.661), 1e-3, "area light power");
}

#[test]
fn scene2_gbs_p_point() {
    let s = load("gbs_p");
    check_box(&s, false);
    check_small_spheres(&s);
    check_materials(&s, false);
    check_camera(&s);
    assert_eq!(s.lights.len(), 1);
    let Light::Point { position, intensity } = s.lights[0] else { panic!("{:?}", s.lights) };
    assert_close(zup(position), Vec3::new(0.0, -0.5, 1.0), 1e-7, "point position");
    assert_close(intensity, v(5.570423), 1e-6, "point intensity");
    assert_close(intensity * 4.0 * PI, v(70.0), 1e-4, "point power");
}

#[test]
fn scene3_gbs_b_background() {
    let s = load("gbs_b");
    check_box(&s, true);
    check_small_spheres(&s);
    check_materials(&s, false);
    check_camera(&s);
    assert_eq!(s.lights.len(), 1);
    let Light::Background { radiance } = s.lights[0] else { panic!("{:?}", s.lights) };
    assert_eq!(radiance, Vec3::new(135.0 / 255.0, 206.0 / 255.0, 250.0 / 255.0));
    assert_close(radiance, Vec3::new(0.529412, 0.807843, 0.980392), 1e-6, "background");
}

#[test]
fn committed_scenes_match_the_generator() {
    let dir = tempfile::tempdir().unwrap();
    let written = scene::reference::write_reference_scenes(dir.path()).unwrap();
    assert_eq!(written.len(), 4);
    let committed = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    for path in written {
        let name = path.file_name().unwrap();
        let fresh = std::fs::read(&path).unwrap();
        let old =
            std::fs::read(committed.join(name)).unwrap_or_else(|e| panic!("scenes/{}: {e}", name.to_string_lossy()));
        assert!(
            fresh == old,
            "scenes/{} differs from the generator's output: run `cargo run --example make_reference_scenes`",
            name.to_string_lossy()
        );
        // The files are self-contained: they load from a folder holding nothing else.
        let alone = tempfile::tempdir().unwrap();
        let copy = alone.path().join(name);
        std::fs::write(&copy, &old).unwrap();
        scene::load(&copy).unwrap();
    }
}

#[test]
fn builtin_names() {
    assert_eq!(scene::builtin_name("default"), Some("gbs_s"));
    assert_eq!(scene::builtin_name("3"), Some("gbs_b"));
    assert_eq!(scene::builtin_name("glm_c"), Some("glm_c"));
    assert_eq!(scene::builtin_name("nope"), None);
    for n in scene::BUILTIN_SCENES {
        assert!(scene::builtin_path(n).unwrap().ends_with(format!("scenes/{n}.gltf")));
    }
    let e = scene::load_named("no_such_scene").unwrap_err().to_string();
    assert!(e.contains("no_such_scene") && e.contains("gbs_s"), "{e}");
}
