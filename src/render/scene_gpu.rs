//! A scene uploaded to the GPU: BVH, shading data, materials, lights and per-render
//! parameters, in the bindings every render kernel declares (glsl/scene.glsl), bound by
//! their names; all but `scene_params` are read as storage or texel buffers as the
//! kernels' variant says ([`Reads`]).

use std::sync::Arc;

use anyhow::{bail, Result};
use glam::Vec3;

use super::albedo_tables;
use super::atomics::SplatAtomics;
use super::environment::EnvironmentTables;
use super::features::FeatureSet;
use super::gpu_types::*;
use super::light_selection::LightDistribution;
use super::light_tree::LightTree;
use super::reads::Reads;
use super::settings::{FrameSettings, LightSelection};
use super::sizes::{Access, BufferSize, SizeLimits};
use super::variants::SceneVariant;
use crate::bvh;
use crate::bvh::layout::{max_wide_nodes, GpuNode4, GpuPrim};
use crate::gpu::{Bind, Buffer, Gpu, BUFFER_DEVICE_ADDRESS, SHADER_INT64};
use crate::scene::{AlphaMode, EnvironmentMap, Filter, Light, Scene, VertexAttributes, Wrap};

/// Upper bounds of the scene's buffers, known before the BVH is built. Not the albedo
/// tables (src/render/albedo_tables.rs): 16 and 7.3 KiB of texels, within every device's
/// limits (maxTexelBufferElements is at least 65,536).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ScenePlan {
    pub buffers: [BufferSize; 15],
    /// The chunk size in bytes when the kernels read [`CHUNKED`] in chunks.
    pub chunk_bytes: Option<u64>,
    /// The light tree is uploaded (`--light-selection tree`; else its buffer has 0 bytes).
    pub light_tree: bool,
}

/// The scene's arrays that the kernels read by device address in chunks, each chunk its
/// own allocation, when one of them is larger than one binding (or, reached by address,
/// than one allocation) allows (glsl/scene.glsl, SCENE_CHUNKS): the BVH and the
/// per-triangle geometry, which grow with the triangles, in the order of
/// `GpuSceneAddresses::chunk_first` (CHUNK_NODES .. CHUNK_VERTEX_ATTRIBUTES). The scene's
/// size is then limited by device memory, not by one binding or allocation.
pub const CHUNKED: [&str; 5] = ["bvh_nodes", "bvh_prims", "triangles", "shading_normals", "vertex_attributes"];

/// The scene's buffers that the kernels reach by device address where the device has it
/// (glsl/scene.glsl, GpuSceneAddresses): each may then be as large as one allocation
/// rather than one storage binding (128 MiB on lavapipe).
const ADDRESSED: [&str; 4] = ["vertex_attributes", "texture_texels", "env_texels", "env_distribution"];

fn size<T>(n: u64) -> u64 {
    n.saturating_mul(std::mem::size_of::<T>() as u64)
}

