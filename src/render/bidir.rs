//! The light-subpath estimators: light tracing (`lt`), bidirectional path tracing
//! (`bpt`), progressive and bidirectional photon mapping (`ppm`, `bpm`) and vertex
//! connection and merging (`vcm`). Per iteration: glsl/light_subpath.comp (one invocation
//! per light subpath), the hash-grid build over the light vertices when merging, then
//! glsl/camera_subpath.comp (one per pixel; it also takes the splats into the film) or,
//! for `lt`, glsl/accumulate.comp.
//!
//! Light vertices use SmallVCM's layout: light subpath p's vertices live in fixed slots
//! (see glsl/vcm.glsl). Vertex connections ([`Connect`]) go either to the vertices of
//! light subpath p = this pixel (SmallVCM) or to vertices drawn uniformly from the whole
//! iteration's store, a light-vertex cache (Davidovic et al. 2014, "Progressive Light
//! Transport Simulation on the GPU: Survey and Improvements"); for the cache, an exclusive
//! prefix sum of the per-path vertex counts is built after the light pass, and from it a
//! dense list of the stored vertices' slots (glsl/lv_cache_compact.comp).

use std::sync::Arc;

use anyhow::{bail, Result};

use super::film::Film;
use super::gpu_types::GpuPush;
use super::hash_grid::{ExclusiveScan, HashGrid};
use super::radius::RadiusSchedule;
use super::reads::Reads;
use super::regen;
use super::scene_gpu::{define_refs, SceneGpu};
use crate::gpu::{groups_2d, Batch, Binding, Buffer, Gpu, Kernel};

/// Which light-subpath estimator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BidirMode {
    LightTracing,
    Bpt,
    Ppm,
    Bpm,
    Vcm,
}

impl BidirMode {
    /// Vertex connection: next-event estimation, light-vertex connections, and light
    /// vertices connected to the camera (with MIS).
    pub fn use_vc(self) -> bool {
        matches!(self, BidirMode::Bpt | BidirMode::Vcm)
    }

    /// Vertex merging through the hash grid.
    pub fn use_vm(self) -> bool {
        matches!(self, BidirMode::Ppm | BidirMode::Bpm | BidirMode::Vcm)
    }

    fn stores_vertices(self) -> bool {
        self != BidirMode::LightTracing
    }
}

/// Where a camera vertex's vertex connections go (bpt, vcm). Every choice is unbiased
/// with the same MIS weights: see glsl/camera_subpath.comp and docs/estimators.md.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Connect {
    /// To every stored vertex of light subpath p = this pixel (SmallVCM).
    Path,
    /// To this many vertices drawn uniformly from all light subpaths' stored vertices
    /// (light-vertex cache, Davidovic et al. 2014), each weighted by
    /// (stored vertices) / (light subpaths x this many).
    Cache(u32),
}

/// Default light vertices per camera vertex of `--connect cache`: 1 measured better at
/// equal time than 2 and 4 (docs/estimators.md).
pub const DEFAULT_CACHE_CONNECTIONS: u32 = 1;

impl Connect {
    /// The default for `algorithm` (`vkvcm render --connect`): for bpt the cache with
    /// [`DEFAULT_CACHE_CONNECTIONS`], measured slightly better at equal time than `Path`
    /// (docs/estimators.md); vcm keeps SmallVCM's layout (not measured); `Path` (ignored)
    /// for the rest.
    pub fn default_for(algorithm: super::Algorithm) -> Connect {
        match algorithm {
            super::Algorithm::Bpt => Connect::Cache(DEFAULT_CACHE_CONNECTIONS),
            _ => Connect::Path,
        }
    }

    /// `path` or `cache:N`, as settings and saved renders show it.
    pub fn name(self) -> String {
        match self {
            Connect::Path => "path".into(),
            Connect::Cache(n) => format!("cache:{n}"),
        }
    }

    /// Parses [`Connect::name`]'s output.
    pub fn parse(s: &str) -> Option<Connect> {
        match s {
            "path" => Some(Connect::Path),
            _ => s.strip_prefix("cache:")?.parse().ok().filter(|&n| n > 0).map(Connect::Cache),
        }
    }
}

pub struct Bidir {
    mode: BidirMode,
    light: Kernel,
    resolve: Kernel,
    grid: Option<HashGrid>,
    /// Light-vertex cache: the passes between the light and camera kernels.
    cache: Option<LvCache>,
    radius: RadiusSchedule,
    grid_origin: [f32; 3],
    pixels: u32,
    light_paths: u32,
    /// Paths per invocation of the light and camera kernels (src/render/regen.rs).
    paths_per_invocation: u32,
    // Owned so they outlive the kernels' descriptor sets.
    _buffers: Vec<Buffer>,
}

