//! How the render kernels read the buffers they only read: the scene's BVH, triangles,
//! spheres, materials, lights and shading normals (bindings 1-7, glsl/scene.glsl), and in
//! the camera kernel the light-vertex store and the hash grid (glsl/vcm_bindings.glsl).
//!
//! * [`Reads::Storage`]: as storage buffers.
//! * [`Reads::Texel`]: as uniform texel buffers of `uvec4` (or `uint`) texels
//!   (`utextureBuffer`, `texelFetch`).
//!
//! Both read the same bytes, so the image is bit-identical (tests/render_reads.rs). On
//! lavapipe (Mesa 25.0) a load from a storage buffer at an address that differs between
//! the lanes of a SIMD group is compiled into a loop over the lanes with a bounds check,
//! a branch and a scalar load per lane and per 32- or 64-bit component, while a texel
//! fetch is one 16-byte load per lane without branches; texel reads measured 1.3-1.9x the
//! samples per CPU-second (docs/performance.md, "Fourth round (texel-buffer reads)").
//! GPUs are left on storage buffers: no GPU measurement backs another choice yet.

use ash::vk;

/// How the kernels read their read-only buffers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Reads {
    /// Storage buffers.
    Storage,
    /// Uniform texel buffers.
    Texel,
}

impl Reads {
    pub fn name(self) -> &'static str {
        match self {
            Reads::Storage => "storage",
            Reads::Texel => "texel",
        }
    }

    /// The choice for a device of type `device_type`: texel buffers on CPU devices
    /// (lavapipe), storage buffers on GPUs.
    pub fn auto(device_type: vk::PhysicalDeviceType) -> Reads {
        if device_type == vk::PhysicalDeviceType::CPU {
            Reads::Texel
        } else {
            Reads::Storage
        }
    }

    /// `requested` (`--reads`), or else [`Reads::auto`] for `gpu`.
    pub fn resolve(gpu: &crate::gpu::Gpu, requested: Option<Reads>) -> Reads {
        requested.unwrap_or_else(|| Reads::auto(gpu.info.device_type))
    }

    /// The kernels' define: `TEXEL_READS` 0 or 1.
    pub fn define(self) -> (String, String) {
        ("TEXEL_READS".into(), if self == Reads::Texel { "1" } else { "0" }.into())
    }

    /// How a kernel binds `b`, a buffer of 16-byte elements it only reads.
    pub fn bind(self, b: &crate::gpu::Buffer) -> crate::gpu::Binding<'_> {
        match self {
            Reads::Storage => crate::gpu::Binding::Storage(b),
            Reads::Texel => crate::gpu::Binding::Texel(b),
        }
    }

    /// The same for a buffer of `uint`s.
    pub fn bind_u32(self, b: &crate::gpu::Buffer) -> crate::gpu::Binding<'_> {
        match self {
            Reads::Storage => crate::gpu::Binding::Storage(b),
            Reads::Texel => crate::gpu::Binding::TexelU32(b),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn texel_reads_on_cpu_devices_only() {
        assert_eq!(Reads::auto(vk::PhysicalDeviceType::CPU), Reads::Texel);
        for t in [vk::PhysicalDeviceType::DISCRETE_GPU, vk::PhysicalDeviceType::INTEGRATED_GPU] {
            assert_eq!(Reads::auto(t), Reads::Storage);
        }
    }
}
