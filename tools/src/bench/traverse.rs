//! Traversal benchmark (`vkvcm-bench traverse`) and the scenes it runs on.
//!
//! [`bench_traverse`] builds the BVH (timed), uploads it, and measures closest-hit and
//! any-hit traversal on the GPU for 2^20 camera rays (a pinhole camera, one ray per pixel
//! of a 1024 x 1024 image in scanline order) and 2^20 random rays (origin uniform in the
//! scene box, direction uniform on the sphere), after a warm-up dispatch, with GPU
//! timestamps.
//! Scenes ([`bench_scene`]): `cornell` (open Cornell box + 2 tessellated spheres, 3,978
//! triangles), `spheres` (4,096 UV spheres of 256 triangles: 1,048,576 triangles),
//! `displaced` (a noise-displaced cube-sphere, 1,002,252 triangles); their results:
//! docs/bvh.md, Benchmark.

use std::sync::Arc;
use std::time::Instant;

use anyhow::Result;
use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use serde::Serialize;

use vkvcm::bvh::traverse::{any_hit_counted, closest_hit_counted};
use vkvcm::bvh::{build_with, Aabb, BuildOptions, Ray};
use vkvcm::gpu::{groups_for, Bind, Gpu, Profile};
use vkvcm::scene::{Sphere, Triangle};

/// Small deterministic generator (PCG32, O'Neill 2014) so the library needs no `rand`.
#[derive(Clone, Debug)]
pub struct Pcg32 {
    state: u64,
}

impl Pcg32 {
    pub fn new(seed: u64) -> Pcg32 {
        let mut r = Pcg32 { state: 0 };
        r.next_u32();
        r.state = r.state.wrapping_add(seed);
        r.next_u32();
        r
    }

    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Uniform in [0, 1).
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
    }

    /// Uniform direction on the unit sphere.
    pub fn unit_vector(&mut self) -> Vec3 {
        let z = 1.0 - 2.0 * self.next_f32();
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = std::f32::consts::TAU * self.next_f32();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    }
}

/// An indexed mesh turned into triangles (shared vertices are bit-identical).
fn triangles_from(verts: &[Vec3], faces: &[[u32; 3]], material: u32) -> Vec<Triangle> {
    faces.iter().map(|f| Triangle { p: f.map(|i| verts[i as usize]), n: None, material, attributes: None }).collect()
}

/// Icosphere: an icosahedron subdivided `subdivisions` times, 20 * 4^s triangles, closed
/// and consistently wound (outward), shared vertices bit-identical.
pub fn icosphere(center: Vec3, radius: f32, subdivisions: u32, material: u32) -> Vec<Triangle> {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut verts: Vec<Vec3> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .iter()
    .map(|v| Vec3::from(*v).normalize())
    .collect();
    let mut faces: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut mid = std::collections::HashMap::new();
        let mut next = Vec::with_capacity(faces.len() * 4);
        let mut midpoint = |a: u32, b: u32, verts: &mut Vec<Vec3>| -> u32 {
            let key = (a.min(b), a.max(b));
            *mid.entry(key).or_insert_with(|| {
                verts.push((verts[a as usize] + verts[b as usize]).normalize());
                verts.len() as u32 - 1
            })
        };
        for [a, b, c] in faces {
            let ab = midpoint(a, b, &mut verts);
            let bc = midpoint(b, c, &mut verts);
            let ca = midpoint(c, a, &mut verts);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        faces = next;
    }
    let verts: Vec<Vec3> = verts.iter().map(|v| center + radius * *v).collect();
    triangles_from(&verts, &faces, material)
}

/// UV sphere with `segments` around and `rings` from pole to pole: 2 * segments *
/// (rings - 1) triangles, closed, shared vertices bit-identical.
pub fn uv_sphere(center: Vec3, radius: f32, segments: u32, rings: u32, material: u32) -> Vec<Triangle> {
    let mut verts = vec![center + Vec3::Y * radius, center - Vec3::Y * radius];
    for r in 1..rings {
        let theta = std::f32::consts::PI * r as f32 / rings as f32;
        for s in 0..segments {
            let phi = std::f32::consts::TAU * s as f32 / segments as f32;
            let d = Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin());
            verts.push(center + radius * d);
        }
    }
    let idx = |r: u32, s: u32| 2 + (r - 1) * segments + s % segments;
    let mut faces = Vec::new();
    for s in 0..segments {
        faces.push([0, idx(1, s + 1), idx(1, s)]);
        faces.push([1, idx(rings - 1, s), idx(rings - 1, s + 1)]);
        for r in 1..rings - 1 {
            let (a, b) = (idx(r, s), idx(r, s + 1));
            let (c, d) = (idx(r + 1, s), idx(r + 1, s + 1));
            faces.push([a, b, d]);
            faces.push([a, d, c]);
        }
    }
    triangles_from(&verts, &faces, material)
}

