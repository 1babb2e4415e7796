//! Scene and frame data as the kernels read it. Each struct here is mirrored, field for
//! field, in glsl/types.glsl; `tests/layout.rs` checks the byte offsets of both sides
//! against each other through the SPIR-V the GLSL compiles to.

use bytemuck::{Pod, Zeroable};

/// Light kinds (`GpuLight::kind`).
pub const LIGHT_AREA: u32 = 0;
pub const LIGHT_POINT: u32 = 1;
pub const LIGHT_SPOT: u32 = 2;
pub const LIGHT_DIRECTIONAL: u32 = 3;
pub const LIGHT_BACKGROUND: u32 = 4;

/// No light attached to a primitive.
pub const NO_LIGHT: u32 = u32::MAX;

/// No texture (`GpuMaterial::surface` x).
pub const NO_TEXTURE: u32 = u32::MAX;

/// `GpuTextureRef::image` w: wrap mode of s in bits 0-1 and of t in bits 2-3 (0 repeat,
/// 1 clamp to edge, 2 mirrored repeat), bit 4 nearest filtering, bit 5 TEXCOORD_1.
pub const TEXTURE_NEAREST: u32 = 1 << 4;
pub const TEXTURE_UV1: u32 = 1 << 5;
/// `GpuTextureRef::image` w bit 6: the texels are linear (a normal map), not sRGB.
pub const TEXTURE_LINEAR: u32 = 1 << 6;
/// `GpuMaterial::surface[2]` of a material whose alpha is ignored.
pub const ALPHA_OPAQUE: f32 = -1.0;
/// `GpuMaterial::surface[2]` of an alphaMode BLEND material (stochastic transparency).
pub const ALPHA_BLEND: f32 = -2.0;
/// `GpuMaterial::medium[3]` bit: the surface is one-sided (`Material::one_sided`).
pub const MATERIAL_ONE_SIDED: u32 = 1;

