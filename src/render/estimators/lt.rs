//! Light tracing (`lt`): light subpaths connected to the camera, every vertex splatted onto
//! the pixel it projects to with weight 1 (no MIS), directly seen emitters included.
//!
//! Passes per iteration (src/render/estimators/bidirectional.rs): light subpaths (connect
//! to the camera, no vertex store), accumulate (splats -> film).

use super::{Algorithm, EstimatorInfo, Techniques};

pub const INFO: EstimatorInfo = EstimatorInfo::light_subpath(
    Algorithm::Lt,
    "lt",
    "Light tracing: light subpaths connected to the camera.",
    TECHNIQUES,
    None,
);

/// Light subpaths connected to the camera, nothing stored, no MIS.
pub const TECHNIQUES: Techniques = Techniques {
    light_subpaths: true,
    store_vertices: false,
    connect_to_camera: true,
    vertex_connection: false,
    vertex_merging: false,
    merge_first_vertex_only: false,
    light_trace_only: true,
};
