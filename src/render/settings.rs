//! What a render is asked for: the estimator, the frame, the budget and the estimator's
//! options, with their defaults ([`RenderSettings::new`]) and their checks
//! ([`RenderSettings::check`]). What each estimator accepts comes from its entry in the
//! registry ([`Algorithm::info`], src/render/estimators/mod.rs); the command line parses
//! into these types (src/cli/render.rs).

use anyhow::{bail, Result};

use super::atomics::SplatAtomics;
use super::radius;
use super::reads::Reads;
use super::techniques::Techniques;

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

// ---- The registry: each estimator, what it is and which settings it takes.

impl Algorithm {
    /// The estimator's entry in the registry.
    pub fn info(self) -> &'static EstimatorInfo {
        match self {
            Algorithm::El => &EL,
            Algorithm::Pt => &PT,
            Algorithm::Lt => &LT,
            Algorithm::Bpt => &BPT,
            Algorithm::Ppm => &PPM,
            Algorithm::Bpm => &BPM,
            Algorithm::Vcm => &VCM,
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

/// What the registry knows of an estimator: what it is and which settings it takes. Its
/// passes are built by `Algorithm::build` (src/render/estimators/mod.rs).
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
}

impl EstimatorInfo {
    /// A light-subpath estimator (lt, bpt, ppm, bpm, vcm): its value is radiance, it is
    /// consistent only when it merges, its kernels regenerate paths and shade with
    /// geometric normals, its camera subpaths draw Sobol samples by default, and its
    /// passes are the shared ones of src/render/estimators/bidirectional.rs.
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
        // The AOVs come from camera paths, which light tracing does not trace.
        if s.aov.any() && self.techniques.light_trace_only {
            bail!(
                "--aov: {} traces no camera paths to take AOVs from; render them with the same \
                 camera and frame with --algo pt (or el, first hits only)",
                self.name
            );
        }
        Ok(())
    }
}

/// Eye light (`el`): |cos| at the first hit times the surface's tint, a preview and not
/// a radiance estimate. One pass: the camera kernel glsl/el.comp.
pub const EL: EstimatorInfo = EstimatorInfo {
    algorithm: Algorithm::El,
    name: "el",
    description: "Eye light: |cos| at the first hit, times its texture (a preview, not radiance).",
    techniques: Techniques::NONE,
    radiance: false,
    consistent_only: false,
    default_connect: None,
    regenerates_paths: false,
    default_sampler: None,
};

/// Path tracing (`pt`): BSDF sampling with next-event estimation, combined by the
/// balance heuristic. One pass: the camera kernel glsl/pt.comp.
pub const PT: EstimatorInfo = EstimatorInfo {
    algorithm: Algorithm::Pt,
    name: "pt",
    description: "Path tracing with next-event estimation and MIS.",
    techniques: Techniques::NONE,
    radiance: true,
    consistent_only: false,
    default_connect: None,
    regenerates_paths: true,
    default_sampler: Some(Sampler::Sobol),
};

/// Light tracing (`lt`): light subpaths connected to the camera, every vertex splatted
/// onto the pixel it projects to with weight 1 (no MIS), directly seen emitters
/// included. Passes: light subpaths (no vertex store), accumulate.
pub const LT: EstimatorInfo = EstimatorInfo::light_subpath(
    Algorithm::Lt,
    "lt",
    "Light tracing: light subpaths connected to the camera.",
    Techniques {
        light_subpaths: true,
        store_vertices: false,
        connect_to_camera: true,
        vertex_connection: false,
        vertex_merging: false,
        merge_first_vertex_only: false,
        light_trace_only: true,
    },
    None,
);

/// Bidirectional path tracing (`bpt`, vertex connection): every camera vertex connects
/// to the lights (next-event estimation) and to light vertices, every light vertex to the
/// camera, all weighted by SmallVCM's recursive MIS with merging off. Connections go to
/// vertices drawn from all light subpaths (`--connect cache`, the default: slightly better
/// at equal time, docs/estimators.md) or to light subpath p = this pixel
/// (`--connect path`, SmallVCM's layout). Passes: light subpaths (store vertices, connect
/// to the camera), camera subpaths.
pub const BPT: EstimatorInfo = EstimatorInfo::light_subpath(
    Algorithm::Bpt,
    "bpt",
    "Bidirectional path tracing (vertex connection), SmallVCM's MIS.",
    Techniques {
        light_subpaths: true,
        store_vertices: true,
        connect_to_camera: true,
        vertex_connection: true,
        vertex_merging: false,
        merge_first_vertex_only: false,
        light_trace_only: false,
    },
    Some(Connect::Cache(DEFAULT_CACHE_CONNECTIONS)),
);