/// A material (see `scene::Material`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuMaterial {
    /// rgb: Lambertian reflectance; w: Phong exponent.
    pub diffuse: [f32; 4],
    /// rgb: Phong reflectance; w: index of refraction (< 0: not a dielectric).
    pub phong: [f32; 4],
    /// rgb: specular (mirror) reflectance; w: the diffuse lobe's Fresnel F0
    /// (`Material::diffuse_fresnel_f0`).
    pub mirror: [f32; 4],
    /// rgb: emitted radiance; w: a dielectric's GGX alpha (`Material::dielectric_roughness`
    /// squared, at least `MIN_GGX_ALPHA`): > 0 is the rough dielectric of glsl/bsdf.glsl,
    /// 0 smooth glass (and every other material).
    pub emission: [f32; 4],
    /// rgb: GGX microfacet lobe colour (Schlick's F0); w: GGX alpha = roughness^2, at
    /// least `MIN_GGX_ALPHA`.
    pub glossy: [f32; 4],
    /// x: index of its base-colour texture in `texture_refs`, or `NO_TEXTURE` (bits);
    /// y: alpha factor; z: alpha cutoff of a cut-out (alphaMode MASK, >= 0), or
    /// `ALPHA_OPAQUE`, or `ALPHA_BLEND` (stochastic transparency);
    /// w: the part of the GGX F0 that the base colour does not tint
    /// (`Material::glossy_untinted`).
    pub surface: [f32; 4],
    /// x: index of its normal map in `texture_refs`, or `NO_TEXTURE` (bits); y: the normal
    /// map's scale; z: index of its emissive texture, or `NO_TEXTURE` (bits); w: index of
    /// its metallic-roughness texture, or `NO_TEXTURE` (bits).
    pub maps: [f32; 4],
    /// With a metallic-roughness texture (`scene::MetallicRoughnessTexture`), what the
    /// kernels recompute the lobes from per point (glsl/bsdf.glsl, `point_material`):
    /// rgb: base colour factor; w: metallic factor. Zero without one.
    pub base_metallic: [f32; 4],
    /// rgb: the dielectric's F0; w: roughness factor. Zero without one.
    pub f0_roughness: [f32; 4],
    /// rgb: the attenuation coefficient inside a transmissive volume
    /// (`Material::attenuation`, per unit length; zero: none); w: flag bits
    /// (`MATERIAL_ONE_SIDED`), as an f32 bit pattern.
    pub medium: [f32; 4],
    /// rgb: the colour that multiplies a dielectric's transmitted part
    /// (`Material::transmission`; 1: clear); w: a dielectric's glass weight
    /// (1 - `Material::lobes_weight`: the glass weight clamped to [0, 1]; 0 on opaque
    /// materials, where it is unused).
    pub transmission: [f32; 4],
    /// The clear coat (`Material::clearcoat`, glsl/lobes/clearcoat.glsl): x: clearcoat
    /// factor (0: none, also where the kernels lack HAS_CLEARCOAT); y: the coat's GGX alpha;
    /// z, w: indices of its clearcoat and clearcoat-roughness textures, or `NO_TEXTURE`
    /// (bits).
    pub coat: [f32; 4],
    /// Indices in `texture_refs` (bits, or `NO_TEXTURE`) of x: its transmissionTexture,
    /// y: specularTexture, z: specularColorTexture (`scene::LayerTextures`); w: reserved.
    pub layers: [f32; 4],
    /// With such textures (glsl/bsdf.glsl, `point_material`): rgb: the F0 of the IOR
    /// times specularColorFactor (not clamped); w: specularFactor. Zero without them.
    pub specular: [f32; 4],
    /// The sheen (`Material::sheen_color`, glsl/lobes/sheen.glsl): rgb: sheenColorFactor
    /// (0: none, also where the kernels lack HAS_SHEEN); w: sheenRoughnessFactor, at
    /// least MIN_SHEEN_ROUGHNESS.
    pub sheen: [f32; 4],
    /// Indices in `texture_refs` (bits, or `NO_TEXTURE`) of x: its sheenColorTexture,
    /// y: sheenRoughnessTexture; z, w: reserved.
    pub sheen_maps: [f32; 4],
    /// The thin film (`Material::iridescence`, glsl/lobes/iridescence.glsl): x:
    /// iridescenceFactor (0: none, also where the kernels lack HAS_IRIDESCENCE); y: the
    /// film's IOR; z, w: its thickness minimum and maximum in nm.
    pub iridescence: [f32; 4],
    /// Indices in `texture_refs` (bits, or `NO_TEXTURE`) of x: its iridescenceTexture,
    /// y: iridescenceThicknessTexture; z, w: reserved.
    pub iridescence_maps: [f32; 4],
    /// The GGX lobe's anisotropy (KHR_materials_anisotropy, glsl/lobes/anisotropy.glsl):
    /// x, y: cos and sin of anisotropyRotation; z: anisotropyStrength (0: isotropic, also
    /// where the kernels lack HAS_ANISOTROPY); w: anisotropyTexture or NO_TEXTURE (bits).
    pub anisotropy: [f32; 4],
    /// The diffuse transmission (`Material::diffuse_transmission`,
    /// glsl/lobes/diffuse_transmission.glsl): rgb: diffuseTransmissionColorFactor, w:
    /// diffuseTransmissionFactor (0: none, also where the kernels lack
    /// HAS_DIFFUSE_TRANSMISSION).
    pub diffuse_transmission: [f32; 4],
    /// Indices in `texture_refs` (bits, or `NO_TEXTURE`) of x: diffuseTransmissionTexture,
    /// y: diffuseTransmissionColorTexture; z: the material's metallic factor (its metal
    /// part transmits nothing); w: reserved.
    pub diffuse_transmission_maps: [f32; 4],
    /// The clear coat's normal map (glsl/lobes/clearcoat.glsl): x: its index in
    /// `texture_refs` (bits, or `NO_TEXTURE`: the coat shades with the base's normal), y:
    /// its scale; z, w: reserved.
    pub coat_normal: [f32; 4],
    /// The glass's dispersion (KHR_materials_dispersion, glsl/lobes/dispersion.glsl): x, y,
    /// z: its IORs for R, G and B (`Material::dispersion_iors`); w: the dispersion (0:
    /// none, also where the kernels lack HAS_DISPERSION).
    pub dispersion: [f32; 4],
}

/// A texture as a material uses it (`scene::TextureRef`): where its image's texels are,
/// how it is sampled and the transform of its texture coordinates.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuTextureRef {
    /// x: first texel in `texture_texels`; y: width; z: height; w: flags (`TEXTURE_*`, wrap
    /// modes).
    pub image: [u32; 4],
    /// uv' = (dot(row0.xyz, (u, v, 1)), dot(row1.xyz, (u, v, 1))); w unused.
    pub row0: [f32; 4],
    pub row1: [f32; 4],
}

/// Attributes of one triangle vertex (`scene::VertexAttributes`): texture coordinates
/// (NaN where the triangle has none) and colour (1 where it has none).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuVertexAttributes {
    /// xy: TEXCOORD_0; zw: TEXCOORD_1.
    pub uv: [f32; 4],
    /// COLOR_0, linear RGBA.
    pub color: [f32; 4],
    /// Tangent (xyz) and bitangent sign (w) for normal maps; NaN where there is none.
    pub tangent: [f32; 4],
}

/// Smallest GGX alpha the kernels see (a smaller one makes D(h) overflow-prone and the
/// lobe a mirror in all but name); glsl/types.glsl has the same.
pub const MIN_GGX_ALPHA: f32 = 1e-3;

/// Smallest sheen roughness the kernels see (glsl/lobes/sheen.glsl: below it the Charlie
/// lobe's exponent 1 / roughness^2 exceeds 200; its albedo table starts there);
/// glsl/types.glsl has the same.
pub const MIN_SHEEN_ROUGHNESS: f32 = 0.07;

/// What shading needs of a triangle beyond its vertices, in original scene order (the
/// vertices are read from the BVH's primitive of the hit, glsl/scene.glsl `surface_at`,
/// so they are stored once).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuTriangle {
    pub material: u32,
    /// Light index, or `NO_LIGHT`.
    pub light: u32,
    /// Index of its first vertex in the per-vertex arrays (`shading_normals`,
    /// `vertex_attributes`), or `u32::MAX` when it has neither.
    pub first_vertex: u32,
    pub _pad: u32,
}

