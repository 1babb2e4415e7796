//! Accessor reads with bounds checks (rather than through the `gltf` crate's reader, which
//! trusts the declared counts, offsets and strides).
//!
//! Every read goes through [`read_components`]: the accessor's elements from its buffer
//! view (or zeros when it has none), decoded to `f64` (exact for every component type,
//! including `UNSIGNED_INT` indices), normalized integers mapped to floats, then the
//! `sparse` substitution (glTF 2.0 section 3.6.2.3, "Sparse Accessors"). The typed readers
//! below first check that the accessor has one of the formats the attribute allows.

use anyhow::{anyhow, bail, Result};
use glam::{DMat4, Vec2, Vec3, Vec4};
use gltf::accessor::{DataType, Dimensions};

/// A component type with its `normalized` flag: one format an attribute may be stored in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Format(DataType, bool);

pub(super) const FLOAT: Format = Format(DataType::F32, false);
pub(super) const BYTE: Format = Format(DataType::I8, false);
pub(super) const BYTE_N: Format = Format(DataType::I8, true);
pub(super) const UBYTE: Format = Format(DataType::U8, false);
pub(super) const UBYTE_N: Format = Format(DataType::U8, true);
pub(super) const SHORT: Format = Format(DataType::I16, false);
pub(super) const SHORT_N: Format = Format(DataType::I16, true);
pub(super) const USHORT: Format = Format(DataType::U16, false);
pub(super) const USHORT_N: Format = Format(DataType::U16, true);

/// The formats of each attribute the importer reads, in the core specification (glTF 2.0
/// section 3.7.2.1, the attribute table; section 3.7.2.2 for morph targets) and with
/// `KHR_mesh_quantization` (its extension specification's tables), which adds integer
/// formats.
pub(super) struct Formats {
    pub core: &'static [Format],
    pub quantized: &'static [Format],
}

pub(super) const POSITION_FORMATS: Formats =
    Formats { core: &[FLOAT], quantized: &[FLOAT, BYTE, BYTE_N, UBYTE, UBYTE_N, SHORT, SHORT_N, USHORT, USHORT_N] };
pub(super) const NORMAL_FORMATS: Formats = Formats { core: &[FLOAT], quantized: &[FLOAT, BYTE_N, SHORT_N] };
/// Morph-target POSITION displacements (signed: a displacement may be negative).
pub(super) const POSITION_TARGET_FORMATS: Formats =
    Formats { core: &[FLOAT], quantized: &[FLOAT, BYTE, BYTE_N, SHORT, SHORT_N] };
pub(super) const NORMAL_TARGET_FORMATS: Formats = NORMAL_FORMATS;
/// JOINTS_n (glTF 2.0 section 3.7.3.3); KHR_mesh_quantization adds nothing.
pub(super) const JOINTS_FORMATS: Formats = Formats { core: &[UBYTE, USHORT], quantized: &[UBYTE, USHORT] };
/// WEIGHTS_n (glTF 2.0 section 3.7.3.3); KHR_mesh_quantization adds nothing.
pub(super) const WEIGHTS_FORMATS: Formats =
    Formats { core: &[FLOAT, UBYTE_N, USHORT_N], quantized: &[FLOAT, UBYTE_N, USHORT_N] };