impl ScenePlan {
    /// The buffers of `scene`, read as `reads` (with texel reads the BVH and the geometry
    /// are bound only as texel buffers, glsl/scene.glsl and glsl/bvh.glsl), with
    /// [`ADDRESSED`] reached by address when `device_addresses`.
    pub fn new(scene: &Scene, reads: Reads, device_addresses: bool, light_tree: bool) -> ScenePlan {
        let texel = |b: BufferSize| if reads == Reads::Texel { b.reached(Access::Texel) } else { b };
        let tris = scene.triangles.len() as u64;
        // Instances: one primitive in the top-level tree and a two-slot record each.
        let prims = tris + scene.spheres.len() as u64 + 3 * scene.instances.len() as u64;
        // Per-vertex arrays: three entries per triangle with normals or attributes.
        let vertices = scene.triangles.iter().filter(|t| t.n.is_some() || t.attributes.is_some()).count() as u64 * 3;
        let refs = scene
            .materials
            .iter()
            .map(|m| {
                m.base_color_texture.is_some() as u64
                    + m.normal_texture.is_some() as u64
                    + m.emissive_texture.is_some() as u64
                    + m.metallic_roughness_texture.is_some() as u64
                    + m.clearcoat_texture.is_some() as u64
                    + m.clearcoat_roughness_texture.is_some() as u64
                    + m.clearcoat_normal_texture.is_some() as u64
                    + m.sheen_color_texture.is_some() as u64
                    + m.sheen_roughness_texture.is_some() as u64
                    + m.iridescence_texture.is_some() as u64
                    + m.iridescence_thickness_texture.is_some() as u64
                    + m.anisotropy_texture.is_some() as u64
                    + m.diffuse_transmission
                        .as_ref()
                        .map_or(0, |d| d.texture.is_some() as u64 + d.color_texture.is_some() as u64)
                    + m.layer_textures.as_ref().map_or(0, |l| {
                        l.transmission.is_some() as u64
                            + l.specular.is_some() as u64
                            + l.specular_color.is_some() as u64
                    })
            })
            .sum::<u64>();
        let lights = scene.lights.len() as u64;
        let area_lights = scene.lights.iter().filter(|l| matches!(l, Light::Area { .. })).count() as u64;
        let tree_elements = if light_tree { LightTree::max_elements(lights, area_lights) } else { 0 };
        let texels: u64 = scene.images.iter().map(|i| i.texels.len() as u64).sum();
        let (env_w, env_h) = environment_map(scene).map_or((0, 0), |m| (m.width as u64, m.height as u64));
        ScenePlan {
            buffers: [
                BufferSize::new("scene_params", size::<GpuParams>(1)),
                texel(BufferSize::new(
                    "bvh_nodes",
                    size::<GpuNode4>(max_wide_nodes(prims, 1 + scene.meshes.len() as u64)),
                )),
                texel(BufferSize::new("bvh_prims", size::<GpuPrim>(prims))),
                texel(BufferSize::new("triangles", size::<GpuTriangle>(tris))),
                texel(BufferSize::new("spheres", size::<GpuSphere>(scene.spheres.len() as u64))),
                texel(BufferSize::new("materials", size::<GpuMaterial>(scene.materials.len() as u64))),
                texel(BufferSize::new("lights", size::<GpuLight>(scene.lights.len() as u64))),
                // With --light-selection tree: its size at most.
                texel(BufferSize::new("light_tree", size::<[u32; 4]>(tree_elements))),
                texel(BufferSize::new("shading_normals", size::<[f32; 4]>(vertices))),
                BufferSize::new("vertex_attributes", size::<GpuVertexAttributes>(vertices)),
                BufferSize::new("texture_refs", size::<GpuTextureRef>(refs)),
                // RGBA8 texels, four to a 16-byte element.
                BufferSize::new("texture_texels", size::<[u32; 4]>(texels.div_ceil(4))),
                BufferSize::new("env_texels", size::<[f32; 4]>(env_w * env_h)),
                BufferSize::new("env_distribution", size::<f32>(env_h + env_h.saturating_sub(1) * (env_w + 1))),
                BufferSize::new("scene_addresses", size::<GpuSceneAddresses>(1)),
            ]
            .map(|b| {
                if device_addresses && ADDRESSED.contains(&b.name) {
                    b.reached(Access::Address)
                } else {
                    b
                }
            }),
            chunk_bytes: None,
            light_tree,
        }
    }

    /// Makes the kernels read [`CHUNKED`] in chunks when one of them is larger than a
    /// device with `limits` binds and the device has addresses (else the plan's check
    /// refuses the scene, naming the buffer).
    pub fn chunk_if_over_binding(&mut self, limits: &SizeLimits, device_addresses: bool) {
        let over = |b: &BufferSize| CHUNKED.contains(&b.name) && b.bytes > limits.max_bytes(b);
        if !device_addresses || self.chunk_bytes.is_some() || !self.buffers.iter().any(over) {
            return;
        }
        for b in &mut self.buffers {
            if CHUNKED.contains(&b.name) {
                *b = b.reached(Access::Chunked);
            }
        }
        self.chunk_bytes = Some(limits.scene_chunk);
    }

    pub fn buffers(&self) -> Vec<BufferSize> {
        self.buffers.to_vec()
    }
}

/// The scene's buffers and what every kernel reading them is compiled with.
pub struct SceneGpu {
    pub params: GpuParams,
    /// In [`ScenePlan`]'s order; each named as the binding it fills (but [`CHUNKED`] when
    /// read in chunks).
    pub buffers: Vec<Buffer>,
    /// When the kernels read [`CHUNKED`] in chunks: the chunks, which no kernel binds (the
    /// binding `scene_chunks` holds their addresses).
    pub chunks: Vec<Buffer>,
    /// The scene's part of every render kernel's variant (features, reads).
    pub variant: SceneVariant,
}

fn v4(v: Vec3, w: f32) -> [f32; 4] {
    [v.x, v.y, v.z, w]
}

fn bits(u: u32) -> f32 {
    f32::from_bits(u)
}

/// The scene's environment map, if its background is one.
fn environment_map(scene: &Scene) -> Option<&EnvironmentMap> {
    scene.lights.iter().find_map(|l| match l {
        Light::Environment(e) => Some(e.map.as_ref()),
        _ => None,
    })
}

/// Vertex `k`'s attributes: NaN texture coordinates where a set is missing (no texture
/// applies), white where the colour is.
fn vertex_attributes(a: Option<&VertexAttributes>, k: usize) -> GpuVertexAttributes {
    let uv = |set: usize| a.and_then(|a| a.uv[set]).map_or([f32::NAN; 2], |uv| uv[k].to_array());
    let (uv0, uv1) = (uv(0), uv(1));
    GpuVertexAttributes {
        uv: [uv0[0], uv0[1], uv1[0], uv1[1]],
        color: a.and_then(|a| a.color).map_or([1.0; 4], |c| c[k].to_array()),
        tangent: a.and_then(|a| a.tangent).map_or([f32::NAN; 4], |t| t[k].to_array()),
    }
}

