//! glTF importer tests on small hand-written files.

mod common;

use glam::Vec3;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use vkvcm::scene::{self, Light, LoadOptions, Scene};

const S: f32 = std::f32::consts::FRAC_1_SQRT_2;

/// A small glTF: node 0 holds mesh 0 (one primitive), node 1 a perspective camera.
/// Buffer 0 is `data.bin`: positions, then normals (if any), then indices (if any).
struct Doc {
    json: Value,
    bin: Vec<u8>,
}

impl Doc {
    fn new(positions: &[[f32; 3]], normals: Option<&[[f32; 3]]>, indices: Option<(&[u32], u32)>) -> Doc {
        let mut bin = Vec::new();
        let mut accessors = Vec::new();
        let mut views = Vec::new();
        let mut push_f32 = |data: &[[f32; 3]], bin: &mut Vec<u8>| {
            let offset = bin.len();
            for p in data {
                for x in p {
                    bin.extend_from_slice(&x.to_le_bytes());
                }
            }
            // min/max over the finite coordinates (JSON has no NaN/Inf).
            let mut lo = [f32::MAX; 3];
            let mut hi = [f32::MIN; 3];
            for p in data {
                for k in 0..3 {
                    if p[k].is_finite() {
                        lo[k] = lo[k].min(p[k]);
                        hi[k] = hi[k].max(p[k]);
                    }
                }
            }
            views.push(json!({"buffer": 0, "byteOffset": offset, "byteLength": bin.len() - offset}));
            accessors.push(json!({"bufferView": views.len() - 1, "componentType": 5126, "count": data.len(), "type": "VEC3", "min": lo, "max": hi}));
            accessors.len() - 1
        };
        let pos = push_f32(positions, &mut bin);
        let mut attributes = json!({ "POSITION": pos });
        if let Some(n) = normals {
            attributes["NORMAL"] = json!(push_f32(n, &mut bin));
        }
        let mut prim = json!({ "attributes": attributes });
        if let Some((idx, ctype)) = indices {
            let offset = bin.len();
            for &i in idx {
                match ctype {
                    5121 => bin.push(i as u8),
                    5123 => bin.extend_from_slice(&(i as u16).to_le_bytes()),
                    _ => bin.extend_from_slice(&i.to_le_bytes()),
                }
            }
            let len = bin.len() - offset;
            while !bin.len().is_multiple_of(4) {
                bin.push(0);
            }
            views.push(json!({"buffer": 0, "byteOffset": offset, "byteLength": len}));
            accessors.push(
                json!({"bufferView": views.len() - 1, "componentType": ctype, "count": idx.len(), "type": "SCALAR"}),
            );
            prim["indices"] = json!(accessors.len() - 1);
        }
        let json = json!({
            "asset": {"version": "2.0"},
            "scene": 0,
            "scenes": [{"nodes": [0, 1]}],
            "nodes": [
                {"name": "geometry", "mesh": 0},
                {"name": "cam", "camera": 0, "translation": [0.0, 0.0, 5.0]},
            ],
            "cameras": [{"name": "main", "type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.01}}],
            "meshes": [{"primitives": [prim]}],
            "accessors": accessors,
            "bufferViews": views,
            "buffers": [{"byteLength": bin.len(), "uri": "data.bin"}],
        });
        Doc { json, bin }
    }

    fn triangle() -> Doc {
        Doc::new(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], None, None)
    }

    /// Writes `scene.gltf` and `data.bin` into `dir`.
    fn write(&self, dir: &Path) -> PathBuf {
        std::fs::write(dir.join("data.bin"), &self.bin).unwrap();
        let path = dir.join("scene.gltf");
        std::fs::write(&path, serde_json::to_vec_pretty(&self.json).unwrap()).unwrap();
        path
    }

    fn load(&self) -> anyhow::Result<Scene> {
        let dir = tempfile::tempdir().unwrap();
        load(&self.write(dir.path()))
    }

    /// The same document as a GLB: buffer 0 becomes the BIN chunk.
    fn glb(&self) -> Vec<u8> {
        let mut j = self.json.clone();
        j["buffers"][0].as_object_mut().unwrap().remove("uri");
        let mut js = serde_json::to_vec(&j).unwrap();
        while !js.len().is_multiple_of(4) {
            js.push(b' ');
        }
        let mut bin = self.bin.clone();
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        let total = 12 + 8 + js.len() + 8 + bin.len();
        let mut out = Vec::new();
        out.extend_from_slice(b"glTF");
        out.extend_from_slice(&2u32.to_le_bytes());
        out.extend_from_slice(&(total as u32).to_le_bytes());
        out.extend_from_slice(&(js.len() as u32).to_le_bytes());
        out.extend_from_slice(b"JSON");
        out.extend_from_slice(&js);
        out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&bin);
        out
    }
}

/// Loads `path` and moves it back to the file's coordinates: the importer re-centres
/// scenes on the camera (`LoadReport::origin`), these tests state positions as written.
fn load(path: &Path) -> anyhow::Result<Scene> {
    load_with(path, &LoadOptions::default())
}

fn load_with(path: &Path, options: &LoadOptions) -> anyhow::Result<Scene> {
    let mut s = scene::load_with(path, options)?;
    s.translate(glam::DVec3::from_array(s.report.origin).as_vec3());
    Ok(s)
}

#[test]
fn scenes_are_recentred_on_the_camera_in_f64() {
    // A triangle 1e5 from the origin, 1 unit in front of the camera: in f32 world
    // coordinates its vertices would round to multiples of 2^-7; camera-relative they
    // keep their exact offsets.
    let far = 100_000.0f64;
    let mut d = Doc::new(&[[0.0, 0.0, 0.0], [0.001, 0.0, 0.0], [0.0, 0.001, 0.0]], None, None);
    d.json["nodes"][0]["translation"] = json!([far, 0.0, 0.0]);
    d.json["nodes"][1]["translation"] = json!([far, 0.0, 1.0]);
    let dir = tempfile::tempdir().unwrap();
    let s = scene::load(&d.write(dir.path())).unwrap();
    assert_eq!(s.report.origin, [far, 0.0, 1.0]);
    assert_eq!(s.camera.position, Vec3::ZERO);
    assert_eq!(s.triangles[0].p[0], Vec3::new(0.0, 0.0, -1.0));
    assert_eq!(s.triangles[0].p[1], Vec3::new(0.001, 0.0, -1.0));
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).abs().max_element() < 1e-5
}

fn assert_close(a: Vec3, b: Vec3) {
    assert!(close(a, b), "{a} != {b}");
}

fn err_of(r: anyhow::Result<Scene>) -> String {
    match r {
        Ok(_) => panic!("expected an error"),
        Err(e) => format!("{e:#}"),
    }
}

#[test]
fn node_transform_hierarchy() {
    let mut d = Doc::triangle();
    // Parent node 2: T(1,2,3) R_y(90 deg) S(2) with the mesh node as child, which adds T(0,0,1).
    d.json["nodes"][0]["translation"] = json!([0.0, 0.0, 1.0]);
    d.json["nodes"].as_array_mut().unwrap().push(json!({
        "translation": [1.0, 2.0, 3.0], "rotation": [0.0, S, 0.0, S], "scale": [2.0, 2.0, 2.0], "children": [0]
    }));
    d.json["scenes"][0]["nodes"] = json!([2, 1]);
    // Camera by matrix (column-major): R_y(90 deg), then translation (5, 0, 0).
    d.json["nodes"][1] = json!({"camera": 0, "matrix": [0.0, 0.0, -1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 5.0, 0.0, 0.0, 1.0]});
    let s = d.load().unwrap();
    assert_eq!(s.triangles.len(), 1);
    let p = s.triangles[0].p;
    assert_close(p[0], Vec3::new(3.0, 2.0, 3.0));
    assert_close(p[1], Vec3::new(3.0, 2.0, 1.0));
    assert_close(p[2], Vec3::new(3.0, 4.0, 3.0));
    assert_close(s.camera.position, Vec3::new(5.0, 0.0, 0.0));
    assert_close(s.camera.forward, Vec3::new(-1.0, 0.0, 0.0));
    assert_close(s.camera.up, Vec3::Y);
    assert_eq!(s.camera.yfov, 0.5);
    assert!(s.report.warnings.iter().all(|w| w.contains("no light")), "{:?}", s.report.warnings);
}

#[test]
fn indexed_and_non_indexed_agree() {
    let quad = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
    let idx = [0u32, 1, 2, 2, 3, 0];
    let flat: Vec<[f32; 3]> = idx.iter().map(|&i| quad[i as usize]).collect();
    let reference = Doc::new(&flat, None, None).load().unwrap();
    assert_eq!(reference.triangles.len(), 2);
    assert_eq!(reference.triangles[1].p[1], Vec3::new(0.0, 1.0, 0.0));
    for ctype in [5121, 5123, 5125] {
        let s = Doc::new(&quad, None, Some((&idx, ctype))).load().unwrap();
        assert_eq!(s.triangles, reference.triangles, "component type {ctype}");
    }
}

#[test]
fn strips_and_fans() {
    let quad = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]];
    let mut d = Doc::new(&quad, None, None);
    d.json["meshes"][0]["primitives"][0]["mode"] = json!(5); // TRIANGLE_STRIP
    let s = d.load().unwrap();
    assert_eq!(s.triangles.len(), 2);
    for t in &s.triangles {
        let n = (t.p[1] - t.p[0]).cross(t.p[2] - t.p[0]);
        assert!(n.z > 0.0, "strip keeps the winding: {n}");
    }
    let fan = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
    let mut d = Doc::new(&fan, None, None);
    d.json["meshes"][0]["primitives"][0]["mode"] = json!(6); // TRIANGLE_FAN
    let s = d.load().unwrap();
    assert_eq!(s.triangles.len(), 2);
    assert_eq!(s.triangles[1].p, [Vec3::new(1.0, 1.0, 0.0), Vec3::new(0.0, 1.0, 0.0), Vec3::ZERO]);
}

#[test]
fn normals_use_the_inverse_transpose() {
    let n = [S, S, 0.0];
    let mut d = Doc::new(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], Some(&[n, n, n]), None);
    d.json["nodes"][0]["scale"] = json!([2.0, 1.0, 1.0]);
    let s = d.load().unwrap();
    let ns = s.triangles[0].n.expect("normals");
    let want = Vec3::new(0.5, 1.0, 0.0).normalize();
    for v in ns {
        assert_close(v, want);
    }
    assert_close(s.triangles[0].p[1], Vec3::new(2.0, 0.0, 0.0));
    // Without NORMAL there are no shading normals.
    assert!(Doc::triangle().load().unwrap().triangles[0].n.is_none());
}

#[test]
fn mirroring_transform_keeps_the_facing_side() {
    let mut d = Doc::triangle();
    d.json["nodes"][0]["scale"] = json!([-1.0, 1.0, 1.0]);
    let s = d.load().unwrap();
    let t = &s.triangles[0];
    let n = (t.p[1] - t.p[0]).cross(t.p[2] - t.p[0]).normalize();
    assert_close(n, Vec3::Z);
    assert!(t.p.contains(&Vec3::new(-1.0, 0.0, 0.0)));
}

#[test]
fn degenerate_triangles_are_counted_and_skipped() {
    let nan = f32::NAN;
    let inf = f32::INFINITY;
    let pos = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0], // good
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [2.0, 0.0, 0.0], // collinear
        [0.0, 0.0, 0.0],
        [0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0], // repeated vertex
        [nan, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0], // NaN
        [0.0, 0.0, 0.0],
        [inf, 0.0, 0.0],
        [0.0, 1.0, 0.0], // Inf
    ];
    let d = Doc::new(&pos, None, None);
    let s = d.load().unwrap();
    assert_eq!(s.triangles.len(), 1);
    assert_eq!(s.report.degenerate_triangles, 4);
    assert_eq!(s.triangles[0].p[2], Vec3::Y);
}

#[test]
fn out_of_range_index_names_the_accessor() {
    let d = Doc::new(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], None, Some((&[0, 1, 7], 5123)));
    let e = err_of(d.load());
    assert!(e.contains("scene.gltf"), "{e}");
    assert!(e.contains("index accessor 1") && e.contains("7") && e.contains("mesh 0 primitive 0"), "{e}");

    // An accessor that reaches past its buffer view.
    let mut d = Doc::triangle();
    d.json["accessors"][0]["count"] = json!(4);
    let e = err_of(d.load());
    assert!(e.contains("accessor 0") && e.contains("buffer view 0"), "{e}");

    // A primitive that refers to an accessor that does not exist.
    let mut d = Doc::triangle();
    d.json["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(9);
    let e = err_of(d.load());
    assert!(e.contains("meshes[0].primitives[0].attributes") && e.contains("POSITION"), "{e}");

    // A buffer view past the end of the buffer file.
    let mut d = Doc::triangle();
    d.json["bufferViews"][0]["byteOffset"] = json!(4);
    let e = err_of(d.load());
    assert!(e.contains("buffer view 0") && e.contains("exceeds buffer 0"), "{e}");
}

#[test]
fn missing_buffer_file_is_named() {
    let mut d = Doc::triangle();
    d.json["buffers"][0]["uri"] = json!("nothere.bin");
    let e = err_of(d.load());
    assert!(e.contains("nothere.bin") && e.contains("scene.gltf") && e.contains("buffer 0"), "{e}");

    let mut d = Doc::triangle();
    d.json["buffers"][0]["byteLength"] = json!(1000);
    let e = err_of(d.load());
    assert!(e.contains("buffer 0") && e.contains("1000"), "{e}");
}

#[test]
fn uris_must_stay_inside_the_scene_folder() {
    let dir = tempfile::tempdir().unwrap();
    let sub = dir.path().join("sub");
    std::fs::create_dir(&sub).unwrap();
    let d = Doc::triangle();
    // The buffer exists outside the folder, so a refusal is not just "file missing".
    std::fs::write(dir.path().join("data.bin"), &d.bin).unwrap();
    let outside = dir.path().join("data.bin").canonicalize().unwrap();
    for (uri, why) in [
        ("../data.bin".to_string(), ".."),
        ("./x/../../data.bin".to_string(), ".."),
        ("%2E%2E/data.bin".to_string(), ".."),
        (outside.to_string_lossy().into_owned(), "absolute"),
        (format!("file://{}", outside.display()), "scheme"),
    ] {
        let mut d = Doc::triangle();
        d.json["buffers"][0]["uri"] = json!(uri);
        let path = sub.join("scene.gltf");
        std::fs::write(&path, serde_json::to_vec(&d.json).unwrap()).unwrap();
        let e = err_of(load(&path));
        assert!(e.contains(why) && e.contains("buffer 0"), "{uri}: {e}");
    }
    // A subfolder of the scene's folder is fine.
    let mut d = Doc::triangle();
    d.json["buffers"][0]["uri"] = json!("bufs/my%20data.bin");
    std::fs::create_dir(sub.join("bufs")).unwrap();
    std::fs::write(sub.join("bufs/my data.bin"), &d.bin).unwrap();
    let path = sub.join("scene.gltf");
    std::fs::write(&path, serde_json::to_vec(&d.json).unwrap()).unwrap();
    assert_eq!(load(&path).unwrap().triangles.len(), 1);
}

#[test]
fn embedded_data_uri() {
    let mut d = Doc::triangle();
    d.json["buffers"][0]["uri"] = json!(scene::encode_data_uri(&d.bin));
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("embedded.gltf");
    std::fs::write(&path, serde_json::to_vec(&d.json).unwrap()).unwrap();
    let s = load(&path).unwrap();
    assert_eq!(s.triangles, Doc::triangle().load().unwrap().triangles);
    assert_eq!(s.name, "embedded");
    d.json["buffers"][0]["uri"] = json!("data:application/octet-stream;base64,@@@@");
    std::fs::write(&path, serde_json::to_vec(&d.json).unwrap()).unwrap();
    assert!(err_of(load(&path)).contains("base64"));
}

#[test]
fn glb_round_trip() {
    let n = [0.0, 0.0, 1.0];
    let d = Doc::new(
        &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]],
        Some(&[n, n, n, n]),
        Some((&[0, 1, 2, 2, 1, 3], 5123)),
    );
    let from_gltf = d.load().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scene.glb");
    std::fs::write(&path, d.glb()).unwrap();
    let from_glb = load(&path).unwrap();
    assert_eq!(from_glb.triangles.len(), 2);
    assert_eq!(from_glb.triangles, from_gltf.triangles);
    assert_eq!(from_glb.camera, from_gltf.camera);

    // A truncated GLB is an error, not a panic.
    let glb = d.glb();
    std::fs::write(&path, &glb[..glb.len() - 10]).unwrap();
    let e = err_of(load(&path));
    assert!(e.contains("scene.glb") && e.contains("GLB"), "{e}");
}