/// TEXCOORD_n (glTF 2.0 section 3.7.2.1: FLOAT, UNSIGNED_BYTE/SHORT normalized);
/// KHR_mesh_quantization adds BYTE, UNSIGNED_BYTE, SHORT and UNSIGNED_SHORT, normalized or
/// not (non-normalized texture coordinates are then usually scaled back by a
/// `KHR_texture_transform`).
pub(super) const TEXCOORD_FORMATS: Formats = Formats {
    core: &[FLOAT, UBYTE_N, USHORT_N],
    quantized: &[FLOAT, BYTE, BYTE_N, UBYTE, UBYTE_N, SHORT, SHORT_N, USHORT, USHORT_N],
};
/// Morph-target TEXCOORD_n displacements (glTF 2.0 section 3.7.2.2: FLOAT and the signed
/// and unsigned normalized BYTE and SHORT); KHR_mesh_quantization adds BYTE and SHORT.
pub(super) const TEXCOORD_TARGET_FORMATS: Formats = Formats {
    core: &[FLOAT, BYTE_N, SHORT_N, UBYTE_N, USHORT_N],
    quantized: &[FLOAT, BYTE, BYTE_N, SHORT, SHORT_N, UBYTE_N, USHORT_N],
};
/// Morph-target COLOR_n displacements (glTF 2.0 section 3.7.2.2).
pub(super) const COLOR_TARGET_FORMATS: Formats = Formats {
    core: &[FLOAT, BYTE_N, SHORT_N, UBYTE_N, USHORT_N],
    quantized: &[FLOAT, BYTE_N, SHORT_N, UBYTE_N, USHORT_N],
};
/// Morph-target TANGENT displacements (glTF 2.0 section 3.7.2.2: FLOAT VEC3);
/// KHR_mesh_quantization adds BYTE and SHORT normalized.
pub(super) const TANGENT_TARGET_FORMATS: Formats = NORMAL_FORMATS;
/// TANGENT (glTF 2.0 section 3.7.2.1: FLOAT VEC4); KHR_mesh_quantization adds BYTE and
/// SHORT normalized.
pub(super) const TANGENT_FORMATS: Formats = Formats { core: &[FLOAT], quantized: &[FLOAT, BYTE_N, SHORT_N] };
/// COLOR_n (glTF 2.0 section 3.7.2.1: VEC3 or VEC4 of FLOAT, UNSIGNED_BYTE/SHORT
/// normalized); KHR_mesh_quantization adds nothing.
pub(super) const COLOR_FORMATS: Formats =
    Formats { core: &[FLOAT, UBYTE_N, USHORT_N], quantized: &[FLOAT, UBYTE_N, USHORT_N] };

/// Zero-initialised accessors (no `bufferView`) are not bounded by any buffer: ones with
/// more components (elements × components per element) are refused rather than allocated
/// (a 2^31-element count would exhaust memory). 2^25 is about 11 million VEC3 elements.
const MAX_COMPONENTS_WITHOUT_VIEW: usize = 1 << 25;

fn type_name(t: DataType) -> &'static str {
    match t {
        DataType::I8 => "BYTE",
        DataType::U8 => "UNSIGNED_BYTE",
        DataType::I16 => "SHORT",
        DataType::U16 => "UNSIGNED_SHORT",
        DataType::U32 => "UNSIGNED_INT",
        DataType::F32 => "FLOAT",
    }
}

fn format_name(f: Format) -> String {
    if f.1 {
        format!("{} normalized", type_name(f.0))
    } else {
        type_name(f.0).to_string()
    }
}

fn dims_name(d: Dimensions) -> &'static str {
    match d {
        Dimensions::Scalar => "SCALAR",
        Dimensions::Vec2 => "VEC2",
        Dimensions::Vec3 => "VEC3",
        Dimensions::Vec4 => "VEC4",
        Dimensions::Mat2 => "MAT2",
        Dimensions::Mat3 => "MAT3",
        Dimensions::Mat4 => "MAT4",
    }
}

fn component_count(d: Dimensions) -> usize {
    match d {
        Dimensions::Scalar => 1,
        Dimensions::Vec2 => 2,
        Dimensions::Vec3 => 3,
        Dimensions::Vec4 | Dimensions::Mat2 => 4,
        Dimensions::Mat3 => 9,
        Dimensions::Mat4 => 16,
    }
}

/// Fails unless `acc` is `dims` in one of the formats `formats` allows (`quantized`:
/// `KHR_mesh_quantization` is used); `what` names the attribute.
fn check_format(acc: &gltf::Accessor, what: &str, dims: Dimensions, formats: &Formats, quantized: bool) -> Result<()> {
    check_formats(acc, what, &[dims], formats, quantized)
}

/// [`check_format`] for an attribute that may have one of several element types `dims`.
fn check_formats(
    acc: &gltf::Accessor,
    what: &str,
    dims: &[Dimensions],
    formats: &Formats,
    quantized: bool,
) -> Result<()> {
    let allowed = if quantized { formats.quantized } else { formats.core };
    let have = Format(acc.data_type(), acc.normalized());
    if dims.contains(&acc.dimensions()) && allowed.contains(&have) {
        return Ok(());
    }
    let names: Vec<String> = allowed.iter().map(|f| format_name(*f)).collect();
    let hint = if !quantized && formats.quantized.contains(&have) {
        " (integer formats need the KHR_mesh_quantization extension)"
    } else {
        ""
    };
    bail!(
        "accessor {} ({what}) must be {} {}, is {} {}{hint}",
        acc.index(),
        names.join(" or "),
        dims.iter().map(|d| dims_name(*d)).collect::<Vec<_>>().join("/"),
        format_name(have),
        dims_name(acc.dimensions())
    )
}

