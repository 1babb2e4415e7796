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
use super::passes::light_subpaths::StoreStatus;
use super::passes::{PassContext, PassInfo};
use super::plan::FramePlan;
use super::radius;
use super::scene_gpu::SceneGpu;
pub use super::settings::{Algorithm, ALGORITHMS};
use super::settings::{Budget, Connect, FrameSettings, RenderSettings, Sampler};
pub use super::techniques::Techniques;
use crate::gpu::{Batch, Buffer, Gpu};

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
    /// Its kernels trace several paths per invocation (path regeneration).
    pub regenerates_paths: bool,
    /// Where its random numbers come from unless `--sampler` says otherwise (None: its
    /// kernel draws independent random numbers only).
    pub default_sampler: Option<Sampler>,
    /// Builds its passes for a render.
    pub build: fn(&Build) -> Result<Box<dyn Estimator>>,
}

impl EstimatorInfo {
    /// A light-subpath estimator (lt, bpt, ppm, bpm, vcm): its value is radiance, it is
    /// consistent only when it merges, its kernels regenerate paths and shade with
    /// geometric normals, its camera subpaths draw Sobol samples by default, and its
    /// passes are [`bidirectional`]'s for `techniques`.
    pub const fn light_subpath(
        algorithm: Algorithm,
        name: &'static str,
        description: &'static str,
        techniques: Techniques,
        default_connect: Option<Connect>,
    ) -> EstimatorInfo {
        EstimatorInfo {
            algorithm,
            name,
            description,
            techniques,
            radiance: true,
            consistent_only: techniques.vertex_merging,
            default_connect,
            regenerates_paths: true,
            // The camera subpaths draw the Sobol samples; lt has none.
            default_sampler: if techniques.light_trace_only { None } else { Some(Sampler::Sobol) },
            build: bidirectional::build,
        }
    }

    /// Where this estimator's vertex connections go when `requested` (`None`: its
    /// default); any request is refused for an estimator without vertex connections, and
    /// a cache of 0 connections for every estimator.
    pub fn connect(&self, requested: Option<Connect>) -> Result<Connect> {
        let connect = match (requested, self.default_connect) {
            (None, default) => default.unwrap_or(Connect::Path),
            (Some(Connect::Cache(n)), None) => bail!(
                "connections to a light-vertex cache (cache:{n}) need an estimator that connects vertices (bpt, vcm), not {}",
                self.name
            ),
            (Some(Connect::Path), None) => bail!(
                "a connection strategy (path) is for the estimators that connect vertices (bpt, vcm), not {}",
                self.name
            ),
            (Some(c), Some(_)) => c,
        };
        if connect == Connect::Cache(0) {
            bail!("the light-vertex cache needs at least 1 connection per camera vertex");
        }
        Ok(connect)
    }

    /// Its sampler when `requested` (`None`: its default). A request it cannot honour is
    /// returned as is, for [`EstimatorInfo::check`] to refuse.
    pub fn sampler(&self, requested: Option<Sampler>) -> Sampler {
        requested.or(self.default_sampler).unwrap_or(Sampler::Independent)
    }

