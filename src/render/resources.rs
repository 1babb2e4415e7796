//! What a render will allocate, checked against the device before anything is allocated:
//! each bound buffer against `maxStorageBufferRange`, the total against the largest
//! device-local memory heap (system RAM on lavapipe). The figures mirror the allocations
//! in scene_gpu.rs, film.rs, bidir.rs and hash_grid.rs (upper bounds where the size is
//! only known after the BVH build).

use anyhow::{bail, Result};

use super::gpu_types::{GpuLight, GpuMaterial, GpuParams, GpuSphere, GpuTriangle};
use super::{film, Algorithm, RenderSettings};
use crate::bvh::layout::{GpuNode, GpuPrim};
use crate::gpu::Gpu;
use crate::scene::Scene;

/// One buffer a render allocates.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BufferNeed {
    pub name: &'static str,
    pub bytes: u64,
}

/// Bytes of one light-vertex half (`light_vertices_a` or `_b`) per vertex: two vec4.
const LV_HALF_BYTES: u64 = 32;
/// Elements per block of the hash grid's scan (hash_grid::SCAN_BLOCK).
const SCAN_BLOCK: u64 = super::hash_grid::SCAN_BLOCK as u64;

fn size<T>(n: u64) -> u64 {
    n.saturating_mul(std::mem::size_of::<T>() as u64)
}

/// Every device buffer a render of `scene` with `s` allocates (sizes as requested; the
/// allocator may round each up a little).
pub fn estimate(scene: &Scene, s: &RenderSettings) -> Vec<BufferNeed> {
    let px = s.frame.width as u64 * s.frame.height as u64;
    let tris = scene.triangles.len() as u64;
    let prims = tris + scene.spheres.len() as u64;
    let normals = scene.triangles.iter().filter(|t| t.n.is_some()).count() as u64 * 3;
    let mut v = vec![
        BufferNeed { name: "params", bytes: size::<GpuParams>(1) },
        // A BVH2 over n primitives has at most n internal nodes (the root is always one).
        BufferNeed { name: "bvh_nodes", bytes: size::<GpuNode>(prims.max(1)) },
        BufferNeed { name: "bvh_prims", bytes: size::<GpuPrim>(prims) },
        BufferNeed { name: "triangles", bytes: size::<GpuTriangle>(tris) },
        BufferNeed { name: "spheres", bytes: size::<GpuSphere>(scene.spheres.len() as u64) },
        BufferNeed { name: "materials", bytes: size::<GpuMaterial>(scene.materials.len() as u64) },
        BufferNeed { name: "lights", bytes: size::<GpuLight>(scene.lights.len() as u64) },
        BufferNeed { name: "shading_normals", bytes: size::<[f32; 4]>(normals) },
        BufferNeed { name: "film", bytes: px.saturating_mul(16 * film::FILM_VEC4_PER_PIXEL as u64) },
        BufferNeed { name: "film_stats", bytes: 16 },
    ];
    let (store, merge) = match s.algorithm {
        Algorithm::El | Algorithm::Pt => return v,
        Algorithm::Lt => (false, false),
        Algorithm::Bpt => (true, false),
        Algorithm::Ppm | Algorithm::Bpm | Algorithm::Vcm => (true, true),
    };
    // bidir.rs: max_path_length - 1 slots per light subpath, one subpath per pixel.
    let slots = s.frame.max_path_length.saturating_sub(1).max(1) as u64;
    let lv = if store { px.saturating_mul(slots) } else { 1 };
    v.extend([
        BufferNeed { name: "splat", bytes: px.saturating_mul(24) },
        BufferNeed { name: "light_vertices_a", bytes: lv.saturating_mul(LV_HALF_BYTES) },
        BufferNeed { name: "light_vertices_b", bytes: lv.saturating_mul(LV_HALF_BYTES) },
        BufferNeed { name: "light_vertex_counts", bytes: if store { px.saturating_mul(4) } else { 4 } },
    ]);
    // hash_grid.rs ExclusiveScan of n elements: its own scratch of the block totals.
    let scan_scratch = |n: u64| {
        let mut scratch = 0u64;
        let mut n = n;
        loop {
            n = n.div_ceil(SCAN_BLOCK);
            scratch += n;
            if n <= 1 {
                break;
            }
        }
        scratch
    };
    if s.connect != super::bidir::Connect::Path {
        // bidir.rs: the light-vertex cache's prefix sum of the per-path counts and the
        // dense list of the stored vertices' slots.
        v.extend([
            BufferNeed { name: "light_vertex_prefix", bytes: (px + 1).saturating_mul(4) },
            BufferNeed { name: "light_vertex_dense", bytes: lv.saturating_mul(4) },
            BufferNeed { name: "hash_grid_scan_scratch", bytes: scan_scratch(px + 1) * 4 },
        ]);
    }
    if merge {
        // bidir.rs: grid_buckets(light subpaths) buckets.
        let buckets = super::bidir::grid_buckets(px) as u64;
        v.extend([
            BufferNeed { name: "grid_start", bytes: (buckets + 1).saturating_mul(4) },
            BufferNeed { name: "grid_points", bytes: lv.saturating_mul(16) },
            BufferNeed { name: "grid_keys", bytes: lv.saturating_mul(8) },
            BufferNeed { name: "hash_grid_scan_scratch", bytes: scan_scratch(buckets + 1) * 4 },
        ]);
    }
    v
}