/// The scene's textures on the GPU: the texture references of the materials (each
/// material's base-colour texture, normal map, emissive texture and metallic-roughness
/// texture, clearcoat and clearcoat-roughness textures, transmission, specular and
/// specular-colour textures, sheen-colour and sheen-roughness textures, iridescence and
/// iridescence-thickness textures, the anisotropy texture, diffuse-transmission and
/// diffuse-transmission-colour textures, the clear coat's normal map, in material order),
/// per material the indices of its seventeen (or `NO_TEXTURE`),
/// and the texels of the scene's images (RGBA8 packed little-endian, R lowest; four to a
/// 16-byte element).
type GpuTextures = (Vec<GpuTextureRef>, Vec<[u32; 17]>, Vec<[u32; 4]>);

fn gpu_textures(scene: &Scene) -> Result<GpuTextures> {
    let mut first = Vec::with_capacity(scene.images.len());
    let mut flat: Vec<u32> = Vec::new();
    for img in &scene.images {
        if img.width == 0 || img.height == 0 || img.texels.len() as u64 != img.width as u64 * img.height as u64 {
            bail!("texture image {:?}: {} texels for {}x{}", img.name, img.texels.len(), img.width, img.height);
        }
        first.push(flat.len() as u32);
        flat.extend(img.texels.iter().map(|t| u32::from_le_bytes(*t)));
    }
    flat.resize(flat.len().div_ceil(4) * 4, 0);
    let texels = flat.chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]).collect();
    let wrap = |w: Wrap| match w {
        Wrap::Repeat => 0,
        Wrap::ClampToEdge => 1,
        Wrap::MirroredRepeat => 2,
    };
    let mut refs = Vec::new();
    let mut indices = Vec::with_capacity(scene.materials.len());
    for (i, m) in scene.materials.iter().enumerate() {
        let mut index = [NO_TEXTURE; 17];
        let layers = m.layer_textures.as_deref();
        let dt = m.diffuse_transmission.as_deref();
        // Normal maps and metallic-roughness textures hold linear values, not sRGB colours.
        let slots = [
            (m.base_color_texture.as_ref(), false),
            (m.normal_texture.as_ref(), true),
            (m.emissive_texture.as_ref(), false),
            (m.metallic_roughness_texture.as_ref().map(|t| &t.texture), true),
            (m.clearcoat_texture.as_ref(), true),
            (m.clearcoat_roughness_texture.as_ref(), true),
            (layers.and_then(|l| l.transmission.as_ref()), true),
            (layers.and_then(|l| l.specular.as_ref()), true),
            // KHR_materials_specular: specularColorTexture is sRGB, specularTexture linear.
            (layers.and_then(|l| l.specular_color.as_ref()), false),
            // KHR_materials_sheen: sheenColorTexture is sRGB, sheenRoughnessTexture linear.
            (m.sheen_color_texture.as_ref(), false),
            (m.sheen_roughness_texture.as_ref(), true),
            // KHR_materials_iridescence: both linear.
            (m.iridescence_texture.as_ref(), true),
            (m.iridescence_thickness_texture.as_ref(), true),
            // KHR_materials_anisotropy: a direction and a strength, linear.
            (m.anisotropy_texture.as_ref(), true),
            // KHR_materials_diffuse_transmission: the factor's texture (A) is linear, the
            // colour's sRGB.
            (dt.and_then(|d| d.texture.as_ref()), true),
            (dt.and_then(|d| d.color_texture.as_ref()), false),
            // KHR_materials_clearcoat's normal map: linear, as normalTexture.
            (m.clearcoat_normal_texture.as_ref(), true),
        ];
        for (slot, (t, linear)) in slots.into_iter().enumerate() {
            let Some(t) = t else { continue };
            let img = scene
                .images
                .get(t.image as usize)
                .ok_or_else(|| anyhow::anyhow!("material {i} names missing texture image {}", t.image))?;
            let mut flags = wrap(t.wrap_s) | (wrap(t.wrap_t) << 2);
            if t.filter == Filter::Nearest {
                flags |= TEXTURE_NEAREST;
            }
            if t.tex_coord == 1 {
                flags |= TEXTURE_UV1;
            }
            if linear {
                flags |= TEXTURE_LINEAR;
            }
            let [r0, r1] = t.transform;
            index[slot] = refs.len() as u32;
            refs.push(GpuTextureRef {
                image: [first[t.image as usize], img.width, img.height, flags],
                row0: [r0[0], r0[1], r0[2], 0.0],
                row1: [r1[0], r1[1], r1[2], 0.0],
            });
        }
        indices.push(index);
    }
    Ok((refs, indices, texels))
}

