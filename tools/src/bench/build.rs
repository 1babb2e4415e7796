//! BVH build benchmark (`vkvcm-bench bvh-build`): wall-clock build seconds per million
//! triangles, per thread count, on generated meshes of 1M and 4M triangles or on loaded
//! scenes; and whether every thread count built the same BVH.
//!
//! Generated meshes ([`build_scene`]): `spheres` and `displaced` are the 1M-triangle
//! traversal scenes ([`super::traverse::bench_scene`]); `spheres-4m` (16,384 UV spheres,
//! 4,194,304 triangles) and `displaced-4m` (cube-sphere of 578^2 * 12 = 4,009,008
//! triangles) are the same kinds at four times the size. Anything else is loaded as a
//! scene ([`vkvcm::scene::load_named`]: a built-in name or a glTF path). No GPU is used.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context, Result};
use serde::Serialize;

use super::traverse::{bench_scene, displaced_sphere, process_cpu_seconds, sphere_grid};
use vkvcm::bvh::{build_instanced, BuildOptions, Bvh, LeafRule};
use vkvcm::scene::{self, Instance, SharedMesh, Sphere, Triangle};

/// The generated meshes [`build_scene`] knows.
pub const BUILD_SCENES: &[&str] = &["spheres", "displaced", "spheres-4m", "displaced-4m"];

/// The primitives of one benchmark scene.
pub struct BuildScene {
    pub name: String,
    /// World-space triangles, then the shared meshes' (see [`vkvcm::scene::Scene`]).
    pub triangles: Vec<Triangle>,
    pub spheres: Vec<Sphere>,
    pub meshes: Vec<SharedMesh>,
    pub instances: Vec<Instance>,
}

/// A generated mesh of [`BUILD_SCENES`], else a scene loaded by name or path.
pub fn build_scene(name: &str) -> Result<BuildScene> {
    let generated = |triangles| {
        Ok(BuildScene { name: name.to_string(), triangles, spheres: Vec::new(), meshes: vec![], instances: vec![] })
    };
    match name {
        "spheres-4m" => generated(sphere_grid([32, 16, 32])),
        "displaced-4m" => generated(displaced_sphere(578)),
        _ => match bench_scene(name) {
            Some(s) => Ok(BuildScene {
                name: s.name,
                triangles: s.triangles,
                spheres: s.spheres,
                meshes: vec![],
                instances: vec![],
            }),
            None => {
                let s = scene::load_named(name).with_context(|| {
                    format!("{name:?} is neither a generated mesh ({}) nor a loadable scene", BUILD_SCENES.join(", "))
                })?;
                Ok(BuildScene {
                    name: name.to_string(),
                    triangles: s.triangles,
                    spheres: s.spheres,
                    meshes: s.meshes,
                    instances: s.instances,
                })
            }
        },
    }
}

/// Writes `scene`'s triangles to `dir/NAME.f32`, the name's characters other than ASCII
/// letters, digits, `-` and `_` replaced by `_`: 9 little-endian `f32` per triangle (the
/// three vertices; spheres are left out; an instanced scene's stored triangles, its
/// shared meshes in object space). Returns the path.
pub fn export_triangles(scene: &BuildScene, dir: &Path) -> Result<PathBuf> {
    let stem: String =
        scene.name.chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' || c == '_' { c } else { '_' }).collect();
    let path = dir.join(format!("{stem}.f32"));
    let mut bytes = Vec::with_capacity(scene.triangles.len() * 36);
    for t in &scene.triangles {
        for v in t.p {
            for x in v.to_array() {
                bytes.extend_from_slice(&x.to_le_bytes());
            }
        }
    }
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    std::fs::write(&path, bytes).with_context(|| format!("cannot write {}", path.display()))?;
    Ok(path)
}

