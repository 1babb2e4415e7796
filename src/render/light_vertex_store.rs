//! The light-vertex store of the light-subpath estimators (bpt, ppm, bpm, vcm; lt keeps
//! a placeholder): its sizes ([`LightVertexPlan`]), its buffers ([`LightVertexStore`]),
//! the status the compaction writes ([`StoreStatus`]) and its growth.
//!
//! The light-subpaths pass (src/render/passes/light_subpaths.rs) traces an iteration's
//! light subpaths in chunks into scratch slots and compacts their vertices into the
//! store in path order, so that it holds exactly the vertices traced (SmallVCM reserves
//! max path length - 1 slots per light subpath, most of them empty); the camera-subpaths
//! pass reads it (glsl/light_vertex_store.glsl has the layout).
//!
//! How many vertices an iteration stores is known only once it is traced. The store is
//! sized for [`INITIAL_VERTICES_PER_PATH`] per light subpath; when an iteration stores
//! more, the compaction writes what fits and records the iteration in
//! `light_vertex_status` ([`StoreStatus`]), the camera kernel leaves it (and the rest of
//! its batch) out of the film, and the estimator grows the store (`FramePlan::grown`),
//! rebuilds its passes and reports those iterations as not done, so that the renderer
//! renders them again: the same image, since an iteration's random numbers depend only on
//! its index.

use std::sync::Arc;

use anyhow::{Context, Result};
use bytemuck::{Pod, Zeroable};

use super::addresses::FrameAddresses;
use super::features::FeatureSet;
use super::passes::exclusive_scan::ScanPlan;
use super::sizes::{Access, BufferSize};
use crate::gpu::{Bind, Buffer, Gpu};

/// Bytes of one light vertex in `light_vertices_a` (position, throughput and two MIS
/// quantities: two vec4).
pub const LIGHT_VERTEX_A_BYTES: u64 = 32;

/// Bytes of one light vertex in `light_vertices_b` for kernels compiled with `features`:
/// (wo, dVM) and (normal, material and length), with shading normals or
/// metallic-roughness textures a vec4 holding the shading normal and the point's metallic,
/// with vertex attributes one holding the tint and its roughness, with clear-coat,
/// transmission, specular, sheen, iridescence and diffuse-transmission textures one each
/// holding the point's multipliers, with clear-coat normal maps one holding the coat's
/// normal, with anisotropy one holding the point's anisotropy direction and strength,
/// with dispersion one holding the subpath's colour channel (glsl/light_vertex_store.glsl,
/// LV_B_STRIDE).
pub fn light_vertex_b_bytes(features: &FeatureSet) -> u64 {
    let normal_slot = features.shading_normals || features.metallic_roughness_textures;
    let slots = [
        normal_slot,
        features.vertex_attributes,
        features.clearcoat_textures,
        features.clearcoat_normal_maps,
        features.sheen_textures,
        features.iridescence_textures,
        features.anisotropy,
        features.diffuse_transmission_textures,
        features.dispersion,
        features.transmission_textures,
        features.specular_textures,
    ];
    32 + 16 * slots.iter().filter(|&&s| s).count() as u64
}

/// Light vertices per light subpath the store is first sized for: the reference scenes
/// store 0.8-2.1 per light subpath at the default max path length of 10, and a scene
/// that stores more grows the store after its first iteration.
pub const INITIAL_VERTICES_PER_PATH: u64 = 4;

/// The most bytes of scratch slots (both halves) one chunk of light subpaths uses.
pub const MAX_SCRATCH_BYTES: u64 = 256 << 20;

/// The capacity to grow the store to after an iteration stored `needed` vertices: a
/// quarter more, so that the next iterations (whose totals vary) fit too, but never more
/// than every light subpath's every slot.
pub fn grown_capacity(needed: u64, plan: &LightVertexPlan) -> u64 {
    let all_slots = plan.light_paths as u64 * plan.slots_per_path as u64;
    (needed + needed / 4 + 64).min(all_slots).max(needed.min(all_slots))
}

