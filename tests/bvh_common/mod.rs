//! Scenes, rays and hit comparison shared by tests/bvh_build.rs and tests/bvh_gpu.rs.
#![allow(dead_code)]

use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use vkvcm::bvh::{Hit, Ray};
use vkvcm::scene::{Sphere, Triangle};
use vkvcm_tools::bench::traverse::icosphere;

pub fn rng(seed: u64) -> Pcg64 {
    Pcg64::seed_from_u64(seed)
}

pub fn rand_vec(r: &mut Pcg64, lo: f32, hi: f32) -> Vec3 {
    Vec3::new(r.random_range(lo..hi), r.random_range(lo..hi), r.random_range(lo..hi))
}

pub fn rand_dir(r: &mut Pcg64) -> Vec3 {
    loop {
        let v = rand_vec(r, -1.0, 1.0);
        let l = v.length_squared();
        if l > 1e-4 && l <= 1.0 {
            return v / l.sqrt();
        }
    }
}

/// Random triangles (sizes 0.01 .. 0.4) in [-1, 1]^3.
pub fn triangle_soup(r: &mut Pcg64, n: usize) -> Vec<Triangle> {
    (0..n)
        .map(|i| {
            let c = rand_vec(r, -1.0, 1.0);
            let s = r.random_range(0.01f32..0.4);
            Triangle {
                p: [c + rand_vec(r, -s, s), c + rand_vec(r, -s, s), c + rand_vec(r, -s, s)],
                n: None,
                material: (i % 7) as u32,
                attributes: None,
            }
        })
        .collect()
}

pub fn random_spheres(r: &mut Pcg64, n: usize) -> Vec<Sphere> {
    (0..n)
        .map(|i| Sphere {
            center: rand_vec(r, -1.0, 1.0),
            radius: r.random_range(0.01f32..0.2),
            material: 100 + i as u32,
        })
        .collect()
}

/// A cube [-1, 1]^3 made of 12 triangles (shared vertices bit-identical).
pub fn triangle_cube(center: Vec3, half: f32) -> Vec<Triangle> {
    let v = |x: f32, y: f32, z: f32| center + half * Vec3::new(x, y, z);
    let c = [
        v(-1., -1., -1.),
        v(1., -1., -1.),
        v(1., 1., -1.),
        v(-1., 1., -1.),
        v(-1., -1., 1.),
        v(1., -1., 1.),
        v(1., 1., 1.),
        v(-1., 1., 1.),
    ];
    let quads = [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [3, 7, 6, 2], [0, 4, 7, 3], [1, 2, 6, 5]];
    let mut t = Vec::new();
    for (k, q) in quads.iter().enumerate() {
        t.push(Triangle { p: [c[q[0]], c[q[1]], c[q[2]]], n: None, material: k as u32, attributes: None });
        t.push(Triangle { p: [c[q[0]], c[q[2]], c[q[3]]], n: None, material: k as u32, attributes: None });
    }
    t
}

/// Test scene: a triangle soup, spheres, a closed icosphere and a triangulated cube.
pub struct TestScene {
    pub triangles: Vec<Triangle>,
    pub spheres: Vec<Sphere>,
    /// Index range of the icosphere's triangles and its centre.
    pub ico: std::ops::Range<usize>,
    pub ico_center: Vec3,
    pub cube: std::ops::Range<usize>,
}

pub fn test_scene(seed: u64, soup: usize, spheres: usize) -> TestScene {
    let mut r = rng(seed);
    let mut triangles = triangle_soup(&mut r, soup);
    let ico_center = Vec3::new(2.5, 0.3, -0.2);
    let a = triangles.len();
    triangles.extend(icosphere(ico_center, 0.8, 3, 50));
    let b = triangles.len();
    triangles.extend(triangle_cube(Vec3::new(-2.5, 0.0, 0.5), 0.5));
    let c = triangles.len();
    TestScene { triangles, spheres: random_spheres(&mut r, spheres), ico: a..b, ico_center, cube: b..c }
}