#[test]
fn unsupported_features_warn_once_per_kind() {
    let mut d = Doc::triangle();
    d.json["extensionsUsed"] = json!(["KHR_materials_unlit", "VKVCM_spheres", "KHR_lights_punctual"]);
    d.json["images"] = json!([{"uri": "never_loaded.png"}]);
    d.json["textures"] = json!([{"source": 0}]);
    // Glass does not read metallicRoughnessTexture (its image is never loaded).
    let glass = json!({"KHR_materials_transmission": {"transmissionFactor": 1.0}});
    d.json["materials"] = json!([
        {"name": "a", "pbrMetallicRoughness": {"metallicFactor": 0.0, "metallicRoughnessTexture": {"index": 0}}, "extensions": glass},
        {"name": "b", "pbrMetallicRoughness": {"metallicFactor": 0.0, "metallicRoughnessTexture": {"index": 0}}, "extensions": glass},
    ]);
    d.json["meshes"][0]["primitives"][0]["material"] = json!(0);
    let mut lines = d.json["meshes"][0]["primitives"][0].clone();
    lines["mode"] = json!(1);
    d.json["meshes"][0]["primitives"].as_array_mut().unwrap().push(lines);
    let s = d.load().unwrap();
    let w = &s.report.warnings;
    let count = |needle: &str| w.iter().filter(|x| x.contains(needle)).count();
    assert_eq!(count("KHR_materials_unlit"), 1, "{w:?}");
    // (An unsupported extension in extensionsRequired is an error: tests/malformed/.)
    assert_eq!(count("VKVCM_spheres"), 0, "{w:?}");
    assert_eq!(count("KHR_lights_punctual"), 0, "{w:?}");
    assert_eq!(count("textures are not supported"), 1, "{w:?}");
    assert!(w.iter().any(|x| x.contains("textures") && x.contains("2 occurrences")), "{w:?}");
    assert_eq!(count("LINES"), 1, "{w:?}");
    assert_eq!(s.triangles.len(), 1, "the LINES primitive is skipped");
}

/// KHR_materials_transmission (+ KHR_materials_ior): glass of the material's roughness:
/// smooth at roughness 0, the rough dielectric (GGX alpha = roughness^2) above; the base
/// colour tints the transmitted part (Material::transmission). Partial transmission t and
/// metallic m make glass of weight w = (1 - m) t beside the metallic/roughness lobes of
/// metallic m / (1 - w) (glsl/bsdf.glsl, "Partial transmission"); metallic 1 is a metal.
/// None of it warns.
#[test]
fn transmission_is_smooth_or_rough_glass() {
    let mut d = Doc::triangle();
    let t =
        |f: f64| json!({"KHR_materials_transmission": {"transmissionFactor": f}, "KHR_materials_ior": {"ior": 1.4}});
    let pbr = |b: f64, r: f64, metallic: f64| json!({"baseColorFactor": [1.0, b, 1.0, 1.0], "metallicFactor": metallic, "roughnessFactor": r});
    d.json["materials"] = json!([
        {"name": "smooth", "pbrMetallicRoughness": pbr(1.0, 0.0, 0.0), "extensions": t(1.0)},
        {"name": "rough", "pbrMetallicRoughness": pbr(1.0, 0.3, 0.0), "extensions": t(1.0)},
        {"name": "tinted", "pbrMetallicRoughness": pbr(0.5, 0.5, 0.0), "extensions": t(1.0)},
        {"name": "default_roughness", "pbrMetallicRoughness": {"metallicFactor": 0.0},
         "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0}}},
        {"name": "partial", "pbrMetallicRoughness": pbr(0.5, 0.5, 0.0), "extensions": t(0.5)},
        {"name": "partial_metal", "pbrMetallicRoughness": pbr(0.5, 0.0, 0.2), "extensions": t(0.5)},
        {"name": "half_metal", "pbrMetallicRoughness": pbr(0.5, 0.5, 0.5), "extensions": t(1.0)},
        {"name": "metal", "pbrMetallicRoughness": pbr(0.5, 0.5, 1.0), "extensions": t(1.0)},
    ]);
    let s = d.load().unwrap();
    let m = &s.materials;
    for g in m.iter().take(4) {
        assert_eq!((g.mirror, g.diffuse, g.glossy), (Vec3::ONE, Vec3::ZERO, Vec3::ZERO), "{}", g.name);
        assert_eq!((g.glass_weight, g.lobes_weight(), g.has_partial_transmission()), (1.0, 0.0, false), "{}", g.name);
    }
    assert_eq!((m[0].ior, m[0].dielectric_roughness, m[0].is_rough_dielectric()), (1.4, 0.0, false));
    assert_eq!((m[1].ior, m[1].dielectric_roughness, m[1].is_rough_dielectric()), (1.4, 0.3, true));
    assert!((m[1].dielectric_alpha() - 0.09).abs() < 1e-6);
    // glTF's default roughnessFactor is 1, KHR_materials_ior's default ior 1.5.
    assert_eq!((m[3].ior, m[3].dielectric_roughness), (1.5, 1.0));
    assert_eq!(m[2].transmission, Vec3::new(1.0, 0.5, 1.0));
    assert_eq!(m[0].transmission, Vec3::ONE);
    let base = Vec3::new(1.0, 0.5, 1.0);
    // KHR_materials_ior 1.4: the dielectric F0 ((1.4 - 1) / (1.4 + 1))^2.
    let f0 = (0.4f32 / 2.4).powi(2);
    let close = |a: Vec3, b: Vec3| (a - b).abs().max_element() < 1e-6;
    // (material, glass weight, the lobes' metallic)
    for (i, w, metallic) in [(4, 0.5, 0.0), (5, 0.4, 0.2 / 0.6), (6, 0.5, 1.0)] {
        let g = &m[i];
        assert!(g.is_dielectric() && g.has_partial_transmission(), "{}", g.name);
        assert_eq!((g.mirror, g.ior, g.transmission), (Vec3::ONE, 1.4, base), "{}", g.name);
        assert!((g.glass_weight - w).abs() < 1e-6 && (g.lobes_weight() - (1.0 - w)).abs() < 1e-6, "{}", g.name);
        assert!(close(g.diffuse, base * (1.0 - metallic)), "{}: diffuse {}", g.name, g.diffuse);
        assert!(close(g.glossy, Vec3::splat(f0).lerp(base, metallic)), "{}: glossy {}", g.name, g.glossy);
        assert_eq!(g.roughness, g.dielectric_roughness, "{}", g.name);
    }
    // A smooth partial metal: the lobes' metal is GGX, the mirror stays the glass's.
    assert_eq!((m[5].roughness, m[5].is_rough_dielectric()), (0.0, false));
    // Metallic 1 (glTF's default) does not transmit: one warning names the material.
    assert!(!m[7].is_dielectric() && m[7].glossy == base, "metallic 1 does not transmit");
    let w = &s.report.warnings;
    assert_eq!(w.iter().filter(|x| x.contains("transmission")).count(), 1, "{w:?}");
    assert!(w.iter().any(|x| x.contains("transmission") && x.contains("metallic") && x.contains("'metal'")), "{w:?}");
}

/// A transmissive material reads its baseColorTexture: it tints the transmitted part and
/// the lobes beside partial glass, like the base colour factor.
#[test]
fn transmission_reads_the_base_color_texture() {
    let mut d = Doc::textured();
    d.json["materials"][0]["extensions"] = json!({"KHR_materials_transmission": {"transmissionFactor": 0.7}});
    d.json["materials"][0]["pbrMetallicRoughness"]["metallicFactor"] = json!(0.0);
    let s = d.load().unwrap();
    assert!(s.materials[0].is_dielectric());
    let _ = texture_of(&s, 0);
    assert!(s.report.warnings.iter().all(|w| !w.contains("texture")), "{:?}", s.report.warnings);
}

/// KHR_materials_volume: on a transmissive material the attenuation coefficient is
/// -ln(attenuationColor) / attenuationDistance per channel (Beer-Lambert), zero without a
/// distance (infinite), MAX_ATTENUATION for a black channel; thickness is ignored without
/// a warning; on an opaque material the extension is ignored with one warning naming it;
/// a distance <= 0 is an error.
#[test]
fn volume_gives_the_attenuation_of_transmissive_materials() {
    use vkvcm::scene::gltf_import::MAX_ATTENUATION;
    let mut d = Doc::triangle();
    d.json["extensionsUsed"] = json!(["KHR_materials_transmission", "KHR_materials_volume"]);
    let t = json!({"transmissionFactor": 1.0});
    let vol = |v: serde_json::Value| json!({"KHR_materials_transmission": t, "KHR_materials_volume": v});
    let pbr = json!({"metallicFactor": 0.0});
    d.json["materials"] = json!([
        {"name": "absorbing", "pbrMetallicRoughness": pbr, "extensions": vol(json!({"thicknessFactor": 0.2, "attenuationDistance": 2.0, "attenuationColor": [0.5, 0.25, 1.0]}))},
        {"name": "no_distance", "pbrMetallicRoughness": pbr, "extensions": vol(json!({"attenuationColor": [0.5, 0.5, 0.5]}))},
        {"name": "black", "pbrMetallicRoughness": pbr, "extensions": vol(json!({"attenuationDistance": 1.0, "attenuationColor": [0.0, 1.0, 0.5]}))},
        {"name": "opaque", "extensions": {"KHR_materials_volume": {"attenuationDistance": 1.0, "attenuationColor": [0.5, 0.5, 0.5]}}},
    ]);
    let s = d.load().unwrap();
    let m = &s.materials;
    let ln2 = std::f32::consts::LN_2;
    assert!((m[0].attenuation - Vec3::new(ln2 / 2.0, ln2, 0.0)).abs().max_element() < 1e-6, "{}", m[0].attenuation);
    assert_eq!(m[1].attenuation, Vec3::ZERO);
    assert_eq!(m[2].attenuation.x, MAX_ATTENUATION);
    assert_eq!((m[2].attenuation.y, m[2].attenuation.z), (0.0, ln2));
    assert_eq!((m[3].ior < 0.0, m[3].attenuation), (true, Vec3::ZERO));
    let w = &s.report.warnings;
    assert_eq!(w.iter().filter(|x| x.contains("KHR_materials_volume")).count(), 1, "{w:?}");
    assert!(w.iter().any(|x| x.contains("KHR_materials_volume") && x.contains("'opaque'")), "{w:?}");
    assert!(!w.iter().any(|x| x.contains("thickness") || x.contains("not supported")), "{w:?}");
    d.json["materials"][0]["extensions"]["KHR_materials_volume"]["attenuationDistance"] = json!(0.0);
    let e = err_of(d.load());
    assert!(e.contains("attenuationDistance"), "{e}");
}

/// A file without a perspective camera gets a default camera that frames its geometry
/// (scene::Camera::framing), with one warning; without geometry either, it is an error.
#[test]
fn missing_camera_gets_one_that_frames_the_scene() {
    let in_view = |s: &vkvcm::scene::Scene| {
        let c = &s.camera;
        let (centre, r) = s.bounding_sphere();
        // The bounding sphere lies inside the vertical field of view.
        let d = centre - c.position;
        let half_angle = (r / d.length()).asin() + d.normalize().dot(c.forward).clamp(-1.0, 1.0).acos();
        assert!(half_angle < 0.5 * c.yfov, "{c:?} does not frame the scene ({half_angle} rad)");
        assert!((c.forward.length() - 1.0).abs() < 1e-5 && c.forward.dot(c.up).abs() < 1e-5);
        assert!(
            s.report.warnings.iter().filter(|w| w.contains("default camera")).count() == 1,
            "{:?}",
            s.report.warnings
        );
    };
    let mut d = Doc::triangle();
    d.json["scenes"][0]["nodes"] = json!([0]);
    in_view(&d.load().unwrap());
    // An orthographic camera does not count.
    let mut d = Doc::triangle();
    d.json["cameras"][0] =
        json!({"type": "orthographic", "orthographic": {"xmag": 1.0, "ymag": 1.0, "znear": 0.1, "zfar": 10.0}});
    in_view(&d.load().unwrap());
    // Nothing to frame.
    let mut d = Doc::triangle();
    d.json["scenes"][0]["nodes"] = json!([]);
    let e = err_of(d.load());
    assert!(e.contains("no perspective camera") && e.contains("no geometry") && e.contains("scene.gltf"), "{e}");
}

/// A file without lights is lit by a uniform white sky, with one warning.
#[test]
fn missing_lights_get_a_white_sky() {
    // The triangle has the default material, which does not emit.
    let s = Doc::triangle().load().unwrap();
    assert_eq!(s.lights, [vkvcm::scene::Light::Background { radiance: glam::Vec3::ONE }]);
    assert_eq!(s.report.warnings.iter().filter(|w| w.contains("white sky")).count(), 1, "{:?}", s.report.warnings);
}

/// LoadOptions::default_environment (vkvcm render's studio) lights a file without
/// punctual lights and without an environment, also when it has emissive surfaces (which
/// stay lights), with a note saying so; a punctual light or the file's own background
/// keeps it out; `no_environment` leaves the file without any environment (no white sky).
#[test]
fn the_default_environment_lights_files_without_punctual_lights() {
    use vkvcm::scene::{default_environments, EnvironmentLight, Light};
    let studio = EnvironmentLight {
        map: std::sync::Arc::new(default_environments::studio(16, 8).unwrap()),
        scale: Vec3::ONE,
        rotation_deg: 0.0,
    };
    let with_default = LoadOptions { default_environment: Some(studio.clone()), ..Default::default() };
    let mut d = Doc::triangle();
    d.json["materials"] = json!([{"emissiveFactor": [1.0, 1.0, 1.0]}]);
    d.json["meshes"][0]["primitives"][0]["material"] = json!(0);
    let dir = tempfile::tempdir().unwrap();
    let path = d.write(dir.path());
    let s = load_with(&path, &with_default).unwrap();
    assert!(matches!(s.lights[..], [Light::Area { .. }, Light::Environment(ref e)] if *e == studio), "{:?}", s.lights);
    let note = s.report.lighting_note.clone().unwrap_or_default();
    assert!(note.contains("studio") && note.contains("emissive") && note.contains("--env"), "{note}");
    assert!(!s.report.warnings.iter().any(|w| w.contains("white sky")), "{:?}", s.report.warnings);
    // Without the option: the emission alone, as before.
    let s = load_with(&path, &LoadOptions::default()).unwrap();
    assert!(matches!(s.lights[..], [Light::Area { .. }]) && s.report.lighting_note.is_none(), "{:?}", s.lights);
    // A punctual light, or the file's background, keeps the default out.
    for (ext, value) in [
        ("KHR_lights_punctual", json!({"lights": [{"type": "point", "intensity": 1.0}]})),
        ("VKVCM_background", json!({"radiance": [0.5, 0.5, 0.5]})),
    ] {
        let mut d = Doc::triangle();
        d.json["extensionsUsed"] = json!([ext]);
        d.json["extensions"] = Value::Object([(ext.to_string(), value)].into_iter().collect());
        if ext == "KHR_lights_punctual" {
            d.json["nodes"][0]["extensions"] = json!({"KHR_lights_punctual": {"light": 0}});
        }
        let s = load_with(&d.write(dir.path()), &with_default).unwrap();
        assert!(!s.lights.iter().any(|l| matches!(l, Light::Environment(_))), "{ext}: {:?}", s.lights);
        assert!(s.report.lighting_note.is_none(), "{ext}");
        let none = LoadOptions { no_environment: true, ..Default::default() };
        let s = load_with(&d.write(dir.path()), &none).unwrap();
        assert!(!s.lights.iter().any(Light::is_environment), "{ext} --env none: {:?}", s.lights);
    }
    // The reference scenes keep SmallVCM's lights.
    let glm_c = vkvcm::scene::load_named_with("glm_c", &with_default).unwrap();
    assert!(!glm_c.lights.iter().any(Light::is_environment), "{:?}", glm_c.lights);
}

/// VKVCM_environment: the map's file relative to the scene's folder, its strength and
/// rotation; LoadOptions::environment replaces it (and the white sky).
#[test]
fn environment_extension_and_override() {
    use vkvcm::scene::{EnvironmentLight, EnvironmentMap, Light};
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let s = load_with(&root.join("tests/env/env_scene.gltf"), &LoadOptions::default()).unwrap();
    let envs: Vec<&EnvironmentLight> =
        s.lights.iter().filter_map(|l| if let Light::Environment(e) = l { Some(e) } else { None }).collect();
    assert_eq!(envs.len(), 1, "{:?}", s.lights);
    assert_eq!((envs[0].map.width, envs[0].map.height), (128, 64));
    assert_eq!((envs[0].scale, envs[0].rotation_deg), (glam::Vec3::ONE, 30.0));
    assert!(s.report.warnings.iter().all(|w| !w.contains("occlusion")), "{:?}", s.report.warnings);
    let other = EnvironmentLight {
        map: std::sync::Arc::new(EnvironmentMap::constant(4, 3, [2.0; 3])),
        scale: glam::Vec3::splat(0.5),
        rotation_deg: 0.0,
    };
    let options = LoadOptions { environment: Some(other.clone()), ..Default::default() };
    let s = load_with(&root.join("tests/env/env_scene.gltf"), &options).unwrap();
    assert_eq!(s.lights, [Light::Environment(other.clone())]);
    let dir = tempfile::tempdir().unwrap();
    let s = load_with(&Doc::triangle().write(dir.path()), &options).unwrap();
    assert_eq!(s.lights, [Light::Environment(other)]);
    assert!(!s.report.warnings.iter().any(|w| w.contains("white sky")), "{:?}", s.report.warnings);
}

/// --look-from / --look-at / --fov (Scene::set_view) take the file's world coordinates.
#[test]
fn the_view_can_be_set_in_world_coordinates() {
    let d = Doc::triangle();
    let mut s = d.load().unwrap();
    let origin = glam::DVec3::from_array(s.report.origin).as_vec3();
    s.set_view(Some(glam::Vec3::new(0.0, 0.0, 5.0)), Some(glam::Vec3::ZERO), None, Some(0.5)).unwrap();
    assert!((s.camera.position - (glam::Vec3::new(0.0, 0.0, 5.0) - origin)).length() < 1e-5, "{:?}", s.camera);
    assert!((s.camera.forward - glam::Vec3::NEG_Z).length() < 1e-5, "{:?}", s.camera);
    assert_eq!(s.camera.yfov, 0.5);
    assert!(s.set_view(None, None, None, Some(4.0)).is_err(), "a field of view past 180 degrees");
    let p = s.camera.position + origin;
    assert!(s.set_view(Some(p), Some(p), None, None).is_err(), "position = target");
    assert!(s.set_view(None, None, Some(Vec3::ZERO), None).is_err(), "an up direction of length 0");
}

/// A new view keeps world +Y up, not the file camera's up: Box.gltf has no camera, so its
/// default camera looks down from 20 degrees and turned 30 degrees, and its up vector,
/// made orthogonal to a head-on view of the +Z face, was rolled about the view (the
/// face's edges drawn slanted). With --up the image's up is that direction.
#[test]
fn a_new_view_keeps_world_up() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/khronos/Box.gltf");
    let mut s = load(&path).unwrap();
    assert!(s.camera.up.x.abs() > 0.05, "the default camera is not tilted: the test would be vacuous {:?}", s.camera);
    s.set_view(Some(Vec3::new(0.0, 0.0, 4.0)), None, None, None).unwrap();
    assert!((s.camera.forward - Vec3::NEG_Z).length() < 1e-5, "{:?}", s.camera);
    assert!((s.camera.up - Vec3::Y).length() < 1e-5, "a head-on view is rolled: {:?}", s.camera);
    // --look-at alone, too.
    let mut s = load(&path).unwrap();
    s.set_view(None, Some(s.camera.position + Vec3::new(1.0, 0.0, 0.0)), None, None).unwrap();
    assert!((s.camera.up - Vec3::Y).length() < 1e-5, "{:?}", s.camera);
    // From below on a diagonal (negative coordinates): up is the part of +Y across the view.
    s.set_view(Some(Vec3::new(-14.0, -14.0, -14.0)), Some(Vec3::ZERO), None, None).unwrap();
    assert!(s.camera.up.y > 0.0 && s.camera.up.dot(s.camera.forward).abs() < 1e-5, "{:?}", s.camera);
    assert!(s.camera.up.cross(Vec3::Y).dot(s.camera.forward).abs() < 1e-5, "up leaves the +Y plane: {:?}", s.camera);
    s.set_view(Some(Vec3::new(0.0, 0.0, 4.0)), None, Some(Vec3::new(2.0, 0.0, 0.0)), None).unwrap();
    assert!((s.camera.up - Vec3::X).length() < 1e-5, "--up 2,0,0: {:?}", s.camera);
}

