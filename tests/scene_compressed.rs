//! Compressed glTF assets (src/scene/gltf_import/meshopt_views.rs, textures.rs): the
//! versions of tests/khronos/BoxTextured.gltf in tests/compressed/ (made by
//! tests/compressed/make_assets.sh with gltfpack and Pillow) load to the scene of their
//! uncompressed counterpart.
//!
//! * EXT_meshopt_compression without filters (ATTRIBUTES, TRIANGLES) is lossless: every
//!   vertex's position, normal and texture coordinate equals the uncompressed file's
//!   (each triangle may start at another of its vertices: the index codec rotates
//!   triangles, keeping their winding), and so do the materials and texels.
//! * With filters: OCTAHEDRAL normals (gltfpack -cc) and EXPONENTIAL positions (-cc -vpf)
//!   are lossy by construction; positions and texture coordinates that are not filtered
//!   stay bit-equal, and the filtered ones agree within the encoders' quantization,
//!   stated at each assert.
//! * EXT_texture_webp: a lossless WebP decodes to the PNG's texels exactly (fingerprints
//!   equal).
//!
//! Sabotage (done by hand, not kept): skipping the filters (the raw octahedral and
//! exponential values read as they are) fails the filter test.

use std::path::Path;

use vkvcm::scene::{self, Scene};

fn load(name: &str) -> Scene {
    let path = format!("tests/compressed/{name}");
    scene::load(Path::new(&path)).unwrap_or_else(|e| panic!("{path}: {e:#}"))
}

/// Vertex `k` of `t`: position, shading normal and TEXCOORD_0.
fn vertex(t: &scene::Triangle, k: usize) -> [glam::Vec3; 3] {
    let uv = t.attributes.as_ref().and_then(|a| a.uv[0]).expect("TEXCOORD_0")[k];
    [t.p[k], t.n.expect("shading normals")[k], uv.extend(0.0)]
}

/// For each pair of corresponding triangles of `a` and `b` (same order: meshopt's index
/// codec keeps the triangles' order but may start a triangle at another of its vertices,
/// the same triangle with the same winding), the rotation of `b`'s vertices that matches
/// `a`'s positions best, and the largest difference of position, normal and texture
/// coordinate over all vertices.
fn max_diffs(a: &Scene, b: &Scene) -> [f32; 3] {
    assert_eq!(a.triangles.len(), b.triangles.len());
    let mut worst = [0f32; 3];
    for (s, t) in a.triangles.iter().zip(&b.triangles) {
        let diff = |r: usize, k: usize, c: usize| (vertex(s, k)[c] - vertex(t, (k + r) % 3)[c]).abs().max_element();
        let r = (0..3).min_by(|&x, &y| {
            let d = |r| (0..3).map(|k| diff(r, k, 0)).fold(0.0, f32::max);
            d(x).total_cmp(&d(y))
        });
        let r = r.unwrap();
        for (c, w) in worst.iter_mut().enumerate() {
            *w = (0..3).map(|k| diff(r, k, c)).fold(*w, f32::max);
        }
    }
    worst
}

#[test]
fn meshopt_without_filters_is_lossless() {
    let (plain, packed) = (load("box_plain.gltf"), load("box_meshopt.gltf"));
    assert_eq!(plain.triangles.len(), 12);
    assert!(!plain.images.is_empty() && plain.triangles[0].attributes.is_some(), "the reference has its texture");
    assert_eq!(max_diffs(&plain, &packed), [0.0; 3], "positions, normals, uvs of the meshopt-compressed box");
    assert_eq!(plain.images[0].texels, packed.images[0].texels);
    assert_eq!(plain.materials, packed.materials);
}

#[test]
fn meshopt_filters_decode_within_their_quantization() {
    // OCTAHEDRAL: the same quantized box, normals stored as 8-bit octahedral pairs instead
    // of 8-bit xyz. Both round a unit normal to 8-bit components (step 1/127), so they
    // agree within two steps per component; positions and uvs are not filtered.
    let [dp, dn, duv] = max_diffs(&load("box_quant.gltf"), &load("box_quant_filters.gltf"));
    assert_eq!((dp, duv), (0.0, 0.0), "positions and texture coordinates are not filtered");
    assert!(dn <= 2.0 / 127.0, "octahedral normals differ by {dn}");
    // EXPONENTIAL: float positions with a shared exponent and gltfpack's default 14-bit
    // mantissa: the box's coordinates (+-0.5) within 2^-13 of the uncompressed ones.
    // (Its texture coordinates are quantized with a KHR_texture_transform, not filtered.)
    let [dp, dn, _] = max_diffs(&load("box_plain.gltf"), &load("box_float_exp.gltf"));
    assert!(dp <= 1.0 / 8192.0, "exponential positions differ by {dp}");
    assert!(dn <= 2.0 / 127.0, "octahedral normals differ by {dn}");
}

#[test]
fn lossless_webp_decodes_to_the_png_texels() {
    let (png, webp) = (load("box_plain.gltf"), load("box_webp.gltf"));
    assert_eq!(webp.images.len(), 1, "only the WebP image is decoded (the PNG is not referenced)");
    assert_eq!(png.images[0].texels, webp.images[0].texels);
    assert_eq!(png.fingerprint(), webp.fingerprint());
}

#[test]
fn broken_meshopt_views_are_clear_errors() {
    let text = std::fs::read_to_string("tests/compressed/box_meshopt.gltf").unwrap();
    let edit = |f: &dyn Fn(&mut serde_json::Value)| {
        let mut doc: serde_json::Value = serde_json::from_str(&text).unwrap();
        f(&mut doc);
        let bytes = serde_json::to_vec(&doc).unwrap();
        let path = Path::new("tests/compressed/edited.gltf");
        let Err(e) = scene::load_gltf_bytes(&bytes, path, &Default::default()) else { panic!("the edited file loads") };
        format!("{e:#}")
    };
    let set = |field: &'static str, v: serde_json::Value| {
        move |d: &mut serde_json::Value| d["bufferViews"][1]["extensions"]["EXT_meshopt_compression"][field] = v.clone()
    };
    let e = edit(&set("byteLength", serde_json::json!(8)));
    assert!(e.contains("do not decode") && e.contains("bufferViews[1]"), "{e}");
    let e = edit(&set("filter", serde_json::json!("BOGUS")));
    assert!(e.contains("BOGUS"), "{e}");
    let e = edit(&set("byteOffset", serde_json::json!(1u64 << 40)));
    assert!(e.contains("not inside buffer"), "{e}");
    let e = edit(&set("count", serde_json::json!(1000)));
    assert!(e.contains("do not fit"), "{e}");
}
