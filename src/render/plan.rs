//! The plan of sizes of a render: every buffer it allocates, by name and size in bytes,
//! computed once from the scene, the settings and the estimator's techniques. The
//! renderer checks the plan against the device before anything is allocated (each
//! buffer against the limit of how the kernels reach it: `maxStorageBufferRange`,
//! `maxTexelBufferElements` or `maxMemoryAllocationSize`; the total against the largest
//! device-local heap, system RAM on lavapipe), and the film and passes allocate what it
//! says. Each part is defined next to the code that uses the buffers: [`ScenePlan`]
//! (src/render/scene_gpu.rs), [`FilmPlan`] (film.rs), [`GridPlan`] (src/render/passes/),
//! [`LightVertexPlan`] (src/render/light_vertex_store.rs). The
//! light-vertex store's capacity is an estimate; when an iteration needs more, the
//! estimator grows it and checks the plan again (src/render/light_vertex_store.rs).

use anyhow::{bail, Result};

use super::features::FeatureSet;
use super::film::FilmPlan;
use super::light_vertex_store::{
    grown_capacity, light_vertex_b_bytes, LightVertexAccess, LightVertexPlan, LightVertexSizing, LIGHT_VERTEX_A_BYTES,
};
use super::passes::hash_grid::{grid_buckets, GridPlan, GRID_KEY_BYTES, GRID_POINT_BYTES};
use super::reads::Reads;
use super::scene_gpu::ScenePlan;
use super::settings::{LightSelection, RenderSettings};
use super::sizes::{check_sizes, Access, BufferSize, SizeLimits};
use super::techniques::Techniques;
use crate::gpu::Gpu;
use crate::scene::Scene;

/// What a render allocates.
#[derive(Clone, Debug)]
pub struct FramePlan {
    pub pixels: u32,
    /// Light subpaths per iteration, N_L (`--light-paths`; default one per pixel,
    /// SmallVCM's choice).
    pub light_paths: u32,
    /// Paths per kernel invocation (path regeneration, src/render/regen.rs).
    pub paths_per_invocation: u32,
    /// How the kernels read the scene (TEXEL_READS, src/render/reads.rs).
    pub reads: Reads,
    /// How the camera kernel reads the light-vertex store, its offsets and the hash grid
    /// (STORE_TEXEL_READS): chosen apart from the scene's, as their sizes grow with the
    /// frame rather than the scene.
    pub store_reads: Reads,
    /// Whether the reads were chosen for the device (no `--reads`): then a buffer over a
    /// texel limit is read from storage instead ([`FramePlan::read_from_storage_where_over`]).
    pub reads_chosen: bool,
    /// Whether the device has buffer device addresses (how the frame's buffers are reached).
    pub device_addresses: bool,
    /// Upper bounds of the scene's buffers (their sizes are exact after the BVH build).
    pub scene: ScenePlan,
    pub film: FilmPlan,
    /// The light-vertex store and splat sums (light-subpath estimators).
    pub light_vertices: Option<LightVertexPlan>,
    /// The hash grid (merging).
    pub grid: Option<GridPlan>,
}

