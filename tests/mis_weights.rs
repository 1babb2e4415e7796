//! The MIS weights of all techniques that can sample one path sum to 1 (issue #5),
//! checked on the GPU by the debug kernel glsl/tests/mis_weights.comp over random paths
//! of the reference scenes (area light, background, point light, sun), a GGX scene
//! with an area and a point light, the same with shading normals tilted off every
//! triangle and a smooth-shaded sphere mesh (the MIS quantities use geometric cosines,
//! glsl/bsdf.glsl), the GGX scene with rough glass spheres, the GGX scene with the glTF
//! extensions' lobes (clear coat, sheen, iridescence, anisotropy, diffuse transmission), and an environment map, in bpt, bpm and vcm modes. The kernel evaluates every
//! weight with the production functions of glsl/subpath.glsl and glsl/mis_weights.glsl (docs/estimators.md, "MIS
//! weights sum to one: the debug kernel"), with the direct pdfs of triangle lights sampled by
//! solid angle from the receiving point (glsl/lights.glsl). Lavapipe, validation on.

mod common;

use std::sync::Arc;

use bytemuck::{Pod, Zeroable};
use common::scenes::*;
use common::with_gpu;
use glam::Vec3;
use vkvcm::gpu::{groups_2d, Bind, Buffer, Gpu, Kernel};
use vkvcm::render::gpu_types::GpuPush;
use vkvcm::render::radius::{RadiusSchedule, DEFAULT_ALPHA, DEFAULT_RADIUS_FACTOR};
use vkvcm::render::reads::Reads;
use vkvcm::render::{FrameSettings, LightSelection, SceneGpu};
use vkvcm::scene::{Light, Material, Scene};

/// Tolerance on |sum - 1|. Every weight is 1 / (1 + sum of positive terms), each term a
/// product of a few factors per vertex over at most 10 vertices, evaluated in float32
/// (relative rounding 6e-8 per operation): a few hundred roundings bound the relative
/// error of a weight by ~1e-5, and no subtraction can cancel. The two ends of the path
/// compute the same cosines and pdfs from directions normalised in opposite senses, and
/// the Phong lobe raises a cosine to the power 90 (a relative error of 1e-7 in the cosine
/// becomes 1e-5). Measured on lavapipe: max |sum - 1| = 2.4e-7 (one float ulp at 1) in
/// every mode without the rough glass scenes; with them up to 2.5e-5 (bpm; the rough
/// dielectric's transmission pdfs divide by |eta wo + wi|^2 and take Fresnel at the half
/// vector each end computes from its own, differently rounded, directions). 1e-4 leaves margin for drivers with approximate division and
/// transcendentals, while each sabotage tried (docs/estimators.md) moves some sum by more
/// than 1e-3.
const TOL: f64 = 1e-4;
/// Random paths per scene and mode (before rejection of joins that contribute nothing).
const PATHS: u32 = 32768;
/// SmallVCM's reference resolution: N_L = 256 x 256 light subpaths per iteration.
const RES: u32 = 256;
const MAX_PATH_LENGTH: u32 = 10;
/// Paths that must be built (not rejected) per mode over all scenes.
const MIN_PATHS: usize = 10000;
/// Floats per path in the kernel's output (OUT_STRIDE, layout in the kernel).
const STRIDE: usize = 32;
/// MAXV of the kernel: merge weights start at 8 + MAXV.
const MAXV: usize = 12;

#[derive(Clone, Copy, Debug)]
struct Mode {
    name: &'static str,
    vc: bool,
    vm: bool,
    radius_factor: f32,
    /// Multiplies mis_vc (negative control: a wrong VC factor).
    vc_scale: f32,
}

const BPT: Mode = Mode { name: "bpt", vc: true, vm: false, radius_factor: DEFAULT_RADIUS_FACTOR, vc_scale: 1.0 };
const BPM: Mode = Mode { name: "bpm", vc: false, vm: true, radius_factor: DEFAULT_RADIUS_FACTOR, vc_scale: 1.0 };
const VCM: Mode = Mode { name: "vcm", vc: true, vm: true, radius_factor: DEFAULT_RADIUS_FACTOR, vc_scale: 1.0 };
/// A 10x larger radius: merging takes a larger share of the weight.
const VCM_WIDE: Mode = Mode { name: "vcm r x10", vc: true, vm: true, radius_factor: 0.03, vc_scale: 1.0 };

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct PathOut {
    v: [f32; STRIDE],
}

