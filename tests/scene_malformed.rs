//! Bad scene input never panics and gives one-line errors (issue #9, parts 1 and 5).
//!
//! * `corpus`: every `tests/malformed/<case>` with its `<case>.expect` (written by
//!   `tests/malformed/make_corpus.py`): the error's `{:#}` text is one line, names the file
//!   and contains the expected substring (`ok`: the file loads).
//! * `mutations_never_panic`: a few thousand deterministic mutations of the reference
//!   scenes (.gltf and .glb) and of small files with sparse accessors, morph targets, skins,
//!   quantized attributes and several scenes (.gltf): byte flips, truncations, splices, and JSON-aware edits
//!   (numbers replaced by huge / negative / out-of-range values, keys deleted, types
//!   swapped). The loader must return `Ok` or a one-line error, never panic. A panicking
//!   input is written to `$CARGO_TARGET_TMPDIR` and named in the failure.
//!   `VKVCM_MUTATIONS=<n>` changes the number of mutations per input (default 500).

use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use serde_json::{json, Value};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use vkvcm::scene::{self, LoadOptions, Scene};

mod common;
use common::corpus::{malformed_cases, malformed_dir as corpus_dir};

/// Loads as the CLI does (`load_named`: also refuses scenes with no emitter or geometry).
fn load_cli(path: &Path) -> anyhow::Result<Scene> {
    scene::load_named(path.to_str().unwrap())
}

fn check_error(path: &Path, r: anyhow::Result<Scene>, expect: &str) -> Result<(), String> {
    let name = path.file_name().unwrap().to_string_lossy().into_owned();
    match (r, expect) {
        (Ok(s), "ok") => {
            // Warnings about where the camera is (inside geometry, facing back faces); the
            // notices that a default camera replaces a missing or orthographic one are not.
            let notice = |w: &str| w.starts_with("no perspective camera") || w.starts_with("orthographic cameras");
            let bad: Vec<_> = s.report.warnings.iter().filter(|w| w.contains("camera") && !notice(w)).collect();
            if bad.is_empty() {
                Ok(())
            } else {
                Err(format!("{name}: unexpected warnings {bad:?}"))
            }
        }
        (Ok(_), _) => Err(format!("{name}: loaded, expected an error containing '{expect}'")),
        (Err(e), "ok") => Err(format!("{name}: expected to load, got: {e:#}")),
        (Err(e), _) => {
            let msg = format!("{e:#}");
            if msg.contains('\n') || msg.contains('\r') {
                Err(format!("{name}: error is not one line: {msg:?}"))
            } else if !msg.contains(&name) {
                Err(format!("{name}: error does not name the file: {msg}"))
            } else if !msg.contains(expect) {
                Err(format!("{name}: error lacks '{expect}': {msg}"))
            } else {
                Ok(())
            }
        }
    }
}

#[test]
fn corpus() {
    let cases = malformed_cases();
    assert!(cases.len() >= 60, "corpus has {} cases", cases.len());
    let mut failures = Vec::new();
    for (path, expect) in &cases {
        let expect = expect.as_str();
        let r = catch_unwind(|| load_cli(path)).unwrap_or_else(|_| panic!("{} panicked", path.display()));
        if let Err(f) = check_error(path, r, expect) {
            failures.push(f);
        }
    }
    assert!(failures.is_empty(), "{} of {} cases failed:\n{}", failures.len(), cases.len(), failures.join("\n"));
}

/// The corpus' valid scene with its buffer moved to `data.bin` beside it.
fn external_buffer_doc(dir: &Path, uri: &str) -> PathBuf {
    let mut j: Value = serde_json::from_slice(&std::fs::read(corpus_dir().join("valid.gltf")).unwrap()).unwrap();
    let bytes = scene::decode_data_uri(j["buffers"][0]["uri"].as_str().unwrap()).unwrap();
    std::fs::write(dir.join("data.bin"), &bytes).unwrap();
    j["buffers"][0]["uri"] = json!(uri);
    let path = dir.join("linked.gltf");
    std::fs::write(&path, serde_json::to_vec(&j).unwrap()).unwrap();
    path
}

