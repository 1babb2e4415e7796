//! Progressive photon mapping (`ppm`): camera subpaths follow specular bounces to the first
//! non-specular vertex and merge there with the light vertices within the radius (weight
//! 1), whose radius shrinks each iteration (docs/smallvcm.md, the radius schedule).
//!
//! Passes per iteration (src/render/estimators/bidirectional.rs): light subpaths (store
//! vertices), grid build, camera subpaths (merging at the first non-specular vertex; film).

use anyhow::Result;

use super::bidirectional::LightSubpathEstimator;
use super::{Algorithm, Build, Estimator, EstimatorInfo, Techniques};

pub const INFO: EstimatorInfo = EstimatorInfo {
    algorithm: Algorithm::Ppm,
    name: "ppm",
    description: "Progressive photon mapping: merging at the first non-specular camera vertex.",
    techniques: TECHNIQUES,
    radiance: true,
    consistent_only: true,
    default_connect: None,
    reads_shading_normals: false,
    regenerates_paths: true,
    build,
};

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

fn build(b: &Build) -> Result<Box<dyn Estimator>> {
    Ok(Box::new(LightSubpathEstimator::new(b, TECHNIQUES)?))
}
