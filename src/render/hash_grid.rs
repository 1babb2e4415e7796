//! The hash grid over an iteration's light vertices (stage 2 of ../shared/DESIGN.md),
//! built on the GPU every iteration with no host round trip: SmallVCM's counting sort
//! (../shared/SCENES.md 4.3) as passes recorded into the caller's batch:
//!
//! 1. count (`hash_grid_count.comp`): one invocation per light path, over its stored
//!    vertices; each does `rank = atomicAdd(cell_start[b], 1)` on its bucket b and keeps
//!    (b, rank);
//! 2. exclusive prefix sum of `cell_start[0..=num_buckets]` in place ([`ExclusiveScan`],
//!    `hash_grid_scan.comp`), so `cell_start[num_buckets]` is the vertex total;
//! 3. scatter (`hash_grid_scatter.comp`): one invocation per light path; each stored
//!    vertex writes (position bits, slot) to `cell_points[cell_start[b] + rank]`, no
//!    atomics; a query's radius test reads one contiguous `uvec4` per candidate instead
//!    of an index and then the scattered store;
//! 4. sort (`hash_grid_sort.comp`): one invocation per bucket sorts its entries ascending
//!    by slot (sorting networks up to 16 entries, then insertion sort, heapsort past 32),
//!    so the result does not depend on the order the atomics happened in: builds are
//!    bit-identical.
//!
//! Queries are in `glsl/hash_grid.glsl`. Details and measurements: docs/hash-grid.md.

use std::sync::Arc;

use anyhow::{bail, Result};
use bytemuck::{Pod, Zeroable};

use crate::gpu::{Batch, Buffer, Gpu, Kernel};

/// Elements per workgroup of `hash_grid_scan.comp` (64 invocations x 4).
pub const SCAN_BLOCK: u32 = 256;
/// Invocations per workgroup of the build and sort kernels.
const LOCAL: u32 = 64;
/// Workgroups per dimension that every device accepts (maxComputeWorkGroupCount minimum);
/// larger dispatches are folded into 2D (`hash_grid_group_index()` in hash_grid.glsl).
const MAX_GROUPS_X: u32 = 65_535;
/// Bytes per light vertex in the `lv_a` buffer (two vec4, the position in the first).
const LV_A_BYTES: u64 = 32;

/// Workgroup counts covering `groups` groups, folded into 2D past 65,535.
fn folded(groups: u32) -> [u32; 3] {
    if groups <= MAX_GROUPS_X {
        [groups, 1, 1]
    } else {
        [MAX_GROUPS_X, groups.div_ceil(MAX_GROUPS_X), 1]
    }
}

fn check_range(gpu: &Gpu, what: &str, bytes: u64) -> Result<()> {
    let max = gpu.limits.max_storage_buffer_range as u64;
    if bytes > max {
        bail!(
            "hash grid: {what} needs {bytes} bytes but this device binds at most {max} bytes per buffer \
             (maxStorageBufferRange); lower the resolution or the max path length"
        );
    }
    Ok(())
}

/// Push constants of the build passes (`HASH_GRID_BUILD_PUSH` in glsl/hash_grid.glsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct BuildPush {
    origin: [f32; 3],
    radius: f32,
    light_paths: u32,
    slots: u32,
    num_buckets: u32,
    _pad: u32,
}

/// Push constants of `hash_grid_scan.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct ScanPush {
    n: u32,
    offset: u32,
    sums_offset: u32,
    _pad: u32,
}

/// One level of the scan: `n` elements at element `offset` (of the target buffer for
/// level 0, of the scratch buffer above).
#[derive(Clone, Copy, Debug)]
struct Level {
    n: u32,
    offset: u32,
}

/// In-place exclusive prefix sum of the first `n` `u32`s of a buffer, on the GPU, for any
/// `n` >= 1 the buffer range allows (sums wrap modulo 2^32). A multi-level scan: each
/// level scans blocks of [`SCAN_BLOCK`] elements in shared memory and writes the block
/// totals to the next level, until one block remains; then the scanned totals are added
/// back down. No subgroup operations (any subgroup width).
pub struct ExclusiveScan {
    scan_target: Kernel,
    add_target: Kernel,
    scan_scratch: Kernel,
    add_scratch: Kernel,
    levels: Vec<Level>,
    _scratch: Buffer,
}

