//! The grid-build pass: the hash grid over an iteration's light vertices (docs/design.md,
//! docs/hash-grid.md), built on the GPU every iteration with no host round trip, as
//! SmallVCM's counting sort (docs/smallvcm.md, the hash grid) in four steps:
//!
//! 1. count (`hash_grid_count.comp`): one invocation per light path, over its stored
//!    vertices (`light_vertex_offsets[p] .. light_vertex_offsets[p + 1]`); each does
//!    `rank = atomicAdd(bucket_start[b], 1)` on its bucket b and keeps (b, rank);
//! 2. exclusive prefix sum of `grid_start[0..=num_buckets]` in place
//!    ([`super::exclusive_scan`]), so `grid_start[num_buckets]` is the vertex total;
//! 3. scatter (`hash_grid_scatter.comp`): one invocation per light path; each stored
//!    vertex i writes (position bits, i) to `grid_points[grid_start[b] + rank]`, no
//!    atomics; a query's radius test reads one contiguous `uvec4` per candidate instead
//!    of an index and then the scattered store;
//! 4. sort (`hash_grid_sort.comp`): one invocation per bucket sorts its entries ascending
//!    by vertex index, so the result does not depend on the order the atomics happened in:
//!    builds are bit-identical.
//!
//! Queries are in `glsl/hash_grid.glsl`.

use std::sync::Arc;

use anyhow::{bail, Result};
use bytemuck::{Pod, Zeroable};

use super::exclusive_scan::{ExclusiveScan, ScanPlan};
use super::PassInfo;
use crate::gpu::{Batch, Bind, Buffer, Gpu, Kernel};
use crate::render::addresses::FrameAddresses;
use crate::render::light_vertex_store::LIGHT_VERTEX_A_BYTES;
use crate::render::sizes::{check_sizes, Access, BufferSize, SizeLimits};
use crate::render::variants::workgroup_defines;

/// The name profiles report.
pub const NAME: &str = "grid build";

/// Hash-grid buckets per light subpath. SmallVCM has one; four cut the candidates that a
/// merge query rejects (other cells hashed into the same buckets); more cost more scan
/// and sort than they save (docs/performance.md, "Defaults that matter for speed, and why").
const GRID_BUCKETS_PER_LIGHT_PATH: u64 = 4;

/// Most hash-grid buckets: `grid_start` (one u32 per bucket + 1) then stays below
/// 2^27 bytes, the smallest maxStorageBufferRange Vulkan allows.
const MAX_GRID_BUCKETS: u64 = 1 << 24;

/// The bucket count of the renderer's hash grid: GRID_BUCKETS_PER_LIGHT_PATH per light
/// subpath, rounded up to a power of two (hash_grid.glsl then masks instead of dividing),
/// at most MAX_GRID_BUCKETS.
pub fn grid_buckets(light_paths: u64) -> u32 {
    (light_paths.max(1) * GRID_BUCKETS_PER_LIGHT_PATH).next_power_of_two().min(MAX_GRID_BUCKETS) as u32
}

/// Bytes per light vertex of `grid_points` (position bits and index, a uvec4).
pub const GRID_POINT_BYTES: u64 = 16;
/// Bytes per light vertex of `grid_keys` (bucket and rank, a uvec2).
pub const GRID_KEY_BYTES: u64 = 8;

/// The sizes of a hash grid over a light-vertex store of `capacity` vertices.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct GridPlan {
    pub light_paths: u32,
    pub capacity: u64,
    pub buckets: u32,
    /// `buckets + 1` u32: the exclusive prefix sum of the bucket sizes.
    pub start: BufferSize,
    /// One uvec4 per vertex the store holds, by bucket.
    pub points: BufferSize,
    /// Per vertex: (bucket, arrival rank in the bucket) from the count step.
    pub keys: BufferSize,
    pub scan: ScanPlan,
}

impl GridPlan {
    /// The sizes (what [`HashGrid::with_plan`] accepts it checks there).
    pub fn new(light_paths: u32, capacity: u64, buckets: u32) -> GridPlan {
        let mut plan = GridPlan {
            light_paths,
            capacity,
            buckets,
            start: BufferSize::new("grid_start", (buckets as u64 + 1) * 4),
            points: BufferSize::new("grid_points", 0),
            keys: BufferSize::new("grid_keys", 0),
            scan: ScanPlan::new(buckets.saturating_add(1), "grid_start_scan_scratch"),
        };
        plan.set_capacity(capacity);
        plan
    }

