//! What a render is asked for: the estimator, the frame, the budget and the estimator's
//! options. Checked once, by [`RenderSettings::check`] and the estimator's own
//! [`super::estimators::EstimatorInfo::check`], before anything is allocated.

use anyhow::{bail, Result};

use super::estimators::Algorithm;
use super::radius;
use super::reads::Reads;

/// When a render stops.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Budget {
    Iterations(u64),
    /// Wall-clock seconds (at least one iteration runs).
    Seconds(f64),
}

/// Settings that shape the kernels' per-render constants.
#[derive(Clone, Debug)]
pub struct FrameSettings {
    pub width: u32,
    pub height: u32,
    pub seed: u32,
    /// Longest path in segments (SmallVCM default 10).
    pub max_path_length: u32,
    pub min_path_length: u32,
}

/// Where a camera vertex's vertex connections go (bpt, vcm). Every choice is unbiased
/// with the same MIS weights: see glsl/camera_subpath.comp and docs/estimators.md.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Connect {
    /// To every stored vertex of light subpath p = this pixel (SmallVCM).
    Path,
    /// To this many vertices drawn uniformly from all light subpaths' stored vertices
    /// (light-vertex cache, Davidovic et al. 2014), each weighted by
    /// (stored vertices) / (light subpaths x this many).
    Cache(u32),
}

/// Default light vertices per camera vertex of `--connect cache`: 1 measured better at
/// equal time than 2 and 4 (docs/estimators.md).
pub const DEFAULT_CACHE_CONNECTIONS: u32 = 1;

impl Connect {
    /// `path` or `cache:N`, as settings and saved renders show it.
    pub fn name(self) -> String {
        match self {
            Connect::Path => "path".into(),
            Connect::Cache(n) => format!("cache:{n}"),
        }
    }

    /// Parses [`Connect::name`]'s output.
    pub fn parse(s: &str) -> Option<Connect> {
        match s {
            "path" => Some(Connect::Path),
            _ => s.strip_prefix("cache:")?.parse().ok().filter(|&n| n > 0).map(Connect::Cache),
        }
    }
}

#[derive(Clone, Debug)]
pub struct RenderSettings {
    pub algorithm: Algorithm,
    pub frame: FrameSettings,
    pub budget: Budget,
    /// Path tracing only: `false` disables next-event estimation (BSDF sampling only).
    pub nee: bool,
    /// Initial merge radius as a fraction of the scene's bounding-sphere radius.
    pub radius_factor: f32,
    /// Radius reduction exponent alpha of r_i = r_0 (i+1)^((alpha-1)/2).
    pub alpha: f32,
    /// Kernels with every scene feature compiled in, instead of only the scene's
    /// (src/render/features.rs); the image is the same.
    pub generic: bool,
    /// Count the rays traced (`Profile::rays`; a few atomics per invocation).
    pub count_rays: bool,
    /// bpt and vcm: where vertex connections go (SmallVCM's matching light subpath or a
    /// light-vertex cache); must be `Path` for the other estimators.
    pub connect: Connect,
    /// Paths per kernel invocation (path regeneration, src/render/regen.rs); `None`
    /// chooses by device. The image does not depend on it.
    pub paths_per_invocation: Option<u32>,
    /// How the kernels read their read-only buffers (src/render/reads.rs); `None` chooses
    /// by device. The image does not depend on it.
    pub reads: Option<Reads>,
}

impl RenderSettings {
    /// `algorithm`'s defaults at `width` x `height`.
    pub fn new(algorithm: Algorithm, width: u32, height: u32, budget: Budget) -> Self {
        RenderSettings {
            algorithm,
            frame: FrameSettings { width, height, seed: 1234, max_path_length: 10, min_path_length: 0 },
            budget,
            nee: true,
            radius_factor: radius::DEFAULT_RADIUS_FACTOR,
            alpha: radius::DEFAULT_ALPHA,
            generic: false,
            count_rays: false,
            connect: algorithm.default_connect(),
            paths_per_invocation: None,
            reads: None,
        }
    }

    /// Checks the settings every estimator shares, then the estimator's own.
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