/// The light-vertex cache's passes: the scan turning `lv_prefix` into prefix sums of the
/// per-path counts, then the compaction writing every stored vertex's slot to
/// `light_vertex_dense` in path order.
struct LvCache {
    scan: ExclusiveScan,
    compact: Kernel,
    slots: u32,
}

/// Push constants of glsl/lv_cache_compact.comp (its `CompactPush`).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct CompactPush {
    light_paths: u32,
    slots: u32,
}

/// Bytes of one light-vertex half (lv_a or lv_b) per vertex.
const LV_HALF_BYTES: u64 = 32;

/// Hash-grid buckets per light subpath. SmallVCM has one; four cut the candidates that a
/// merge query rejects (other cells hashed into the same buckets): bpm +6-7%, vcm +4-5%
/// samples per CPU-second on lavapipe, ppm within noise; 8 and 16 measured no faster (the
/// larger table's build costs more than the fewer collisions save; docs/performance.md,
/// "Performance work").
const GRID_BUCKETS_PER_LIGHT_PATH: u64 = 4;

/// Most hash-grid buckets: `grid_start` (one u32 per bucket + 1) then stays below
/// 2^27 bytes, the smallest maxStorageBufferRange Vulkan allows.
const MAX_GRID_BUCKETS: u64 = 1 << 24;

/// The bucket count of the hash grid: GRID_BUCKETS_PER_LIGHT_PATH per light subpath,
/// rounded up to a power of two (hash_grid.glsl then masks instead of dividing), at most
/// MAX_GRID_BUCKETS. resources.rs sizes `grid_start` with it too.
pub(crate) fn grid_buckets(light_paths: u64) -> u32 {
    (light_paths.max(1) * GRID_BUCKETS_PER_LIGHT_PATH).next_power_of_two().min(MAX_GRID_BUCKETS) as u32
}

/// What a [`Bidir`] is built for.
#[derive(Clone, Copy, Debug)]
pub struct BidirConfig {
    pub mode: BidirMode,
    pub max_path_length: u32,
    pub radius: RadiusSchedule,
    /// As `render::check_frame` accepts it (the cache only with vertex connections, at
    /// least 1 draw): [`super::Renderer::new`] checks before building.
    pub connect: Connect,
    /// Paths per invocation of the light and camera kernels (src/render/regen.rs).
    pub paths_per_invocation: u32,
}