/// The lights in GPU form, with their selection table (`d.xyz`: the probability of
/// picking the light, its slot's threshold and alias, src/render/light_selection.rs), and
/// the index of the background light (constant or environment map) if any.
pub fn gpu_lights(scene: &Scene, selection: LightSelection) -> Result<(Vec<GpuLight>, u32)> {
    let mut out = Vec::with_capacity(scene.lights.len());
    let mut background = NO_LIGHT;
    let table = LightDistribution::new(scene, selection);
    for (i, l) in scene.lights.iter().enumerate() {
        let mut g = match *l {
            Light::Area { triangle, radiance } => {
                let t = scene
                    .triangles
                    .get(triangle as usize)
                    .ok_or_else(|| anyhow::anyhow!("area light {i} names missing triangle {triangle}"))?;
                let e1 = t.p[1] - t.p[0];
                let e2 = t.p[2] - t.p[0];
                let area = 0.5 * e1.cross(e2).length();
                GpuLight {
                    a: v4(t.p[0], bits(triangle)),
                    b: v4(e1, 0.0),
                    c: v4(e2, 0.0),
                    d: [0.0, 0.0, 0.0, area],
                    radiance: v4(radiance, bits(LIGHT_AREA)),
                }
            }
            Light::Point { position, intensity } => {
                GpuLight { a: v4(position, 0.0), radiance: v4(intensity, bits(LIGHT_POINT)), ..Default::default() }
            }
            Light::Spot { position, direction, intensity, cos_inner, cos_outer } => GpuLight {
                a: v4(position, 0.0),
                b: v4(direction.normalize(), cos_inner),
                c: [0.0, 0.0, 0.0, cos_outer],
                radiance: v4(intensity, bits(LIGHT_SPOT)),
                ..Default::default()
            },
            Light::Directional { direction, irradiance } => GpuLight {
                b: v4(direction.normalize(), 0.0),
                radiance: v4(irradiance, bits(LIGHT_DIRECTIONAL)),
                ..Default::default()
            },
            Light::Background { .. } | Light::Environment(_) if background != NO_LIGHT => {
                bail!("the scene has more than one background light (VKVCM_background, VKVCM_environment or --env)")
            }
            Light::Background { radiance } => {
                background = i as u32;
                GpuLight { radiance: v4(radiance, bits(LIGHT_BACKGROUND)), ..Default::default() }
            }
            // glsl/environment.glsl: a = (W, H) bits, b = (cos, sin) of the rotation.
            Light::Environment(ref e) => {
                background = i as u32;
                let (sin, cos) = e.rotation_deg.to_radians().sin_cos();
                GpuLight {
                    a: [bits(e.map.width), bits(e.map.height), 0.0, 0.0],
                    b: [cos, sin, 0.0, 0.0],
                    radiance: v4(e.scale, bits(LIGHT_BACKGROUND)),
                    ..Default::default()
                }
            }
        };
        g.d[0] = table.prob[i];
        g.d[1] = table.threshold[i];
        g.d[2] = bits(table.alias[i]);
        out.push(g);
    }
    Ok((out, background))
}

/// Per-render constants from the scene's camera and the frame settings.
pub fn gpu_params(scene: &Scene, frame: &FrameSettings, background: u32) -> GpuParams {
    let cam = &scene.camera;
    let forward = cam.forward.normalize();
    let right = forward.cross(cam.up).normalize();
    let up = right.cross(forward);
    // Pixels have unit area: the image plane is H / (2 tan(yfov/2)) pixels away.
    let plane = frame.height as f32 / (2.0 * (0.5 * cam.yfov).tan());
    let (center, radius) = scene.bounding_sphere();
    GpuParams {
        cam_pos: v4(cam.position, plane),
        cam_forward: v4(forward, 0.0),
        cam_right: v4(right, 0.0),
        cam_up: v4(up, 0.0),
        scene_sphere: v4(center, radius),
        dims: [frame.width, frame.height, scene.lights.len() as u32, frame.max_path_length],
        misc: [frame.seed, frame.min_path_length, background, 0],
    }
}

/// The triangles as the kernels read them, with their per-vertex arrays.
struct GpuGeometry {
    triangles: Vec<GpuTriangle>,
    normals: Vec<[f32; 4]>,
    attributes: Vec<GpuVertexAttributes>,
}

