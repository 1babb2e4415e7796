//! How the render kernels read the buffers they only read: the scene's BVH, triangles,
//! spheres, materials, lights and shading normals (glsl/scene.glsl), and in the camera
//! kernel the light-vertex store, the hash grid and the cache's index
//! (glsl/light_vertex_store.glsl, glsl/camera_subpath.comp).
//!
//! * [`Reads::Storage`]: as storage buffers.
//! * [`Reads::Texel`]: as uniform texel buffers of `uvec4` (or `uint`) texels
//!   (`utextureBuffer`, `texelFetch`).
//!
//! The kernels declare either kind (TEXEL_READS for the scene, src/render/variants.rs;
//! STORE_TEXEL_READS for the light-vertex store and the hash grid, `CameraKernel`) and
//! are bound by name, so the Rust side only chooses the variant. Both read the same
//! bytes, so the image is bit-identical (tests/render_reads.rs). On lavapipe a load from
//! a storage buffer at an address that differs between the lanes of a SIMD group is
//! compiled into a loop over the lanes with a bounds check, a branch and a scalar load
//! per lane and per component, while a texel fetch is one 16-byte load per lane, so
//! texel reads are faster there (docs/performance.md, "Defaults that matter for speed, and why"). GPUs keep storage
//! buffers: their memory path differs and no GPU measurement backs another choice.

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

    /// `requested` (`--reads`), or else [`Reads::auto`] for `gpu`; storage buffers on a
    /// device that cannot read the texel formats (docs/devices.md), where `--reads texel`
    /// is refused.
    pub fn resolve(gpu: &crate::gpu::Gpu, requested: Option<Reads>) -> anyhow::Result<Reads> {
        let texel_ok = gpu.has(crate::gpu::TEXEL_BUFFER_FORMATS);
        match requested {
            Some(Reads::Texel) if !texel_ok => anyhow::bail!(
                "--reads texel: device {:?} cannot read {}; use --reads storage",
                gpu.info.name,
                crate::gpu::TEXEL_BUFFER_FORMATS
            ),
            Some(r) => Ok(r),
            None if texel_ok => Ok(Reads::auto(gpu.info.device_type)),
            None => Ok(Reads::Storage),
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
