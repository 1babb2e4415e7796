//! Generator of the four reference scenes (`scenes/gbs_s.gltf`, `glm_c`, `gbs_p`,
//! `gbs_b`): SmallVCM's Cornell box configurations as stated in `docs/smallvcm.md` (the
//! predefined scenes), written as self-contained glTF files (buffers embedded as `data:`
//! URIs).
//!
//! All numbers are taken in SmallVCM's z-up frame and converted to glTF's y-up frame with
//! the rotation (x, y, z) -> (x, z, -y), which leaves the image unchanged. Geometry is
//! stored unindexed in SmallVCM's triangle order and vertex order, so every triangle's
//! geometric normal (p1-p0)x(p2-p0) is the one SmallVCM uses: walls face into the box,
//! the light box's sides face out of it and its (emitting) bottom faces down.
//!
//! Run `cargo run --example make_reference_scenes` to rewrite `scenes/`; a test checks
//! that the committed files equal this generator's output.

use super::gltf_import::encode_data_uri;
use anyhow::{Context, Result};
use glam::{DMat3, DQuat, DVec3};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// A reference scene: its file name and SmallVCM scene id.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ReferenceScene {
    pub name: &'static str,
    pub smallvcm_id: u32,
    pub description: &'static str,
}

/// SmallVCM's four predefined scenes in id order.
pub const REFERENCE_SCENES: [ReferenceScene; 4] = [
    ReferenceScene {
        name: "gbs_s",
        smallvcm_id: 0,
        description: "glossy floor, small mirror and glass spheres, sun (directional light)",
    },
    ReferenceScene {
        name: "glm_c",
        smallvcm_id: 1,
        description: "glossy floor, large mirror sphere, light box bottom as area light",
    },
    ReferenceScene {
        name: "gbs_p",
        smallvcm_id: 2,
        description: "glossy floor, small mirror and glass spheres, point light (no light box)",
    },
    ReferenceScene {
        name: "gbs_b",
        smallvcm_id: 3,
        description: "glossy floor, small mirror and glass spheres, constant background light",
    },
];

type P = [f32; 3];
/// Triangles (z-up) with their material index.
type Tris = Vec<([P; 3], u32)>;

/// Cornell box corners cb0..cb7 (z-up).
const CB: [P; 8] = [
    [-1.27029, 1.30455, -1.28002],
    [1.28975, 1.30455, -1.28002],
    [1.28975, 1.30455, 1.28002],
    [-1.27029, 1.30455, 1.28002],
    [-1.27029, -1.25549, -1.28002],
    [1.28975, -1.25549, -1.28002],
    [1.28975, -1.25549, 1.28002],
    [-1.27029, -1.25549, 1.28002],
];

/// Light box corners lb0..lb7 (z-up).
const LB: [P; 8] = [
    [-0.25, 0.25, 1.26002],
    [0.25, 0.25, 1.26002],
    [0.25, 0.25, 1.28002],
    [-0.25, 0.25, 1.28002],
    [-0.25, -0.25, 1.26002],
    [0.25, -0.25, 1.26002],
    [0.25, -0.25, 1.28002],
    [-0.25, -0.25, 1.28002],
];

/// Material indices of docs/smallvcm.md 2.4.
const M_LIGHT0: u32 = 0;
const M_LIGHT1: u32 = 1;
const M_FLOOR: u32 = 2;
const M_GREEN: u32 = 3;
const M_RED: u32 = 4;
const M_WHITE: u32 = 5;
const M_MIRROR: u32 = 6;
const M_GLASS: u32 = 7;
const M_BLUE: u32 = 8;

/// Radiance of the light-box emitter (scene 1).
pub const AREA_RADIANCE: f64 = 25.03329895614464;

/// (x, y, z) z-up -> (x, z, -y) y-up.
fn yup(p: P) -> P {
    [p[0], p[2], -p[1]]
}

fn yup_d(p: DVec3) -> DVec3 {
    DVec3::new(p.x, p.z, -p.y)
}

/// A JSON number that prints as the shortest decimal identifying the f32 `x`.
fn num(x: f32) -> Value {
    let s = x.to_string();
    json!(s.parse::<f64>().expect("float formatting"))
}

fn vec(v: P) -> Value {
    Value::Array(v.iter().map(|&x| num(x)).collect())
}

