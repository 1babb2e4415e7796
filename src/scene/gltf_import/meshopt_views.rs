//! EXT_meshopt_compression: buffer views whose bytes are stored compressed by
//! meshoptimizer's vertex and index codecs (and its filters), decoded by the `meshopt`
//! crate (bindings to meshoptimizer itself) into the place the view names, so that the
//! rest of the importer reads them as any other view. The extension's specification:
//! the view's `buffer`, `byteOffset` and `byteLength` say where the decoded bytes go (often
//! a "fallback" buffer with no data of its own), the extension's `buffer`, `byteOffset`
//! and `byteLength` where the compressed bytes are, and `count`, `byteStride`, `mode`
//! (ATTRIBUTES, TRIANGLES, INDICES) and `filter` (NONE, OCTAHEDRAL, QUATERNION,
//! EXPONENTIAL) how to decode them.

use anyhow::{anyhow, bail, Context, Result};
use serde_json::Value;

/// The extension's name.
pub const EXT_MESHOPT_COMPRESSION: &str = "EXT_meshopt_compression";

/// The most bytes a fallback buffer (one with no data, whose views are all decoded) may
/// declare: its bytes are allocated before decoding.
const MAX_FALLBACK_BYTES: usize = 1 << 31;

/// Whether `buffer` is a fallback buffer (`extensions.EXT_meshopt_compression.fallback`):
/// it has no data; the views that decode into it fill it.
pub(super) fn is_fallback(buffer: &gltf::Buffer) -> bool {
    let ext = buffer.extension_value(EXT_MESHOPT_COMPRESSION);
    ext.and_then(|e| e.get("fallback")).and_then(Value::as_bool) == Some(true)
}

/// The zeroed bytes of fallback buffer `buffer`, for the views to decode into.
pub(super) fn fallback_bytes(buffer: &gltf::Buffer) -> Result<Vec<u8>> {
    let n = buffer.length();
    if n > MAX_FALLBACK_BYTES {
        bail!(
            "buffer {} ({EXT_MESHOPT_COMPRESSION} fallback) declares {n} bytes, more than {MAX_FALLBACK_BYTES}",
            buffer.index()
        );
    }
    Ok(vec![0; n])
}

/// Decodes every compressed view of `doc` into `buffers`.
pub(super) fn decode_views(doc: &gltf::Document, buffers: &mut [Vec<u8>]) -> Result<()> {
    for view in doc.views() {
        if let Some(ext) = view.extension_value(EXT_MESHOPT_COMPRESSION) {
            let ctx = format!("bufferViews[{}].extensions.{EXT_MESHOPT_COMPRESSION}", view.index());
            decode_view(&view, ext, buffers).with_context(|| ctx)?;
        }
    }
    Ok(())
}

/// The non-negative integer `ext[field]` (`default` when absent and given).
fn field(ext: &Value, field: &str, default: Option<usize>) -> Result<usize> {
    match ext.get(field) {
        None => default.ok_or_else(|| anyhow!("{field} is missing")),
        Some(v) => v
            .as_u64()
            .and_then(|n| usize::try_from(n).ok())
            .ok_or_else(|| anyhow!("{field} must be an unsigned integer")),
    }
}

