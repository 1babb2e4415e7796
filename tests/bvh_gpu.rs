//! GPU traversal (glsl/bvh.glsl) against the CPU brute force and the CPU traversal, on
//! lavapipe (or VKVCM_TEST_DEVICE) with validation on.

mod bvh_common;
mod common;

use std::sync::Arc;

use bvh_common::*;
use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use rand::Rng;
use vkvcm::bvh::{brute_force_closest, build, build_with, BuildOptions, GpuBvh, Hit, LeafRule, Ray};
use vkvcm::gpu::{groups_for, Bind, Gpu};

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct TestRay {
    o: [f32; 4], // w = tmin
    d: [f32; 4], // w = tmax
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct TestHit {
    t: f32,
    prim: u32,
    u: f32,
    v: f32,
    flags: u32,
    material: u32,
    instance_record: u32,
    pad: u32,
}

struct GpuResult {
    closest: Option<Hit>,
    any: bool,
    /// The record slot of the instance hit (0xffffffff: none).
    instance_record: u32,
}

/// Runs glsl/tests/test_bvh_trace.comp over `rays`.
fn trace_on_gpu(gpu: &Arc<Gpu>, bvh: &GpuBvh, rays: &[(Ray, f32, f32)]) -> Vec<GpuResult> {
    trace_on_gpu_with(gpu, bvh, rays, false)
}

fn trace_on_gpu_with(gpu: &Arc<Gpu>, bvh: &GpuBvh, rays: &[(Ray, f32, f32)], vec4: bool) -> Vec<GpuResult> {
    let data: Vec<TestRay> = rays
        .iter()
        .map(|(r, tmin, tmax)| TestRay { o: [r.o.x, r.o.y, r.o.z, *tmin], d: [r.d.x, r.d.y, r.d.z, *tmax] })
        .collect();
    let nodes = gpu.buffer_from_slice("bvh_nodes", &bvh.nodes).unwrap();
    let prims = gpu.buffer_from_slice("bvh_prims", &bvh.prims).unwrap();
    let ray_buf = gpu.buffer_from_slice("rays", &data).unwrap();
    let out = gpu.buffer_zeroed::<TestHit>("hits", data.len()).unwrap();
    let defines = bvh.glsl_defines();
    let mut defines: Vec<(&str, &str)> = defines.iter().map(|(k, v)| (*k, v.as_str())).collect();
    if vec4 {
        defines.push(("BVH_VEC4", "1"));
    }
    let k = gpu
        .kernel(
            "tests/test_bvh_trace.comp",
            &defines,
            &[Bind::own(&nodes), Bind::own(&prims), Bind::vec4("test_rays", &ray_buf), Bind::vec4("test_hits", &out)],
        )
        .unwrap();
    let n = data.len() as u32;
    let mut batch = gpu.batch().unwrap();
    batch.dispatch(&k, [groups_for(n, 64), 1, 1], bytemuck::bytes_of(&n)).unwrap();
    batch.submit_wait(None).unwrap();
    out.read::<TestHit>()
        .unwrap()
        .into_iter()
        .map(|h| GpuResult {
            closest: (h.flags & 1 != 0).then_some(Hit {
                t: h.t,
                prim: h.prim,
                u: h.u,
                v: h.v,
                is_sphere: h.flags & 2 != 0,
                material: h.material,
                // The kernel reports the instance's record slot, not its index (see
                // tests/bvh_instances.rs); these scenes have no instances.
                instance: None,
            }),
            any: h.flags & 4 != 0,
            instance_record: h.instance_record,
        })
        .collect()
}

/// `vec4`: the kernel declares the buffers as vec4 arrays (compatible path); otherwise
/// bvh.glsl declares them as u64vec2 arrays. `spheres`: with spheres, else with
/// BVH_NO_SPHERES.
fn check_against_brute_force(vec4: bool, spheres: bool) {
    let s = test_scene(11, 4000, if spheres { 400 } else { 0 });
    let bvh = build(&s.triangles, &s.spheres).into_gpu();
    let rays = test_rays(&s, 12, 6000);
    let results = common::with_gpu(|gpu| trace_on_gpu_with(gpu, &bvh, &rays, vec4));
    let mut errors = Vec::new();
    let mut hits = 0;
    let mut same_as_cpu = 0;
    for ((ray, tmin, tmax), r) in rays.iter().zip(&results) {
        let want = brute_force_closest(&s.triangles, &s.spheres, ray, *tmin, *tmax);
        hits += want.is_some() as usize;
        if let Err(e) = check_hit(&s, "gpu", ray, r.closest, want) {
            errors.push(e);
        }
        if r.any != r.closest.is_some() {
            errors.push(format!("any-hit {} but closest {:?} for {ray:?}", r.any, r.closest));
        }
        let cpu = bvh.closest_hit(ray, *tmin, *tmax);
        same_as_cpu += (cpu.map(|h| (h.prim, h.is_sphere)) == r.closest.map(|h| (h.prim, h.is_sphere))) as usize;
    }
    println!(
        "vec4 {vec4}, spheres {spheres}: {} rays, {hits} hits, {same_as_cpu} same prim as the CPU traversal",
        rays.len()
    );
    assert!(errors.is_empty(), "{} of {} rays: {:#?}", errors.len(), rays.len(), &errors[..errors.len().min(10)]);
    assert!(hits > rays.len() / 5);
}

#[test]
fn gpu_matches_brute_force() {
    check_against_brute_force(false, true);
}

#[test]
fn gpu_matches_brute_force_vec4_buffers() {
    check_against_brute_force(true, true);
}

#[test]
fn gpu_matches_brute_force_without_spheres() {
    check_against_brute_force(false, false);
}

#[test]
fn gpu_icosphere_is_watertight() {
    let s = test_scene(13, 0, 0);
    let bvh = build(&s.triangles, &s.spheres).into_gpu();
    let mut r = rng(14);
    let mut dirs: Vec<Vec3> = Vec::new();
    for t in &s.triangles[s.ico.clone()] {
        for e in 0..3 {
            let (a, b) = (t.p[e], t.p[(e + 1) % 3]);
            dirs.push(a - s.ico_center);
            dirs.push(0.5 * (a + b) - s.ico_center);
            dirs.push(a.lerp(b, r.random_range(0.0f32..1.0)) - s.ico_center);
        }
    }
    for _ in 0..100_000 {
        dirs.push(rand_dir(&mut r));
    }
    let rays: Vec<(Ray, f32, f32)> = dirs.iter().map(|&d| (Ray { o: s.ico_center, d }, 0.0, f32::INFINITY)).collect();
    let results = common::with_gpu(|gpu| trace_on_gpu(gpu, &bvh, &rays));
    let escaped: Vec<_> = rays
        .iter()
        .zip(&results)
        .filter(|(_, r)| !r.closest.is_some_and(|h| s.ico.contains(&(h.prim as usize))) || !r.any)
        .map(|(ray, _)| ray.0)
        .collect();
    assert!(
        escaped.is_empty(),
        "{} of {} rays escaped: {:?}",
        escaped.len(),
        rays.len(),
        &escaped[..escaped.len().min(5)]
    );
}

#[test]
fn gpu_matches_cpu_traversal_on_large_scene() {
    // 200k triangles + 5k spheres: the GPU must agree with the CPU traversal (itself
    // checked against the brute force) on the primitive hit and t, for trees of both leaf
    // rules (the SAH's, the default at this size, and the size rule of larger scenes).
    let s = test_scene(15, 200_000, 5000);
    let rays = test_rays(&s, 16, 30_000);
    for leaf_rule in [LeafRule::Auto, LeafRule::Size] {
        let bvh = build_with(&s.triangles, &s.spheres, &BuildOptions { leaf_rule, ..Default::default() }).into_gpu();
        let results = common::with_gpu(|gpu| trace_on_gpu(gpu, &bvh, &rays));
        let mut errors = Vec::new();
        for ((ray, tmin, tmax), r) in rays.iter().zip(&results) {
            let want = bvh.closest_hit(ray, *tmin, *tmax);
            if let Err(e) = check_hit(&s, "gpu vs cpu bvh", ray, r.closest, want) {
                errors.push(e);
            }
            if r.any != bvh.any_hit(ray, *tmin, *tmax) {
                errors.push(format!("any-hit differs for {ray:?}"));
            }
        }
        assert!(
            errors.is_empty(),
            "{leaf_rule:?}: {} of {} rays: {:#?}",
            errors.len(),
            rays.len(),
            &errors[..errors.len().min(10)]
        );
    }
}

/// The two-level BVH on the GPU against its CPU mirror (itself checked against the brute
/// force over the flattened scene, tests/bvh_build.rs): the same primitive and instance
/// for every ray, distances within float rounding (the GPU may contract the transform's
/// multiply-adds), and any-hit agreeing.
#[test]
fn gpu_matches_cpu_traversal_with_instances() {
    let s = instanced_scene(43, 24);
    let bvh = vkvcm::bvh::build_scene(&s, &vkvcm::bvh::BuildOptions::default()).into_gpu();
    assert!(bvh.glsl_defines().iter().any(|(k, _)| *k == "BVH_INSTANCES"));
    let record_base = (bvh.prims.len() - 2 * s.instances.len()) as u32;
    let rays = instanced_rays(&s, 44, 20_000);
    let results = common::with_gpu(|gpu| trace_on_gpu(gpu, &bvh, &rays));
    let mut errors = Vec::new();
    let mut instanced_hits = 0;
    for (k, ((ray, tmin, tmax), r)) in rays.iter().zip(&results).enumerate() {
        let want = bvh.closest_hit(ray, *tmin, *tmax);
        let got = r.closest.map(|h| {
            let instance = (r.instance_record != u32::MAX).then(|| (r.instance_record - record_base) / 2);
            Hit { instance, ..h }
        });
        match (got, want) {
            (None, None) => {}
            (Some(g), Some(w)) => {
                instanced_hits += g.instance.is_some() as usize;
                let distance = (g.t - w.t).abs() * ray.d.length();
                let same = (g.prim, g.instance, g.is_sphere) == (w.prim, w.instance, w.is_sphere);
                if distance > 1e-4 || (!same && distance > 1e-6) {
                    errors.push(format!("ray {k}: gpu {g:?}, cpu {w:?}"));
                }
            }
            (g, w) => errors.push(format!("ray {k}: gpu {g:?}, cpu {w:?}")),
        }
        if r.any != want.is_some() {
            errors.push(format!("ray {k}: gpu any-hit {} but the cpu's closest {want:?}", r.any));
        }
    }
    println!("{} rays, {instanced_hits} hits on instances", rays.len());
    assert!(errors.is_empty(), "{} of {} rays: {:#?}", errors.len(), rays.len(), &errors[..errors.len().min(10)]);
    assert!(instanced_hits > 2000);
}
