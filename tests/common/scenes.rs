//! Small procedural scenes for analytic render tests.
#![allow(dead_code)]

use glam::Vec3;
use vkvcm::scene::{Camera, Light, LoadReport, Material, Scene, Triangle};

/// Axis-aligned box [-h, h]^3 as 12 triangles whose geometric normals point inwards.
pub fn inward_box(h: f32, material: u32) -> Vec<Triangle> {
    let c = |x: f32, y: f32, z: f32| Vec3::new(x * h, y * h, z * h);
    // Each face: four corners counter-clockwise as seen from inside.
    let faces = [
        [c(-1., -1., -1.), c(1., -1., -1.), c(1., 1., -1.), c(-1., 1., -1.)], // z = -h, normal +z
        [c(-1., -1., 1.), c(-1., 1., 1.), c(1., 1., 1.), c(1., -1., 1.)],     // z = +h, normal -z
        [c(-1., -1., -1.), c(-1., 1., -1.), c(-1., 1., 1.), c(-1., -1., 1.)], // x = -h, normal +x
        [c(1., -1., -1.), c(1., -1., 1.), c(1., 1., 1.), c(1., 1., -1.)],     // x = +h, normal -x
        [c(-1., -1., -1.), c(-1., -1., 1.), c(1., -1., 1.), c(1., -1., -1.)], // y = -h, normal +y
        [c(-1., 1., -1.), c(1., 1., -1.), c(1., 1., 1.), c(-1., 1., 1.)],     // y = +h, normal -y
    ];
    let mut out = Vec::new();
    for f in faces {
        out.push(Triangle { p: [f[0], f[1], f[2]], n: None, material, attributes: None });
        out.push(Triangle { p: [f[0], f[2], f[3]], n: None, material, attributes: None });
    }
    for t in &out {
        let n = (t.p[1] - t.p[0]).cross(t.p[2] - t.p[0]);
        let centroid = (t.p[0] + t.p[1] + t.p[2]) / 3.0;
        assert!(n.dot(-centroid) > 0.0, "box triangle does not face inwards");
    }
    out
}

pub fn camera(position: Vec3, forward: Vec3, up: Vec3, yfov_deg: f32) -> Camera {
    Camera { position, forward: forward.normalize(), up: up.normalize(), yfov: yfov_deg.to_radians() }
}

pub fn scene(name: &str, triangles: Vec<Triangle>, materials: Vec<Material>, lights: Vec<Light>, cam: Camera) -> Scene {
    Scene {
        name: name.into(),
        triangles,
        meshes: vec![],
        instances: vec![],
        spheres: vec![],
        materials,
        lights,
        camera: cam,
        report: LoadReport::default(),
        images: vec![],
    }
}

/// Every emissive triangle becomes an area light, as the importer does.
pub fn area_lights(triangles: &[Triangle], materials: &[Material]) -> Vec<Light> {
    triangles
        .iter()
        .enumerate()
        .filter(|(_, t)| materials[t.material as usize].emission.max_element() > 0.0)
        .map(|(i, t)| Light::Area { triangle: i as u32, radiance: materials[t.material as usize].emission })
        .collect()
}

