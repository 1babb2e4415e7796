//! Scene description shared by the importer, the BVH builder and the renderers.
//!
//! Units and conventions: right-handed, y-up (glTF). Radiometric quantities are linear
//! RGB. Every light's meaning is stated on its variant.

use glam::{Affine3A, Vec2, Vec3, Vec4};

pub use environment::{EnvironmentLight, EnvironmentMap};

/// A triangle in world space.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Triangle {
    pub p: [Vec3; 3],
    /// Per-vertex shading normals (world space, unit length) when the source gives them.
    pub n: Option<[Vec3; 3]>,
    pub material: u32,
    /// Texture coordinates and colours of its vertices, when the source gives any (boxed:
    /// most triangles of most scenes have none, and a scene holds millions of triangles).
    pub attributes: Option<Box<VertexAttributes>>,
}

/// Per-vertex attributes of a triangle beyond position and normal.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct VertexAttributes {
    /// TEXCOORD_0 and TEXCOORD_1 (glTF: (0, 0) is the image's top-left corner, u to the
    /// right, v down).
    pub uv: [Option<[Vec2; 3]>; 2],
    /// COLOR_0, linear RGBA (it multiplies the base colour).
    pub color: Option<[Vec4; 3]>,
    /// Tangents for normal maps, world space: xyz the unit tangent (the direction of
    /// increasing u of the normal map's texture coordinates), w = ±1 the bitangent's sign
    /// (bitangent = w cross(normal, tangent), glTF's TANGENT).
    pub tangent: Option<[Vec4; 3]>,
}

/// A decoded texture image: RGBA8 texels, row by row from the top-left corner. The RGB
/// of a base-colour texture is sRGB-encoded (decoded per texel by the kernels), alpha is
/// linear.
#[derive(Clone, PartialEq)]
pub struct TextureImage {
    pub name: String,
    pub width: u32,
    pub height: u32,
    pub texels: Vec<[u8; 4]>,
}

impl std::fmt::Debug for TextureImage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "TextureImage({:?}, {}x{})", self.name, self.width, self.height)
    }
}

/// How texture coordinates outside [0, 1] map into the image (glTF sampler wrap modes).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Wrap {
    #[default]
    Repeat,
    ClampToEdge,
    MirroredRepeat,
}

/// Texel filtering: the nearest texel, or bilinear between the four nearest (no mip-maps:
/// a path tracer's pixel samples average the texture over the pixel's footprint).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Filter {
    Nearest,
    #[default]
    Linear,
}

/// A texture as a material uses it: an image, its sampler, which texture coordinates
/// and their KHR_texture_transform.
#[derive(Clone, Debug, PartialEq)]
pub struct TextureRef {
    /// Index into `Scene::images`.
    pub image: u32,
    pub wrap_s: Wrap,
    pub wrap_t: Wrap,
    pub filter: Filter,
    /// 0: TEXCOORD_0, 1: TEXCOORD_1.
    pub tex_coord: u32,
    /// uv' = (row 0 . (u, v, 1), row 1 . (u, v, 1)) (KHR_texture_transform's matrix;
    /// identity without it).
    pub transform: [[f32; 3]; 2],
}

impl TextureRef {
    pub const IDENTITY: [[f32; 3]; 2] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
}

/// glTF's alpha modes: how a material's alpha (base colour factor x texture x vertex
/// colour) makes it transparent.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum AlphaMode {
    /// Alpha is ignored.
    #[default]
    Opaque,
    /// A cut-out: where alpha < cutoff the surface is not there, for every ray.
    Mask { cutoff: f32 },
    /// Stochastic transparency: each ray meets the surface with probability alpha and
    /// passes straight through it otherwise (glsl/textures.glsl, `alpha_visible`).
    Blend,
}

/// A mesh stored once and placed in the world by [`Instance`]s (a two-level BVH: instances
/// over per-mesh trees, docs/bvh.md "Instancing"): `Scene::triangles[first..first + count]`,
/// in the mesh's object space. Shared meshes' triangles follow every world-space triangle
/// ([`Scene::world_triangles`]) and are never area lights.
#[derive(Clone, Debug, PartialEq)]
pub struct SharedMesh {
    pub name: String,
    pub first: u32,
    pub count: u32,
}

impl SharedMesh {
    pub fn range(&self) -> std::ops::Range<usize> {
        self.first as usize..(self.first + self.count) as usize
    }

    /// How many of `triangles` triangles are world-space: those before the first shared
    /// mesh of `meshes`.
    pub fn world_triangle_count(meshes: &[SharedMesh], triangles: usize) -> usize {
        meshes.iter().map(|m| m.first as usize).min().unwrap_or(triangles)
    }
}

/// A tangent (xyz the direction, w the bitangent's sign) placed by a transform whose
/// linear part is `lin`: the direction transformed (it lies in the surface, unlike a
/// normal) and normalised, the sign flipped by a mirroring transform so that
/// w cross(normal, tangent) stays the transformed bitangent.
pub fn transform_tangent(lin: glam::Mat3, t: Vec4) -> Vec4 {
    let sign = if lin.determinant() < 0.0 { -1.0 } else { 1.0 };
    (lin * t.truncate()).normalize_or_zero().extend(t.w * sign)
}

/// One placement of a [`SharedMesh`]: its object space mapped to the world by an affine,
/// invertible transform.
#[derive(Clone, Debug, PartialEq)]
pub struct Instance {
    /// Index into `Scene::meshes`.
    pub mesh: u32,
    pub object_to_world: Affine3A,
}

/// An analytic sphere (glTF extension `VKVCM_spheres`).
#[derive(Clone, Debug, PartialEq)]
pub struct Sphere {
    pub center: Vec3,
    pub radius: f32,
    pub material: u32,
}