impl FramePlan {
    /// The plan of a render of `scene` with `s` (already checked: `RenderSettings::check`,
    /// as `Renderer::plan_for` does) by an estimator with `techniques`, tracing
    /// `paths_per_invocation` paths per invocation, with kernels compiled for `features`
    /// (with shading normals and vertex attributes light vertices carry more).
    /// The frame's large buffers (film, splat sums, light-vertex store and its offsets and
    /// scratch slots, hash-grid keys and entries) are written by device address when
    /// `device_addresses` (src/render/addresses.rs); the scene, the store, its offsets and
    /// the grid's entries are read as `reads`. `light_sizing` bounds the light pass's
    /// chunks and sets the store's first capacity; the light kernel traces
    /// `light_paths_per_invocation(chunk)` paths per invocation.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        scene: &Scene,
        s: &RenderSettings,
        techniques: Techniques,
        paths_per_invocation: u32,
        features: &FeatureSet,
        reads: Reads,
        device_addresses: bool,
        light_sizing: LightVertexSizing,
        light_paths_per_invocation: impl Fn(u32) -> u32,
    ) -> Result<FramePlan> {
        let frame_access = if device_addresses { Access::Address } else { Access::Storage };
        let prims = scene.triangles.len() + scene.spheres.len() + 3 * scene.instances.len();
        if prims > crate::bvh::layout::MAX_PRIMS {
            bail!(
                "scene {:?} has {prims} primitives; the BVH holds at most {}",
                scene.name,
                crate::bvh::layout::MAX_PRIMS
            );
        }
        let pixels = s.frame.width * s.frame.height;
        let light_paths = s.light_paths();
        // The store's read access is set by `set_store_reads` below.
        let access = LightVertexAccess { frame: frame_access, vertices: frame_access, offsets: frame_access };
        let light_vertices = techniques.light_subpaths.then(|| {
            LightVertexPlan::new(
                pixels,
                light_paths,
                s.frame.max_path_length,
                techniques.store_vertices,
                light_vertex_b_bytes(features),
                access,
                light_sizing,
                light_paths_per_invocation,
            )
        });
        let grid = match &light_vertices {
            Some(lv) if techniques.vertex_merging => {
                let plan = GridPlan::new(light_paths, lv.capacity, grid_buckets(light_paths as u64));
                Some(plan.reached(frame_access, frame_access))
            }
            _ => None,
        };
        let mut plan = FramePlan {
            pixels,
            light_paths,
            paths_per_invocation,
            reads,
            store_reads: reads,
            reads_chosen: false,
            device_addresses,
            scene: ScenePlan::new(scene, reads, device_addresses, s.frame.light_selection == LightSelection::Tree),
            film: FilmPlan::new(s.frame.width, s.frame.height, frame_access).with_aov(s.aov.any()),
            light_vertices,
            grid,
        };
        plan.set_store_reads(reads);
        Ok(plan)
    }

    /// Makes the camera kernel read the light-vertex store, its offsets and the hash
    /// grid's entries as `reads`, and sets how each of those buffers is reached: written
    /// by address (or bound as storage buffers without addresses) and, with texel reads,
    /// also bound as texel buffers; `grid_start` is always bound as a storage buffer by
    /// the grid's build (src/render/passes/hash_grid.rs).
    pub fn set_store_reads(&mut self, reads: Reads) {
        self.store_reads = reads;
        let written = if self.device_addresses { Access::Address } else { Access::Storage };
        let texel = |bytes: u64| (reads == Reads::Texel).then_some(bytes);
        if let Some(lv) = &mut self.light_vertices {
            lv.vertices_a = lv.vertices_a.reached(written.with_texels(texel(16)));
            lv.vertices_b = lv.vertices_b.reached(written.with_texels(texel(16)));
            lv.offsets = lv.offsets.reached(written.with_texels(texel(4)));
        }
        if let Some(g) = &mut self.grid {
            g.points = g.points.reached(written.with_texels(texel(16)));
            g.start = g.start.reached(Access::Storage.with_texels(texel(4)));
        }
    }

    /// Where the reads were chosen for the device (`reads_chosen`) and a buffer read as
    /// texels is larger than the device's texel limit allows, reads it from storage
    /// instead, so that the automatic choice is never one the plan refuses: the scene's
    /// buffers all together (they share TEXEL_READS), and apart from them the store and
    /// the grid (STORE_TEXEL_READS). `scene` rebuilds the scene's part; the scene is
    /// chunked again as [`ScenePlan::chunk_if_over_binding`] would. Returns whether
    /// anything changed.
    pub fn read_from_storage_where_over(&mut self, scene: &Scene, limits: &SizeLimits) -> bool {
        if !self.reads_chosen {
            return false;
        }
        let over = |b: &BufferSize| b.access.texel_bytes().is_some() && b.bytes > limits.max_bytes(b);
        let mut changed = false;
        if self.reads == Reads::Texel && self.scene.buffers().iter().any(over) {
            self.reads = Reads::Storage;
            self.scene = ScenePlan::new(scene, Reads::Storage, self.device_addresses, self.scene.light_tree);
            self.scene.chunk_if_over_binding(limits, self.device_addresses);
            changed = true;
        }
        if self.store_over_texel_limit(limits) {
            self.set_store_reads(Reads::Storage);
            changed = true;
        }
        changed
    }

    /// Whether the camera kernel reads the store or the grid as texels and one of their
    /// buffers is larger than the device's texel limit allows.
    fn store_over_texel_limit(&self, limits: &SizeLimits) -> bool {
        let over = |b: &BufferSize| b.access.texel_bytes().is_some() && b.bytes > limits.max_bytes(b);
        let mut store = self.light_vertices.iter().flat_map(|p| p.buffers()).collect::<Vec<_>>();
        store.extend(self.grid.iter().flat_map(|p| p.buffers()));
        self.store_reads == Reads::Texel && store.iter().any(over)
    }

    /// Every buffer.
    pub fn buffers(&self) -> Vec<BufferSize> {
        let mut v = self.scene.buffers();
        v.extend(self.film.buffers());
        v.extend(self.light_vertices.iter().flat_map(|p| p.buffers()));
        v.extend(self.grid.iter().flat_map(|p| p.buffers()));
        v
    }

    /// Fails when the plan does not fit `gpu`; `what` describes the render in the message.
    pub fn check(&self, gpu: &Gpu, what: &str) -> Result<()> {
        check_sizes(&self.buffers(), &SizeLimits::of(gpu), what)
    }
}

