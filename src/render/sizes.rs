//! Buffer sizes by name, and their check against a device's limits before anything is
//! allocated: the unit of the plan of sizes (src/render/plan.rs).

use std::sync::Arc;

use anyhow::{bail, Result};

use crate::gpu::{Buffer, Gpu};

/// How the kernels reach a buffer, which sets its size limit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Access {
    /// Bound as a storage buffer: at most `maxStorageBufferRange`.
    Storage,
    /// Bound only as a uniform texel buffer of 16-byte texels (`--reads texel`): at most
    /// `maxTexelBufferElements` texels.
    Texel,
    /// As [`Access::Texel`], of 4-byte (`uint`) texels.
    TexelU32,
    /// Bound as a storage buffer by one kernel and as a uniform texel buffer of 16-byte
    /// texels by another: both limits apply.
    StorageAndTexel,
    /// As [`Access::StorageAndTexel`], of 4-byte (`uint`) texels.
    StorageAndTexelU32,
    /// Reached by device address (src/render/addresses.rs): limited by the allocation size
    /// and by [`MAX_ADDRESSED_BYTES`].
    Address,
    /// Reached by device address in chunks of [`SizeLimits::scene_chunk`] bytes, each its
    /// own allocation (the scene's BVH and geometry past one binding:
    /// src/render/scene_gpu.rs): limited by [`MAX_CHUNKED_BYTES`] and the memory heap.
    Chunked,
}

/// One buffer of the plan.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BufferSize {
    pub name: &'static str,
    pub bytes: u64,
    pub access: Access,
}

impl BufferSize {
    /// A buffer bound as a storage buffer.
    pub const fn new(name: &'static str, bytes: u64) -> BufferSize {
        BufferSize { name, bytes, access: Access::Storage }
    }

    /// This buffer reached as `access`.
    pub const fn reached(self, access: Access) -> BufferSize {
        BufferSize { access, ..self }
    }

    /// The buffer, zero-filled.
    pub fn zeroed(&self, gpu: &Arc<Gpu>) -> Result<Buffer> {
        gpu.buffer_zeroed_bytes(self.name, self.bytes)
    }
}

impl Access {
    /// The size in bytes of one texel, when a kernel binds the buffer as a texel buffer.
    pub fn texel_bytes(self) -> Option<u64> {
        match self {
            Access::Texel | Access::StorageAndTexel => Some(16),
            Access::TexelU32 | Access::StorageAndTexelU32 => Some(4),
            _ => None,
        }
    }

    /// This access with the texel binding of `texel_bytes` added (or removed with `None`):
    /// how the store's buffers are reached with and without texel reads.
    pub fn with_texels(self, texel_bytes: Option<u64>) -> Access {
        let storage = matches!(self, Access::Storage | Access::StorageAndTexel | Access::StorageAndTexelU32);
        match (storage, texel_bytes) {
            (_, None) if storage => Access::Storage,
            (_, None) => self,
            (true, Some(16)) => Access::StorageAndTexel,
            (true, Some(_)) => Access::StorageAndTexelU32,
            (false, Some(16)) => Access::Texel,
            (false, Some(_)) => Access::TexelU32,
        }
    }
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

/// `needed` and `max` for a message: in MiB, or in bytes where MiB would print them alike
/// (262148 bytes against 262144 both print as 0.25 MiB).
pub fn sizes_apart(needed: u64, max: u64) -> (String, String) {
    if mib(needed) == mib(max) {
        (format!("{needed} bytes"), format!("{max} bytes"))
    } else {
        (mib(needed), mib(max))
    }
}

/// What to change when buffer `name` is larger than one binding.
fn remedy(name: &str) -> &'static str {
    match name {
        n if n.starts_with("env_") => "use a smaller environment map (20 bytes per texel)",
        n if n.starts_with("texture_") => "use smaller textures (4 bytes per texel, all images in one buffer)",
        "bvh_nodes" | "bvh_prims" | "triangles" | "spheres" | "materials" | "lights" | "shading_normals"
        | "vertex_attributes" => {
            "the scene is too large for this device (fewer triangles, or a device with a larger maxStorageBufferRange)"
        }
        n if n.contains("vert") || n.starts_with("grid") => "lower --light-paths, the resolution or --max-path-length",
        _ => "lower the resolution",
    }
}

/// The largest buffer reached by device address: the kernels index its elements (4 bytes
/// at the least) with 32-bit integers, which a compiler may sign-extend when it forms
/// the address, so at most 2^31 of them.
pub const MAX_ADDRESSED_BYTES: u64 = 4 << 31;

/// The largest array read in chunks: the kernels index its 16-byte elements with 32-bit
/// integers.
pub const MAX_CHUNKED_BYTES: u64 = 16 << 32;

