//! Where the bytes come from: the file container (`.gltf` JSON or `.glb` chunks), buffer
//! URIs, base64 `data:` URIs, and the sandbox that keeps relative URIs inside the scene's
//! folder.

use anyhow::{anyhow, bail, Context, Result};
use base64::alphabet;
use base64::engine::{DecodePaddingMode, GeneralPurpose, GeneralPurposeConfig};
use base64::{DecodeError, Engine as _};
use gltf::json;
use std::borrow::Cow;
use std::path::{Component, Path};

/// The glTF JSON of a `.gltf` file or of a `.glb` file's JSON chunk, the `.glb` binary
/// chunk if there is one, and the morph-target attributes that [`json::Root`] drops
/// ([`extra_morph_attributes`]).
pub(super) fn read_container(bytes: &[u8]) -> Result<(json::Root, Option<Vec<u8>>, Vec<MorphAttribute>)> {
    if bytes.starts_with(b"glTF") {
        check_glb_header(bytes)?;
        let glb = gltf::binary::Glb::from_slice(bytes).map_err(|e| anyhow!("invalid GLB container: {e}"))?;
        let root =
            serde_json::from_slice(&glb.json).map_err(|e| anyhow!("invalid glTF JSON in the GLB JSON chunk: {e}"))?;
        let morph = extra_morph_attributes(&glb.json);
        Ok((root, glb.bin.map(|b| b.into_owned()), morph))
    } else {
        let root = serde_json::from_slice(bytes).map_err(|e| anyhow!("invalid glTF JSON: {e}"))?;
        Ok((root, None, extra_morph_attributes(bytes)))
    }
}

/// A morph-target attribute that gltf-json's `MorphTarget` has no field for (all but
/// POSITION, NORMAL and TANGENT: TEXCOORD_n, COLOR_n, ...), found in the raw JSON.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct MorphAttribute {
    pub mesh: usize,
    pub primitive: usize,
    pub target: usize,
    /// The attribute's semantic, e.g. `TEXCOORD_0`.
    pub name: String,
    /// The accessor of its displacements; `None` when the JSON value is not an index.
    pub accessor: Option<usize>,
}

impl MorphAttribute {
    /// Its JSON path, for messages.
    pub fn path(&self) -> String {
        format!("meshes[{}].primitives[{}].targets[{}].{}", self.mesh, self.primitive, self.target, self.name)
    }
}

/// The morph-target attributes other than POSITION, NORMAL and TANGENT in the glTF JSON
/// `json`: gltf-json drops them, so they are read here to be applied or named. Empty when
/// `json` does not have the expected shape (the main parse reports that).
fn extra_morph_attributes(json: &[u8]) -> Vec<MorphAttribute> {
    use std::collections::BTreeMap;
    #[derive(serde::Deserialize)]
    struct Doc {
        #[serde(default)]
        meshes: Vec<Mesh>,
    }
    #[derive(serde::Deserialize)]
    struct Mesh {
        #[serde(default)]
        primitives: Vec<Prim>,
    }
    #[derive(serde::Deserialize)]
    struct Prim {
        #[serde(default)]
        targets: Vec<BTreeMap<String, serde_json::Value>>,
    }
    let Ok(doc) = serde_json::from_slice::<Doc>(json) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    for (mesh, m) in doc.meshes.iter().enumerate() {
        for (primitive, p) in m.primitives.iter().enumerate() {
            for (target, t) in p.targets.iter().enumerate() {
                for (name, value) in t.iter().filter(|(k, _)| !matches!(k.as_str(), "POSITION" | "NORMAL" | "TANGENT"))
                {
                    let accessor = value.as_u64().and_then(|i| usize::try_from(i).ok());
                    out.push(MorphAttribute { mesh, primitive, target, name: name.clone(), accessor });
                }
            }
        }
    }
    out
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

/// The contents of every buffer of `doc`, in order: the GLB binary chunk for the (first)
/// buffer without a URI, otherwise the buffer's URI resolved in `base_dir`; zeros for an
/// EXT_meshopt_compression fallback buffer (src/scene/gltf_import/meshopt_views.rs). Each buffer is
/// at least as long as its declared `byteLength`.
pub(super) fn load_buffers(doc: &gltf::Document, blob: Option<Vec<u8>>, base_dir: &Path) -> Result<Vec<Vec<u8>>> {
    let mut blob = blob;
    let mut out = Vec::new();
    for buffer in doc.buffers() {
        let i = buffer.index();
        let data = match buffer.source() {
            // EXT_meshopt_compression: its compressed views decode into it.
            _ if super::meshopt_views::is_fallback(&buffer) => super::meshopt_views::fallback_bytes(&buffer)?,
            gltf::buffer::Source::Bin => blob
                .take()
                .ok_or_else(|| anyhow!("buffer {i} has no uri and there is no (unused) GLB binary chunk for it"))?,
            gltf::buffer::Source::Uri(uri) => {
                load_uri(uri, base_dir, "buffer").with_context(|| format!("buffer {i}"))?
            }
        };
        if data.len() < buffer.length() {
            bail!("buffer {i} holds {} bytes but its byteLength is {}", data.len(), buffer.length());
        }
        out.push(data);
    }
    Ok(out)
}

/// `data:` URI holding `bytes` in base64, as used for embedded glTF buffers.
pub fn encode_data_uri(bytes: &[u8]) -> String {
    format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(bytes))
}

/// The bytes of a base64 `data:` URI (the inverse of [`encode_data_uri`]).
pub fn decode_data_uri(uri: &str) -> Result<Vec<u8>> {
    if !uri.starts_with("data:") {
        bail!("not a data: URI");
    }
    load_uri(uri, Path::new("."), "buffer")
}