#[cfg(unix)]
#[test]
fn symlink_escaping_the_folder_is_refused() {
    let outside = tempfile::tempdir().unwrap();
    let root = tempfile::tempdir().unwrap();
    let dir = root.path().join("scene");
    std::fs::create_dir_all(dir.join("sub")).unwrap();
    let path = external_buffer_doc(&dir, "data.bin");
    assert!(load_cli(&path).is_ok(), "the plain external buffer loads");
    // A link inside the folder to a file inside it is fine.
    std::os::unix::fs::symlink(dir.join("data.bin"), dir.join("sub/inner.bin")).unwrap();
    let path = external_buffer_doc(&dir, "sub/inner.bin");
    assert!(load_cli(&path).is_ok(), "a link that stays inside the folder loads");
    // A link (file or folder) that leads outside is refused.
    std::fs::copy(dir.join("data.bin"), outside.path().join("secret.bin")).unwrap();
    std::os::unix::fs::symlink(outside.path().join("secret.bin"), dir.join("escape.bin")).unwrap();
    std::os::unix::fs::symlink(outside.path(), dir.join("out")).unwrap();
    for uri in ["escape.bin", "out/secret.bin"] {
        let path = external_buffer_doc(&dir, uri);
        let r = load_cli(&path);
        check_error(&path, r, "outside the scene's folder").unwrap();
    }
}

/// A closed cube of 12 triangles around the origin, normals facing out (`outward`) or in.
fn cube_doc(outward: bool, sphere_around_camera: Option<f32>) -> Value {
    let mut tris: Vec<[[f32; 3]; 3]> = Vec::new();
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let corner = |a: f32, b: f32| {
                let mut p = [0.0f32; 3];
                p[axis] = sign;
                p[u] = a;
                p[v] = b;
                p
            };
            let (p00, p10, p11, p01) = (corner(-1.0, -1.0), corner(1.0, -1.0), corner(1.0, 1.0), corner(-1.0, 1.0));
            // (u x v) = axis direction: counter-clockwise in (u, v) faces +axis.
            let out = sign > 0.0;
            if out == outward {
                tris.push([p00, p10, p11]);
                tris.push([p00, p11, p01]);
            } else {
                tris.push([p00, p11, p10]);
                tris.push([p00, p01, p11]);
            }
        }
    }
    let bin: Vec<u8> = tris.iter().flatten().flatten().flat_map(|x| x.to_le_bytes()).collect();
    let mut j = json!({
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"mesh": 0}, {"camera": 0, "translation": [0.2, 0.1, 0.3]}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 1.0, "znear": 0.01}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "material": 0}]}],
        "materials": [{"emissiveFactor": [1.0, 1.0, 1.0]}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": tris.len() * 3, "type": "VEC3",
                       "min": [-1, -1, -1], "max": [1, 1, 1]}],
        "bufferViews": [{"buffer": 0, "byteLength": bin.len()}],
        "buffers": [{"byteLength": bin.len(), "uri": scene::encode_data_uri(&bin)}],
    });
    if let Some(r) = sphere_around_camera {
        j["extensionsUsed"] = json!(["VKVCM_spheres"]);
        j["nodes"][0]["extensions"] =
            json!({"VKVCM_spheres": {"spheres": [{"center": [0.0, 0.0, 0.0], "radius": r, "material": 0}]}});
    }
    j
}

fn load_json(j: &Value) -> Scene {
    let dir = tempfile::tempdir().unwrap();
    let bytes = serde_json::to_vec(j).unwrap();
    scene::load_gltf_bytes(&bytes, &dir.path().join("cube.gltf"), &LoadOptions::default()).unwrap()
}

fn camera_warnings(s: &Scene) -> Vec<&String> {
    s.report.warnings.iter().filter(|w| w.contains("camera")).collect()
}

