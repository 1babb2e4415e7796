//! The estimators, one module each, and the registry ([`Algorithm::info`]) that the
//! renderer, the command line, `bench` and `converge` read: its name, description,
//! settings, checks and the passes it builds.
//!
//! An estimator is a sequence of passes (src/render/passes/) recorded once per
//! iteration; [`Estimator`] is what the renderer holds. pt and el are one camera pass
//! each; lt, bpt, ppm, bpm and vcm share one pass sequence ([`bidirectional`]) and differ
//! in the [`Techniques`] they turn on.

pub mod bidirectional;
pub mod bpm;
pub mod bpt;
pub mod el;
pub mod lt;
pub mod ppm;
pub mod pt;
pub mod vcm;

use std::sync::Arc;

use anyhow::{bail, Result};

use super::film::Film;
use super::passes::PassInfo;
use super::plan::FramePlan;
use super::scene_gpu::SceneGpu;
use super::settings::{Connect, RenderSettings};
use crate::gpu::{Batch, Buffer, Gpu};

/// The estimators vkvcm implements (the keys of the registry).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Algorithm {
    El,
    Pt,
    Lt,
    Bpt,
    Ppm,
    Bpm,
    Vcm,
}

/// Every estimator, in the order the command line lists them.
pub const ALGORITHMS: [Algorithm; 7] =
    [Algorithm::El, Algorithm::Pt, Algorithm::Lt, Algorithm::Bpt, Algorithm::Ppm, Algorithm::Bpm, Algorithm::Vcm];

impl Algorithm {
    /// The estimator's entry in the registry.
    pub fn info(self) -> &'static EstimatorInfo {
        match self {
            Algorithm::El => &el::INFO,
            Algorithm::Pt => &pt::INFO,
            Algorithm::Lt => &lt::INFO,
            Algorithm::Bpt => &bpt::INFO,
            Algorithm::Ppm => &ppm::INFO,
            Algorithm::Bpm => &bpm::INFO,
            Algorithm::Vcm => &vcm::INFO,
        }
    }

    /// The name on the command line and in saved renders (`pt`, `vcm`, ...).
    pub fn name(self) -> &'static str {
        self.info().name
    }

    /// Where its vertex connections go unless `--connect` says otherwise (`Path`, which
    /// means nothing, for the estimators without vertex connections).
    pub fn default_connect(self) -> Connect {
        self.info().default_connect.unwrap_or(Connect::Path)
    }

    /// The estimator called `name`.
    pub fn from_name(name: &str) -> Option<Algorithm> {
        ALGORITHMS.into_iter().find(|a| a.name() == name)
    }
}

impl clap::ValueEnum for Algorithm {
    fn value_variants<'a>() -> &'a [Self] {
        &ALGORITHMS
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        Some(clap::builder::PossibleValue::new(self.name()).help(self.info().description))
    }
}

/// The light-transport techniques an estimator uses; they decide its passes and kernel
/// variants (src/render/variants.rs) and its MIS factors.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Techniques {
    /// Light subpaths are traced each iteration (lt, bpt, ppm, bpm, vcm).
    pub light_subpaths: bool,
    /// Their non-delta vertices are stored for the camera pass (bpt, ppm, bpm, vcm).
    pub store_vertices: bool,
    /// Light vertices connect to the camera, splatting onto any pixel (lt, bpt, vcm).
    pub connect_to_camera: bool,
    /// Camera vertices connect to lights (next-event estimation) and to light vertices,
    /// with MIS (bpt, vcm; SmallVCM's "vertex connection").
    pub vertex_connection: bool,
    /// Camera vertices merge with light vertices within the radius (ppm, bpm, vcm).
    pub vertex_merging: bool,
    /// Merging only at the first non-specular camera vertex, weight 1 (ppm).
    pub merge_first_vertex_only: bool,
    /// Light tracing without MIS, which also splats directly seen emitters (lt).
    pub light_trace_only: bool,
}