/// Cube-sphere: each face of a cube tessellated into `n x n` quads and projected onto the
/// unit sphere, then `displace(unit position)` gives the radius. 12 n^2 triangles, closed:
/// vertices are functions of integer lattice points, so shared ones are bit-identical.
pub fn cube_sphere(n: u32, displace: impl Fn(Vec3) -> f32, material: u32) -> Vec<Triangle> {
    let n = n as i32;
    // Lattice points of the cube [-n, n]^3: face grid index g maps to 2 g - n.
    let point = |ip: [i32; 3]| -> Vec3 {
        let p = Vec3::new(ip[0] as f32, ip[1] as f32, ip[2] as f32) / n as f32;
        let u = p.normalize();
        u * displace(u)
    };
    let mut tris = Vec::with_capacity(12 * (n * n) as usize);
    for axis in 0..3 {
        for sign in [-1i32, 1] {
            let (ua, va) = ((axis + 1) % 3, (axis + 2) % 3);
            let lattice = |a: i32, b: i32| -> [i32; 3] {
                let mut ip = [0; 3];
                ip[axis] = sign * n;
                ip[ua] = 2 * a - n;
                ip[va] = 2 * b - n;
                ip
            };
            for a in 0..n {
                for b in 0..n {
                    let p00 = point(lattice(a, b));
                    let p10 = point(lattice(a + 1, b));
                    let p01 = point(lattice(a, b + 1));
                    let p11 = point(lattice(a + 1, b + 1));
                    // ua x va points along +axis: keep the order on the + face (outward).
                    let quad =
                        if sign > 0 { [[p00, p10, p11], [p00, p11, p01]] } else { [[p00, p11, p10], [p00, p01, p11]] };
                    for p in quad {
                        tris.push(Triangle { p, n: None, material, attributes: None });
                    }
                }
            }
        }
    }
    tris
}

/// Smooth 3D value noise in [-1, 1] (hashed lattice values, quintic interpolation).
pub fn value_noise(p: Vec3) -> f32 {
    fn hash(x: i32, y: i32, z: i32) -> f32 {
        let mut h = (x as u32).wrapping_mul(0x8da6_b343)
            ^ (y as u32).wrapping_mul(0xd816_3841)
            ^ (z as u32).wrapping_mul(0xcb1a_b31f);
        h ^= h >> 15;
        h = h.wrapping_mul(0x2c1b_3c6d);
        h ^= h >> 12;
        h = h.wrapping_mul(0x297a_2d39);
        h ^= h >> 15;
        (h >> 8) as f32 / 8_388_608.0 - 1.0
    }
    let f = p.floor();
    let (x, y, z) = (f.x as i32, f.y as i32, f.z as i32);
    let t = p - f;
    let s = t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
    let lerp = |a: f32, b: f32, w: f32| a + (b - a) * w;
    let mut c = [0.0f32; 8];
    for (k, v) in c.iter_mut().enumerate() {
        *v = hash(x + (k & 1) as i32, y + ((k >> 1) & 1) as i32, z + ((k >> 2) & 1) as i32);
    }
    let x00 = lerp(c[0], c[1], s.x);
    let x10 = lerp(c[2], c[3], s.x);
    let x01 = lerp(c[4], c[5], s.x);
    let x11 = lerp(c[6], c[7], s.x);
    lerp(lerp(x00, x10, s.y), lerp(x01, x11, s.y), s.z)
}

/// A pinhole camera for the benchmark's primary rays.
#[derive(Clone, Debug)]
pub struct BenchCamera {
    pub position: Vec3,
    pub target: Vec3,
    /// Vertical field of view, radians.
    pub yfov: f32,
}

/// A generated scene for the traversal benchmark.
#[derive(Clone, Debug)]
pub struct BenchScene {
    pub name: String,
    pub triangles: Vec<Triangle>,
    pub spheres: Vec<Sphere>,
    pub camera: BenchCamera,
}

/// Names accepted by [`bench_scene`].
pub const BENCH_SCENES: &[&str] = &["cornell", "spheres", "displaced"];