/// A camera's aspectRatio is reported (the image's default shape); `--camera auto` frames
/// the scene although the file has a camera; a wrong name lists the cameras and auto.
#[test]
fn camera_aspect_ratio_and_auto() {
    let mut d = Doc::triangle();
    let s = d.load().unwrap();
    assert_eq!(s.report.camera_aspect, None);
    d.json["cameras"][0]["perspective"]["aspectRatio"] = json!(1.5);
    let s = d.load().unwrap();
    assert_eq!(s.report.camera_aspect, Some(1.5));
    let dir = tempfile::tempdir().unwrap();
    let path = d.write(dir.path());
    let auto = load_with(&path, &LoadOptions { camera: Some("auto".into()), ..Default::default() }).unwrap();
    let (c, r) = auto.bounding_sphere();
    assert_eq!(Some(auto.camera.clone()), scene::Camera::framing(c, r), "--camera auto");
    assert_ne!(auto.camera.position, s.camera.position);
    assert_eq!(auto.report.camera_aspect, None);
    assert!(!auto.report.warnings.iter().any(|w| w.contains("default camera")), "{:?}", auto.report.warnings);
    let e = err_of(load_with(&path, &LoadOptions { camera: Some("nope".into()), ..Default::default() }));
    assert!(e.contains("available: cam") && e.contains("auto"), "{e}");
    d.json["cameras"][0]["perspective"]["aspectRatio"] = json!(0.0);
    let e = err_of(d.load());
    assert!(e.contains("aspectRatio"), "{e}");
}

#[test]
fn camera_selected_by_name() {
    let mut d = Doc::triangle();
    d.json["cameras"]
        .as_array_mut()
        .unwrap()
        .push(json!({"name": "wide", "type": "perspective", "perspective": {"yfov": 1.2, "znear": 0.01}}));
    d.json["nodes"]
        .as_array_mut()
        .unwrap()
        .push(json!({"name": "second", "camera": 1, "translation": [0.0, 7.0, 0.0]}));
    d.json["scenes"][0]["nodes"] = json!([0, 1, 2]);
    let dir = tempfile::tempdir().unwrap();
    let path = d.write(dir.path());
    let first = load(&path).unwrap();
    assert_eq!(first.camera.position, Vec3::new(0.0, 0.0, 5.0));
    for name in ["second", "wide"] {
        let s = load_with(&path, &LoadOptions { camera: Some(name.into()), ..Default::default() }).unwrap();
        assert_eq!(s.camera.position, Vec3::new(0.0, 7.0, 0.0));
        assert_eq!(s.camera.yfov, 1.2);
    }
    let e = err_of(load_with(&path, &LoadOptions { camera: Some("nope".into()), ..Default::default() }));
    assert!(e.contains("nope") && e.contains("cam") && e.contains("second"), "{e}");
}

#[test]
fn material_mapping_and_emission() {
    let tri = |x: f32| [[x, 0.0, 0.0], [x + 1.0, 0.0, 0.0], [x, 1.0, 0.0]];
    let pos: Vec<[f32; 3]> = (0..5).flat_map(|k| tri(k as f32 * 2.0)).collect();
    let mut d = Doc::new(&pos, None, None);
    // Split the 5 triangles into 5 primitives with materials 0..4, plus one without.
    let prim0 = d.json["meshes"][0]["primitives"][0].clone();
    let mut prims = Vec::new();
    for k in 0..6 {
        let mut acc = d.json["accessors"][0].clone();
        acc["byteOffset"] = json!((k % 5) * 36);
        acc["count"] = json!(3);
        d.json["accessors"].as_array_mut().unwrap().push(acc);
        let mut p = prim0.clone();
        p["attributes"]["POSITION"] = json!(d.json["accessors"].as_array().unwrap().len() - 1);
        if k < 5 {
            p["material"] = json!(k);
        }
        prims.push(p);
    }
    d.json["meshes"][0]["primitives"] = json!(prims);
    d.json["materials"] = json!([
        {"name": "plastic", "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0}},
        {"name": "mirror", "pbrMetallicRoughness": {"baseColorFactor": [1.0, 0.5, 0.25, 1.0], "metallicFactor": 1.0, "roughnessFactor": 0.0}, "doubleSided": true},
        {"name": "glass", "pbrMetallicRoughness": {"roughnessFactor": 0.0, "metallicFactor": 0.0},
         "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0}, "KHR_materials_ior": {"ior": 1.33}}},
        {"name": "lamp", "emissiveFactor": [1.0, 0.5, 0.0], "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4.0}}},
        {"name": "exact", "pbrMetallicRoughness": {"metallicFactor": 1.0},
         "extensions": {"VKVCM_materials_phong": {"diffuse": [0.1, 0.2, 0.3], "phong": [0.4, 0.4, 0.4], "exponent": 90, "mirror": [0, 0, 0], "ior": -1}}},
    ]);
    let s = d.load().unwrap();
    assert_eq!(s.triangles.len(), 6);
    let m = &s.materials;
    assert_eq!(m.len(), 6, "5 + the glTF default material");
    assert_eq!(m[0].name, "plastic");
    // metallic/roughness -> diffuse (1-m) b + GGX lobe F0 = mix(0.04, b, m), roughness r.
    assert_close(m[0].diffuse, Vec3::splat(0.5));
    assert_close(m[0].glossy, Vec3::splat(0.04));
    assert_eq!(m[0].roughness, 1.0);
    assert_eq!(m[0].phong, Vec3::ZERO);
    assert_eq!(m[0].mirror, Vec3::ZERO);
    // metallic 1, roughness 0 stays a perfect mirror.
    assert_eq!(m[1].mirror, Vec3::new(1.0, 0.5, 0.25));
    assert_eq!(m[1].diffuse + m[1].phong + m[1].glossy, Vec3::ZERO);
    assert_eq!(m[1].ior, -1.0);
    assert_eq!((m[2].mirror, m[2].ior, m[2].diffuse), (Vec3::ONE, 1.33, Vec3::ZERO));
    assert_eq!(m[3].emission, Vec3::new(4.0, 2.0, 0.0));
    assert_eq!(m[4].diffuse, Vec3::new(0.1, 0.2, 0.3));
    assert_eq!(m[4].phong, Vec3::splat(0.4));
    assert_eq!(m[4].phong_exponent, 90.0);
    assert_eq!(m[4].mirror, Vec3::ZERO);
    assert_eq!(m[4].glossy, Vec3::ZERO, "VKVCM_materials_phong states the material completely");
    assert_eq!(s.triangles[5].material, 5);
    assert_eq!(m[5].name, "gltf-default");
    // glTF's default material: base 1, metallic 1, roughness 1 -> a rough white metal.
    assert_eq!((m[5].diffuse, m[5].glossy, m[5].roughness), (Vec3::ZERO, Vec3::ONE, 1.0));
    assert_eq!(s.lights, vec![Light::Area { triangle: 3, radiance: Vec3::new(4.0, 2.0, 0.0) }]);
    // doubleSided (default false, as for the default material): one-sided, except a
    // dielectric, whose refracted rays leave through its back side.
    let one_sided: Vec<bool> = m.iter().map(|m| m.one_sided).collect();
    assert_eq!(one_sided, [true, false, false, true, true, true]);
}

#[test]
fn punctual_lights() {
    let mut d = Doc::triangle();
    d.json["extensionsUsed"] = json!(["KHR_lights_punctual"]);
    d.json["extensions"] = json!({"KHR_lights_punctual": {"lights": [
        {"type": "point", "color": [1.0, 0.5, 0.25], "intensity": 8.0},
        {"type": "spot", "intensity": 2.0, "spot": {"innerConeAngle": 0.25, "outerConeAngle": 0.5}},
        {"type": "directional", "color": [0.5, 1.0, 1.0], "intensity": 3.0},
    ]}});
    let nodes = d.json["nodes"].as_array_mut().unwrap();
    nodes.push(json!({"translation": [1.0, 2.0, 3.0], "extensions": {"KHR_lights_punctual": {"light": 0}}}));
    // Rotated -90 deg about X: local -Z points to -Y.
    nodes.push(json!({"translation": [0.0, 4.0, 0.0], "rotation": [-S, 0.0, 0.0, S], "extensions": {"KHR_lights_punctual": {"light": 1}}}));
    // Rotated 90 deg about Y: local -Z points to -X.
    nodes.push(json!({"rotation": [0.0, S, 0.0, S], "extensions": {"KHR_lights_punctual": {"light": 2}}}));
    d.json["scenes"][0]["nodes"] = json!([0, 1, 2, 3, 4]);
    let s = d.load().unwrap();
    assert_eq!(s.lights.len(), 3);
    assert_eq!(s.lights[0], Light::Point { position: Vec3::new(1.0, 2.0, 3.0), intensity: Vec3::new(8.0, 4.0, 2.0) });
    let Light::Spot { position, direction, intensity, cos_inner, cos_outer } = s.lights[1] else { panic!() };
    assert_close(position, Vec3::new(0.0, 4.0, 0.0));
    assert_close(direction, Vec3::NEG_Y);
    assert_eq!(intensity, Vec3::splat(2.0));
    assert!((cos_inner - 0.25f32.cos()).abs() < 1e-6 && (cos_outer - 0.5f32.cos()).abs() < 1e-6);
    let Light::Directional { direction, irradiance } = s.lights[2] else { panic!() };
    assert_close(direction, Vec3::NEG_X);
    assert_eq!(irradiance, Vec3::new(1.5, 3.0, 3.0));
    assert!(s.report.warnings.iter().all(|w| !w.contains("occlusion")), "{:?}", s.report.warnings);
}

#[test]
fn spheres_extension() {
    let mut d = Doc::triangle();
    d.json["materials"] = json!([{"name": "a"}, {"name": "b"}]);
    d.json["nodes"].as_array_mut().unwrap().push(json!({
        "translation": [1.0, 2.0, 3.0], "scale": [2.0, 2.0, 2.0],
        "extensions": {"VKVCM_spheres": {"spheres": [
            {"center": [1.0, 0.0, 0.0], "radius": 0.5, "material": 1},
            {"center": [0.0, 0.0, 0.0], "radius": 1.0, "material": 0},
        ]}}
    }));
    d.json["scenes"][0]["nodes"] = json!([0, 1, 2]);
    let s = d.load().unwrap();
    assert_eq!(s.spheres.len(), 2);
    assert_close(s.spheres[0].center, Vec3::new(3.0, 2.0, 3.0));
    assert_eq!((s.spheres[0].radius, s.spheres[0].material), (1.0, 1));
    assert_close(s.spheres[1].center, Vec3::new(1.0, 2.0, 3.0));
    assert_eq!((s.spheres[1].radius, s.spheres[1].material), (2.0, 0));
    // bounds include the spheres: x from -1 (sphere 1) to 4 (sphere 0)
    let (lo, hi) = s.bounds();
    assert_close(lo, Vec3::new(-1.0, 0.0, 0.0));
    assert_close(hi, Vec3::new(4.0, 4.0, 5.0));
    let (c, r) = s.bounding_sphere();
    assert_close(c, (lo + hi) * 0.5);
    assert!((r - (hi - lo).length() * 0.5).abs() < 1e-6);

    let mut bad = d.json.clone();
    bad["nodes"][2]["scale"] = json!([1.0, 2.0, 1.0]);
    let e = err_of(Doc { json: bad, bin: d.bin.clone() }.load());
    assert!(e.contains("uniform") && e.contains("nodes[2]"), "{e}");
    let mut bad = d.json.clone();
    bad["nodes"][2]["extensions"]["VKVCM_spheres"]["spheres"][0]["material"] = json!(5);
    let e = err_of(Doc { json: bad, bin: d.bin.clone() }.load());
    assert!(e.contains("material") && e.contains("out of range"), "{e}");
    let mut bad = d.json.clone();
    bad["nodes"][2]["extensions"]["VKVCM_spheres"]["spheres"][1]["radius"] = json!(-1.0);
    assert!(err_of(Doc { json: bad, bin: d.bin.clone() }.load()).contains("radius"));
}

#[test]
fn background_extension() {
    let mut d = Doc::triangle();
    d.json["extensionsUsed"] = json!(["VKVCM_background"]);
    d.json["extensions"] = json!({"VKVCM_background": {"radiance": [0.25, 0.5, 1.0]}});
    let s = d.load().unwrap();
    assert_eq!(s.lights, vec![Light::Background { radiance: Vec3::new(0.25, 0.5, 1.0) }]);
    d.json["extensions"] = json!({"VKVCM_background": {"radiance": [0.25, "x", 1.0]}});
    assert!(err_of(d.load()).contains("VKVCM_background.radiance[1]"));
}

#[test]
fn malformed_files_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("broken.gltf");
    std::fs::write(&path, b"{ \"asset\": { \"version\": \"2.0\" }, ").unwrap();
    let e = err_of(load(&path));
    assert!(e.contains("broken.gltf") && e.contains("JSON"), "{e}");
    let e = err_of(load(&dir.path().join("absent.gltf")));
    assert!(e.contains("absent.gltf"), "{e}");
    // A node hierarchy with a cycle.
    let mut d = Doc::triangle();
    d.json["nodes"][0]["children"] = json!([1]);
    d.json["nodes"][1]["children"] = json!([0]);
    d.json["scenes"][0]["nodes"] = json!([0]);
    assert!(err_of(d.load()).contains("not a tree"));
}

#[test]
fn missing_position_bounds_are_tolerated_with_a_warning() {
    let mut d = Doc::triangle();
    d.json["accessors"][0].as_object_mut().unwrap().remove("min");
    let s = d.load().unwrap();
    assert_eq!(s.triangles.len(), 1);
    assert!(s.report.warnings.iter().any(|w| w.contains("min/max")), "{:?}", s.report.warnings);
    // Present bounds give no such warning.
    assert!(!Doc::triangle().load().unwrap().report.warnings.iter().any(|w| w.contains("min/max")));
}

// --- Sparse accessors, KHR_mesh_quantization, morph targets, skins, scenes (issue #18) ---

fn khronos(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/khronos").join(format!("{name}.gltf"))
}

/// Every triangle's vertices, in order.
fn vertices(s: &Scene) -> Vec<[Vec3; 3]> {
    s.triangles.iter().map(|t| t.p).collect()
}

impl Doc {
    /// Appends `bytes` to the buffer (4-byte aligned) as a new buffer view; its index.
    fn push_view(&mut self, bytes: &[u8], stride: Option<usize>) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let mut v = json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()});
        if let Some(s) = stride {
            v["byteStride"] = json!(s);
        }
        self.bin.extend_from_slice(bytes);
        self.json["buffers"][0]["byteLength"] = json!(self.bin.len());
        let views = self.json["bufferViews"].as_array_mut().unwrap();
        views.push(v);
        views.len() - 1
    }

    /// Appends accessor `a`; its index.
    fn push_accessor(&mut self, a: Value) -> usize {
        let accs = self.json["accessors"].as_array_mut().unwrap();
        accs.push(a);
        accs.len() - 1
    }

    fn prim(&mut self) -> &mut Value {
        &mut self.json["meshes"][0]["primitives"][0]
    }
}