/// vkvcm's material model: a sum of components, each selected with probability
/// proportional to its luminance albedo (docs/smallvcm.md, the materials of the
/// predefined scenes).
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    /// Lambertian reflectance.
    pub diffuse: Vec3,
    /// Normalised Phong lobe around the mirror direction: rho (n+2)/(2 pi) cos^n.
    pub phong: Vec3,
    pub phong_exponent: f32,
    /// Perfect specular reflectance (Fresnel-weighted when `ior >= 0`).
    pub mirror: Vec3,
    /// Index of refraction of a dielectric; negative means "not a dielectric".
    pub ior: f32,
    /// Perceptual roughness of the dielectric (with `ior >= 0`): 0 is smooth glass (delta
    /// reflection and refraction, `mirror` its reflectance), > 0 the rough dielectric of
    /// glsl/bsdf.glsl, GGX microfacet reflection and transmission of alpha = roughness^2
    /// (at least 1e-3; Walter et al. 2007), which is then the material's only component
    /// (the other lobes are ignored).
    pub dielectric_roughness: f32,
    /// Emitted radiance (W/(m^2 sr)) for area emitters; zero for non-emitters.
    pub emission: Vec3,
    /// GGX microfacet reflection lobe: colour = Schlick's F0 (zero: no lobe). See
    /// glsl/bsdf.glsl.
    pub glossy: Vec3,
    /// Perceptual roughness of the GGX lobe; its alpha is roughness^2 (at least 1e-3).
    pub roughness: f32,
    /// The base-colour texture. Where a triangle has texture coordinates or vertex
    /// colours, its tint (the texel's linear colour, or white without a texture, times the
    /// vertex colour) multiplies `diffuse` and `mirror`, and the GGX lobe's F0 becomes
    /// `glossy_untinted + (glossy - glossy_untinted) x tint`.
    pub base_color_texture: Option<TextureRef>,
    /// The part of `glossy` the base colour does not tint (glTF: 0.04 (1 - metallic),
    /// the dielectric's reflectance).
    pub glossy_untinted: f32,
    /// Opacity factor (glTF's baseColorFactor alpha), times the texel's and the vertex
    /// colour's alpha; used by `alpha_mode`.
    pub alpha: f32,
    pub alpha_mode: AlphaMode,
    /// A tangent-space normal map (glTF normalTexture, linear RGB = (n + 1) / 2) and its
    /// scale of the normal's x and y; it bends the shading normal where a triangle has
    /// texture coordinates and tangents (glsl/textures.glsl).
    pub normal_texture: Option<TextureRef>,
    pub normal_scale: f32,
    /// Schlick F0 of a dielectric interface over the diffuse lobe (glTF metallic/roughness:
    /// 0.04), which then reflects only what the interface transmits: it is weighted by
    /// (1 - F(cos_o)) (1 - F(cos_i)) / (1 - E_avg), glsl/bsdf.glsl. 0: plain Lambert.
    pub diffuse_fresnel_f0: f32,
    /// glTF's emissiveTexture (sRGB): where a triangle has its texture coordinates, the
    /// emitted radiance is `emission` times the texel's linear colour (glsl/textures.glsl,
    /// `emission_tint`), for every way an estimator meets the light.
    pub emissive_texture: Option<TextureRef>,
    /// glTF's metallicRoughnessTexture and the metallic/roughness parameters it modulates
    /// (`Material::metallic_roughness_textured`): where a triangle has its texture
    /// coordinates, `diffuse`, `glossy`, `glossy_untinted` and the GGX width are those of
    /// the point's own metallic and roughness (glsl/bsdf.glsl, `point_material`).
    pub metallic_roughness_texture: Option<MetallicRoughnessTexture>,
    /// A one-sided surface (glTF `doubleSided: false` on a surface that is not a
    /// dielectric): the camera does not see a triangle's back side (against the winding's
    /// normal): camera rays pass through it and light-subpath vertices on it do not reach
    /// the camera (glsl/scene.glsl, `trace_camera_segment`, `visible_to_camera`). Light
    /// meets both sides.
    pub one_sided: bool,
    /// Attenuation coefficient (per unit length, per channel) of the medium inside a
    /// closed dielectric mesh (KHR_materials_volume: -ln(attenuationColor) /
    /// attenuationDistance); zero: clear. Beer-Lambert absorption: a path segment with an
    /// end on the inner side of a surface of this material (the side opposite the
    /// geometric normal, which the winding gives: the side a refracted ray enters),
    /// travelling into the inside from there, is multiplied by exp(-attenuation x length)
    /// (glsl/medium.glsl). Only dielectrics (`ior >= 0`) that do not emit bound a medium;
    /// the kernels see zero for every other material (src/render/scene_gpu.rs).
    pub attenuation: Vec3,
    /// Colour that multiplies the dielectric's transmitted part, smooth and rough, in both
    /// directions (glTF KHR_materials_transmission: the transmission BTDF is tinted by the
    /// base colour; reflection is not). One: clear. The pdfs do not depend on it.
    pub transmission: Vec3,
    /// A dielectric's glass weight w in [0, 1] (partial transmission, glsl/bsdf.glsl): its
    /// interface (the Fresnel-weighted `mirror` reflection and the refraction, or the rough
    /// dielectric) is weighted by w and its `diffuse`, `phong` and `glossy` lobes by
    /// 1 - w ([`Material::lobes_weight`]), on both sides of the surface. One (clear glass,
    /// the default): the other lobes have no weight. Unused by opaque materials.
    pub glass_weight: f32,
    /// KHR_materials_clearcoat's clearcoatFactor in [0, 1] (0: no coat): a GGX layer of
    /// F0 0.04 (IOR 1.5) over the rest of the material, blended as the extension writes
    /// it, f = mix(base, coat, clearcoat x F_coat(n.v)) (glsl/lobes/clearcoat.glsl).
    pub clearcoat: f32,
    /// clearcoatRoughnessFactor: the coat's GGX alpha is its square (at least
    /// `MIN_GGX_ALPHA`).
    pub clearcoat_roughness: f32,
    /// clearcoatTexture and clearcoatRoughnessTexture (linear): where a triangle has their
    /// texture coordinates, the factors are multiplied by the texel's R and G channel
    /// respectively (glsl/textures.glsl, `surface_tint`).
    pub clearcoat_texture: Option<TextureRef>,
    pub clearcoat_roughness_texture: Option<TextureRef>,
    /// clearcoatNormalTexture and its scale: the coat's own normal map (linear, read as
    /// normalTexture is), which bends the coat's shading normal where a triangle has its
    /// texture coordinates and tangents; the base keeps its own (glsl/lobes/clearcoat.glsl).
    pub clearcoat_normal_texture: Option<TextureRef>,
    pub clearcoat_normal_scale: f32,
    /// KHR_materials_sheen's sheenColorFactor (linear, each channel in [0, 1]; black: no
    /// sheen): the colour of a Charlie sheen lobe over the rest of the material,
    /// f = f_sheen + f_base (1 - max(sheenColor) E) (glsl/lobes/sheen.glsl).
    pub sheen_color: Vec3,
    /// sheenRoughnessFactor in [0, 1] (the kernels take at least
    /// `MIN_SHEEN_ROUGHNESS`).
    pub sheen_roughness: f32,
    /// sheenColorTexture (sRGB) and sheenRoughnessTexture (linear): where a triangle has
    /// their texture coordinates, the factors are multiplied by the texel's RGB and A
    /// channel respectively (glsl/textures.glsl, `surface_tint`).
    pub sheen_color_texture: Option<TextureRef>,
    pub sheen_roughness_texture: Option<TextureRef>,
    /// KHR_materials_iridescence's iridescenceFactor in [0, 1] (0: none): a thin film whose
    /// interference replaces the Fresnel term of the GGX lobe and of the diffuse lobe's
    /// interface, F = mix(F_schlick, F_iridescence, factor) (glsl/lobes/iridescence.glsl).
    pub iridescence: f32,
    /// iridescenceIor: the film's index of refraction (default 1.3).
    pub iridescence_ior: f32,
    /// iridescenceThicknessMinimum and Maximum in nm (default 100 and 400): the film is
    /// the maximum thick, or where a triangle has the thickness texture's coordinates
    /// mix(minimum, maximum, texel G).
    pub iridescence_thickness_min: f32,
    pub iridescence_thickness_max: f32,
    /// iridescenceTexture and iridescenceThicknessTexture (linear): the factor is
    /// multiplied by the texel's R, the thickness interpolated by its G
    /// (glsl/textures.glsl, `surface_tint`).
    pub iridescence_texture: Option<TextureRef>,
    pub iridescence_thickness_texture: Option<TextureRef>,
    /// KHR_materials_anisotropy's anisotropyStrength in [0, 1] (0: isotropic): the GGX
    /// lobe's alpha along the anisotropy direction is mix(alpha, 1, strength^2), across it
    /// alpha (glsl/lobes/anisotropy.glsl). Needs the triangle's tangents.
    pub anisotropy_strength: f32,
    /// anisotropyRotation: radians from the tangent towards the bitangent.
    pub anisotropy_rotation: f32,
    /// anisotropyTexture (linear): RG the direction in tangent space ([0, 1] to [-1, 1]),
    /// rotated by the rotation; B multiplies the strength (glsl/textures.glsl).
    pub anisotropy_texture: Option<TextureRef>,
    /// KHR_materials_diffuse_transmission on an opaque material (None: none): the diffuse
    /// lobe becomes mix(diffuse reflection, diffuse transmission, factor)
    /// (glsl/lobes/diffuse_transmission.glsl).
    pub diffuse_transmission: Option<Box<DiffuseTransmission>>,
    /// KHR_materials_dispersion's dispersion (20 / Abbe number; 0: none) on a dielectric:
    /// its glass refracts channel c of RGB with its own IOR ([`Material::dispersion_iors`],
    /// glsl/lobes/dispersion.glsl).
    pub dispersion: f32,
    /// KHR_materials_transmission's transmissionTexture and KHR_materials_specular's
    /// specularTexture and specularColorTexture, with the factors the kernels recompute the
    /// lobes from where a triangle has their texture coordinates ([`LayerTextures`]).
    pub layer_textures: Option<Box<LayerTextures>>,
}

