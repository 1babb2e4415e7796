//! glTF 2.0 import (`.gltf` with external or embedded buffers, `.glb`) into [`Scene`].
//!
//! What is read, what is approximated and what is refused is specified in
//! `docs/scene-format.md`; in short: the default scene's node hierarchy with world
//! transforms, triangle primitives (TRIANGLES, TRIANGLE_STRIP, TRIANGLE_FAN; indexed or
//! not) with optional normals, sparse accessors, `KHR_mesh_quantization`, morph targets at
//! their default weights, skins in the pose their joints' node transforms give, the
//! metallic/roughness material mapped to vkvcm's diffuse + GGX + mirror/dielectric model,
//! emission (one area light per emitting triangle), `KHR_lights_punctual`, the first
//! perspective camera, base-colour textures (PNG/JPEG images, samplers,
//! `KHR_texture_transform`) with TEXCOORD_0/1, vertex colours (COLOR_0), alpha modes (BLEND
//! as stochastic transparency), and the vkvcm extensions `VKVCM_spheres`, `VKVCM_materials_phong` and
//! `VKVCM_background`.
//!
//! Everything that is not represented produces one warning per kind in
//! [`LoadReport::warnings`]; malformed input produces an error that names the file and the
//! offending object. Buffers are resolved here (not by `gltf::import`) so that relative
//! URIs cannot leave the scene's folder.
//!
//! This module holds the entry points and the node walk; the rest is split by concern:
//!
//! - `sources.rs`: the file container (`.gltf` JSON or `.glb` chunks), buffer URIs, `data:`
//!   URIs and the folder sandbox;
//! - `document.rs`: validation of the parsed JSON before the `gltf` crate's reader sees it;
//! - `extensions.rs`: the extensions the importer understands and readers for their payloads;
//! - `accessors.rs`: bounds-checked accessor reads (sparse and normalized/quantized
//!   attributes, indices, skin matrices);
//! - `geometry.rs`: meshes (morph targets, skinning, triangulation, transforms) and
//!   `VKVCM_spheres`;
//! - `instancing.rs`: meshes stored once and placed by instances (several nodes,
//!   `EXT_mesh_gpu_instancing`);
//! - `materials.rs`: the glTF material -> vkvcm material mapping;
//! - `lights.rs`: punctual lights, area lights from emission and the background;
//! - `cameras.rs`: camera candidates and the choice of the rendered camera;
//! - `warnings.rs`: warnings collected once per kind.

mod accessors;
mod cameras;
mod document;
mod extensions;
mod geometry;
mod instancing;
mod lights;
mod materials;
mod meshopt_views;
mod skins;
mod sources;
mod tangents;
mod textures;
mod warnings;

pub use extensions::{EXT_BACKGROUND, EXT_MATERIALS_PHONG, EXT_SPHERES, SUPPORTED_EXTENSIONS};
pub use materials::MAX_ATTENUATION;
pub use sources::{decode_data_uri, encode_data_uri};
pub use textures::{MAX_IMAGE_SIDE, MAX_IMAGE_TEXELS};

use super::{Camera, EnvironmentLight, Light, LoadReport, Scene};
use anyhow::{anyhow, bail, Result};
use cameras::CameraCandidate;
use glam::{DMat4, DQuat, DVec3, Mat4, Vec3};
use std::path::Path;
use warnings::Warnings;

/// Options of [`load_gltf`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LoadOptions {
    /// Select the camera whose node name or camera name equals this; `None`: the first
    /// perspective camera in node order.
    pub camera: Option<String>,
    /// Render the glTF scene (`scenes[i]`) with this name, else the one with this index
    /// (`vkvcm render --gltf-scene`); `None`: the file's `scene`, else scene 0.
    pub scene: Option<String>,
    /// Light the scene with this environment instead of the file's background
    /// (`VKVCM_background` / `VKVCM_environment`, which are then not read) or the default
    /// white sky (`vkvcm render --env`).
    pub environment: Option<EnvironmentLight>,
    /// The environment of a file that has neither punctual lights nor an environment of
    /// its own (`VKVCM_background` / `VKVCM_environment`), emissive surfaces or not, as
    /// glTF viewers light such files (`vkvcm render`'s default: the studio,
    /// src/scene/default_environments.rs); it sets `LoadReport::lighting_note`. `None`:
    /// only a file without any light gets a light, the uniform white sky.
    pub default_environment: Option<EnvironmentLight>,
    /// No environment at all, not even the file's own or the white sky (`--env none`).
    pub no_environment: bool,
    /// Store every mesh placement as world-space triangles, even of meshes that several
    /// nodes (or `EXT_mesh_gpu_instancing`) place, which are otherwise stored once and
    /// instanced (`vkvcm render --flatten-instances`; the image is the same up to float
    /// rounding, the memory is not).
    pub flatten_instances: bool,
}