impl ExclusiveScan {
    /// Prepares the scan of `data[0..n]` (kernels and scratch are created here, once).
    pub fn new(gpu: &Arc<Gpu>, data: &Buffer, n: u32) -> Result<ExclusiveScan> {
        if n == 0 {
            bail!("exclusive scan of zero elements");
        }
        if data.size() < 4 * n as u64 {
            bail!("exclusive scan of {n} elements but buffer {:?} holds {} bytes", data.name(), data.size());
        }
        check_range(gpu, "the scan input", 4 * n as u64)?;
        // levels[0] is the input; each next level holds the previous one's block totals;
        // the last holds one element (the grand total, never scanned).
        let mut levels = vec![Level { n, offset: 0 }];
        let mut scratch_len = 0u32;
        loop {
            let next = levels.last().unwrap().n.div_ceil(SCAN_BLOCK);
            levels.push(Level { n: next, offset: scratch_len });
            scratch_len += next;
            if next == 1 {
                break;
            }
        }
        let scratch = gpu.buffer_zeroed::<u32>("hash_grid_scan_scratch", scratch_len as usize)?;
        Ok(ExclusiveScan {
            scan_target: gpu.kernel("hash_grid_scan.comp", &[("ADD", "0")], &[data, &scratch])?,
            add_target: gpu.kernel("hash_grid_scan.comp", &[("ADD", "1")], &[data, &scratch])?,
            scan_scratch: gpu.kernel("hash_grid_scan.comp", &[("ADD", "0")], &[&scratch, &scratch])?,
            add_scratch: gpu.kernel("hash_grid_scan.comp", &[("ADD", "1")], &[&scratch, &scratch])?,
            levels,
            _scratch: scratch,
        })
    }

    /// Number of elements scanned.
    pub fn len(&self) -> u32 {
        self.levels[0].n
    }

    /// The same scan with its kernels named `name` in profiles.
    pub fn labelled(self, name: &str) -> ExclusiveScan {
        ExclusiveScan {
            scan_target: self.scan_target.labelled(name),
            add_target: self.add_target.labelled(name),
            scan_scratch: self.scan_scratch.labelled(name),
            add_scratch: self.add_scratch.labelled(name),
            ..self
        }
    }

    /// The scratch buffer of the block totals (for buffer listings).
    pub fn buffers(&self) -> Vec<&Buffer> {
        vec![&self._scratch]
    }

    /// Always false (a scan has at least one element).
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Records the scan's dispatches (2 L - 1 for L levels of 256-element blocks).
    pub fn record(&self, batch: &mut Batch) -> Result<()> {
        let scanned = self.levels.len() - 1;
        let push = |k: usize| ScanPush {
            n: self.levels[k].n,
            offset: self.levels[k].offset,
            sums_offset: self.levels[k + 1].offset,
            _pad: 0,
        };
        for k in 0..scanned {
            let kernel = if k == 0 { &self.scan_target } else { &self.scan_scratch };
            let groups = folded(self.levels[k].n.div_ceil(SCAN_BLOCK));
            batch.dispatch(kernel, groups, bytemuck::bytes_of(&push(k)))?;
        }
        // The top scanned level is a single block, already final.
        for k in (0..scanned.saturating_sub(1)).rev() {
            let kernel = if k == 0 { &self.add_target } else { &self.add_scratch };
            let groups = folded(self.levels[k].n.div_ceil(SCAN_BLOCK));
            batch.dispatch(kernel, groups, bytemuck::bytes_of(&push(k)))?;
        }
        Ok(())
    }
}

/// The GPU hash grid over the light-vertex store. After [`HashGrid::record_build`] has
/// run, bucket `b` holds the valid light vertices
/// `cell_points[cell_start[b] .. cell_start[b + 1]]`, ascending by slot, and
/// `cell_start[num_buckets]` is the number of valid vertices.
pub struct HashGrid {
    /// `num_buckets + 1` `u32`: exclusive prefix sum of the bucket sizes.
    pub cell_start: Buffer,
    /// `light_paths * slots` `uvec4` (the most vertices there can be), by bucket: entry i
    /// is (`floatBitsToUint` of a vertex's position, its slot). What the camera kernel
    /// reads (docs/hash-grid.md).
    pub cell_points: Buffer,
    /// Per slot: (bucket, arrival rank in the bucket) from the count pass.
    _keys: Buffer,
    count: Kernel,
    scatter: Kernel,
    sort: Kernel,
    scan: ExclusiveScan,
    light_paths: u32,
    slots: u32,
    num_buckets: u32,
}