    /// Checks the settings that only concern this estimator.
    pub fn check(&self, s: &RenderSettings) -> Result<()> {
        if self.default_sampler.is_none() && s.sampler() != Sampler::Independent {
            bail!("--sampler {}: {} draws independent random numbers only", s.sampler().name(), self.name);
        }
        // Settings always hold a strategy: `Path` means none to the estimators without
        // vertex connections.
        if self.default_connect.is_some() || s.connect != Connect::Path {
            self.connect(Some(s.connect))?;
        }
        // Light vertices keep their path length in 8 bits (glsl/light_vertex_store.glsl); lt, which
        // stores none, keeps the same limit as the other light-subpath estimators.
        if self.techniques.light_subpaths && s.frame.max_path_length > 256 {
            bail!("max path length {} is more than the light-vertex store's 256", s.frame.max_path_length);
        }
        match s.light_paths {
            Some(_) if !self.techniques.light_subpaths => {
                bail!("--light-paths: {} traces no light subpaths (lt, bpt, ppm, bpm and vcm do)", self.name)
            }
            Some(0) => bail!("--light-paths must be at least 1"),
            _ => {}
        }
        if s.light_chunk_paths == Some(0) {
            bail!("light subpaths per chunk must be at least 1");
        }
        if s.light_vertex_capacity == Some(0) {
            bail!("the light-vertex store's capacity must be at least 1");
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

impl Build<'_> {
    /// What its passes are built from.
    pub fn passes(&self) -> PassContext<'_> {
        PassContext {
            gpu: self.gpu,
            scene: self.scene,
            film: self.film,
            pixels: self.plan.pixels,
            light_paths: self.plan.light_paths,
            paths_per_invocation: self.plan.paths_per_invocation,
        }
    }
}

impl RenderSettings {
    /// `algorithm`'s defaults at `width` x `height`.
    pub fn new(algorithm: Algorithm, width: u32, height: u32, budget: Budget) -> Self {
        RenderSettings {
            algorithm,
            frame: FrameSettings {
                width,
                height,
                seed: 1234,
                max_path_length: 10,
                min_path_length: 0,
                light_selection: super::settings::DEFAULT_LIGHT_SELECTION,
            },
            budget,
            nee: true,
            sampler: None,
            radius_factor: radius::DEFAULT_RADIUS_FACTOR,
            alpha: radius::DEFAULT_ALPHA,
            generic: false,
            count_rays: false,
            connect: algorithm.default_connect(),
            paths_per_invocation: None,
            reads: None,
            atomics: None,
            light_paths: None,
            light_chunk_paths: None,
            light_vertex_capacity: None,
        }
    }

    /// Where the kernels' random numbers come from: as set (`--sampler`), or the
    /// estimator's default.
    pub fn sampler(&self) -> Sampler {
        self.algorithm.info().sampler(self.sampler)
    }

    /// Light subpaths per iteration, N_L: as set (`--light-paths`), or one per pixel.
    pub fn light_paths(&self) -> u32 {
        self.light_paths.unwrap_or(self.frame.width.saturating_mul(self.frame.height))
    }

    /// Checks the settings every estimator shares, then the estimator's own
    /// ([`EstimatorInfo::check`]).
    pub fn check(&self) -> Result<()> {
        let (w, h) = (self.frame.width, self.frame.height);
        if w == 0 || h == 0 {
            bail!("image size {w}x{h}: width and height must be at least 1");
        }
        if w as u64 * h as u64 > u32::MAX as u64 {
            bail!("a {w}x{h} image has {} pixels, more than the 2^32 - 1 the kernels can index", w as u64 * h as u64);
        }
        if self.frame.max_path_length == 0 {
            bail!("max path length must be at least 1");
        }
        if self.paths_per_invocation == Some(0) {
            bail!("paths per invocation must be at least 1");
        }
        if let Budget::Iterations(0) = self.budget {
            bail!("iterations must be at least 1");
        }
        self.algorithm.info().check(self)
    }
}

/// An estimator built for one render: its passes, recorded once per iteration.
pub trait Estimator {
    /// Records iteration `iteration`'s passes into `batch`.
    fn record(&self, batch: &mut Batch, iteration: u32) -> Result<()>;
    /// The passes it records, in order, for `--verbose`.
    fn passes(&self) -> Vec<PassInfo>;
    /// The buffers it allocated (beyond the scene's and the film's).
    fn buffers(&self) -> Vec<&Buffer>;
    /// For an estimator that stores light vertices: what the light pass recorded of the
    /// iterations submitted so far (read back; the device must be idle).
    fn light_vertex_store(&self) -> Result<Option<StoreStatus>> {
        Ok(None)
    }
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
