//! Buffer sizes by name, and their check against a device's limits before anything is
//! allocated: the unit of the plan of sizes (src/render/plan.rs).

use std::sync::Arc;

use anyhow::{bail, Result};

use crate::gpu::{Buffer, Gpu};

/// One buffer of the plan.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BufferSize {
    pub name: &'static str,
    pub bytes: u64,
}

impl BufferSize {
    pub const fn new(name: &'static str, bytes: u64) -> BufferSize {
        BufferSize { name, bytes }
    }

    /// The buffer, zero-filled.
    pub fn zeroed(&self, gpu: &Arc<Gpu>) -> Result<Buffer> {
        gpu.buffer_zeroed_bytes(self.name, self.bytes)
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

/// What to change when buffer `name` is larger than one binding.
fn remedy(name: &str) -> &'static str {
    match name {
        n if n.starts_with("env_") => "use a smaller environment map (20 bytes per texel)",
        n if n.starts_with("texture_") => "use smaller textures (4 bytes per texel, all images in one buffer)",
        "bvh_nodes" | "bvh_prims" | "triangles" | "spheres" | "materials" | "lights" | "shading_normals"
        | "vertex_attributes" => {
            "the scene is too large for this device (fewer triangles, or a device with a larger maxStorageBufferRange)"
        }
        n if n.contains("vert") || n.starts_with("grid") => "lower the resolution or --max-path-length",
        _ => "lower the resolution",
    }
}

/// Checks `sizes` against a per-buffer binding limit `max_binding` and a memory heap of
/// `heap` bytes; `what` describes the render in the message.
pub fn check_sizes(sizes: &[BufferSize], max_binding: u64, heap: u64, what: &str) -> Result<()> {
    if let Some(b) = sizes.iter().rev().filter(|b| b.bytes > max_binding).max_by_key(|b| b.bytes) {
        bail!(
            "{what} needs {} for buffer {}, but the device binds at most {} per buffer (maxStorageBufferRange); {}",
            mib(b.bytes),
            b.name,
            mib(max_binding),
            remedy(b.name)
        );
    }
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

    #[test]
    fn binding_and_heap_limits() {
        let v = [BufferSize::new("film", 100), BufferSize::new("splat", 50)];
        assert!(check_sizes(&v, 100, 150, "x").is_ok());
        let e = check_sizes(&v, 99, 1000, "x").unwrap_err().to_string();
        assert!(e.contains("buffer film") && e.contains("maxStorageBufferRange"), "{e}");
        assert!(e.contains("lower the resolution"), "{e}");
        let env = [BufferSize::new("env_texels", 100)];
        let e = check_sizes(&env, 99, 1000, "x").unwrap_err().to_string();
        assert!(e.contains("smaller environment map") && !e.contains("resolution"), "{e}");
        let bvh = [BufferSize::new("bvh_prims", 100)];
        let e = check_sizes(&bvh, 99, 1000, "x").unwrap_err().to_string();
        assert!(e.contains("scene is too large") && !e.contains("resolution"), "{e}");
        let e = check_sizes(&v, 100, 149, "x").unwrap_err().to_string();
        assert!(e.contains("heap"), "{e}");
        assert!(!e.contains('\n'));
    }
}