fn f32_bytes(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

fn u16_bytes(v: &[u16]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// Khronos SimpleSparseAccessor: 14 vertices on two rows, (i, 0, 0) and (i - 7, 1, 0),
/// of which the sparse substitution moves vertices 8, 10 and 12 to (1, 2, 0), (3, 3, 0)
/// and (5, 4, 0) (the values in its buffer, bytes 240..284).
#[test]
fn sparse_accessor_khronos_sample() {
    let s = load(&khronos("SimpleSparseAccessor")).unwrap();
    let mut v: Vec<Vec3> = (0..14)
        .map(|i| if i < 7 { Vec3::new(i as f32, 0.0, 0.0) } else { Vec3::new(i as f32 - 7.0, 1.0, 0.0) })
        .collect();
    v[8] = Vec3::new(1.0, 2.0, 0.0);
    v[10] = Vec3::new(3.0, 3.0, 0.0);
    v[12] = Vec3::new(5.0, 4.0, 0.0);
    let idx = [
        0, 8, 7, 0, 1, 8, 1, 9, 8, 1, 2, 9, 2, 10, 9, 2, 3, 10, 3, 11, 10, 3, 4, 11, 4, 12, 11, 4, 5, 12, 5, 13, 12, 5,
        6, 13,
    ];
    let want: Vec<[Vec3; 3]> = idx.chunks(3).map(|c| [v[c[0]], v[c[1]], v[c[2]]]).collect();
    assert_eq!(vertices(&s), want);
    assert!(!s.report.warnings.iter().any(|w| w.contains("sparse")), "{:?}", s.report.warnings);
}

/// Sparse POSITION without a bufferView (zeros, then the substitution), sparse indices
/// over a base, sparse NORMAL.
#[test]
fn sparse_accessors_without_and_with_a_base() {
    let reference = Doc::triangle().load().unwrap();
    // POSITION: zeros, with vertices 1 and 2 replaced.
    let mut d = Doc::triangle();
    let iv = d.push_view(&[1u32, 2].iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>(), None);
    let vv = d.push_view(&f32_bytes(&[1.0, 0.0, 0.0, 0.0, 1.0, 0.0]), None);
    let a = d
        .push_accessor(json!({"componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0],
        "sparse": {"count": 2, "indices": {"bufferView": iv, "componentType": 5125}, "values": {"bufferView": vv}}}));
    d.prim()["attributes"]["POSITION"] = json!(a);
    let s = d.load().unwrap();
    assert_eq!(s.triangles, reference.triangles);

    // Indices: a base of [0, 1, 2, 0, 1, 2] whose elements 3..6 become [2, 3, 0].
    let quad = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
    let want = Doc::new(&quad, None, Some((&[0, 1, 2, 2, 3, 0], 5123))).load().unwrap();
    let mut d = Doc::new(&quad, None, Some((&[0, 1, 2, 0, 1, 2], 5123)));
    let iv = d.push_view(&u16_bytes(&[3, 4, 5]), None);
    let vv = d.push_view(&u16_bytes(&[2, 3, 0]), None);
    d.json["accessors"][1]["sparse"] =
        json!({"count": 3, "indices": {"bufferView": iv, "componentType": 5123}, "values": {"bufferView": vv}});
    let s = d.load().unwrap();
    assert_eq!(s.triangles.len(), 2);
    assert_eq!(s.triangles, want.triangles);

    // NORMAL: all +Z, vertex 1 replaced by +X (one UNSIGNED_BYTE index).
    let z = [0.0, 0.0, 1.0];
    let mut d = Doc::new(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], Some(&[z, z, z]), None);
    let iv = d.push_view(&[1u8], None);
    let vv = d.push_view(&f32_bytes(&[1.0, 0.0, 0.0]), None);
    d.json["accessors"][1]["sparse"] =
        json!({"count": 1, "indices": {"bufferView": iv, "componentType": 5121}, "values": {"bufferView": vv}});
    let n = d.load().unwrap().triangles[0].n.unwrap();
    assert_eq!(n, [Vec3::Z, Vec3::X, Vec3::Z]);
}

/// KHR_mesh_quantization: integer POSITION (plain and normalized) and normalized NORMAL,
/// decoded by glTF's int-to-float equations (SHORT: max(c / 32767, -1); BYTE:
/// max(c / 127, -1); UNSIGNED_BYTE: c / 255). Without the extension they are refused.
#[test]
fn quantized_attributes_decode_per_the_spec() {
    fn quantized(pos: (u32, bool, Vec<u8>, usize), normal: Option<(u32, bool, Vec<u8>, usize)>) -> Doc {
        let mut d = Doc::triangle();
        d.json["extensionsUsed"] = json!(["KHR_mesh_quantization"]);
        d.json["extensionsRequired"] = json!(["KHR_mesh_quantization"]);
        let (ct, norm, bytes, stride) = pos;
        let v = d.push_view(&bytes, Some(stride));
        let a = d.push_accessor(
            json!({"bufferView": v, "componentType": ct, "normalized": norm, "count": 3, "type": "VEC3",
            "min": [-32768, -32768, -32768], "max": [32767, 32767, 32767]}),
        );
        d.prim()["attributes"]["POSITION"] = json!(a);
        if let Some((ct, norm, bytes, stride)) = normal {
            let v = d.push_view(&bytes, Some(stride));
            let a = d.push_accessor(
                json!({"bufferView": v, "componentType": ct, "normalized": norm, "count": 3, "type": "VEC3"}),
            );
            d.prim()["attributes"]["NORMAL"] = json!(a);
        }
        d
    }
    let shorts = |v: &[i16]| -> Vec<u8> {
        // VEC3 of 2-byte components padded to 8 bytes per element (glTF's 4-byte alignment).
        v.chunks(3).flat_map(|c| c.iter().flat_map(|x| x.to_le_bytes()).chain([0, 0])).collect()
    };
    // Plain UNSIGNED_SHORT positions are the integers themselves.
    let raw = shorts(&[0, 0, 0, 2, 0, 0, 0, 3, 0]);
    let s = quantized((5123, false, raw.clone(), 8), None).load().unwrap();
    assert_eq!(vertices(&s), [[Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 3.0, 0.0)]]);
    assert!(s.report.warnings.iter().all(|w| !w.contains("KHR_mesh_quantization")), "{:?}", s.report.warnings);

    // SHORT normalized: 32767 -> 1, -32768 -> -1 (clamped), 16384 -> 16384/32767.
    let raw = shorts(&[0, 0, 0, 32767, 0, 0, -32768, 16384, 0]);
    // BYTE normalized normals, 4 bytes per element: 127 -> 1, -128 -> -1 (clamped: the
    // direction of the third one depends on it), 64 -> 64/127.
    let nb: Vec<u8> = [[0i8, 0, 127], [-127, 0, 0], [64, -128, 0]]
        .iter()
        .flat_map(|c| c.iter().map(|x| *x as u8).chain([0]).collect::<Vec<u8>>())
        .collect();
    let s = quantized((5122, true, raw, 8), Some((5120, true, nb, 4))).load().unwrap();
    let t = &s.triangles[0];
    assert_eq!(t.p, [Vec3::ZERO, Vec3::X, Vec3::new(-1.0, (16384.0f64 / 32767.0) as f32, 0.0)]);
    let want_n2 = Vec3::new((64.0f64 / 127.0) as f32, -1.0, 0.0).normalize();
    let n = t.n.unwrap();
    assert_eq!((n[0], n[1]), (Vec3::Z, Vec3::NEG_X));
    assert_close(n[2], want_n2);

    // BYTE normalized positions: 127 -> 1, -128 -> -1, 64 -> 64/127.
    let b: Vec<u8> = [[0i8, 0, 0], [127, 0, 0], [-128, 64, 0]]
        .iter()
        .flat_map(|c| c.iter().map(|x| *x as u8).chain([0]).collect::<Vec<u8>>())
        .collect();
    let s = quantized((5120, true, b, 4), None).load().unwrap();
    assert_eq!(vertices(&s), [[Vec3::ZERO, Vec3::X, Vec3::new(-1.0, (64.0f64 / 127.0) as f32, 0.0)]]);

    // UNSIGNED_BYTE normalized positions: c / 255 (51 -> 0.2).
    let ub: Vec<u8> = vec![0, 0, 0, 0, 255, 0, 0, 0, 0, 51, 0, 0];
    let s = quantized((5121, true, ub, 4), None).load().unwrap();
    assert_eq!(vertices(&s), [[Vec3::ZERO, Vec3::X, Vec3::new(0.0, (51.0f64 / 255.0) as f32, 0.0)]]);

    // Without the extension: refused, with the reason.
    let mut d = quantized((5123, false, shorts(&[0, 0, 0, 2, 0, 0, 0, 3, 0]), 8), None);
    d.json.as_object_mut().unwrap().remove("extensionsUsed");
    d.json.as_object_mut().unwrap().remove("extensionsRequired");
    let e = err_of(d.load());
    assert!(e.contains("must be FLOAT VEC3") && e.contains("KHR_mesh_quantization"), "{e}");
    // A normal must be normalized even with it (KHR_mesh_quantization allows BYTE/SHORT normalized only).
    let nb: Vec<u8> = vec![0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0];
    let e =
        err_of(quantized((5123, false, shorts(&[0, 0, 0, 2, 0, 0, 0, 3, 0]), 8), Some((5120, false, nb, 4))).load());
    assert!(e.contains("NORMAL") && e.contains("BYTE normalized"), "{e}");
}

/// Writes `json` (a modified sample) as `scene.gltf` in a fresh folder and loads it.
fn load_json(json: &Value, options: &LoadOptions) -> anyhow::Result<Scene> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scene.gltf");
    std::fs::write(&path, serde_json::to_vec(json).unwrap()).unwrap();
    load_with(&path, options)
}

fn sample_json(name: &str) -> Value {
    serde_json::from_slice(&std::fs::read(khronos(name)).unwrap()).unwrap()
}

/// Khronos SimpleMorph at its default weights (0.5, 0.5): vertex 2 (0.5, 0.5, 0) moves by
/// 0.5 (-1, 1, 0) + 0.5 (1, 1, 0) to (0.5, 1.5, 0); node weights override the mesh's.
#[test]
fn morph_targets_at_the_default_weights() {
    let s = load(&khronos("SimpleMorph")).unwrap();
    assert_eq!(vertices(&s), [[Vec3::ZERO, Vec3::X, Vec3::new(0.5, 1.5, 0.0)]]);
    let w = &s.report.warnings;
    assert!(w.iter().any(|w| w.contains("animations are not supported")), "{w:?}");
    assert!(!w.iter().any(|w| w.contains("morph")), "{w:?}");

    let mut j = sample_json("SimpleMorph");
    j["nodes"][0]["weights"] = json!([1.0, 0.25]);
    // (0.5, 0.5) + (-1, 1) + 0.25 (1, 1) = (-0.25, 1.75)
    let s = load_json(&j, &LoadOptions::default()).unwrap();
    assert_eq!(vertices(&s), [[Vec3::ZERO, Vec3::X, Vec3::new(-0.25, 1.75, 0.0)]]);
    // No weights anywhere: all 0, the base geometry.
    j["nodes"][0].as_object_mut().unwrap().remove("weights");
    j["meshes"][0].as_object_mut().unwrap().remove("weights");
    let s = load_json(&j, &LoadOptions::default()).unwrap();
    assert_eq!(vertices(&s), [[Vec3::ZERO, Vec3::X, Vec3::new(0.5, 0.5, 0.0)]]);
    // A weight count that does not match the targets.
    j["meshes"][0]["weights"] = json!([0.5]);
    let e = err_of(load_json(&j, &LoadOptions::default()));
    assert!(
        e.contains("1 morph target weight(s)") && e.contains("2 morph target(s)") && e.contains("mesh 0 primitive 0"),
        "{e}"
    );
}

/// Morph targets with NORMAL displacements, and a sparse target (no bufferView).
#[test]
fn morph_target_normals_and_sparse_targets() {
    let z = [0.0, 0.0, 1.0];
    let mut d = Doc::new(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], Some(&[z, z, z]), None);
    // Target 0: POSITION only vertex 2 moves by (0, 2, 0), sparse over zeros.
    let iv = d.push_view(&[2u8], None);
    let vv = d.push_view(&f32_bytes(&[0.0, 2.0, 0.0]), None);
    let t0 = d
        .push_accessor(json!({"componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [0, 2, 0],
        "sparse": {"count": 1, "indices": {"bufferView": iv, "componentType": 5121}, "values": {"bufferView": vv}}}));
    // Target 1: NORMAL displacements (1, 0, -1) on every vertex: +Z becomes +X.
    let nv = d.push_view(&f32_bytes(&[1.0, 0.0, -1.0, 1.0, 0.0, -1.0, 1.0, 0.0, -1.0]), None);
    let t1 = d.push_accessor(json!({"bufferView": nv, "componentType": 5126, "count": 3, "type": "VEC3"}));
    d.prim()["targets"] = json!([{"POSITION": t0}, {"NORMAL": t1}]);
    d.json["meshes"][0]["weights"] = json!([0.5, 1.0]);
    let s = d.load().unwrap();
    assert_eq!(s.triangles[0].p, [Vec3::ZERO, Vec3::X, Vec3::new(0.0, 2.0, 0.0)]);
    assert_eq!(s.triangles[0].n.unwrap(), [Vec3::X; 3]);
}

/// Khronos TextureSettingsTest: each textured material's sampler wrap modes (REPEAT,
/// MIRRORED_REPEAT, CLAMP_TO_EDGE in both directions), its three embedded PNGs, and
/// doubleSided: only DoubleSidedMaterial is two-sided (glTF's default is one-sided).
#[test]
fn texture_settings_test_samplers_and_sides() {
    let s = load(&khronos("TextureSettingsTest")).unwrap();
    assert_eq!(s.images.len(), 3);
    let by_name = |n: &str| s.materials.iter().find(|m| m.name == n).unwrap_or_else(|| panic!("no material {n}"));
    let wrap = |n: &str| {
        let t = by_name(n).base_color_texture.clone().unwrap_or_else(|| panic!("{n}: no texture"));
        assert_eq!(t.filter, Filter::Linear, "{n}");
        (t.wrap_s, t.wrap_t)
    };
    assert_eq!(wrap("TextureMirrorMaterialT"), (Wrap::Repeat, Wrap::MirroredRepeat));
    assert_eq!(wrap("TextureMirrorMaterialS"), (Wrap::MirroredRepeat, Wrap::Repeat));
    assert_eq!(wrap("TextureRepeatMaterialT"), (Wrap::ClampToEdge, Wrap::Repeat));
    assert_eq!(wrap("TextureClampMaterialT"), (Wrap::Repeat, Wrap::ClampToEdge));
    assert_eq!(wrap("DoubleSidedMaterial"), (Wrap::Repeat, Wrap::Repeat));
    assert!(!by_name("DoubleSidedMaterial").one_sided);
    assert!(by_name("SingleSidedMaterial").one_sided);
    assert!(by_name("BackgroundMaterial").base_color_texture.is_none());
    let w = &s.report.warnings;
    assert!(!w.iter().any(|x| x.contains("texture") || x.contains("sampler")), "{w:?}");
}

/// Khronos SimpleSkin: its joints' node transforms are the bind pose (joint matrices =
/// identity), so the skinned mesh is its stored geometry. With joint 1 (node 2) turned 90
/// degrees about +Z the upper vertices bend around (0, 1, 0): J1 = T(0,1,0) R T(0,-1,0).
#[test]
fn skinned_mesh_in_its_joints_pose() {
    let stored = |x: f32, y: f32| Vec3::new(x, y, 0.0);
    let s = load(&khronos("SimpleSkin")).unwrap();
    assert_eq!(s.triangles.len(), 8);
    assert_eq!(s.triangles[0].p, [stored(-0.5, 0.0), stored(0.5, 0.0), stored(0.5, 0.5)]);
    assert_eq!(s.triangles[7].p, [stored(-0.5, 1.5), stored(0.5, 2.0), stored(-0.5, 2.0)]);
    assert!(!s.report.warnings.iter().any(|w| w.contains("skin")), "{:?}", s.report.warnings);

    let mut j = sample_json("SimpleSkin");
    j["nodes"][2]["rotation"] = json!([0.0, 0.0, S, S]);
    // The skinned mesh node's own transform is ignored (glTF 2.0 section 3.7.3.2).
    j["nodes"][0]["translation"] = json!([100.0, 0.0, 0.0]);
    let s = load_json(&j, &LoadOptions::default()).unwrap();
    // Vertex 9 (0.5, 2) has weight 1 on joint 1: (0.5, 1) turned -> (-1, 0.5), + (0, 1).
    // Vertex 4 (-0.5, 1) has weights 0.5/0.5: 0.5 (-0.5, 1) + 0.5 (0, 0.5) = (-0.25, 0.75).
    // Vertex 0 (-0.5, 0) has weight 1 on joint 0, which did not move.
    let t7 = s.triangles[7].p; // vertices 6, 9, 8
    assert_close(t7[1], Vec3::new(-1.0, 1.5, 0.0));
    assert_close(t7[2], Vec3::new(-1.0, 0.5, 0.0));
    // Vertex 5 (0.5, 1), weights 0.5/0.5: 0.5 (0.5, 1) + 0.5 (0, 1.5) = (0.25, 1.25).
    // Vertex 2 (-0.5, 0.5), weights 0.75/0.25: 0.75 (-0.5, 0.5) + 0.25 (0.5, 0.5) = (-0.25, 0.5).
    let t2 = s.triangles[2].p; // vertices 2, 3, 5
    assert_close(t2[2], Vec3::new(0.25, 1.25, 0.0));
    assert_close(t2[0], Vec3::new(-0.25, 0.5, 0.0));
    assert_eq!(s.triangles[0].p[0], stored(-0.5, 0.0));
    let t3 = s.triangles[3].p; // vertices 2, 5, 4
    assert_close(t3[2], Vec3::new(-0.25, 0.75, 0.0));
}