/// Open Cornell box (5 walls of 2 triangles, 2 x 2 x 2 box centred at the origin, open
/// towards +z) with two UV spheres of 1,984 triangles each: 3,978 triangles.
pub fn scene_cornell() -> BenchScene {
    let mut tris = Vec::new();
    let mut quad = |a: Vec3, b: Vec3, c: Vec3, d: Vec3, m: u32| {
        tris.push(Triangle { p: [a, b, c], n: None, material: m, attributes: None });
        tris.push(Triangle { p: [a, c, d], n: None, material: m, attributes: None });
    };
    let v = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    quad(v(-1., -1., -1.), v(1., -1., -1.), v(1., -1., 1.), v(-1., -1., 1.), 0); // floor
    quad(v(-1., 1., -1.), v(-1., 1., 1.), v(1., 1., 1.), v(1., 1., -1.), 0); // ceiling
    quad(v(-1., -1., -1.), v(-1., 1., -1.), v(1., 1., -1.), v(1., -1., -1.), 0); // back
    quad(v(-1., -1., -1.), v(-1., -1., 1.), v(-1., 1., 1.), v(-1., 1., -1.), 1); // left
    quad(v(1., -1., -1.), v(1., 1., -1.), v(1., 1., 1.), v(1., -1., 1.), 2); // right
    tris.extend(uv_sphere(v(-0.45, -0.6, -0.3), 0.4, 32, 32, 3));
    tris.extend(uv_sphere(v(0.45, -0.6, 0.35), 0.4, 32, 32, 4));
    BenchScene {
        name: "cornell".into(),
        triangles: tris,
        spheres: Vec::new(),
        camera: BenchCamera { position: v(0.0, 0.0, 3.4), target: Vec3::ZERO, yfov: 0.8 },
    }
}

/// 4,096 UV spheres (16 segments x 9 rings = 256 triangles each, radius 0.3 to 0.6) on a
/// jittered 16^3 grid of spacing 2: 1,048,576 triangles.
pub fn scene_spheres() -> BenchScene {
    BenchScene {
        name: "spheres".into(),
        triangles: sphere_grid([16, 16, 16]),
        spheres: Vec::new(),
        camera: BenchCamera { position: Vec3::new(24.0, 18.0, 40.0), target: Vec3::ZERO, yfov: 0.9 },
    }
}

/// UV spheres (16 segments x 9 rings = 256 triangles each, radius 0.3 to 0.6) on a
/// jittered `n[0] x n[1] x n[2]` grid of spacing 2 centred at the origin: `256 n0 n1 n2`
/// triangles, materials 0..8 in turn.
pub fn sphere_grid(n: [u32; 3]) -> Vec<Triangle> {
    let mut rng = Pcg32::new(7);
    let count = n[0] * n[1] * n[2];
    let centre = (Vec3::new(n[0] as f32, n[1] as f32, n[2] as f32) - 1.0) * 0.5;
    let mut tris = Vec::with_capacity(256 * count as usize);
    for i in 0..count {
        let g = Vec3::new((i % n[0]) as f32, ((i / n[0]) % n[1]) as f32, (i / (n[0] * n[1])) as f32);
        let jitter = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5;
        let c = (g - centre) * 2.0 + jitter * 0.6;
        let r = 0.3 + 0.3 * rng.next_f32();
        tris.extend(uv_sphere(c, r, 16, 9, i % 8));
    }
    tris
}

/// A unit cube-sphere of 289^2 * 12 = 1,002,252 triangles with its radius displaced by
/// four octaves of value noise (amplitude 0.25).
pub fn scene_displaced() -> BenchScene {
    BenchScene {
        name: "displaced".into(),
        triangles: displaced_sphere(289),
        spheres: Vec::new(),
        camera: BenchCamera { position: Vec3::new(0.6, 0.9, 3.0), target: Vec3::ZERO, yfov: 0.75 },
    }
}

/// A unit [`cube_sphere`] of `12 n^2` triangles with its radius displaced by four octaves
/// of value noise (amplitude 0.25).
pub fn displaced_sphere(n: u32) -> Vec<Triangle> {
    let displace = |u: Vec3| {
        let mut a = 0.0;
        let mut f = 2.0;
        let mut w = 0.125;
        for _ in 0..4 {
            a += w * value_noise(u * f + 17.0);
            f *= 2.3;
            w *= 0.5;
        }
        1.0 + a
    };
    cube_sphere(n, displace, 0)
}

