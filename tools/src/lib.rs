//! vkvcm-tools: what measures and checks the renderer but is no part of a render, kept out
//! of the `vkvcm` library and binary.
//!
//! * [`bench`]: the benchmark harnesses behind the `vkvcm-bench` binary (docs/performance.md,
//!   docs/bvh.md).
//! * [`stats`]: per-pixel hypothesis tests between renders, used by the render tests.

pub mod bench;
pub mod stats;
