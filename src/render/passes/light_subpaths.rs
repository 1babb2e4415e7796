//! The light-subpaths pass: N_L light subpaths per iteration (one per pixel unless
//! `--light-paths` says otherwise), traced in chunks of at most
//! [`LightVertexPlan::chunk_paths`]. It writes the light-vertex store
//! ([`LightVertexStore`]) and, for the estimators that connect light vertices to the
//! camera, the splat sums. For an estimator that stores vertices, each chunk takes three
//! steps:
//!
//! 1. glsl/light_subpath.comp traces the chunk's light subpaths. Light subpath
//!    `first + q` writes its vertices to the scratch slots `[q S, q S + S)` (S = max path
//!    length - 1, the most a light subpath stores) and its vertex count to
//!    `light_vertex_chunk_counts[q]`;
//! 2. exclusive_scan.comp turns the counts into the chunk's prefix sums;
//! 3. glsl/light_vertex_compact.comp copies each light subpath's vertices into the store
//!    behind those of every earlier light subpath and writes where they start,
//!    `light_vertex_offsets[p]` (entry N_L: the iteration's total).
//!
//! So the store holds exactly the vertices traced, in path order (SmallVCM reserves S
//! slots per light subpath, most of them empty), and the chunks bound only the scratch
//! slots: the image does not depend on the chunk size. Camera subpath `p` finds light
//! subpath `p`'s vertices at `light_vertex_offsets[p] .. light_vertex_offsets[p + 1]`,
//! the light-vertex cache draws from all of them by index, and the hash grid indexes them.
//!
//! How many vertices an iteration stores is known only once it is traced. The store is
//! sized for [`INITIAL_VERTICES_PER_PATH`] per light subpath; when an iteration stores
//! more, the compaction writes what fits and records the iteration in
//! `light_vertex_status` ([`StoreStatus`]), the camera kernel leaves it (and the rest of
//! its batch) out of the film, and the renderer grows the store
//! ([`grown_capacity`]) and renders those iterations again: the same image, since an
//! iteration's random numbers depend only on its index.

use std::sync::Arc;

use anyhow::{Context, Result};
use bytemuck::{Pod, Zeroable};

use super::exclusive_scan::{ExclusiveScan, ScanPlan};
use super::PassContext;
use super::PassInfo;
use crate::gpu::{Batch, Bind, Buffer, Gpu, Kernel};
use crate::render::addresses::FrameAddresses;
use crate::render::features::FeatureSet;
use crate::render::gpu_types::GpuPush;
use crate::render::regen;
use crate::render::sizes::{Access, BufferSize};
use crate::render::techniques::Techniques;
use crate::render::variants::{kernel_switches, workgroup_defines};

/// The name profiles report.
pub const NAME: &str = "light subpaths";

kernel_switches! {
    /// What glsl/light_subpath.comp is compiled with: the light side of the estimator's
    /// [`Techniques`], under the same names.
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    pub struct LightKernel {
        /// Non-delta vertices go to the light-vertex store.
        pub store_vertices: bool,
        /// Vertices connect to the camera (splats).
        pub connect_to_camera: bool,
        /// Weight 1, and emitters seen directly are splatted too (lt).
        pub light_trace_only: bool,
    }
}

impl LightKernel {
    pub fn new(t: Techniques) -> LightKernel {
        LightKernel {
            store_vertices: t.store_vertices,
            connect_to_camera: t.connect_to_camera,
            light_trace_only: t.light_trace_only,
        }
    }
}

/// Bytes of one light vertex in `light_vertices_a` (position, throughput and two MIS
/// quantities: two vec4).
pub const LIGHT_VERTEX_A_BYTES: u64 = 32;

/// Bytes of one light vertex in `light_vertices_b` for kernels compiled with `features`:
/// (wo, dVM) and (normal, material and length), with shading normals or
/// metallic-roughness textures a vec4 holding the shading normal and the point's metallic,
/// with vertex attributes one holding the tint and its roughness (glsl/light_vertex_store.glsl,
/// LV_B_STRIDE).
pub fn light_vertex_b_bytes(features: &FeatureSet) -> u64 {
    let normal_slot = features.shading_normals || features.metallic_roughness_textures;
    32 + 16 * normal_slot as u64 + 16 * features.vertex_attributes as u64
}

/// Light vertices per light subpath the store is first sized for. The reference scenes
/// store 0.8-2.1 per light subpath at the default max path length of 10
/// (docs/performance.md, "The light-vertex store"); a scene that stores more grows the
/// store after its first iteration.
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

/// Push constants of glsl/light_vertex_compact.comp (its `CompactPush`).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct CompactPush {
    first_path: u32,
    count: u32,
    light_paths: u32,
    capacity: u32,
    slots: u32,
    b_stride: u32,
    iteration: u32,
}

/// Steps 2 and 3 of a chunk: the scan of its vertex counts and the copy into the store,
/// with the scratch slots they read.
struct Compaction {
    kernel: Kernel,
    scan: ExclusiveScan,
    chunk_counts: Buffer,
    scratch: [Buffer; 2],
    capacity: u32,
    b_stride: u32,
}