#[test]
fn camera_inside_geometry_warns() {
    // Inside a closed outward-facing cube: every test ray hits a back face.
    let s = load_json(&cube_doc(true, None));
    let w = camera_warnings(&s);
    assert!(w.len() == 1 && w[0].contains("inside closed geometry"), "{w:?}");
    // The same cube facing inward is a room: no warning.
    assert!(camera_warnings(&load_json(&cube_doc(false, None))).is_empty());
    // Inside an opaque sphere (exact test), and outside one.
    let s = load_json(&cube_doc(false, Some(0.9)));
    let w = camera_warnings(&s);
    assert!(w.iter().any(|w| w.contains("inside an opaque sphere")), "{w:?}");
    assert!(camera_warnings(&load_json(&cube_doc(false, Some(0.1)))).is_empty());
    // The reference scenes have none.
    for name in scene::BUILTIN_SCENES {
        let s = scene::load_named(name).unwrap();
        assert!(camera_warnings(&s).is_empty(), "{name}: {:?}", s.report.warnings);
    }
}

// ---------------------------------------------------------------------------------------
// Mutations.

/// The GLB form of a .gltf whose buffer 0 is a data: URI.
fn to_glb(gltf: &[u8]) -> Vec<u8> {
    let mut j: Value = serde_json::from_slice(gltf).unwrap();
    let bin = scene::decode_data_uri(j["buffers"][0]["uri"].as_str().unwrap()).unwrap();
    j["buffers"][0].as_object_mut().unwrap().remove("uri");
    glb(&serde_json::to_vec(&j).unwrap(), Some(&bin))
}

fn glb(json: &[u8], bin: Option<&[u8]>) -> Vec<u8> {
    let pad = |b: &[u8], with: u8| {
        let mut v = b.to_vec();
        while !v.len().is_multiple_of(4) {
            v.push(with);
        }
        v
    };
    let js = pad(json, b' ');
    let mut body = Vec::new();
    body.extend_from_slice(&(js.len() as u32).to_le_bytes());
    body.extend_from_slice(b"JSON");
    body.extend_from_slice(&js);
    if let Some(bin) = bin {
        let bin = pad(bin, 0);
        body.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        body.extend_from_slice(b"BIN\0");
        body.extend_from_slice(&bin);
    }
    let mut out = b"glTF".to_vec();
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(12 + body.len() as u32).to_le_bytes());
    out.extend_from_slice(&body);
    out
}

/// JSON pointers of every value in `v`.
fn pointers(v: &Value, at: String, out: &mut Vec<String>) {
    match v {
        Value::Object(m) => {
            for (k, x) in m {
                pointers(x, format!("{at}/{}", k.replace('~', "~0").replace('/', "~1")), out);
            }
        }
        Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                pointers(x, format!("{at}/{i}"), out);
            }
        }
        _ => {}
    }
    out.push(at);
}

const NUMBERS: &[f64] = &[
    0.0,
    -0.0,
    -1.0,
    1.0,
    2.0,
    3.0,
    0.5,
    -2.5,
    255.0,
    256.0,
    65535.0,
    65536.0,
    2147483647.0,
    2147483648.0,
    4294967295.0,
    4294967296.0,
    9007199254740993.0,
    1.8e19,
    1e38,
    3.5e38,
    1e308,
    -1e308,
    1e-320,
];

