//! The light-vertex-prefix pass of the light-vertex cache (Davidovic et al. 2014,
//! "Progressive Light Transport Simulation on the GPU: Survey and Improvements"): with
//! `--connect cache`, camera vertices connect to vertices drawn uniformly from all light
//! subpaths' stored vertices instead of those of light subpath p = their pixel. After the
//! light pass has copied the per-path vertex counts into `light_vertex_prefix`, this pass
//! scans them in place into each path's first index among all stored vertices (entry N_L:
//! their total), then writes every stored vertex's slot to `light_vertex_dense` in path
//! order (glsl/lv_cache_compact.comp), so a draw is one load.

use std::sync::Arc;

use anyhow::Result;
use bytemuck::{Pod, Zeroable};

use super::exclusive_scan::{ExclusiveScan, ScanPlan};
use super::light_subpaths::{LightVertexPlan, LightVertexStore};
use super::PassInfo;
use crate::gpu::{Batch, Bind, Buffer, Gpu, Kernel};
use crate::render::addresses::FrameAddresses;
use crate::render::sizes::{Access, BufferSize};
use crate::render::variants::workgroup_defines;

/// The name profiles report.
pub const NAME: &str = "light-vertex prefix";

/// The cache's sizes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LightVertexCachePlan {
    /// N_L + 1 u32.
    pub prefix: BufferSize,
    /// One u32 per store slot.
    pub dense: BufferSize,
    pub scan: ScanPlan,
}

impl LightVertexCachePlan {
    /// The cache over `store`, its dense list reached as `dense_access`.
    pub fn new(store: &LightVertexPlan, dense_access: Access) -> LightVertexCachePlan {
        let n = store.light_paths as u64 + 1;
        LightVertexCachePlan {
            prefix: BufferSize::new("light_vertex_prefix", n * 4),
            dense: BufferSize::new("light_vertex_dense", store.capacity * 4).reached(dense_access),
            scan: ScanPlan::new(store.light_paths + 1, "light_vertex_prefix_scan_scratch"),
        }
    }

    pub fn buffers(&self) -> Vec<BufferSize> {
        vec![self.prefix, self.dense, self.scan.scratch]
    }
}

/// Push constants of glsl/lv_cache_compact.comp (its `CompactPush`).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct CompactPush {
    light_paths: u32,
    slots: u32,
}

/// The cache's buffers and the pass that fills them.
pub struct LightVertexCache {
    /// Binding `light_vertex_prefix`.
    pub prefix: Buffer,
    /// `light_vertex_dense`: by device address (src/render/addresses.rs) or as a binding.
    pub dense: Buffer,
    scan: ExclusiveScan,
    compact: Kernel,
    light_paths: u32,
    slots: u32,
}

impl LightVertexCache {
    /// The cache of `plan` over `store`; the dense list's address goes to `addresses`.
    pub fn new(
        gpu: &Arc<Gpu>,
        store: &LightVertexStore,
        plan: &LightVertexCachePlan,
        addresses: &FrameAddresses,
    ) -> Result<LightVertexCache> {
        let prefix = plan.prefix.zeroed(gpu)?;
        let dense = plan.dense.zeroed(gpu)?;
        addresses.set(|a| &mut a.light_vertex_dense, &dense)?;
        let scan = ExclusiveScan::with_plan(gpu, &prefix, &plan.scan)?;
        let compact = gpu.kernel(
            "lv_cache_compact.comp",
            &workgroup_defines().flag("DEVICE_ADDRESSES", addresses.enabled()).pairs(),
            &[Bind::own_u32(&store.counts), Bind::own_u32(&prefix), Bind::own_u32(&dense), addresses.bind()],
        )?;
        Ok(LightVertexCache {
            prefix,
            dense,
            scan,
            compact,
            light_paths: store.light_paths,
            slots: store.slots_per_path,
        })
    }

    pub fn record(&self, batch: &mut Batch) -> Result<()> {
        batch.begin_pass(NAME);
        self.scan.record(batch)?;
        let p = CompactPush { light_paths: self.light_paths, slots: self.slots };
        batch.dispatch(&self.compact, self.compact.groups_for(self.light_paths), bytemuck::bytes_of(&p))
    }

    pub fn buffers(&self) -> Vec<&Buffer> {
        let mut b = vec![&self.prefix, &self.dense];
        b.extend(self.scan.buffers());
        b
    }

    pub fn info(&self) -> PassInfo {
        PassInfo {
            name: NAME,
            detail: "exclusive_scan.comp: prefix sum of the per-path vertex counts; lv_cache_compact.comp: the stored vertices' slots in one list (light-vertex cache)".into(),
        }
    }
}