/// Two quads in the plane z = 0 (x < 0 and x > 0) with materials `left` and `right`,
/// under a large one-sided square area light at height 1.5 facing down, with a diffuse
/// back wall; the camera looks down at the floor and sees the light's glossy reflection.
/// The light is large so that BSDF-sampled hits of it are not rare events.
pub fn glossy_floor_scene(left: Material, right: Material) -> Scene {
    let wall = Material {
        name: "wall".into(),
        diffuse: Vec3::splat(0.3),
        glossy: Vec3::splat(0.5),
        roughness: 0.5,
        ..Default::default()
    };
    let lamp = Material { name: "lamp".into(), emission: Vec3::splat(2.0), ..Default::default() };
    let quad = |a: Vec3, b: Vec3, c: Vec3, d: Vec3, material: u32| {
        vec![
            Triangle { p: [a, b, c], n: None, material, attributes: None },
            Triangle { p: [a, c, d], n: None, material, attributes: None },
        ]
    };
    let v = Vec3::new;
    let mut tris = Vec::new();
    tris.extend(quad(v(-3., -3., 0.), v(0., -3., 0.), v(0., 3., 0.), v(-3., 3., 0.), 0));
    tris.extend(quad(v(0., -3., 0.), v(3., -3., 0.), v(3., 3., 0.), v(0., 3., 0.), 1));
    tris.extend(quad(v(-3., 3., 0.), v(3., 3., 0.), v(3., 3., 3.), v(-3., 3., 3.), 2));
    // Light: normal -z (counter-clockwise seen from below).
    tris.extend(quad(v(-1.5, -0.5, 1.5), v(-1.5, 2.5, 1.5), v(1.5, 2.5, 1.5), v(1.5, -0.5, 1.5), 3));
    let materials = vec![left, right, wall, lamp];
    let lights = area_lights(&tris, &materials);
    let cam = camera(v(0.0, -2.5, 1.0), v(0.0, 2.5, -0.8), Vec3::Z, 60.0);
    scene("glossy_floor", tris, materials, lights, cam)
}

/// The environment-map test scene (tests/render_environment.rs; the same layout as
/// scripts/env_reference.py writes for the Mitsuba comparison): a grey diffuse ground
/// square y = 0, |x|, |z| <= 2, a diffuse sphere and a mirror sphere of radius 0.5 on it,
/// lit only by `map` turned by `rotation_deg`; the camera sees the spheres, the ground
/// and the sky.
pub fn environment_scene(map: vkvcm::scene::EnvironmentMap, rotation_deg: f32) -> Scene {
    use vkvcm::scene::{EnvironmentLight, Sphere};
    let c = |x: f32, z: f32| Vec3::new(x, 0.0, z);
    let triangles = vec![
        Triangle { p: [c(-2.0, -2.0), c(-2.0, 2.0), c(2.0, 2.0)], n: None, material: 0, attributes: None },
        Triangle { p: [c(-2.0, -2.0), c(2.0, 2.0), c(2.0, -2.0)], n: None, material: 0, attributes: None },
    ];
    let materials = vec![
        Material { name: "ground".into(), diffuse: Vec3::splat(0.5), ..Default::default() },
        Material { name: "diffuse".into(), diffuse: Vec3::new(0.8, 0.5, 0.3), ..Default::default() },
        Material { name: "mirror".into(), mirror: Vec3::splat(0.9), ..Default::default() },
    ];
    let light = Light::Environment(EnvironmentLight { map: std::sync::Arc::new(map), scale: Vec3::ONE, rotation_deg });
    let cam = Camera::looking_at(Vec3::new(0.0, 1.2, 3.5), Vec3::new(0.0, 0.4, 0.0), Vec3::Y, 40f32.to_radians())
        .expect("camera");
    let mut s = scene("environment", triangles, materials, vec![light], cam);
    s.spheres = vec![
        Sphere { center: Vec3::new(-0.6, 0.5, 0.0), radius: 0.5, material: 1 },
        Sphere { center: Vec3::new(0.6, 0.5, 0.0), radius: 0.5, material: 2 },
    ];
    s
}

/// A strongly non-uniform lat-long map: a pale sky, a broad warm glow 40 degrees
/// above the horizon towards +X (radiance up to ~6), a dark ground (no constant region:
/// a pixel seeing one would have zero variance, which the z-tests cannot compare).
pub fn smooth_sky(width: u32, height: u32) -> vkvcm::scene::EnvironmentMap {
    let glow = Vec3::new(0.75, 0.6, 0.0).normalize();
    let mut texels = Vec::new();
    for j in 0..height {
        let theta = std::f32::consts::PI * j as f32 / (height - 1) as f32;
        for i in 0..width {
            let phi = 2.0 * std::f32::consts::PI * (i as f32 + 0.5) / width as f32;
            let d = Vec3::new(phi.sin() * theta.sin(), theta.cos(), -phi.cos() * theta.sin());
            let g = d.dot(glow).max(0.0).powi(8) * 6.0;
            let base = if d.y >= 0.0 { Vec3::new(0.4, 0.5, 0.7) } else { Vec3::splat(0.05 - 0.04 * d.y) };
            // A texel checkerboard (x1.6 / x0.4) makes the radiance vary within every
            // sampling cell, so sampling that misplaces directions inside a cell shows.
            let checker = if (i + j) % 2 == 0 { 1.6 } else { 0.4 };
            texels.push((checker * (base + Vec3::new(g, 0.8 * g, 0.5 * g))).to_array());
        }
    }
    vkvcm::scene::EnvironmentMap::new("smooth_sky", width, height, texels).expect("map")
}

