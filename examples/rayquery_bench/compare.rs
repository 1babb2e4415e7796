//! vkvcm's BVH traversal (`glsl/tests/bvh_bench.comp`, as in `vkvcm-bench traverse`) against
//! the driver's VK_KHR_ray_query on the same triangles and the same rays
//! (`vkvcm_tools::bench::traverse::{bench_scene, bench_ray_sets}`), interleaved per ray set so that
//! other load on the machine hits both alike.

use std::sync::Arc;

use anyhow::{anyhow, Result};
use vkvcm::bvh::{build_with, BuildOptions, GpuBvh, Ray};
use vkvcm::gpu::{groups_for, Bind, Gpu, GpuOptions, Profile};
use vkvcm_tools::bench::traverse::{bench_ray_sets, bench_scene, BenchRay, BenchScene};

use crate::rq::RqDevice;

/// Relative tolerance on closest-hit distances.
pub const T_TOLERANCE: f64 = 1e-4;

#[derive(Clone, Debug)]
pub struct Options {
    pub scenes: Vec<String>,
    pub rays: u32,
    /// Timed rounds; each round times one vkvcm and one ray-query dispatch per ray set,
    /// alternating which goes first.
    pub rounds: u32,
    pub validation: bool,
    /// Device index or name substring for vkvcm's `Gpu` (the ray-query side opens the
    /// same device by name).
    pub device: Option<String>,
    /// Differing rays to describe per ray set.
    pub show_differences: usize,
}

/// One scene and ray set.
#[derive(Clone, Debug)]
pub struct Row {
    pub scene: String,
    pub rays: &'static str,
    pub count: u32,
    /// Per-round dispatch times, ms (GPU timestamps).
    pub vkvcm_ms: Vec<f64>,
    pub rq_ms: Vec<f64>,
    /// Rays where the ray query's closest hit differs from the CPU traversal of vkvcm's
    /// BVH: hit vs miss, or distance beyond `T_TOLERANCE` relative.
    pub t_differ: u32,
    /// Rays where the two report different triangles (shared edges, coplanar faces).
    pub prim_differ: u32,
    /// Rays where vkvcm's GPU kernel and its CPU traversal hit different triangles.
    pub vkvcm_gpu_cpu_differ: u32,
    pub hit_fraction: f64,
    /// The first `Options::show_differences` rays whose distances differ, described.
    pub differences: Vec<String>,
}

fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len();
    if n == 0 {
        f64::NAN
    } else if n % 2 == 1 {
        s[n / 2]
    } else {
        0.5 * (s[n / 2 - 1] + s[n / 2])
    }
}

impl Row {
    pub fn vkvcm_mrays(&self) -> f64 {
        self.count as f64 / median(&self.vkvcm_ms) * 1e-3
    }
    pub fn rq_mrays(&self) -> f64 {
        self.count as f64 / median(&self.rq_ms) * 1e-3
    }
    /// Per-round vkvcm / ray-query speed ratios (= rq time / vkvcm time).
    pub fn ratios(&self) -> Vec<f64> {
        self.vkvcm_ms.iter().zip(&self.rq_ms).map(|(v, r)| r / v).collect()
    }
    pub fn median_ratio(&self) -> f64 {
        median(&self.ratios())
    }
}

/// Build figures of one scene.
#[derive(Clone, Debug)]
pub struct SceneBuild {
    pub scene: String,
    pub triangles: usize,
    /// vkvcm's CPU SAH build (threads), s.
    pub vkvcm_build_s: f64,
    pub vkvcm_bytes: usize,
    /// The driver's BLAS and TLAS builds (device timestamps) and the build submission's
    /// wall time, s.
    pub blas_s: f64,
    pub tlas_s: f64,
    pub rq_build_wall_s: f64,
    pub blas_bytes: u64,
}

pub struct Report {
    pub device: String,
    pub driver: String,
    pub builds: Vec<SceneBuild>,
    pub rows: Vec<Row>,
    pub validation_messages: Vec<String>,
}

/// Runs the comparison. `Ok(Err(reason))` when the device has no ray queries.
pub fn run(opts: &Options) -> Result<std::result::Result<Report, String>> {
    // No kernel cache: it builds one kernel, and tests/rayquery_bench.rs runs this too.
    let gpu = Gpu::new(&GpuOptions {
        device: opts.device.clone(),
        validation: opts.validation,
        kernel_cache: None,
        device_addresses: true,
    })?;
    let rq = match RqDevice::new(&gpu.info.name, opts.validation)? {
        Ok(d) => d,
        Err(why) => return Ok(Err(why)),
    };
    let mut builds = Vec::new();
    let mut rows = Vec::new();
    for name in &opts.scenes {
        let scene = bench_scene(name).ok_or_else(|| anyhow!("unknown scene {name:?} (cornell, spheres, displaced)"))?;
        let (b, r) = compare_scene(&gpu, &rq, &scene, opts)?;
        builds.push(b);
        rows.extend(r);
    }
    let mut validation_messages = gpu.validation_messages().list();
    validation_messages.extend(rq.messages());
    Ok(Ok(Report { device: rq.name.clone(), driver: rq.driver.clone(), builds, rows, validation_messages }))
}

