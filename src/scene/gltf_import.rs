//! glTF 2.0 import (`.gltf` with external or embedded buffers, `.glb`) into [`Scene`].
//!
//! What is read, what is approximated and what is refused is specified in
//! `docs/scene-format.md`; in short: the default scene's node hierarchy with world
//! transforms, triangle primitives (TRIANGLES, TRIANGLE_STRIP, TRIANGLE_FAN; indexed or
//! not) with optional normals, the metallic/roughness material mapped to vkvcm's
//! diffuse + GGX + mirror/dielectric model, emission (one area light per emitting
//! triangle), `KHR_lights_punctual`, the first perspective camera, and the vkvcm
//! extensions `VKVCM_spheres`, `VKVCM_materials_phong` and `VKVCM_background`.
//!
//! Everything that is not represented produces one warning per kind in
//! [`LoadReport::warnings`]; malformed input produces an error that names the file and the
//! offending object. Buffers are resolved here (not by `gltf::import`) so that relative
//! URIs cannot leave the scene's folder.

use super::{Camera, Light, LoadReport, Material, Scene, Sphere, Triangle};
use anyhow::{anyhow, bail, Context, Result};
use glam::{DMat4, DQuat, DVec3, Mat3, Mat4, Vec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::json;
use gltf::mesh::{Mode, Semantic};
use serde_json::Value;
use std::path::{Component, Path};

/// Extension names understood by the importer.
pub const EXT_SPHERES: &str = "VKVCM_spheres";
pub const EXT_MATERIALS_PHONG: &str = "VKVCM_materials_phong";
pub const EXT_BACKGROUND: &str = "VKVCM_background";

/// All extensions the importer interprets; any other one in `extensionsUsed` or
/// `extensionsRequired` is reported as a warning.
pub const SUPPORTED_EXTENSIONS: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_transmission",
    "KHR_materials_ior",
    "KHR_materials_emissive_strength",
    EXT_SPHERES,
    EXT_MATERIALS_PHONG,
    EXT_BACKGROUND,
];

/// Options of [`load_gltf`].
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LoadOptions {
    /// Select the camera whose node name or camera name equals this; `None`: the first
    /// perspective camera in node order.
    pub camera: Option<String>,
}

/// Specular reflectance of dielectrics at normal incidence used by the
/// metallic/roughness mapping (glTF's fixed F0).
const DIELECTRIC_F0: f32 = 0.04;

/// Loads a `.gltf` or `.glb` file. Errors name the file and the offending object.
pub fn load_gltf(path: &Path, options: &LoadOptions) -> Result<Scene> {
    let bytes = std::fs::read(path).map_err(|e| one_line(path, &anyhow!("cannot read scene file: {e}")))?;
    load_gltf_bytes(&bytes, path, options)
}

/// Imports `bytes` as if they were the contents of the `.gltf`/`.glb` file `path`: external
/// buffers are resolved in `path`'s folder, the scene is named after its file stem, and an
/// error is one line that starts with `path`. The entry point of the fuzz target
/// (`fuzz/fuzz_targets/gltf_load.rs`); it never panics on malformed input.
pub fn load_gltf_bytes(bytes: &[u8], path: &Path, options: &LoadOptions) -> Result<Scene> {
    let base_dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let name = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    import_bytes(bytes, base_dir, name, options).map_err(|e| one_line(path, &e))
}

/// `"<path>: <error chain>"` on one line (the CLI prints errors as one `error: ...` line;
/// a newline in a file name or a nested message must not break that).
pub(crate) fn one_line(path: &Path, e: &anyhow::Error) -> anyhow::Error {
    let msg = format!("{}: {e:#}", path.display());
    anyhow!(msg.replace(['\n', '\r'], " "))
}

/// `data:` URI holding `bytes` in base64, as used for embedded glTF buffers.
pub fn encode_data_uri(bytes: &[u8]) -> String {
    format!("data:application/octet-stream;base64,{}", base64_encode(bytes))
}

/// The bytes of a base64 `data:` URI (the inverse of [`encode_data_uri`]).
pub fn decode_data_uri(uri: &str) -> Result<Vec<u8>> {
    if !uri.starts_with("data:") {
        bail!("not a data: URI");
    }
    load_uri(uri, Path::new("."))
}

// ---------------------------------------------------------------------------------------
// Warnings: one entry per kind, with the first occurrence and a count.

#[derive(Default)]
struct Warnings {
    kinds: Vec<(String, String, usize)>,
}

impl Warnings {
    fn warn(&mut self, kind: impl Into<String>, detail: impl Into<String>) {
        let kind = kind.into();
        if let Some(entry) = self.kinds.iter_mut().find(|(k, _, _)| *k == kind) {
            entry.2 += 1;
        } else {
            self.kinds.push((kind, detail.into(), 1));
        }
    }

    fn finish(self) -> Vec<String> {
        self.kinds
            .into_iter()
            .map(|(kind, first, count)| {
                let mut s = kind;
                if !first.is_empty() {
                    s.push_str(&format!(" (first: {first}"));
                    if count > 1 {
                        s.push_str(&format!("; {} occurrences", count));
                    }
                    s.push(')');
                } else if count > 1 {
                    s.push_str(&format!(" ({count} occurrences)"));
                }
                s
            })
            .collect()
    }
}

// ---------------------------------------------------------------------------------------
// Document parsing and validation.