/// One of [`BENCH_SCENES`].
pub fn bench_scene(name: &str) -> Option<BenchScene> {
    match name {
        "cornell" => Some(scene_cornell()),
        "spheres" => Some(scene_spheres()),
        "displaced" => Some(scene_displaced()),
        _ => None,
    }
}

/// Primary rays of a `width x height` pinhole image (scanline order), as
/// `(origin, direction)` pairs with unit directions.
pub fn camera_rays(cam: &BenchCamera, width: u32, height: u32) -> Vec<(Vec3, Vec3)> {
    let fwd = (cam.target - cam.position).normalize();
    let right = fwd.cross(Vec3::Y).normalize();
    let up = right.cross(fwd);
    let h = (cam.yfov * 0.5).tan();
    let w = h * width as f32 / height as f32;
    let mut rays = Vec::with_capacity((width * height) as usize);
    for y in 0..height {
        for x in 0..width {
            let sx = (2.0 * (x as f32 + 0.5) / width as f32 - 1.0) * w;
            let sy = (1.0 - 2.0 * (y as f32 + 0.5) / height as f32) * h;
            rays.push((cam.position, (fwd + sx * right + sy * up).normalize()));
        }
    }
    rays
}

/// `count` rays with origins uniform in `[lo, hi]` and directions uniform on the sphere.
pub fn random_rays(lo: Vec3, hi: Vec3, count: usize, seed: u64) -> Vec<(Vec3, Vec3)> {
    let mut rng = Pcg32::new(seed);
    (0..count)
        .map(|_| {
            let t = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
            (lo + (hi - lo) * t, rng.unit_vector())
        })
        .collect()
}

/// Settings of [`bench_traverse`].
#[derive(Clone, Debug)]
pub struct TraverseBenchOptions {
    /// Rays per batch (camera rays: a square image of this many pixels).
    pub rays: u32,
    /// Timed dispatches per ray set (after one warm-up); the fastest counts.
    pub repeats: u32,
    pub build: BuildOptions,
    /// Workgroup size of the benchmark kernel.
    pub local_size: u32,
    /// Rays whose GPU result is compared with the CPU traversal.
    pub verify: u32,
}

impl Default for TraverseBenchOptions {
    fn default() -> Self {
        TraverseBenchOptions { rays: 1 << 20, repeats: 3, build: BuildOptions::default(), local_size: 64, verify: 4096 }
    }
}

/// Traversal speed for one ray set.
#[derive(Clone, Debug, Serialize)]
pub struct RaySetResult {
    pub rays: &'static str,
    pub count: u32,
    /// Fastest timed dispatch (GPU timestamps), closest hit.
    pub closest_ms: f64,
    pub closest_mrays_per_s: f64,
    /// Fastest timed dispatch, any hit (shadow-ray mode) over the same rays.
    pub any_ms: f64,
    pub any_mrays_per_s: f64,
    /// Process CPU time (user + sys) per dispatch, closest and any hit, on a CPU device
    /// such as lavapipe: `rays / cpu_ms` is robust against other load on the machine.
    pub closest_cpu_ms: f64,
    pub any_cpu_ms: f64,
    /// Share of rays that hit something.
    pub hit_fraction: f64,
    /// Verified rays whose GPU closest hit differs from the CPU traversal's.
    pub mismatches: u32,
    /// Mean internal nodes visited and primitives tested per ray, closest and any hit
    /// (CPU mirror of the traversal, over the verified rays).
    pub closest_nodes_per_ray: f64,
    pub closest_prims_per_ray: f64,
    pub any_nodes_per_ray: f64,
    pub any_prims_per_ray: f64,
}

/// What [`bench_traverse`] measured.
#[derive(Clone, Debug, Serialize)]
pub struct TraverseBenchReport {
    pub scene: String,
    pub device: String,
    pub driver: String,
    pub triangles: usize,
    pub spheres: usize,
    pub build_seconds: f64,
    pub nodes: usize,
    pub max_depth: u32,
    pub sah_cost: f64,
    pub bvh_bytes: usize,
    pub local_size: u32,
    pub sets: Vec<RaySetResult>,
}