/// One JSON-aware edit of `j` at a random place.
fn mutate_json(j: &mut Value, rng: &mut Pcg64) {
    let mut ptrs = Vec::new();
    pointers(j, String::new(), &mut ptrs);
    let p = &ptrs[rng.random_range(0..ptrs.len())];
    let Some(target) = j.pointer_mut(p) else { return };
    match rng.random_range(0..8) {
        0 | 1 => *target = json!(NUMBERS[rng.random_range(0..NUMBERS.len())]),
        2 => *target = json!(rng.random_range(0u64..64)),
        3 => {
            *target = match rng.random_range(0..6) {
                0 => json!("x"),
                1 => json!([]),
                2 => json!({}),
                3 => Value::Null,
                4 => json!(true),
                _ => json!([0, 1, 2]),
            }
        }
        4 => match target {
            Value::Object(m) if !m.is_empty() => {
                let k = m.keys().nth(rng.random_range(0..m.len())).unwrap().clone();
                m.remove(&k);
            }
            Value::Array(a) if !a.is_empty() => {
                a.remove(rng.random_range(0..a.len()));
            }
            _ => *target = Value::Null,
        },
        5 => {
            if let Value::Array(a) = target {
                if !a.is_empty() {
                    let x = a[rng.random_range(0..a.len())].clone();
                    a.push(x);
                }
            }
        }
        6 => {
            // Delete this value from its parent.
            if let Some((parent, key)) = p.rsplit_once('/') {
                let key = key.replace("~1", "/").replace("~0", "~");
                match j.pointer_mut(parent) {
                    Some(Value::Object(m)) => {
                        m.remove(&key);
                    }
                    Some(Value::Array(a)) => {
                        if let Ok(i) = key.parse::<usize>() {
                            if i < a.len() {
                                a.remove(i);
                            }
                        }
                    }
                    _ => {}
                }
            }
        }
        _ => {
            if let Some(x) = target.as_f64() {
                *target = json!(-x);
            } else {
                *target = json!(-1);
            }
        }
    }
}

/// Textual edits JSON values cannot express: out-of-range literals, NaN, stray bytes.
fn mutate_text(text: &mut Vec<u8>, rng: &mut Pcg64) {
    let digits: Vec<usize> = text.iter().enumerate().filter(|(_, b)| b.is_ascii_digit()).map(|(i, _)| i).collect();
    if digits.is_empty() {
        return;
    }
    let at = digits[rng.random_range(0..digits.len())];
    let lits: &[&[u8]] =
        &[b"1e999", b"-1e999", b"NaN", b"Infinity", b"99999999999999999999999", b"-", b"\"", b"\\u0000"];
    text.splice(at..at + 1, lits[rng.random_range(0..lits.len())].iter().copied());
}

fn mutate_bytes(b: &mut Vec<u8>, rng: &mut Pcg64) {
    if b.is_empty() {
        return;
    }
    match rng.random_range(0..4) {
        0 => {
            for _ in 0..rng.random_range(1..5) {
                let i = rng.random_range(0..b.len());
                b[i] ^= 1 << rng.random_range(0..8);
            }
        }
        1 => {
            let n = rng.random_range(0..b.len());
            b.truncate(n);
        }
        2 => {
            let i = rng.random_range(0..b.len());
            let n = rng.random_range(0..(b.len() - i).min(64));
            b.drain(i..i + n);
        }
        _ => {
            // Overwrite a little-endian u32 with an edge value: half of the time one of the
            // GLB header words (version, length, JSON chunk length and type).
            let i = if rng.random_bool(0.5) {
                [4, 8, 12, 16][rng.random_range(0..4)]
            } else {
                rng.random_range(0..b.len())
            };
            let v: u32 =
                [0, 1, 3, 12, 19, 20, 0x7fff_ffff, 0xffff_ffff, 0x7fc0_0000, 0x7f80_0000][rng.random_range(0..10)];
            for (k, x) in v.to_le_bytes().into_iter().enumerate() {
                if let Some(slot) = b.get_mut(i + k) {
                    *slot = x;
                }
            }
        }
    }
}

