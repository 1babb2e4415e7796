//! Benchmark harnesses: not used by rendering.
//!
//! * [`build`]: BVH build seconds per million triangles (`vkvcm-bench bvh-build`).
//! * [`render`]: samples per CPU-second of whole renders (`vkvcm-bench render`,
//!   `equal-time`, `suite`).
//! * [`traverse`]: the BVH traversal benchmark (`vkvcm-bench traverse`) and its scenes.

pub mod build;
pub mod render;
pub mod traverse;