/// Loads a `.gltf` or `.glb` file. Errors name the file and the offending object.
pub fn load_gltf(path: &Path, options: &LoadOptions) -> Result<Scene> {
    let bytes = std::fs::read(path).map_err(|e| one_line(path, &anyhow!("cannot read scene file: {e}")))?;
    load_gltf_bytes(&bytes, path, options)
}

/// Imports `bytes` as if they were the contents of the `.gltf`/`.glb` file `path`: external
/// buffers are resolved in `path`'s folder, the scene is named after its file stem, and an
/// error is one line that starts with `path`. The entry point of the fuzz target
/// (`fuzz/fuzz_targets/gltf_load.rs`); it never panics on malformed input.
pub fn load_gltf_bytes(bytes: &[u8], path: &Path, options: &LoadOptions) -> Result<Scene> {
    let base_dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let name = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    import_bytes(bytes, base_dir, name, options).map_err(|e| one_line(path, &e))
}

/// `"<path>: <error chain>"` on one line (the CLI prints errors as one `error: ...` line;
/// a newline in a file name or a nested message must not break that).
pub(crate) fn one_line(path: &Path, e: &anyhow::Error) -> anyhow::Error {
    let msg = format!("{}: {e:#}", path.display());
    anyhow!(msg.replace(['\n', '\r'], " "))
}

/// Parses and validates the document, loads its buffers from `base_dir`, converts it and
/// attaches the collected warnings (the importer's own and the camera checks of
/// [`super::validate`]) to the scene's report.
fn import_bytes(bytes: &[u8], base_dir: &Path, name: String, options: &LoadOptions) -> Result<Scene> {
    let mut warnings = Warnings::default();
    let parsed = document::parse_document(bytes, &mut warnings)?;
    let doc = gltf::Document::from_json_without_validation(parsed.root);
    let mut buffers = sources::load_buffers(&doc, parsed.blob, base_dir)?;
    meshopt_views::decode_views(&doc, &mut buffers)?;
    let morph_attributes = parsed.morph_attributes;
    let mut importer = Importer {
        doc: &doc,
        base_dir,
        buffers,
        quantized: parsed.quantized,
        warnings,
        scene: Scene {
            name,
            triangles: Vec::new(),
            meshes: Vec::new(),
            instances: Vec::new(),
            spheres: Vec::new(),
            materials: Vec::new(),
            lights: Vec::new(),
            camera: Camera {
                position: Vec3::ZERO,
                forward: Vec3::NEG_Z,
                up: Vec3::Y,
                yfov: std::f32::consts::FRAC_PI_4,
            },
            report: LoadReport::default(),
            images: Vec::new(),
        },
        default_material: None,
        image_cache: vec![None; doc.images().len()],
        cameras: Vec::new(),
        orthographic: Vec::new(),
        punctual: Vec::new(),
        node_world: Vec::new(),
        rebase: DMat4::IDENTITY,
        instancing: Default::default(),
        morph_attributes,
    };
    importer.run(options)?;
    let Importer { mut scene, mut warnings, .. } = importer;
    for (kind, detail) in super::validate::camera_warnings(&scene) {
        warnings.warn(kind, detail);
    }
    scene.report.warnings = warnings.finish();
    Ok(scene)
}

