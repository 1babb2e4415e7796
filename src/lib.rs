//! vkvcm: a light-transport renderer running in Vulkan compute shaders.
//!
//! Layout (the design behind it: docs/design.md): `gpu` is the Vulkan core, `scene` the
//! glTF import and built-in scenes, `bvh` the acceleration structure, `render` the
//! estimators, `image` file output and error metrics; `activity` announces long work
//! (scene loads, BVH builds) to a front end that shows progress. Benchmarks and the
//! render tests' statistics are not here: tools/ (crate `vkvcm-tools`).

pub mod activity;
pub mod bvh;
pub mod gpu;
pub mod image;
pub mod render;
pub mod scene;
