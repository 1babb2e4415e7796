//! The light-subpaths pass (glsl/light_subpath.comp): one light subpath per pixel and
//! iteration, `paths_per_invocation` per kernel invocation (path regeneration). It writes
//! the light-vertex store ([`LightVertexStore`]) and, for the estimators that connect
//! light vertices to the camera, the splat sums.
//!
//! Light vertices use SmallVCM's layout: light subpath p's vertices live in the fixed
//! slots [p S, p S + S) with S = max path length - 1 (glsl/vcm.glsl), so a camera subpath
//! finds the vertices of light subpath p = its pixel without a search.

use anyhow::Result;

use super::PassContext;
use super::PassInfo;
use crate::gpu::{Batch, Bind, Buffer, Gpu, Kernel};
use crate::render::addresses::FrameAddresses;
use crate::render::features::FeatureSet;
use crate::render::gpu_types::GpuPush;
use crate::render::regen;
use crate::render::sizes::{Access, BufferSize};
use crate::render::variants::LightKernel;

/// The name profiles report.
pub const NAME: &str = "light subpaths";

/// Bytes of one light vertex in `light_vertices_a` (position, throughput and two MIS
/// quantities: two vec4).
pub const LIGHT_VERTEX_A_BYTES: u64 = 32;

/// Bytes of one light vertex in `light_vertices_b`: (wo, dVM) and (normal, material and
/// length), with `normal_slot` a vec4 holding the shading normal (and the point's
/// metallic), with vertex attributes one holding the tint (glsl/vcm.glsl, LV_B_STRIDE).
/// The normal slot is there with shading normals or metallic-roughness textures.
pub fn light_vertex_b_bytes(normal_slot: bool, vertex_attributes: bool) -> u64 {
    32 + 16 * normal_slot as u64 + 16 * vertex_attributes as u64
}

/// The sizes of the light-vertex store and the splat sums.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LightVertexPlan {
    pub light_paths: u32,
    /// Store slots per light subpath (max path length - 1, at least 1).
    pub slots_per_path: u32,
    /// Slots in all: light paths x slots per path, or a 1-vertex placeholder when the
    /// estimator stores none (lt: its kernels still declare the store).
    pub capacity: u64,
    /// Per pixel three fixed-point u64 sums (glsl/film.glsl).
    pub splat: BufferSize,
    pub vertices_a: BufferSize,
    pub vertices_b: BufferSize,
    /// One u32 per light subpath: its stored vertices.
    pub counts: BufferSize,
}

impl LightVertexPlan {
    /// The store of `light_paths` subpaths of up to `max_path_length` segments (with the
    /// vertex fields `features` asks for), reached as `store_access`; the splat sums of
    /// `pixels` pixels are reached as `splat_access`.
    pub fn new(
        pixels: u32,
        light_paths: u32,
        max_path_length: u32,
        store_vertices: bool,
        features: &FeatureSet,
        splat_access: Access,
        store_access: Access,
    ) -> LightVertexPlan {
        let normal_slot = features.shading_normals || features.metallic_roughness_textures;
        let vertex_attributes = features.vertex_attributes;
        let slots_per_path = max_path_length.saturating_sub(1).max(1);
        let capacity = if store_vertices { light_paths as u64 * slots_per_path as u64 } else { 1 };
        let count_entries = if store_vertices { light_paths as u64 } else { 1 };
        LightVertexPlan {
            light_paths,
            slots_per_path,
            capacity,
            splat: BufferSize::new("splat", (pixels as u64).saturating_mul(24)).reached(splat_access),
            vertices_a: BufferSize::new("light_vertices_a", capacity.saturating_mul(LIGHT_VERTEX_A_BYTES))
                .reached(store_access),
            vertices_b: BufferSize::new(
                "light_vertices_b",
                capacity.saturating_mul(light_vertex_b_bytes(normal_slot, vertex_attributes)),
            )
            .reached(store_access),
            counts: BufferSize::new("light_vertex_counts", count_entries * 4),
        }
    }