impl std::fmt::Display for TraverseBenchReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "scene {}: {} triangles, {} spheres; device {} ({})",
            self.scene, self.triangles, self.spheres, self.device, self.driver
        )?;
        writeln!(
            f,
            "BVH build {:.3} s: {} nodes, depth {}, SAH cost {:.1}, {:.1} MiB; kernel local size {}",
            self.build_seconds,
            self.nodes,
            self.max_depth,
            self.sah_cost,
            self.bvh_bytes as f64 / (1 << 20) as f64,
            self.local_size
        )?;
        for s in &self.sets {
            writeln!(
                f,
                "{:>7} rays x{}: closest {:6.2} Mrays/s ({:.1} ms; {:.2} Mrays/CPU-s), any {:6.2} Mrays/s ({:.1} ms; {:.2} Mrays/CPU-s), hit {:.1}%, nodes/prims per ray {:.1}/{:.1} (any {:.1}/{:.1}), mismatches {}",
                s.rays,
                s.count,
                s.closest_mrays_per_s,
                s.closest_ms,
                s.count as f64 / s.closest_cpu_ms * 1e-3,
                s.any_mrays_per_s,
                s.any_ms,
                s.count as f64 / s.any_cpu_ms * 1e-3,
                100.0 * s.hit_fraction,
                s.closest_nodes_per_ray,
                s.closest_prims_per_ray,
                s.any_nodes_per_ray,
                s.any_prims_per_ray,
                s.mismatches
            )?;
        }
        Ok(())
    }
}

/// User + system CPU time of this process (all threads), from /proc/self/stat (Linux).
pub(crate) fn process_cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the parenthesised command name; utime and stime are fields 14 and 15.
    let rest = &stat[stat.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0) // USER_HZ is 100 on Linux
}

/// One ray as the benchmark kernels read it (`glsl/tests/bvh_bench.comp`, and the ray-query
/// comparison in `examples/rayquery_bench/`): origin and direction, `w` unused.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct BenchRay {
    pub o: [f32; 4],
    pub d: [f32; 4],
}

impl BenchRay {
    pub fn new(o: Vec3, d: Vec3) -> BenchRay {
        BenchRay { o: [o.x, o.y, o.z, 0.0], d: [d.x, d.y, d.z, 0.0] }
    }
}

/// The box of the scene's primitives themselves (not the BVH's padded, quantised boxes).
pub fn scene_bounds(scene: &BenchScene) -> Aabb {
    let mut bounds = Aabb::EMPTY;
    for t in &scene.triangles {
        for p in t.p {
            bounds.grow_point(p);
        }
    }
    for s in &scene.spheres {
        bounds.grow(&Aabb { min: s.center - s.radius.abs(), max: s.center + s.radius.abs() });
    }
    bounds
}