/// Skinning errors name the accessor: a joint index past the skin's joints, a negative
/// weight, too few inverse bind matrices.
#[test]
fn malformed_skins_are_errors() {
    let mut j = sample_json("SimpleSkin");
    j["skins"][0]["joints"] = json!([1]);
    let e = err_of(load_json(&j, &LoadOptions::default()));
    assert!(e.contains("JOINTS_0 accessor 2") && e.contains("joint 1") && e.contains("1 joints"), "{e}");
    let mut j = sample_json("SimpleSkin");
    j["skins"][0]["joints"] = json!([1, 2, 0]);
    let e = err_of(load_json(&j, &LoadOptions::default()));
    assert!(e.contains("inverseBindMatrices accessor 4 has 2 matrices for 3 joints"), "{e}");
    // Without inverseBindMatrices every one is the identity: the mesh moves up by 1 (the
    // joints' translation).
    let mut j = sample_json("SimpleSkin");
    j["skins"][0].as_object_mut().unwrap().remove("inverseBindMatrices");
    let s = load_json(&j, &LoadOptions::default()).unwrap();
    assert_eq!(s.triangles[0].p[0], Vec3::new(-0.5, 1.0, 0.0));
}

/// Khronos MultipleScenes: the default scene (1, a square) is rendered, with a warning
/// naming it; LoadOptions::scene picks another by index or name; an unknown one is an
/// error that lists the scenes.
#[test]
fn scenes_are_selected_by_name_or_index() {
    let path = khronos("MultipleScenes");
    let s = load(&path).unwrap();
    assert_eq!(s.triangles.len(), 2);
    let w = &s.report.warnings;
    assert!(
        w.iter().any(|w| w.contains("2 scenes") && w.contains("the default one") && w.contains("scene 1")),
        "{w:?}"
    );
    let pick = |want: &str| load_with(&path, &LoadOptions { scene: Some(want.into()), ..Default::default() });
    let s = pick("0").unwrap();
    assert_eq!(vertices(&s), [[Vec3::ZERO, Vec3::X, Vec3::Y]]);
    assert!(!s.report.warnings.iter().any(|w| w.contains("scenes")), "{:?}", s.report.warnings);
    assert_eq!(pick("1").unwrap().triangles.len(), 2);
    let e = err_of(pick("2"));
    assert!(e.contains("'2'") && e.contains("available scenes: 0, 1"), "{e}");

    // By name; a name wins over an index, and the list names the scenes.
    let mut j = sample_json("MultipleScenes");
    j["scenes"][0]["name"] = json!("1");
    j["scenes"][1]["name"] = json!("square");
    let opts = |want: &str| LoadOptions { scene: Some(want.into()), ..Default::default() };
    assert_eq!(load_json(&j, &opts("square")).unwrap().triangles.len(), 2);
    assert_eq!(load_json(&j, &opts("1")).unwrap().triangles.len(), 1, "scene 0 is named '1'");
    let e = err_of(load_json(&j, &opts("nope")));
    assert!(e.contains("'nope'") && e.contains("0 '1', 1 'square'"), "{e}");
    // Without a default scene, the first is rendered (and the warning says so).
    j.as_object_mut().unwrap().remove("scene");
    let s = load_json(&j, &LoadOptions::default()).unwrap();
    assert_eq!(s.triangles.len(), 1);
    assert!(
        s.report.warnings.iter().any(|w| w.contains("2 scenes") && w.contains("no default")),
        "{:?}",
        s.report.warnings
    );
}

/// Orthographic cameras: skipped with a warning when the camera is chosen by default (a
/// later perspective camera is used), an error that says so when `camera` names one.
#[test]
fn orthographic_cameras_are_skipped_or_refused() {
    let mut d = Doc::triangle();
    d.json["cameras"].as_array_mut().unwrap().insert(
        0,
        json!({"name": "flat", "type": "orthographic", "orthographic": {"xmag": 1.0, "ymag": 1.0, "znear": 0.1, "zfar": 10.0}}),
    );
    d.json["nodes"][1]["camera"] = json!(1);
    d.json["nodes"]
        .as_array_mut()
        .unwrap()
        .push(json!({"name": "ortho_node", "camera": 0, "translation": [0.0, 0.0, 9.0]}));
    d.json["scenes"][0]["nodes"] = json!([0, 2, 1]);
    let dir = tempfile::tempdir().unwrap();
    let path = d.write(dir.path());
    let s = load(&path).unwrap();
    assert_eq!(s.camera.position, Vec3::new(0.0, 0.0, 5.0), "the perspective camera after the orthographic one");
    assert_eq!(s.report.warnings.iter().filter(|w| w.contains("orthographic cameras are not supported")).count(), 1);
    for want in ["flat", "ortho_node"] {
        let e = err_of(load_with(&path, &LoadOptions { camera: Some(want.into()), ..Default::default() }));
        assert!(
            e.contains(&format!("camera '{want}' (node 2) is orthographic")) && e.contains("perspective cameras: cam"),
            "{e}"
        );
    }
}

/// Skin weights are divided by their sum (UNSIGNED_BYTE normalized 128/255 alone still
/// moves the vertex the whole way); a vertex whose weights are all 0 stays as stored, with
/// a warning.
#[test]
fn skin_weights_are_normalised() {
    let mut d = Doc::triangle();
    d.json["scenes"][0]["nodes"] = json!([0, 1, 2]);
    d.json["nodes"].as_array_mut().unwrap().push(json!({"name": "joint", "translation": [0.0, 0.0, 1.0]}));
    d.json["nodes"][0]["skin"] = json!(0);
    d.json["skins"] = json!([{"joints": [2]}]);
    let jv = d.push_view(&[0u8; 12], None);
    let ja = d.push_accessor(json!({"bufferView": jv, "componentType": 5121, "count": 3, "type": "VEC4"}));
    let wv = d.push_view(&[128, 0, 0, 0, 128, 0, 0, 0, 0, 0, 0, 0], None);
    let wa = d.push_accessor(
        json!({"bufferView": wv, "componentType": 5121, "normalized": true, "count": 3, "type": "VEC4"}),
    );
    d.prim()["attributes"]["JOINTS_0"] = json!(ja);
    d.prim()["attributes"]["WEIGHTS_0"] = json!(wa);
    let s = d.load().unwrap();
    assert_eq!(s.triangles[0].p, [Vec3::new(0.0, 0.0, 1.0), Vec3::new(1.0, 0.0, 1.0), Vec3::Y]);
    assert!(s.report.warnings.iter().any(|w| w.contains("weights are all 0")), "{:?}", s.report.warnings);
}

/// A skinned node whose primitive has no JOINTS_0/WEIGHTS_0: its vertices as stored (the
/// node's transform is still ignored), with a warning.
#[test]
fn skinned_primitive_without_influences_warns() {
    let mut j = sample_json("SimpleSkin");
    let attrs = j["meshes"][0]["primitives"][0]["attributes"].as_object_mut().unwrap();
    attrs.remove("JOINTS_0");
    attrs.remove("WEIGHTS_0");
    j["nodes"][0]["translation"] = json!([100.0, 0.0, 0.0]);
    let s = load_json(&j, &LoadOptions::default()).unwrap();
    assert_eq!(s.triangles[0].p, [Vec3::new(-0.5, 0.0, 0.0), Vec3::new(0.5, 0.0, 0.0), Vec3::new(0.5, 0.5, 0.0)]);
    let w = &s.report.warnings;
    assert_eq!(w.iter().filter(|w| w.contains("no JOINTS_0/WEIGHTS_0")).count(), 1, "{w:?}");
}

// --- Textures, texture coordinates, vertex colours and alpha (issue #18 items 1-2) ---

use glam::{Vec2, Vec4};
use vkvcm::scene::{AlphaMode, Filter, TextureRef, Wrap};

/// A 2 x 2 RGBA image: red, green / blue, half-transparent white (row by row from the top).
const TEXELS: [[u8; 4]; 4] = [[255, 0, 0, 255], [0, 255, 0, 255], [0, 0, 255, 255], [255, 255, 255, 128]];

fn encode(w: u32, h: u32, texels: &[[u8; 4]], format: image::ImageFormat) -> Vec<u8> {
    let img = image::RgbaImage::from_raw(w, h, texels.concat()).unwrap();
    let mut out = Vec::new();
    match format {
        // JPEG has no alpha.
        image::ImageFormat::Jpeg => {
            image::DynamicImage::ImageRgba8(img).to_rgb8().write_to(&mut std::io::Cursor::new(&mut out), format)
        }
        _ => img.write_to(&mut std::io::Cursor::new(&mut out), format),
    }
    .unwrap();
    out
}

fn png_2x2() -> Vec<u8> {
    encode(2, 2, &TEXELS, image::ImageFormat::Png)
}

impl Doc {
    /// Adds a FLOAT VEC2 TEXCOORD_`k` with these per-vertex values.
    fn texcoord(&mut self, k: u32, uv: &[[f32; 2]]) {
        let v = self.push_view(&f32_bytes(&uv.concat()), None);
        let a = self.push_accessor(json!({"bufferView": v, "componentType": 5126, "count": uv.len(), "type": "VEC2"}));
        self.prim()["attributes"][format!("TEXCOORD_{k}")] = json!(a);
    }

