//! Bidirectional path tracing (`bpt`, vertex connection): every camera vertex connects to
//! the lights (next-event estimation) and to light vertices, every light vertex to the
//! camera, all weighted by SmallVCM's recursive MIS (docs/smallvcm.md) with merging off.
//! Connections go to the vertices of light subpath p = this pixel (`--connect path`,
//! SmallVCM) or to vertices drawn from all light subpaths (`--connect cache`, the default:
//! measured slightly better at equal time, docs/estimators.md).
//!
//! Passes per iteration (src/render/estimators/bidirectional.rs): light subpaths (store
//! vertices, connect to the camera), camera subpaths (NEE + vertex connections; splats ->
//! film).

use super::{Algorithm, EstimatorInfo, Techniques};
use crate::render::settings::{Connect, DEFAULT_CACHE_CONNECTIONS};

pub const INFO: EstimatorInfo = EstimatorInfo::light_subpath(
    Algorithm::Bpt,
    "bpt",
    "Bidirectional path tracing (vertex connection), SmallVCM's MIS.",
    TECHNIQUES,
    Some(Connect::Cache(DEFAULT_CACHE_CONNECTIONS)),
);

/// Vertex connection: light-vertex connections, NEE and camera connections, with MIS.
pub const TECHNIQUES: Techniques = Techniques {
    light_subpaths: true,
    store_vertices: true,
    connect_to_camera: true,
    vertex_connection: true,
    vertex_merging: false,
    merge_first_vertex_only: false,
    light_trace_only: false,
};