/// The two ray sets [`bench_traverse`] traces, `("camera", ..)` then `("random", ..)`,
/// `rays` each: primary rays of a square-ish pinhole image in scanline order, and rays
/// with origins uniform in [`scene_bounds`] and uniform directions (seed 12345).
pub fn bench_ray_sets(scene: &BenchScene, rays: u32) -> [(&'static str, Vec<(Vec3, Vec3)>); 2] {
    let bounds = scene_bounds(scene);
    let side = (rays as f64).sqrt().round() as u32;
    let mut camera = camera_rays(&scene.camera, side, rays.div_ceil(side));
    camera.truncate(rays as usize);
    let random = random_rays(bounds.min, bounds.max, rays as usize, 12345);
    [("camera", camera), ("random", random)]
}

/// Builds the BVH of `scene` (timed), then measures GPU closest-hit and any-hit traversal
/// of camera rays and random rays (see the module docs), timed with GPU timestamps after
/// a warm-up dispatch. A sample of the results is checked against the CPU traversal.
pub fn bench_traverse(gpu: &Arc<Gpu>, scene: &BenchScene, opts: &TraverseBenchOptions) -> Result<TraverseBenchReport> {
    let bvh = build_with(&scene.triangles, &scene.spheres, &opts.build);
    let stats = bvh.stats.clone();
    let g = bvh.into_gpu();
    let nodes = gpu.buffer_from_slice("bvh_nodes", &g.nodes)?;
    let prims = gpu.buffer_from_slice("bvh_prims", &g.prims)?;
    let mut sets = Vec::new();
    let ls = opts.local_size.to_string();
    let bvh_defines = g.glsl_defines();
    for (label, rays) in bench_ray_sets(scene, opts.rays) {
        let data: Vec<BenchRay> = rays.iter().map(|&(o, d)| BenchRay::new(o, d)).collect();
        let n = data.len() as u32;
        let ray_buf = gpu.buffer_from_slice("bench_rays", &data)?;
        let out = gpu.buffer_zeroed::<u32>("bench_results", data.len())?;
        let mut times = [0.0f64; 2];
        let mut cpu_ms = [f64::NAN; 2];
        let mut hit_fraction = 0.0;
        let mut mismatches = 0;
        let mut work = [[0u64; 2]; 2];
        let mut verified = [0u64; 2];
        for mode in 0..2u32 {
            let m = mode.to_string();
            let mut defines = vec![("MODE", m.as_str()), ("LOCAL_SIZE", ls.as_str())];
            defines.extend(bvh_defines.iter().map(|(k, v)| (*k, v.as_str())));
            let binds = [Bind::own(&nodes), Bind::own(&prims), Bind::own(&ray_buf), Bind::own(&out)];
            let k = gpu.kernel("tests/bvh_bench.comp", &defines, &binds)?;
            let groups = [groups_for(n, opts.local_size), 1, 1];
            let mut batch = gpu.batch()?;
            // Warm-up: pays lavapipe's shader compile and faults the buffers in.
            batch.dispatch(&k, groups, bytemuck::bytes_of(&n))?;
            batch.submit_wait(None)?;
            let mut best = f64::INFINITY;
            let cpu_start = process_cpu_seconds();
            for _ in 0..opts.repeats.max(1) {
                let mut profile = Profile::default();
                batch.dispatch(&k, groups, bytemuck::bytes_of(&n))?;
                let wall = Instant::now();
                batch.submit_wait(Some(&mut profile))?;
                let wall_ms = wall.elapsed().as_secs_f64() * 1e3;
                // GPU timestamps when the device has them, else wall clock.
                let ms = if profile.kernels.is_empty() { wall_ms } else { profile.total_ms() };
                best = best.min(ms);
            }
            if let (Some(a), Some(b)) = (cpu_start, process_cpu_seconds()) {
                cpu_ms[mode as usize] = (b - a) * 1e3 / opts.repeats.max(1) as f64;
            }
            times[mode as usize] = best;
            let res: Vec<u32> = out.read()?;
            let hits = if mode == 0 {
                res.iter().filter(|&&p| p != u32::MAX).count()
            } else {
                res.iter().filter(|&&p| p != 0).count()
            };
            if mode == 0 {
                hit_fraction = hits as f64 / n as f64;
            }
            let step = (n / opts.verify.max(1)).max(1) as usize;
            for i in (0..n as usize).step_by(step) {
                let (o, d) = rays[i];
                let ray = Ray { o, d };
                let (ok, c) = if mode == 0 {
                    let (h, c) = closest_hit_counted(&g.nodes[..], &g.prims, &ray, 0.0, 1e30);
                    (res[i] == h.map_or(u32::MAX, |h| h.prim), c)
                } else {
                    let (h, c) = any_hit_counted(&g.nodes[..], &g.prims, &ray, 0.0, 1e30);
                    ((res[i] != 0) == h, c)
                };
                mismatches += u32::from(!ok);
                work[mode as usize][0] += c.nodes as u64;
                work[mode as usize][1] += c.prims as u64;
                verified[mode as usize] += 1;
            }
        }
        sets.push(RaySetResult {
            rays: label,
            count: n,
            closest_ms: times[0],
            closest_mrays_per_s: n as f64 / times[0] * 1e-3,
            any_ms: times[1],
            any_mrays_per_s: n as f64 / times[1] * 1e-3,
            closest_cpu_ms: cpu_ms[0],
            any_cpu_ms: cpu_ms[1],
            hit_fraction,
            mismatches,
            closest_nodes_per_ray: work[0][0] as f64 / verified[0].max(1) as f64,
            closest_prims_per_ray: work[0][1] as f64 / verified[0].max(1) as f64,
            any_nodes_per_ray: work[1][0] as f64 / verified[1].max(1) as f64,
            any_prims_per_ray: work[1][1] as f64 / verified[1].max(1) as f64,
        });
    }
    Ok(TraverseBenchReport {
        scene: scene.name.clone(),
        device: gpu.info.name.clone(),
        driver: gpu.info.driver.clone(),
        triangles: stats.triangles,
        spheres: stats.spheres,
        build_seconds: stats.build_seconds,
        nodes: stats.nodes,
        max_depth: stats.max_depth,
        sah_cost: stats.sah_cost,
        bvh_bytes: g.size_bytes(),
        local_size: opts.local_size,
        sets,
    })
}
