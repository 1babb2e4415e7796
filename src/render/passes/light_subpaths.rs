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
//! The store itself, its sizes and its growth: src/render/light_vertex_store.rs.

use anyhow::{Context, Result};
use bytemuck::{Pod, Zeroable};

use super::exclusive_scan::ExclusiveScan;
use super::PassContext;
use super::PassInfo;
use crate::gpu::{Batch, Bind, Buffer, Kernel};
use crate::render::gpu_types::GpuPush;
use crate::render::light_vertex_store::{LightVertexPlan, LightVertexStore};
use crate::render::regen;
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
        // Chunks of at most chunk_paths, shorter where the batch's budget asks: the image
        // does not depend on the chunk size.
        batch.record_paths(&self.kernel, self.light_paths, self.chunk_paths, |batch, first, count| {
            self.record_chunk(batch, push, first, count)
        })
    }

    /// One chunk: light subpaths `first .. first + count`.
    fn record_chunk(&self, batch: &mut Batch, push: &GpuPush, first: u32, count: u32) -> Result<()> {
        let p = GpuPush { first_path: first, count, paths_per_invocation: self.paths_per_invocation, ..*push };
        let invocations = regen::invocations(count, self.paths_per_invocation);
        if let Some(c) = &self.compaction {
            batch.fill(&c.chunk_counts, 0)?;
        }
        batch.dispatch_paths(&self.kernel, self.kernel.groups_for(invocations), bytemuck::bytes_of(&p), count)?;
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
            batch.dispatch_paths(&c.kernel, c.kernel.groups_for(count), bytemuck::bytes_of(&cp), count)?;
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