/// The device's limits on buffer sizes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SizeLimits {
    /// `maxStorageBufferRange`.
    pub storage_binding: u64,
    /// `maxTexelBufferElements`.
    pub texel_elements: u64,
    /// `maxMemoryAllocationSize`: every buffer lies in one allocation.
    pub allocation: u64,
    /// The largest device-local memory heap: all buffers together.
    pub heap: u64,
    /// The chunk of an array read in chunks ([`Access::Chunked`]): the largest power of two
    /// bytes one allocation holds (at most [`MAX_ADDRESSED_BYTES`]).
    pub scene_chunk: u64,
}

impl SizeLimits {
    pub fn of(gpu: &Gpu) -> SizeLimits {
        SizeLimits {
            storage_binding: gpu.limits.max_storage_buffer_range as u64,
            texel_elements: gpu.limits.max_texel_buffer_elements as u64,
            allocation: gpu.max_allocation_bytes,
            heap: gpu.device_local_heap_bytes(),
            scene_chunk: scene_chunk_bytes(gpu.max_allocation_bytes),
        }
    }

    /// The largest `b` may be, by how it is reached.
    pub fn max_bytes(&self, b: &BufferSize) -> u64 {
        self.for_buffer(b).0
    }

    /// The largest `b` may be, and the limit's name for messages.
    fn for_buffer(&self, b: &BufferSize) -> (u64, &'static str) {
        let binding = match b.access {
            Access::Storage => {
                Some((self.storage_binding, "the device binds at most {} per storage buffer (maxStorageBufferRange)"))
            }
            Access::Texel | Access::TexelU32 | Access::StorageAndTexel | Access::StorageAndTexelU32 => {
                let texel = b.access.texel_bytes().unwrap_or(16);
                let max = self.texel_elements.saturating_mul(texel);
                let storage_too = matches!(b.access, Access::StorageAndTexel | Access::StorageAndTexelU32);
                if storage_too && self.storage_binding < max {
                    Some((
                        self.storage_binding,
                        "the device binds at most {} per storage buffer (maxStorageBufferRange)",
                    ))
                } else {
                    Some((max, "the device binds at most {} per texel buffer (maxTexelBufferElements)"))
                }
            }
            Access::Address if MAX_ADDRESSED_BYTES < self.allocation => {
                Some((MAX_ADDRESSED_BYTES, "the kernels index at most {} of a buffer by address (2^31 elements)"))
            }
            Access::Address => None,
            Access::Chunked => {
                return (MAX_CHUNKED_BYTES, "the kernels index at most {} of a scene array (2^32 16-byte elements)")
            }
        };
        match binding {
            Some((max, text)) if max <= self.allocation => (max, text),
            _ => (self.allocation, "the device allocates at most {} per buffer (maxMemoryAllocationSize)"),
        }
    }
}

/// The chunk size of arrays read in chunks on a device that allocates at most
/// `allocation` bytes per buffer: the largest power of two that fits, at most
/// [`MAX_ADDRESSED_BYTES`] (and for tests at most `VKVCM_TEST_SCENE_CHUNK_BYTES`,
/// src/gpu/fault_injection.rs), at least 256.
pub fn scene_chunk_bytes(allocation: u64) -> u64 {
    let max = allocation.min(MAX_ADDRESSED_BYTES).min(crate::gpu::fault_injection::scene_chunk_cap());
    if max < 256 {
        return 256;
    }
    1 << (63 - max.leading_zeros())
}

