//! `vkvcm info SCENE`: what a render of the scene would hold and need, before rendering:
//! what the importer read and skipped, the features the kernels are compiled with, and the
//! plan of buffer sizes (`Renderer::plan_sizes`) against the chosen device's limits.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::Args;
use serde::Serialize;
use serde_json::Value;

use super::exit::{Class, ClassifyExt};
use vkvcm::render::features::FeatureSet;
use vkvcm::render::sizes::SizeLimits;
use vkvcm::render::{Algorithm, Budget, RenderSettings, Renderer};
use vkvcm::scene::{self, Light, Material, Scene};

#[derive(Args)]
pub struct InfoArgs {
    #[command(flatten)]
    pub scene: super::scene_args::SceneArgs,
    /// The estimator whose buffers are planned.
    #[arg(long, short = 'a', value_enum, default_value = "vcm")]
    pub algo: Algorithm,
    /// Light subpaths per iteration, N_L (as `render --light-paths`).
    #[arg(long, value_name = "N")]
    pub light_paths: Option<u32>,
    /// The features and plan of `render --generic`.
    #[arg(long)]
    pub generic: bool,
    /// Print JSON (one object: scene, features, plan) instead of text.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub gpu: super::GpuArgs,
}

/// Everything `info` reports; `--json` prints it as is.
#[derive(Serialize)]
struct Info {
    scene: SceneInfo,
    features: FeatureSet,
    plan: PlanInfo,
}

#[derive(Serialize)]
struct SceneInfo {
    name: String,
    file: Option<PathBuf>,
    /// Triangles placed in the world (instances counted once per placement).
    triangles: u64,
    /// Triangles stored (world-space ones and the shared meshes' once each).
    stored_triangles: usize,
    /// Meshes stored once and placed by instances.
    shared_meshes: usize,
    instances: usize,
    spheres: usize,
    /// Materials by lobes: "diffuse", "ggx+diffuse", "dielectric", ... (+ "emissive").
    materials_by_kind: BTreeMap<String, usize>,
    /// The file's materials by glTF extension (KHR_materials_transmission, ...).
    materials_by_extension: BTreeMap<String, usize>,
    /// The file's extensionsUsed.
    extensions_used: Vec<String>,
    textures: Vec<TextureInfo>,
    lights_by_kind: BTreeMap<String, usize>,
    /// The file's cameras; the render uses `camera_used`.
    cameras: Vec<CameraInfo>,
    camera_used: UsedCamera,
    /// What the importer skipped or could not represent (its warnings).
    warnings: Vec<String>,
    degenerate_triangles: usize,
}

#[derive(Serialize)]
struct TextureInfo {
    name: String,
    width: u32,
    height: u32,
    bytes: u64,
}

#[derive(Serialize)]
struct CameraInfo {
    name: Option<String>,
    kind: String,
    yfov_degrees: Option<f64>,
    /// The file's aspectRatio (width / height), if it gives one.
    aspect: Option<f64>,
}

#[derive(Serialize)]
struct UsedCamera {
    /// `--camera`, else the file's first camera (or one framing the scene).
    selected: Option<String>,
    yfov_degrees: f32,
    /// The image's aspect (--width / --height, else the camera's), which the render uses.
    aspect: f64,
}

#[derive(Serialize)]
struct PlanInfo {
    algorithm: String,
    width: u32,
    height: u32,
    device: String,
    buffers: Vec<BufferInfo>,
    total_bytes: u64,
    /// The device's largest device-local memory heap, which holds every buffer.
    heap_bytes: u64,
    /// Whether the device can hold the plan (each buffer within its limit, the total
    /// within the heap), as `render` checks before allocating.
    fits: bool,
    /// Why not, when it does not fit.
    error: Option<String>,
}

#[derive(Serialize)]
struct BufferInfo {
    name: String,
    bytes: u64,
    /// How the kernels reach it, which sets its limit.
    access: String,
    limit_bytes: u64,
}

