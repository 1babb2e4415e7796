//! Progressive photon mapping (`ppm`): camera subpaths follow specular bounces to the first
//! non-specular vertex and merge there with the light vertices within the radius (weight
//! 1), whose radius shrinks each iteration (docs/smallvcm.md, the radius schedule).
//!
//! Passes per iteration (src/render/estimators/bidirectional.rs): light subpaths (store
//! vertices), grid build, camera subpaths (merging at the first non-specular vertex; film).

use super::{Algorithm, EstimatorInfo, Techniques};

pub const INFO: EstimatorInfo = EstimatorInfo::light_subpath(
    Algorithm::Ppm,
    "ppm",
    "Progressive photon mapping: merging at the first non-specular camera vertex.",
    TECHNIQUES,
    None,
);

/// Merging at the first non-specular camera vertex only, no MIS.
pub const TECHNIQUES: Techniques = Techniques {
    light_subpaths: true,
    store_vertices: true,
    connect_to_camera: false,
    vertex_connection: false,
    vertex_merging: true,
    merge_first_vertex_only: true,
    light_trace_only: false,
};
