//! Vulkan compute core: device choice, buffers, GLSL kernels, batches, profiling and
//! validation. Everything is owned (RAII) and holds an `Arc<Gpu>`, so the device outlives
//! every object created from it.

mod batch;
mod buffer;
mod context;
mod kernel;
mod profile;
pub mod shader;
mod validation;

pub use batch::Batch;
pub use buffer::Buffer;
pub use context::{list_devices, DeviceInfo, FeatureStatus, Gpu, GpuOptions};
pub use kernel::{Kernel, PUSH_CONSTANT_BYTES};
pub use profile::{KernelTime, Profile};
pub use validation::Messages;

/// Workgroups needed to cover `n` invocations with groups of `local` invocations.
pub fn groups_for(n: u32, local: u32) -> u32 {
    n.div_ceil(local)
}