/// Technique classes, for the weight distribution.
const CLASSES: [&str; 5] = ["emitter hit", "nee", "connection", "light->camera", "merge"];

#[derive(Default, Debug)]
struct Summary {
    paths: usize,
    max_err: f64,
    worst: Option<(String, Vec<f32>)>,
    errors: Vec<String>,
    /// Paths that no technique of this mode can sample (bpm only).
    unsampled: usize,
    /// Paths with at least one specular inner vertex.
    through_specular: usize,
    /// Paths whose largest weight is below 0.9 (the weight is shared).
    shared: usize,
    class_weight: [f64; 5],
    class_count: [usize; 5],
    by_length: [usize; 12],
    /// Paths whose y_0 next-event estimation at y_1 samples by solid angle.
    solid_angle: usize,
}

fn check_paths(label: &str, mode: Mode, out: &[PathOut], s: &mut Summary) {
    for (i, p) in out.iter().map(|p| &p.v).enumerate() {
        if p[0] != 1.0 {
            continue;
        }
        let k = p[1] as usize;
        let n = p[3] as usize;
        let sum = p[4] as f64;
        s.paths += 1;
        s.by_length[k] += 1;
        s.through_specular += (p[6] > 0.0) as usize;
        s.solid_angle += (p[STRIDE - 1] == 1.0) as usize;
        let id = format!("{label} {} path {i} (k {k}, generated with s = {})", mode.name, p[2]);
        if p[5] != 0.0 {
            s.errors.push(format!("{id}: {} weights negative or not finite: {:?}", p[5], &p[8..]));
        }
        if n == 0 {
            // Only merging-only estimators leave paths unsampled (e.g. a point light seen
            // through a mirror: no merge vertex, and delta lights cannot be hit).
            if mode.vc || sum != 0.0 {
                s.errors.push(format!("{id}: no technique samples it (sum {sum})"));
            }
            s.unsampled += 1;
            continue;
        }
        let err = (sum - 1.0).abs();
        let err = if err.is_nan() { f64::INFINITY } else { err };
        if err > TOL {
            s.errors.push(format!("{id}: sum of {n} weights = {sum}: {:?}", &p[8..]));
        }
        if err > s.max_err || s.worst.is_none() {
            s.max_err = err;
            s.worst = Some((id, p[8..].to_vec()));
        }
        let mut max_w = 0.0f32;
        for t in 0..=k {
            let w = p[8 + t];
            if w >= 0.0 {
                let class = if t == 0 {
                    0
                } else if t == 1 {
                    1
                } else if t == k {
                    3
                } else {
                    2
                };
                s.class_weight[class] += w as f64;
                s.class_count[class] += 1;
                max_w = max_w.max(w);
            }
        }
        for i in 1..k {
            let w = p[8 + MAXV + i];
            if w >= 0.0 {
                s.class_weight[4] += w as f64;
                s.class_count[4] += 1;
                max_w = max_w.max(w);
            }
        }
        s.shared += (max_w < 0.9) as usize;
    }
}

/// The debug kernel compiled for one scene.
struct Bench {
    scene: SceneGpu,
    kernel: Kernel,
    out: Buffer,
    _dummy: Vec<Buffer>,
}

impl Bench {
    fn new(gpu: &Arc<Gpu>, scene: &Scene, seed: u32, light_selection: LightSelection) -> Bench {
        let frame = FrameSettings {
            width: RES,
            height: RES,
            seed,
            max_path_length: MAX_PATH_LENGTH,
            min_path_length: 0,
            light_selection,
        };
        let sg = SceneGpu::new(gpu, scene, &frame, Reads::resolve(gpu, None).unwrap()).unwrap();
        // The film, splats and light-vertex store are declared by the includes of the kernels
        // but not used by the debug kernel.
        let names = [
            "film",
            "film_stats",
            "frame_addresses",
            "splat",
            "light_vertices_a",
            "light_vertices_b",
            "light_vertex_offsets",
        ];
        let dummy: Vec<_> = names.iter().map(|n| gpu.buffer_zeroed::<[u32; 4]>(n, 4).unwrap()).collect();
        let out = gpu.buffer_zeroed::<PathOut>("mis_results", PATHS as usize).unwrap();
        let mut binds = sg.binds();
        binds.extend(dummy.iter().map(Bind::own));
        binds.push(Bind::own(&out));
        let kernel = gpu.kernel("tests/mis_weights.comp", &sg.variant.defines().pairs(), &binds).unwrap();
        Bench { scene: sg, kernel, out, _dummy: dummy }
    }

