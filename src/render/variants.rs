//! Kernel variants: what each render kernel is compiled with, as typed values, turned
//! into `#define`s in one place. The kernels refuse to compile without the defines of
//! their variant (`#error`), so no GLSL default picks an estimator.
//!
//! Every render kernel gets the scene's part ([`SceneVariant`]: the feature set of
//! src/render/features.rs, how it reads its buffers, the workgroup size); the light,
//! camera and path-tracing kernels add their own ([`LightKernel`], [`CameraKernel`],
//! [`PtKernel`]).

use super::atomics::SplatAtomics;
use super::features::FeatureSet;
use super::reads::Reads;
use super::settings::Connect;
use super::techniques::Techniques;
use crate::gpu::Defines;

/// Invocations per workgroup of every render kernel (their GLSL's `WORKGROUP_SIZE`);
/// dispatches read it back from each kernel's SPIR-V (`Kernel::groups_for`).
pub const WORKGROUP_SIZE: u32 = 64;

/// `WORKGROUP_SIZE`, which every render kernel is compiled with.
pub fn workgroup_defines() -> Defines {
    Defines::new().value("WORKGROUP_SIZE", WORKGROUP_SIZE)
}

/// What every render kernel that reads the scene is compiled with.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SceneVariant {
    pub features: FeatureSet,
    /// How the kernels read the scene (TEXEL_READS).
    pub reads: Reads,
    /// BVH_INT64: the BVH is read with 64-bit loads (the device has `shaderInt64`).
    pub int64_loads: bool,
    /// How splats are summed (SPLAT_ATOMICS_64).
    pub atomics: SplatAtomics,
    /// DEVICE_ADDRESSES: the film and the frame's other large buffers are reached by
    /// device address (src/render/addresses.rs).
    pub device_addresses: bool,
    /// SCENE_CHUNK_SHIFT: the kernels read the BVH and the geometry in chunks of 2^shift
    /// 16-byte elements (src/render/scene_gpu.rs, CHUNKED).
    pub chunk_shift: Option<u32>,
}

impl SceneVariant {
    pub fn defines(&self) -> Defines {
        let defines = self
            .features
            .defines()
            .flag("TEXEL_READS", self.reads == Reads::Texel)
            .flag("BVH_INT64", self.int64_loads)
            .with(&self.film_defines())
            .with(&workgroup_defines());
        match self.chunk_shift {
            Some(shift) => defines.flag("SCENE_CHUNKS", true).value("SCENE_CHUNK_SHIFT", shift),
            None => defines,
        }
    }

    /// What glsl/film.glsl is compiled with: SPLAT_ATOMICS_64 and DEVICE_ADDRESSES.
    pub fn film_defines(&self) -> Defines {
        Defines::new()
            .flag("SPLAT_ATOMICS_64", self.atomics == SplatAtomics::Bits64)
            .flag("DEVICE_ADDRESSES", self.device_addresses)
    }
}

/// glsl/light_subpath.comp.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LightKernel {
    /// STORE_VERTICES: non-delta vertices go to the light-vertex store.
    pub store_vertices: bool,
    /// CONNECT_CAMERA: vertices connect to the camera (splats).
    pub connect_camera: bool,
    /// LIGHT_TRACE_ONLY: weight 1, emitters seen directly are splatted too (lt).
    pub light_trace_only: bool,
}

impl LightKernel {
    pub fn new(t: Techniques) -> LightKernel {
        LightKernel {
            store_vertices: t.store_vertices,
            connect_camera: t.connect_to_camera,
            light_trace_only: t.light_trace_only,
        }
    }

    pub fn defines(&self) -> Defines {
        Defines::new()
            .flag("STORE_VERTICES", self.store_vertices)
            .flag("LIGHT_TRACE_ONLY", self.light_trace_only)
            .flag("CONNECT_CAMERA", self.connect_camera)
            .flag("LV_TEXEL", false)
            .flag("LV_CACHE", false)
    }
}

/// glsl/camera_subpath.comp.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CameraKernel {
    /// USE_VC: next-event estimation and vertex connections, with MIS.
    pub vertex_connection: bool,
    /// USE_VM: merging with the light vertices in the radius.
    pub vertex_merging: bool,
    /// PPM: merging at the first non-specular vertex only, weight 1.
    pub merge_first_vertex_only: bool,
    /// Where the vertex connections go (LV_CACHE, LV_CACHE_CONNECTIONS).
    pub connect: Connect,
    /// LV_TEXEL: the light vertices, grid and cache index are read as texel buffers.
    pub texel_reads: bool,
    /// SOBOL: Owen-scrambled Sobol samples (0: independent random numbers).
    pub sobol: bool,
}

impl CameraKernel {
    pub fn new(t: Techniques, connect: Connect, reads: Reads, sobol: bool) -> CameraKernel {
        CameraKernel {
            vertex_connection: t.vertex_connection,
            vertex_merging: t.vertex_merging,
            merge_first_vertex_only: t.merge_first_vertex_only,
            connect,
            texel_reads: reads == Reads::Texel,
            sobol,
        }
    }

    pub fn defines(&self) -> Defines {
        let d = Defines::new()
            .flag("USE_VC", self.vertex_connection)
            .flag("USE_VM", self.vertex_merging)
            .flag("PPM", self.merge_first_vertex_only)
            .flag("LV_TEXEL", self.texel_reads)
            .flag("SOBOL", self.sobol);
        match self.connect {
            Connect::Path => d.flag("LV_CACHE", false),
            Connect::Cache(n) => d.flag("LV_CACHE", true).value("LV_CACHE_CONNECTIONS", n),
        }
    }
}

/// glsl/pt.comp.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PtKernel {
    /// NEE: next-event estimation with MIS (0: BSDF sampling only).
    pub nee: bool,
    /// SOBOL: Owen-scrambled Sobol samples (0: independent random numbers).
    pub sobol: bool,
}

impl PtKernel {
    pub fn defines(&self) -> Defines {
        Defines::new().flag("NEE", self.nee).flag("SOBOL", self.sobol)
    }
}
