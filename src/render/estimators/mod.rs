//! The estimators, one module each: the passes each builds ([`Algorithm::build`]) and
//! records per iteration. What each estimator is and which settings it takes is its
//! registry entry in src/render/settings.rs ([`Algorithm::info`]).
//!
//! An estimator is a sequence of passes (src/render/passes/) recorded once per
//! iteration; [`Estimator`] is what the renderer holds. pt and el are one camera pass
//! each; lt, bpt, ppm, bpm and vcm share one pass sequence ([`bidirectional`]) and differ
//! in the [`Techniques`] they turn on.

pub mod bidirectional;
pub mod el;
pub mod pt;

use std::sync::Arc;

use anyhow::Result;

use super::film::Film;
use super::light_vertex_store::StoreUse;
use super::passes::{PassContext, PassInfo};
use super::plan::FramePlan;
use super::scene_gpu::SceneGpu;
use super::settings::RenderSettings;
pub use super::settings::{Algorithm, EstimatorInfo, ALGORITHMS};
pub use super::techniques::Techniques;
use crate::gpu::{Batch, Buffer, Gpu};

impl Algorithm {
    /// Builds the estimator's passes for the render `b`.
    pub fn build(self, b: &Build) -> Result<Box<dyn Estimator>> {
        match self {
            Algorithm::El => el::build(b),
            Algorithm::Pt => pt::build(b),
            Algorithm::Lt | Algorithm::Bpt | Algorithm::Ppm | Algorithm::Bpm | Algorithm::Vcm => {
                bidirectional::build(b)
            }
        }
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

/// An estimator built for one render: its passes, recorded once per iteration.
pub trait Estimator {
    /// Records iteration `iteration`'s passes into `batch`.
    fn record(&self, batch: &mut Batch, iteration: u32) -> Result<()>;
    /// The passes it records, in order, for `--verbose`.
    fn passes(&self) -> Vec<PassInfo>;
    /// The buffers it allocated (beyond the scene's and the film's).
    fn buffers(&self) -> Vec<&Buffer>;
    /// After the batch of iterations `first .. first + n` has run (the device is idle):
    /// how many of them are in the film. The light-subpath estimators check their
    /// light-vertex store here; when an iteration did not fit, they grow it and rebuild
    /// their passes from `b` (src/render/light_vertex_store.rs), and the iterations left
    /// out are rendered again.
    fn finish_batch(&mut self, _b: &Build, _first: u64, n: u64) -> Result<BatchEnd> {
        Ok(BatchEnd { accepted: n, note: None })
    }
    /// How the light-vertex store was used so far (None: it stores no light vertices).
    fn light_vertex_store_use(&self) -> Option<StoreUse> {
        None
    }
}

/// What [`Estimator::finish_batch`] found.
pub struct BatchEnd {
    /// The batch's first iterations that are in the film.
    pub accepted: u64,
    /// A line for the progress display (the store grew).
    pub note: Option<String>,
}
