//! Path regeneration (Novák, Havran & Dachsbacher, "Path Regeneration for Interactive Path
//! Tracing", Eurographics 2010 short papers): the path tracer's, light tracer's and
//! camera kernels trace `k` paths per invocation, starting the next path of an invocation
//! in the loop iteration in which its current one ends (glsl/common.glsl `regen_stride`).
//! A SIMD group then runs until its lanes' total work is done, instead of once per path
//! until its longest path is. The image does not depend on `k`: every path keeps its
//! index, random sequence and outputs (tests/render_regen.rs checks equality).
//!
//! On a CPU device (lavapipe: 8 lanes per SIMD group) a SIMD group otherwise waits for
//! its longest path, so more paths per invocation are faster, up to 2 workgroups per
//! thread (docs/performance.md, "Defaults that matter for speed, and why"). GPUs keep one path per invocation: they
//! hide divergence differently and need many invocations in flight.

use ash::vk;

use super::variants::WORKGROUP_SIZE;

/// The most paths per invocation [`auto`] chooses.
pub const MAX_AUTO: u32 = 256;

/// Workgroups per CPU thread [`auto`] keeps at least, so that the device's threads share
/// the dispatch evenly.
const WORKGROUPS_PER_THREAD: u32 = 2;

/// Paths per invocation for `paths` paths per dispatch on a device of type
/// `device_type`: 1 on GPUs; on a CPU device as many as keep
/// [`WORKGROUPS_PER_THREAD`] workgroups per thread, at most [`MAX_AUTO`].
pub fn auto(device_type: vk::PhysicalDeviceType, cpu_threads: u32, paths: u32) -> u32 {
    if device_type != vk::PhysicalDeviceType::CPU {
        return 1;
    }
    let per_dispatch = WORKGROUP_SIZE * WORKGROUPS_PER_THREAD * cpu_threads.max(1);
    (paths / per_dispatch).clamp(1, MAX_AUTO)
}

/// Paths per invocation of an estimator's kernels for `paths` paths per dispatch on
/// `gpu`: `requested` (`--paths-per-invocation`) or else [`auto`]; 1 for an estimator
/// whose kernels do not regenerate paths (`el`: one short ray per pixel).
pub fn resolve(gpu: &crate::gpu::Gpu, regenerates_paths: bool, requested: Option<u32>, paths: u32) -> u32 {
    if !regenerates_paths {
        return 1;
    }
    requested.unwrap_or_else(|| auto(gpu.info.device_type, cpu_threads(), paths))
}

/// The threads a CPU device (lavapipe) runs a dispatch on: `LP_NUM_THREADS` when set,
/// else the machine's available parallelism (lavapipe's default).
pub fn cpu_threads() -> u32 {
    let set = std::env::var("LP_NUM_THREADS").ok().and_then(|v| v.trim().parse::<u32>().ok());
    set.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get() as u32)).max(1)
}

/// Invocations of a dispatch over `paths` paths with `k` per invocation (as the kernels'
/// `regen_stride`).
pub fn invocations(paths: u32, k: u32) -> u32 {
    paths.div_ceil(k.max(1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gpus_take_one_path_per_invocation() {
        for t in [vk::PhysicalDeviceType::DISCRETE_GPU, vk::PhysicalDeviceType::INTEGRATED_GPU] {
            assert_eq!(auto(t, 16, 1 << 20), 1);
        }
    }

    #[test]
    fn cpus_keep_workgroups_for_every_thread() {
        let cpu = vk::PhysicalDeviceType::CPU;
        assert_eq!(auto(cpu, 2, 65_536), 256);
        assert_eq!(auto(cpu, 16, 65_536), 32);
        assert_eq!(auto(cpu, 2, 1 << 22), MAX_AUTO);
        assert_eq!(auto(cpu, 2, 100), 1);
        assert_eq!(auto(cpu, 0, 0), 1);
    }

    #[test]
    fn invocations_cover_every_path() {
        for (paths, k) in [(0, 1), (1, 1), (10, 3), (65_536, 128), (65_537, 128), (7, 0)] {
            let n = invocations(paths, k);
            assert!(n as u64 * k.max(1) as u64 >= paths as u64);
            assert!(n == 0 || (n as u64 - 1) * (k.max(1) as u64) < paths as u64);
        }
    }
}