/// Build times of one scene at one thread count.
#[derive(Clone, Debug, Serialize)]
pub struct BuildRow {
    pub scene: String,
    pub triangles: usize,
    pub spheres: usize,
    /// Builder threads (`BuildOptions::threads`; 0 = all cores).
    pub threads: usize,
    pub rounds: u32,
    /// Fastest and median wall-clock build over the rounds (`BuildStats::build_seconds`).
    pub min_seconds: f64,
    pub median_seconds: f64,
    /// Median process CPU time (user + system, all threads) per build: less sensitive to
    /// other load on the machine than wall-clock time; `None` where /proc is missing.
    pub median_cpu_seconds: Option<f64>,
    /// Median seconds per 1,000,000 primitives (triangles + spheres).
    pub seconds_per_million: f64,
    pub nodes: usize,
    pub sah_cost: f64,
    /// CRC-32 of the BVH's node and primitive arrays (to compare builds across versions).
    pub checksum: u32,
    /// The BVH (nodes and primitives) equals the first thread count's, bit for bit.
    pub same_as_first: bool,
}

/// Builds `scene` `rounds` times with each of `threads` and `leaf_rule` (default options
/// otherwise), and compares every BVH with the first one built.
pub fn bench_build(scene: &BuildScene, threads: &[usize], rounds: u32, leaf_rule: LeafRule) -> Result<Vec<BuildRow>> {
    if threads.is_empty() || rounds == 0 {
        bail!("need at least one thread count and one round");
    }
    let prims = (scene.triangles.len() + scene.spheres.len()).max(1);
    let mut first: Option<Bvh> = None;
    let mut rows = Vec::new();
    for &t in threads {
        let opts = BuildOptions { threads: t, leaf_rule, ..Default::default() };
        let mut seconds = Vec::new();
        let mut cpu_seconds = Vec::new();
        let mut same = true;
        for _ in 0..rounds {
            let cpu_start = process_cpu_seconds();
            let start = Instant::now();
            let bvh = build_instanced(&scene.triangles, &scene.spheres, &scene.meshes, &scene.instances, &opts);
            seconds.push(start.elapsed().as_secs_f64());
            if let (Some(a), Some(b)) = (cpu_start, process_cpu_seconds()) {
                cpu_seconds.push(b - a);
            }
            match &first {
                Some(f) => same &= f.nodes == bvh.nodes && f.prims == bvh.prims,
                None => first = Some(bvh),
            }
        }
        seconds.sort_by(f64::total_cmp);
        cpu_seconds.sort_by(f64::total_cmp);
        let median = seconds[seconds.len() / 2];
        let reference = first.as_ref().expect("one build done");
        rows.push(BuildRow {
            scene: scene.name.clone(),
            triangles: scene.triangles.len(),
            spheres: scene.spheres.len(),
            threads: t,
            rounds,
            min_seconds: seconds[0],
            median_seconds: median,
            median_cpu_seconds: (cpu_seconds.len() == seconds.len()).then(|| cpu_seconds[cpu_seconds.len() / 2]),
            seconds_per_million: median * 1e6 / prims as f64,
            nodes: reference.stats.nodes,
            sah_cost: reference.stats.sah_cost,
            checksum: checksum(reference),
            same_as_first: same,
        });
    }
    Ok(rows)
}

/// CRC-32 of the node array's bytes followed by the primitive array's.
pub fn checksum(bvh: &Bvh) -> u32 {
    let mut h = crc32fast::Hasher::new();
    h.update(bytemuck::cast_slice(&bvh.nodes));
    h.update(bytemuck::cast_slice(&bvh.prims));
    h.finalize()
}

impl std::fmt::Display for BuildRow {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let threads = if self.threads == 0 { "all".to_string() } else { self.threads.to_string() };
        let cpu = self.median_cpu_seconds.map_or("-".to_string(), |c| format!("{c:.3} s"));
        write!(
            f,
            "{}: {} triangles, {} spheres, threads {threads}: median {:.3} s (min {:.3} s, CPU {cpu}) over {} rounds = {:.3} s per 1M primitives; {} nodes, SAH cost {:.1}, checksum {:08x}, {}",
            self.scene,
            self.triangles,
            self.spheres,
            self.median_seconds,
            self.min_seconds,
            self.rounds,
            self.seconds_per_million,
            self.nodes,
            self.sah_cost,
            self.checksum,
            if self.same_as_first { "same BVH as the first thread count" } else { "BVH DIFFERS from the first thread count" }
        )
    }
}