    /// Resizes the grid for a store of `capacity` vertices.
    pub fn set_capacity(&mut self, capacity: u64) {
        self.capacity = capacity;
        self.points.bytes = capacity.saturating_mul(GRID_POINT_BYTES);
        self.keys.bytes = capacity.saturating_mul(GRID_KEY_BYTES);
    }

    /// This plan with the entries reached as `points` and the keys as `keys` (how the
    /// render reaches them: src/render/plan.rs).
    pub fn reached(self, points: Access, keys: Access) -> GridPlan {
        GridPlan { points: self.points.reached(points), keys: self.keys.reached(keys), ..self }
    }

    pub fn buffers(&self) -> Vec<BufferSize> {
        vec![self.start, self.points, self.keys, self.scan.scratch]
    }
}

/// Push constants of the build steps (`HASH_GRID_BUILD_PUSH` in glsl/hash_grid.glsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct BuildPush {
    origin: [f32; 3],
    radius: f32,
    light_paths: u32,
    capacity: u32,
    num_buckets: u32,
    _pad: u32,
}

/// The GPU hash grid over the light-vertex store. After [`HashGrid::record_build`] has
/// run, bucket `b` holds the stored light vertices
/// `cell_points[cell_start[b] .. cell_start[b + 1]]`, ascending by index, and
/// `cell_start[num_buckets]` is the number of stored vertices.
pub struct HashGrid {
    /// `num_buckets + 1` `u32` (binding `grid_start`).
    pub cell_start: Buffer,
    /// (`floatBitsToUint` of a vertex's position, its index) by bucket (binding
    /// `grid_points`): what the camera kernel reads (docs/hash-grid.md).
    pub cell_points: Buffer,
    keys: Buffer,
    /// The addresses the kernels read, when the grid was built on its own
    /// ([`HashGrid::new`]); a render's are its film's.
    own_addresses: Option<FrameAddresses>,
    count: Kernel,
    scatter: Kernel,
    sort: Kernel,
    scan: ExclusiveScan,
    light_paths: u32,
    capacity: u32,
    num_buckets: u32,
}

impl HashGrid {
    /// A grid over the light-vertex store `lv_a` (`vec4[]`, two per vertex, position in
    /// the first) of `capacity` vertices, where light path p's vertices are `offsets[p]
    /// .. offsets[p + 1]` (`uint[]`, `light_paths` + 1 of them), hashing into
    /// `num_buckets` buckets (SmallVCM: one per light path; the renderer:
    /// [`grid_buckets`]).
    pub fn new(
        gpu: &Arc<Gpu>,
        lv_a: &Buffer,
        offsets: &Buffer,
        light_paths: u32,
        capacity: u64,
        num_buckets: u32,
    ) -> Result<HashGrid> {
        let addresses = FrameAddresses::new(gpu)?;
        addresses.set(|a| &mut a.light_vertices_a, lv_a)?;
        addresses.set(|a| &mut a.light_vertex_offsets, offsets)?;
        let mut grid =
            Self::with_plan(gpu, lv_a, offsets, &GridPlan::new(light_paths, capacity, num_buckets), &addresses)?;
        grid.own_addresses = Some(addresses);
        Ok(grid)
    }

