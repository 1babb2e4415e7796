//! The plan of sizes of a render: every buffer it allocates, by name and size in bytes,
//! computed once from the scene, the settings and the estimator's techniques. The
//! renderer checks the plan against the device before anything is allocated (each
//! buffer against `maxStorageBufferRange`, the total against the largest device-local
//! heap, system RAM on lavapipe), and the film and passes allocate what it says. Each
//! part is defined next to the code that uses the buffers: [`ScenePlan`]
//! (src/render/scene_gpu.rs), [`FilmPlan`] (film.rs), [`LightVertexPlan`],
//! [`LightVertexCachePlan`], [`GridPlan`] (src/render/passes/).

use std::sync::Arc;

use anyhow::{bail, Result};

use super::estimators::Techniques;
use super::film::FilmPlan;
use super::passes::hash_grid::{grid_buckets, GridPlan};
use super::passes::light_subpaths::LightVertexPlan;
use super::passes::light_vertex_cache::LightVertexCachePlan;
use super::scene_gpu::ScenePlan;
use super::settings::{Connect, RenderSettings};
use crate::gpu::{Buffer, Gpu};
use crate::scene::Scene;

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

/// What a render allocates.
#[derive(Clone, Debug)]
pub struct FramePlan {
    pub pixels: u32,
    /// Light subpaths per iteration, N_L (one per pixel, SmallVCM's choice).
    pub light_paths: u32,
    /// Paths per kernel invocation (path regeneration, src/render/regen.rs).
    pub paths_per_invocation: u32,
    /// Upper bounds of the scene's buffers (their sizes are exact after the BVH build).
    pub scene: ScenePlan,
    pub film: FilmPlan,
    /// The light-vertex store and splat sums (light-subpath estimators).
    pub light_vertices: Option<LightVertexPlan>,
    /// The light-vertex cache (`--connect cache`).
    pub cache: Option<LightVertexCachePlan>,
    /// The hash grid (merging).
    pub grid: Option<GridPlan>,
}

impl FramePlan {
    /// The plan of a render of `scene` with `s` by an estimator with `techniques`,
    /// tracing `paths_per_invocation` paths per invocation. The settings are checked
    /// ([`RenderSettings::check`]).
    pub fn new(
        scene: &Scene,
        s: &RenderSettings,
        techniques: Techniques,
        paths_per_invocation: u32,
    ) -> Result<FramePlan> {
        s.check()?;
        let prims = scene.triangles.len() + scene.spheres.len();
        if prims > crate::bvh::layout::MAX_PRIMS {
            bail!(
                "scene {:?} has {prims} primitives; the BVH holds at most {}",
                scene.name,
                crate::bvh::layout::MAX_PRIMS
            );
        }
        let pixels = s.frame.width * s.frame.height;
        let light_paths = pixels;
        let light_vertices = techniques
            .light_subpaths
            .then(|| LightVertexPlan::new(pixels, light_paths, s.frame.max_path_length, techniques.store_vertices));
        let cache = match (&light_vertices, s.connect) {
            (Some(lv), Connect::Cache(_)) if techniques.vertex_connection => Some(LightVertexCachePlan::new(lv)),
            _ => None,
        };
        let grid = match &light_vertices {
            Some(lv) if techniques.vertex_merging => {
                Some(GridPlan::new(light_paths, lv.slots_per_path, grid_buckets(light_paths as u64)))
            }
            _ => None,
        };
        Ok(FramePlan {
            pixels,
            light_paths,
            paths_per_invocation,
            scene: ScenePlan::new(scene),
            film: FilmPlan::new(s.frame.width, s.frame.height),
            light_vertices,
            cache,
            grid,
        })
    }

    /// Every buffer, in allocation order.
    pub fn buffers(&self) -> Vec<BufferSize> {
        let mut v = self.scene.buffers();
        v.extend(self.film.buffers());
        v.extend(self.light_vertices.iter().flat_map(|p| p.buffers()));
        v.extend(self.grid.iter().flat_map(|p| p.buffers()));
        v.extend(self.cache.iter().flat_map(|p| p.buffers()));
        v
    }

    /// Fails when the plan does not fit `gpu`; `what` describes the render in the message.
    pub fn check(&self, gpu: &Gpu, what: &str) -> Result<()> {
        check_sizes(&self.buffers(), gpu.limits.max_storage_buffer_range as u64, gpu.device_local_heap_bytes(), what)
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

/// Checks `sizes` against a per-buffer binding limit `max_binding` and a memory heap of
/// `heap` bytes; `what` describes the render in the message.
pub fn check_sizes(sizes: &[BufferSize], max_binding: u64, heap: u64, what: &str) -> Result<()> {
    if let Some(b) = sizes.iter().rev().filter(|b| b.bytes > max_binding).max_by_key(|b| b.bytes) {
        bail!(
            "{what} needs {} for buffer {}, but the device binds at most {} per buffer (maxStorageBufferRange); \
             lower the resolution{}",
            mib(b.bytes),
            b.name,
            mib(max_binding),
            if b.name.contains("vert") || b.name.starts_with("grid") { " or --max-path-length" } else { "" }
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
        let e = check_sizes(&v, 100, 149, "x").unwrap_err().to_string();
        assert!(e.contains("heap"), "{e}");
        assert!(!e.contains('\n'));
    }
}