/// Checks `sizes` against each buffer's limit (by how it is reached) and all of them
/// against the memory heap; `what` describes the render in the message.
pub fn check_sizes(sizes: &[BufferSize], limits: &SizeLimits, what: &str) -> Result<()> {
    let over = |b: &&BufferSize| b.bytes > limits.for_buffer(b).0;
    if let Some(b) = sizes.iter().rev().filter(over).max_by_key(|b| b.bytes) {
        let (max, text) = limits.for_buffer(b);
        let (needed, max) = sizes_apart(b.bytes, max);
        // Texel reads are what limits it: storage reads lift that limit (src/render/reads.rs).
        let storage_reads = if text.contains("maxTexelBufferElements") { "use --reads storage, or " } else { "" };
        bail!(
            "{what} needs {needed} for buffer {}, but {}; {storage_reads}{}",
            b.name,
            text.replace("{}", &max),
            remedy(b.name)
        );
    }
    let heap = limits.heap;
    let total = sizes.iter().fold(0u64, |a, b| a.saturating_add(b.bytes));
    if total > heap {
        let mut big: Vec<&BufferSize> = sizes.iter().collect();
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

#[cfg(test)]
mod tests {
    use super::*;

    fn limits(binding: u64, heap: u64) -> SizeLimits {
        SizeLimits {
            storage_binding: binding,
            texel_elements: binding / 4,
            allocation: 8 * binding,
            heap,
            scene_chunk: 256,
        }
    }

    #[test]
    fn binding_and_heap_limits() {
        let v = [BufferSize::new("film", 100), BufferSize::new("splat", 50)];
        assert!(check_sizes(&v, &limits(100, 150), "x").is_ok());
        let e = check_sizes(&v, &limits(99, 1000), "x").unwrap_err().to_string();
        assert!(e.contains("buffer film") && e.contains("maxStorageBufferRange"), "{e}");
        assert!(e.contains("lower the resolution"), "{e}");
        let env = [BufferSize::new("env_texels", 100)];
        let e = check_sizes(&env, &limits(99, 1000), "x").unwrap_err().to_string();
        assert!(e.contains("smaller environment map") && !e.contains("resolution"), "{e}");
        let bvh = [BufferSize::new("bvh_prims", 100)];
        let e = check_sizes(&bvh, &limits(99, 1000), "x").unwrap_err().to_string();
        assert!(e.contains("scene is too large") && !e.contains("resolution"), "{e}");
        let e = check_sizes(&v, &limits(100, 149), "x").unwrap_err().to_string();
        assert!(e.contains("heap"), "{e}");
        assert!(!e.contains('\n'));
    }

    #[test]
    fn each_buffer_has_the_limit_of_how_it_is_reached() {
        let l = limits(100, 10_000);
        let texel = [BufferSize::new("bvh_prims", 400).reached(Access::Texel)];
        assert!(check_sizes(&texel, &l, "x").is_ok());
        let e = check_sizes(&[texel[0].reached(Access::Storage)], &l, "x").unwrap_err().to_string();
        assert!(e.contains("maxStorageBufferRange"), "{e}");
        let e = check_sizes(&[BufferSize::new("bvh_prims", 401).reached(Access::Texel)], &l, "x").unwrap_err();
        assert!(e.to_string().contains("maxTexelBufferElements"), "{e}");
        // Texel limits name the way around them, and sizes that MiB would print alike are exact.
        assert!(e.to_string().contains("--reads storage") && e.to_string().contains("401 bytes"), "{e}");
        let both = BufferSize::new("grid_start", 100).reached(Access::StorageAndTexelU32);
        assert!(check_sizes(&[both], &l, "x").is_ok());
        // Bound both ways: the smaller of the two limits applies (here the storage one).
        let wide_texels = SizeLimits { texel_elements: 50, ..l };
        let e = check_sizes(&[BufferSize { bytes: 101, ..both }], &wide_texels, "x").unwrap_err().to_string();
        assert!(e.contains("maxStorageBufferRange") && e.contains("101 bytes") && e.contains("100 bytes"), "{e}");
        let tight = SizeLimits { texel_elements: 10, ..l };
        let e = check_sizes(&[BufferSize { bytes: 41, ..both }], &tight, "x").unwrap_err().to_string();
        assert!(e.contains("maxTexelBufferElements") && e.contains("--reads storage"), "{e}");
        let index = BufferSize::new("light_vertex_offsets", 100).reached(Access::TexelU32);
        assert!(check_sizes(&[index], &l, "x").is_ok());
        assert!(check_sizes(&[BufferSize { bytes: 101, ..index }], &l, "x").is_err());
        let film = BufferSize::new("film", 800).reached(Access::Address);
        assert!(check_sizes(&[film], &l, "x").is_ok());
        let e = check_sizes(&[BufferSize { bytes: 801, ..film }], &l, "x").unwrap_err().to_string();
        assert!(e.contains("maxMemoryAllocationSize") && e.contains("lower the resolution"), "{e}");
        // Past 2^31 elements of 4 bytes, whatever the allocation limit.
        let huge = SizeLimits { allocation: u64::MAX, heap: u64::MAX, ..l };
        let big = BufferSize::new("film", MAX_ADDRESSED_BYTES).reached(Access::Address);
        assert!(check_sizes(&[big], &huge, "x").is_ok());
        let e = check_sizes(&[BufferSize { bytes: MAX_ADDRESSED_BYTES + 1, ..big }], &huge, "x").unwrap_err();
        assert!(e.to_string().contains("2^31 elements"), "{e}");
        // A binding limit above the allocation limit: the allocation limit applies.
        let small_alloc = SizeLimits { allocation: 50, ..l };
        let e = check_sizes(&[BufferSize::new("film", 60)], &small_alloc, "x").unwrap_err().to_string();
        assert!(e.contains("maxMemoryAllocationSize"), "{e}");
    }
}
