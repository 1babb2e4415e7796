//! Light tracing (`lt`): light subpaths connected to the camera, every vertex splatted onto
//! the pixel it projects to with weight 1 (no MIS), directly seen emitters included.
//!
//! Passes per iteration (src/render/estimators/bidirectional.rs): light subpaths (connect
//! to the camera, no vertex store), accumulate (splats -> film).

use anyhow::Result;

use super::bidirectional::LightSubpathEstimator;
use super::{Algorithm, Build, Estimator, EstimatorInfo, Techniques};

pub const INFO: EstimatorInfo = EstimatorInfo {
    algorithm: Algorithm::Lt,
    name: "lt",
    description: "Light tracing: light subpaths connected to the camera.",
    techniques: TECHNIQUES,
    radiance: true,
    consistent_only: false,
    default_connect: None,
    reads_shading_normals: false,
    regenerates_paths: true,
    build,
};

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

fn build(b: &Build) -> Result<Box<dyn Estimator>> {
    Ok(Box::new(LightSubpathEstimator::new(b, TECHNIQUES)?))
}
