//! Bounding volume hierarchy: binned SAH build on the CPU, GPU node layout.
//!
//! Modules, each using only those listed before it: [`aabb`] (boxes), [`intersect`]
//! (ray/primitive tests), [`layout`] (the GPU arrays and their encoding),
//! [`build`](mod@build) (the builder, which writes that layout), [`traverse`] (the CPU
//! traversal of the layout).
//!
//! * [`build`](fn@build) / [`build_with`]: binned SAH build over one unified primitive list
//!   (all triangles, then all spheres), parallel (rayon) with the same tree for any number
//!   of threads, see [`build`](mod@build); [`build_scene`]: a scene's BVH, two levels when
//!   it has instances of shared meshes (see [`layout`]).
//! * [`Bvh::to_gpu`]: the flattened BVH2 in the GPU layout ([`GpuNode`], [`GpuPrim`]),
//!   read by `glsl/bvh.glsl` (`trace_closest`, `trace_any`).
//! * [`GpuBvh::closest_hit`] / [`GpuBvh::any_hit`]: the CPU mirror of the GLSL
//!   traversal over the same flattened data; [`brute_force_closest`] /
//!   [`brute_force_any`]: the reference without any acceleration structure.
//!
//! Design notes and measured figures: docs/bvh.md.

pub mod aabb;
pub mod build;
pub mod intersect;
pub mod layout;
pub mod traverse;

pub use aabb::Aabb;
pub use build::{
    build, build_instanced, build_scene, build_with, BuildOptions, BuildStats, Bvh, LeafRule, SplitMethod,
    SIZE_LEAF_RULE_MIN_PRIMS,
};
pub use intersect::{brute_force_any, brute_force_closest, intersect_sphere, intersect_triangle, Hit, Ray};
pub use layout::{GpuBvh, GpuNode, GpuPrim, INSTANCE_FLAG, MAX_DEPTH, MAX_LEAF_PRIMS, SPHERE_FLAG};