/// The bytes of buffer view `view`, checked to lie inside its buffer.
pub(super) fn view_slice<'b>(buffers: &'b [Vec<u8>], view: &gltf::buffer::View) -> Result<&'b [u8]> {
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
    Ok(&data[view.offset()..view_end])
}

/// The bytes of `acc` from its first element to the end of its buffer view, and the
/// stride between elements of `elem_size` bytes; `None` when the accessor has no buffer
/// view. Fails unless all `count` elements lie inside the view and the view inside its
/// buffer.
fn view_bytes<'b>(buffers: &'b [Vec<u8>], acc: &gltf::Accessor, elem_size: usize) -> Result<Option<(&'b [u8], usize)>> {
    let ai = acc.index();
    let Some(view) = acc.view() else {
        return Ok(None);
    };
    let vi = view.index();
    let view_data = view_slice(buffers, &view)?;
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

/// The component of type `t` at `data[o..]` (in range: the caller checked), as `f64`;
/// with `normalized`, mapped to [-1, 1] or [0, 1] by glTF 2.0's int-to-float equations
/// for normalized integers (the table in the specification's Animations section, which
/// `KHR_mesh_quantization` also refers to): BYTE `max(c / 127, -1)`, UNSIGNED_BYTE
/// `c / 255`, SHORT `max(c / 32767, -1)`, UNSIGNED_SHORT `c / 65535`.
fn component(data: &[u8], o: usize, t: DataType, normalized: bool) -> f64 {
    let c = match t {
        DataType::I8 => data[o] as i8 as f64,
        DataType::U8 => data[o] as f64,
        DataType::I16 => i16::from_le_bytes([data[o], data[o + 1]]) as f64,
        DataType::U16 => u16::from_le_bytes([data[o], data[o + 1]]) as f64,
        DataType::U32 => u32::from_le_bytes([data[o], data[o + 1], data[o + 2], data[o + 3]]) as f64,
        DataType::F32 => f32::from_le_bytes([data[o], data[o + 1], data[o + 2], data[o + 3]]) as f64,
    };
    if !normalized {
        return c;
    }
    match t {
        DataType::I8 => (c / 127.0).max(-1.0),
        DataType::U8 => c / 255.0,
        DataType::I16 => (c / 32767.0).max(-1.0),
        DataType::U16 => c / 65535.0,
        // glTF forbids `normalized` on FLOAT and UNSIGNED_INT; [`check_format`] never
        // allows it, so this value is never used.
        _ => c,
    }
}

/// The `count` bytes at `offset` of buffer view `view` (sparse indices or values, which
/// are tightly packed: glTF 2.0 section 3.6.2.3), checked to lie inside the view.
fn sparse_slice<'b>(
    buffers: &'b [Vec<u8>],
    view: &gltf::buffer::View,
    offset: usize,
    len: Option<usize>,
    what: &str,
) -> Result<&'b [u8]> {
    let data = view_slice(buffers, view)?;
    match len.and_then(|l| offset.checked_add(l)) {
        Some(end) if end <= data.len() => Ok(&data[offset..end]),
        _ => bail!(
            "{what} ({} bytes at offset {offset}) exceeds buffer view {} ({} bytes)",
            len.map_or("too many".to_string(), |l| l.to_string()),
            view.index(),
            data.len()
        ),
    }
}