fn parse_document(bytes: &[u8], warnings: &mut Warnings) -> Result<(json::Root, Option<Vec<u8>>)> {
    let (mut root, blob): (json::Root, Option<Vec<u8>>) = if bytes.starts_with(b"glTF") {
        check_glb_header(bytes)?;
        let glb = gltf::binary::Glb::from_slice(bytes).map_err(|e| anyhow!("invalid GLB container: {e}"))?;
        let root =
            serde_json::from_slice(&glb.json).map_err(|e| anyhow!("invalid glTF JSON in the GLB JSON chunk: {e}"))?;
        (root, glb.bin.map(|b| b.into_owned()))
    } else {
        let root = serde_json::from_slice(bytes).map_err(|e| anyhow!("invalid glTF JSON: {e}"))?;
        (root, None)
    };

    // Extensions. glTF 2.0 (section 3.12): a loader that does not support an extension
    // listed in `extensionsRequired` must not load the asset, so those are errors; unknown
    // extensions that are only used become warnings.
    let unsupported: Vec<&str> =
        root.extensions_required.iter().map(String::as_str).filter(|e| !SUPPORTED_EXTENSIONS.contains(e)).collect();
    if !unsupported.is_empty() {
        bail!(
            "unsupported required extension(s) {} (extensionsRequired; supported: {})",
            unsupported.join(", "),
            SUPPORTED_EXTENSIONS.join(", ")
        );
    }
    let mut seen = Vec::new();
    for ext in &root.extensions_used {
        if SUPPORTED_EXTENSIONS.contains(&ext.as_str()) || seen.contains(ext) {
            continue;
        }
        seen.push(ext.clone());
        warnings.warn(format!("extension {ext} is not supported and was ignored"), "");
    }
    // vkvcm's own extensions are handled here; the gltf crate's validation refuses
    // required extensions it does not know.
    root.extensions_required.retain(|e| json::extensions::ENABLED_EXTENSIONS.contains(&e.as_str()));

    // gltf-json's primitive check indexes the POSITION accessor without a bounds check:
    // refuse dangling attribute indices first.
    for (mi, mesh) in root.meshes.iter().enumerate() {
        for (pi, prim) in mesh.primitives.iter().enumerate() {
            for (sem, index) in &prim.attributes {
                if index.value() >= root.accessors.len() {
                    let sem = match sem {
                        json::validation::Checked::Valid(s) => s.to_string(),
                        json::validation::Checked::Invalid => "?".to_string(),
                    };
                    bail!(
                        "invalid glTF: meshes[{mi}].primitives[{pi}].attributes[\"{sem}\"] refers to accessor {}, but there are {} accessors",
                        index.value(),
                        root.accessors.len()
                    );
                }
            }
        }
    }

    use json::validation::{Error as VError, Validate};
    let mut errors = Vec::new();
    let mut missing_bounds = None;
    root.validate(&root, json::Path::new, &mut |path, error| {
        let path = path().to_string();
        if matches!(error, VError::Missing)
            && path.contains("[\"POSITION\"]")
            && (path.ends_with(".min") || path.ends_with(".max"))
        {
            // Required by the spec but not needed here: tolerated with a warning.
            missing_bounds.get_or_insert(path);
            return;
        }
        let hint = match error {
            VError::IndexOutOfBounds => " (refers to an object that does not exist)",
            _ => "",
        };
        errors.push(format!("{path}: {error}{hint}"));
    });
    if let Some(path) = missing_bounds {
        warnings.warn("POSITION accessor without the required min/max (tolerated)", path);
    }
    if !errors.is_empty() {
        let shown = errors.iter().take(8).cloned().collect::<Vec<_>>().join("; ");
        let more = if errors.len() > 8 { format!(" (and {} more)", errors.len() - 8) } else { String::new() };
        bail!("invalid glTF: {shown}{more}");
    }
    Ok((root, blob))
}