/// Textures that vary a glTF material's transmission and specular factors per point, and
/// what the kernels recompute the metallic/roughness lobes from there (glsl/bsdf.glsl,
/// `point_material`, the twin of [`Material::metallic_roughness_with_f0`] and
/// [`Material::transmissive`]). Linear texels but for specularColorTexture (sRGB).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LayerTextures {
    /// transmissionTexture: its R multiplies transmissionFactor (the glass weight).
    pub transmission: Option<TextureRef>,
    /// specularTexture: its A multiplies specularFactor.
    pub specular: Option<TextureRef>,
    /// specularColorTexture: its RGB (sRGB) multiplies specularColorFactor.
    pub specular_color: Option<TextureRef>,
    /// baseColorFactor (RGB), metallicFactor and roughnessFactor.
    pub base: Vec3,
    pub metallic: f32,
    pub roughness: f32,
    /// The dielectric's F0 of the factors (KHR_materials_ior and _specular).
    pub dielectric_f0: Vec3,
    /// The F0 of the IOR times specularColorFactor, not clamped, and specularFactor
    /// (clamped to [0, 1]): the dielectric's F0 at a point is
    /// min(specular_f0 x colour texel, 1) x specular_factor x specular texel.
    pub specular_f0: Vec3,
    pub specular_factor: f32,
}

/// glTF 2.0's metallicRoughnessTexture (section 3.9.2, "Metallic-Roughness Material"),
/// with what [`Material::metallic_roughness_textured`] was given: at a point with the
/// texture's coordinates the roughness is `roughness` times the texel's G channel and
/// the metallic `metallic` times its B channel (linear values: the texture is not sRGB;
/// R is unused), and the material's lobes are those of
/// [`Material::metallic_roughness_with_f0`]`(base, metallic', roughness', dielectric_f0)`
/// there, computed per point by the kernels (glsl/bsdf.glsl, `point_material`; the base
/// colour's own tint applies on top, as for a constant material).
#[derive(Clone, Debug, PartialEq)]
pub struct MetallicRoughnessTexture {
    pub texture: TextureRef,
    /// baseColorFactor (RGB).
    pub base: Vec3,
    /// metallicFactor and roughnessFactor.
    pub metallic: f32,
    pub roughness: f32,
    /// The F0 of the dielectric part (0.04 unless KHR_materials_ior/specular say
    /// otherwise).
    pub dielectric_f0: Vec3,
}

