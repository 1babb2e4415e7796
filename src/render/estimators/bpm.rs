//! Bidirectional photon mapping (`bpm`): merging at every non-specular camera vertex,
//! weighted by SmallVCM's recursive MIS with connections off.
//!
//! Passes per iteration (src/render/estimators/bidirectional.rs): light subpaths (store
//! vertices), grid build, camera subpaths (merging at every vertex, MIS; film).

use super::{Algorithm, EstimatorInfo, Techniques};

pub const INFO: EstimatorInfo = EstimatorInfo::light_subpath(
    Algorithm::Bpm,
    "bpm",
    "Bidirectional photon mapping: merging at every camera vertex, with MIS.",
    TECHNIQUES,
    None,
);

/// Vertex merging at every non-specular camera vertex, with MIS.
pub const TECHNIQUES: Techniques = Techniques {
    light_subpaths: true,
    store_vertices: true,
    connect_to_camera: false,
    vertex_connection: false,
    vertex_merging: true,
    merge_first_vertex_only: false,
    light_trace_only: false,
};
