//! Accessor reads with bounds checks (rather than through the `gltf` crate's reader, which
//! trusts the declared counts, offsets and strides).

use anyhow::{anyhow, bail, Result};
use glam::Vec3;
use gltf::accessor::{DataType, Dimensions};

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

/// The elements of a FLOAT VEC3 accessor (POSITION, NORMAL); `what` names the attribute
/// in errors.
pub(super) fn read_vec3(buffers: &[Vec<u8>], acc: &gltf::Accessor, what: &str) -> Result<Vec<Vec3>> {
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

/// The elements of an index accessor (SCALAR of UNSIGNED_BYTE, UNSIGNED_SHORT or
/// UNSIGNED_INT) widened to `u32`. The indices are not checked against a vertex count.
pub(super) fn read_indices(buffers: &[Vec<u8>], acc: &gltf::Accessor) -> Result<Vec<u32>> {
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
