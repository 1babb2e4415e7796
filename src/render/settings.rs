//! What a render is asked for: the estimator, the frame, the budget and the estimator's
//! options. The types only: an estimator's defaults and checks are in the registry that
//! [`Algorithm`] keys (src/render/estimators/mod.rs: `RenderSettings::new`,
//! `RenderSettings::check`, `Algorithm::info`).

use super::atomics::SplatAtomics;
use super::reads::Reads;

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
    /// How next-event estimation and light subpaths choose a light.
    pub light_selection: LightSelection,
}

/// The default light selection: by power (docs/performance.md, "Light selection by
/// power", measured against uniform).
pub const DEFAULT_LIGHT_SELECTION: LightSelection = LightSelection::Power;

/// How a light is chosen for next-event estimation and for a light subpath's start
/// (src/render/light_selection.rs; every estimator's MIS uses the same probabilities).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, clap::ValueEnum)]
pub enum LightSelection {
    /// In proportion to each light's emitted power (pbrt-v4's power light sampler).
    Power,
    /// Each light with probability 1 / #lights (SmallVCM).
    Uniform,
}

impl LightSelection {
    /// `power` or `uniform`, as the command line and saved renders name it.
    pub fn name(self) -> &'static str {
        match self {
            LightSelection::Power => "power",
            LightSelection::Uniform => "uniform",
        }
    }

    /// Parses [`LightSelection::name`]'s output.
    pub fn parse(s: &str) -> Option<LightSelection> {
        match s {
            "power" => Some(LightSelection::Power),
            "uniform" => Some(LightSelection::Uniform),
            _ => None,
        }
    }
}

/// Where the camera paths' random numbers come from (glsl/path_sampler.glsl).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, clap::ValueEnum)]
pub enum Sampler {
    /// Owen-scrambled Sobol points per pixel, each sample dimension with its own
    /// scramble (Burley 2020; pbrt-v4's padded Sobol sampler): a pixel's samples are
    /// stratified across iterations. The default of every estimator with camera paths
    /// (pt, bpt, ppm, bpm, vcm).
    Sobol,
    /// Independent pseudo-random numbers (a PCG stream per path and iteration).
    Independent,
}

impl Sampler {
    /// `sobol` or `independent`, as the command line and saved renders name it.
    pub fn name(self) -> &'static str {
        match self {
            Sampler::Sobol => "sobol",
            Sampler::Independent => "independent",
        }
    }
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

/// Default light vertices per camera vertex of `--connect cache` (bpt's and vcm's
/// default): 1 measured better at equal time than 2 (bpt and vcm) and 4 (bpt;
/// docs/estimators.md).
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
    /// Where the kernels' random numbers come from; `None`: the estimator's default
    /// ([`RenderSettings::sampler`]). lt and el take `Independent` only.
    pub sampler: Option<Sampler>,
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
    /// How splats are summed (src/render/atomics.rs); `None` chooses by device. The image
    /// does not depend on it.
    pub atomics: Option<SplatAtomics>,
    /// Light subpaths per iteration, N_L (the light-subpath estimators); `None`: one per
    /// pixel, SmallVCM's choice ([`RenderSettings::light_paths`]).
    pub light_paths: Option<u32>,
    /// The most light subpaths the light pass traces in one chunk
    /// (src/render/passes/light_subpaths.rs); `None`: as many as the scratch budget holds.
    /// The image does not depend on it.
    pub light_chunk_paths: Option<u32>,
    /// The light-vertex store's first capacity in vertices; `None`: an estimate from N_L.
    /// The store grows when an iteration needs more; the image does not depend on it.
    pub light_vertex_capacity: Option<u64>,
}