/// The bytes a buffer (or image, or environment map) URI names: a base64 `data:` URI, or a
/// relative file path (%-escapes decoded) that must stay inside `base_dir`, symbolic links
/// included. Other schemes and absolute paths are refused. `what` ("buffer", "image", ...)
/// names the kind of file in errors.
pub(super) fn load_uri(uri: &str, base_dir: &Path, what: &str) -> Result<Vec<u8>> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let (meta, payload) = rest.split_once(',').ok_or_else(|| anyhow!("malformed data URI (no ',')"))?;
        if !meta.ends_with(";base64") {
            bail!("data URI without base64 encoding is not supported");
        }
        return decode_base64(payload).map_err(|e| anyhow!("data URI: {e}"));
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
        bail!("URI '{uri}' is an absolute path; {what}s must be given relative to the scene's folder");
    }
    if decoded.split(['/', '\\']).any(|c| c == "..") {
        bail!("URI '{uri}' contains '..'; {what}s must stay inside the scene's folder");
    }
    let rel = Path::new(&decoded);
    if rel.components().any(|c| !matches!(c, Component::Normal(_) | Component::CurDir)) {
        bail!("URI '{uri}' does not name a file inside the scene's folder");
    }
    let file = base_dir.join(rel);
    let cannot = |e: std::io::Error| anyhow!("cannot read {what} file {}: {e}", file.display());
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

/// `s` with its `%XX` escapes decoded; `None` for a malformed escape or a result that is
/// not UTF-8.
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

/// The base64 decoder of `data:` URI payloads: the standard alphabet, no padding (it is
/// stripped before decoding), and the unused low bits of the last symbol ignored.
const DATA_URI_BASE64: GeneralPurpose = GeneralPurpose::new(
    &alphabet::STANDARD,
    GeneralPurposeConfig::new()
        .with_decode_padding_mode(DecodePaddingMode::RequireNone)
        .with_decode_allow_trailing_bits(true),
);

/// Decodes a base64 payload leniently: trailing `=` padding is optional (any amount is
/// accepted), and the URL-safe symbols `-` and `_` are read as `+` and `/`. The error
/// names the first byte that is not a base64 symbol, or says that the payload is cut off
/// in the middle of a byte.
fn decode_base64(payload: &str) -> std::result::Result<Vec<u8>, String> {
    let symbols = payload.trim_end_matches('=');
    let symbols: Cow<str> = if symbols.contains(['-', '_']) {
        Cow::Owned(symbols.replace('-', "+").replace('_', "/"))
    } else {
        Cow::Borrowed(symbols)
    };
    DATA_URI_BASE64.decode(symbols.as_bytes()).map_err(|e| match e {
        DecodeError::InvalidByte(offset, _) => {
            // The crate reports some offending byte, not necessarily the first one.
            let first = symbols.bytes().position(|b| !(b.is_ascii_alphanumeric() || b == b'+' || b == b'/'));
            format!("invalid base64 character at position {}", first.unwrap_or(offset))
        }
        DecodeError::InvalidLength(_) => "truncated base64 payload".to_string(),
        e => format!("invalid base64 payload: {e}"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn data_uri_round_trip() {
        for n in 0..20 {
            let data: Vec<u8> = (0..n).map(|i| (i * 37 + 11) as u8).collect();
            let uri = encode_data_uri(&data);
            let payload = uri.strip_prefix("data:application/octet-stream;base64,").unwrap();
            assert_eq!(payload.len() % 4, 0);
            assert_eq!(decode_data_uri(&uri).unwrap(), data);
        }
        assert_eq!(encode_data_uri(b"Man"), "data:application/octet-stream;base64,TWFu");
        assert_eq!(encode_data_uri(b"Ma"), "data:application/octet-stream;base64,TWE=");
    }

    #[test]
    fn lenient_base64() {
        assert_eq!(decode_base64("TWE=").unwrap(), b"Ma");
        assert_eq!(decode_base64("TWE").unwrap(), b"Ma");
        assert_eq!(decode_base64("TWE===").unwrap(), b"Ma");
        // Nonzero unused bits in the last symbol are ignored.
        assert_eq!(decode_base64("TWF").unwrap(), b"Ma");
        assert_eq!(decode_base64("-_-_").unwrap(), decode_base64("+/+/").unwrap());
        assert_eq!(decode_base64("TW!u").unwrap_err(), "invalid base64 character at position 2");
        assert_eq!(decode_base64("A=+/\n").unwrap_err(), "invalid base64 character at position 1");
        assert_eq!(decode_base64("TWFuT").unwrap_err(), "truncated base64 payload");
        assert!(decode_data_uri("TWFu").unwrap_err().to_string().contains("not a data: URI"));
    }

    #[test]
    fn uri_rules() {
        let d = Path::new("/nonexistent-dir");
        assert!(load_uri("../x.bin", d, "buffer").unwrap_err().to_string().contains(".."));
        assert!(load_uri("a/../../x.bin", d, "buffer").is_err());
        assert!(load_uri("/etc/passwd", d, "buffer").unwrap_err().to_string().contains("absolute"));
        assert!(load_uri("C:/x.bin", d, "buffer").unwrap_err().to_string().contains("absolute"));
        assert!(load_uri("http://x/y.bin", d, "buffer").unwrap_err().to_string().contains("scheme"));
        assert!(load_uri("%2e%2e/x.bin", d, "buffer").unwrap_err().to_string().contains(".."));
        assert_eq!(load_uri("data:application/octet-stream;base64,TWFu", d, "buffer").unwrap(), b"Man");
        let e = load_uri("missing%20file.bin", d, "buffer").unwrap_err().to_string();
        assert!(e.contains("missing file.bin"), "{e}");
    }
}