/// Progressive photon mapping (`ppm`): camera subpaths follow specular bounces to the
/// first non-specular vertex and merge there with the light vertices within the radius
/// (weight 1, no MIS); the radius shrinks each iteration (src/render/radius.rs). Passes:
/// light subpaths (store vertices), grid build, camera subpaths.
pub const PPM: EstimatorInfo = EstimatorInfo::light_subpath(
    Algorithm::Ppm,
    "ppm",
    "Progressive photon mapping: merging at the first non-specular camera vertex.",
    Techniques {
        light_subpaths: true,
        store_vertices: true,
        connect_to_camera: false,
        vertex_connection: false,
        vertex_merging: true,
        merge_first_vertex_only: true,
        light_trace_only: false,
    },
    None,
);

/// Bidirectional photon mapping (`bpm`): merging at every non-specular camera vertex,
/// weighted by SmallVCM's recursive MIS with connections off. Passes: light subpaths
/// (store vertices), grid build, camera subpaths.
pub const BPM: EstimatorInfo = EstimatorInfo::light_subpath(
    Algorithm::Bpm,
    "bpm",
    "Bidirectional photon mapping: merging at every camera vertex, with MIS.",
    Techniques {
        light_subpaths: true,
        store_vertices: true,
        connect_to_camera: false,
        vertex_connection: false,
        vertex_merging: true,
        merge_first_vertex_only: false,
        light_trace_only: false,
    },
    None,
);

/// Vertex connection and merging (`vcm`, Georgiev et al. 2012): bpt's connections and
/// bpm's merging, all weighted by SmallVCM's recursive MIS; connections as bpt's. Passes:
/// light subpaths (store vertices, connect to the camera), grid build, camera subpaths.
pub const VCM: EstimatorInfo = EstimatorInfo::light_subpath(
    Algorithm::Vcm,
    "vcm",
    "Vertex connection and merging: bpt's connections and bpm's merging, with MIS.",
    Techniques {
        light_subpaths: true,
        store_vertices: true,
        connect_to_camera: true,
        vertex_connection: true,
        vertex_merging: true,
        merge_first_vertex_only: false,
        light_trace_only: false,
    },
    Some(Connect::Cache(DEFAULT_CACHE_CONNECTIONS)),
);

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

/// The default light selection: by power, so that next-event samples and light subpaths
/// are not spent on dim lights (docs/performance.md, "Defaults that matter for speed, and why").
pub const DEFAULT_LIGHT_SELECTION: LightSelection = LightSelection::Power;

/// How a light is chosen for next-event estimation and for a light subpath's start
/// (src/render/light_selection.rs; every estimator's MIS uses the same probabilities).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, clap::ValueEnum)]
pub enum LightSelection {
    /// In proportion to each light's emitted power (pbrt-v4's power light sampler).
    Power,
    /// Each light with probability 1 / #lights (SmallVCM).
    Uniform,
    /// Next-event estimation picks emissive triangles by a light tree that weighs them by
    /// their importance at the shading point (src/render/light_tree.rs), the other lights
    /// and light subpaths' starts by power.
    Tree,
}

impl LightSelection {
    /// `power` or `uniform`, as the command line and saved renders name it.
    pub fn name(self) -> &'static str {
        match self {
            LightSelection::Power => "power",
            LightSelection::Uniform => "uniform",
            LightSelection::Tree => "tree",
        }
    }

    /// Parses [`LightSelection::name`]'s output.
    pub fn parse(s: &str) -> Option<LightSelection> {
        match s {
            "power" => Some(LightSelection::Power),
            "uniform" => Some(LightSelection::Uniform),
            "tree" => Some(LightSelection::Tree),
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
    /// The most GPU time of one queue submission, in milliseconds (src/gpu/batch.rs: passes
    /// split into pieces of paths to fit); `None` chooses by device (500 on GPUs, none on
    /// CPU devices), 0 turns it off. The image does not depend on it.
    pub submission_budget_ms: Option<f64>,
    /// AOV layers to sum beside the image (`--aov`, src/render/aov.rs); none by default.
    pub aov: super::aov::AovSet,
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
                light_selection: DEFAULT_LIGHT_SELECTION,
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
            submission_budget_ms: None,
            aov: Default::default(),
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
