//! Vulkan compute core: device choice, buffers, GLSL kernels, batches, profiling and
//! validation. Everything is owned (RAII) and holds an `Arc<Gpu>`, so the device outlives
//! every object created from it.

mod batch;
mod buffer;
mod context;
mod debug_names;
pub mod fault_injection;
mod kernel;
pub mod kernel_cache;
mod pipeline_cache;
mod profile;
pub mod reflect;
pub mod shader;
mod validation;

pub use batch::{default_submission_budget_ms, Batch};
pub use buffer::Buffer;
pub use context::{
    list_devices, DeviceInfo, FeatureStatus, Gpu, GpuArgs, GpuOptions, BUFFER_DEVICE_ADDRESS, SHADER_INT64,
    SHADER_INT64_ATOMICS, TEXEL_BUFFER_FORMATS, TIMESTAMPS,
};
pub use kernel::{Bind, Defines, Kernel, Texels, PUSH_CONSTANT_BYTES};
pub use profile::{trace_clock_us, DispatchEvent, KernelTime, Profile, ProfileReport, StageTime};
pub use shader::ShaderCounts;
pub use validation::Messages;

/// Workgroups needed to cover `n` invocations with groups of `local` invocations.
pub fn groups_for(n: u32, local: u32) -> u32 {
    n.div_ceil(local)
}

/// Most workgroups per dispatch dimension every Vulkan device accepts.
pub const MAX_GROUPS_PER_DIM: u32 = 65_535;

/// A dispatch covering `n` invocations of a 1-D problem with groups of `local`, folded
/// into two dimensions when it needs more than [`MAX_GROUPS_PER_DIM`] groups; kernels
/// recover the index with `invocation_index()` (glsl/common.glsl) and skip indices >= n.
pub fn groups_2d(n: u32, local: u32) -> [u32; 3] {
    fold_groups(groups_for(n, local))
}

/// `total` workgroups as a dispatch, folded into two dimensions past
/// [`MAX_GROUPS_PER_DIM`]; kernels recover the workgroup's index with `workgroup_index()`
/// (glsl/common.glsl) and skip those past the end.
pub fn fold_groups(total: u32) -> [u32; 3] {
    if total <= MAX_GROUPS_PER_DIM {
        [total, 1, 1]
    } else {
        [MAX_GROUPS_PER_DIM, total.div_ceil(MAX_GROUPS_PER_DIM), 1]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn groups_2d_covers_every_invocation() {
        for n in [1u32, 64, 65, 64 * 65_535, 64 * 65_535 + 1, 8_294_400, u32::MAX / 2] {
            let [x, y, z] = groups_2d(n, 64);
            assert!(x <= MAX_GROUPS_PER_DIM && y <= MAX_GROUPS_PER_DIM && z == 1);
            assert!(x as u64 * y as u64 * 64 >= n as u64, "{n}");
            // No whole row of groups is wasted.
            assert!((x as u64 * (y as u64 - 1)) * 64 < n as u64, "{n}");
        }
    }
}