/// What the registry knows of an estimator.
pub struct EstimatorInfo {
    pub algorithm: Algorithm,
    /// Name on the command line.
    pub name: &'static str,
    /// One line for `--help`.
    pub description: &'static str,
    pub techniques: Techniques,
    /// Its value is radiance (false for the `el` preview).
    pub radiance: bool,
    /// Biased but consistent (merging): its error has a bias that vanishes as the radius
    /// shrinks, so a reference from it is consistent only.
    pub consistent_only: bool,
    /// The default of `--connect` for estimators with vertex connections (None: the
    /// estimator has none and accepts only `Connect::Path`, which means nothing to it).
    pub default_connect: Option<Connect>,
    /// Its kernels read shading normals (only `el` today; the estimators shade with
    /// geometric normals).
    pub reads_shading_normals: bool,
    /// Its kernels trace several paths per invocation (path regeneration).
    pub regenerates_paths: bool,
    /// Builds its passes for a render.
    pub build: fn(&Build) -> Result<Box<dyn Estimator>>,
}

impl EstimatorInfo {
    /// Where this estimator's vertex connections go when `requested` (`None`: its
    /// default); any request is refused for an estimator without vertex connections, and
    /// a cache of 0 connections for every estimator.
    pub fn connect(&self, requested: Option<Connect>) -> Result<Connect> {
        let connect = match (requested, self.default_connect) {
            (None, default) => default.unwrap_or(Connect::Path),
            (Some(c), None) => bail!(
                "a connection strategy ({}) is for the estimators that connect vertices (bpt, vcm), not {}",
                c.name(),
                self.name
            ),
            (Some(c), Some(_)) => c,
        };
        if connect == Connect::Cache(0) {
            bail!("the light-vertex cache needs at least 1 connection per camera vertex");
        }
        Ok(connect)
    }

    /// Checks the settings that only concern this estimator.
    pub fn check(&self, s: &RenderSettings) -> Result<()> {
        // Settings always hold a strategy: `Path` means none to the estimators without
        // vertex connections.
        if self.default_connect.is_some() || s.connect != Connect::Path {
            self.connect(Some(s.connect))?;
        }
        // Light vertices keep their path length in 8 bits (glsl/vcm.glsl); lt, which
        // stores none, keeps the same limit as the other light-subpath estimators.
        if self.techniques.light_subpaths && s.frame.max_path_length > 256 {
            bail!("max path length {} is more than the light-vertex store's 256", s.frame.max_path_length);
        }
        Ok(())
    }
}

/// What an estimator is built from.
pub struct Build<'a> {
    pub gpu: &'a Arc<Gpu>,
    pub scene: &'a SceneGpu,
    pub film: &'a Film,
    pub settings: &'a RenderSettings,
    pub plan: &'a FramePlan,
}

/// An estimator built for one render: its passes, recorded once per iteration.
pub trait Estimator {
    /// Records iteration `iteration`'s passes into `batch`.
    fn record(&self, batch: &mut Batch, iteration: u32) -> Result<()>;
    /// The passes it records, in order, for `--verbose`.
    fn passes(&self) -> Vec<PassInfo>;
    /// The buffers it allocated (beyond the scene's and the film's).
    fn buffers(&self) -> Vec<&Buffer>;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn registry_is_keyed_by_algorithm_and_names_are_unique() {
        for a in ALGORITHMS {
            assert_eq!(a.info().algorithm, a);
            assert_eq!(Algorithm::from_name(a.name()), Some(a));
        }
        let mut names: Vec<&str> = ALGORITHMS.iter().map(|a| a.name()).collect();
        names.dedup();
        assert_eq!(names.len(), ALGORITHMS.len());
    }

    #[test]
    fn techniques_are_consistent() {
        for a in ALGORITHMS {
            let t = a.info().techniques;
            assert!(!t.store_vertices || t.light_subpaths, "{a:?}");
            assert!(!(t.vertex_merging || t.vertex_connection) || t.store_vertices, "{a:?}");
            assert!(!t.merge_first_vertex_only || t.vertex_merging, "{a:?}");
            assert_eq!(a.info().default_connect.is_some(), t.vertex_connection, "{a:?}");
            assert_eq!(a.info().consistent_only, t.vertex_merging, "{a:?}");
        }
    }
}