/// The pass.
pub struct LightSubpaths {
    // Field order is drop order: the kernels before the buffers they bind.
    kernel: Kernel,
    compaction: Option<Compaction>,
    variant: LightKernel,
    light_paths: u32,
    chunk_paths: u32,
    slots: u32,
    paths_per_invocation: u32,
}

impl LightSubpaths {
    /// The light kernel in `variant` for the render `b`, writing `store` as `plan` says.
    pub fn new(
        b: &PassContext,
        store: &LightVertexStore,
        plan: &LightVertexPlan,
        variant: LightKernel,
    ) -> Result<LightSubpaths> {
        let gpu = b.gpu;
        let addresses = &b.film.addresses;
        let compaction = if variant.store_vertices {
            let scratch = [plan.scratch_a.zeroed(gpu)?, plan.scratch_b.zeroed(gpu)?];
            addresses.set(|a| &mut a.light_scratch_a, &scratch[0])?;
            addresses.set(|a| &mut a.light_scratch_b, &scratch[1])?;
            let chunk_counts = plan.chunk_counts.zeroed(gpu)?;
            let scan = ExclusiveScan::with_plan(gpu, &chunk_counts, &plan.chunk_scan)?;
            let mut binds = vec![Bind::own_u32(&chunk_counts), Bind::own(&scratch[0]), Bind::own(&scratch[1])];
            binds.extend(store.binds());
            binds.push(addresses.bind());
            let defines = workgroup_defines().flag("DEVICE_ADDRESSES", addresses.enabled());
            let kernel = gpu.kernel("light_vertex_compact.comp", &defines.pairs(), &binds)?;
            // The plan of sizes keeps the store within 2^31 elements (u32 indices).
            let capacity = u32::try_from(plan.capacity).context("light-vertex store capacity")?;
            Some(Compaction {
                kernel,
                scan,
                chunk_counts,
                scratch,
                capacity,
                b_stride: (plan.vertex_b_bytes / 16) as u32,
            })
        } else {
            None
        };
        let defines = b.scene.variant.defines().with(&variant.defines());
        let mut binds = b.scene.binds();
        binds.extend(b.film.binds());
        binds.extend(store.binds());
        if let Some(c) = &compaction {
            binds.extend([Bind::own_u32(&c.chunk_counts), Bind::own(&c.scratch[0]), Bind::own(&c.scratch[1])]);
        }
        let kernel = gpu.kernel("light_subpath.comp", &defines.pairs(), &binds)?;
        Ok(LightSubpaths {
            kernel,
            compaction,
            variant,
            light_paths: plan.light_paths,
            chunk_paths: plan.chunk_paths,
            slots: plan.slots_per_path,
            paths_per_invocation: plan.paths_per_invocation,
        })
    }

    /// Records the pass for the iteration of `push` (its count, first path and paths per
    /// invocation are the pass's own).
    pub fn record(&self, batch: &mut Batch, push: &GpuPush) -> Result<()> {
        batch.begin_pass(NAME);
        let mut first = 0u32;
        while first < self.light_paths {
            let count = (self.light_paths - first).min(self.chunk_paths);
            let p = GpuPush { first_path: first, count, paths_per_invocation: self.paths_per_invocation, ..*push };
            let invocations = regen::invocations(count, self.paths_per_invocation);
            if let Some(c) = &self.compaction {
                batch.fill(&c.chunk_counts, 0)?;
            }
            batch.dispatch(&self.kernel, self.kernel.groups_for(invocations), bytemuck::bytes_of(&p))?;
            if let Some(c) = &self.compaction {
                c.scan.record(batch)?;
                let cp = CompactPush {
                    first_path: first,
                    count,
                    light_paths: self.light_paths,
                    capacity: c.capacity,
                    slots: self.slots,
                    b_stride: c.b_stride,
                    iteration: push.iteration,
                };
                batch.dispatch(&c.kernel, c.kernel.groups_for(count), bytemuck::bytes_of(&cp))?;
            }
            first += count;
        }
        Ok(())
    }

    /// The buffers the pass owns (the scratch slots and the chunk's counts).
    pub fn buffers(&self) -> Vec<&Buffer> {
        match &self.compaction {
            Some(c) => {
                let mut b = vec![&c.scratch[0], &c.scratch[1], &c.chunk_counts];
                b.extend(c.scan.buffers());
                b
            }
            None => vec![],
        }
    }

    pub fn info(&self) -> PassInfo {
        let v = self.variant;
        let what = match (v.store_vertices, v.connect_to_camera) {
            (true, true) => "store vertices, connect to the camera",
            (true, false) => "store vertices",
            (false, true) => "connect to the camera (splats), no vertex store",
            (false, false) => "trace only",
        };
        let chunks = self.light_paths.div_ceil(self.chunk_paths);
        let mut detail = format!(
            "light_subpath.comp: {what}; {} light subpaths in {chunks} chunk(s) of at most {}",
            self.light_paths, self.chunk_paths
        );
        if let Some(c) = &self.compaction {
            detail += &format!(
                "; exclusive_scan.comp, light_vertex_compact.comp: the vertices into the store (capacity {})",
                c.capacity
            );
        }
        PassInfo { name: NAME, detail }
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
