//! Bidirectional photon mapping (`bpm`): merging at every non-specular camera vertex,
//! weighted by SmallVCM's recursive MIS with connections off.
//!
//! Passes per iteration (src/render/estimators/bidirectional.rs): light subpaths (store
//! vertices), grid build, camera subpaths (merging at every vertex, MIS; film).

use anyhow::Result;

use super::bidirectional::LightSubpathEstimator;
use super::{Algorithm, Build, Estimator, EstimatorInfo, Techniques};

pub const INFO: EstimatorInfo = EstimatorInfo {
    algorithm: Algorithm::Bpm,
    name: "bpm",
    description: "Bidirectional photon mapping: merging at every camera vertex, with MIS.",
    techniques: TECHNIQUES,
    radiance: true,
    consistent_only: true,
    default_connect: None,
    reads_shading_normals: false,
    regenerates_paths: true,
    build,
};

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

fn build(b: &Build) -> Result<Box<dyn Estimator>> {
    Ok(Box::new(LightSubpathEstimator::new(b, TECHNIQUES)?))
}