fn decode_view(view: &gltf::buffer::View, ext: &Value, buffers: &mut [Vec<u8>]) -> Result<()> {
    let source = field(ext, "buffer", None)?;
    let offset = field(ext, "byteOffset", Some(0))?;
    let length = field(ext, "byteLength", None)?;
    let stride = field(ext, "byteStride", None)?;
    let count = field(ext, "count", None)?;
    let mode = ext.get("mode").and_then(Value::as_str).ok_or_else(|| anyhow!("mode must be a string"))?;
    let filter = match ext.get("filter") {
        None => "NONE",
        Some(f) => f.as_str().ok_or_else(|| anyhow!("filter must be a string"))?,
    };
    let src = buffers
        .get(source)
        .and_then(|b| b.get(offset..offset.checked_add(length)?))
        .ok_or_else(|| anyhow!("compressed bytes {offset}..+{length} are not inside buffer {source}"))?;
    let size = count.checked_mul(stride).ok_or_else(|| anyhow!("count x byteStride overflows"))?;
    if size > view.length() {
        bail!("{count} elements of {stride} bytes do not fit the view's {} bytes", view.length());
    }
    // Decoded into u32 words: the filters read 16- and 32-bit components, so the bytes are
    // aligned whatever the view's offset.
    let mut words = vec![0u32; size.div_ceil(4)];
    let dst = words.as_mut_ptr().cast::<std::ffi::c_void>();
    let rc = match mode {
        "ATTRIBUTES" => {
            if stride == 0 || stride % 4 != 0 || stride > 256 {
                bail!("ATTRIBUTES need a byteStride that is a multiple of 4 up to 256, not {stride}");
            }
            // SAFETY: `dst` holds count * stride bytes; the decoder reads `src` within its length.
            unsafe { ::meshopt::ffi::meshopt_decodeVertexBuffer(dst, count, stride, src.as_ptr(), src.len()) }
        }
        "TRIANGLES" | "INDICES" => {
            if stride != 2 && stride != 4 {
                bail!("{mode} need a byteStride of 2 or 4, not {stride}");
            }
            if mode == "TRIANGLES" && count % 3 != 0 {
                bail!("TRIANGLES need a count that is a multiple of 3, not {count}");
            }
            // SAFETY: as above (count indices of `stride` bytes).
            unsafe {
                if mode == "TRIANGLES" {
                    ::meshopt::ffi::meshopt_decodeIndexBuffer(dst, count, stride, src.as_ptr(), src.len())
                } else {
                    ::meshopt::ffi::meshopt_decodeIndexSequence(dst, count, stride, src.as_ptr(), src.len())
                }
            }
        }
        m => bail!("mode {m:?} is not one of ATTRIBUTES, TRIANGLES, INDICES"),
    };
    if rc != 0 {
        bail!("the compressed bytes do not decode (meshoptimizer error {rc})");
    }
    apply_filter(filter, mode, &mut words, count, stride)?;
    let bytes: &[u8] = bytemuck::cast_slice(&words);
    let target = &mut buffers[view.buffer().index()];
    let end = view.offset().checked_add(size).filter(|&e| e <= target.len());
    let end = end.ok_or_else(|| anyhow!("the decoded bytes do not fit buffer {}", view.buffer().index()))?;
    target[view.offset()..end].copy_from_slice(&bytes[..size]);
    Ok(())
}

/// Applies the extension's `filter` to decoded ATTRIBUTES, in place.
fn apply_filter(filter: &str, mode: &str, words: &mut [u32], count: usize, stride: usize) -> Result<()> {
    if filter != "NONE" && mode != "ATTRIBUTES" {
        bail!("filter {filter} applies to ATTRIBUTES only, not {mode}");
    }
    let ok = match filter {
        "NONE" => return Ok(()),
        "OCTAHEDRAL" => stride == 4 || stride == 8,
        "QUATERNION" => stride == 8,
        "EXPONENTIAL" => stride.is_multiple_of(4),
        f => bail!("filter {f:?} is not one of NONE, OCTAHEDRAL, QUATERNION, EXPONENTIAL"),
    };
    if !ok {
        bail!("filter {filter} does not take a byteStride of {stride}");
    }
    let buf = words.as_mut_ptr().cast::<std::ffi::c_void>();
    // SAFETY: `buf` holds count * stride bytes, 4-byte aligned; the strides were checked
    // against what each filter reads.
    unsafe {
        match filter {
            "OCTAHEDRAL" => ::meshopt::ffi::meshopt_decodeFilterOct(buf, count, stride),
            "QUATERNION" => ::meshopt::ffi::meshopt_decodeFilterQuat(buf, count, stride),
            _ => ::meshopt::ffi::meshopt_decodeFilterExp(buf, count, stride),
        }
    }
    Ok(())
}