impl Default for Material {
    fn default() -> Self {
        Material {
            name: String::new(),
            diffuse: Vec3::ZERO,
            phong: Vec3::ZERO,
            phong_exponent: 1.0,
            mirror: Vec3::ZERO,
            ior: -1.0,
            dielectric_roughness: 0.0,
            emission: Vec3::ZERO,
            glossy: Vec3::ZERO,
            roughness: 1.0,
            diffuse_fresnel_f0: 0.0,
            base_color_texture: None,
            glossy_untinted: 0.0,
            alpha: 1.0,
            alpha_mode: AlphaMode::Opaque,
            normal_texture: None,
            normal_scale: 1.0,
            emissive_texture: None,
            metallic_roughness_texture: None,
            one_sided: false,
            attenuation: Vec3::ZERO,
            transmission: Vec3::ONE,
            glass_weight: 1.0,
            clearcoat: 0.0,
            clearcoat_roughness: 0.0,
            clearcoat_texture: None,
            clearcoat_roughness_texture: None,
            clearcoat_normal_texture: None,
            clearcoat_normal_scale: 1.0,
            sheen_color: Vec3::ZERO,
            sheen_roughness: 0.0,
            sheen_color_texture: None,
            sheen_roughness_texture: None,
            iridescence: 0.0,
            iridescence_ior: 1.3,
            iridescence_thickness_min: 100.0,
            iridescence_thickness_max: 400.0,
            iridescence_texture: None,
            iridescence_thickness_texture: None,
            anisotropy_strength: 0.0,
            anisotropy_rotation: 0.0,
            anisotropy_texture: None,
            diffuse_transmission: None,
            dispersion: 0.0,
            layer_textures: None,
        }
    }
}

/// Specular reflectance of dielectrics at normal incidence in glTF's metallic/roughness
/// model (its fixed F0).
pub const GLTF_DIELECTRIC_F0: f32 = 0.04;

/// KHR_materials_diffuse_transmission (glsl/lobes/diffuse_transmission.glsl): the diffuse
/// lobe of the material's dielectric part, f_d = base / pi (reflection), becomes
/// (1 - factor) base / pi on wo's side plus factor x color / pi on the other side (a
/// Lambertian transmission), each under the diffuse lobe's interface weight; the metal
/// part (`metallic`) transmits nothing.
#[derive(Clone, Debug, PartialEq)]
pub struct DiffuseTransmission {
    /// diffuseTransmissionFactor in [0, 1].
    pub factor: f32,
    /// diffuseTransmissionColorFactor (linear, each channel in [0, 1]).
    pub color: Vec3,
    /// The material's metallic factor: the transmitted colour is color x (1 - metallic),
    /// with the point's metallic where a metallic-roughness texture varies it.
    pub metallic: f32,
    /// diffuseTransmissionTexture (its A channel multiplies the factor, linear) and
    /// diffuseTransmissionColorTexture (its RGB multiply the colour, sRGB), where a triangle
    /// has their texture coordinates (glsl/textures.glsl, `surface_tint`).
    pub texture: Option<TextureRef>,
    pub color_texture: Option<TextureRef>,
}

impl Material {
    /// The GGX alpha of a rough dielectric (`dielectric_roughness`^2, at least
    /// `MIN_GGX_ALPHA`), 0 for smooth glass and every other material (GpuMaterial's
    /// emission.w, glsl/bsdf.glsl).
    pub fn dielectric_alpha(&self) -> f32 {
        if self.is_rough_dielectric() {
            (self.dielectric_roughness * self.dielectric_roughness).max(crate::render::gpu_types::MIN_GGX_ALPHA)
        } else {
            0.0
        }
    }

    /// The medium coefficient the kernels get (GpuMaterial.medium.rgb): `attenuation` on a
    /// dielectric that does not emit, else zero (an emitter's surface never starts a
    /// medium segment of a light sample, so it bounds no medium anywhere).
    pub fn medium_attenuation(&self) -> Vec3 {
        if self.is_dielectric() && self.emission == Vec3::ZERO {
            self.attenuation
        } else {
            Vec3::ZERO
        }
    }

    /// A dielectric: the kernels treat every IOR that is not negative (NaN included) as one.
    pub fn is_dielectric(&self) -> bool {
        self.ior >= 0.0 || self.ior.is_nan()
    }

    /// The weight of the `diffuse`, `phong` and `glossy` lobes: 1 - `glass_weight` on a
    /// dielectric (clamped to [0, 1]; 0 for a NaN weight), 1 on an opaque material.
    pub fn lobes_weight(&self) -> f32 {
        if self.is_dielectric() {
            (1.0 - self.glass_weight.clamp(0.0, 1.0)).max(0.0)
        } else {
            1.0
        }
    }

    /// A dielectric whose glass weight is below 1: partial transmission, its other lobes
    /// weighted by 1 - the glass weight (HAS_PARTIAL_TRANSMISSION).
    /// Whether the material's GGX lobe is anisotropic (KHR_materials_anisotropy).
    pub fn has_anisotropy(&self) -> bool {
        self.anisotropy_strength > 0.0
    }

    /// Whether the material has a sheen (a sheen colour above black).
    pub fn has_sheen(&self) -> bool {
        self.sheen_color.max_element() > 0.0
    }

    /// Whether the material has a thin-film iridescence (a factor above 0).
    pub fn has_iridescence(&self) -> bool {
        self.iridescence > 0.0
    }

    /// Whether the material transmits diffusely: an opaque material (the kernels give a
    /// dielectric none) with a diffuse-transmission factor and colour above zero.
    pub fn has_diffuse_transmission(&self) -> bool {
        !self.is_dielectric()
            && self.diffuse_transmission.as_deref().is_some_and(|d| d.factor > 0.0 && d.color.max_element() > 0.0)
    }

    /// Whether the material's glass disperses (KHR_materials_dispersion): a dielectric with
    /// a glass weight above 0 and a dispersion above 0.
    pub fn has_dispersion(&self) -> bool {
        self.is_dielectric() && self.glass_weight > 0.0 && self.dispersion > 0.0
    }