/// The sizes of the light-vertex store, the scratch slots of a chunk and the splat sums.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LightVertexPlan {
    pub light_paths: u32,
    /// Scratch slots per light subpath (max path length - 1, at least 1).
    pub slots_per_path: u32,
    /// Light subpaths per chunk (one dispatch of the light kernel).
    pub chunk_paths: u32,
    /// Paths per invocation of the light kernel (path regeneration over a chunk).
    pub paths_per_invocation: u32,
    /// Whether the estimator stores vertices (lt does not: its kernels still declare the
    /// store, which is then a 1-vertex placeholder).
    pub store_vertices: bool,
    /// Vertices the store holds.
    pub capacity: u64,
    /// Bytes of a vertex in `light_vertices_b`.
    pub vertex_b_bytes: u64,
    /// Per pixel three fixed-point u64 sums (glsl/film.glsl).
    pub splat: BufferSize,
    pub vertices_a: BufferSize,
    pub vertices_b: BufferSize,
    /// N_L + 1 u32: where each light subpath's vertices start, then the total.
    pub offsets: BufferSize,
    pub scratch_a: BufferSize,
    pub scratch_b: BufferSize,
    /// `chunk_paths + 1` u32: the chunk's vertex counts, scanned in place.
    pub chunk_counts: BufferSize,
    pub chunk_scan: ScanPlan,
    /// [`StoreStatus`].
    pub status: BufferSize,
}

/// What [`LightVertexPlan::new`] is sized from besides the frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LightVertexSizing {
    /// The most bytes one scratch half may have (the binding limit where it is bound).
    pub scratch_limit: u64,
    /// Light subpaths per chunk at most (`RenderSettings::light_chunk_paths`).
    pub chunk_paths: Option<u32>,
    /// The store's first capacity (`RenderSettings::light_vertex_capacity`; default
    /// [`INITIAL_VERTICES_PER_PATH`] per light subpath).
    pub capacity: Option<u64>,
}

/// How each buffer of the store is reached (src/render/plan.rs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LightVertexAccess {
    /// The splat sums and the scratch slots (written by the light kernels).
    pub frame: Access,
    /// The store's vertices (read by the camera kernel).
    pub vertices: Access,
    /// The offsets (read by the camera kernel).
    pub offsets: Access,
}

impl LightVertexPlan {
    /// The store of `light_paths` subpaths of up to `max_path_length` segments, with
    /// `vertex_b_bytes` per vertex in `light_vertices_b` ([`light_vertex_b_bytes`]), and
    /// the splat sums of `pixels` pixels; the light kernel traces
    /// `paths_per_invocation(chunk)` paths per invocation.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        pixels: u32,
        light_paths: u32,
        max_path_length: u32,
        store_vertices: bool,
        vertex_b_bytes: u64,
        access: LightVertexAccess,
        sizing: LightVertexSizing,
        paths_per_invocation: impl Fn(u32) -> u32,
    ) -> LightVertexPlan {
        let slots_per_path = max_path_length.saturating_sub(1).max(1);
        let slot_bytes = LIGHT_VERTEX_A_BYTES + vertex_b_bytes;
        let chunk_paths = if store_vertices {
            let per_path = slots_per_path as u64 * slot_bytes;
            let by_budget = MAX_SCRATCH_BYTES / per_path;
            let by_binding = sizing.scratch_limit / (slots_per_path as u64 * vertex_b_bytes);
            let most = by_budget.min(by_binding).clamp(1, u32::MAX as u64) as u32;
            light_paths.min(most).min(sizing.chunk_paths.unwrap_or(u32::MAX)).max(1)
        } else {
            light_paths.min(sizing.chunk_paths.unwrap_or(u32::MAX)).max(1)
        };
        let all_slots = light_paths as u64 * slots_per_path as u64;
        let capacity = match (store_vertices, sizing.capacity) {
            (false, _) => 1,
            (true, Some(c)) => c.clamp(1, all_slots),
            (true, None) => (light_paths as u64 * INITIAL_VERTICES_PER_PATH).min(all_slots),
        };
        let scratch_slots = if store_vertices { chunk_paths as u64 * slots_per_path as u64 } else { 1 };
        let offsets = if store_vertices { light_paths as u64 + 1 } else { 1 };
        let counts = if store_vertices { chunk_paths + 1 } else { 1 };
        let mut plan = LightVertexPlan {
            light_paths,
            slots_per_path,
            chunk_paths,
            paths_per_invocation: paths_per_invocation(chunk_paths),
            store_vertices,
            capacity,
            vertex_b_bytes,
            splat: BufferSize::new("splat", (pixels as u64).saturating_mul(24)).reached(access.frame),
            vertices_a: BufferSize::new("light_vertices_a", 0).reached(access.vertices),
            vertices_b: BufferSize::new("light_vertices_b", 0).reached(access.vertices),
            offsets: BufferSize::new("light_vertex_offsets", offsets * 4).reached(access.offsets),
            scratch_a: BufferSize::new("light_vertex_scratch_a", scratch_slots * LIGHT_VERTEX_A_BYTES)
                .reached(access.frame),
            scratch_b: BufferSize::new("light_vertex_scratch_b", scratch_slots * vertex_b_bytes).reached(access.frame),
            chunk_counts: BufferSize::new("light_vertex_chunk_counts", counts as u64 * 4),
            chunk_scan: ScanPlan::new(counts, "light_vertex_chunk_scan_scratch"),
            status: BufferSize::new("light_vertex_status", std::mem::size_of::<StoreStatus>() as u64),
        };
        plan.set_capacity(capacity);
        plan
    }

    /// Resizes the store for `capacity` vertices.
    pub fn set_capacity(&mut self, capacity: u64) {
        self.capacity = capacity;
        self.vertices_a.bytes = capacity.saturating_mul(LIGHT_VERTEX_A_BYTES);
        self.vertices_b.bytes = capacity.saturating_mul(self.vertex_b_bytes);
    }

    pub fn buffers(&self) -> Vec<BufferSize> {
        let mut v = vec![self.splat, self.vertices_a, self.vertices_b, self.offsets, self.status];
        if self.store_vertices {
            v.extend([self.scratch_a, self.scratch_b, self.chunk_counts, self.chunk_scan.scratch]);
        }
        v
    }
}