    /// The grid that `plan` describes, over the store whose address (with device
    /// addresses) `addresses` holds; the grid's own buffers are registered there.
    pub fn with_plan(
        gpu: &Arc<Gpu>,
        lv_a: &Buffer,
        offsets: &Buffer,
        plan: &GridPlan,
        addresses: &FrameAddresses,
    ) -> Result<HashGrid> {
        let (light_paths, capacity, buckets) = (plan.light_paths, plan.capacity, plan.buckets);
        if light_paths == 0 || capacity == 0 || buckets == 0 {
            bail!(
                "hash grid: light paths ({light_paths}), store capacity ({capacity}) and buckets ({buckets}) must be at least 1"
            );
        }
        if capacity > u32::MAX as u64 || light_paths == u32::MAX || buckets == u32::MAX {
            bail!("hash grid: {capacity} light vertices, {light_paths} light paths or {buckets} buckets exceed 32-bit indices");
        }
        if lv_a.size() < capacity * LIGHT_VERTEX_A_BYTES {
            bail!(
                "hash grid: buffer {:?} has {} bytes, {capacity} light vertices need {}",
                lv_a.name(),
                lv_a.size(),
                capacity * LIGHT_VERTEX_A_BYTES
            );
        }
        if offsets.size() < 4 * (light_paths as u64 + 1) {
            bail!(
                "hash grid: buffer {:?} has {} bytes, the offsets of {light_paths} light paths need more",
                offsets.name(),
                offsets.size()
            );
        }
        check_sizes(&plan.buffers(), &SizeLimits::of(gpu), "the hash grid")?;
        let cell_start = plan.start.zeroed(gpu)?;
        let keys = plan.keys.zeroed(gpu)?;
        let cell_points = plan.points.zeroed(gpu)?;
        addresses.set(|a| &mut a.grid_keys, &keys)?;
        addresses.set(|a| &mut a.grid_points, &cell_points)?;
        let binds = [
            Bind::vec4("light_vertices_a", lv_a),
            Bind::u32("light_vertex_offsets", offsets),
            Bind::u32("grid_start", &cell_start),
            Bind::vec4("grid_keys", &keys),
            Bind::vec4("grid_points", &cell_points),
            addresses.bind(),
        ];
        let defines = workgroup_defines().flag("DEVICE_ADDRESSES", addresses.enabled());
        let count = gpu.kernel("hash_grid_count.comp", &defines.pairs(), &binds)?;
        let scatter = gpu.kernel("hash_grid_scatter.comp", &defines.pairs(), &binds)?;
        let sort = gpu.kernel("hash_grid_sort.comp", &defines.pairs(), &binds)?;
        let scan = ExclusiveScan::with_plan(gpu, &cell_start, &plan.scan)?;
        Ok(HashGrid {
            cell_start,
            cell_points,
            keys,
            own_addresses: None,
            count,
            scatter,
            sort,
            scan,
            light_paths,
            capacity: capacity as u32,
            num_buckets: plan.buckets,
        })
    }

    /// Records the whole build for merge radius `radius` (cells of side 2 `radius`) and
    /// grid origin `origin` into `batch` (no submit), as the pass [`NAME`]. It reads the
    /// light-vertex store as the batch's earlier dispatches left it.
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
            capacity: self.capacity,
            num_buckets: self.num_buckets,
            _pad: 0,
        };
        let push = bytemuck::bytes_of(&push);
        batch.begin_pass(NAME);
        batch.fill(&self.cell_start, 0)?;
        batch.dispatch(&self.count, self.count.groups_for(self.light_paths), push)?;
        self.scan.record(batch)?;
        batch.dispatch(&self.scatter, self.scatter.groups_for(self.light_paths), push)?;
        batch.dispatch(&self.sort, self.sort.groups_for(self.num_buckets), push)
    }

    pub fn num_buckets(&self) -> u32 {
        self.num_buckets
    }

    /// Every buffer the grid owns (for `vkvcm render --verbose`).
    pub fn buffers(&self) -> Vec<&Buffer> {
        let mut b = vec![&self.cell_start, &self.cell_points, &self.keys];
        b.extend(self.scan.buffers());
        b
    }

    pub fn light_paths(&self) -> u32 {
        self.light_paths
    }

    /// Vertices of the store it is built over.
    pub fn capacity(&self) -> u32 {
        self.capacity
    }

    pub fn info(&self) -> PassInfo {
        PassInfo {
            name: NAME,
            detail: format!(
                "hash grid over the light vertices in {} buckets (count, scan, scatter, sort)",
                self.num_buckets
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_buckets_are_powers_of_two_per_light_path_within_the_binding() {
        assert_eq!(grid_buckets(65_536), 262_144);
        assert_eq!(grid_buckets(100), 512);
        assert_eq!(grid_buckets(1), 4);
        assert_eq!(grid_buckets(0), 4);
        // 4K: 4 x 8,294,400 would round up to 2^25; capped at 2^24 (64 MiB of grid_start).
        assert_eq!(grid_buckets(3840 * 2160), 1 << 24);
        assert_eq!(grid_buckets(u32::MAX as u64), 1 << 24);
    }

    #[test]
    fn push_layout() {
        assert_eq!(std::mem::size_of::<BuildPush>(), 32);
        assert_eq!(std::mem::offset_of!(BuildPush, radius), 12);
        assert_eq!(std::mem::offset_of!(BuildPush, num_buckets), 24);
    }
}