    /// The IORs of the glass for R, G and B under KHR_materials_dispersion, as the
    /// extension's implementation note (what glTF viewers do) computes them: half the
    /// spread n_F - n_C = (ior - 1) / V_d = (ior - 1) dispersion / 20 either side of
    /// green's `ior`, red the smallest, each at least 1.
    pub fn dispersion_iors(&self) -> Vec3 {
        let half_spread = (self.ior - 1.0) * 0.025 * self.dispersion;
        Vec3::new(self.ior - half_spread, self.ior, self.ior + half_spread).max(Vec3::ONE)
    }

    pub fn has_partial_transmission(&self) -> bool {
        self.lobes_weight() > 0.0 && self.is_dielectric()
    }

    /// A rough dielectric: a dielectric (`ior >= 0`, not 1) of `dielectric_roughness` > 0.
    pub fn is_rough_dielectric(&self) -> bool {
        // IOR 1 refracts straight through any microfacet and reflects nothing: the rough
        // dielectric would be a delta transmission, which smooth glass is exactly.
        self.ior >= 0.0 && self.ior != 1.0 && self.dielectric_roughness > 0.0
    }

    /// glTF 2.0's metallic/roughness material (Appendix B) in vkvcm's model: a GGX lobe
    /// whose Schlick F0 is mix(0.04, base, metallic) (the dielectric's and the metal's
    /// Fresnel terms are the same Schlick form, so their mix is one lobe), over a diffuse
    /// lobe (1 - metallic) base behind a dielectric interface of F0 0.04. A metal with
    /// roughness 0 is a perfect mirror of colour `base`. docs/scene-format.md says what
    /// differs from the specification's `fresnel_mix` and why.
    pub fn metallic_roughness(base: Vec3, metallic: f32, roughness: f32) -> Material {
        Material::metallic_roughness_with_f0(base, metallic, roughness, Vec3::splat(GLTF_DIELECTRIC_F0))
    }

    /// [`Material::metallic_roughness`] with the dielectric's F0 `dielectric_f0` instead of
    /// 0.04 (KHR_materials_ior: ((ior - 1) / (ior + 1))^2; KHR_materials_specular: times
    /// specularColorFactor, clamped to 1, times specularFactor). The diffuse lobe's
    /// interface takes the largest component of it, so that a coloured F0 never makes the
    /// layering reflect more than it receives; the part of the GGX F0 that the base colour
    /// does not tint is its mean.
    pub fn metallic_roughness_with_f0(base: Vec3, metallic: f32, roughness: f32, dielectric_f0: Vec3) -> Material {
        if metallic >= 1.0 && roughness <= 0.0 {
            return Material { mirror: base, ..Material::default() };
        }
        Material::metallic_roughness_lobes(base, metallic, roughness, dielectric_f0, None)
    }

    /// glTF 2.0's metallic/roughness material with KHR_materials_transmission factor
    /// `transmission` > 0 and metallic < 1, of index of refraction `ior`: glTF's BSDF,
    /// mix(mix(opaque dielectric, glass, transmission), metal, metallic), is linear in both
    /// factors, so it is glass of weight w = (1 - metallic) transmission (`glass_weight`)
    /// plus, with weight 1 - w, the metallic/roughness lobes of metallic
    /// metallic / (1 - w), which keeps the metal's weight metallic (glsl/bsdf.glsl,
    /// "Partial transmission"). The glass has the material's roughness (smooth at 0, else
    /// the rough dielectric) and its transmitted part is tinted by `base`; its reflection
    /// is the mirror (white, Fresnel-weighted), so the lobes' smooth metal is a GGX lobe of
    /// the smallest width.
    pub fn transmissive(
        base: Vec3,
        metallic: f32,
        roughness: f32,
        transmission: f32,
        ior: f32,
        dielectric_f0: Vec3,
    ) -> Material {
        let glass_weight = (1.0 - metallic) * transmission.min(1.0);
        let mut m = if glass_weight < 1.0 {
            let lobes_metallic = (metallic / (1.0 - glass_weight)).min(1.0);
            Material::metallic_roughness_lobes(base, lobes_metallic, roughness, dielectric_f0, None)
        } else {
            Material::default()
        };
        m.mirror = Vec3::ONE;
        m.ior = ior;
        m.dielectric_roughness = roughness;
        m.transmission = base;
        m.glass_weight = glass_weight;
        m
    }

    /// [`Material::metallic_roughness_with_f0`] with glTF's metallicRoughnessTexture
    /// `texture`, which multiplies `roughness` by its texels' G and `metallic` by their B
    /// per point ([`MetallicRoughnessTexture`]). The material's own lobes are those of the
    /// constant factors (what a triangle without the texture's coordinates shows), except
    /// that a smooth metal is a GGX lobe of the smallest width rather than a mirror (the
    /// kernels vary the GGX lobe per point, not the choice of lobes), and that the diffuse
    /// lobe keeps its interface wherever the texture can make the point less metallic.
    pub fn metallic_roughness_textured(
        base: Vec3,
        metallic: f32,
        roughness: f32,
        dielectric_f0: Vec3,
        texture: TextureRef,
    ) -> Material {
        Material::metallic_roughness_lobes(base, metallic, roughness, dielectric_f0, Some(texture))
    }

    /// The diffuse and GGX lobes of glTF's metallic/roughness model (the kernels' per-point
    /// twin is glsl/bsdf.glsl, `point_material`).
    fn metallic_roughness_lobes(
        base: Vec3,
        metallic: f32,
        roughness: f32,
        dielectric_f0: Vec3,
        texture: Option<TextureRef>,
    ) -> Material {
        let diffuse = base * (1.0 - metallic);
        let glossy = dielectric_f0.lerp(base, metallic);
        // Is there a diffuse lobe anywhere: with a texture wherever the base is not black.
        let diffuse_somewhere = if texture.is_some() { base != Vec3::ZERO } else { diffuse != Vec3::ZERO };
        let diffuse_fresnel_f0 = if diffuse_somewhere { dielectric_f0.max_element() } else { 0.0 };
        let glossy_untinted = dielectric_f0.element_sum() / 3.0 * (1.0 - metallic);
        let metallic_roughness_texture =
            texture.map(|texture| MetallicRoughnessTexture { texture, base, metallic, roughness, dielectric_f0 });
        Material {
            diffuse,
            glossy,
            roughness,
            diffuse_fresnel_f0,
            glossy_untinted,
            metallic_roughness_texture,
            ..Material::default()
        }
    }
}