/// Checks the 12-byte GLB header before `gltf::binary::Glb::from_slice`, which computes
/// `length - 12` unchecked (a debug-build panic for a declared length below 12).
fn check_glb_header(bytes: &[u8]) -> Result<()> {
    let word = |i: usize| bytes.get(i..i + 4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
    let (Some(version), Some(length)) = (word(4), word(8)) else {
        bail!("invalid GLB container: the file ends inside the 12-byte header ({} bytes)", bytes.len());
    };
    if version != 2 {
        bail!("invalid GLB container: version {version} is not supported (only 2)");
    }
    if (length as usize) < 12 + 8 {
        bail!("invalid GLB container: declared length {length} is too short for a header and a JSON chunk");
    }
    if length as usize > bytes.len() {
        bail!("invalid GLB container: declared length {length} but the file has {} bytes (truncated?)", bytes.len());
    }
    Ok(())
}

fn import_bytes(bytes: &[u8], base_dir: &Path, name: String, options: &LoadOptions) -> Result<Scene> {
    let mut warnings = Warnings::default();
    let (root, blob) = parse_document(bytes, &mut warnings)?;
    let doc = gltf::Document::from_json_without_validation(root);
    let buffers = load_buffers(&doc, blob, base_dir)?;
    let mut importer = Importer {
        doc: &doc,
        buffers,
        warnings,
        scene: Scene {
            name,
            triangles: Vec::new(),
            spheres: Vec::new(),
            materials: Vec::new(),
            lights: Vec::new(),
            camera: Camera {
                position: Vec3::ZERO,
                forward: Vec3::NEG_Z,
                up: Vec3::Y,
                yfov: std::f32::consts::FRAC_PI_4,
            },
            report: LoadReport::default(),
        },
        default_material: None,
        cameras: Vec::new(),
        punctual: Vec::new(),
    };
    importer.run(options)?;
    let Importer { mut scene, mut warnings, .. } = importer;
    for (kind, detail) in super::validate::camera_warnings(&scene) {
        warnings.warn(kind, detail);
    }
    scene.report.warnings = warnings.finish();
    Ok(scene)
}

// ---------------------------------------------------------------------------------------
// Buffers and URIs.

fn load_buffers(doc: &gltf::Document, blob: Option<Vec<u8>>, base_dir: &Path) -> Result<Vec<Vec<u8>>> {
    let mut blob = blob;
    let mut out = Vec::new();
    for buffer in doc.buffers() {
        let i = buffer.index();
        let data = match buffer.source() {
            gltf::buffer::Source::Bin => blob
                .take()
                .ok_or_else(|| anyhow!("buffer {i} has no uri and there is no (unused) GLB binary chunk for it"))?,
            gltf::buffer::Source::Uri(uri) => load_uri(uri, base_dir).with_context(|| format!("buffer {i}"))?,
        };
        if data.len() < buffer.length() {
            bail!("buffer {i} holds {} bytes but its byteLength is {}", data.len(), buffer.length());
        }
        out.push(data);
    }
    Ok(out)
}

fn load_uri(uri: &str, base_dir: &Path) -> Result<Vec<u8>> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let (meta, payload) = rest.split_once(',').ok_or_else(|| anyhow!("malformed data URI (no ',')"))?;
        if !meta.ends_with(";base64") {
            bail!("data URI without base64 encoding is not supported");
        }
        return base64_decode(payload).map_err(|e| anyhow!("data URI: {e}"));
    }
    // A scheme ("http:", "file:", ...) has at least two characters before ':'; a single
    // letter is a Windows drive, refused below as absolute.
    if let Some((scheme, _)) = uri.split_once(':') {
        if scheme.len() > 1 && scheme.chars().all(|c| c.is_ascii_alphanumeric() || matches!(c, '+' | '-' | '.')) {
            bail!("URI '{uri}' has a scheme ({scheme}:); only relative file paths and data: URIs are supported");
        }
    }
    let decoded = percent_decode(uri).ok_or_else(|| anyhow!("URI '{uri}' has a bad %-escape"))?;
    let bytes = decoded.as_bytes();
    let absolute = decoded.starts_with('/')
        || decoded.starts_with('\\')
        || (bytes.len() >= 2 && bytes[0].is_ascii_alphabetic() && bytes[1] == b':');
    if absolute {
        bail!("URI '{uri}' is an absolute path; buffers must be given relative to the scene's folder");
    }
    if decoded.split(['/', '\\']).any(|c| c == "..") {
        bail!("URI '{uri}' contains '..'; buffers must stay inside the scene's folder");
    }
    let rel = Path::new(&decoded);
    if rel.components().any(|c| !matches!(c, Component::Normal(_) | Component::CurDir)) {
        bail!("URI '{uri}' does not name a file inside the scene's folder");
    }
    let file = base_dir.join(rel);
    let cannot = |e: std::io::Error| anyhow!("cannot read buffer file {}: {e}", file.display());
    // A symbolic link may still lead outside: compare the resolved paths.
    let real = std::fs::canonicalize(&file).map_err(cannot)?;
    let real_base = std::fs::canonicalize(base_dir).map_err(cannot)?;
    if !real.starts_with(&real_base) {
        bail!("URI '{uri}' resolves (through a symbolic link) to {}, outside the scene's folder", real.display());
    }
    if !std::fs::metadata(&real).map_err(cannot)?.is_file() {
        bail!("URI '{uri}': {} is not a regular file", file.display());
    }
    std::fs::read(&real).map_err(cannot)
}

