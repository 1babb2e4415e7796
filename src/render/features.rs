//! The feature set of a render: which material components, light kinds and geometry the
//! scene has, and which kernel stages the estimator runs. The kernels are compiled with
//! only that code (`HAS_...` defines, glsl/features.glsl); `--generic` compiles every
//! feature in, for comparison. Leaving out a feature the scene lacks does not change the
//! image: an absent material component has zero albedo in every material (so its
//! selection probability and contribution are 0, and it adds exact zeros to the sums), an
//! absent light kind is never picked, and the removed code draws no random numbers, so both
//! variants follow the same random sequence (tests/render_features.rs compares them).
//!
//! Textures: vkvcm has none (materials are constant per primitive), so there is nothing
//! to specialise; the feature set says so.

use std::fmt;

use glam::Vec3;
use serde::Serialize;

use super::bidir::Connect;
use super::Algorithm;
use crate::scene::{Light, Scene};

/// What the kernels of one render are compiled with.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct FeatureSet {
    #[serde(serialize_with = "algorithm_name")]
    pub algorithm: Algorithm,
    /// Every feature compiled in (`--generic`), whatever the scene has.
    pub generic: bool,
    /// Rays are counted (profiling: COUNT_RAYS).
    pub count_rays: bool,
    /// Material components of the materials that primitives use.
    pub diffuse: bool,
    pub phong: bool,
    pub ggx: bool,
    pub mirror: bool,
    pub dielectric: bool,
    /// Light kinds.
    pub area_lights: bool,
    pub point_lights: bool,
    pub spot_lights: bool,
    pub directional_lights: bool,
    pub background: bool,
    pub spheres: bool,
    /// Shading normals are uploaded and read (only `el` reads them: the estimators shade
    /// with geometric normals).
    pub shading_normals: bool,
    /// The scene has shading normals (whether or not the kernels read them).
    pub scene_has_shading_normals: bool,
    /// bpt, vcm: vertex connections to the matching light subpath or to a light-vertex
    /// cache (LV_CACHE, LV_CACHE_CONNECTIONS; the same in both variants).
    #[serde(serialize_with = "connect_name")]
    pub connect: Connect,
}

/// One kernel stage of an iteration.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct Stage {
    /// The stage's name in profiles: "light subpaths", "light-vertex prefix", "grid
    /// build", "camera subpaths", "accumulate" (src/gpu/profile.rs maps kernels to it).
    pub name: &'static str,
    /// What it does for this estimator.
    pub detail: &'static str,
}

/// The stages `algorithm` runs per iteration, in order (src/render/pt.rs, bidir.rs).
pub fn stages(algorithm: Algorithm) -> &'static [Stage] {
    const GRID: Stage =
        Stage { name: "grid build", detail: "hash grid over the light vertices (count, scan, scatter, sort)" };
    match algorithm {
        Algorithm::El => {
            &[Stage { name: "camera subpaths", detail: "el.comp: first hit, |cos| with the shading normal; film" }]
        }
        Algorithm::Pt => {
            &[Stage { name: "camera subpaths", detail: "pt.comp: BSDF sampling + next-event estimation, MIS; film" }]
        }
        Algorithm::Lt => &[
            Stage {
                name: "light subpaths",
                detail: "light_subpath.comp: connect to the camera (splats), no vertex store",
            },
            Stage { name: "accumulate", detail: "accumulate.comp: splats -> film" },
        ],
        Algorithm::Bpt => &[
            Stage { name: "light subpaths", detail: "light_subpath.comp: store vertices, connect to the camera" },
            Stage {
                name: "camera subpaths",
                detail: "camera_subpath.comp: NEE + vertex connections, MIS; splats -> film",
            },
        ],
        Algorithm::Ppm => &[
            Stage { name: "light subpaths", detail: "light_subpath.comp: store vertices" },
            GRID,
            Stage {
                name: "camera subpaths",
                detail: "camera_subpath.comp: merge at the first non-specular vertex; film",
            },
        ],
        Algorithm::Bpm => &[
            Stage { name: "light subpaths", detail: "light_subpath.comp: store vertices" },
            GRID,
            Stage { name: "camera subpaths", detail: "camera_subpath.comp: merging at every vertex, MIS; film" },
        ],
        Algorithm::Vcm => &[
            Stage { name: "light subpaths", detail: "light_subpath.comp: store vertices, connect to the camera" },
            GRID,
            Stage {
                name: "camera subpaths",
                detail: "camera_subpath.comp: NEE + connections + merging, MIS; splats -> film",
            },
        ],
    }
}

