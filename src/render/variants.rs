//! Kernel variants: what each render kernel is compiled with, as typed values, turned
//! into `#define`s in one place. The kernels refuse to compile without the defines of
//! their variant (`#error`), so no GLSL default picks an estimator.
//!
//! Every render kernel gets the scene's part ([`SceneVariant`]: the feature set of
//! src/render/features.rs, how it reads its buffers, the workgroup size); the light,
//! camera and path-tracing kernels add their own switches, declared with
//! [`kernel_switches!`] next to the pass that compiles them (`LightKernel`,
//! `CameraKernel`, `PtKernel` in src/render/passes/), so that each switch has one name
//! from Rust to GLSL.

use super::atomics::SplatAtomics;
use super::features::FeatureSet;
use super::reads::Reads;
use crate::gpu::Defines;

/// Declares a struct of kernel switches with `defines()`: each field becomes the
/// `#define` of its own name in upper case (a `bool` as 1 or 0, a `u32` as its value),
/// so that a switch cannot be called one thing in Rust and another in GLSL.
macro_rules! kernel_switches {
    ($(#[$meta:meta])* pub struct $name:ident { $($(#[$fmeta:meta])* pub $field:ident: $ty:ty,)* }) => {
        $(#[$meta])*
        pub struct $name {
            $($(#[$fmeta])* pub $field: $ty,)*
        }

        impl $name {
            /// Each field as the `#define` of its name in upper case.
            pub fn defines(&self) -> $crate::gpu::Defines {
                let d = $crate::gpu::Defines::new();
                $(let d = $crate::render::variants::KernelSwitch::define(
                    &self.$field,
                    &stringify!($field).to_uppercase(),
                    d,
                );)*
                d
            }
        }
    };
}
pub(crate) use kernel_switches;

/// A value a kernel switch can hold, and how it becomes a `#define`.
pub trait KernelSwitch {
    fn define(&self, name: &str, defines: Defines) -> Defines;
}

impl KernelSwitch for bool {
    fn define(&self, name: &str, defines: Defines) -> Defines {
        defines.flag(name, *self)
    }
}

impl KernelSwitch for u32 {
    fn define(&self, name: &str, defines: Defines) -> Defines {
        defines.value(name, *self)
    }
}

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
    /// LIGHT_TREE: next-event estimation picks area lights by the light tree
    /// (src/render/light_tree.rs, glsl/light_tree.glsl).
    pub light_tree: bool,
}

impl SceneVariant {
    pub fn defines(&self) -> Defines {
        let defines = self
            .features
            .defines()
            .flag("TEXEL_READS", self.reads == Reads::Texel)
            .flag("BVH_INT64", self.int64_loads)
            .flag("LIGHT_TREE", self.light_tree)
            .value("GGX_ALBEDO_MU", crate::render::ggx_albedo::GGX_ALBEDO_MU)
            .value("GGX_ALBEDO_R", crate::render::ggx_albedo::GGX_ALBEDO_R)
            .value("SHEEN_ALBEDO_MU", crate::render::sheen_albedo::SHEEN_ALBEDO_MU)
            .value("SHEEN_ALBEDO_R", crate::render::sheen_albedo::SHEEN_ALBEDO_R)
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