/// An analytic sphere in original scene order.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuSphere {
    /// xyz: centre; w: radius.
    pub center_radius: [f32; 4],
    /// x: material index (bits); y: light index (bits, always `NO_LIGHT`).
    pub info: [u32; 4],
}

/// A light (see `scene::Light`). Fields by kind:
/// area: `a` = p0 (w: triangle index bits), `b` = edge p1-p0, `c` = edge p2-p0,
/// `d.w` = area; point: `a` = position; spot: `a` = position, `b` = direction (w: cos
/// inner), `c.w` = cos outer; directional: `b` = propagation direction; background:
/// nothing; environment map: `a.xy` = size (bits), `b.xy` = cos, sin of the rotation.
/// Every kind: `d.x` = the probability of picking it, `d.y` and `d.z` (bits) its slot's
/// threshold and alias in the selection table (src/render/light_selection.rs).
/// `radiance`: rgb radiance (area, background), intensity (point, spot) or
/// irradiance (directional); w: kind (bits).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuLight {
    pub a: [f32; 4],
    pub b: [f32; 4],
    pub c: [f32; 4],
    pub d: [f32; 4],
    pub radiance: [f32; 4],
}

/// Per-render constants (one small buffer, written once per render).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuParams {
    /// xyz: camera position; w: distance of the image plane in pixels.
    pub cam_pos: [f32; 4],
    /// xyz: unit forward; w: unused.
    pub cam_forward: [f32; 4],
    /// xyz: unit right; w: unused.
    pub cam_right: [f32; 4],
    /// xyz: unit up; w: unused.
    pub cam_up: [f32; 4],
    /// xyz: scene bounding-sphere centre; w: radius.
    pub scene_sphere: [f32; 4],
    /// width, height, number of lights, max path length (segments).
    pub dims: [u32; 4],
    /// base seed, min path length, index of the background light or `NO_LIGHT`, flags.
    pub misc: [u32; 4],
}

/// The device addresses of the frame's large buffers (src/render/addresses.rs), each as
/// (low, high) 32-bit words; 0 for a buffer the render does not have.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct GpuAddresses {
    /// The film's sums (src/render/film.rs).
    pub film: [u32; 2],
    /// The splat sums (src/render/passes/light_subpaths.rs).
    pub splat: [u32; 2],
    /// The light-vertex store's two halves (src/render/passes/light_subpaths.rs).
    pub light_vertices_a: [u32; 2],
    pub light_vertices_b: [u32; 2],
    /// The hash grid's per-vertex keys and its entries (src/render/passes/hash_grid.rs).
    pub grid_keys: [u32; 2],
    pub grid_points: [u32; 2],
    /// Where each light subpath's vertices start in the store, and the light kernel's
    /// scratch slots (src/render/passes/light_subpaths.rs).
    pub light_vertex_offsets: [u32; 2],
    pub light_scratch_a: [u32; 2],
    pub light_scratch_b: [u32; 2],
}

/// Device addresses of the scene's buffers that can outgrow one binding (glsl/types.glsl;
/// src/render/scene_gpu.rs): (low, high) 32-bit words.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct GpuSceneAddresses {
    pub vertex_attributes: [u32; 2],
    pub texture_texels: [u32; 2],
    pub env_texels: [u32; 2],
    pub env_distribution: [u32; 2],
    /// Where in `scene_chunks` the chunks of the BVH nodes, BVH primitives, triangles,
    /// shading normals and vertex attributes start (then 3 unused), when the scene reads
    /// them in chunks (SCENE_CHUNKS; src/render/scene_gpu.rs, CHUNKED).
    pub chunk_first: [u32; 8],
}

/// Per-dispatch push constants.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuPush {
    /// 0-based iteration index (selects random numbers and the merge radius).
    pub iteration: u32,
    /// Paths (pixels, light subpaths) in this dispatch.
    pub count: u32,
    /// MIS weight factor of merging, eta = pi r^2 N_L (0 when the estimator does not merge).
    pub mis_vm: f32,
    /// MIS weight factor of connections, 1 / eta (0 when the estimator does not connect).
    pub mis_vc: f32,
    /// Merge radius of this iteration.
    pub radius: f32,
    /// Light subpaths per iteration (N_L).
    pub light_paths: u32,
    /// Buckets of the light-vertex hash grid (estimators that merge; else 0).
    pub grid_buckets: u32,
    /// Paths per invocation (path regeneration, src/render/regen.rs); 0 means 1.
    pub paths_per_invocation: u32,
    /// The light-subpaths pass: the index of the dispatch's first light subpath (an
    /// iteration's light subpaths are traced in chunks).
    pub first_path: u32,
}

impl GpuPush {
    /// Push constants of an estimator without merging or light subpaths.
    pub fn simple(iteration: u32, count: u32) -> GpuPush {
        GpuPush { iteration, count, ..Default::default() }
    }
}