/// Light sources. Emission and next-event estimation pick a light by power, or uniformly
/// as SmallVCM (`LightSelection`, src/render/light_selection.rs).
#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    /// One emitting triangle (index into `Scene::triangles`), Lambertian, one-sided: it
    /// emits on the side its geometric normal (p1-p0)x(p2-p0) points to.
    Area { triangle: u32, radiance: Vec3 },
    /// Isotropic point light; `intensity` in W/sr (glTF candela).
    Point { position: Vec3, intensity: Vec3 },
    /// Spot light; intensity in W/sr inside the inner cone, smooth falloff to the outer.
    Spot {
        position: Vec3,
        /// Unit direction the spot points to.
        direction: Vec3,
        intensity: Vec3,
        cos_inner: f32,
        cos_outer: f32,
    },
    /// Directional (sun) light; `direction` is the unit direction photons travel,
    /// `irradiance` in W/m^2 on a surface facing the light (glTF lux).
    Directional { direction: Vec3, irradiance: Vec3 },
    /// Constant environment radiance from every direction (extension `VKVCM_background`).
    Background { radiance: Vec3 },
    /// An image-based environment at infinity (extension `VKVCM_environment`, or
    /// `vkvcm render --env`). At most one background or environment per scene.
    Environment(EnvironmentLight),
}

impl Light {
    /// The light surrounds the scene at infinity (background or environment map).
    pub fn is_environment(&self) -> bool {
        matches!(self, Light::Background { .. } | Light::Environment(_))
    }
}

/// Pinhole camera.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    pub position: Vec3,
    /// Unit viewing direction.
    pub forward: Vec3,
    /// Unit up vector, orthogonal to `forward`.
    pub up: Vec3,
    /// Vertical field of view in radians (for a square image equal to the horizontal).
    pub yfov: f32,
}

/// What the importer skipped or could not represent; printed once per kind.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LoadReport {
    pub degenerate_triangles: usize,
    /// World position (in the file's coordinates, f64) that the importer moved to the
    /// origin: the chosen camera's position. Scene coordinates are camera-relative.
    pub origin: [f64; 3],
    /// The chosen glTF camera's `aspectRatio` (width / height), when it has one: the
    /// image's default shape (`vkvcm render` without --width/--height).
    pub camera_aspect: Option<f32>,
    pub warnings: Vec<String>,
    /// What lit the scene when the importer chose its light (the default environment),
    /// one line for the user; none otherwise.
    pub lighting_note: Option<String>,
}

/// A scene ready for BVH construction and rendering.
#[derive(Clone, Debug)]
pub struct Scene {
    pub name: String,
    /// World-space triangles, then the object-space triangles of the shared meshes.
    pub triangles: Vec<Triangle>,
    /// Meshes placed by `instances` (empty when everything is flattened into world space).
    pub meshes: Vec<SharedMesh>,
    pub instances: Vec<Instance>,
    pub spheres: Vec<Sphere>,
    pub materials: Vec<Material>,
    pub lights: Vec<Light>,
    pub camera: Camera,
    pub report: LoadReport,
    /// Texture images, referenced by the materials' textures (`TextureRef::image`).
    pub images: Vec<TextureImage>,
}

impl Scene {
    /// A checksum (CRC-32, 8 hex digits) of everything in the scene that shapes an image:
    /// triangles (positions, shading normals, materials, texture coordinates and colours),
    /// spheres, materials, texture images (sizes and texels), lights and the camera; not
    /// its name or load report. Resumed renders compare it, so that an edited
    /// scene file of the same name is not mixed into an old image. CRC-32 is meant for
    /// accidental changes, which is all this guards against.
    pub fn fingerprint(&self) -> String {
        let mut h = crc32fast::Hasher::new();
        for t in &self.triangles {
            h.update(bytemuck::cast_slice(&t.p));
            match &t.n {
                Some(n) => {
                    h.update(&[1]);
                    h.update(bytemuck::cast_slice(n));
                }
                None => h.update(&[0]),
            }
            h.update(&t.material.to_le_bytes());
            match &t.attributes {
                Some(a) => {
                    h.update(&[1]);
                    for uv in &a.uv {
                        match uv {
                            Some(uv) => {
                                h.update(&[1]);
                                h.update(bytemuck::cast_slice(uv));
                            }
                            None => h.update(&[0]),
                        }
                    }
                    for v in [&a.color, &a.tangent] {
                        match v {
                            Some(c) => {
                                h.update(&[1]);
                                h.update(bytemuck::cast_slice(c));
                            }
                            None => h.update(&[0]),
                        }
                    }
                }
                None => h.update(&[0]),
            }
        }
        for img in &self.images {
            h.update(&img.width.to_le_bytes());
            h.update(&img.height.to_le_bytes());
            h.update(bytemuck::cast_slice(&img.texels));
        }
        // Few and small: their Debug text (floats print as the shortest round-trip string).
        let rest = format!(
            "{:?}{:?}{:?}{:?}{:?}{:?}",
            self.meshes, self.instances, self.spheres, self.materials, self.lights, self.camera
        );
        h.update(rest.as_bytes());
        format!("{:08x}", h.finalize())
    }
}

pub mod default_environments;
pub mod environment;
pub mod gltf_import;
pub mod reference;
pub mod validate;

pub use gltf_import::{decode_data_uri, encode_data_uri, load_gltf_bytes, LoadOptions};
pub use validate::check_renderable;

use std::path::{Path, PathBuf};

/// Names of the four built-in reference scenes (`docs/smallvcm.md`, the predefined
/// scenes), in SmallVCM's scene-id order 0..3. `"default"` is an alias of `gbs_s`.
pub const BUILTIN_SCENES: [&str; 4] = ["gbs_s", "glm_c", "gbs_p", "gbs_b"];