fn add(a: P, b: P) -> P {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn scale(a: P, s: f32) -> P {
    [a[0] * s, a[1] * s, a[2] * s]
}

struct Geometry {
    /// (mesh name, triangles (z-up) with material).
    meshes: Vec<(&'static str, Tris)>,
    /// (center z-up, radius, material)
    spheres: Vec<(P, f32, u32)>,
}

fn geometry(id: u32) -> Geometry {
    let light_ceiling = id == 1;
    let light_box = id != 2;
    let t = |a: usize, b: usize, c: usize, m: u32| ([CB[a], CB[b], CB[c]], m);
    let box_tris = vec![
        // floor
        t(0, 4, 5, M_FLOOR),
        t(5, 1, 0, M_FLOOR),
        // back wall
        t(0, 1, 2, M_BLUE),
        t(2, 3, 0, M_BLUE),
        // ceiling
        t(2, 6, 7, M_WHITE),
        t(7, 3, 2, M_WHITE),
        // left wall
        t(3, 7, 4, M_GREEN),
        t(4, 0, 3, M_GREEN),
        // right wall
        t(1, 5, 6, M_RED),
        t(6, 2, 1, M_RED),
    ];
    let mut meshes = vec![("cornell_box", box_tris)];
    if light_box {
        let l = |a: usize, b: usize, c: usize, m: u32| ([LB[a], LB[b], LB[c]], m);
        let (m0, m1) = if light_ceiling { (M_LIGHT0, M_LIGHT1) } else { (M_WHITE, M_WHITE) };
        meshes.push((
            "light_box",
            vec![
                // back, left, right, front sides
                l(0, 2, 1, M_WHITE),
                l(2, 0, 3, M_WHITE),
                l(3, 4, 7, M_WHITE),
                l(4, 3, 0, M_WHITE),
                l(1, 6, 5, M_WHITE),
                l(6, 1, 2, M_WHITE),
                l(4, 5, 6, M_WHITE),
                l(6, 7, 4, M_WHITE),
                // bottom (the emitter in scene 1)
                l(0, 5, 4, m0),
                l(5, 0, 1, m1),
            ],
        ));
    }

    // Spheres, computed in f32 as SmallVCM's LoadCornellBox does.
    let mut spheres = Vec::new();
    if id == 1 {
        let r = 0.8f32;
        let c = add(scale(add(add(add(CB[0], CB[1]), CB[4]), CB[5]), 1.0 / 4.0), [0.0, 0.0, r]);
        spheres.push((c, r, M_MIRROR));
    } else {
        let r = 0.5f32;
        let left_wall = add(scale(add(CB[0], CB[4]), 1.0 / 2.0), [0.0, 0.0, r]);
        let right_wall = add(scale(add(CB[1], CB[5]), 1.0 / 2.0), [0.0, 0.0, r]);
        let xlen = right_wall[0] - left_wall[0];
        let shift = 2.0 * xlen / 7.0;
        spheres.push((add(left_wall, [shift, 0.0, 0.0]), r, M_MIRROR));
        spheres.push((add(right_wall, [-shift, 0.0, 0.0]), r, M_GLASS));
    }
    Geometry { meshes, spheres }
}

fn material(name: &str, pbr: Value, phong: (P, P, f32, P, f32), extra_ext: Option<(&str, Value)>) -> Value {
    let (diffuse, phong_refl, exponent, mirror, ior) = phong;
    let mut ext = serde_json::Map::new();
    ext.insert(
        "VKVCM_materials_phong".into(),
        json!({
            "diffuse": vec(diffuse),
            "phong": vec(phong_refl),
            "exponent": num(exponent),
            "mirror": vec(mirror),
            "ior": num(ior),
        }),
    );
    if let Some((k, v)) = extra_ext {
        ext.insert(k.into(), v);
    }
    // SmallVCM's surfaces scatter on both sides.
    json!({ "name": name, "pbrMetallicRoughness": pbr, "doubleSided": true, "extensions": ext })
}

fn materials(id: u32) -> Vec<Value> {
    const Z: P = [0.0; 3];
    let diffuse_pbr = |c: P| json!({"baseColorFactor": [num(c[0]), num(c[1]), num(c[2]), 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0});
    let black = diffuse_pbr(Z);
    let lambert = |name: &str, c: P| material(name, diffuse_pbr(c), (c, Z, 1.0, Z, -1.0), None);
    let light = |name: &str| {
        let mut m = material(name, black.clone(), (Z, Z, 1.0, Z, -1.0), None);
        if id == 1 {
            m["emissiveFactor"] = json!([1.0, 1.0, 1.0]);
            m["extensions"]["KHR_materials_emissive_strength"] = json!({ "emissiveStrength": AREA_RADIANCE });
        }
        m
    };
    let green: P = [0.156863, 0.803922, 0.172549];
    let red: P = [0.803922, 0.152941, 0.152941];
    let white: P = [0.803922, 0.803922, 0.803922];
    let blue: P = [0.156863, 0.172549, 0.803922];
    vec![
        light("light1"),
        light("light2"),
        // Approximation for viewers without VKVCM_materials_phong: diffuse ~0.115,
        // specular ~0.69, roughness (2/(90+2))^(1/4).
        material(
            "glossy_floor",
            json!({"baseColorFactor": [0.8, 0.8, 0.8, 1.0], "metallicFactor": 0.85, "roughnessFactor": 0.384}),
            ([0.1; 3], [0.7; 3], 90.0, Z, -1.0),
            None,
        ),
        lambert("green_left_wall", green),
        lambert("red_right_wall", red),
        lambert("white", white),
        material(
            "mirror",
            json!({"baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 1.0, "roughnessFactor": 0.0}),
            (Z, Z, 1.0, [1.0; 3], -1.0),
            None,
        ),
        {
            let mut m = material(
                "glass",
                json!({"baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.0}),
                (Z, Z, 1.0, [1.0; 3], 1.6),
                Some(("KHR_materials_transmission", json!({"transmissionFactor": 1.0}))),
            );
            m["extensions"]["KHR_materials_ior"] = json!({ "ior": num(1.6) });
            m
        },
        lambert("blue_back_wall", blue),
    ]
}

/// The glTF document of reference scene `name` (`gbs_s`, `glm_c`, `gbs_p`, `gbs_b`).
pub fn reference_scene_json(name: &str) -> Option<Value> {
    let info = REFERENCE_SCENES.iter().find(|s| s.name == name)?;
    let id = info.smallvcm_id;
    let geo = geometry(id);
    let mesh_json = mesh_json(&geo);
    let mut nodes = mesh_json.nodes;
    let bytes: Vec<u8> = mesh_json.positions.iter().flat_map(|x| x.to_le_bytes()).collect();

    let mut used = vec!["KHR_materials_ior", "KHR_materials_transmission", "VKVCM_materials_phong", "VKVCM_spheres"];

    // Spheres.
    let spheres: Vec<Value> = geo
        .spheres
        .iter()
        .map(|(c, r, m)| json!({ "center": vec(yup(*c)), "radius": num(*r), "material": m }))
        .collect();
    nodes.push(json!({
        "name": "spheres",
        "extensions": { "VKVCM_spheres": { "spheres": spheres } },
    }));
    nodes.push(camera_node());
    let root_ext = add_lights(id, &mut nodes, &mut used);
    used.sort_unstable();

    let mut doc = json!({
        "asset": {
            "version": "2.0",
            "generator": "vkvcm examples/make_reference_scenes.rs",
            "extras": {
                "smallvcm_scene": id,
                "description": info.description,
                "source": "SmallVCM LoadCornellBox (docs/smallvcm.md section 2); z-up (x,y,z) stored as y-up (x,z,-y)",
            },
        },
        "extensionsUsed": used,
        "scene": 0,
        "scenes": [{ "name": info.name, "nodes": (0..nodes.len()).collect::<Vec<_>>() }],
        "nodes": nodes,
        "meshes": mesh_json.meshes,
        "materials": materials(id),
        "cameras": [{
            "name": "smallvcm_camera",
            "type": "perspective",
            "perspective": { "yfov": std::f64::consts::FRAC_PI_4, "znear": 0.1, "zfar": 10000.0 },
        }],
        "accessors": mesh_json.accessors,
        "bufferViews": [{ "buffer": 0, "byteOffset": 0, "byteLength": bytes.len(), "target": 34962 }],
        "buffers": [{ "byteLength": bytes.len(), "uri": encode_data_uri(&bytes) }],
    });
    if !root_ext.is_empty() {
        doc["extensions"] = Value::Object(root_ext);
    }
    Some(doc)
}

/// The triangle meshes of a reference scene as glTF: one buffer of unindexed y-up
/// positions, one accessor (and primitive) per run of equal material, one node per mesh.
struct MeshJson {
    positions: Vec<f32>,
    accessors: Vec<Value>,
    meshes: Vec<Value>,
    nodes: Vec<Value>,
}

/// The triangle meshes of `geo` as glTF.
fn mesh_json(geo: &Geometry) -> MeshJson {
    let mut out = MeshJson { positions: Vec::new(), accessors: Vec::new(), meshes: Vec::new(), nodes: Vec::new() };
    for (mesh_name, tris) in &geo.meshes {
        let mut primitives = Vec::new();
        let mut start = 0;
        while start < tris.len() {
            let m = tris[start].1;
            let end = (start..tris.len()).find(|&k| tris[k].1 != m).unwrap_or(tris.len());
            let first_vertex = out.positions.len() / 3;
            let mut lo = [f32::INFINITY; 3];
            let mut hi = [f32::NEG_INFINITY; 3];
            for (tri, _) in &tris[start..end] {
                for p in tri {
                    let q = yup(*p);
                    for k in 0..3 {
                        lo[k] = lo[k].min(q[k]);
                        hi[k] = hi[k].max(q[k]);
                    }
                    out.positions.extend_from_slice(&q);
                }
            }
            out.accessors.push(json!({
                "bufferView": 0,
                "byteOffset": first_vertex * 12,
                "componentType": 5126,
                "count": (end - start) * 3,
                "type": "VEC3",
                "min": vec(lo),
                "max": vec(hi),
            }));
            primitives.push(json!({
                "attributes": { "POSITION": out.accessors.len() - 1 },
                "material": m,
                "mode": 4,
            }));
            start = end;
        }
        out.meshes.push(json!({ "name": mesh_name, "primitives": primitives }));
        out.nodes.push(json!({ "name": mesh_name, "mesh": out.meshes.len() - 1 }));
    }
    out
}

/// SmallVCM's camera as a node: -Z = forward, +Y = up (orthogonalised as SmallVCM's
/// Camera::Setup does).
fn camera_node() -> Value {
    let c_pos: P = [-0.0439815, -4.12529, 0.222539];
    let c_fwd: P = [0.00688625, 0.998505, -0.0542161];
    let c_up: P = [3.73896e-4, 0.0542148, 0.998529];
    let d = |p: P| DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64);
    let f = yup_d(d(c_fwd)).normalize();
    let up = yup_d(d(c_up));
    let up = (up - f * f.dot(up)).normalize();
    let right = f.cross(up);
    let q = DQuat::from_mat3(&DMat3::from_cols(right, up, -f)).normalize();
    json!({
        "name": "camera",
        "camera": 0,
        "translation": vec(yup(c_pos)),
        "rotation": [q.x, q.y, q.z, q.w],
    })
}

/// The lights of SmallVCM scene `id` beside its emissive materials: adds their nodes and
/// extensions to `nodes` and `used`; returns the document's root extensions.
fn add_lights(id: u32, nodes: &mut Vec<Value>, used: &mut Vec<&str>) -> serde_json::Map<String, Value> {
    let mut root_ext = serde_json::Map::new();
    match id {
        0 => {
            // Sun: photons travel along normalize(-1, 1.5, -1) (z-up); irradiance
            // (0.5, 0.2, 0) * 20 = (10, 4, 0) = color (1, 0.4, 0) * 10 lux.
            let dir = yup_d(DVec3::new(-1.0, 1.5, -1.0)).normalize();
            let q = DQuat::from_rotation_arc(DVec3::NEG_Z, dir).normalize();
            root_ext.insert(
                "KHR_lights_punctual".into(),
                json!({"lights": [{"name": "sun", "type": "directional", "color": [1.0, 0.4, 0.0], "intensity": 10.0}]}),
            );
            nodes.push(json!({
                "name": "sun",
                "rotation": [q.x, q.y, q.z, q.w],
                "extensions": { "KHR_lights_punctual": { "light": 0 } },
            }));
            used.push("KHR_lights_punctual");
        }
        1 => used.push("KHR_materials_emissive_strength"),
        2 => {
            // Point light: 70 W total = 70 / (4 pi) W/sr, computed in f32 as SmallVCM.
            let intensity = 70.0f32 * (std::f32::consts::FRAC_1_PI * 0.25);
            root_ext.insert(
                "KHR_lights_punctual".into(),
                json!({"lights": [{"name": "point", "type": "point", "color": [1.0, 1.0, 1.0], "intensity": num(intensity)}]}),
            );
            nodes.push(json!({
                "name": "point_light",
                "translation": vec(yup([0.0, -0.5, 1.0])),
                "extensions": { "KHR_lights_punctual": { "light": 0 } },
            }));
            used.push("KHR_lights_punctual");
        }
        _ => {
            root_ext.insert(
                "VKVCM_background".into(),
                json!({ "radiance": [135.0 / 255.0, 206.0 / 255.0, 250.0 / 255.0] }),
            );
            used.push("VKVCM_background");
        }
    }
    root_ext
}

/// The exact bytes of `scenes/<name>.gltf`.
pub fn reference_scene_bytes(name: &str) -> Option<Vec<u8>> {
    let mut doc = reference_scene_json(name)?;
    // Sorted keys whether or not serde_json's `preserve_order` is enabled.
    doc.sort_all_objects();
    let mut s = serde_json::to_string_pretty(&doc).expect("serialising JSON");
    s.push('\n');
    Some(s.into_bytes())
}

/// Writes all four reference scenes into `dir` (created if needed); returns the paths.
pub fn write_reference_scenes(dir: &Path) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let mut out = Vec::new();
    for s in REFERENCE_SCENES {
        let path = dir.join(format!("{}.gltf", s.name));
        let bytes = reference_scene_bytes(s.name).expect("known scene");
        std::fs::write(&path, bytes).with_context(|| format!("writing {}", path.display()))?;
        out.push(path);
    }
    Ok(out)
}