/// The conversion of one validated document into a [`Scene`]. Its methods are spread over
/// the submodules by concern; [`Importer::run`] is the order in which they are applied.
struct Importer<'d> {
    doc: &'d gltf::Document,
    /// The folder relative URIs are resolved in (environment maps).
    base_dir: &'d Path,
    /// The document's buffers, indexed like `doc.buffers()`, each at least `byteLength` long.
    buffers: Vec<Vec<u8>>,
    /// The file uses `KHR_mesh_quantization`: integer vertex attributes are allowed.
    quantized: bool,
    warnings: Warnings,
    /// The scene being built; its camera is a placeholder until [`Importer::run`] chooses one.
    scene: Scene,
    /// Index of glTF's default material in `scene.materials`, added on first use.
    default_material: Option<u32>,
    /// Index in `scene.images` of each glTF image decoded so far, by glTF image index.
    image_cache: Vec<Option<u32>>,
    /// Perspective cameras met in node order.
    cameras: Vec<CameraCandidate>,
    /// Orthographic cameras met in node order, by name (node name, else camera name, else
    /// `node N`): skipped, but named when `--camera` asks for one.
    orthographic: Vec<(Option<String>, Option<String>, usize)>,
    /// Punctual lights met in node order; appended after the area lights.
    punctual: Vec<Light>,
    /// World transform (f64, not re-centred) of every node of the rendered scene, by node
    /// index; `None` for nodes outside it. Skins read their joints' transforms here.
    node_world: Vec<Option<DMat4>>,
    /// The re-centring applied to every world transform (translation by minus the chosen
    /// camera's position, docs/numerics.md).
    rebase: DMat4,
    /// Which meshes are stored once, and their placements met so far.
    instancing: instancing::Instancing,
    /// The TEXCOORD_0, TEXCOORD_1 and COLOR_0 morph-target displacements (gltf-json does
    /// not have them), each with a valid accessor index.
    morph_attributes: Vec<sources::MorphAttribute>,
}

impl<'d> Importer<'d> {
    fn run(&mut self, options: &LoadOptions) -> Result<()> {
        let doc = self.doc;
        for m in doc.materials() {
            let mat = self.convert_material(&m)?;
            self.scene.materials.push(mat);
        }
        if doc.animations().len() > 0 {
            self.warnings.warn(
                "animations are not supported (the static pose is used)",
                format!("{} animation(s)", doc.animations().len()),
            );
        }

        let scene = self.scene_to_render(options.scene.as_deref())?;
        // World transforms are composed in f64 and the scene is re-centred on the chosen
        // camera before it is rounded to f32 (camera-relative coordinates,
        // docs/numerics.md): a scene 1e5 units from the origin keeps the precision it has
        // near the origin.
        let order = walk_nodes(&scene, doc.nodes().len())?;
        let origin = cameras::camera_origin(&order, options.camera.as_deref());
        self.scene.report.origin = origin.to_array();
        let rebase = DMat4::from_translation(-origin);
        self.rebase = rebase;
        self.node_world = vec![None; doc.nodes().len()];
        for (node, world) in &order {
            self.node_world[node.index()] = Some(*world);
        }
        let nodes: Vec<gltf::Node> = order.iter().map(|(n, _)| n.clone()).collect();
        self.choose_shared_meshes(&nodes, options.flatten_instances)?;
        for (node, world) in &order {
            self.visit_node(node, (rebase * *world).as_mat4())?;
        }
        self.add_shared_meshes()?;

        self.scene.camera = self.choose_camera(options)?;
        self.collect_lights(options)
    }