/// `light_vertex_status` (glsl/light_vertex_compact.comp): what the compaction found.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Pod, Zeroable)]
pub struct StoreStatus {
    /// The earliest iteration whose vertices did not fit the store ([`StoreStatus::NONE`]:
    /// none).
    pub first_overflow: u32,
    /// The most vertices one iteration stored (saturating at 2^32 - 1).
    pub most_vertices: u32,
}

impl StoreStatus {
    pub const NONE: u32 = u32::MAX;
}

/// The light-vertex store and the splat sums, written by the light pass and read by the
/// passes after it.
pub struct LightVertexStore {
    pub splat: Buffer,
    pub vertices_a: Buffer,
    pub vertices_b: Buffer,
    /// N_L + 1 u32 (binding `light_vertex_offsets`).
    pub offsets: Buffer,
    /// [`StoreStatus`] (binding `light_vertex_status`).
    pub status: Buffer,
}

impl LightVertexStore {
    /// The store of `plan`; the addresses of its large buffers go to `addresses`.
    pub fn new(gpu: &Arc<Gpu>, plan: &LightVertexPlan, addresses: &FrameAddresses) -> Result<LightVertexStore> {
        let splat = plan.splat.zeroed(gpu)?;
        let vertices_a = plan.vertices_a.zeroed(gpu)?;
        let vertices_b = plan.vertices_b.zeroed(gpu)?;
        let offsets = plan.offsets.zeroed(gpu)?;
        addresses.set(|a| &mut a.splat, &splat)?;
        addresses.set(|a| &mut a.light_vertices_a, &vertices_a)?;
        addresses.set(|a| &mut a.light_vertices_b, &vertices_b)?;
        addresses.set(|a| &mut a.light_vertex_offsets, &offsets)?;
        let status = plan.status.zeroed(gpu)?;
        status.write(&[StoreStatus { first_overflow: StoreStatus::NONE, most_vertices: 0 }])?;
        Ok(LightVertexStore { splat, vertices_a, vertices_b, offsets, status })
    }

    /// The store's bindings (the splat sums, both vertex halves, the offsets, the status).
    pub fn binds(&self) -> [Bind<'_>; 5] {
        [
            Bind::own(&self.splat),
            Bind::own(&self.vertices_a),
            Bind::own(&self.vertices_b),
            Bind::own_u32(&self.offsets),
            Bind::own_u32(&self.status),
        ]
    }

    pub fn buffers(&self) -> Vec<&Buffer> {
        vec![&self.splat, &self.vertices_a, &self.vertices_b, &self.offsets, &self.status]
    }