/// The triangles with their materials and lights. The per-vertex arrays share one index
/// per triangle: entries for the normals the kernels read (zero where a triangle has
/// none: flat) and for the attributes (none: NaN texture coordinates, white).
fn gpu_triangles(scene: &Scene, features: &FeatureSet) -> GpuGeometry {
    let mut light_of_triangle = vec![NO_LIGHT; scene.triangles.len()];
    for (i, l) in scene.lights.iter().enumerate() {
        if let Light::Area { triangle, .. } = l {
            light_of_triangle[*triangle as usize] = i as u32;
        }
    }
    let mut normals: Vec<[f32; 4]> = Vec::new();
    let mut attributes: Vec<GpuVertexAttributes> = Vec::new();
    let triangles: Vec<GpuTriangle> = scene
        .triangles
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let n = t.n.as_ref().filter(|_| features.shading_normals);
            let a = t.attributes.as_deref().filter(|_| features.vertex_attributes);
            let first = if n.is_some() || a.is_some() {
                let first = (normals.len().max(attributes.len())) as u32;
                if features.shading_normals {
                    normals.extend((0..3).map(|k| n.map_or([0.0; 4], |n| v4(n[k], 0.0))));
                }
                if features.vertex_attributes {
                    attributes.extend((0..3).map(|k| vertex_attributes(a, k)));
                }
                first
            } else {
                u32::MAX
            };
            GpuTriangle { material: t.material, light: light_of_triangle[i], first_vertex: first, _pad: 0 }
        })
        .collect();
    GpuGeometry { triangles, normals, attributes }
}

/// The materials as the kernels read them, with the texture indices of each
/// (`texture_indices`, [`gpu_textures`]) where `features` has the textures' kind.
fn gpu_materials(scene: &Scene, features: &FeatureSet, texture_indices: &[[u32; 17]]) -> Vec<GpuMaterial> {
    scene
        .materials
        .iter()
        .zip(texture_indices)
        .map(
            |(
                m,
                &[texture, normal_map, emissive, metallic_roughness, coat, coat_roughness, t, s, sc, sh, shr, ir, irt, an, dtt, dtc, cn],
            )| {
                let normal_map = if features.normal_maps { normal_map } else { NO_TEXTURE };
                let emissive = if features.emissive_textures { emissive } else { NO_TEXTURE };
                let (metallic_roughness, mut base_metallic, mut f0_roughness) =
                    match (&m.metallic_roughness_texture, features.metallic_roughness_textures) {
                        (Some(t), true) => {
                            (metallic_roughness, v4(t.base, t.metallic), v4(t.dielectric_f0, t.roughness))
                        }
                        _ => (NO_TEXTURE, [0.0; 4], [0.0; 4]),
                    };
                let (layers, specular) = match m.layer_textures.as_deref() {
                    Some(l) if features.transmission_textures || features.specular_textures => {
                        // The same factors as a metallic-roughness texture's, where it has one.
                        base_metallic = v4(l.base, l.metallic);
                        f0_roughness = v4(l.dielectric_f0, l.roughness);
                        let on = |i: u32, f: bool| bits(if f { i } else { NO_TEXTURE });
                        let (ft, fs) = (features.transmission_textures, features.specular_textures);
                        ([on(t, ft), on(s, fs), on(sc, fs), 0.0], v4(l.specular_f0, l.specular_factor))
                    }
                    _ => ([bits(NO_TEXTURE), bits(NO_TEXTURE), bits(NO_TEXTURE), 0.0], [0.0; 4]),
                };
                // glsl/types.glsl, GpuMaterial.surface.z.
                let cutoff = match m.alpha_mode {
                    AlphaMode::Mask { cutoff } if features.alpha_mask => cutoff,
                    AlphaMode::Blend if features.alpha_mask => ALPHA_BLEND,
                    _ => ALPHA_OPAQUE,
                };
                // A dielectric's lobes beside its glass have weight lobes_weight (glsl/bsdf.glsl);
                // of weight 0 (clear glass) they are uploaded black, so that kernels without
                // HAS_PARTIAL_TRANSMISSION, which apply no weight, give them none too.
                let lobe = |c: Vec3| if m.lobes_weight() > 0.0 { c } else { Vec3::ZERO };
                GpuMaterial {
                    diffuse: v4(lobe(m.diffuse), m.phong_exponent),
                    phong: v4(lobe(m.phong), m.ior),
                    mirror: v4(m.mirror, m.diffuse_fresnel_f0),
                    emission: v4(m.emission, m.dielectric_alpha()),
                    glossy: v4(lobe(m.glossy), (m.roughness * m.roughness).max(MIN_GGX_ALPHA)),
                    surface: [bits(texture), m.alpha, cutoff, m.glossy_untinted],
                    maps: [bits(normal_map), m.normal_scale, bits(emissive), bits(metallic_roughness)],
                    base_metallic,
                    f0_roughness,
                    medium: v4(
                        m.medium_attenuation(),
                        f32::from_bits(if m.one_sided { MATERIAL_ONE_SIDED } else { 0 }),
                    ),
                    transmission: v4(m.transmission, 1.0 - m.lobes_weight()),
                    coat: gpu_coat(m, features, [coat, coat_roughness]),
                    layers,
                    specular,
                    sheen: gpu_sheen(m, features),
                    sheen_maps: gpu_sheen_maps(m, features, [sh, shr]),
                    iridescence: gpu_iridescence(m, features),
                    iridescence_maps: gpu_iridescence_maps(m, features, [ir, irt]),
                    anisotropy: gpu_anisotropy(m, features, an),
                    diffuse_transmission: gpu_diffuse_transmission(m, features),
                    diffuse_transmission_maps: gpu_diffuse_transmission_maps(m, features, [dtt, dtc]),
                    coat_normal: gpu_coat_normal(m, features, cn),
                    dispersion: gpu_dispersion(m, features),
                }
            },
        )
        .collect()
}