fn compare_scene(gpu: &Arc<Gpu>, rq: &RqDevice, scene: &BenchScene, opts: &Options) -> Result<(SceneBuild, Vec<Row>)> {
    if !scene.spheres.is_empty() {
        // The bench scenes tessellate their spheres; analytic ones would need procedural
        // AABB geometry and an intersection in the ray-query shader.
        return Err(anyhow!("scene {} has analytic spheres: not supported by this comparison", scene.name));
    }
    let bvh = build_with(&scene.triangles, &scene.spheres, &BuildOptions::default());
    let vkvcm_build_s = bvh.stats.build_seconds;
    let g: GpuBvh = bvh.into_gpu();
    let rq_scene = rq.build(&scene.triangles)?;
    let build = SceneBuild {
        scene: scene.name.clone(),
        triangles: scene.triangles.len(),
        vkvcm_build_s,
        vkvcm_bytes: g.size_bytes(),
        blas_s: rq_scene.blas_ms * 1e-3,
        tlas_s: rq_scene.tlas_ms * 1e-3,
        rq_build_wall_s: rq_scene.build_wall_ms * 1e-3,
        blas_bytes: rq_scene.blas_bytes,
    };
    let nodes = gpu.buffer_from_slice("bvh_nodes", &g.nodes)?;
    let prims = gpu.buffer_from_slice("bvh_prims", &g.prims)?;
    let mut defines: Vec<(&str, &str)> = vec![("MODE", "0"), ("LOCAL_SIZE", "64")];
    let bvh_defines = g.glsl_defines();
    defines.extend(bvh_defines.iter().map(|(k, v)| (*k, v.as_str())));

    let mut rows = Vec::new();
    for (label, rays) in bench_ray_sets(scene, opts.rays) {
        let data: Vec<BenchRay> = rays.iter().map(|&(o, d)| BenchRay::new(o, d)).collect();
        let n = data.len() as u32;
        let ray_buf = gpu.buffer_from_slice("bench_rays", &data)?;
        let out = gpu.buffer_zeroed::<u32>("bench_results", data.len())?;
        let binds = [Bind::own(&nodes), Bind::own(&prims), Bind::own(&ray_buf), Bind::own(&out)];
        let kernel = gpu.kernel("tests/bvh_bench.comp", &defines, &binds)?;
        let mut batch = gpu.batch()?;
        let groups = [groups_for(n, 64), 1, 1];
        let mut vkvcm_dispatch = || -> Result<f64> {
            let mut profile = Profile::default();
            batch.dispatch(&kernel, groups, bytemuck::bytes_of(&n))?;
            batch.submit_wait(Some(&mut profile))?;
            Ok(profile.total_ms())
        };
        let rq_rays = rq.rays(&data)?;
        // Warm-up: lavapipe compiles each pipeline at its first dispatch.
        vkvcm_dispatch()?;
        rq.trace(&rq_scene, &rq_rays)?;
        let (mut vkvcm_ms, mut rq_ms) = (Vec::new(), Vec::new());
        for round in 0..opts.rounds.max(1) {
            if round % 2 == 0 {
                vkvcm_ms.push(vkvcm_dispatch()?);
                rq_ms.push(rq.trace(&rq_scene, &rq_rays)?);
            } else {
                rq_ms.push(rq.trace(&rq_scene, &rq_rays)?);
                vkvcm_ms.push(vkvcm_dispatch()?);
            }
        }
        // Correctness: every ray against the CPU traversal of vkvcm's BVH (the GPU
        // kernel's mirror).
        let vk_prims: Vec<u32> = out.read()?;
        let rq_res = rq.results(&rq_rays);
        rq.free_rays(rq_rays);
        let (mut t_differ, mut prim_differ, mut gpu_cpu, mut hits) = (0, 0, 0, 0u64);
        let mut differences = Vec::new();
        for (i, &(o, d)) in rays.iter().enumerate() {
            let cpu = g.closest_hit(&Ray { o, d }, 0.0, 1e30);
            let (rt, rp) = rq_res[i];
            let rq_hit = (rp != u32::MAX).then_some((rt, rp));
            gpu_cpu += u32::from(vk_prims[i] != cpu.as_ref().map_or(u32::MAX, |h| h.prim));
            hits += u64::from(cpu.is_some());
            let differs = match (&cpu, rq_hit) {
                (None, None) => false,
                (Some(h), Some((t, p))) => {
                    let rel = (t as f64 - h.t as f64).abs() / (h.t as f64).abs().max(1e-30);
                    prim_differ += u32::from(p != h.prim);
                    // A NaN distance counts as differing.
                    rel.is_nan() || rel > T_TOLERANCE
                }
                _ => {
                    prim_differ += 1;
                    true
                }
            };
            t_differ += u32::from(differs);
            if differs && differences.len() < opts.show_differences {
                differences.push(format!(
                    "ray {i}: o {o:?} d {d:?}: vkvcm (CPU) {:?}, ray query {:?}",
                    cpu.as_ref().map(|h| (h.t, h.prim)),
                    rq_hit
                ));
            }
        }
        rows.push(Row {
            scene: scene.name.clone(),
            rays: label,
            count: n,
            vkvcm_ms,
            rq_ms,
            t_differ,
            prim_differ,
            vkvcm_gpu_cpu_differ: gpu_cpu,
            hit_fraction: hits as f64 / n.max(1) as f64,
            differences,
        });
    }
    rq.free_scene(rq_scene);
    Ok((build, rows))
}