/// The components of `acc`, `n` per element for its `count` elements, element by element,
/// decoded by [`component`]. An accessor without a `bufferView` starts as zeros (glTF 2.0
/// section 3.6.2.3); then its `sparse` elements, if any, replace the elements their
/// indices name. Fails, naming the accessor, when an element lies outside its buffer view,
/// a sparse index is out of range or the indices do not strictly increase (both required
/// by section 3.6.2.3).
fn read_components(buffers: &[Vec<u8>], acc: &gltf::Accessor) -> Result<Vec<f64>> {
    let ai = acc.index();
    let t = acc.data_type();
    let norm = acc.normalized();
    let n = component_count(acc.dimensions());
    let csize = t.size();
    // Element size without padding: the importer reads no matrices of 1- or 2-byte
    // components (whose columns glTF pads to 4 bytes).
    let elem = n * csize;
    let count = acc.count();
    let mut out = match view_bytes(buffers, acc, elem)? {
        Some((data, stride)) => {
            let mut out = Vec::with_capacity(count * n);
            for i in 0..count {
                let o = i * stride;
                out.extend((0..n).map(|k| component(data, o + k * csize, t, norm)));
            }
            out
        }
        None => {
            if acc.sparse().is_none() {
                bail!("accessor {ai} has neither a bufferView nor sparse values");
            }
            if count.checked_mul(n).is_none_or(|c| c > MAX_COMPONENTS_WITHOUT_VIEW) {
                bail!(
                    "accessor {ai} has no bufferView and {count} elements of {n} components (zero-initialised accessors of more than {MAX_COMPONENTS_WITHOUT_VIEW} components are refused)"
                );
            }
            vec![0.0; count * n]
        }
    };
    if let Some(sparse) = acc.sparse() {
        let k = sparse.count();
        if k > count {
            bail!("accessor {ai}: sparse.count {k} exceeds the accessor's count {count}");
        }
        let idx = sparse.indices();
        let isize = idx.index_type().size();
        let idx_bytes = sparse_slice(
            buffers,
            &idx.view(),
            idx.offset(),
            k.checked_mul(isize),
            &format!("accessor {ai} sparse.indices ({k} indices of {isize} bytes)"),
        )?;
        let values = sparse.values();
        let val_bytes = sparse_slice(
            buffers,
            &values.view(),
            values.offset(),
            k.checked_mul(elem),
            &format!("accessor {ai} sparse.values ({k} elements of {elem} bytes)"),
        )?;
        let it = match isize {
            1 => DataType::U8,
            2 => DataType::U16,
            _ => DataType::U32,
        };
        let mut previous: Option<usize> = None;
        for j in 0..k {
            let i = component(idx_bytes, j * isize, it, false) as usize;
            if i >= count {
                bail!("accessor {ai}: sparse index {j} = {i} is out of range (the accessor has {count} elements)");
            }
            if let Some(p) = previous.filter(|&p| i <= p) {
                bail!("accessor {ai}: sparse indices must strictly increase, but index {j} = {i} follows {p}");
            }
            previous = Some(i);
            for c in 0..n {
                out[i * n + c] = component(val_bytes, j * elem + c * csize, t, norm);
            }
        }
    }
    Ok(out)
}

/// The elements of a VEC3 accessor (POSITION, NORMAL, their morph-target displacements)
/// in one of `formats` (`quantized`: `KHR_mesh_quantization` is used), decoded to floats;
/// `what` names the attribute in errors.
pub(super) fn read_vec3(
    buffers: &[Vec<u8>],
    acc: &gltf::Accessor,
    what: &str,
    formats: &Formats,
    quantized: bool,
) -> Result<Vec<Vec3>> {
    check_format(acc, what, Dimensions::Vec3, formats, quantized)?;
    let c = read_components(buffers, acc)?;
    Ok(c.chunks_exact(3).map(|v| Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32)).collect())
}

/// The elements of a VEC2 accessor (TEXCOORD_n) in one of `formats` (`quantized`:
/// `KHR_mesh_quantization` is used), decoded to floats (normalized integers by glTF's
/// equations, plain integers as they are).
pub(super) fn read_vec2(
    buffers: &[Vec<u8>],
    acc: &gltf::Accessor,
    what: &str,
    formats: &Formats,
    quantized: bool,
) -> Result<Vec<Vec2>> {
    check_format(acc, what, Dimensions::Vec2, formats, quantized)?;
    let c = read_components(buffers, acc)?;
    Ok(c.chunks_exact(2).map(|v| Vec2::new(v[0] as f32, v[1] as f32)).collect())
}