fn percent_decode(s: &str) -> Option<String> {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' {
            let hex = s.get(i + 1..i + 3)?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

const B64: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

pub(crate) fn base64_encode(bytes: &[u8]) -> String {
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let n = chunk.len();
        let v = (chunk[0] as u32) << 16
            | (chunk.get(1).copied().unwrap_or(0) as u32) << 8
            | chunk.get(2).copied().unwrap_or(0) as u32;
        for k in 0..4 {
            if k <= n {
                out.push(B64[((v >> (18 - 6 * k)) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

pub(crate) fn base64_decode(s: &str) -> std::result::Result<Vec<u8>, String> {
    let s = s.trim_end_matches('=');
    let mut out = Vec::with_capacity(s.len() * 3 / 4);
    let mut acc = 0u32;
    let mut bits = 0;
    for (i, c) in s.bytes().enumerate() {
        let v = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            _ => return Err(format!("invalid base64 character at position {i}")),
        } as u32;
        acc = (acc << 6) | v;
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    if bits >= 6 {
        return Err("truncated base64 payload".into());
    }
    Ok(out)
}

// ---------------------------------------------------------------------------------------
// Accessors (read here with bounds checks rather than through gltf's reader).

fn view_bytes<'b>(buffers: &'b [Vec<u8>], acc: &gltf::Accessor, elem_size: usize) -> Result<Option<(&'b [u8], usize)>> {
    let ai = acc.index();
    let Some(view) = acc.view() else {
        return Ok(None);
    };
    let vi = view.index();
    let bi = view.buffer().index();
    let data = &buffers[bi];
    let view_end = view.offset().checked_add(view.length()).filter(|&e| e <= data.len()).ok_or_else(|| {
        anyhow!(
            "buffer view {vi} (offset {}, length {}) exceeds buffer {bi} ({} bytes)",
            view.offset(),
            view.length(),
            data.len()
        )
    })?;
    let view_data = &data[view.offset()..view_end];
    let stride = view.stride().unwrap_or(elem_size);
    if stride < elem_size {
        bail!("accessor {ai}: byteStride {stride} of buffer view {vi} is smaller than the element size {elem_size}");
    }
    let count = acc.count();
    if count > 0 {
        let needed = (count - 1)
            .checked_mul(stride)
            .and_then(|x| x.checked_add(elem_size))
            .and_then(|x| x.checked_add(acc.offset()));
        match needed {
            Some(n) if n <= view_data.len() => {}
            _ => bail!(
                "accessor {ai} ({count} elements of {elem_size} bytes, stride {stride}, offset {}) exceeds buffer view {vi} ({} bytes)",
                acc.offset(),
                view_data.len()
            ),
        }
    }
    Ok(Some((&view_data[acc.offset().min(view_data.len())..], stride)))
}

fn read_vec3(buffers: &[Vec<u8>], acc: &gltf::Accessor, what: &str) -> Result<Vec<Vec3>> {
    let ai = acc.index();
    if acc.data_type() != DataType::F32 || acc.dimensions() != Dimensions::Vec3 {
        bail!("accessor {ai} ({what}) must be FLOAT VEC3, is {:?} {:?}", acc.data_type(), acc.dimensions());
    }
    let count = acc.count();
    let Some((data, stride)) = view_bytes(buffers, acc, 12)? else {
        bail!("accessor {ai} ({what}) has no bufferView (all zeros; sparse accessors are not supported)");
    };
    let f = |o: usize| f32::from_le_bytes([data[o], data[o + 1], data[o + 2], data[o + 3]]);
    Ok((0..count)
        .map(|i| {
            let o = i * stride;
            Vec3::new(f(o), f(o + 4), f(o + 8))
        })
        .collect())
}

fn read_indices(buffers: &[Vec<u8>], acc: &gltf::Accessor) -> Result<Vec<u32>> {
    let ai = acc.index();
    if acc.dimensions() != Dimensions::Scalar {
        bail!("index accessor {ai} must be SCALAR, is {:?}", acc.dimensions());
    }
    let size = match acc.data_type() {
        DataType::U8 => 1,
        DataType::U16 => 2,
        DataType::U32 => 4,
        t => bail!("index accessor {ai} must be UNSIGNED_BYTE/SHORT/INT, is {t:?}"),
    };
    let count = acc.count();
    let Some((data, stride)) = view_bytes(buffers, acc, size)? else {
        bail!("index accessor {ai} has no bufferView (all zeros; sparse accessors are not supported)");
    };
    Ok((0..count)
        .map(|i| {
            let o = i * stride;
            match size {
                1 => data[o] as u32,
                2 => u16::from_le_bytes([data[o], data[o + 1]]) as u32,
                _ => u32::from_le_bytes([data[o], data[o + 1], data[o + 2], data[o + 3]]),
            }
        })
        .collect())
}

// ---------------------------------------------------------------------------------------
// Extension payloads.

fn ext_vec3(v: &Value, field: &str, default: Vec3, ctx: &str) -> Result<Vec3> {
    match v.get(field) {
        None => Ok(default),
        Some(Value::Array(a)) if a.len() == 3 => {
            let mut out = [0f32; 3];
            for (k, x) in a.iter().enumerate() {
                out[k] = x
                    .as_f64()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| anyhow!("{ctx}.{field}[{k}] must be a finite number"))?
                    as f32;
            }
            Ok(Vec3::from_array(out))
        }
        Some(_) => bail!("{ctx}.{field} must be an array of 3 numbers"),
    }
}

fn ext_f32(v: &Value, field: &str, default: f32, ctx: &str) -> Result<f32> {
    match v.get(field) {
        None => Ok(default),
        Some(x) => {
            Ok(x.as_f64().filter(|x| x.is_finite()).ok_or_else(|| anyhow!("{ctx}.{field} must be a finite number"))?
                as f32)
        }
    }
}

fn non_negative(v: Vec3, what: &str) -> Result<Vec3> {
    if v.min_element() < 0.0 {
        bail!("{what} must not be negative, is {v}");
    }
    Ok(v)
}

// ---------------------------------------------------------------------------------------
// The importer proper.

struct CameraCandidate {
    node_name: Option<String>,
    camera_name: Option<String>,
    world: Mat4,
    yfov: f32,
    node: usize,
}

struct Importer<'d> {
    doc: &'d gltf::Document,
    buffers: Vec<Vec<u8>>,
    warnings: Warnings,
    scene: Scene,
    default_material: Option<u32>,
    cameras: Vec<CameraCandidate>,
    punctual: Vec<Light>,
}

impl Importer<'_> {
    fn run(&mut self, options: &LoadOptions) -> Result<()> {
        let doc = self.doc;
        for m in doc.materials() {
            let mat = self.convert_material(&m)?;
            self.scene.materials.push(mat);
        }
        if doc.animations().len() > 0 {
            self.warnings.warn(
                "animations are not supported (the static pose is used)",
                format!("{} animation(s)", doc.animations().len()),
            );
        }

        let scene = match doc.default_scene() {
            Some(s) => s,
            None => {
                let s = doc.scenes().next().ok_or_else(|| anyhow!("the file has no scene"))?;
                if doc.scenes().len() > 1 {
                    self.warnings.warn(
                        "no default scene: the first scene is rendered",
                        format!("{} scenes", doc.scenes().len()),
                    );
                }
                s
            }
        };

        // Depth-first traversal in node order; glTF requires a forest, so a node reached
        // twice is an error rather than an infinite loop. World transforms are composed in
        // f64 and the scene is re-centred on the chosen camera before it is rounded to f32
        // (camera-relative coordinates, docs/numerics.md): a scene 1e5 units from the origin
        // keeps the precision it has near the origin.
        let mut visited = vec![false; doc.nodes().len()];
        let mut order: Vec<(gltf::Node, DMat4)> = Vec::new();
        let mut stack: Vec<(gltf::Node, DMat4)> =
            scene.nodes().map(|n| (n, DMat4::IDENTITY)).collect::<Vec<_>>().into_iter().rev().collect();
        while let Some((node, parent)) = stack.pop() {
            if std::mem::replace(&mut visited[node.index()], true) {
                bail!(
                    "node {} is reached twice in scene {}: the node hierarchy is not a tree",
                    node.index(),
                    scene.index()
                );
            }
            let world = parent * local_transform_f64(&node);
            let children: Vec<_> = node.children().collect();
            for child in children.into_iter().rev() {
                stack.push((child, world));
            }
            order.push((node, world));
        }
        let origin = camera_origin(&order, options.camera.as_deref());
        self.scene.report.origin = origin.to_array();
        let rebase = DMat4::from_translation(-origin);
        for (node, world) in &order {
            self.visit_node(node, (rebase * *world).as_mat4())?;
        }

        // Camera.
        let chosen = match &options.camera {
            Some(want) => self
                .cameras
                .iter()
                .find(|c| {
                    c.node_name.as_deref() == Some(want.as_str()) || c.camera_name.as_deref() == Some(want.as_str())
                })
                .ok_or_else(|| {
                    let names: Vec<String> = self
                        .cameras
                        .iter()
                        .map(|c| {
                            c.node_name.clone().or(c.camera_name.clone()).unwrap_or_else(|| format!("node {}", c.node))
                        })
                        .collect();
                    anyhow!(
                        "no perspective camera named '{want}' (available: {})",
                        if names.is_empty() { "none".to_string() } else { names.join(", ") }
                    )
                })?,
            None => self.cameras.first().ok_or_else(|| anyhow!("no perspective camera in the default scene"))?,
        };
        let w = chosen.world;
        let position = w.transform_point3(Vec3::ZERO);
        let forward = w.transform_vector3(Vec3::NEG_Z).normalize();
        let up_raw = w.transform_vector3(Vec3::Y);
        let up = (up_raw - forward * forward.dot(up_raw)).normalize();
        if !(position.is_finite() && forward.is_finite() && up.is_finite()) {
            bail!("camera node {} has a degenerate world transform", chosen.node);
        }
        if !(chosen.yfov > 0.0 && chosen.yfov < std::f32::consts::PI) {
            bail!("camera node {}: yfov {} is not in (0, pi)", chosen.node, chosen.yfov);
        }
        self.scene.camera = Camera { position, forward, up, yfov: chosen.yfov };

        // Lights: area lights (triangle order), punctual lights (node order), background.
        for (i, t) in self.scene.triangles.iter().enumerate() {
            let e = self.scene.materials[t.material as usize].emission;
            if e.max_element() > 0.0 {
                self.scene.lights.push(Light::Area { triangle: i as u32, radiance: e });
            }
        }
        for s in &self.scene.spheres {
            let m = &self.scene.materials[s.material as usize];
            if m.emission.max_element() > 0.0 {
                self.warnings.warn(
                    "emissive spheres are not light sources (emission on spheres is ignored for lighting)",
                    format!("material {}", m.name),
                );
            }
        }
        self.scene.lights.append(&mut self.punctual);
        if let Some(bg) = doc.extensions().and_then(|e| e.get(EXT_BACKGROUND)) {
            let ctx = format!("extensions.{EXT_BACKGROUND}");
            let radiance = non_negative(ext_vec3(bg, "radiance", Vec3::ZERO, &ctx)?, &ctx)?;
            self.scene.lights.push(Light::Background { radiance });
        }
        if self.scene.lights.is_empty() {
            self.warnings.warn("the scene has no light source", "");
        }
        Ok(())
    }

    fn default_material(&mut self) -> u32 {
        if let Some(i) = self.default_material {
            return i;
        }
        // glTF's default material: baseColor 1, metallic 1, roughness 1.
        let mut m = metallic_roughness(Vec3::ONE, 1.0, 1.0);
        m.name = "gltf-default".into();
        let i = self.scene.materials.len() as u32;
        self.scene.materials.push(m);
        self.default_material = Some(i);
        i
    }

    fn convert_material(&mut self, m: &gltf::Material) -> Result<Material> {
        let index = m.index().unwrap_or(0);
        let name = m.name().map(str::to_string).unwrap_or_else(|| format!("material{index}"));
        let label = format!("material {index} '{name}'");
        let pbr = m.pbr_metallic_roughness();
        let bc = pbr.base_color_factor();
        let base = Vec3::new(bc[0], bc[1], bc[2]).clamp(Vec3::ZERO, Vec3::ONE);
        let metallic = pbr.metallic_factor().clamp(0.0, 1.0);
        let roughness = pbr.roughness_factor().clamp(0.0, 1.0);

        let mut textures = Vec::new();
        if pbr.base_color_texture().is_some() {
            textures.push("baseColorTexture");
        }
        if pbr.metallic_roughness_texture().is_some() {
            textures.push("metallicRoughnessTexture");
        }
        if m.normal_texture().is_some() {
            textures.push("normalTexture");
        }
        if m.occlusion_texture().is_some() {
            textures.push("occlusionTexture");
        }
        if m.emissive_texture().is_some() {
            textures.push("emissiveTexture");
        }
        if m.transmission().and_then(|t| t.transmission_texture()).is_some() {
            textures.push("transmissionTexture");
        }
        for t in textures {
            self.warnings.warn("textures are not supported (the constant factors are used)", format!("{label} {t}"));
        }
        if m.alpha_mode() != gltf::material::AlphaMode::Opaque {
            self.warnings.warn("alphaMode MASK/BLEND is not supported (materials are opaque)", label.clone());
        }

        let phong_ext = m.extensions().and_then(|e| e.get(EXT_MATERIALS_PHONG));
        let mut out = if let Some(v) = phong_ext {
            let ctx = format!("materials[{index}].extensions.{EXT_MATERIALS_PHONG}");
            if !v.is_object() {
                bail!("{ctx} must be an object");
            }
            let c =
                |f: &str| -> Result<Vec3> { non_negative(ext_vec3(v, f, Vec3::ZERO, &ctx)?, &format!("{ctx}.{f}")) };
            let exponent = ext_f32(v, "exponent", 1.0, &ctx)?;
            if exponent < 0.0 {
                bail!("{ctx}.exponent must not be negative");
            }
            Material {
                name: String::new(),
                diffuse: c("diffuse")?,
                phong: c("phong")?,
                phong_exponent: exponent,
                mirror: c("mirror")?,
                ior: ext_f32(v, "ior", -1.0, &ctx)?,
                emission: Vec3::ZERO,
                glossy: Vec3::ZERO,
                roughness: 1.0,
            }
        } else if let Some(t) = m.transmission().filter(|t| t.transmission_factor() > 0.0) {
            if t.transmission_factor() < 1.0 || roughness > 0.0 || base != Vec3::ONE {
                self.warnings
                    .warn("partial, rough or tinted transmission is approximated by clear smooth glass", label.clone());
            }
            let ior = m.ior().unwrap_or(1.5);
            if !(ior >= 1.0 && ior.is_finite()) {
                bail!("{label}: KHR_materials_ior ior = {ior} is not supported (need >= 1)");
            }
            Material { mirror: Vec3::ONE, ior, ..Material::default() }
        } else {
            metallic_roughness(base, metallic, roughness)
        };
        let strength = m.emissive_strength().unwrap_or(1.0);
        let ef = m.emissive_factor();
        out.emission = non_negative(Vec3::from_array(ef) * strength, &format!("{label} emission"))?;
        if !out.emission.is_finite() {
            bail!("{label}: emission is not finite");
        }
        out.name = name;
        Ok(out)
    }

    fn visit_node(&mut self, node: &gltf::Node, world: Mat4) -> Result<()> {
        let ni = node.index();
        let label = match node.name() {
            Some(n) => format!("node {ni} '{n}'"),
            None => format!("node {ni}"),
        };
        if !world.is_finite() {
            bail!("{label}: world transform is not finite");
        }
        if node.skin().is_some() {
            self.warnings
                .warn("skins are not supported (meshes are placed by their node transform, unskinned)", label.clone());
        }
        if node.weights().is_some() {
            self.warnings.warn("morph targets are not supported (base geometry used)", label.clone());
        }
        if let Some(cam) = node.camera() {
            match cam.projection() {
                gltf::camera::Projection::Perspective(p) => self.cameras.push(CameraCandidate {
                    node_name: node.name().map(str::to_string),
                    camera_name: cam.name().map(str::to_string),
                    world,
                    yfov: p.yfov(),
                    node: ni,
                }),
                gltf::camera::Projection::Orthographic(_) => self.warnings.warn(
                    "orthographic cameras are not supported (skipped)",
                    format!("camera {} on {label}", cam.index()),
                ),
            }
        }
        if let Some(light) = node.light() {
            self.add_light(&light, world, &label)?;
        }
        if let Some(mesh) = node.mesh() {
            self.add_mesh(&mesh, world, &label)?;
        }
        if let Some(v) = node.extensions().and_then(|e| e.get(EXT_SPHERES)) {
            self.add_spheres(v, world, ni)?;
        }
        Ok(())
    }

    fn add_light(&mut self, light: &gltf::khr_lights_punctual::Light, world: Mat4, label: &str) -> Result<()> {
        use gltf::khr_lights_punctual::Kind;
        let li = light.index();
        let power = Vec3::from_array(light.color()) * light.intensity();
        if !power.is_finite() || power.min_element() < 0.0 {
            bail!("light {li}: color * intensity must be finite and non-negative, is {power}");
        }
        if light.range().is_some() {
            self.warnings.warn(
                "light range is ignored (lights fall off with the inverse square law only)",
                format!("light {li} on {label}"),
            );
        }
        let position = world.transform_point3(Vec3::ZERO);
        let direction = world.transform_vector3(Vec3::NEG_Z).normalize();
        let l = match light.kind() {
            Kind::Point => Light::Point { position, intensity: power },
            Kind::Spot { inner_cone_angle, outer_cone_angle } => {
                if !direction.is_finite() {
                    bail!("light {li} on {label}: degenerate node orientation");
                }
                Light::Spot {
                    position,
                    direction,
                    intensity: power,
                    cos_inner: inner_cone_angle.cos(),
                    cos_outer: outer_cone_angle.cos(),
                }
            }
            Kind::Directional => {
                if !direction.is_finite() {
                    bail!("light {li} on {label}: degenerate node orientation");
                }
                Light::Directional { direction, irradiance: power }
            }
        };
        self.punctual.push(l);
        Ok(())
    }

    fn add_spheres(&mut self, v: &Value, world: Mat4, ni: usize) -> Result<()> {
        let ctx = format!("nodes[{ni}].extensions.{EXT_SPHERES}");
        let list =
            v.get("spheres").and_then(Value::as_array).ok_or_else(|| anyhow!("{ctx}.spheres must be an array"))?;
        let m3 = Mat3::from_mat4(world);
        let s = [m3.x_axis.length(), m3.y_axis.length(), m3.z_axis.length()];
        let smax = s[0].max(s[1]).max(s[2]);
        let gram = m3.transpose() * m3;
        let uniform = smax > 0.0
            && (gram - Mat3::from_diagonal(Vec3::splat(smax * smax)))
                .to_cols_array()
                .iter()
                .all(|x| x.abs() <= 1e-5 * smax * smax);
        if !uniform {
            bail!(
                "{ctx}: spheres need a uniform scale, but the node's world matrix scales by ({}, {}, {}) or shears",
                s[0],
                s[1],
                s[2]
            );
        }
        for (k, sp) in list.iter().enumerate() {
            let c = format!("{ctx}.spheres[{k}]");
            if sp.get("center").is_none() {
                bail!("{c}.center is missing");
            }
            let center = ext_vec3(sp, "center", Vec3::ZERO, &c)?;
            let radius = sp
                .get("radius")
                .and_then(Value::as_f64)
                .filter(|r| *r > 0.0 && r.is_finite())
                .ok_or_else(|| anyhow!("{c}.radius must be a positive number"))? as f32;
            let material = match sp.get("material") {
                None => self.default_material(),
                Some(m) => {
                    let n = self.doc.materials().len() as u64;
                    let i = m.as_u64().ok_or_else(|| anyhow!("{c}.material must be a material index"))?;
                    if i >= n {
                        bail!("{c}.material = {i} is out of range ({n} materials)");
                    }
                    i as u32
                }
            };
            self.scene.spheres.push(Sphere { center: world.transform_point3(center), radius: radius * smax, material });
        }
        Ok(())
    }

    fn add_mesh(&mut self, mesh: &gltf::Mesh, world: Mat4, label: &str) -> Result<()> {
        let mi = mesh.index();
        let normal_matrix = Mat3::from_mat4(world).inverse().transpose();
        let flip = Mat3::from_mat4(world).determinant() < 0.0;
        for prim in mesh.primitives() {
            let pi = prim.index();
            let where_ = format!("mesh {mi} primitive {pi} (on {label})");
            let mode = prim.mode();
            if !matches!(mode, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
                let name = match mode {
                    Mode::Points => "POINTS",
                    Mode::Lines => "LINES",
                    Mode::LineLoop => "LINE_LOOP",
                    Mode::LineStrip => "LINE_STRIP",
                    _ => "?",
                };
                self.warnings.warn(format!("primitive mode {name} is not supported (primitive skipped)"), where_);
                continue;
            }
            if prim.morph_targets().len() > 0 {
                self.warnings.warn("morph targets are not supported (base geometry used)", where_.clone());
            }
            if prim.get(&Semantic::Colors(0)).is_some() {
                self.warnings.warn("vertex colors (COLOR_0) are not supported (ignored)", where_.clone());
            }
            let Some(pos_acc) = prim.get(&Semantic::Positions) else {
                self.warnings.warn("primitive without POSITION (skipped)", where_.clone());
                continue;
            };
            let normal_acc = prim.get(&Semantic::Normals);
            let index_acc = prim.indices();
            let sparse = [Some(&pos_acc), normal_acc.as_ref(), index_acc.as_ref()]
                .into_iter()
                .flatten()
                .find(|a| a.sparse().is_some());
            if let Some(a) = sparse {
                self.warnings.warn(
                    "sparse accessors are not supported (primitive skipped)",
                    format!("accessor {} of {where_}", a.index()),
                );
                continue;
            }
            let positions = read_vec3(&self.buffers, &pos_acc, "POSITION").with_context(|| where_.clone())?;
            let normals = match &normal_acc {
                Some(a) => {
                    let n = read_vec3(&self.buffers, a, "NORMAL").with_context(|| where_.clone())?;
                    if n.len() != positions.len() {
                        bail!(
                            "{where_}: NORMAL accessor {} has {} elements, POSITION accessor {} has {}",
                            a.index(),
                            n.len(),
                            pos_acc.index(),
                            positions.len()
                        );
                    }
                    Some(n)
                }
                None => None,
            };
            let indices: Vec<u32> = match &index_acc {
                Some(a) => {
                    let idx = read_indices(&self.buffers, a).with_context(|| where_.clone())?;
                    if let Some((k, &v)) = idx.iter().enumerate().find(|(_, &v)| v as usize >= positions.len()) {
                        bail!(
                            "{where_}: index accessor {} element {k} = {v} is out of range (POSITION accessor {} has {} vertices)",
                            a.index(),
                            pos_acc.index(),
                            positions.len()
                        );
                    }
                    idx
                }
                None => (0..positions.len() as u32).collect(),
            };
            let tris: Vec<[u32; 3]> = match mode {
                Mode::Triangles => {
                    if !indices.len().is_multiple_of(3) {
                        self.warnings.warn(
                            "TRIANGLES primitive whose vertex/index count is not a multiple of 3 (trailing vertices ignored)",
                            where_.clone(),
                        );
                    }
                    indices.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()
                }
                Mode::TriangleStrip => (0..indices.len().saturating_sub(2))
                    .map(|i| {
                        if i % 2 == 0 {
                            [indices[i], indices[i + 1], indices[i + 2]]
                        } else {
                            [indices[i + 1], indices[i], indices[i + 2]]
                        }
                    })
                    .collect(),
                _ => (1..indices.len().saturating_sub(1)).map(|i| [indices[i], indices[i + 1], indices[0]]).collect(),
            };
            let material = match prim.material().index() {
                Some(i) => i as u32,
                None => self.default_material(),
            };
            for t in tris {
                let mut p = t.map(|i| world.transform_point3(positions[i as usize]));
                let mut n = normals.as_ref().map(|ns| t.map(|i| (normal_matrix * ns[i as usize]).normalize_or_zero()));
                if flip {
                    // A mirroring transform reverses the winding; keep the geometric normal
                    // on the side the author meant.
                    p.swap(1, 2);
                    if let Some(n) = n.as_mut() {
                        n.swap(1, 2);
                    }
                }
                let area2 = (p[1] - p[0]).cross(p[2] - p[0]);
                let zero_area = area2.length_squared().partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater);
                if !p.iter().all(|q| q.is_finite()) || zero_area || !area2.normalize().is_finite() {
                    self.scene.report.degenerate_triangles += 1;
                    continue;
                }
                if let Some(ns) = &n {
                    if ns.iter().any(|v| *v == Vec3::ZERO || !v.is_finite()) {
                        self.warnings.warn(
                            "zero-length or invalid vertex normals (that triangle uses its geometric normal)",
                            where_.clone(),
                        );
                        n = None;
                    }
                }
                self.scene.triangles.push(Triangle { p, n, material });
            }
        }
        Ok(())
    }
}

/// The metallic/roughness -> diffuse + GGX (+ mirror) mapping of docs/scene-format.md.
/// A node's local transform in f64 (TRS composed in f64, so a large translation stays exact).
fn local_transform_f64(node: &gltf::Node) -> DMat4 {
    match node.transform() {
        gltf::scene::Transform::Matrix { matrix } => DMat4::from_cols_array_2d(&matrix.map(|c| c.map(f64::from))),
        gltf::scene::Transform::Decomposed { translation, rotation, scale } => {
            let q = DQuat::from_array(rotation.map(f64::from));
            // glTF rotations are unit quaternions; normalising guards against rounding in the file.
            let q = if q.length_squared() > 0.0 { q.normalize() } else { DQuat::IDENTITY };
            DMat4::from_scale_rotation_translation(
                DVec3::from_array(scale.map(f64::from)),
                q,
                DVec3::from_array(translation.map(f64::from)),
            )
        }
    }
}

/// World position of the camera the importer will choose (the one named `want`, else the
/// first perspective camera in traversal order), or the origin when there is none: the
/// scene is translated so that this point becomes (0, 0, 0).
fn camera_origin(order: &[(gltf::Node, DMat4)], want: Option<&str>) -> DVec3 {
    let is_persp =
        |n: &gltf::Node| n.camera().is_some_and(|c| matches!(c.projection(), gltf::camera::Projection::Perspective(_)));
    let matches = |n: &gltf::Node| match want {
        None => true,
        Some(w) => n.name() == Some(w) || n.camera().and_then(|c| c.name().map(str::to_string)).as_deref() == Some(w),
    };
    order
        .iter()
        .find(|(n, _)| is_persp(n) && matches(n))
        .map(|(_, w)| w.transform_point3(DVec3::ZERO))
        .filter(|p| p.is_finite())
        .unwrap_or(DVec3::ZERO)
}

fn metallic_roughness(base: Vec3, metallic: f32, roughness: f32) -> Material {
    if metallic >= 1.0 && roughness <= 0.0 {
        return Material { mirror: base, ..Material::default() };
    }
    let diffuse = base * (1.0 - metallic);
    let glossy = Vec3::splat(DIELECTRIC_F0).lerp(base, metallic);
    Material { diffuse, glossy, roughness, ..Material::default() }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_round_trip() {
        for n in 0..20 {
            let data: Vec<u8> = (0..n).map(|i| (i * 37 + 11) as u8).collect();
            let enc = base64_encode(&data);
            assert_eq!(enc.len() % 4, 0);
            assert_eq!(base64_decode(&enc).unwrap(), data);
        }
        assert_eq!(base64_encode(b"Man"), "TWFu");
        assert_eq!(base64_encode(b"Ma"), "TWE=");
        assert!(base64_decode("TW!u").is_err());
    }

    #[test]
    fn metallic_roughness_mapping() {
        let close = |a: Vec3, b: Vec3| (a - b).abs().max_element() < 1e-6;
        let m = metallic_roughness(Vec3::splat(0.5), 0.0, 1.0);
        assert!(close(m.diffuse, Vec3::splat(0.5)));
        assert!(close(m.glossy, Vec3::splat(0.04)));
        assert_eq!(m.roughness, 1.0);
        assert_eq!(m.phong, Vec3::ZERO);
        let m = metallic_roughness(Vec3::new(1.0, 0.5, 0.25), 1.0, 0.0);
        assert_eq!(m.mirror, Vec3::new(1.0, 0.5, 0.25));
        assert_eq!(m.diffuse, Vec3::ZERO);
        assert_eq!(m.glossy, Vec3::ZERO);
        let m = metallic_roughness(Vec3::new(1.0, 0.5, 0.25), 1.0, 0.5);
        assert!(close(m.glossy, Vec3::new(1.0, 0.5, 0.25)));
        assert_eq!(m.diffuse, Vec3::ZERO);
        assert_eq!(m.roughness, 0.5);
        let m = metallic_roughness(Vec3::ONE, 0.5, 0.0);
        assert!(close(m.diffuse, Vec3::splat(0.5)));
        assert!(close(m.glossy, Vec3::splat(0.52)));
        assert_eq!(m.mirror, Vec3::ZERO);
    }

    #[test]
    fn uri_rules() {
        let d = Path::new("/nonexistent-dir");
        assert!(load_uri("../x.bin", d).unwrap_err().to_string().contains(".."));
        assert!(load_uri("a/../../x.bin", d).is_err());
        assert!(load_uri("/etc/passwd", d).unwrap_err().to_string().contains("absolute"));
        assert!(load_uri("C:/x.bin", d).unwrap_err().to_string().contains("absolute"));
        assert!(load_uri("http://x/y.bin", d).unwrap_err().to_string().contains("scheme"));
        assert!(load_uri("%2e%2e/x.bin", d).unwrap_err().to_string().contains(".."));
        assert_eq!(load_uri("data:application/octet-stream;base64,TWFu", d).unwrap(), b"Man");
        let e = load_uri("missing%20file.bin", d).unwrap_err().to_string();
        assert!(e.contains("missing file.bin"), "{e}");
    }
}