/// Loads a glTF 2.0 scene (`.gltf` or `.glb`) with the first perspective camera.
pub fn load(path: &Path) -> anyhow::Result<Scene> {
    load_with(path, &LoadOptions::default())
}

/// Loads a glTF 2.0 scene (`.gltf` or `.glb`); `options.camera` selects a camera by node
/// or camera name.
pub fn load_with(path: &Path, options: &LoadOptions) -> anyhow::Result<Scene> {
    let _activity = crate::activity::Activity::begin(|| format!("loading {}", path.display()), None);
    gltf_import::load_gltf(path, options)
}

/// Loads a built-in scene by name (`gbs_s`, `glm_c`, `gbs_p`, `gbs_b`, `default` = `gbs_s`,
/// or SmallVCM's ids `0`..`3`), or else treats the argument as a path to a glTF file.
pub fn load_named(name_or_path: &str) -> anyhow::Result<Scene> {
    load_named_with(name_or_path, &LoadOptions::default())
}

/// [`load_named`] with load options. Unlike [`load_with`], it also refuses scenes that
/// cannot be rendered ([`check_renderable`]: no emitter, no geometry): it is the entry
/// point of the commands that render.
pub fn load_named_with(name_or_path: &str, options: &LoadOptions) -> anyhow::Result<Scene> {
    if let Some(name) = builtin_name(name_or_path) {
        let path = builtin_path(name).ok_or_else(|| {
            anyhow::anyhow!(
                "built-in scene '{name}': scenes/{name}.gltf was found neither in {} nor next to the executable",
                env!("CARGO_MANIFEST_DIR")
            )
        })?;
        // The reference scenes are lit as SmallVCM defines them: no viewer's default light.
        let options = LoadOptions { default_environment: None, ..options.clone() };
        let mut scene = load_with(&path, &options)?;
        check_renderable(&scene).map_err(|e| gltf_import::one_line(&path, &e))?;
        scene.name = name.to_string();
        return Ok(scene);
    }
    let path = Path::new(name_or_path);
    if !path.exists() {
        anyhow::bail!(
            "unknown scene '{name_or_path}': not a built-in name ({}, default) and no such file",
            BUILTIN_SCENES.join(", ")
        );
    }
    let scene = load_with(path, options)?;
    check_renderable(&scene).map_err(|e| gltf_import::one_line(path, &e))?;
    Ok(scene)
}

/// Canonical built-in name for `name` (`"default"` and `"0"`..`"3"` are aliases).
pub fn builtin_name(name: &str) -> Option<&'static str> {
    match name {
        "default" | "0" => Some(BUILTIN_SCENES[0]),
        "1" => Some(BUILTIN_SCENES[1]),
        "2" => Some(BUILTIN_SCENES[2]),
        "3" => Some(BUILTIN_SCENES[3]),
        _ => BUILTIN_SCENES.iter().copied().find(|n| *n == name),
    }
}

/// Where the file of a built-in scene lives: `<crate>/scenes/<name>.gltf` when the source
/// tree is present, else `scenes/<name>.gltf` or `<name>.gltf` next to the executable (or
/// in its parent folders, for `target/<profile>/` layouts).
pub fn builtin_path(name: &str) -> Option<PathBuf> {
    let name = builtin_name(name)?;
    let file = format!("{name}.gltf");
    let mut candidates = vec![Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(&file)];
    if let Ok(exe) = std::env::current_exe() {
        let mut dir = exe.parent().map(Path::to_path_buf);
        for _ in 0..3 {
            let Some(d) = dir else { break };
            candidates.push(d.join("scenes").join(&file));
            candidates.push(d.join(&file));
            dir = d.parent().map(Path::to_path_buf);
        }
    }
    candidates.into_iter().find(|p| p.is_file())
}

impl Scene {
    /// The world-space triangles: all but the shared meshes' (which follow them).
    pub fn world_triangles(&self) -> &[Triangle] {
        &self.triangles[..SharedMesh::world_triangle_count(&self.meshes, self.triangles.len())]
    }

    /// Triangles in the world, counting each instance's mesh once per instance.
    pub fn placed_triangles(&self) -> u64 {
        let instanced: u64 = self.instances.iter().map(|i| self.meshes[i.mesh as usize].count as u64).sum();
        self.world_triangles().len() as u64 + instanced
    }

    /// Every triangle in world space, instances expanded (for tests and small scenes: it
    /// allocates the flattened scene).
    pub fn flattened_triangles(&self) -> Vec<Triangle> {
        let mut out = self.world_triangles().to_vec();
        for inst in &self.instances {
            let m = inst.object_to_world;
            let lin = glam::Mat3::from(m.matrix3);
            let normal_matrix = lin.inverse().transpose();
            let flip = lin.determinant() < 0.0;
            for t in &self.triangles[self.meshes[inst.mesh as usize].range()] {
                let mut w = t.clone();
                w.p = t.p.map(|p| m.transform_point3(p));
                w.n = t.n.map(|n| n.map(|v| (normal_matrix * v).normalize_or_zero()));
                if let Some(a) = &mut w.attributes {
                    a.tangent = a.tangent.map(|ts| ts.map(|t| transform_tangent(lin, t)));
                }
                // A mirroring transform reverses the winding: swap vertices 1 and 2 (with
                // their attributes) so the geometric normal stays on the authored side, as
                // the importer does.
                if flip {
                    w.p.swap(1, 2);
                    if let Some(n) = &mut w.n {
                        n.swap(1, 2);
                    }
                    if let Some(a) = &mut w.attributes {
                        for uv in a.uv.iter_mut().flatten() {
                            uv.swap(1, 2);
                        }
                        if let Some(c) = &mut a.color {
                            c.swap(1, 2);
                        }
                        if let Some(t) = &mut a.tangent {
                            t.swap(1, 2);
                        }
                    }
                }
                out.push(w);
            }
        }
        out
    }