impl Bidir {
    pub fn new(gpu: &Arc<Gpu>, scene: &SceneGpu, film: &Film, config: BidirConfig) -> Result<Bidir> {
        let BidirConfig { mode, max_path_length, radius, connect, paths_per_invocation } = config;
        let pixels = film.width * film.height;
        let light_paths = pixels;
        let store = mode.stores_vertices();
        let slots = max_path_length.saturating_sub(1).max(1) as u64;
        let lv_vertices = if store { light_paths as u64 * slots } else { 1 };
        let max = gpu.limits.max_storage_buffer_range as u64;
        if lv_vertices * LV_HALF_BYTES > max {
            bail!(
                "the light-vertex store needs 2 x {} bytes ({} light subpaths x {} vertices) but this device binds at most {} bytes per buffer; lower the resolution or --max-path-length",
                lv_vertices * LV_HALF_BYTES,
                light_paths,
                slots,
                max
            );
        }
        let mut buffers = vec![
            gpu.buffer_zeroed::<u64>("splat", 3 * pixels as usize)?,
            gpu.buffer_zeroed::<[f32; 4]>("light_vertices_a", 2 * lv_vertices as usize)?,
            gpu.buffer_zeroed::<[f32; 4]>("light_vertices_b", 2 * lv_vertices as usize)?,
            gpu.buffer_zeroed::<u32>("light_vertex_counts", if store { light_paths as usize } else { 1 })?,
        ];
        if connect != Connect::Path {
            // light_subpath.comp copies the counts here; scanned in place, entry p is the
            // index of path p's first vertex among all stored ones, entry N_L the total.
            buffers.push(gpu.buffer_zeroed::<u32>("light_vertex_prefix", light_paths as usize + 1)?);
            // Entry i: the store slot of the i-th of all stored vertices.
            buffers.push(gpu.buffer_zeroed::<u32>("light_vertex_dense", lv_vertices as usize)?);
        }
        let cache = match (buffers.get(4), buffers.get(5)) {
            (Some(prefix), Some(dense)) => Some(LvCache {
                scan: ExclusiveScan::new(gpu, prefix, light_paths + 1)?
                    .labelled(crate::gpu::LIGHT_VERTEX_PREFIX_KERNEL),
                compact: gpu.kernel("lv_cache_compact.comp", &[], &[&buffers[3], prefix, dense])?,
                slots: slots as u32,
            }),
            _ => None,
        };
        let grid = if mode.use_vm() {
            let buckets = grid_buckets(light_paths as u64);
            Some(HashGrid::new(gpu, &buffers[1], &buffers[3], light_paths, slots as u32, buckets)?)
        } else {
            None
        };
        let mut bind = scene.bindings(&[&film.accum, &film.stats]);
        bind.extend(buffers[..4].iter().map(Binding::Storage));
        // The prefix buffer binds after the hash grid's (glsl/vcm_bindings.glsl), the dense
        // list after it (camera kernel only).
        let prefix = buffers.get(4);
        let lt = mode == BidirMode::LightTracing;
        let flag = |b: bool| (b as u32).to_string();
        let mut light_defines = scene.defines.clone();
        light_defines.push(("STORE_VERTICES".into(), flag(store)));
        light_defines.push(("LIGHT_TRACE_ONLY".into(), flag(lt)));
        light_defines.push(("CONNECT_CAMERA".into(), flag(lt || mode.use_vc())));
        let mut light_bind = bind.clone();
        light_bind.extend(prefix.map(Binding::Storage));
        let light = gpu.kernel_with("light_subpath.comp", &define_refs(&light_defines), &light_bind)?;
        let resolve = if lt {
            gpu.kernel_with("accumulate.comp", &define_refs(&scene.defines), &bind)?
        } else {
            let mut d = scene.defines.clone();
            d.push(("USE_VC".into(), flag(mode.use_vc())));
            d.push(("USE_VM".into(), flag(mode.use_vm())));
            d.push(("PPM".into(), flag(mode == BidirMode::Ppm)));
            // The camera kernel only reads the light vertices, the grid and the cache's
            // index: as texel buffers when the scene's reads are (src/render/reads.rs).
            let reads = scene.reads;
            d.push(("LV_TEXEL".into(), flag(reads == Reads::Texel)));
            let mut cam_bind = scene.bindings(&[&film.accum, &film.stats, &buffers[0]]);
            cam_bind.extend([reads.bind(&buffers[1]), reads.bind(&buffers[2]), reads.bind_u32(&buffers[3])]);
            if let Some(g) = &grid {
                cam_bind.push(reads.bind_u32(&g.cell_start));
                cam_bind.push(reads.bind(&g.cell_points));
            }
            cam_bind.extend(buffers.get(4..6).into_iter().flatten().map(|b| reads.bind_u32(b)));
            gpu.kernel_with("camera_subpath.comp", &define_refs(&d), &cam_bind)?
        };
        let s = scene.params.scene_sphere;
        let grid_origin = [s[0] - s[3], s[1] - s[3], s[2] - s[3]];
        Ok(Bidir {
            mode,
            light,
            resolve,
            grid,
            cache,
            radius,
            grid_origin,
            pixels,
            light_paths,
            paths_per_invocation,
            _buffers: buffers,
        })
    }

    /// Every buffer this estimator allocated: the splat sums and the light-vertex store
    /// (1-vertex placeholders for `lt`, which stores none), and the hash grid's when
    /// merging.
    pub fn buffers(&self) -> Vec<&Buffer> {
        let mut b: Vec<&Buffer> = self._buffers.iter().collect();
        if let Some(g) = &self.grid {
            b.extend(g.buffers());
        }
        if let Some(c) = &self.cache {
            b.extend(c.scan.buffers());
        }
        b
    }

    pub fn record(&self, batch: &mut Batch, iteration: u32) -> Result<()> {
        let i = iteration as u64;
        let (mis_vm, mis_vc) = self.radius.mis_factors(i, self.light_paths, self.mode.use_vc(), self.mode.use_vm());
        let radius = self.radius.radius(i);
        let mut push = GpuPush {
            iteration,
            count: self.light_paths,
            mis_vm,
            mis_vc,
            radius,
            light_paths: self.light_paths,
            grid_buckets: self.grid.as_ref().map_or(0, |g| g.num_buckets()),
            paths_per_invocation: self.paths_per_invocation,
        };
        let k = self.paths_per_invocation;
        batch.dispatch(
            &self.light,
            groups_2d(regen::invocations(self.light_paths, k), 64),
            bytemuck::bytes_of(&push),
        )?;
        if let Some(g) = &self.grid {
            g.record_build(batch, radius, self.grid_origin)?;
        }
        if let Some(c) = &self.cache {
            c.scan.record(batch)?;
            let p = CompactPush { light_paths: self.light_paths, slots: c.slots };
            batch.dispatch(&c.compact, groups_2d(self.light_paths, 64), bytemuck::bytes_of(&p))?;
        }
        push.count = self.pixels;
        // accumulate.comp (lt) takes one pixel per invocation; the camera kernel k.
        let k = if self.mode == BidirMode::LightTracing { 1 } else { k };
        batch.dispatch(&self.resolve, groups_2d(regen::invocations(self.pixels, k), 64), bytemuck::bytes_of(&push))
    }
}

#[cfg(test)]
mod tests {
    use super::grid_buckets;

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
}
