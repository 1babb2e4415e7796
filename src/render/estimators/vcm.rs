//! Vertex connection and merging (`vcm`, Georgiev et al. 2012): bpt's connections and bpm's
//! merging, all weighted by SmallVCM's recursive MIS (docs/smallvcm.md). Connections go to
//! vertices drawn from all light subpaths (`--connect cache`, the default: measured better
//! at equal time on the four reference scenes, docs/estimators.md) or to light subpath
//! p = this pixel (`--connect path`, SmallVCM's layout).
//!
//! Passes per iteration (src/render/estimators/bidirectional.rs): light subpaths (store
//! vertices, connect to the camera), grid build, camera subpaths (NEE + connections +
//! merging, MIS; splats -> film).

use super::{Algorithm, EstimatorInfo, Techniques};
use crate::render::settings::{Connect, DEFAULT_CACHE_CONNECTIONS};

pub const INFO: EstimatorInfo = EstimatorInfo::light_subpath(
    Algorithm::Vcm,
    "vcm",
    "Vertex connection and merging: bpt's connections and bpm's merging, with MIS.",
    TECHNIQUES,
    Some(Connect::Cache(DEFAULT_CACHE_CONNECTIONS)),
);

/// Vertex connection and vertex merging, with MIS.
pub const TECHNIQUES: Techniques = Techniques {
    light_subpaths: true,
    store_vertices: true,
    connect_to_camera: true,
    vertex_connection: true,
    vertex_merging: true,
    merge_first_vertex_only: false,
    light_trace_only: false,
};