#[test]
fn mutations_never_panic() {
    let per_input: usize = std::env::var("VKVCM_MUTATIONS").ok().and_then(|s| s.parse().ok()).unwrap_or(500);
    let dir = tempfile::tempdir().unwrap();
    let path_gltf = dir.path().join("mutant.gltf");
    let path_glb = dir.path().join("mutant.glb");
    // An external buffer file for mutations that turn a URI into a relative name.
    std::fs::write(dir.path().join("x"), [0u8; 64]).unwrap();
    let mut inputs: Vec<(String, Vec<u8>)> = Vec::new();
    for name in scene::BUILTIN_SCENES {
        let text = std::fs::read(scene::builtin_path(name).unwrap()).unwrap();
        inputs.push((format!("{name}.glb"), to_glb(&text)));
        inputs.push((format!("{name}.gltf"), text));
    }
    // Sparse accessors, morph targets, skins, quantized attributes and several scenes
    // (embedded buffers: the mutations reach their accessor and skin reads).
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for file in [
        "tests/khronos/SimpleSparseAccessor.gltf",
        "tests/khronos/SimpleMorph.gltf",
        "tests/khronos/SimpleSkin.gltf",
        "tests/khronos/MultipleScenes.gltf",
        "tests/malformed/quantized_mesh.gltf",
        "tests/malformed/skinned.gltf",
        "tests/malformed/sparse_without_view.gltf",
    ] {
        let name = Path::new(file).file_name().unwrap().to_string_lossy().into_owned();
        inputs.push((name, std::fs::read(root.join(file)).unwrap()));
    }
    let (mut ok, mut errors) = (0usize, 0usize);
    let start = std::time::Instant::now();
    for (k, (name, original)) in inputs.iter().enumerate() {
        let is_glb = name.ends_with(".glb");
        let path = if is_glb { &path_glb } else { &path_gltf };
        // GLB: 12-byte header, JSON chunk (8-byte header + len), BIN chunk (8 + rest).
        let (original_json, glb_bin): (Value, Option<&[u8]>) = if is_glb {
            let len = u32::from_le_bytes(original[12..16].try_into().unwrap()) as usize;
            (serde_json::from_slice(&original[20..20 + len]).unwrap(), Some(&original[20 + len + 8..]))
        } else {
            (serde_json::from_slice(original).unwrap(), None)
        };
        let mut rng = Pcg64::seed_from_u64(0x5eed_0000 + k as u64);
        for i in 0..per_input {
            let bytes = match rng.random_range(0..3) {
                0 => {
                    let mut b = original.clone();
                    for _ in 0..rng.random_range(1..3) {
                        mutate_bytes(&mut b, &mut rng);
                    }
                    b
                }
                kind => {
                    let mut j = original_json.clone();
                    for _ in 0..rng.random_range(1..4) {
                        mutate_json(&mut j, &mut rng);
                    }
                    let mut text = serde_json::to_vec(&j).unwrap();
                    if kind == 2 {
                        mutate_text(&mut text, &mut rng);
                    }
                    if is_glb {
                        // Keep the container consistent so the edit reaches the importer.
                        glb(&text, glb_bin)
                    } else {
                        text
                    }
                }
            };
            let r = catch_unwind(AssertUnwindSafe(|| {
                let r = scene::load_gltf_bytes(&bytes, path, &LoadOptions::default());
                if let Ok(s) = &r {
                    if scene::check_renderable(s).is_ok() {
                        vkvcm::bvh::build(&s.triangles, &s.spheres);
                    }
                }
                r.map(|_| ())
            }));
            match r {
                Ok(Ok(())) => ok += 1,
                Ok(Err(e)) => {
                    let msg = format!("{e:#}");
                    assert!(
                        !msg.contains('\n') && msg.starts_with(&path.display().to_string()),
                        "{name} mutation {i}: error is not one line naming the file: {msg:?}"
                    );
                    errors += 1;
                }
                Err(_) => {
                    let out = Path::new(env!("CARGO_TARGET_TMPDIR"))
                        .join(format!("scene_malformed-panic-{name}-{i}.{}", if is_glb { "glb" } else { "gltf" }));
                    std::fs::write(&out, &bytes).unwrap();
                    panic!("{name} mutation {i} panicked; input written to {}", out.display());
                }
            }
        }
    }
    eprintln!(
        "{} mutations: {ok} loaded, {errors} refused, {:.1} s",
        inputs.len() * per_input,
        start.elapsed().as_secs_f64()
    );
    // The mutations must exercise both outcomes, or they test nothing.
    assert!(ok > inputs.len() * per_input / 20 && errors > inputs.len() * per_input / 5, "ok {ok}, errors {errors}");
}