    /// Runs the kernel over PATHS random paths in `mode`.
    fn run(&self, gpu: &Arc<Gpu>, mode: Mode) -> Vec<PathOut> {
        let light_paths = RES * RES;
        let schedule = RadiusSchedule::new(mode.radius_factor, self.scene.params.scene_sphere[3], DEFAULT_ALPHA);
        let (mis_vm, mis_vc) = schedule.mis_factors(0, light_paths, mode.vc, mode.vm);
        let push = GpuPush {
            iteration: 0,
            count: PATHS,
            mis_vm,
            mis_vc: mis_vc * mode.vc_scale,
            radius: schedule.radius(0),
            light_paths,
            ..Default::default()
        };
        let mut batch = gpu.batch().unwrap();
        batch.dispatch(&self.kernel, groups_2d(PATHS, 64), bytemuck::bytes_of(&push)).unwrap();
        batch.submit_wait(None).unwrap();
        self.out.read::<PathOut>().unwrap()
    }
}

/// glossy_floor_scene (GGX floor, GGX + diffuse wall, area light) plus a point light:
/// lights of both kinds, one of them delta, picked by power (the default), so the pick
/// probabilities differ per light.
fn ggx_scene() -> Scene {
    let metal = Material {
        name: "ggx metal".into(),
        diffuse: Vec3::splat(0.1),
        glossy: Vec3::new(0.9, 0.7, 0.5),
        roughness: 0.3,
        ..Default::default()
    };
    let plastic = Material {
        name: "ggx plastic".into(),
        diffuse: Vec3::new(0.5, 0.3, 0.2),
        glossy: Vec3::splat(0.04),
        roughness: 0.6,
        ..Default::default()
    };
    let mut s = glossy_floor_scene(metal, plastic);
    s.lights.push(Light::Point { position: Vec3::new(0.5, 1.0, 1.0), intensity: Vec3::splat(3.0) });
    s.name = "ggx + point".into();
    s
}

/// ggx_scene with 60 small emitters of four colours facing every way: with
/// `--light-selection tree` next-event estimation's pick depends on the receiving point
/// (src/render/light_tree.rs), the light subpaths' does not (glsl/mis_weights.glsl).
fn emitter_cloud_scene() -> Scene {
    let mut s = ggx_scene();
    add_emitter_cloud(&mut s, 60, 3);
    s.name = "ggx + point + emitter cloud".into();
    s
}

/// ggx_scene with shading normals: tilted up to 30 degrees off every triangle, and a
/// coarse smooth-shaded sphere mesh on the floor.
fn smooth_ggx_scene() -> Scene {
    let mut s = ggx_scene();
    tilt_shading_normals(&mut s, 30.0, 7);
    s.triangles.extend(smooth_sphere_mesh(Vec3::new(-0.5, 0.8, 0.4), 0.4, 5, 8, 0));
    s.name = "ggx + point, shading normals".into();
    s
}

/// ggx_scene with a rough glass sphere (IOR 1.5, roughness 0.3) and a rougher glass
/// sphere mesh (IOR 1.33, roughness 0.6) with its sphere's shading normals on the floor:
/// paths through the rough dielectric's transmission in both directions, connected and
/// merged on it (its forward and reverse pdfs, glsl/bsdf.glsl).
fn rough_glass_scene() -> Scene {
    let mut s = ggx_scene();
    let glass = |name: &str, ior: f32, roughness: f32| Material {
        name: name.into(),
        mirror: Vec3::ONE,
        ior,
        dielectric_roughness: roughness,
        ..Default::default()
    };
    let a = s.materials.len() as u32;
    s.materials.push(glass("rough glass 0.3", 1.5, 0.3));
    s.materials.push(glass("rough glass 0.6", 1.33, 0.6));
    s.spheres.push(vkvcm::scene::Sphere { center: Vec3::new(-0.8, 0.2, 0.5), radius: 0.5, material: a });
    s.triangles.extend(smooth_sphere_mesh(Vec3::new(0.8, 0.4, 0.55), 0.55, 5, 8, a + 1));
    s.name = "ggx + point, rough glass".into();
    s
}