impl HashGrid {
    /// A grid over the light-vertex store `lv_a` (`vec4[]`, two per slot, position in
    /// the first) / `lv_count` (`uint` per light path) of `light_paths` paths with `slots`
    /// slots each, hashing into `num_buckets` buckets (SmallVCM: one per light path; the
    /// renderer: bidir::grid_buckets, four per light path as a power of two).
    pub fn new(
        gpu: &Arc<Gpu>,
        lv_a: &Buffer,
        lv_count: &Buffer,
        light_paths: u32,
        slots: u32,
        num_buckets: u32,
    ) -> Result<HashGrid> {
        if light_paths == 0 || slots == 0 || num_buckets == 0 {
            bail!(
                "hash grid: light paths ({light_paths}), slots per path ({slots}) and buckets ({num_buckets}) must be at least 1"
            );
        }
        let total_slots = light_paths as u64 * slots as u64;
        if total_slots > u32::MAX as u64 || num_buckets == u32::MAX {
            bail!(
                "hash grid: {light_paths} light paths x {slots} slots or {num_buckets} buckets exceed 32-bit indices"
            );
        }
        if lv_a.size() < total_slots * LV_A_BYTES {
            bail!(
                "hash grid: buffer {:?} has {} bytes, {light_paths} x {slots} light vertices need {}",
                lv_a.name(),
                lv_a.size(),
                total_slots * LV_A_BYTES
            );
        }
        if lv_count.size() < 4 * light_paths as u64 {
            bail!(
                "hash grid: buffer {:?} has {} bytes, {light_paths} path counts need more",
                lv_count.name(),
                lv_count.size()
            );
        }
        check_range(gpu, "the light-vertex store (lv_a)", total_slots * LV_A_BYTES)?;
        check_range(gpu, "the grid's keys (two u32 per light-vertex slot)", total_slots * 8)?;
        check_range(gpu, "the grid's points (one uvec4 per light-vertex slot)", total_slots * 16)?;
        check_range(gpu, "cell_start (one u32 per bucket + 1)", (num_buckets as u64 + 1) * 4)?;
        let n = total_slots as usize;
        let cell_start = gpu.buffer_zeroed::<u32>("grid_start", num_buckets as usize + 1)?;
        let keys = gpu.buffer_zeroed::<[u32; 2]>("grid_keys", n)?;
        let cell_points = gpu.buffer_zeroed::<[u32; 4]>("grid_points", n)?;
        let count = gpu.kernel("hash_grid_count.comp", &[], &[lv_a, lv_count, &cell_start, &keys])?;
        let scatter = gpu.kernel("hash_grid_scatter.comp", &[], &[lv_a, lv_count, &cell_start, &keys, &cell_points])?;
        let sort = gpu.kernel("hash_grid_sort.comp", &[], &[&cell_start, &cell_points])?;
        let scan = ExclusiveScan::new(gpu, &cell_start, num_buckets + 1)?;
        Ok(HashGrid {
            cell_start,
            cell_points,
            _keys: keys,
            count,
            scatter,
            sort,
            scan,
            light_paths,
            slots,
            num_buckets,
        })
    }

    /// Records the whole build for merge radius `radius` (cells of side 2 `radius`) and
    /// grid origin `origin` into `batch` (no submit). It reads the light-vertex store as
    /// the batch's earlier dispatches left it.
    pub fn record_build(&self, batch: &mut Batch, radius: f32, origin: [f32; 3]) -> Result<()> {
        if !(radius.is_finite() && radius > 0.0) {
            bail!("hash grid: merge radius {radius} must be positive and finite");
        }
        if !origin.iter().all(|c| c.is_finite()) {
            bail!("hash grid: origin {origin:?} must be finite");
        }
        let push = BuildPush {
            origin,
            radius,
            light_paths: self.light_paths,
            slots: self.slots,
            num_buckets: self.num_buckets,
            _pad: 0,
        };
        let path_groups = folded(self.light_paths.div_ceil(LOCAL));
        let push = bytemuck::bytes_of(&push);
        batch.fill(&self.cell_start, 0)?;
        batch.dispatch(&self.count, path_groups, push)?;
        self.scan.record(batch)?;
        batch.dispatch(&self.scatter, path_groups, push)?;
        batch.dispatch(&self.sort, folded(self.num_buckets.div_ceil(LOCAL)), push)
    }

    pub fn num_buckets(&self) -> u32 {
        self.num_buckets
    }

    /// Every buffer the grid owns (for `vkvcm render --verbose`).
    pub fn buffers(&self) -> Vec<&Buffer> {
        vec![&self.cell_start, &self.cell_points, &self._keys, &self.scan._scratch]
    }

    pub fn light_paths(&self) -> u32 {
        self.light_paths
    }

    pub fn slots(&self) -> u32 {
        self.slots
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn folding_covers_every_group() {
        for g in [1u32, 65_535, 65_536, 200_000, u32::MAX / 64] {
            let [x, y, z] = folded(g);
            assert!(x <= MAX_GROUPS_X && y <= MAX_GROUPS_X && z == 1);
            assert!(x as u64 * y as u64 >= g as u64);
        }
    }

    #[test]
    fn push_layouts() {
        assert_eq!(std::mem::size_of::<BuildPush>(), 32);
        assert_eq!(std::mem::offset_of!(BuildPush, radius), 12);
        assert_eq!(std::mem::offset_of!(BuildPush, num_buckets), 24);
        assert_eq!(std::mem::size_of::<ScanPush>(), 16);
    }
}