    /// The scene to render: the one `want` names (a scene name, else a scene index), else
    /// the default scene (`scene`), else the first one. Names the choice in a warning when
    /// the file has several scenes and `want` is `None`, since the others are not rendered.
    fn scene_to_render(&mut self, want: Option<&str>) -> Result<gltf::Scene<'d>> {
        let doc = self.doc;
        let n = doc.scenes().len();
        let describe = |s: &gltf::Scene| match s.name() {
            Some(name) => format!("{} '{name}'", s.index()),
            None => s.index().to_string(),
        };
        if let Some(w) = want {
            let by_name = doc.scenes().find(|s| s.name() == Some(w));
            let by_index = || w.trim().parse::<usize>().ok().and_then(|i| doc.scenes().nth(i));
            return by_name.or_else(by_index).ok_or_else(|| {
                let names: Vec<String> = doc.scenes().map(|s| describe(&s)).collect();
                anyhow!(
                    "no glTF scene named or numbered '{w}' (available scenes: {})",
                    if names.is_empty() { "none".to_string() } else { names.join(", ") }
                )
            });
        }
        let (s, how) = match doc.default_scene() {
            Some(s) => (s, "the default one (`scene`)"),
            None => (
                doc.scenes().next().ok_or_else(|| anyhow!("the file has no scene"))?,
                "the first (the file has no default `scene`)",
            ),
        };
        if n > 1 {
            self.warnings.warn(
                format!("the file has {n} scenes: only {how} is rendered (--gltf-scene NAME|INDEX selects another)"),
                format!("scene {}", describe(&s)),
            );
        }
        Ok(s)
    }

    /// Converts what one node carries (camera, light, mesh, spheres), placed by its world
    /// transform `world` (already re-centred and rounded to f32).
    fn visit_node(&mut self, node: &gltf::Node, world: Mat4) -> Result<()> {
        let ni = node.index();
        let label = match node.name() {
            Some(n) => format!("node {ni} '{n}'"),
            None => format!("node {ni}"),
        };
        if !world.is_finite() {
            bail!("{label}: world transform is not finite");
        }
        if let Some(cam) = node.camera() {
            self.add_camera(node, &cam, world, &label);
        }
        if let Some(light) = node.light() {
            self.add_light(&light, world, &label)?;
        }
        if let Some(mesh) = node.mesh() {
            if !self.place_instanced(node, world, &label) {
                // glTF 2.0 section 3.7.3.2: a skinned mesh is placed by its joints alone.
                match node.skin() {
                    Some(skin) => {
                        let placement = geometry::Placement::Skinned(self.joint_matrices(&skin, &label)?);
                        self.add_mesh(&mesh, &placement, node.weights(), &label)?;
                    }
                    None => {
                        for m in self.node_placements(node, world) {
                            self.add_mesh(&mesh, &geometry::Placement::Rigid(m), node.weights(), &label)?;
                        }
                    }
                }
            }
        }
        if let Some(v) = node.extensions().and_then(|e| e.get(EXT_SPHERES)) {
            self.add_spheres(v, world, ni)?;
        }
        Ok(())
    }
}

/// The nodes of `scene` in depth-first order (parents before children, siblings in
/// document order) with their world transforms in f64. glTF requires the hierarchy to be
/// a forest, so a node reached twice is an error rather than an infinite loop; `node_count`
/// is the number of nodes in the document.
fn walk_nodes<'a>(scene: &gltf::Scene<'a>, node_count: usize) -> Result<Vec<(gltf::Node<'a>, DMat4)>> {
    let mut visited = vec![false; node_count];
    let mut order: Vec<(gltf::Node, DMat4)> = Vec::new();
    let mut stack: Vec<(gltf::Node, DMat4)> =
        scene.nodes().map(|n| (n, DMat4::IDENTITY)).collect::<Vec<_>>().into_iter().rev().collect();
    while let Some((node, parent)) = stack.pop() {
        if std::mem::replace(&mut visited[node.index()], true) {
            bail!(
                "node {} is reached twice in scene {}: the node hierarchy is not a tree",
                node.index(),
                scene.index()
            );
        }
        let world = parent * local_transform_f64(&node);
        let children: Vec<_> = node.children().collect();
        for child in children.into_iter().rev() {
            stack.push((child, world));
        }
        order.push((node, world));
    }
    Ok(order)
}

/// A node's local transform in f64 (TRS composed in f64, so a large translation stays exact).
fn local_transform_f64(node: &gltf::Node) -> DMat4 {
    match node.transform() {
        gltf::scene::Transform::Matrix { matrix } => DMat4::from_cols_array_2d(&matrix.map(|c| c.map(f64::from))),
        gltf::scene::Transform::Decomposed { translation, rotation, scale } => {
            let q = DQuat::from_array(rotation.map(f64::from));
            // glTF rotations are unit quaternions; normalising guards against rounding in the file.
            let q = if q.length_squared() > 0.0 { q.normalize() } else { DQuat::IDENTITY };
            DMat4::from_scale_rotation_translation(
                DVec3::from_array(scale.map(f64::from)),
                q,
                DVec3::from_array(translation.map(f64::from)),
            )
        }
    }
}