/// (ray, tmin, tmax) triples: random rays through the scene box, rays aimed exactly at
/// vertices and at points on edges of the closed meshes, grazing rays along the cube's
/// faces, rays from the icosphere's centre, rays with zero direction components.
pub fn test_rays(s: &TestScene, seed: u64, n_random: usize) -> Vec<(Ray, f32, f32)> {
    let mut r = rng(seed);
    let mut rays = Vec::new();
    let inf = f32::INFINITY;
    for _ in 0..n_random {
        let o = rand_vec(&mut r, -3.5, 3.5);
        let d = rand_dir(&mut r) * r.random_range(0.5f32..2.0);
        rays.push((Ray { o, d }, 0.0, inf));
    }
    // Rays aimed at vertices and edges of the icosphere and the cube, from outside.
    for range in [s.ico.clone(), s.cube.clone()] {
        for k in 0..400 {
            let tri = &s.triangles[r.random_range(range.clone())];
            let e = k % 3;
            let target = match k % 4 {
                0 => tri.p[e],
                1 => 0.5 * (tri.p[e] + tri.p[(e + 1) % 3]),
                _ => tri.p[e].lerp(tri.p[(e + 1) % 3], r.random_range(0.0f32..1.0)),
            };
            let o = target + rand_dir(&mut r) * r.random_range(1.0f32..4.0);
            rays.push((Ray { o, d: target - o }, 0.0, inf));
        }
    }
    // From the icosphere's centre towards vertices, edge points and random directions.
    for k in 0..600 {
        let tri = &s.triangles[r.random_range(s.ico.clone())];
        let e = k % 3;
        let target = match k % 3 {
            0 => tri.p[e],
            1 => tri.p[e].lerp(tri.p[(e + 1) % 3], r.random_range(0.0f32..1.0)),
            _ => s.ico_center + rand_dir(&mut r),
        };
        let o = s.ico_center;
        rays.push((Ray { o, d: target - o }, 0.0, inf));
    }
    // Grazing rays in the planes of the cube's faces and along its edges.
    let cube = &s.triangles[s.cube.clone()];
    let (lo, hi) = cube
        .iter()
        .flat_map(|t| t.p)
        .fold((Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)), |(a, b), p| (a.min(p), b.max(p)));
    for k in 0..300 {
        let axis = k % 3;
        let mut o = rand_vec(&mut r, 0.0, 1.0) * (hi - lo) + lo;
        o[axis] = if k % 2 == 0 { lo[axis] } else { hi[axis] };
        let mut d = rand_dir(&mut r);
        d[axis] = 0.0;
        if k % 5 == 0 {
            // Along an edge: fix a second coordinate too.
            let a2 = (axis + 1) % 3;
            o[a2] = lo[a2];
            d[a2] = 0.0;
        }
        let o = o - d * 3.0;
        rays.push((Ray { o, d }, 0.0, inf));
    }
    // Axis-aligned rays (zero direction components) and a bounded interval.
    for k in 0..200 {
        let mut d = Vec3::ZERO;
        d[k % 3] = if k % 2 == 0 { 1.0 } else { -1.0 };
        let o = rand_vec(&mut r, -3.0, 3.0);
        let tmax = if k % 4 == 0 { 1.5 } else { inf };
        rays.push((Ray { o, d }, 0.01, tmax));
    }
    rays
}

fn shares_vertex(a: &Triangle, b: &Triangle) -> bool {
    a.p.iter().any(|p| b.p.contains(p))
}

/// Checks a traversal's closest hit against the brute-force one. Hits on different
/// primitives are accepted only at equal t on triangles that share a vertex.
pub fn check_hit(s: &TestScene, what: &str, ray: &Ray, got: Option<Hit>, want: Option<Hit>) -> Result<(), String> {
    match (got, want) {
        (None, None) => Ok(()),
        (Some(g), Some(w)) => {
            let t_ok = (g.t - w.t).abs() <= 1e-5 * w.t.abs().max(1e-6);
            let same = g.prim == w.prim && g.is_sphere == w.is_sphere;
            let tie = !g.is_sphere
                && !w.is_sphere
                && shares_vertex(&s.triangles[g.prim as usize], &s.triangles[w.prim as usize]);
            if t_ok && (same || tie) {
                if same && !g.is_sphere && ((g.u - w.u).abs() > 1e-4 || (g.v - w.v).abs() > 1e-4) {
                    return Err(format!("{what}: barycentrics differ {ray:?}: {g:?} vs {w:?}"));
                }
                if same && g.material != w.material {
                    return Err(format!("{what}: material differs {ray:?}: {g:?} vs {w:?}"));
                }
                Ok(())
            } else {
                Err(format!("{what}: hit differs {ray:?}: got {g:?}, want {w:?}"))
            }
        }
        (g, w) => Err(format!("{what}: hit existence differs {ray:?}: got {g:?}, want {w:?}")),
    }
}