    /// Moves everything by `by` (geometry, punctual lights, camera; directions unchanged).
    pub fn translate(&mut self, by: Vec3) {
        let world = self.world_triangles().len();
        for t in &mut self.triangles[..world] {
            t.p = t.p.map(|p| p + by);
        }
        for inst in &mut self.instances {
            inst.object_to_world.translation += glam::Vec3A::from(by);
        }
        for s in &mut self.spheres {
            s.center += by;
        }
        for l in &mut self.lights {
            match l {
                Light::Point { position, .. } | Light::Spot { position, .. } => *position += by,
                Light::Area { .. } | Light::Directional { .. } | Light::Background { .. } | Light::Environment(_) => {}
            }
        }
        self.camera.position += by;
    }

    /// Axis-aligned bounds (min, max) of all triangles (instances' included) and spheres;
    /// `(0, 0)` when the
    /// scene has no geometry.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for t in self.world_triangles() {
            for p in t.p {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        // Instances: their mesh's vertices, transformed (exact, as the flattened scene's
        // bounds: the scene radius sets ray offsets and photon radii).
        use rayon::prelude::*;
        let (ilo, ihi) = self
            .instances
            .par_iter()
            .map(|inst| {
                let m = inst.object_to_world;
                self.triangles[self.meshes[inst.mesh as usize].range()].iter().flat_map(|t| t.p).fold(
                    (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
                    |(l, h), p| {
                        let q = m.transform_point3(p);
                        (l.min(q), h.max(q))
                    },
                )
            })
            .reduce(
                || (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
                |(l0, h0), (l1, h1)| (l0.min(l1), h0.max(h1)),
            );
        lo = lo.min(ilo);
        hi = hi.max(ihi);
        for s in &self.spheres {
            lo = lo.min(s.center - Vec3::splat(s.radius));
            hi = hi.max(s.center + Vec3::splat(s.radius));
        }
        if lo.x > hi.x {
            (Vec3::ZERO, Vec3::ZERO)
        } else {
            (lo, hi)
        }
    }

    /// Scene bounding sphere as SmallVCM's `BuildSceneSphere`: centre of [`Scene::bounds`]
    /// and half the length of its diagonal.
    pub fn bounding_sphere(&self) -> (Vec3, f32) {
        let (lo, hi) = self.bounds();
        ((lo + hi) * 0.5, (hi - lo).length_squared().sqrt() * 0.5)
    }

    /// Points the camera as the command line asks (`--look-from`, `--look-at`, `--up`,
    /// `--fov`), in the file's world coordinates (the importer re-centred the scene on
    /// `report.origin`, which is subtracted here). A position without a target looks at
    /// the centre of the scene's bounds; a target without a position keeps the camera
    /// where it is. A new view keeps `up`, else world +Y (as glTF viewers' orbit cameras
    /// do), made orthogonal to the view; the file camera's own up is not kept, since a
    /// tilted camera moved to look head-on at a face would draw it rotated. `up` alone
    /// turns the camera about its viewing direction.
    pub fn set_view(
        &mut self,
        look_from: Option<Vec3>,
        look_at: Option<Vec3>,
        up: Option<Vec3>,
        yfov: Option<f32>,
    ) -> anyhow::Result<()> {
        let origin = glam::DVec3::from_array(self.report.origin);
        let local = |p: Vec3| (p.as_dvec3() - origin).as_vec3();
        if let Some(f) = yfov {
            if !(f > 0.0 && f < std::f32::consts::PI) {
                anyhow::bail!("field of view {} degrees is not in (0, 180)", f.to_degrees());
            }
            self.camera.yfov = f;
        }
        if let Some(u) = up {
            if u.try_normalize().is_none() {
                anyhow::bail!("the up direction {u} has no length");
            }
        }
        if look_from.is_none() && look_at.is_none() && up.is_none() {
            return Ok(());
        }
        let position = look_from.map(local).unwrap_or(self.camera.position);
        let target = look_at.map(local).unwrap_or_else(|| {
            if look_from.is_some() {
                self.bounding_sphere().0
            } else {
                self.camera.position + self.camera.forward
            }
        });
        let camera = Camera::looking_at(position, target, up.unwrap_or(Vec3::Y), self.camera.yfov)
            .ok_or_else(|| anyhow::anyhow!("the camera's position and target are the same point"))?;
        self.camera = camera;
        Ok(())
    }
}

/// Where the camera of a file without one looks from: the direction from the centre of the
/// scene to the camera (+Z is glTF's front; raised 20 degrees and turned 30 degrees to the
/// right around +Y), and its vertical field of view.
pub const DEFAULT_VIEW_DIRECTION_DEGREES: (f32, f32) = (30.0, 20.0);
pub const DEFAULT_YFOV_DEGREES: f32 = 40.0;

impl Camera {
    /// A camera at `position` looking at `target`, with `up` made orthogonal to the view
    /// (world +Y when `up` is along it); `None` when position and target coincide.
    pub fn looking_at(position: Vec3, target: Vec3, up: Vec3, yfov: f32) -> Option<Camera> {
        let forward = (target - position).try_normalize()?;
        let ortho = |u: Vec3| (u - forward * forward.dot(u)).try_normalize();
        let up = ortho(up).or_else(|| ortho(Vec3::Y)).or_else(|| ortho(Vec3::Z))?;
        Some(Camera { position, forward, up, yfov })
    }

    /// The default camera of a scene without one: looking at the centre of the bounding
    /// sphere (centre `c`, radius `r`) from [`DEFAULT_VIEW_DIRECTION_DEGREES`], far enough
    /// that the sphere fits the vertical field of view [`DEFAULT_YFOV_DEGREES`] with a
    /// margin of 10%; `None` for an empty scene.
    pub fn framing(c: Vec3, r: f32) -> Option<Camera> {
        if !(r > 0.0 && r.is_finite()) {
            return None;
        }
        let (azimuth, elevation) =
            (DEFAULT_VIEW_DIRECTION_DEGREES.0.to_radians(), DEFAULT_VIEW_DIRECTION_DEGREES.1.to_radians());
        let towards_camera =
            Vec3::new(azimuth.sin() * elevation.cos(), elevation.sin(), azimuth.cos() * elevation.cos());
        let yfov = DEFAULT_YFOV_DEGREES.to_radians();
        let distance = 1.1 * r / (0.5 * yfov).sin();
        Camera::looking_at(c + towards_camera * distance, c, Vec3::Y, yfov)
    }
}