/// GpuMaterial.coat of `m` (glsl/types.glsl) with the indices of its two textures:
/// zero where the kernels have no clear coat.
fn gpu_coat(m: &crate::scene::Material, features: &FeatureSet, textures: [u32; 2]) -> [f32; 4] {
    if !features.clearcoat || m.clearcoat <= 0.0 {
        return [0.0, 0.0, bits(NO_TEXTURE), bits(NO_TEXTURE)];
    }
    let t = |i: u32| bits(if features.clearcoat_textures { i } else { NO_TEXTURE });
    let r = m.clearcoat_roughness.clamp(0.0, 1.0);
    [m.clearcoat.min(1.0), (r * r).max(MIN_GGX_ALPHA), t(textures[0]), t(textures[1])]
}

/// GpuMaterial.coat_normal of `m` with the index of its clearcoatNormalTexture: none
/// where the kernels have no clear-coat normal maps or `m` no coat.
fn gpu_coat_normal(m: &crate::scene::Material, features: &FeatureSet, texture: u32) -> [f32; 4] {
    let on = features.clearcoat_normal_maps && m.clearcoat > 0.0;
    [bits(if on { texture } else { NO_TEXTURE }), m.clearcoat_normal_scale, 0.0, 0.0]
}

/// GpuMaterial.dispersion of `m` (glsl/types.glsl): no dispersion where the kernels have
/// none.
fn gpu_dispersion(m: &crate::scene::Material, features: &FeatureSet) -> [f32; 4] {
    if !features.dispersion || !m.has_dispersion() {
        return [m.ior, m.ior, m.ior, 0.0];
    }
    v4(m.dispersion_iors(), m.dispersion)
}

/// GpuMaterial.sheen of `m` (glsl/types.glsl): zero where the kernels have no sheen.
fn gpu_sheen(m: &crate::scene::Material, features: &FeatureSet) -> [f32; 4] {
    if !features.sheen || !m.has_sheen() {
        return [0.0; 4];
    }
    v4(m.sheen_color.clamp(Vec3::ZERO, Vec3::ONE), m.sheen_roughness.clamp(MIN_SHEEN_ROUGHNESS, 1.0))
}

/// GpuMaterial.sheen_maps of `m` with the indices of its two textures: none where the
/// kernels have no sheen textures.
fn gpu_sheen_maps(m: &crate::scene::Material, features: &FeatureSet, textures: [u32; 2]) -> [f32; 4] {
    let t = |i: u32| bits(if features.sheen_textures && m.has_sheen() { i } else { NO_TEXTURE });
    [t(textures[0]), t(textures[1]), 0.0, 0.0]
}

/// GpuMaterial.iridescence of `m` (glsl/types.glsl): zero where the kernels have none.
fn gpu_iridescence(m: &crate::scene::Material, features: &FeatureSet) -> [f32; 4] {
    if !features.iridescence || !m.has_iridescence() {
        return [0.0, 1.0, 0.0, 0.0];
    }
    [m.iridescence.min(1.0), m.iridescence_ior, m.iridescence_thickness_min, m.iridescence_thickness_max]
}

/// GpuMaterial.iridescence_maps of `m` with the indices of its two textures: none where
/// the kernels have no iridescence textures.
fn gpu_iridescence_maps(m: &crate::scene::Material, features: &FeatureSet, textures: [u32; 2]) -> [f32; 4] {
    let t = |i: u32| bits(if features.iridescence_textures && m.has_iridescence() { i } else { NO_TEXTURE });
    [t(textures[0]), t(textures[1]), 0.0, 0.0]
}

/// GpuMaterial.anisotropy of `m` (glsl/types.glsl) with the index of its texture:
/// isotropic where the kernels have no anisotropy.
fn gpu_anisotropy(m: &crate::scene::Material, features: &FeatureSet, texture: u32) -> [f32; 4] {
    if !features.anisotropy || !m.has_anisotropy() {
        return [1.0, 0.0, 0.0, bits(NO_TEXTURE)];
    }
    let (s, c) = m.anisotropy_rotation.sin_cos();
    let t = if features.textures { texture } else { NO_TEXTURE };
    [c, s, m.anisotropy_strength.min(1.0), bits(t)]
}

