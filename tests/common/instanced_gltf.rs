//! A glTF scene whose meshes are placed several times: a smooth sphere mesh (vertex
//! normals) placed by four nodes (one rotated, one scaled non-uniformly, one mirrored)
//! and by a node with three EXT_mesh_gpu_instancing transforms, a floor, and an emitting
//! panel placed by two nodes (emitters are flattened), with a camera.

use serde_json::{json, Value};

/// The document, its buffer embedded as a data URI.
pub fn instanced_gltf() -> Value {
    let mut bin: Vec<u8> = Vec::new();
    let mut views = Vec::new();
    let mut accessors = Vec::new();
    let mut push = |bin: &mut Vec<u8>, data: &[f32], n: usize, ty: &str, bounds: bool| {
        let offset = bin.len();
        bin.extend(data.iter().flat_map(|x| x.to_le_bytes()));
        views.push(json!({"buffer": 0, "byteOffset": offset, "byteLength": bin.len() - offset}));
        let mut acc =
            json!({"bufferView": views.len() - 1, "componentType": 5126, "count": data.len() / n, "type": ty});
        if bounds {
            let lo: Vec<f32> =
                (0..n).map(|k| data.iter().skip(k).step_by(n).copied().fold(f32::MAX, f32::min)).collect();
            let hi: Vec<f32> =
                (0..n).map(|k| data.iter().skip(k).step_by(n).copied().fold(f32::MIN, f32::max)).collect();
            acc["min"] = json!(lo);
            acc["max"] = json!(hi);
        }
        accessors.push(acc);
        accessors.len() - 1
    };
    let push_indices = |bin: &mut Vec<u8>, views: &mut Vec<Value>, accessors: &mut Vec<Value>, idx: &[u32]| {
        let offset = bin.len();
        bin.extend(idx.iter().flat_map(|i| i.to_le_bytes()));
        views.push(json!({"buffer": 0, "byteOffset": offset, "byteLength": bin.len() - offset}));
        accessors
            .push(json!({"bufferView": views.len() - 1, "componentType": 5125, "count": idx.len(), "type": "SCALAR"}));
        accessors.len() - 1
    };
    // UV sphere of radius 0.5: rings x segments quads.
    let (rings, segments) = (10u32, 16u32);
    let mut pos = Vec::new();
    let mut nrm = Vec::new();
    for i in 0..=rings {
        let th = std::f32::consts::PI * i as f32 / rings as f32;
        for j in 0..=segments {
            let ph = std::f32::consts::TAU * j as f32 / segments as f32;
            // Exact poles (sin(pi) is not 0 in f32): the triangles meeting them have zero
            // area in any placement.
            let (st, ct) = match i {
                0 => (0.0, 1.0),
                _ if i == rings => (0.0, -1.0),
                _ => (th.sin(), th.cos()),
            };
            let n = [st * ph.cos(), ct, st * ph.sin()];
            pos.extend(n.map(|c| 0.5 * c));
            nrm.extend(n);
        }
    }
    let mut idx = Vec::new();
    for i in 0..rings {
        for j in 0..segments {
            let a = i * (segments + 1) + j;
            let b = a + segments + 1;
            // Counter-clockwise seen from outside.
            idx.extend([a, a + 1, b, a + 1, b + 1, b]);
        }
    }
    let sphere_pos = push(&mut bin, &pos, 3, "VEC3", true);
    let sphere_nrm = push(&mut bin, &nrm, 3, "VEC3", false);
    let floor_pos = push(&mut bin, &[-3.0, 0.0, -3.0, -3.0, 0.0, 3.0, 3.0, 0.0, 3.0, 3.0, 0.0, -3.0], 3, "VEC3", true);
    // Facing down (-y).
    let panel_pos = push(&mut bin, &[-0.6, 0.0, -0.6, 0.6, 0.0, -0.6, 0.6, 0.0, 0.6, -0.6, 0.0, 0.6], 3, "VEC3", true);
    let translations = push(&mut bin, &[-1.2, 0.5, -1.5, 0.0, 0.45, -1.8, 1.2, 0.5, -1.5], 3, "VEC3", true);
    let (s, c) = (0.6f32.sin(), 0.6f32.cos());
    let rotations = push(&mut bin, &[0.0, 0.0, 0.0, 1.0, 0.0, s, 0.0, c, s, 0.0, 0.0, c], 4, "VEC4", false);
    let scales = push(&mut bin, &[1.0, 1.0, 1.0, 0.8, 0.9, 1.1, 0.7, 0.7, 0.7], 3, "VEC3", false);
    let sphere_idx = push_indices(&mut bin, &mut views, &mut accessors, &idx);
    let quad_idx = push_indices(&mut bin, &mut views, &mut accessors, &[0, 1, 2, 0, 2, 3]);
    let (r, w) = (0.3f32.sin(), 0.3f32.cos());
    json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["EXT_mesh_gpu_instancing", "KHR_materials_emissive_strength"],
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2, 3, 4, 5, 6, 7, 8]}],
        "nodes": [
            {"name": "cam", "camera": 0, "translation": [0.0, 1.4, 4.0], "rotation": [-0.1305, 0.0, 0.0, 0.9914]},
            {"name": "floor", "mesh": 1},
            {"name": "panel a", "mesh": 2, "translation": [-0.8, 2.5, 0.0]},
            {"name": "panel b", "mesh": 2, "translation": [0.8, 2.5, 0.0]},
            {"name": "sphere", "mesh": 0, "translation": [-1.2, 0.5, 0.6]},
            {"name": "rotated", "mesh": 0, "translation": [0.0, 0.5, 0.6], "rotation": [r, 0.0, 0.0, w]},
            {"name": "stretched", "mesh": 0, "translation": [1.2, 0.6, 0.6], "scale": [0.7, 1.2, 0.9]},
            {"name": "mirrored", "mesh": 0, "translation": [0.0, 0.35, 1.5], "scale": [-0.7, 0.7, 0.7]},
            {"name": "group", "children": [9], "translation": [0.0, 0.0, 0.2]},
            {"name": "gpu instanced", "mesh": 0, "extensions": {"EXT_mesh_gpu_instancing": {"attributes": {
                "TRANSLATION": translations, "ROTATION": rotations, "SCALE": scales}}}},
        ],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.9, "znear": 0.01}}],
        "materials": [
            {"name": "sphere", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.5, 0.3, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.4}},
            {"name": "floor", "pbrMetallicRoughness": {"baseColorFactor": [0.6, 0.6, 0.6, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0}},
            {"name": "panel", "emissiveFactor": [1.0, 0.9, 0.8], "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 6.0}},
             "pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0}},
        ],
        "meshes": [
            {"name": "sphere", "primitives": [{"attributes": {"POSITION": sphere_pos, "NORMAL": sphere_nrm}, "indices": sphere_idx, "material": 0}]},
            {"name": "floor", "primitives": [{"attributes": {"POSITION": floor_pos}, "indices": quad_idx, "material": 1}]},
            {"name": "panel", "primitives": [{"attributes": {"POSITION": panel_pos}, "indices": quad_idx, "material": 2}]},
        ],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": bin.len(), "uri": vkvcm::scene::encode_data_uri(&bin)}],
    })
}

/// Writes [`instanced_gltf`] to `dir/instanced.gltf`.
pub fn write_instanced_gltf(dir: &std::path::Path) -> std::path::PathBuf {
    let path = dir.join("instanced.gltf");
    std::fs::write(&path, serde_json::to_vec_pretty(&instanced_gltf()).unwrap()).unwrap();
    path
}