/// Uniform numbers in [0, 1] from a 32-bit xorshift generator (Marsaglia 2003) seeded
/// with `seed`: deterministic test scenes.
pub fn xorshift(seed: u32) -> impl FnMut() -> f32 {
    let mut rng = seed | 1;
    move || {
        rng ^= rng << 13;
        rng ^= rng >> 17;
        rng ^= rng << 5;
        rng as f32 / u32::MAX as f32
    }
}

/// Gives every triangle of `scene` vertex normals tilted off its geometric normal by
/// random angles of up to `max_tilt_deg` (deterministic in `seed`), on the geometric
/// normal's side: shading normals that disagree with the geometry everywhere, as a coarse
/// mesh's interpolated normals do.
pub fn tilt_shading_normals(scene: &mut Scene, max_tilt_deg: f32, seed: u32) {
    let mut rnd = xorshift(seed);
    let tan_max = max_tilt_deg.to_radians().tan();
    for t in &mut scene.triangles {
        let ng = (t.p[1] - t.p[0]).cross(t.p[2] - t.p[0]).normalize();
        let (a, b) = ng.any_orthonormal_pair();
        t.n = Some([0; 3].map(|_| {
            let phi = 2.0 * std::f32::consts::PI * rnd();
            let r = tan_max * rnd().sqrt();
            (ng + r * (phi.cos() * a + phi.sin() * b)).normalize()
        }));
    }
}

/// A UV sphere of `rings` x `segments` quads (two triangles each, outward geometric
/// normals) with the sphere's exact normals at its vertices: a coarse tessellation whose
/// interpolated shading normals differ from the facets' geometric normals by up to about
/// 180 / rings degrees.
pub fn smooth_sphere_mesh(center: Vec3, radius: f32, rings: u32, segments: u32, material: u32) -> Vec<Triangle> {
    use std::f32::consts::PI;
    let dir = |i: u32, j: u32| {
        let theta = PI * i as f32 / rings as f32;
        let phi = 2.0 * PI * j as f32 / segments as f32;
        Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin())
    };
    let mut out = Vec::new();
    let mut push = |a: Vec3, b: Vec3, c: Vec3| {
        let ng = (b - a).cross(c - a);
        if ng.length() > 1e-9 {
            // Counter-clockwise seen from outside.
            let [a, b, c] = if ng.dot(a + b + c) > 0.0 { [a, b, c] } else { [a, c, b] };
            out.push(Triangle {
                p: [a, b, c].map(|d| center + radius * d),
                n: Some([a, b, c]),
                material,
                attributes: None,
            });
        }
    };
    for i in 0..rings {
        for j in 0..segments {
            let (a, b, c, d) = (dir(i, j), dir(i + 1, j), dir(i + 1, j + 1), dir(i, j + 1));
            push(a, b, c);
            push(a, c, d);
        }
    }
    out
}

/// Adds a small emitter, a 0.3 x 0.3 square in the plane y = `centre.y` around `centre`,
/// emitting towards -y with `radiance` (a frosted bulb's filament inside a glass sphere
/// centred there), and makes the scene's lights again.
pub fn add_filament(s: &mut Scene, centre: Vec3, radiance: f32) {
    let material = s.materials.len() as u32;
    s.materials.push(Material { name: "filament".into(), emission: Vec3::splat(radiance), ..Default::default() });
    let p = |dx: f32, dz: f32| Vec3::new(centre.x + dx, centre.y, centre.z + dz);
    let (lo, hi) = (-0.15, 0.15);
    for t in [[p(lo, lo), p(hi, lo), p(hi, hi)], [p(lo, lo), p(hi, hi), p(lo, hi)]] {
        s.triangles.push(Triangle { p: t, n: None, material, attributes: None });
    }
    s.lights = area_lights(&s.triangles, &s.materials);
}