/// ggx_scene with the glTF extensions' lobes (glsl/lobes/): the left floor a red
/// dielectric (roughness 0.5) under a clear coat (roughness 0.3), a sheen and an iridescent
/// film; the right floor an anisotropic metal (strength 0.7, rotated 0.3 rad off its +x
/// tangents); a smooth-shaded sphere mesh that transmits half its diffuse light; a sphere
/// of rough glass of weight 0.5 beside the lobes (partial transmission): each lobe's
/// forward and reverse pdfs on both subpaths, and Russian roulette's continuation
/// probabilities, which depend on the fixed direction under a coat or a sheen and on a
/// dielectric (glsl/bsdf.glsl `cont_prob_from`). Not smooth partial glass: this kernel's
/// fixed paths cannot tell its delta refraction from its lobes at one vertex
/// (`mis_on_scatter_to`).
fn layered_scene() -> Scene {
    let mut s = ggx_scene();
    s.materials[0] = Material {
        name: "coat + sheen + film".into(),
        clearcoat: 1.0,
        clearcoat_roughness: 0.3,
        sheen_color: Vec3::new(0.6, 0.5, 0.4),
        sheen_roughness: 0.5,
        iridescence: 1.0,
        iridescence_thickness_max: 400.0,
        ..Material::metallic_roughness(Vec3::new(0.8, 0.2, 0.1), 0.0, 0.5)
    };
    s.materials[1] = Material {
        name: "anisotropic metal".into(),
        anisotropy_strength: 0.7,
        anisotropy_rotation: 0.3,
        ..Material::metallic_roughness(Vec3::new(0.9, 0.8, 0.6), 1.0, 0.4)
    };
    for tri in s.triangles.iter_mut().filter(|t| t.material == 1) {
        tri.attributes = Some(Box::new(vkvcm::scene::VertexAttributes {
            uv: [Some([glam::Vec2::ZERO, glam::Vec2::X, glam::Vec2::Y]), None],
            color: None,
            tangent: Some([glam::Vec4::new(1.0, 0.0, 0.0, 1.0); 3]),
        }));
    }
    let translucent = s.materials.len() as u32;
    s.materials.push(Material {
        name: "diffuse transmission".into(),
        diffuse_transmission: Some(Box::new(vkvcm::scene::DiffuseTransmission {
            factor: 0.5,
            color: Vec3::new(0.9, 0.8, 0.7),
            metallic: 0.0,
            texture: None,
            color_texture: None,
        })),
        ..Material::metallic_roughness(Vec3::new(0.7, 0.7, 0.6), 0.0, 0.7)
    });
    s.triangles.extend(smooth_sphere_mesh(Vec3::new(-0.6, 0.5, 0.5), 0.5, 5, 8, translucent));
    let partial = s.materials.len() as u32;
    s.materials.push(Material {
        name: "rough glass beside lobes".into(),
        ..Material::transmissive(Vec3::new(0.8, 0.9, 0.7), 0.0, 0.4, 0.5, 1.5, Vec3::splat(0.04))
    });
    s.spheres.push(vkvcm::scene::Sphere { center: Vec3::new(0.8, 0.4, 0.6), radius: 0.4, material: partial });
    s.name = "ggx + point, layered lobes".into();
    s
}

/// `s` under a constant sky as well, with a mirror sphere: next-event estimation draws the
/// sky's directions from the BSDF at the receiving point, so a light subpath from the sky
/// has the direct pdf of its first hit only once the camera side's direction is known
/// (glsl/subpath.glsl `dvcm_at`), here for every lobe of `s` and at a delta first hit.
fn with_sky(mut s: Scene) -> Scene {
    s.lights.push(Light::Background { radiance: Vec3::splat(0.5) });
    let mirror = s.materials.len() as u32;
    s.materials.push(Material { name: "mirror".into(), mirror: Vec3::splat(0.9), ior: -1.0, ..Default::default() });
    s.spheres.push(vkvcm::scene::Sphere { center: Vec3::new(0.0, -0.6, 0.35), radius: 0.35, material: mirror });
    s.name = format!("{} + sky + mirror", s.name);
    s
}

