//! Benchmark harnesses: not used by rendering.
//!
//! * [`traverse`]: the BVH traversal benchmark (`vkvcm bench traverse`) and its scenes.

pub mod traverse;