    /// What the compaction has recorded since the store was made (the device must be idle).
    pub fn status(&self) -> Result<StoreStatus> {
        let s = self.status.read::<StoreStatus>().context("reading the light-vertex store's status back")?;
        Ok(s[0])
    }
}

/// How a render used its light-vertex store (`vkvcm render --verbose`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StoreUse {
    pub light_paths: u32,
    /// The scratch slots per light subpath (the most it can store).
    pub slots_per_path: u32,
    /// Vertices the store holds now.
    pub capacity: u64,
    /// The most vertices one iteration stored.
    pub most_vertices: u64,
    /// How often the store grew, and the iterations rendered again because of it.
    pub grown: u32,
    pub iterations_redone: u64,
}

/// What the store has seen over a render (the counters of [`StoreUse`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct StoreCounters {
    most_vertices: u64,
    grown: u32,
    iterations_redone: u64,
}

impl StoreCounters {
    /// Takes the status read back after the batch of iterations `first .. first + n`:
    /// how many of them are in the film and, when one did not fit, the most vertices an
    /// iteration of the batch stored (the store must grow to that).
    pub fn after_batch(&mut self, status: StoreStatus, first: u64, n: u64) -> (u64, Option<u64>) {
        self.most_vertices = self.most_vertices.max(status.most_vertices as u64);
        if status.first_overflow == StoreStatus::NONE {
            return (n, None);
        }
        let accepted = (status.first_overflow as u64).saturating_sub(first).min(n);
        self.grown += 1;
        self.iterations_redone += n - accepted;
        (accepted, Some(status.most_vertices as u64))
    }

    /// The use of the store of `plan` so far.
    pub fn store_use(&self, plan: &LightVertexPlan) -> StoreUse {
        StoreUse {
            light_paths: plan.light_paths,
            slots_per_path: plan.slots_per_path,
            capacity: plan.capacity,
            most_vertices: self.most_vertices,
            grown: self.grown,
            iterations_redone: self.iterations_redone,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plan(light_paths: u32, max_path_length: u32, sizing: LightVertexSizing) -> LightVertexPlan {
        let access = LightVertexAccess { frame: Access::Address, vertices: Access::Address, offsets: Access::Address };
        LightVertexPlan::new(light_paths, light_paths, max_path_length, true, 32, access, sizing, |_| 1)
    }

    const UNCAPPED: LightVertexSizing =
        LightVertexSizing { scratch_limit: u64::MAX, chunk_paths: None, capacity: None };

    #[test]
    fn chunks_keep_the_scratch_within_its_budget() {
        // 4K at the default max path length: 8.3M light subpaths of 9 slots of 64 bytes.
        let p = plan(3840 * 2160, 10, UNCAPPED);
        assert_eq!(p.slots_per_path, 9);
        assert!(p.scratch_a.bytes + p.scratch_b.bytes <= MAX_SCRATCH_BYTES);
        assert_eq!(p.chunk_paths as u64, MAX_SCRATCH_BYTES / (9 * 64));
        assert_eq!(p.capacity, 3840 * 2160 * INITIAL_VERTICES_PER_PATH);
        // A small frame is one chunk; the setting caps it.
        assert_eq!(plan(4096, 10, UNCAPPED).chunk_paths, 4096);
        let capped = LightVertexSizing { chunk_paths: Some(100), ..UNCAPPED };
        assert_eq!(plan(4096, 10, capped).chunk_paths, 100);
        assert_eq!(plan(4096, 10, capped).chunk_counts.bytes, 101 * 4);
        // The binding limit of a bound scratch half.
        let bound = LightVertexSizing { scratch_limit: 9 * 32 * 10, ..UNCAPPED };
        assert_eq!(plan(4096, 10, bound).chunk_paths, 10);
    }

    #[test]
    fn the_store_never_holds_more_than_every_slot() {
        let p = plan(100, 3, UNCAPPED);
        assert_eq!(p.capacity, 200);
        assert_eq!(grown_capacity(150, &p), 200);
        let p = plan(1000, 10, LightVertexSizing { capacity: Some(10), ..UNCAPPED });
        assert_eq!(p.capacity, 10);
        assert_eq!(p.vertices_a.bytes, 320);
        assert_eq!(grown_capacity(1000, &p), 1314);
        assert_eq!(grown_capacity(100_000, &p), 9000);
    }
}