fn print_summary(mode: Mode, s: &Summary) {
    let shares: Vec<String> = CLASSES
        .iter()
        .enumerate()
        .map(|(c, name)| format!("{name} {:.3} (n {})", s.class_weight[c] / s.paths.max(1) as f64, s.class_count[c]))
        .collect();
    println!(
        "{}: {} paths (by length {:?}), {} through specular vertices, {} from area lights sampled by solid angle, {} unsampled, {} with max weight < 0.9; max |sum-1| = {:.3e}; mean weight per path: {}",
        mode.name,
        s.paths,
        &s.by_length[1..=MAX_PATH_LENGTH as usize],
        s.through_specular,
        s.solid_angle,
        s.unsampled,
        s.shared,
        s.max_err,
        shares.join(", ")
    );
    if let Some((id, w)) = &s.worst {
        println!("  worst: {id}: {w:?}");
    }
}

fn check_mode(mode: Mode, s: &Summary) {
    assert!(
        s.errors.is_empty(),
        "{}: {} of {} paths fail:\n{}",
        mode.name,
        s.errors.len(),
        s.paths,
        s.errors[..s.errors.len().min(10)].join("\n")
    );
    // Not vacuous: enough paths of every length, through specular vertices, with the
    // weight shared between techniques, and every technique class of the mode (but the
    // rarely applicable emitter hit) carrying a part of the total weight.
    assert!(s.paths >= MIN_PATHS, "{}: only {} paths were built", mode.name, s.paths);
    for (k, n) in s.by_length[1..=MAX_PATH_LENGTH as usize].iter().enumerate() {
        assert!(*n >= 30, "{}: only {n} paths of length {}", mode.name, k + 1);
    }
    assert!(
        s.through_specular * 10 >= s.paths,
        "{}: only {} paths through specular vertices",
        mode.name,
        s.through_specular
    );
    // Triangle lights' solid-angle pdfs (lights.glsl) enter the emitter-hit, next-event and
    // light-start weights of a good share of the paths.
    assert!(
        s.solid_angle * 5 >= s.paths,
        "{}: only {} of {} paths start on an area light sampled by solid angle",
        mode.name,
        s.solid_angle,
        s.paths
    );
    assert!(s.shared * 4 >= s.paths, "{}: only {} of {} paths share their weight", mode.name, s.shared, s.paths);
    for (c, name) in CLASSES.iter().enumerate().skip(1) {
        let present = if c == 4 { mode.vm } else { mode.vc };
        let share = s.class_weight[c] / s.paths as f64;
        if present {
            assert!(share > 0.005, "{}: technique class '{name}' carries only {share:.4} of the weight", mode.name);
        }
    }
}

#[test]
fn mis_weights_sum_to_one() {
    let scenes: Vec<(Scene, LightSelection)> = ["glm_c", "gbs_b", "gbs_p", "gbs_s"]
        .iter()
        .map(|n| vkvcm::scene::load_named(n).unwrap())
        .chain(std::iter::once(ggx_scene()))
        .chain(std::iter::once(smooth_ggx_scene()))
        .chain(std::iter::once(rough_glass_scene()))
        .chain(std::iter::once(layered_scene()))
        .chain(std::iter::once(environment_scene(smooth_sky(16, 9), 40.0)))
        .chain(std::iter::once(with_sky(rough_glass_scene())))
        .chain(std::iter::once(with_sky(layered_scene())))
        .map(|s| (s, LightSelection::Power))
        .chain(std::iter::once((emitter_cloud_scene(), LightSelection::Tree)))
        .collect();
    // The last mode is the negative control: the check can fail.
    let bad = Mode { name: "vcm, mis_vc x2", vc_scale: 2.0, ..VCM_WIDE };
    let modes = [BPT, BPM, VCM, VCM_WIDE, bad];
    let mut sums: Vec<Summary> = modes.iter().map(|_| Summary::default()).collect();
    with_gpu(|gpu| {
        for (i, (scene, selection)) in scenes.iter().enumerate() {
            let bench = Bench::new(gpu, scene, 1234 + i as u32, *selection);
            for (m, mode) in modes.iter().enumerate() {
                check_paths(&scene.name, *mode, &bench.run(gpu, *mode), &mut sums[m]);
            }
        }
    });
    for (mode, s) in modes.iter().zip(&sums) {
        print_summary(*mode, s);
    }
    for (mode, s) in modes.iter().zip(&sums).take(modes.len() - 1) {
        check_mode(*mode, s);
    }
    let s = &sums[modes.len() - 1];
    assert!(s.max_err > 10.0 * TOL, "max |sum-1| = {} with a wrong mis_vc", s.max_err);
    assert!(s.errors.len() * 20 > s.paths, "only {} of {} paths fail with a wrong mis_vc", s.errors.len(), s.paths);
}