    /// A triangle with TEXCOORD_0 (0,0), (1,0), (0,1) and material 0 using texture 0 (image
    /// 0: the 2 x 2 PNG as a data URI), without a sampler.
    fn textured() -> Doc {
        let mut d = Doc::triangle();
        d.texcoord(0, &[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]);
        d.json["images"] = json!([{"name": "checker", "uri": scene::encode_data_uri(&png_2x2())}]);
        d.json["textures"] = json!([{"source": 0}]);
        d.json["materials"] = json!([{"name": "m", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]);
        d.prim()["material"] = json!(0);
        d
    }
}

fn texture_of(s: &Scene, material: usize) -> TextureRef {
    s.materials[material].base_color_texture.clone().expect("a base colour texture")
}

#[test]
fn base_color_texture_from_a_data_uri() {
    let s = Doc::textured().load().unwrap();
    assert_eq!(s.images.len(), 1);
    let img = &s.images[0];
    assert_eq!((img.width, img.height, img.name.as_str()), (2, 2, "checker"));
    assert_eq!(img.texels, TEXELS.to_vec(), "texels row by row from the top-left, unchanged (sRGB stays encoded)");
    let t = texture_of(&s, 0);
    // No sampler: repeat wrapping and (auto =) linear filtering; no transform.
    assert_eq!(
        t,
        TextureRef {
            image: 0,
            wrap_s: Wrap::Repeat,
            wrap_t: Wrap::Repeat,
            filter: Filter::Linear,
            tex_coord: 0,
            transform: TextureRef::IDENTITY
        }
    );
    let a = s.triangles[0].attributes.as_ref().expect("attributes");
    assert_eq!(a.uv, [Some([Vec2::ZERO, Vec2::X, Vec2::Y]), None]);
    assert_eq!(a.color, None);
    // The metallic/roughness factors are still those of the material (base factor 1).
    assert_eq!(s.materials[0].diffuse, Vec3::ZERO, "glTF's default metallic is 1");
    assert!(s.report.warnings.iter().all(|w| !w.contains("texture")), "{:?}", s.report.warnings);
}

#[test]
fn samplers_and_shared_images() {
    let mut d = Doc::textured();
    d.json["samplers"] = json!([
        {"wrapS": 33071, "wrapT": 33648, "magFilter": 9728, "minFilter": 9984},
        {"wrapT": 33071, "magFilter": 9729, "minFilter": 9987},
        {"minFilter": 9728},
    ]);
    d.json["textures"] = json!([{"source": 0, "sampler": 0}, {"source": 0, "sampler": 1}, {"source": 0, "sampler": 2}]);
    d.json["materials"] = json!([
        {"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}},
        {"pbrMetallicRoughness": {"baseColorTexture": {"index": 1}}},
        {"pbrMetallicRoughness": {"baseColorTexture": {"index": 2}}},
    ]);
    let s = d.load().unwrap();
    assert_eq!(s.images.len(), 1, "one image decoded once for three textures");
    let t: Vec<TextureRef> = (0..3).map(|i| texture_of(&s, i)).collect();
    assert!(t.iter().all(|t| t.image == 0));
    assert_eq!((t[0].wrap_s, t[0].wrap_t, t[0].filter), (Wrap::ClampToEdge, Wrap::MirroredRepeat, Filter::Nearest));
    // A mip-map minification filter: bilinear (no mip-maps are used).
    assert_eq!((t[1].wrap_s, t[1].wrap_t, t[1].filter), (Wrap::Repeat, Wrap::ClampToEdge, Filter::Linear));
    // Only the magnification filter selects NEAREST.
    assert_eq!(t[2].filter, Filter::Linear);

    // A bad enum value is a validation error naming the field.
    let mut d = Doc::textured();
    d.json["samplers"] = json!([{"wrapS": 12345}]);
    d.json["textures"][0]["sampler"] = json!(0);
    let e = err_of(d.load());
    assert!(e.contains("samplers[0].wrapS"), "{e}");
}

#[test]
fn images_from_buffer_views_files_and_jpeg() {
    // A PNG in a buffer view (mimeType required there).
    let mut d = Doc::textured();
    let v = d.push_view(&png_2x2(), None);
    d.json["images"] = json!([{"bufferView": v, "mimeType": "image/png"}]);
    let s = d.load().unwrap();
    assert_eq!(s.images[0].texels, TEXELS.to_vec());
    assert_eq!(s.images[0].name, "image0");

    // A JPEG file next to the scene (a uniform colour survives the compression closely).
    let dir = tempfile::tempdir().unwrap();
    let grey = [[200u8, 100, 50, 255]; 64];
    std::fs::write(dir.path().join("tex.jpg"), encode(8, 8, &grey, image::ImageFormat::Jpeg)).unwrap();
    let mut d = Doc::textured();
    d.json["images"] = json!([{"uri": "tex.jpg"}]);
    let s = load(&d.write(dir.path())).unwrap();
    let img = &s.images[0];
    assert_eq!((img.width, img.height, img.name.as_str()), (8, 8, "tex.jpg"));
    for t in &img.texels {
        assert!(t.iter().zip([200u8, 100, 50, 255]).all(|(a, b)| a.abs_diff(b) <= 3), "{t:?}");
    }

    // Unreadable images: errors naming the material, the texture and the image.
    let mut d = Doc::textured();
    d.json["images"] = json!([{"uri": "missing.png"}]);
    let e = err_of(d.load());
    assert!(
        e.contains("material 0 'm' baseColorTexture (texture 0)") && e.contains("image 0") && e.contains("missing.png"),
        "{e}"
    );
    let mut d = Doc::textured();
    d.json["images"] = json!([{"name": "junk", "uri": scene::encode_data_uri(b"not an image")}]);
    let e = err_of(d.load());
    assert!(e.contains("image 0 'junk'") && e.contains("not a PNG or JPEG"), "{e}");
    let mut d = Doc::textured();
    d.json["images"] = json!([{"uri": "../outside.png"}]);
    assert!(err_of(d.load()).contains("images must stay inside the scene's folder"));
    // A truncated PNG: a decoder error, not a panic.
    let mut d = Doc::textured();
    let png = png_2x2();
    d.json["images"] = json!([{"uri": scene::encode_data_uri(&png[..png.len() - 20])}]);
    let e = err_of(d.load());
    assert!(e.contains("cannot decode the PNG image"), "{e}");
}

#[test]
fn texture_transform_and_tex_coord_override() {
    let mut d = Doc::textured();
    d.texcoord(1, &[[0.5, 0.5], [0.25, 0.5], [0.5, 0.25]]);
    d.json["extensionsUsed"] = json!(["KHR_texture_transform"]);
    d.json["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"] = json!({
        "KHR_texture_transform": {"offset": [0.25, 0.5], "rotation": std::f64::consts::FRAC_PI_2, "scale": [2.0, 3.0], "texCoord": 1}
    });
    let s = d.load().unwrap();
    let t = texture_of(&s, 0);
    assert_eq!(t.tex_coord, 1, "texCoord of KHR_texture_transform overrides the textureInfo's");
    // T * R * S at r = pi/2 (cos 0, sin 1): rows [0, sy, ox] and [-sx, 0, oy].
    let want = [[0.0, 3.0, 0.25], [-2.0, 0.0, 0.5]];
    let got = t.transform.iter().flatten();
    assert!(got.zip(want.iter().flatten()).all(|(a, b)| (a - b).abs() < 1e-6), "{:?}", t.transform);
    assert!(s.report.warnings.iter().all(|w| !w.contains("KHR_texture_transform")), "{:?}", s.report.warnings);
    let a = s.triangles[0].attributes.as_ref().unwrap();
    assert_eq!(a.uv[1], Some([Vec2::splat(0.5), Vec2::new(0.25, 0.5), Vec2::new(0.5, 0.25)]));

    let mut d = Doc::textured();
    d.json["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"] =
        json!({"KHR_texture_transform": {"scale": [1.0, "x"]}});
    let e = err_of(d.load());
    assert!(e.contains("KHR_texture_transform.scale[1] must be a finite number"), "{e}");
}

#[test]
fn texture_on_missing_texture_coordinates_is_not_applied() {
    let mut d = Doc::textured();
    d.json["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["texCoord"] = json!(1);
    let s = d.load().unwrap();
    assert_eq!(texture_of(&s, 0).tex_coord, 1);
    // TEXCOORD_0 stays (other textures may use it); the missing set 1 makes the kernels
    // use the factor alone (tests/render_textures.rs).
    let a = s.triangles[0].attributes.as_ref().expect("TEXCOORD_0 is kept");
    assert!(a.uv[0].is_some() && a.uv[1].is_none());
    assert!(
        s.report.warnings.iter().any(|w| w.contains("TEXCOORD_1, which the primitive does not have")),
        "{:?}",
        s.report.warnings
    );
    // TEXCOORD_2 and above are not read: the texture is dropped.
    let mut d = Doc::textured();
    d.json["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["texCoord"] = json!(2);
    let s = d.load().unwrap();
    assert_eq!(s.materials[0].base_color_texture, None);
    assert!(
        s.report.warnings.iter().any(|w| w.contains("only TEXCOORD_0 and TEXCOORD_1 are read")),
        "{:?}",
        s.report.warnings
    );
}

#[test]
fn extension_only_texture_sources_are_ignored() {
    let mut d = Doc::textured();
    d.json["extensionsUsed"] = json!(["KHR_texture_basisu"]);
    d.json["textures"] = json!([{"extensions": {"KHR_texture_basisu": {"source": 0}}}]);
    let s = d.load().unwrap();
    assert_eq!(s.materials[0].base_color_texture, None);
    assert!(s.images.is_empty());
    assert!(
        s.report.warnings.iter().any(|w| w.contains("given only by KHR_texture_basisu")),
        "{:?}",
        s.report.warnings
    );
    // With a core `source` as well (the extension's fallback), that one is used.
    let mut d = Doc::textured();
    d.json["extensionsUsed"] = json!(["EXT_texture_webp"]);
    d.json["textures"] = json!([{"source": 0, "extensions": {"EXT_texture_webp": {"source": 0}}}]);
    let s = d.load().unwrap();
    assert_eq!(texture_of(&s, 0).image, 0);
    assert_eq!(s.images[0].texels, TEXELS.to_vec());
}

#[test]
fn alpha_factor_and_modes() {
    let load_mode = |m: Value| {
        let mut d = Doc::triangle();
        d.json["materials"] = json!([m]);
        d.prim()["material"] = json!(0);
        d.load()
    };
    let s = load_mode(json!({"pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 0.25]}})).unwrap();
    assert_eq!((s.materials[0].alpha, s.materials[0].alpha_mode), (0.25, AlphaMode::Opaque));
    let s = load_mode(json!({"alphaMode": "MASK"})).unwrap();
    assert_eq!((s.materials[0].alpha, s.materials[0].alpha_mode), (1.0, AlphaMode::Mask { cutoff: 0.5 }));
    let s = load_mode(json!({"alphaMode": "MASK", "alphaCutoff": 0.75})).unwrap();
    assert_eq!(s.materials[0].alpha_mode, AlphaMode::Mask { cutoff: 0.75 });
    assert!(s.report.warnings.iter().all(|w| !w.contains("alpha")), "{:?}", s.report.warnings);
    let s = load_mode(
        json!({"alphaMode": "BLEND", "alphaCutoff": 0.75, "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 0.5]}}),
    )
    .unwrap();
    assert_eq!((s.materials[0].alpha, s.materials[0].alpha_mode), (0.5, AlphaMode::Blend));
    assert!(s.report.warnings.iter().all(|w| !w.contains("alpha")), "{:?}", s.report.warnings);
    let e = err_of(load_mode(json!({"alphaMode": "MASK", "alphaCutoff": -1})));
    assert!(e.contains("alphaCutoff -1 must be a finite number >= 0"), "{e}");
}

#[test]
fn texcoord_formats_decode_per_the_spec() {
    let with_uv = |ct: u32, norm: bool, bytes: Vec<u8>, stride: usize, quantized: bool| {
        let mut d = Doc::triangle();
        if quantized {
            d.json["extensionsUsed"] = json!(["KHR_mesh_quantization"]);
        }
        let v = d.push_view(&bytes, Some(stride));
        let a = d.push_accessor(
            json!({"bufferView": v, "componentType": ct, "normalized": norm, "count": 3, "type": "VEC2"}),
        );
        d.prim()["attributes"]["TEXCOORD_0"] = json!(a);
        d.load().map(|s| s.triangles[0].attributes.as_ref().unwrap().uv[0].unwrap())
    };
    // UNSIGNED_BYTE normalized (core): c / 255; elements padded to 4 bytes.
    let uv = with_uv(5121, true, vec![0, 0, 0, 0, 255, 0, 0, 0, 0, 51, 0, 0], 4, false).unwrap();
    assert_eq!(uv, [Vec2::ZERO, Vec2::X, Vec2::new(0.0, (51.0f64 / 255.0) as f32)]);
    // UNSIGNED_SHORT normalized (core): c / 65535.
    let us: Vec<u8> = [0u16, 0, 65535, 0, 0, 13107].iter().flat_map(|x| x.to_le_bytes()).collect();
    let uv = with_uv(5123, true, us, 4, false).unwrap();
    assert_eq!(uv, [Vec2::ZERO, Vec2::X, Vec2::new(0.0, (13107.0f64 / 65535.0) as f32)]);
    // KHR_mesh_quantization: plain SHORT as integers, BYTE normalized max(c / 127, -1).
    let sh: Vec<u8> = [0i16, 0, -3, 7, 2, -1].iter().flat_map(|x| x.to_le_bytes()).collect();
    let uv = with_uv(5122, false, sh.clone(), 4, true).unwrap();
    assert_eq!(uv, [Vec2::ZERO, Vec2::new(-3.0, 7.0), Vec2::new(2.0, -1.0)]);
    let b: Vec<u8> = [0i8, 0, 0, 0, 127, -128, 0, 0, 64, 0, 0, 0].iter().map(|x| *x as u8).collect();
    let uv = with_uv(5120, true, b, 4, true).unwrap();
    assert_eq!(uv, [Vec2::ZERO, Vec2::new(1.0, -1.0), Vec2::new((64.0f64 / 127.0) as f32, 0.0)]);
    // Without the extension, SHORT is refused with the reason.
    let e = err_of(with_uv(5122, false, sh, 4, false).map(|_| unreachable!()));
    assert!(e.contains("TEXCOORD_0") && e.contains("KHR_mesh_quantization"), "{e}");
}

#[test]
fn vertex_colours() {
    let with_color = |ct: u32, ty: &str, bytes: Vec<u8>| {
        let mut d = Doc::triangle();
        let v = d.push_view(&bytes, None);
        let norm = ct != 5126;
        let a =
            d.push_accessor(json!({"bufferView": v, "componentType": ct, "normalized": norm, "count": 3, "type": ty}));
        d.prim()["attributes"]["COLOR_0"] = json!(a);
        d.load()
    };
    // FLOAT VEC3: alpha 1.
    let s = with_color(5126, "VEC3", f32_bytes(&[1.0, 0.0, 0.0, 0.0, 0.5, 0.0, 0.0, 0.0, 0.25])).unwrap();
    let a = s.triangles[0].attributes.as_ref().unwrap();
    assert_eq!(a.uv, [None, None]);
    assert_eq!(
        a.color,
        Some([Vec4::new(1.0, 0.0, 0.0, 1.0), Vec4::new(0.0, 0.5, 0.0, 1.0), Vec4::new(0.0, 0.0, 0.25, 1.0)])
    );
    assert!(s.report.warnings.iter().all(|w| !w.contains("COLOR")), "{:?}", s.report.warnings);
    // UNSIGNED_BYTE normalized VEC4: c / 255.
    let s = with_color(5121, "VEC4", vec![255, 0, 0, 51, 0, 255, 0, 255, 0, 0, 255, 0]).unwrap();
    let c = s.triangles[0].attributes.as_ref().unwrap().color.unwrap();
    assert_eq!(c[0], Vec4::new(1.0, 0.0, 0.0, (51.0f64 / 255.0) as f32));
    assert_eq!(c[2], Vec4::new(0.0, 0.0, 1.0, 0.0));
    // Out-of-range floats are clamped, with one warning.
    let s =
        with_color(5126, "VEC4", f32_bytes(&[2.0, -1.0, 0.5, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0])).unwrap();
    assert_eq!(s.triangles[0].attributes.as_ref().unwrap().color.unwrap()[0], Vec4::new(1.0, 0.0, 0.5, 1.0));
    assert!(s.report.warnings.iter().any(|w| w.contains("COLOR_0 values outside [0, 1] are clamped")));
    // A wrong type is an error naming the attribute.
    let e = err_of(with_color(5126, "VEC2", f32_bytes(&[0.0; 6])));
    assert!(e.contains("COLOR_0") && e.contains("VEC3/VEC4"), "{e}");
    // A count other than POSITION's is an error.
    let e = err_of(with_color(5126, "VEC3", f32_bytes(&[0.0; 9])).and_then(|_| {
        let mut d = Doc::triangle();
        let v = d.push_view(&f32_bytes(&[0.0; 6]), None);
        let a = d.push_accessor(json!({"bufferView": v, "componentType": 5126, "count": 2, "type": "VEC3"}));
        d.prim()["attributes"]["COLOR_0"] = json!(a);
        d.load()
    }));
    assert!(e.contains("COLOR_0 accessor 1 has 2 elements, the primitive has 3 vertices"), "{e}");
}

#[test]
fn mirrored_nodes_swap_attributes_with_vertices() {
    let mut d = Doc::textured();
    let v = d.push_view(&f32_bytes(&[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]), None);
    let a = d.push_accessor(json!({"bufferView": v, "componentType": 5126, "count": 3, "type": "VEC3"}));
    d.prim()["attributes"]["COLOR_0"] = json!(a);
    d.json["nodes"][0]["scale"] = json!([-1.0, 1.0, 1.0]);
    let s = d.load().unwrap();
    let t = &s.triangles[0];
    assert_eq!(t.p, [Vec3::ZERO, Vec3::new(0.0, 1.0, 0.0), Vec3::new(-1.0, 0.0, 0.0)]);
    let a = t.attributes.as_ref().unwrap();
    assert_eq!(a.uv[0], Some([Vec2::ZERO, Vec2::Y, Vec2::X]), "uvs follow their vertices");
    assert_eq!(a.color.unwrap().map(|c| c.truncate()), [Vec3::X, Vec3::Z, Vec3::Y]);
}

#[test]
fn triangles_without_texcoords_or_colours_have_no_attributes() {
    let s = Doc::triangle().load().unwrap();
    assert_eq!(s.triangles[0].attributes, None);
    assert!(s.images.is_empty());
}

/// Morph targets displace TEXCOORD_0 and COLOR_0 (gltf-json drops them: read from the raw
/// JSON) at the weights in force, like positions; a VEC3 colour displacement leaves alpha
/// alone; TEXCOORD_2 displacements are named in a warning; a displacement accessor that
/// does not exist is an error naming the target.
#[test]
fn morph_targets_of_texture_coordinates_and_colours() {
    let mut d = Doc::textured();
    let colours = [[1.0f32, 1.0, 1.0, 1.0], [1.0, 0.0, 0.0, 1.0], [0.0, 1.0, 0.0, 1.0]];
    let v = d.push_view(&f32_bytes(&colours.concat()), None);
    let c = d.push_accessor(json!({"bufferView": v, "componentType": 5126, "count": 3, "type": "VEC4"}));
    d.prim()["attributes"]["COLOR_0"] = json!(c);
    let uv = d.push_view(&f32_bytes(&[0.5, 0.0, 0.0, 0.0, 0.0, 0.5]), None);
    let duv = d.push_accessor(json!({"bufferView": uv, "componentType": 5126, "count": 3, "type": "VEC2"}));
    // Signed normalized bytes: -127 is -1.
    let dc = d.push_view(&[0i8, 0, 0, -127, 0, 0, 0, 0, 0].map(|b| b as u8), None);
    let dcol = d.push_accessor(
        json!({"bufferView": dc, "componentType": 5120, "normalized": true, "count": 3, "type": "VEC3"}),
    );
    d.prim()["targets"] = json!([{"TEXCOORD_0": duv}, {"COLOR_0": dcol, "TEXCOORD_2": duv}]);
    d.json["meshes"][0]["weights"] = json!([0.5, 0.25]);
    let s = d.load().unwrap();
    let a = s.triangles[0].attributes.as_ref().unwrap();
    assert_eq!(a.uv[0], Some([Vec2::new(0.25, 0.0), Vec2::X, Vec2::new(0.0, 1.25)]));
    assert_eq!(
        a.color,
        Some([Vec4::new(1.0, 1.0, 1.0, 1.0), Vec4::new(0.75, 0.0, 0.0, 1.0), Vec4::new(0.0, 1.0, 0.0, 1.0)])
    );
    let w = &s.report.warnings;
    assert!(w.iter().any(|w| w.contains("morph-target displacements") && w.contains("targets[1].TEXCOORD_2")), "{w:?}");
    assert!(!w.iter().any(|w| w.contains("TEXCOORD_0") || w.contains("COLOR_0")), "{w:?}");
    // Without weights (all 0) nothing moves.
    d.json["meshes"][0].as_object_mut().unwrap().remove("weights");
    let s = d.load().unwrap();
    assert_eq!(s.triangles[0].attributes.as_ref().unwrap().uv[0], Some([Vec2::ZERO, Vec2::X, Vec2::Y]));
    d.prim()["targets"][0]["TEXCOORD_0"] = json!(99);
    let e = err_of(d.load());
    assert!(e.contains("targets[0].TEXCOORD_0 refers to accessor 99"), "{e}");
}

/// TANGENT displacements move the tangents' xyz (the bitangent sign stays).
#[test]
fn morph_targets_of_tangents() {
    let mut d = normal_mapped();
    let v = d.push_view(&f32_bytes(&[[0.0f32, 1.0, 0.0, -1.0]; 3].concat()), None);
    let a = d.push_accessor(json!({"bufferView": v, "componentType": 5126, "count": 3, "type": "VEC4"}));
    d.prim()["attributes"]["TANGENT"] = json!(a);
    let dv = d.push_view(&f32_bytes(&[[1.0f32, -1.0, 0.0]; 3].concat()), None);
    let dt = d.push_accessor(json!({"bufferView": dv, "componentType": 5126, "count": 3, "type": "VEC3"}));
    d.prim()["targets"] = json!([{"TANGENT": dt}]);
    d.json["meshes"][0]["weights"] = json!([1.0]);
    let s = d.load().unwrap();
    let t = s.triangles[0].attributes.as_ref().unwrap().tangent.unwrap();
    assert_eq!(t, [glam::Vec4::new(1.0, 0.0, 0.0, -1.0); 3]);
}

#[test]
fn fingerprint_covers_texture_coordinates_colours_and_texels() {
    let base = Doc::textured().load().unwrap().fingerprint();
    let mut d = Doc::textured();
    d.texcoord(0, &[[0.0, 0.0], [1.0, 0.0], [0.0, 0.5]]);
    assert_ne!(d.load().unwrap().fingerprint(), base, "a texture coordinate");
    let mut texels = TEXELS;
    texels[3][3] = 127;
    let mut d = Doc::textured();
    d.json["images"][0]["uri"] = json!(scene::encode_data_uri(&encode(2, 2, &texels, image::ImageFormat::Png)));
    assert_ne!(d.load().unwrap().fingerprint(), base, "a texel");
    let mut d = Doc::textured();
    d.json["samplers"] = json!([{"magFilter": 9728}]);
    d.json["textures"][0]["sampler"] = json!(0);
    assert_ne!(d.load().unwrap().fingerprint(), base, "a sampler");
    let mut s = Doc::textured().load().unwrap();
    assert_eq!(s.fingerprint(), base);
    s.triangles[0].attributes.as_mut().unwrap().color = Some([Vec4::ONE; 3]);
    assert_ne!(s.fingerprint(), base, "a vertex colour");
    let mut s = Doc::textured().load().unwrap();
    s.triangles[0].attributes.as_mut().unwrap().tangent = Some([Vec4::X; 3]);
    assert_ne!(s.fingerprint(), base, "a tangent");
}

/// Khronos BoxTextured: 12 triangles, all with TEXCOORD_0; its one material's
/// baseColorTexture is a 211 x 211 PNG (its IHDR), sampler REPEAT/REPEAT, LINEAR magnification
/// (LINEAR_MIPMAP_LINEAR minification: bilinear here).
#[test]
fn khronos_box_textured() {
    let s = load(&khronos("BoxTextured")).unwrap();
    assert_eq!(s.triangles.len(), 12);
    assert!(s
        .triangles
        .iter()
        .all(|t| t.attributes.as_ref().is_some_and(|a| a.uv[0].is_some() && a.uv[1].is_none() && a.color.is_none())));
    assert_eq!(s.images.len(), 1);
    let img = &s.images[0];
    assert_eq!(img.texels.len(), (img.width * img.height) as usize);
    assert_eq!((img.width, img.height), (211, 211));
    let t = texture_of(&s, 0);
    assert_eq!((t.wrap_s, t.wrap_t, t.filter, t.tex_coord), (Wrap::Repeat, Wrap::Repeat, Filter::Linear, 0));
    assert_eq!(s.materials[0].alpha_mode, AlphaMode::Opaque);
    assert!(s.report.warnings.iter().all(|w| !w.contains("texture")), "{:?}", s.report.warnings);
}

/// Khronos TextureCoordinateTest: four textured quads (materials 1-4 share texture 0, so
/// one image) and an untextured back plane without TEXCOORD_0 (no attributes).
#[test]
fn khronos_texture_coordinate_test() {
    let s = load(&khronos("TextureCoordinateTest")).unwrap();
    assert_eq!(s.images.len(), 1);
    assert_eq!(s.materials[0].base_color_texture, None);
    for m in 1..5 {
        let t = texture_of(&s, m);
        assert_eq!((t.image, t.wrap_s, t.wrap_t, t.filter), (0, Wrap::Repeat, Wrap::Repeat, Filter::Linear));
    }
    let with = s.triangles.iter().filter(|t| t.attributes.is_some()).count();
    assert_eq!(with, 8, "four quads of two triangles");
    assert!(s.triangles.iter().filter(|t| t.material == 0).all(|t| t.attributes.is_none()));
    assert!(s.report.warnings.iter().all(|w| !w.contains("texture")), "{:?}", s.report.warnings);
}

/// Khronos BoxVertexColors: 12 triangles with FLOAT VEC4 COLOR_0 (and TEXCOORD_0).
#[test]
fn khronos_box_vertex_colors() {
    let s = load(&khronos("BoxVertexColors")).unwrap();
    assert_eq!(s.triangles.len(), 12);
    for t in &s.triangles {
        let a = t.attributes.as_ref().expect("attributes");
        let c = a.color.expect("COLOR_0");
        assert!(c.iter().all(|c| c.min_element() >= 0.0 && c.max_element() <= 1.0));
        assert!(a.uv[0].is_some());
    }
    assert!(s.images.is_empty());
    assert!(s.report.warnings.iter().all(|w| !w.contains("COLOR")), "{:?}", s.report.warnings);
}

/// `Doc::textured` with the texture as a normal map (scale 0.5) instead of a base colour.
fn normal_mapped() -> Doc {
    let mut d = Doc::textured();
    d.json["materials"] = json!([{"name": "bumpy", "normalTexture": {"index": 0, "scale": 0.5}}]);
    d
}

#[test]
fn normal_maps_get_mikktspace_tangents_when_the_file_has_none() {
    let s = normal_mapped().load().unwrap();
    let m = &s.materials[0];
    assert_eq!(m.normal_texture.as_ref().map(|t| (t.image, t.tex_coord)), Some((0, 0)));
    assert_eq!(m.normal_scale, 0.5);
    assert!(s.report.warnings.iter().all(|w| !w.contains("normalTexture")), "{:?}", s.report.warnings);
    // The triangle (0,0,0), (1,0,0), (0,1,0) with uv (0,0), (1,0), (0,1): u grows along +x
    // and v along +y; its normal is +z, so the tangent is +x. The normal map's +Y is up
    // in its image, towards decreasing v (glTF's texture origin is the top-left corner):
    // -y = -cross(+z, +x), sign -1 (the image is mirrored on this triangle).
    let t = s.triangles[0].attributes.as_ref().unwrap().tangent.expect("generated tangents");
    for v in t {
        assert!((v - glam::Vec4::new(1.0, 0.0, 0.0, -1.0)).abs().max_element() < 1e-5, "{v:?}");
    }
}

#[test]
fn tangents_are_read_and_follow_mirroring() {
    let mut d = normal_mapped();
    let tangents = [[0.0f32, 1.0, 0.0, -1.0]; 3];
    let v = d.push_view(&f32_bytes(&tangents.concat()), None);
    let a = d.push_accessor(json!({"bufferView": v, "componentType": 5126, "count": 3, "type": "VEC4"}));
    d.prim()["attributes"]["TANGENT"] = json!(a);
    let s = d.load().unwrap();
    let t = s.triangles[0].attributes.as_ref().unwrap().tangent.unwrap();
    assert_eq!(t, [glam::Vec4::new(0.0, 1.0, 0.0, -1.0); 3], "the file's tangents, not generated ones");
    // Mirrored in x: the tangent (0, 1, 0) stays, its bitangent sign flips (the bitangent
    // w cross(n, t) must follow the mirrored surface).
    d.json["nodes"][0]["scale"] = json!([-1.0, 1.0, 1.0]);
    let s = d.load().unwrap();
    let t = s.triangles[0].attributes.as_ref().unwrap().tangent.unwrap();
    assert_eq!(t, [glam::Vec4::new(0.0, 1.0, 0.0, 1.0); 3]);
}

/// emissiveTexture is read (sRGB, as the base colour) when the material emits:
/// emission = emissiveFactor x texture; without a factor (glTF's default 0) nothing emits
/// and the texture is not kept. occlusionTexture, which a path tracer does not need (it
/// computes occlusion), gives no warning.
#[test]
fn emissive_textures_are_read_and_occlusion_is_silent() {
    let mut d = Doc::textured();
    d.json["materials"] = json!([{
        "name": "glow",
        "emissiveFactor": [1.0, 0.5, 0.25],
        "emissiveTexture": {"index": 0},
        "occlusionTexture": {"index": 0}
    }]);
    let s = d.load().unwrap();
    let m = &s.materials[0];
    assert_eq!(m.emission, Vec3::new(1.0, 0.5, 0.25));
    assert_eq!(m.emissive_texture.as_ref().map(|t| (t.image, t.tex_coord)), Some((0, 0)));
    assert!(s.report.warnings.iter().all(|w| !w.contains("emissiveTexture")), "{:?}", s.report.warnings);
    assert!(s.report.warnings.iter().all(|w| !w.contains("occlusion")), "{:?}", s.report.warnings);
    assert!(matches!(s.lights[0], vkvcm::scene::Light::Area { .. }));

    d.json["materials"][0].as_object_mut().unwrap().remove("emissiveFactor");
    let s = d.load().unwrap();
    assert_eq!(s.materials[0].emission, Vec3::ZERO);
    assert!(s.materials[0].emissive_texture.is_none());
}

/// metallicRoughnessTexture is read (glTF 2.0 section 3.9.2) with its sampler, texCoord and
/// KHR_texture_transform, and kept with the factors it multiplies; the material's own
/// lobes are the factors' (a smooth metal stays a GGX lobe, not a mirror, as the texture
/// may make a point less metallic or rougher). A primitive without the texture's
/// coordinates is named in a warning (the factors alone apply there).
#[test]
fn metallic_roughness_textures_are_read() {
    let mut d = Doc::textured();
    d.json["extensionsUsed"] = json!(["KHR_texture_transform"]);
    d.json["samplers"] = json!([{"wrapS": 33071, "magFilter": 9728}]);
    d.json["textures"] = json!([{"source": 0, "sampler": 0}]);
    d.json["materials"] = json!([{"name": "m", "pbrMetallicRoughness": {
        "baseColorFactor": [0.5, 0.25, 1.0, 1.0], "metallicFactor": 1.0, "roughnessFactor": 0.0,
        "metallicRoughnessTexture": {"index": 0, "extensions": {"KHR_texture_transform": {"offset": [0.5, 0.0]}}}
    }}]);
    let s = d.load().unwrap();
    let m = &s.materials[0];
    let base = Vec3::new(0.5, 0.25, 1.0);
    let want = scene::MetallicRoughnessTexture {
        texture: TextureRef {
            image: 0,
            wrap_s: Wrap::ClampToEdge,
            wrap_t: Wrap::Repeat,
            filter: Filter::Nearest,
            tex_coord: 0,
            transform: [[1.0, 0.0, 0.5], [0.0, 1.0, 0.0]],
        },
        base,
        metallic: 1.0,
        roughness: 0.0,
        dielectric_f0: Vec3::splat(scene::GLTF_DIELECTRIC_F0),
    };
    assert_eq!(m.metallic_roughness_texture.as_ref(), Some(&want));
    assert_eq!((m.mirror, m.glossy, m.diffuse, m.roughness), (Vec3::ZERO, base, Vec3::ZERO, 0.0));
    assert_eq!(m.diffuse_fresnel_f0, scene::GLTF_DIELECTRIC_F0, "texels below metallic 1 are diffuse");
    assert_eq!(s.images[0].texels, TEXELS.to_vec(), "texels unchanged (read as linear by the kernels)");
    assert!(s.report.warnings.iter().all(|w| !w.contains("texture")), "{:?}", s.report.warnings);

    d.json["materials"][0]["pbrMetallicRoughness"]["metallicRoughnessTexture"]["texCoord"] = json!(1);
    let s = d.load().unwrap();
    let w = &s.report.warnings;
    assert!(
        w.iter().any(|w| w.contains("metallicRoughnessTexture on TEXCOORD_1, which the primitive does not have")),
        "{w:?}"
    );
}

/// KHR_materials_ior and KHR_materials_specular set the dielectric's F0 of a
/// metallic/roughness material: ((ior - 1) / (ior + 1))^2, times specularColorFactor
/// (clamped to 1) and specularFactor; specularFactor 0 leaves a plain Lambertian.
#[test]
fn specular_and_ior_set_the_dielectric_f0() {
    let mut d = Doc::triangle();
    d.json["extensionsUsed"] = json!(["KHR_materials_specular", "KHR_materials_ior"]);
    d.json["materials"] = json!([{"name": "m", "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1.0], "metallicFactor": 0.0}}]);
    d.json["meshes"][0]["primitives"][0]["material"] = json!(0);
    let m = d.load().unwrap().materials[0].clone();
    assert_eq!((m.glossy, m.diffuse_fresnel_f0), (Vec3::splat(0.04), 0.04));

    d.json["materials"][0]["extensions"] = json!({"KHR_materials_ior": {"ior": 2.0}});
    let m = d.load().unwrap().materials[0].clone();
    assert!((m.glossy - Vec3::splat(1.0 / 9.0)).abs().max_element() < 1e-6, "{:?}", m.glossy);

    d.json["materials"][0]["extensions"] =
        json!({"KHR_materials_specular": {"specularColorFactor": [2.0, 1.0, 0.0], "specularFactor": 1.0}});
    let s = d.load().unwrap();
    let m = &s.materials[0];
    assert!((m.glossy - Vec3::new(0.08, 0.04, 0.0)).abs().max_element() < 1e-6, "{:?}", m.glossy);
    assert_eq!(m.diffuse_fresnel_f0, 0.08);
    assert!(s.report.warnings.iter().all(|w| !w.contains("KHR_materials_specular")), "{:?}", s.report.warnings);

    d.json["materials"][0]["extensions"] = json!({"KHR_materials_specular": {"specularFactor": 0.0}});
    let m = d.load().unwrap().materials[0].clone();
    assert_eq!((m.glossy, m.diffuse_fresnel_f0, m.diffuse), (Vec3::ZERO, 0.0, Vec3::splat(0.5)));

    d.json["materials"][0]["extensions"] = json!({"KHR_materials_specular": {"specularFactor": 0.5}});
    let s = d.load().unwrap();
    assert!((s.materials[0].glossy - Vec3::splat(0.02)).abs().max_element() < 1e-6);
    assert!(s.report.warnings.iter().any(|w| w.contains("specularFactor between 0 and 1")), "{:?}", s.report.warnings);
}

/// A mesh placed by several rigid nodes and by EXT_mesh_gpu_instancing is stored once
/// and instanced; the emitting panel placed twice stays world-space triangles (area
/// lights); expanding the instances gives the triangles of the flattened load
/// (`flatten_instances`), mirrored and non-uniformly scaled placements included.
#[test]
fn shared_meshes_are_instanced_and_expand_to_the_flattened_load() {
    let dir = tempfile::tempdir().unwrap();
    let path = common::instanced_gltf::write_instanced_gltf(dir.path());
    let inst = load(&path).unwrap();
    let flat = load_with(&path, &LoadOptions { flatten_instances: true, ..Default::default() }).unwrap();
    assert!(inst.report.warnings.is_empty(), "{:?}", inst.report.warnings);
    assert_eq!(inst.meshes.len(), 1, "only the sphere is shared");
    // 320 triangles, of which the 32 that meet a pole have zero area (dropped).
    assert_eq!(inst.meshes[0].count, 288);
    assert_eq!(inst.instances.len(), 7, "four nodes and three EXT_mesh_gpu_instancing transforms");
    assert_eq!(inst.world_triangles().len(), 6, "the floor and the two panels");
    assert!(flat.meshes.is_empty() && flat.instances.is_empty());
    assert_eq!(inst.placed_triangles(), flat.triangles.len() as u64);
    let area = |s: &Scene| s.lights.iter().filter(|l| matches!(l, Light::Area { .. })).count();
    assert_eq!((area(&inst), area(&flat)), (4, 4));
    let expanded = inst.flattened_triangles();
    assert_eq!(expanded.len(), flat.triangles.len());
    for (k, (a, b)) in expanded.iter().zip(&flat.triangles).enumerate() {
        for v in 0..3 {
            assert!(a.p[v].abs_diff_eq(b.p[v], 1e-5), "triangle {k} vertex {v}: {} vs {}", a.p[v], b.p[v]);
            assert_eq!(a.n.is_some(), b.n.is_some(), "triangle {k}");
            if let (Some(na), Some(nb)) = (a.n, b.n) {
                assert!(na[v].abs_diff_eq(nb[v], 1e-5), "triangle {k} normal {v}: {} vs {}", na[v], nb[v]);
            }
        }
    }
    let (lo_a, hi_a) = inst.bounds();
    let (lo_b, hi_b) = flat.bounds();
    assert!(lo_a.abs_diff_eq(lo_b, 1e-5) && hi_a.abs_diff_eq(hi_b, 1e-5), "bounds {lo_a} {hi_a} vs {lo_b} {hi_b}");
    assert_ne!(inst.fingerprint(), flat.fingerprint());
}

/// A placement of a shared mesh whose matrix is singular is skipped with a warning (its
/// flattened triangles would all be degenerate); EXT_mesh_gpu_instancing attributes of
/// different counts are an error naming the node.
#[test]
fn singular_placements_and_mismatched_instancing_attributes() {
    let mut j = common::instanced_gltf::instanced_gltf();
    j["nodes"][6]["scale"] = json!([0.0, 1.2, 0.9]);
    let s = load_json(&j, &LoadOptions::default()).unwrap();
    assert_eq!(s.instances.len(), 6);
    assert!(
        s.report.warnings.iter().any(|w| w.contains("singular") && w.contains("stretched")),
        "{:?}",
        s.report.warnings
    );

    let mut j = common::instanced_gltf::instanced_gltf();
    // TRANSLATION with the sphere's normals: a VEC3 FLOAT accessor of another count.
    j["nodes"][9]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"]["TRANSLATION"] = json!(1);
    let e = err_of(load_json(&j, &LoadOptions::default()));
    assert!(e.contains("node 9 EXT_mesh_gpu_instancing") && e.contains("different counts"), "{e}");
}

/// KHR_materials_clearcoat: its factors reach the material (clamped to [0, 1]), so do its
/// normal texture and that texture's scale (default 1) without a warning, a texture index
/// out of range is an error, and the extension is no longer an unsupported one.
#[test]
fn clearcoat_factors_are_read() {
    let mut d = Doc::triangle();
    d.json["extensionsUsed"] = json!(["KHR_materials_clearcoat"]);
    let coat =
        |f: f64, r: f64| json!({"KHR_materials_clearcoat": {"clearcoatFactor": f, "clearcoatRoughnessFactor": r}});
    d.json["materials"] = json!([
        {"name": "a", "extensions": coat(0.7, 0.25)},
        {"name": "b", "extensions": {"KHR_materials_clearcoat": {"clearcoatFactor": 2.0, "clearcoatNormalTexture": {"index": 0}}}},
        {"name": "c", "extensions": {"KHR_materials_clearcoat": {"clearcoatFactor": 1.0, "clearcoatNormalTexture": {"index": 0, "scale": 0.5}}}},
    ]);
    d.json["images"] = json!([{"name": "checker", "uri": scene::encode_data_uri(&png_2x2())}]);
    d.json["textures"] = json!([{"source": 0}]);
    d.json["meshes"][0]["primitives"][0]["material"] = json!(0);
    let s = d.load().unwrap();
    assert_eq!((s.materials[0].clearcoat, s.materials[0].clearcoat_roughness), (0.7, 0.25));
    assert_eq!((s.materials[1].clearcoat, s.materials[1].clearcoat_roughness), (1.0, 0.0));
    let w = &s.report.warnings;
    assert!(!w.iter().any(|x| x.contains("clearcoatNormalTexture")), "{w:?}");
    assert!(s.materials[0].clearcoat_normal_texture.is_none());
    let (b, c) = (&s.materials[1], &s.materials[2]);
    assert!(b.clearcoat_normal_texture.is_some() && b.clearcoat_normal_scale == 1.0);
    assert!(c.clearcoat_normal_texture.is_some() && c.clearcoat_normal_scale == 0.5);
    assert!(!w.iter().any(|x| x.contains("extension KHR_materials_clearcoat is not supported")), "{w:?}");
    // A clearcoatTexture naming no texture is an error that names it.
    d.json["materials"][1]["extensions"]["KHR_materials_clearcoat"]["clearcoatTexture"] = json!({"index": 7});
    let e = format!("{:#}", d.load().unwrap_err());
    assert!(e.contains("clearcoatTexture.index"), "{e}");
}

/// KHR_materials_sheen: its factors reach the material (clamped to [0, 1]; defaults
/// black and 0) and so do its textures, without a warning.
#[test]
fn sheen_factors_are_read() {
    let mut d = Doc::triangle();
    d.json["extensionsUsed"] = json!(["KHR_materials_sheen"]);
    d.json["materials"] = json!([
        {"name": "a", "extensions": {"KHR_materials_sheen": {"sheenColorFactor": [0.5, 2.0, -1.0], "sheenRoughnessFactor": 0.3}}},
        {"name": "b", "extensions": {"KHR_materials_sheen": {"sheenRoughnessFactor": 1.5}}},
    ]);
    d.json["meshes"][0]["primitives"][0]["material"] = json!(0);
    let s = d.load().unwrap();
    assert_eq!((s.materials[0].sheen_color, s.materials[0].sheen_roughness), (Vec3::new(0.5, 1.0, 0.0), 0.3));
    assert!(s.materials[0].has_sheen());
    assert_eq!((s.materials[1].sheen_color, s.materials[1].sheen_roughness), (Vec3::ZERO, 1.0));
    assert!(!s.materials[1].has_sheen());
    let w = &s.report.warnings;
    assert!(!w.iter().any(|x| x.contains("KHR_materials_sheen")), "{w:?}");
    // A colour that is not three numbers is an error that names it.
    d.json["materials"][1]["extensions"]["KHR_materials_sheen"]["sheenColorFactor"] = json!([1.0, 1.0]);
    let e = format!("{:#}", d.load().unwrap_err());
    assert!(e.contains("KHR_materials_sheen") && e.contains("sheenColorFactor"), "{e}");
    // Its textures reach the material; one naming no texture is an error that names it.
    let mut d = Doc::textured();
    d.json["materials"][0]["extensions"] = json!({"KHR_materials_sheen": {"sheenColorFactor": [1.0, 1.0, 1.0],
        "sheenColorTexture": {"index": 0}, "sheenRoughnessTexture": {"index": 0}}});
    let s = d.load().unwrap();
    assert!(s.materials[0].sheen_color_texture.is_some() && s.materials[0].sheen_roughness_texture.is_some());
    assert!(!s.report.warnings.iter().any(|x| x.contains("sheen")), "{:?}", s.report.warnings);
    d.json["materials"][0]["extensions"]["KHR_materials_sheen"]["sheenRoughnessTexture"] = json!({"index": 7});
    let e = format!("{:#}", d.load().unwrap_err());
    assert!(e.contains("sheenRoughnessTexture"), "{e}");
}

/// KHR_materials_iridescence: its factors reach the material (the factor clamped to [0, 1];
/// defaults 0, IOR 1.3, 100 and 400 nm) and so do its textures, without a warning; a smooth
/// metal (a mirror otherwise) becomes the GGX lobe whose Fresnel term the film replaces; an
/// IOR below 1 or a negative thickness is an error that names it.
#[test]
fn iridescence_factors_are_read() {
    let mut d = Doc::triangle();
    d.json["extensionsUsed"] = json!(["KHR_materials_iridescence"]);
    d.json["materials"] = json!([
        {"name": "a", "extensions": {"KHR_materials_iridescence": {"iridescenceFactor": 1.5, "iridescenceIor": 1.8,
            "iridescenceThicknessMinimum": 200.0, "iridescenceThicknessMaximum": 800.0}}},
        {"name": "b", "extensions": {"KHR_materials_iridescence": {}}},
        {"name": "c", "pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.6, 0.3, 1.0], "metallicFactor": 1.0,
            "roughnessFactor": 0.0}, "extensions": {"KHR_materials_iridescence": {"iridescenceFactor": 0.5}}},
    ]);
    d.json["meshes"][0]["primitives"][0]["material"] = json!(0);
    let s = d.load().unwrap();
    let film = |m: &vkvcm::scene::Material| {
        (m.iridescence, m.iridescence_ior, m.iridescence_thickness_min, m.iridescence_thickness_max)
    };
    assert_eq!(film(&s.materials[0]), (1.0, 1.8, 200.0, 800.0));
    assert!(s.materials[0].has_iridescence());
    assert_eq!(film(&s.materials[1]), (0.0, 1.3, 100.0, 400.0));
    assert!(!s.materials[1].has_iridescence());
    let c = &s.materials[2];
    assert_eq!((c.glossy, c.mirror, c.roughness), (Vec3::new(0.9, 0.6, 0.3), Vec3::ZERO, 0.0));
    let w = &s.report.warnings;
    assert!(!w.iter().any(|x| x.contains("KHR_materials_iridescence")), "{w:?}");
    d.json["materials"][1]["extensions"]["KHR_materials_iridescence"]["iridescenceIor"] = json!(0.5);
    let e = format!("{:#}", d.load().unwrap_err());
    assert!(e.contains("KHR_materials_iridescence") && e.contains("iridescenceIor"), "{e}");
    d.json["materials"][1]["extensions"]["KHR_materials_iridescence"] = json!({"iridescenceThicknessMinimum": -1.0});
    let e = format!("{:#}", d.load().unwrap_err());
    assert!(e.contains("KHR_materials_iridescence") && e.contains("thickness"), "{e}");
    // Its textures reach the material; one naming no texture is an error that names it.
    let mut d = Doc::textured();
    d.json["materials"][0]["extensions"] = json!({"KHR_materials_iridescence": {"iridescenceFactor": 1.0,
        "iridescenceTexture": {"index": 0}, "iridescenceThicknessTexture": {"index": 0}}});
    let s = d.load().unwrap();
    assert!(s.materials[0].iridescence_texture.is_some() && s.materials[0].iridescence_thickness_texture.is_some());
    assert!(!s.report.warnings.iter().any(|x| x.contains("iridescence")), "{:?}", s.report.warnings);
    d.json["materials"][0]["extensions"]["KHR_materials_iridescence"]["iridescenceThicknessTexture"] =
        json!({"index": 7});
    let e = format!("{:#}", d.load().unwrap_err());
    assert!(e.contains("iridescenceThicknessTexture"), "{e}");
}

/// KHR_materials_anisotropy: strength (clamped to [0, 1], default 0), rotation and texture
/// reach the material without a warning; a smooth metal becomes a GGX lobe (a mirror
/// cannot be anisotropic); the triangles get tangents generated from their texture
/// coordinates (none in the file), and a primitive with neither TANGENT nor texture
/// coordinates is warned of (its lobe stays isotropic), as is a transmissive material
/// (its glass stays isotropic).
#[test]
fn anisotropy_is_read() {
    let mut d = Doc::textured();
    d.json["extensionsUsed"] = json!(["KHR_materials_anisotropy"]);
    d.json["materials"] = json!([{"name": "m",
        "pbrMetallicRoughness": {"metallicFactor": 1.0, "roughnessFactor": 0.0, "baseColorFactor": [0.9, 0.8, 0.7, 1.0]},
        "extensions": {"KHR_materials_anisotropy": {"anisotropyStrength": 1.5, "anisotropyRotation": 0.5,
            "anisotropyTexture": {"index": 0}}}}]);
    let s = d.load().unwrap();
    let m = &s.materials[0];
    assert_eq!((m.anisotropy_strength, m.anisotropy_rotation), (1.0, 0.5));
    assert!(m.has_anisotropy() && m.anisotropy_texture.is_some());
    assert_eq!((m.mirror, m.glossy), (Vec3::ZERO, Vec3::new(0.9, 0.8, 0.7)), "a smooth metal is a GGX lobe");
    let a = s.triangles[0].attributes.as_ref().unwrap();
    let t = a.tangent.expect("tangents generated for the anisotropy");
    assert!(t.iter().all(|t| (t.truncate().length() - 1.0).abs() < 1e-5), "{t:?}");
    let w = &s.report.warnings;
    assert!(!w.iter().any(|x| x.contains("anisotropy")), "{w:?}");
    assert!(vkvcm::render::features::FeatureSet::new(&s, false).anisotropy);
    // Defaults: strength 0 (isotropic), and a plain material stays as it was.
    d.json["materials"][0]["extensions"]["KHR_materials_anisotropy"] = json!({});
    let s = d.load().unwrap();
    assert!(!s.materials[0].has_anisotropy());
    assert_eq!(s.materials[0].mirror, Vec3::new(0.9, 0.8, 0.7));
    // A texture naming no texture is an error that names it.
    d.json["materials"][0]["extensions"]["KHR_materials_anisotropy"] = json!({"anisotropyTexture": {"index": 7}});
    let e = format!("{:#}", d.load().unwrap_err());
    assert!(e.contains("anisotropyTexture"), "{e}");
    // No texture coordinates and no TANGENT: warned of, no tangents.
    let mut d = Doc::triangle();
    d.json["materials"] =
        json!([{"name": "m", "extensions": {"KHR_materials_anisotropy": {"anisotropyStrength": 0.5}}}]);
    d.prim()["material"] = json!(0);
    let s = d.load().unwrap();
    assert!(s.materials[0].has_anisotropy());
    assert!(s.triangles[0].attributes.as_ref().is_none_or(|a| a.tangent.is_none()));
    let w = &s.report.warnings;
    assert!(w.iter().any(|x| x.contains("KHR_materials_anisotropy without TANGENT")), "{w:?}");
    assert!(!vkvcm::render::features::FeatureSet::new(&s, false).anisotropy, "no tangents, no anisotropic kernels");
    // On a transmissive material the glass stays isotropic: warned of.
    d.json["materials"][0]["extensions"]["KHR_materials_transmission"] = json!({"transmissionFactor": 1.0});
    d.json["materials"][0]["pbrMetallicRoughness"] = json!({"metallicFactor": 0.0});
    let s = d.load().unwrap();
    let w = &s.report.warnings;
    assert!(w.iter().any(|x| x.contains("transmitted and refracted light stays isotropic")), "{w:?}");
}

/// KHR_materials_diffuse_transmission: its factors reach an opaque material (clamped to
/// [0, 1]; defaults 0 and white) with the metallic factor, and so do its textures, without
/// a warning; a transmitting surface is two-sided though doubleSided is false; beside
/// KHR_materials_transmission it is ignored with a warning.
#[test]
fn diffuse_transmission_factors_are_read() {
    let ext = "KHR_materials_diffuse_transmission";
    let mut d = Doc::triangle();
    d.json["extensionsUsed"] = json!([ext]);
    d.json["materials"] = json!([
        {"name": "a", "pbrMetallicRoughness": {"metallicFactor": 0.25},
         "extensions": {ext: {"diffuseTransmissionFactor": 1.5, "diffuseTransmissionColorFactor": [0.5, 2.0, -1.0]}}},
        {"name": "b", "extensions": {ext: {}}},
        {"name": "c", "extensions": {ext: {"diffuseTransmissionFactor": 0.5},
         "KHR_materials_transmission": {"transmissionFactor": 1.0}}, "pbrMetallicRoughness": {"metallicFactor": 0.0}},
    ]);
    d.json["meshes"][0]["primitives"][0]["material"] = json!(0);
    let s = d.load().unwrap();
    let a = s.materials[0].diffuse_transmission.as_deref().unwrap();
    assert_eq!((a.factor, a.color, a.metallic), (1.0, Vec3::new(0.5, 1.0, 0.0), 0.25));
    assert!(s.materials[0].has_diffuse_transmission() && !s.materials[0].one_sided);
    let b = s.materials[1].diffuse_transmission.as_deref().unwrap();
    assert_eq!((b.factor, b.color), (0.0, Vec3::ONE));
    assert!(!s.materials[1].has_diffuse_transmission() && s.materials[1].one_sided);
    assert!(s.materials[2].diffuse_transmission.is_none() && !s.materials[2].has_diffuse_transmission());
    let w = &s.report.warnings;
    assert_eq!(w.iter().filter(|x| x.contains(ext)).count(), 1, "{w:?}");
    assert!(
        w.iter().any(|x| x.contains(ext) && x.contains("KHR_materials_transmission") && x.contains("'c'")),
        "{w:?}"
    );
    // A colour that is not three numbers is an error that names it.
    d.json["materials"][1]["extensions"][ext]["diffuseTransmissionColorFactor"] = json!([1.0, 1.0]);
    let e = format!("{:#}", d.load().unwrap_err());
    assert!(e.contains(ext) && e.contains("diffuseTransmissionColorFactor"), "{e}");
    // Its textures reach the material; one naming no texture is an error that names it.
    let mut d = Doc::textured();
    d.json["materials"][0]["extensions"] = json!({ext: {"diffuseTransmissionFactor": 1.0,
        "diffuseTransmissionTexture": {"index": 0}, "diffuseTransmissionColorTexture": {"index": 0}}});
    let s = d.load().unwrap();
    let t = s.materials[0].diffuse_transmission.as_deref().unwrap();
    assert!(t.texture.is_some() && t.color_texture.is_some());
    assert!(!s.report.warnings.iter().any(|x| x.contains("iffuse")), "{:?}", s.report.warnings);
    d.json["materials"][0]["extensions"][ext]["diffuseTransmissionColorTexture"] = json!({"index": 7});
    let e = format!("{:#}", d.load().unwrap_err());
    assert!(e.contains("diffuseTransmissionColorTexture"), "{e}");
}

/// KHR_materials_transmission's transmissionTexture and KHR_materials_specular's
/// specularTexture and specularColorTexture reach the material (`LayerTextures`) with the
/// factors they multiply, without a texture warning; a transmissionTexture on a fully
/// metallic material (which transmits nothing) is not read, and a specularTexture naming
/// no texture is an error that names it.
#[test]
fn transmission_and_specular_textures_are_read() {
    let mut d = Doc::textured();
    d.json["materials"][0]["pbrMetallicRoughness"]["metallicFactor"] = json!(0.25);
    d.json["materials"][0]["extensions"] = json!({
        "KHR_materials_transmission": {"transmissionFactor": 0.5, "transmissionTexture": {"index": 0}},
        "KHR_materials_specular": {"specularFactor": 1.0, "specularColorFactor": [2.0, 1.0, 0.5],
                                   "specularTexture": {"index": 0}, "specularColorTexture": {"index": 0}},
    });
    let s = d.load().unwrap();
    let l = s.materials[0].layer_textures.as_deref().expect("layer textures");
    assert!(l.transmission.is_some() && l.specular.is_some() && l.specular_color.is_some());
    assert_eq!((l.metallic, l.roughness, l.specular_factor), (0.25, 1.0, 1.0));
    assert!(close(l.specular_f0, Vec3::new(0.08, 0.04, 0.02)) && close(l.dielectric_f0, l.specular_f0));
    assert_eq!(s.materials[0].glass_weight, 0.75 * 0.5);
    assert!(s.report.warnings.iter().all(|w| !w.contains("texture")), "{:?}", s.report.warnings);
    // An opaque material reads the specular textures alone.
    d.json["materials"][0]["pbrMetallicRoughness"]["metallicFactor"] = json!(1.0);
    let s = d.load().unwrap();
    let l = s.materials[0].layer_textures.as_deref().expect("layer textures");
    assert!(l.transmission.is_none() && l.specular.is_some() && !s.materials[0].is_dielectric());
    d.json["materials"][0]["extensions"]["KHR_materials_specular"]["specularTexture"] = json!({"index": 9});
    let e = err_of(d.load());
    assert!(e.contains("specularTexture"), "{e}");
}

/// A material extension that is not a JSON object is an error naming the material and the
/// extension, for each of the extensions read by name (gltf_import's material_extension).
#[test]
fn material_extension_that_is_not_an_object_is_an_error() {
    for ext in [
        "KHR_materials_clearcoat",
        "KHR_materials_sheen",
        "KHR_materials_iridescence",
        "KHR_materials_anisotropy",
        "KHR_materials_diffuse_transmission",
        "KHR_materials_dispersion",
    ] {
        let mut d = Doc::triangle();
        d.json["extensionsUsed"] = json!([ext]);
        d.json["materials"] = json!([{"name": "m", "extensions": {ext: 3}}]);
        d.json["meshes"][0]["primitives"][0]["material"] = json!(0);
        let e = err_of(d.load());
        assert!(e.contains(&format!("material 0 'm': {ext} must be an object")), "{ext}: {e}");
    }
}

/// KHR_materials_dispersion reaches a transmissive material, also when the file requires
/// it, with the three IORs of the extension's implementation note; on a material that does
/// not transmit it is ignored with a warning; a negative dispersion is an error naming it.
#[test]
fn dispersion_is_read() {
    let ext = "KHR_materials_dispersion";
    let mut d = Doc::triangle();
    d.json["extensionsUsed"] = json!([ext, "KHR_materials_transmission", "KHR_materials_ior", "VKVCM_materials_phong"]);
    d.json["extensionsRequired"] = json!([ext]);
    d.json["materials"] = json!([
        {"name": "a", "pbrMetallicRoughness": {"metallicFactor": 0.0},
         "extensions": {ext: {"dispersion": 2.0}, "KHR_materials_transmission": {"transmissionFactor": 1.0},
                        "KHR_materials_ior": {"ior": 1.6}}},
        {"name": "b", "extensions": {ext: {"dispersion": 1.0}}},
        {"name": "c", "pbrMetallicRoughness": {"metallicFactor": 0.0},
         "extensions": {ext: {}, "KHR_materials_transmission": {"transmissionFactor": 1.0}}},
        {"name": "d", "extensions": {ext: {"dispersion": 0.5},
                                     "VKVCM_materials_phong": {"mirror": [1.0, 1.0, 1.0], "ior": 1.5}}},
    ]);
    d.json["meshes"][0]["primitives"][0]["material"] = json!(0);
    let s = d.load().unwrap();
    let a = &s.materials[0];
    assert!(a.has_dispersion() && a.dispersion == 2.0);
    // halfSpread = (ior - 1) 0.025 dispersion = 0.03 either side of 1.6.
    assert!((a.dispersion_iors() - Vec3::new(1.57, 1.6, 1.63)).abs().max_element() < 1e-6, "{}", a.dispersion_iors());
    assert!(!s.materials[1].has_dispersion() && s.materials[1].dispersion == 0.0);
    assert!(!s.materials[2].has_dispersion() && s.materials[2].dispersion == 0.0);
    // SmallVCM's glass (VKVCM_materials_phong) disperses too.
    assert!(s.materials[3].has_dispersion() && s.materials[3].dispersion == 0.5);
    let w = &s.report.warnings;
    assert_eq!(w.iter().filter(|x| x.contains(ext)).count(), 1, "{w:?}");
    assert!(w.iter().any(|x| x.contains(ext) && x.contains("'b'")), "{w:?}");
    d.json["materials"][0]["extensions"][ext]["dispersion"] = json!(-0.5);
    let e = format!("{:#}", d.load().unwrap_err());
    assert!(e.contains(ext) && e.contains("dispersion"), "{e}");
}