/// The elements of a TANGENT accessor (VEC4: xyz the tangent, w the bitangent's sign) in
/// one of `formats` (`quantized`: `KHR_mesh_quantization` is used), decoded to floats.
pub(super) fn read_tangents(
    buffers: &[Vec<u8>],
    acc: &gltf::Accessor,
    formats: &Formats,
    quantized: bool,
) -> Result<Vec<Vec4>> {
    check_format(acc, "TANGENT", Dimensions::Vec4, formats, quantized)?;
    let c = read_components(buffers, acc)?;
    Ok(c.chunks_exact(4).map(|v| Vec4::new(v[0] as f32, v[1] as f32, v[2] as f32, v[3] as f32)).collect())
}

/// The elements of a rotation accessor (VEC4 quaternions x, y, z, w in one of `formats`),
/// decoded to floats (normalized integers by glTF's equations).
pub(super) fn read_rotations(
    buffers: &[Vec<u8>],
    acc: &gltf::Accessor,
    formats: &Formats,
    quantized: bool,
) -> Result<Vec<[f32; 4]>> {
    check_format(acc, "ROTATION", Dimensions::Vec4, formats, quantized)?;
    let c = read_components(buffers, acc)?;
    Ok(c.chunks_exact(4).map(|v| [v[0] as f32, v[1] as f32, v[2] as f32, v[3] as f32]).collect())
}

/// The elements of a colour accessor (COLOR_n: VEC3 or VEC4 in one of `formats`) as RGBA,
/// alpha 1 for a VEC3 accessor.
pub(super) fn read_color(
    buffers: &[Vec<u8>],
    acc: &gltf::Accessor,
    what: &str,
    formats: &Formats,
) -> Result<Vec<Vec4>> {
    check_formats(acc, what, &[Dimensions::Vec3, Dimensions::Vec4], formats, false)?;
    let n = component_count(acc.dimensions());
    let c = read_components(buffers, acc)?;
    Ok(c.chunks_exact(n)
        .map(|v| Vec4::new(v[0] as f32, v[1] as f32, v[2] as f32, if n == 4 { v[3] as f32 } else { 1.0 }))
        .collect())
}

/// The elements of a VEC4 accessor (JOINTS_n, WEIGHTS_n) in one of `formats`, decoded:
/// integers exactly, normalized integers as floats in [0, 1].
pub(super) fn read_vec4(
    buffers: &[Vec<u8>],
    acc: &gltf::Accessor,
    what: &str,
    formats: &Formats,
) -> Result<Vec<[f64; 4]>> {
    check_format(acc, what, Dimensions::Vec4, formats, false)?;
    let c = read_components(buffers, acc)?;
    Ok(c.chunks_exact(4).map(|v| [v[0], v[1], v[2], v[3]]).collect())
}

/// The elements of a FLOAT MAT4 accessor (a skin's inverseBindMatrices; column-major, as
/// glTF stores matrices).
pub(super) fn read_mat4(buffers: &[Vec<u8>], acc: &gltf::Accessor, what: &str) -> Result<Vec<DMat4>> {
    check_format(acc, what, Dimensions::Mat4, &Formats { core: &[FLOAT], quantized: &[FLOAT] }, false)?;
    let c = read_components(buffers, acc)?;
    Ok(c.chunks_exact(16).map(DMat4::from_cols_slice).collect())
}

/// The elements of an index accessor (SCALAR of UNSIGNED_BYTE, UNSIGNED_SHORT or
/// UNSIGNED_INT, sparse or not) widened to `u32`. The indices are not checked against a
/// vertex count.
pub(super) fn read_indices(buffers: &[Vec<u8>], acc: &gltf::Accessor) -> Result<Vec<u32>> {
    let ai = acc.index();
    if acc.dimensions() != Dimensions::Scalar {
        bail!("index accessor {ai} must be SCALAR, is {:?}", acc.dimensions());
    }
    match acc.data_type() {
        DataType::U8 | DataType::U16 | DataType::U32 => {}
        t => bail!("index accessor {ai} must be UNSIGNED_BYTE/SHORT/INT, is {t:?}"),
    }
    if acc.normalized() {
        bail!("index accessor {ai} must not be normalized");
    }
    // Every value is an exact integer below 2^32 (decoded from at most 4 bytes).
    Ok(read_components(buffers, acc)?.into_iter().map(|v| v as u32).collect())
}