/// Prints the report; `Some(Class::Memory)` when the frame does not fit the device.
pub fn info_cmd(a: InfoArgs) -> Result<Option<Class>> {
    a.scene.check().class(Class::Usage)?;
    let name = a.scene.name();
    let loaded = a.scene.load().class(Class::Scene)?;
    let (width, height) = a.scene.frame_size(&loaded);
    let file = scene::builtin_path(&name).or_else(|| Some(PathBuf::from(&name)).filter(|p| p.is_file()));
    let document = match &file {
        Some(f) => document_json(f).class(Class::Scene)?,
        None => Value::Null,
    };
    let mut settings = RenderSettings::new(a.algo, width, height, Budget::Iterations(1));
    settings.light_paths = a.light_paths;
    settings.generic = a.generic;
    let gpu = super::open_device(&a.gpu)?;
    let plan = Renderer::plan_sizes(&gpu, &loaded, &settings).class(Class::Usage)?;
    let limits = SizeLimits::of(&gpu);
    let buffers: Vec<BufferInfo> = plan
        .buffers()
        .iter()
        .map(|b| BufferInfo {
            name: b.name.to_string(),
            bytes: b.bytes,
            access: format!("{:?}", b.access).to_lowercase(),
            limit_bytes: limits.max_bytes(b),
        })
        .collect();
    let what = format!("a {width}x{height} {} render", a.algo.name());
    let error = plan.check(&gpu, &what).err().map(|e| format!("{e:#}"));
    let info = Info {
        scene: scene_info(&loaded, file, &document, a.scene.camera.clone(), width, height),
        features: FeatureSet::new(&loaded, a.generic),
        plan: PlanInfo {
            algorithm: a.algo.name().to_string(),
            width,
            height,
            device: gpu.info.name.clone(),
            total_bytes: buffers.iter().map(|b| b.bytes).sum(),
            buffers,
            heap_bytes: limits.heap,
            fits: error.is_none(),
            error,
        },
    };
    if a.json {
        println!("{}", serde_json::to_string_pretty(&info)?);
    } else {
        print!("{}", text(&info));
    }
    Ok((!info.plan.fits).then_some(Class::Memory))
}

/// The file's glTF JSON (of a .gltf or a .glb's JSON chunk), for what the scene does not
/// keep: extensions and the list of cameras.
fn document_json(path: &Path) -> Result<Value> {
    let g = gltf::Gltf::open(path).with_context(|| format!("{}", path.display()))?;
    Ok(serde_json::to_value(g.document.as_json())?)
}

fn scene_info(s: &Scene, file: Option<PathBuf>, doc: &Value, camera: Option<String>, w: u32, h: u32) -> SceneInfo {
    let mut materials_by_kind = BTreeMap::new();
    for m in &s.materials {
        *materials_by_kind.entry(material_kind(m)).or_insert(0) += 1;
    }
    let mut materials_by_extension = BTreeMap::new();
    for m in doc["materials"].as_array().into_iter().flatten() {
        for ext in m["extensions"].as_object().into_iter().flat_map(|o| o.keys()) {
            *materials_by_extension.entry(ext.clone()).or_insert(0) += 1;
        }
    }
    let mut lights_by_kind = BTreeMap::new();
    for l in &s.lights {
        *lights_by_kind.entry(light_kind(l).to_string()).or_insert(0) += 1;
    }
    let cameras = doc["cameras"]
        .as_array()
        .into_iter()
        .flatten()
        .map(|c| {
            let p = &c["perspective"];
            CameraInfo {
                name: c["name"].as_str().map(str::to_string),
                kind: c["type"].as_str().unwrap_or("?").to_string(),
                yfov_degrees: p["yfov"].as_f64().map(f64::to_degrees),
                aspect: p["aspectRatio"].as_f64(),
            }
        })
        .collect();
    let strings =
        |v: &Value| v.as_array().into_iter().flatten().filter_map(|e| e.as_str().map(str::to_string)).collect();
    SceneInfo {
        name: s.name.clone(),
        file,
        triangles: s.placed_triangles(),
        stored_triangles: s.triangles.len(),
        shared_meshes: s.meshes.len(),
        instances: s.instances.len(),
        spheres: s.spheres.len(),
        materials_by_kind,
        materials_by_extension,
        extensions_used: strings(&doc["extensionsUsed"]),
        textures: s
            .images
            .iter()
            .map(|t| TextureInfo {
                name: t.name.clone(),
                width: t.width,
                height: t.height,
                bytes: t.texels.len() as u64 * 4,
            })
            .collect(),
        lights_by_kind,
        cameras,
        camera_used: UsedCamera {
            selected: camera,
            yfov_degrees: s.camera.yfov.to_degrees(),
            aspect: w as f64 / h as f64,
        },
        warnings: s.report.warnings.clone(),
        degenerate_triangles: s.report.degenerate_triangles,
    }
}