/// glossy_floor_scene with `left` and `right` on floors whose triangles carry texture
/// coordinates, under one texel everywhere (a 1 x 1 image, RGBA `texel`): a textured
/// material there must render as its factors times the texel.
pub fn textured_floor_scene(left: Material, right: Material, texel: [u8; 4]) -> Scene {
    let mut sc = glossy_floor_scene(left, right);
    for t in sc.triangles.iter_mut().filter(|t| t.material < 2) {
        t.attributes = Some(Box::new(vkvcm::scene::VertexAttributes {
            uv: [Some([glam::Vec2::ZERO, glam::Vec2::X, glam::Vec2::Y]), None],
            color: None,
            tangent: None,
        }));
    }
    sc.images = vec![vkvcm::scene::TextureImage { name: "texel".into(), width: 1, height: 1, texels: vec![texel] }];
    sc
}

/// A reference to image `image`, texture coordinates 0, nearest filtering, repeating.
pub fn nearest_texture(image: u32) -> vkvcm::scene::TextureRef {
    vkvcm::scene::TextureRef {
        image,
        wrap_s: vkvcm::scene::Wrap::Repeat,
        wrap_t: vkvcm::scene::Wrap::Repeat,
        filter: vkvcm::scene::Filter::Nearest,
        tex_coord: 0,
        transform: vkvcm::scene::TextureRef::IDENTITY,
    }
}

/// The cos(view ray, normal) of the first hit of the unit sphere at the origin along the
/// camera ray through (x, y) of a `w` x `h` frame (glsl/scene.glsl's camera model), or None.
pub fn unit_sphere_hit_cos(cam: &Camera, w: u32, h: u32, x: f32, y: f32) -> Option<f64> {
    let plane = 0.5 * h as f32 / (0.5 * cam.yfov).tan();
    let right = cam.forward.cross(cam.up).normalize();
    let up = right.cross(cam.forward);
    let d = (cam.forward * plane + right * (x - 0.5 * w as f32) + up * (0.5 * h as f32 - y)).normalize();
    let b = cam.position.dot(d);
    let disc = b * b - (cam.position.length_squared() - 1.0);
    (disc >= 0.0).then(|| {
        let p = cam.position + d * (-b - disc.sqrt());
        -d.dot(p.normalize()) as f64
    })
}

/// Adds `count` small emissive triangles (sides about 0.1) of four colours, facing random
/// directions, scattered over the box [-2, 2] x [-1, 2.5] x [0.2, 1.4] (deterministic in
/// `seed`), and makes the scene's area lights again (other lights stay): the light tree's
/// case (src/render/light_tree.rs), many lights whose importance varies over the scene.
pub fn add_emitter_cloud(s: &mut Scene, count: usize, seed: u32) {
    let mut rnd = xorshift(seed);
    let first = s.materials.len() as u32;
    for (i, c) in [Vec3::new(8.0, 2.0, 1.0), Vec3::new(1.0, 6.0, 2.0), Vec3::new(1.0, 2.0, 9.0), Vec3::splat(4.0)]
        .into_iter()
        .enumerate()
    {
        s.materials.push(Material { name: format!("emitter {i}"), emission: c, ..Default::default() });
    }
    for i in 0..count {
        let centre = Vec3::new(-2.0 + 4.0 * rnd(), -1.0 + 3.5 * rnd(), 0.2 + 1.2 * rnd());
        let (a, b) =
            (Vec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5), Vec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5));
        let p = [centre, centre + 0.15 * a, centre + 0.15 * b];
        s.triangles.push(Triangle { p, n: None, material: first + (i % 4) as u32, attributes: None });
    }
    let others: Vec<Light> = s.lights.iter().filter(|l| !matches!(l, Light::Area { .. })).cloned().collect();
    s.lights = area_lights(&s.triangles, &s.materials);
    s.lights.extend(others);
}