fn connect_name<S: serde::Serializer>(c: &Connect, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(&c.name())
}

fn algorithm_name<S: serde::Serializer>(a: &Algorithm, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(a.name())
}

fn nonzero(v: Vec3) -> bool {
    v != Vec3::ZERO
}

impl FeatureSet {
    /// The features of `scene` rendered with `algorithm`; with `generic` every feature is
    /// on (the scene's own features are still recorded in `scene_has_shading_normals`).
    pub fn new(scene: &Scene, algorithm: Algorithm, generic: bool) -> FeatureSet {
        // Only materials that a primitive uses can be evaluated.
        let mut used = vec![false; scene.materials.len()];
        let prims = scene.triangles.iter().map(|t| t.material).chain(scene.spheres.iter().map(|s| s.material));
        for m in prims {
            if let Some(u) = used.get_mut(m as usize) {
                *u = true;
            }
        }
        let mats: Vec<_> = scene.materials.iter().zip(&used).filter(|(_, u)| **u).map(|(m, _)| m).collect();
        let any_mat = |f: &dyn Fn(&crate::scene::Material) -> bool| mats.iter().any(|m| f(m));
        let any_light = |f: &dyn Fn(&Light) -> bool| scene.lights.iter().any(f);
        let scene_has_shading_normals = scene.triangles.iter().any(|t| t.n.is_some());
        let g = generic;
        FeatureSet {
            algorithm,
            generic,
            count_rays: false,
            diffuse: g || any_mat(&|m| nonzero(m.diffuse)),
            phong: g || any_mat(&|m| nonzero(m.phong)),
            ggx: g || any_mat(&|m| nonzero(m.glossy)),
            mirror: g || any_mat(&|m| nonzero(m.mirror)),
            // The kernels treat every IOR that is not negative (NaN included) as a dielectric.
            dielectric: g || any_mat(&|m| m.ior >= 0.0 || m.ior.is_nan()),
            area_lights: g || any_light(&|l| matches!(l, Light::Area { .. })),
            point_lights: g || any_light(&|l| matches!(l, Light::Point { .. })),
            spot_lights: g || any_light(&|l| matches!(l, Light::Spot { .. })),
            directional_lights: g || any_light(&|l| matches!(l, Light::Directional { .. })),
            background: g || any_light(&|l| matches!(l, Light::Background { .. })),
            spheres: g || !scene.spheres.is_empty(),
            shading_normals: g || (scene_has_shading_normals && algorithm == Algorithm::El),
            scene_has_shading_normals,
            connect: Connect::Path,
        }
    }

    /// Where bpt's and vcm's vertex connections go (kept `Path` for the other estimators,
    /// whose kernels have no connections).
    pub fn with_connect(mut self, connect: Connect) -> FeatureSet {
        if matches!(self.algorithm, Algorithm::Bpt | Algorithm::Vcm) {
            self.connect = connect;
        }
        self
    }

    /// Also compile the ray counter in (`--profile`).
    pub fn with_count_rays(mut self, on: bool) -> FeatureSet {
        self.count_rays = on;
        self
    }

    /// The `#define`s of every render kernel (glsl/features.glsl; BVH_NO_SPHERES for
    /// glsl/bvh.glsl).
    pub fn defines(&self) -> Vec<(String, String)> {
        let flag = |b: bool| if b { "1" } else { "0" }.to_string();
        let mut d: Vec<(String, String)> = [
            ("HAS_DIFFUSE", self.diffuse),
            ("HAS_PHONG", self.phong),
            ("HAS_GGX", self.ggx),
            ("HAS_MIRROR", self.mirror),
            ("HAS_DIELECTRIC", self.dielectric),
            ("HAS_AREA_LIGHTS", self.area_lights),
            ("HAS_POINT_LIGHTS", self.point_lights),
            ("HAS_SPOT_LIGHTS", self.spot_lights),
            ("HAS_DIRECTIONAL_LIGHTS", self.directional_lights),
            ("HAS_BACKGROUND", self.background),
            ("HAS_SPHERES", self.spheres),
            ("HAS_SHADING_NORMALS", self.shading_normals),
            ("COUNT_RAYS", self.count_rays),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), flag(v)))
        .collect();
        if !self.spheres {
            d.push(("BVH_NO_SPHERES".into(), "1".into()));
        }
        if let Connect::Cache(n) = self.connect {
            d.push(("LV_CACHE".into(), "1".into()));
            d.push(("LV_CACHE_CONNECTIONS".into(), n.to_string()));
        }
        d
    }

    /// The estimator's stages, with the light-vertex cache's prefix sum after the light
    /// subpaths when connecting to the cache.
    pub fn stages(&self) -> Vec<Stage> {
        let mut v = stages(self.algorithm).to_vec();
        if let Connect::Cache(_) = self.connect {
            let prefix = Stage {
                name: "light-vertex prefix",
                detail: "hash_grid_scan.comp: exclusive prefix sum of the per-path vertex counts, lv_cache_compact.comp: the stored vertices' slots in one list (light-vertex cache)",
            };
            v.insert(1, prefix);
        }
        v
    }
}