/// A material's lobes, "+"-joined in a fixed order, with "emissive" when it emits.
fn material_kind(m: &Material) -> String {
    use glam::Vec3;
    let lobes = [
        ("dielectric", m.is_dielectric()),
        ("mirror", m.mirror != Vec3::ZERO),
        ("ggx", m.glossy != Vec3::ZERO),
        ("phong", m.phong != Vec3::ZERO),
        ("diffuse", m.diffuse != Vec3::ZERO),
        ("emissive", m.emission != Vec3::ZERO),
    ];
    let names: Vec<&str> = lobes.iter().filter(|(_, on)| *on).map(|(n, _)| *n).collect();
    if names.is_empty() {
        "black".into()
    } else {
        names.join("+")
    }
}

fn light_kind(l: &Light) -> &'static str {
    match l {
        Light::Area { .. } => "area (emitting triangle)",
        Light::Point { .. } => "point",
        Light::Spot { .. } => "spot",
        Light::Directional { .. } => "directional",
        Light::Background { .. } => "background",
        Light::Environment(_) => "environment map",
    }
}

fn mib(b: u64) -> f64 {
    b as f64 / (1u64 << 20) as f64
}

/// The report as text.
fn text(i: &Info) -> String {
    let s = &i.scene;
    let mut o = format!("scene {}", s.name);
    if let Some(f) = &s.file {
        o += &format!(" ({})", f.display());
    }
    o += &format!("\n  {} triangles placed, {} stored", s.triangles, s.stored_triangles);
    if s.instances > 0 {
        o += &format!(" ({} shared mesh(es) placed by {} instances)", s.shared_meshes, s.instances);
    }
    o += &format!(", {} sphere(s)\n", s.spheres);
    let counts = |m: &BTreeMap<String, usize>| {
        if m.is_empty() {
            "none".to_string()
        } else {
            m.iter().map(|(k, n)| format!("{n} {k}")).collect::<Vec<_>>().join(", ")
        }
    };
    o += &format!("  materials: {}\n", counts(&s.materials_by_kind));
    o += &format!("  material extensions: {}\n", counts(&s.materials_by_extension));
    if !s.extensions_used.is_empty() {
        o += &format!("  extensions used: {}\n", s.extensions_used.join(", "));
    }
    o += &format!("  textures: {}\n", s.textures.len());
    for t in &s.textures {
        o += &format!("    {} {}x{} ({:.2} MiB)\n", t.name, t.width, t.height, mib(t.bytes));
    }
    o += &format!("  lights: {}\n", counts(&s.lights_by_kind));
    o += &format!("  cameras in the file: {}\n", s.cameras.len());
    for c in &s.cameras {
        let fov = c.yfov_degrees.map_or(String::new(), |f| format!(", yfov {f:.1} deg"));
        let aspect = c.aspect.map_or(", no aspect".to_string(), |a| format!(", aspect {a:.3}"));
        o += &format!("    {} ({}{fov}{aspect})\n", c.name.as_deref().unwrap_or("unnamed"), c.kind);
    }
    let u = &s.camera_used;
    o += &format!(
        "  camera used: {} (yfov {:.1} deg, image aspect {:.3})\n",
        u.selected.as_deref().unwrap_or("default"),
        u.yfov_degrees,
        u.aspect
    );
    for w in &s.warnings {
        o += &format!("  skipped: {w}\n");
    }
    if s.degenerate_triangles > 0 {
        o += &format!("  skipped: {} degenerate triangle(s)\n", s.degenerate_triangles);
    }
    let features = i.features.to_string();
    o += features.trim_end();
    o += "\n";
    let p = &i.plan;
    o += &format!("plan of a {}x{} {} render on {}:\n", p.width, p.height, p.algorithm, p.device);
    let named: Vec<(String, u64)> = p.buffers.iter().map(|b| (b.name.clone(), b.bytes)).collect();
    o += &vkvcm::render::features::buffer_table(&named);
    o += &format!("  device heap: {:.0} MiB\n", mib(p.heap_bytes));
    o += &match &p.error {
        None => "fits the device\n".to_string(),
        Some(e) => format!("does NOT fit the device: {e}\n"),
    };
    o
}