/// A scene with instances: a world-space triangle soup and spheres, and two shared meshes
/// (a closed icosphere of radius 1 at the origin, and a triangle soup) placed by random
/// affine transforms: rotations, non-uniform scales (every third instance mirrored) and
/// translations in [-6, 6]^3. Each instance's position is its placement's translation.
pub fn instanced_scene(seed: u64, instances: usize) -> vkvcm::scene::Scene {
    use glam::{Affine3A, Quat};
    use vkvcm::scene::{Camera, Instance, LoadReport, Scene, SharedMesh};
    let mut r = rng(seed);
    let mut triangles = triangle_soup(&mut r, 400);
    let world = triangles.len() as u32;
    let ico = icosphere(Vec3::ZERO, 1.0, 3, 50);
    let ico_count = ico.len() as u32;
    triangles.extend(ico);
    let soup = triangle_soup(&mut r, 300);
    let soup_count = soup.len() as u32;
    triangles.extend(soup);
    let meshes = vec![
        SharedMesh { name: "icosphere".into(), first: world, count: ico_count },
        SharedMesh { name: "soup".into(), first: world + ico_count, count: soup_count },
    ];
    let instances = (0..instances)
        .map(|k| {
            let axis = rand_dir(&mut r);
            let rot = Quat::from_axis_angle(axis, r.random_range(0.0f32..std::f32::consts::TAU));
            let mut scale = rand_vec(&mut r, 0.3, 1.2);
            if k % 3 == 2 {
                scale.x = -scale.x;
            }
            let t = rand_vec(&mut r, -6.0, 6.0);
            Instance { mesh: (k % 2) as u32, object_to_world: Affine3A::from_scale_rotation_translation(scale, rot, t) }
        })
        .collect();
    Scene {
        name: "instanced".into(),
        triangles,
        meshes,
        instances,
        spheres: random_spheres(&mut r, 40),
        materials: vec![],
        lights: vec![],
        camera: Camera { position: Vec3::ZERO, forward: Vec3::NEG_Z, up: Vec3::Y, yfov: 1.0 },
        report: LoadReport::default(),
        images: vec![],
    }
}

/// For each triangle of `Scene::flattened_triangles`, its instance (`None`: world space)
/// and its index in `Scene::triangles`.
pub fn flattened_origin(s: &vkvcm::scene::Scene) -> Vec<(Option<u32>, u32)> {
    let mut out: Vec<(Option<u32>, u32)> = (0..s.world_triangles().len() as u32).map(|i| (None, i)).collect();
    for (k, inst) in s.instances.iter().enumerate() {
        let m = &s.meshes[inst.mesh as usize];
        out.extend((m.first..m.first + m.count).map(|i| (Some(k as u32), i)));
    }
    out
}

/// Random rays through [-7, 7]^3, and rays from the centre of every icosphere instance
/// (mesh 0 of [`instanced_scene`]) in random directions: each must hit something, since
/// the icosphere is closed.
pub fn instanced_rays(s: &vkvcm::scene::Scene, seed: u64, n_random: usize) -> Vec<(Ray, f32, f32)> {
    let mut r = rng(seed);
    let mut rays: Vec<(Ray, f32, f32)> = (0..n_random)
        .map(|_| {
            (
                Ray { o: rand_vec(&mut r, -7.0, 7.0), d: rand_dir(&mut r) * r.random_range(0.5f32..2.0) },
                0.0,
                f32::INFINITY,
            )
        })
        .collect();
    for inst in s.instances.iter().filter(|i| i.mesh == 0) {
        let o = Vec3::from(inst.object_to_world.translation);
        for _ in 0..200 {
            rays.push((Ray { o, d: rand_dir(&mut r) }, 0.0, f32::INFINITY));
        }
    }
    rays
}