fn list(items: &[(&str, bool)]) -> String {
    let on: Vec<&str> = items.iter().filter(|(_, b)| *b).map(|(n, _)| *n).collect();
    let off: Vec<&str> = items.iter().filter(|(_, b)| !*b).map(|(n, _)| *n).collect();
    let mut s = if on.is_empty() { "none".to_string() } else { on.join(", ") };
    if !off.is_empty() {
        s += &format!(" (compiled out: {})", off.join(", "));
    }
    s
}

impl fmt::Display for FeatureSet {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let variant = if self.generic { "generic (--generic: every feature compiled in)" } else { "specialised" };
        writeln!(f, "kernels: {variant}, estimator {}", self.algorithm.name())?;
        let mats = [
            ("diffuse", self.diffuse),
            ("phong", self.phong),
            ("ggx", self.ggx),
            ("mirror", self.mirror),
            ("dielectric", self.dielectric),
        ];
        writeln!(f, "  materials: {}", list(&mats))?;
        let lights = [
            ("area", self.area_lights),
            ("point", self.point_lights),
            ("spot", self.spot_lights),
            ("directional", self.directional_lights),
            ("background", self.background),
        ];
        writeln!(f, "  lights: {}", list(&lights))?;
        writeln!(f, "  geometry: {}", list(&[("triangles", true), ("spheres", self.spheres)]))?;
        let normals = match (self.scene_has_shading_normals, self.shading_normals) {
            (_, true) => "read (uploaded)",
            (true, false) => "in the scene, not read by this estimator (geometric normals): not uploaded",
            (false, false) => "none in the scene",
        };
        writeln!(f, "  shading normals: {normals}")?;
        writeln!(f, "  textures: none (not supported by vkvcm)")?;
        writeln!(f, "  ray counter: {}", if self.count_rays { "on (--profile)" } else { "off" })?;
        if matches!(self.algorithm, Algorithm::Bpt | Algorithm::Vcm) {
            let c = match self.connect {
                Connect::Path => "to the vertices of light subpath p = this pixel (--connect path)".to_string(),
                Connect::Cache(n) => {
                    format!("to {n} light vertex(es) per camera vertex drawn from all light subpaths (--connect cache)")
                }
            };
            writeln!(f, "  vertex connections: {c}")?;
        }
        writeln!(f, "  stages per iteration:")?;
        for s in self.stages() {
            writeln!(f, "    {}: {}", s.name, s.detail)?;
        }
        let defines: Vec<String> = self.defines().into_iter().map(|(k, v)| format!("{k}={v}")).collect();
        write!(f, "  defines: {}", defines.join(" "))
    }
}

/// `(name, bytes)` of buffers as a table with MiB, and the total.
pub fn buffer_table(buffers: &[(String, u64)]) -> String {
    let w = buffers.iter().map(|(n, _)| n.len()).max().unwrap_or(6).max(6);
    let mib = |b: u64| b as f64 / (1024.0 * 1024.0);
    let mut s = format!("  {:<w$} {:>10}\n", "buffer", "MiB");
    for (n, b) in buffers {
        s += &format!("  {n:<w$} {:>10.3}\n", mib(*b));
    }
    let total: u64 = buffers.iter().map(|(_, b)| b).sum();
    s += &format!("  {:<w$} {:>10.3}\n", "total", mib(total));
    s
}