/// The light-vertex store's growth (src/render/light_vertex_store.rs).
impl FramePlan {
    /// This plan with a store for iterations that store `needed` vertices and a margin
    /// ([`grown_capacity`], as far as the device allows), checked against `gpu`; `what`
    /// describes the render in the message when it does not fit.
    pub fn grown(&self, gpu: &Gpu, needed: u64, what: &str) -> Result<FramePlan> {
        let lv = self.light_vertices.as_ref().expect("an estimator that stores light vertices has a store");
        let mut grown = self.clone();
        grown.set_light_vertex_capacity(grown_capacity(needed, lv));
        // A store grown past the texel limit is read from storage (when the reads were
        // chosen for the device): the estimator rebuilds its kernels from this plan.
        let mut at_least = grown.clone();
        at_least.set_light_vertex_capacity(needed);
        if self.reads_chosen && at_least.store_over_texel_limit(&SizeLimits::of(gpu)) {
            grown.set_store_reads(Reads::Storage);
        }
        // The margin only as far as the device allows; `needed` itself is checked below.
        grown.fit_light_vertex_capacity(&SizeLimits::of(gpu));
        let capacity = grown.light_vertices.as_ref().map_or(needed, |lv| lv.capacity.max(needed));
        grown.set_light_vertex_capacity(capacity);
        grown.check(gpu, what)?;
        Ok(grown)
    }

    /// Resizes the light-vertex store, and the hash grid over it, for `capacity` vertices.
    pub fn set_light_vertex_capacity(&mut self, capacity: u64) {
        if let Some(lv) = &mut self.light_vertices {
            lv.set_capacity(capacity);
            if let Some(g) = &mut self.grid {
                g.set_capacity(capacity);
            }
        }
    }

    /// Lowers the light-vertex store's capacity to the most vertices that the store's
    /// buffers and the hash grid's per-vertex buffers can hold on a device with `limits`,
    /// when the estimate is more: an iteration that stores fewer renders, and one that
    /// stores more is refused when the store cannot grow.
    pub fn fit_light_vertex_capacity(&mut self, limits: &SizeLimits) {
        let Some(lv) = self.light_vertices.as_ref().filter(|lv| lv.store_vertices) else {
            return;
        };
        let mut per_vertex = vec![(lv.vertices_a, LIGHT_VERTEX_A_BYTES), (lv.vertices_b, lv.vertex_b_bytes)];
        if let Some(g) = &self.grid {
            per_vertex.extend([(g.points, GRID_POINT_BYTES), (g.keys, GRID_KEY_BYTES)]);
        }
        let fits = per_vertex.iter().map(|(b, bytes)| limits.max_bytes(b) / bytes).min().unwrap_or(u64::MAX);
        if fits < lv.capacity {
            self.set_light_vertex_capacity(fits.max(1));
        }
    }
}