/// GpuMaterial.diffuse_transmission of `m` (glsl/types.glsl): zero where the kernels have
/// no diffuse transmission.
fn gpu_diffuse_transmission(m: &crate::scene::Material, features: &FeatureSet) -> [f32; 4] {
    match m.diffuse_transmission.as_deref() {
        Some(d) if features.diffuse_transmission && m.has_diffuse_transmission() => {
            v4(d.color.clamp(Vec3::ZERO, Vec3::ONE), d.factor.clamp(0.0, 1.0))
        }
        _ => [0.0; 4],
    }
}

/// GpuMaterial.diffuse_transmission_maps of `m` with the indices of its two textures
/// (none where the kernels have no diffuse-transmission textures) and its metallic factor.
fn gpu_diffuse_transmission_maps(m: &crate::scene::Material, features: &FeatureSet, textures: [u32; 2]) -> [f32; 4] {
    let on = features.diffuse_transmission_textures && m.has_diffuse_transmission();
    let t = |i: u32| bits(if on { i } else { NO_TEXTURE });
    let metallic = m.diffuse_transmission.as_deref().map_or(0.0, |d| d.metallic.clamp(0.0, 1.0));
    [t(textures[0]), t(textures[1]), metallic, 0.0]
}

/// Uploads the [`CHUNKED`] arrays: whole, each one buffer added to `buffers`, or with
/// `chunk_bytes` in chunks of that many bytes (a power of two, so the kernels find element
/// i's chunk by a shift), each chunk its own buffer (returned). Then adds `scene_chunks`,
/// the chunks' addresses (a placeholder entry when there are none). Also returns each
/// array's first entry in that table.
fn upload_chunked(
    gpu: &Arc<Gpu>,
    chunked: [(&'static str, &[u8]); 5],
    chunk_bytes: Option<u64>,
    buffers: &mut Vec<Buffer>,
) -> Result<(Vec<Buffer>, [u32; 8])> {
    let mut chunks = Vec::new();
    let mut chunk_table: Vec<[u32; 2]> = Vec::new();
    let mut chunk_first = [0u32; 8];
    match chunk_bytes {
        None => {
            for (name, bytes) in chunked {
                buffers.push(gpu.buffer_from_slice(name, bytes)?);
            }
        }
        Some(size) => {
            for (k, (name, bytes)) in chunked.into_iter().enumerate() {
                chunk_first[k] = chunk_table.len() as u32;
                for piece in bytes.chunks(size as usize) {
                    let b = gpu.buffer_from_slice(name, piece)?;
                    let a = b.device_address()?;
                    chunk_table.push([a as u32, (a >> 32) as u32]);
                    chunks.push(b);
                }
            }
        }
    }
    if chunk_table.is_empty() {
        chunk_table.push([0, 0]);
    }
    buffers.push(gpu.buffer_from_slice("scene_chunks", &chunk_table)?);
    Ok((chunks, chunk_first))
}

/// The addresses of the [`ADDRESSED`] buffers among `buffers` (all zero without device
/// addresses; zero for the vertex attributes when they are read in chunks: no buffer of
/// that name then).
fn scene_addresses(gpu: &Gpu, buffers: &[Buffer], chunk_first: [u32; 8]) -> Result<GpuSceneAddresses> {
    if !gpu.has(BUFFER_DEVICE_ADDRESS) {
        return Ok(GpuSceneAddresses { chunk_first, ..Default::default() });
    }
    let address = |name: &str| -> Result<[u32; 2]> {
        let Some(b) = buffers.iter().find(|b| b.name() == name) else { return Ok([0, 0]) };
        let a = b.device_address()?;
        Ok([a as u32, (a >> 32) as u32])
    };
    Ok(GpuSceneAddresses {
        vertex_attributes: address(ADDRESSED[0])?,
        texture_texels: address(ADDRESSED[1])?,
        env_texels: address(ADDRESSED[2])?,
        env_distribution: address(ADDRESSED[3])?,
        chunk_first,
    })
}

impl SceneGpu {
    /// The scene with kernels specialised to it, read as `reads`.
    pub fn new(gpu: &Arc<Gpu>, scene: &Scene, frame: &FrameSettings, reads: Reads) -> Result<SceneGpu> {
        let atomics = SplatAtomics::resolve(gpu, None)?;
        Self::with_features(gpu, scene, frame, &FeatureSet::new(scene, false), reads, atomics, None)
    }

    /// The scene for kernels compiled with `features`, reading it as `reads` and summing
    /// splats with `atomics`: shading normals are uploaded when the scene has them and
    /// the kernels read them (a 16-byte placeholder is bound otherwise); the BVH is read with 64-bit loads when
    /// the device has `shaderInt64`. With `chunk_bytes` ([`ScenePlan::chunk_bytes`]) the
    /// kernels read [`CHUNKED`] in chunks of that many bytes.
    pub fn with_features(
        gpu: &Arc<Gpu>,
        scene: &Scene,
        frame: &FrameSettings,
        features: &FeatureSet,
        reads: Reads,
        atomics: SplatAtomics,
        chunk_bytes: Option<u64>,
    ) -> Result<SceneGpu> {
        if scene.lights.is_empty() {
            bail!("scene {:?} has no light source (no emissive material, punctual light or background)", scene.name);
        }
        if scene.triangles.is_empty() && scene.spheres.is_empty() {
            bail!("scene {:?} has no geometry", scene.name);
        }
        let tree = bvh::build_scene(scene, &bvh::BuildOptions::default());
        let gb = tree.into_gpu();
        // The layout needs the instance traversal exactly when the scene has instances
        // (compiled in for an instance-free layout is fine: that is the generic variant).
        if gb.num_instances > 0 && !features.instances {
            bail!("internal error: the kernels of scene {:?} are compiled without instances", scene.name);
        }
        let (lights, background) = gpu_lights(scene, frame.light_selection)?;
        let params = gpu_params(scene, frame, background);
        let geometry = gpu_triangles(scene, features);
        let spheres: Vec<GpuSphere> = scene
            .spheres
            .iter()
            .map(|s| GpuSphere { center_radius: v4(s.center, s.radius), info: [s.material, NO_LIGHT, 0, 0] })
            .collect();
        let (texture_refs, texture_indices, texels) = if features.textures {
            gpu_textures(scene)?
        } else {
            (Vec::new(), vec![[NO_TEXTURE; 17]; scene.materials.len()], Vec::new())
        };
        let materials = gpu_materials(scene, features, &texture_indices);
        let env = match environment_map(scene) {
            Some(m) if features.environment_map => EnvironmentTables::new(m),
            _ => EnvironmentTables { texels: Vec::new(), distribution: Vec::new() },
        };
        let chunked: [(&'static str, &[u8]); 5] = [
            (CHUNKED[0], bytemuck::cast_slice(&gb.nodes)),
            (CHUNKED[1], bytemuck::cast_slice(&gb.prims)),
            (CHUNKED[2], bytemuck::cast_slice(&geometry.triangles)),
            (CHUNKED[3], bytemuck::cast_slice(&geometry.normals)),
            (CHUNKED[4], bytemuck::cast_slice(&geometry.attributes)),
        ];
        let mut buffers = vec![gpu.buffer_from_slice("scene_params", &[params])?];
        let (chunks, chunk_first) = upload_chunked(gpu, chunked, chunk_bytes, &mut buffers)?;
        buffers.extend([
            gpu.buffer_from_slice("spheres", &spheres)?,
            gpu.buffer_from_slice("materials", &materials)?,
            gpu.buffer_from_slice("lights", &lights)?,
            gpu.buffer_from_slice("texture_refs", &texture_refs)?,
            gpu.buffer_from_slice("texture_texels", &texels)?,
            gpu.buffer_from_slice("env_texels", &env.texels)?,
            gpu.buffer_from_slice("env_distribution", &env.distribution)?,
            gpu.fixed_table("ggx_albedo_table", &albedo_tables::ggx_cells())?,
            gpu.fixed_table("sheen_albedo_table", &albedo_tables::sheen_cells())?,
        ]);
        // --light-selection tree on a scene with area lights: LIGHT_TREE kernels.
        let light_tree = match frame.light_selection {
            LightSelection::Tree => LightTree::new(scene),
            _ => None,
        };
        if let Some(t) = &light_tree {
            buffers.push(gpu.buffer_from_slice("light_tree", &t.gpu_elements())?);
        }
        let addresses = scene_addresses(gpu, &buffers, chunk_first)?;
        buffers.push(gpu.buffer_from_slice("scene_addresses", &[addresses])?);
        let variant = SceneVariant {
            features: features.clone(),
            reads,
            int64_loads: gpu.has(SHADER_INT64),
            atomics,
            device_addresses: gpu.has(BUFFER_DEVICE_ADDRESS),
            chunk_shift: chunk_bytes.map(|b| (b / 16).trailing_zeros()),
            light_tree: light_tree.is_some(),
        };
        Ok(SceneGpu { params, buffers, chunks, variant })
    }

    /// The scene's bindings, each buffer at the binding of its name (all are arrays of
    /// 16-byte elements, read as `uvec4` texels where the kernel declares texel buffers).
    pub fn binds(&self) -> Vec<Bind<'_>> {
        self.buffers.iter().map(Bind::own).collect()
    }

    /// How the kernels read the scene.
    pub fn reads(&self) -> Reads {
        self.variant.reads
    }
}