/// `bytes` in MiB for messages.
pub fn mib(bytes: u64) -> String {
    let m = bytes as f64 / (1u64 << 20) as f64;
    if m < 10.0 {
        format!("{m:.2} MiB")
    } else {
        format!("{m:.0} MiB")
    }
}

/// Checks `needs` against a per-buffer binding limit `max_binding` and a memory heap of
/// `heap` bytes; `what` describes the render in the message.
pub fn check_needs(needs: &[BufferNeed], max_binding: u64, heap: u64, what: &str) -> Result<()> {
    if let Some(b) = needs.iter().rev().filter(|b| b.bytes > max_binding).max_by_key(|b| b.bytes) {
        bail!(
            "{what} needs {} for buffer {}, but the device binds at most {} per buffer (maxStorageBufferRange); \
             lower the resolution{}",
            mib(b.bytes),
            b.name,
            mib(max_binding),
            if b.name.contains("vert") || b.name.starts_with("grid") { " or --max-path-length" } else { "" }
        );
    }
    let total = needs.iter().fold(0u64, |a, b| a.saturating_add(b.bytes));
    if total > heap {
        let mut big: Vec<&BufferNeed> = needs.iter().collect();
        big.sort_by_key(|b| std::cmp::Reverse(b.bytes));
        let list: Vec<String> = big.iter().take(3).map(|b| format!("{} {}", b.name, mib(b.bytes))).collect();
        bail!(
            "{what} needs {} of device memory ({}, ...), but the device's largest memory heap has {}",
            mib(total),
            list.join(", "),
            mib(heap)
        );
    }
    Ok(())
}

/// Fails, before anything is allocated, when a render of `scene` with `s` would not fit
/// the device: image size, primitive count, per-buffer binding range, total memory.
pub fn check(gpu: &Gpu, scene: &Scene, s: &RenderSettings) -> Result<()> {
    let (w, h) = (s.frame.width, s.frame.height);
    if w == 0 || h == 0 {
        bail!("image size {w}x{h}: width and height must be at least 1");
    }
    let what = format!("a {w}x{h} {} render", s.algorithm.name());
    if w as u64 * h as u64 > u32::MAX as u64 {
        bail!("{what} has {} pixels, more than the 2^32 - 1 the kernels can index", w as u64 * h as u64);
    }
    let prims = scene.triangles.len() + scene.spheres.len();
    if prims > crate::bvh::layout::MAX_PRIMS {
        bail!("scene {:?} has {prims} primitives; the BVH holds at most {}", scene.name, crate::bvh::layout::MAX_PRIMS);
    }
    let needs = estimate(scene, s);
    check_needs(&needs, gpu.limits.max_storage_buffer_range as u64, gpu.device_local_heap_bytes(), &what)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn need(name: &'static str, bytes: u64) -> BufferNeed {
        BufferNeed { name, bytes }
    }

    #[test]
    fn binding_and_heap_limits() {
        let v = [need("film", 100), need("splat", 50)];
        assert!(check_needs(&v, 100, 150, "x").is_ok());
        let e = check_needs(&v, 99, 1000, "x").unwrap_err().to_string();
        assert!(e.contains("buffer film") && e.contains("maxStorageBufferRange"), "{e}");
        let e = check_needs(&v, 100, 149, "x").unwrap_err().to_string();
        assert!(e.contains("heap"), "{e}");
        assert!(!e.contains('\n'));
    }
}