    pub fn buffers(&self) -> Vec<BufferSize> {
        vec![self.splat, self.vertices_a, self.vertices_b, self.counts]
    }
}

/// The light-vertex store and the splat sums, written by the light pass and read by the
/// passes after it.
pub struct LightVertexStore {
    pub splat: Buffer,
    pub vertices_a: Buffer,
    pub vertices_b: Buffer,
    pub counts: Buffer,
    pub slots_per_path: u32,
    pub light_paths: u32,
}

impl LightVertexStore {
    /// The store of `plan`; the addresses of the splat sums and the vertices go to
    /// `addresses`.
    pub fn new(
        gpu: &std::sync::Arc<Gpu>,
        plan: &LightVertexPlan,
        addresses: &FrameAddresses,
    ) -> Result<LightVertexStore> {
        let splat = plan.splat.zeroed(gpu)?;
        let vertices_a = plan.vertices_a.zeroed(gpu)?;
        let vertices_b = plan.vertices_b.zeroed(gpu)?;
        addresses.set(|a| &mut a.splat, &splat)?;
        addresses.set(|a| &mut a.light_vertices_a, &vertices_a)?;
        addresses.set(|a| &mut a.light_vertices_b, &vertices_b)?;
        Ok(LightVertexStore {
            splat,
            vertices_a,
            vertices_b,
            counts: plan.counts.zeroed(gpu)?,
            slots_per_path: plan.slots_per_path,
            light_paths: plan.light_paths,
        })
    }

    /// The store's bindings (the splat sums, both vertex halves, the counts).
    pub fn binds(&self) -> [Bind<'_>; 4] {
        [Bind::own(&self.splat), Bind::own(&self.vertices_a), Bind::own(&self.vertices_b), Bind::own_u32(&self.counts)]
    }

    pub fn buffers(&self) -> Vec<&Buffer> {
        vec![&self.splat, &self.vertices_a, &self.vertices_b, &self.counts]
    }
}

/// The pass.
pub struct LightSubpaths {
    kernel: Kernel,
    variant: LightKernel,
    light_paths: u32,
    paths_per_invocation: u32,
}

impl LightSubpaths {
    /// The light kernel in `variant` for the render `b`, writing `store` and, with the
    /// light-vertex cache, a copy of the per-path counts into `cache_prefix` (the cache's
    /// `light_vertex_prefix`, scanned in place after this pass).
    pub fn new(
        b: &PassContext,
        store: &LightVertexStore,
        cache_prefix: Option<&Buffer>,
        variant: LightKernel,
    ) -> Result<LightSubpaths> {
        let defines = b.scene.variant.defines().with(&variant.defines());
        let mut binds = b.scene.binds();
        binds.extend(b.film.binds());
        binds.extend(store.binds());
        binds.extend(cache_prefix.map(Bind::own_u32));
        let kernel = b.gpu.kernel("light_subpath.comp", &defines.pairs(), &binds)?;
        Ok(LightSubpaths { kernel, variant, light_paths: b.light_paths, paths_per_invocation: b.paths_per_invocation })
    }

    pub fn record(&self, batch: &mut Batch, push: &GpuPush) -> Result<()> {
        batch.begin_pass(NAME);
        let invocations = regen::invocations(self.light_paths, self.paths_per_invocation);
        batch.dispatch(&self.kernel, self.kernel.groups_for(invocations), bytemuck::bytes_of(push))
    }

    pub fn info(&self) -> PassInfo {
        let v = self.variant;
        let what = match (v.store_vertices, v.connect_camera) {
            (true, true) => "store vertices, connect to the camera",
            (true, false) => "store vertices",
            (false, true) => "connect to the camera (splats), no vertex store",
            (false, false) => "trace only",
        };
        PassInfo { name: NAME, detail: format!("light_subpath.comp: {what}") }
    }
}
