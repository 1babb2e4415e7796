//! The feature set of a render: which material components, light kinds and geometry the
//! scene has. The kernels are compiled with only that code (`HAS_...` defines,
//! glsl/features.glsl); `--generic` compiles every feature in, for comparison. Leaving out
//! a feature the scene lacks does not change the image: an absent material component has
//! zero albedo in every material (so its selection probability and contribution are 0,
//! and it adds exact zeros to the sums), an absent light kind is never picked, and the
//! removed code draws no random numbers, so both variants follow the same random sequence
//! (tests/render_features.rs compares them).
//!
//! Surface detail (vertex attributes, base-colour, metallic-roughness, normal and emissive
//! textures, alpha) is specialised the same way: its code is compiled in only for scenes
//! that have it.

use std::fmt;

use glam::Vec3;
use serde::Serialize;

use crate::gpu::Defines;
use crate::scene::{Light, Scene};

/// What the kernels of one render are compiled with.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct FeatureSet {
    /// Every feature compiled in (`--generic`), whatever the scene has.
    pub generic: bool,
    /// Rays are counted (profiling: COUNT_RAYS).
    pub count_rays: bool,
    /// Material components of the materials that primitives use.
    pub diffuse: bool,
    pub phong: bool,
    pub ggx: bool,
    pub mirror: bool,
    pub dielectric: bool,
    /// Some dielectric transmits partially (`Material::has_partial_transmission`): its
    /// diffuse, Phong and GGX lobes carry 1 - its glass weight (glsl/bsdf.glsl).
    pub partial_transmission: bool,
    /// Some dielectric is rough (`Material::is_rough_dielectric`, glsl/bsdf.glsl).
    pub rough_dielectric: bool,
    /// Some dielectric bounds an absorbing medium (`Material::medium_attenuation`,
    /// glsl/medium.glsl): path segments inside it are attenuated (Beer-Lambert).
    pub volume: bool,
    /// Some material has a clear coat (`Material::clearcoat` > 0,
    /// glsl/lobes/clearcoat.glsl).
    pub clearcoat: bool,
    /// Some coated material has a clearcoat or clearcoat-roughness texture and some
    /// triangle texture coordinates: surfaces and light vertices carry the point's coat
    /// factor and roughness multipliers (glsl/textures.glsl, `surface_tint`).
    pub clearcoat_textures: bool,
    /// Some material with a clear coat has a clearcoatNormalTexture and some triangle
    /// tangents: surfaces and light vertices carry the coat's own shading normal
    /// (glsl/lobes/clearcoat.glsl, `Tint.coat_normal`).
    pub clearcoat_normal_maps: bool,
    /// Some material has a sheen (`Material::has_sheen`, glsl/lobes/sheen.glsl).
    pub sheen: bool,
    /// Some material with a sheen has a sheen-colour or sheen-roughness texture and some
    /// triangle texture coordinates: surfaces and light vertices carry the point's sheen
    /// colour and roughness multipliers (glsl/textures.glsl, `surface_tint`).
    pub sheen_textures: bool,
    /// Some material has a thin-film iridescence (`Material::has_iridescence`,
    /// glsl/lobes/iridescence.glsl).
    pub iridescence: bool,
    /// Some iridescent material has an iridescence or thickness texture and some triangle
    /// texture coordinates: surfaces and light vertices carry the point's iridescence
    /// factor and thickness (glsl/textures.glsl, `surface_tint`).
    pub iridescence_textures: bool,
    /// Some material with a GGX lobe is anisotropic (`Material::has_anisotropy`) and some
    /// triangle has tangents: surfaces and light vertices carry the point's anisotropy
    /// direction and strength (glsl/lobes/anisotropy.glsl).
    pub anisotropy: bool,
    /// Some material transmits diffusely (`Material::has_diffuse_transmission`,
    /// glsl/lobes/diffuse_transmission.glsl).
    pub diffuse_transmission: bool,
    /// Some material that transmits diffusely has a diffuse-transmission or
    /// diffuse-transmission-colour texture and some triangle texture coordinates: surfaces
    /// and light vertices carry the point's multipliers (glsl/textures.glsl, `surface_tint`).
    pub diffuse_transmission_textures: bool,
    /// Some dielectric's glass disperses (`Material::has_dispersion`,
    /// glsl/lobes/dispersion.glsl): subpaths that meet one choose a colour channel, and
    /// light vertices carry it.
    pub dispersion: bool,
    /// Light kinds.
    pub area_lights: bool,
    pub point_lights: bool,
    pub spot_lights: bool,
    pub directional_lights: bool,
    pub background: bool,
    /// The background is an environment map (glsl/environment.glsl).
    pub environment_map: bool,
    pub spheres: bool,
    /// The BVH has two levels: instances of shared meshes (glsl/bvh.glsl, BVH_INSTANCES).
    pub instances: bool,
    /// Shading normals are uploaded and every estimator shades with them (glsl/bsdf.glsl).
    pub shading_normals: bool,
    /// The scene has shading normals (whether or not the kernels read them).
    pub scene_has_shading_normals: bool,
    /// Triangles carry texture coordinates or vertex colours, which tint the materials
    /// they use (glsl/textures.glsl): the per-vertex attributes are uploaded, surfaces
    /// and light vertices carry a tint.
    pub vertex_attributes: bool,
    /// Some material has a base-colour texture (or another texture that applies): the
    /// texture lookup is compiled in.
    pub textures: bool,
    /// Some material is a cut-out (alphaMode MASK) or blended (BLEND, stochastic
    /// transparency): traversal tests alpha at every candidate hit.
    pub alpha_mask: bool,
    /// Some material is one-sided (glTF doubleSided false): traversal drops hits on the
    /// back side of its triangles (glsl/bvh.glsl, BVH_FACE_TEST).
    pub one_sided: bool,
    /// Some material has a normal map and some triangle tangents: the shading normal is
    /// bent by it (with the shading-normal code compiled in).
    pub normal_maps: bool,
    /// Some emitting material has an emissive texture and some triangle texture
    /// coordinates: area lights' radiance is textured (glsl/textures.glsl, `emission_tint`).
    pub emissive_textures: bool,
    /// Some material has a metallic-roughness texture and some triangle texture
    /// coordinates: surfaces and light vertices carry the point's metallic and roughness,
    /// which vary its lobes (glsl/bsdf.glsl, `point_material`).
    pub metallic_roughness_textures: bool,
    /// Some dielectric has a transmissionTexture and some triangle texture coordinates:
    /// surfaces and light vertices carry the point's transmission multiplier, which varies
    /// its glass weight and lobes (glsl/bsdf.glsl, `point_material`; partial transmission
    /// is compiled in).
    pub transmission_textures: bool,
    /// Some material has a KHR_materials_specular texture and some triangle texture
    /// coordinates: surfaces and light vertices carry the point's specular multipliers,
    /// which vary the dielectric F0 of its lobes (glsl/bsdf.glsl, `point_material`).
    pub specular_textures: bool,
}

fn nonzero(v: Vec3) -> bool {
    v != Vec3::ZERO
}

impl FeatureSet {
    /// The features of `scene`; with `generic` every feature is on (the scene's own
    /// shading normals are still recorded in `scene_has_shading_normals`).
    pub fn new(scene: &Scene, generic: bool) -> FeatureSet {
        // Only materials that a primitive uses can be evaluated.
        let mut used = vec![false; scene.materials.len()];
        for m in scene.triangles.iter().map(|t| t.material).chain(scene.spheres.iter().map(|s| s.material)) {
            if let Some(u) = used.get_mut(m as usize) {
                *u = true;
            }
        }
        let mats: Vec<_> = scene.materials.iter().zip(&used).filter(|(_, u)| **u).map(|(m, _)| m).collect();
        let any_mat = |f: &dyn Fn(&crate::scene::Material) -> bool| mats.iter().any(|m| f(m));
        let any_light = |f: &dyn Fn(&Light) -> bool| scene.lights.iter().any(f);
        let scene_has_shading_normals = scene.triangles.iter().any(|t| t.n.is_some());
        let vertex_attributes = scene.triangles.iter().any(|t| t.attributes.is_some());
        let tangents = scene.triangles.iter().any(|t| t.attributes.as_ref().is_some_and(|a| a.tangent.is_some()));
        let normal_maps = tangents && any_mat(&|m| m.normal_texture.is_some());
        let clearcoat_normal_maps = tangents && any_mat(&|m| m.clearcoat > 0.0 && m.clearcoat_normal_texture.is_some());
        let emissive_textures = vertex_attributes && any_mat(&|m| m.emissive_texture.is_some() && nonzero(m.emission));
        let metallic_roughness_textures = vertex_attributes && any_mat(&|m| m.metallic_roughness_texture.is_some());
        let clearcoat_textures = vertex_attributes
            && any_mat(&|m| {
                m.clearcoat > 0.0 && (m.clearcoat_texture.is_some() || m.clearcoat_roughness_texture.is_some())
            });
        let sheen_textures = vertex_attributes
            && any_mat(&|m| m.has_sheen() && (m.sheen_color_texture.is_some() || m.sheen_roughness_texture.is_some()));
        let iridescence_textures = vertex_attributes
            && any_mat(&|m| {
                m.has_iridescence() && (m.iridescence_texture.is_some() || m.iridescence_thickness_texture.is_some())
            });
        let anisotropy = tangents && any_mat(&|m| m.has_anisotropy());
        let diffuse_transmission_textures = vertex_attributes
            && any_mat(&|m| {
                m.has_diffuse_transmission()
                    && m.diffuse_transmission
                        .as_deref()
                        .is_some_and(|d| d.texture.is_some() || d.color_texture.is_some())
            });
        let transmission_textured = |m: &crate::scene::Material| {
            m.is_dielectric() && m.layer_textures.as_deref().is_some_and(|l| l.transmission.is_some())
        };
        let transmission_textures = vertex_attributes && any_mat(&transmission_textured);
        let specular_textures = vertex_attributes
            && any_mat(&|m| {
                m.layer_textures.as_deref().is_some_and(|l| l.specular.is_some() || l.specular_color.is_some())
            });
        // A transmission texture can give clear glass's points the lobes of its factors.
        let glass_lobes = |m: &crate::scene::Material, f: &dyn Fn(&crate::scene::LayerTextures) -> bool| {
            transmission_textures && transmission_textured(m) && m.layer_textures.as_deref().is_some_and(f)
        };
        // A metallic-roughness texture can give a point the lobes its factors lack: diffuse
        // where the base is not black (metallic below 1), GGX where base or dielectric is not.
        let textured = |m: &crate::scene::Material, f: &dyn Fn(&crate::scene::MetallicRoughnessTexture) -> bool| {
            metallic_roughness_textures && m.metallic_roughness_texture.as_ref().is_some_and(f)
        };
        // A lobe counts where it has weight (clear glass's other lobes have none).
        let lobe = |m: &crate::scene::Material, c: Vec3| m.lobes_weight() > 0.0 && nonzero(c);
        let g = generic;
        FeatureSet {
            generic,
            count_rays: false,
            diffuse: g
                || any_mat(&|m| {
                    lobe(m, m.diffuse) || textured(m, &|t| nonzero(t.base)) || glass_lobes(m, &|l| nonzero(l.base))
                }),
            phong: g || any_mat(&|m| lobe(m, m.phong)),
            ggx: g
                || any_mat(&|m| {
                    lobe(m, m.glossy)
                        || textured(m, &|t| nonzero(t.base) || nonzero(t.dielectric_f0))
                        || glass_lobes(m, &|l| nonzero(l.base) || nonzero(l.dielectric_f0))
                }),
            mirror: g || any_mat(&|m| nonzero(m.mirror)),
            // The kernels treat every IOR that is not negative (NaN included) as a dielectric.
            dielectric: g || any_mat(&|m| m.is_dielectric()),
            partial_transmission: g || transmission_textures || any_mat(&|m| m.has_partial_transmission()),
            rough_dielectric: g || any_mat(&|m| m.is_rough_dielectric()),
            volume: g || any_mat(&|m| nonzero(m.medium_attenuation())),
            clearcoat: g || any_mat(&|m| m.clearcoat > 0.0),
            clearcoat_textures: g || clearcoat_textures,
            clearcoat_normal_maps: g || clearcoat_normal_maps,
            sheen: g || any_mat(&|m| m.has_sheen()),
            sheen_textures: g || sheen_textures,
            iridescence: g || any_mat(&|m| m.has_iridescence()),
            iridescence_textures: g || iridescence_textures,
            anisotropy: g || anisotropy,
            diffuse_transmission: g || any_mat(&|m| m.has_diffuse_transmission()),
            diffuse_transmission_textures: g || diffuse_transmission_textures,
            dispersion: g || any_mat(&|m| m.has_dispersion()),
            area_lights: g || any_light(&|l| matches!(l, Light::Area { .. })),
            point_lights: g || any_light(&|l| matches!(l, Light::Point { .. })),
            spot_lights: g || any_light(&|l| matches!(l, Light::Spot { .. })),
            directional_lights: g || any_light(&|l| matches!(l, Light::Directional { .. })),
            background: g || any_light(&Light::is_environment),
            environment_map: g || any_light(&|l| matches!(l, Light::Environment(_))),
            spheres: g || !scene.spheres.is_empty(),
            instances: g || !scene.instances.is_empty(),
            shading_normals: g || scene_has_shading_normals || normal_maps || clearcoat_normal_maps,
            scene_has_shading_normals,
            vertex_attributes: g || vertex_attributes,
            textures: g
                || (vertex_attributes && any_mat(&|m| m.base_color_texture.is_some()))
                || normal_maps
                || clearcoat_normal_maps
                || emissive_textures
                || metallic_roughness_textures
                || clearcoat_textures
                || sheen_textures
                || iridescence_textures
                || (anisotropy && any_mat(&|m| m.has_anisotropy() && m.anisotropy_texture.is_some()))
                || diffuse_transmission_textures
                || transmission_textures
                || specular_textures,
            alpha_mask: g || any_mat(&|m| m.alpha_mode != crate::scene::AlphaMode::Opaque),
            one_sided: g || any_mat(&|m| m.one_sided),
            normal_maps: g || normal_maps,
            emissive_textures: g || emissive_textures,
            metallic_roughness_textures: g || metallic_roughness_textures,
            transmission_textures: g || transmission_textures,
            specular_textures: g || specular_textures,
        }
    }

    /// Also compile the ray counter in (`--profile`).
    pub fn with_count_rays(mut self, on: bool) -> FeatureSet {
        self.count_rays = on;
        self
    }

    /// The `#define`s of every render kernel (glsl/features.glsl; BVH_NO_SPHERES and
    /// BVH_INSTANCES for glsl/bvh.glsl).
    pub fn defines(&self) -> Defines {
        let mut d = Defines::new();
        for (name, on) in [
            ("HAS_DIFFUSE", self.diffuse),
            ("HAS_PHONG", self.phong),
            ("HAS_GGX", self.ggx),
            ("HAS_MIRROR", self.mirror),
            ("HAS_DIELECTRIC", self.dielectric),
            ("HAS_PARTIAL_TRANSMISSION", self.partial_transmission),
            ("HAS_ROUGH_DIELECTRIC", self.rough_dielectric),
            ("HAS_VOLUME", self.volume),
            ("HAS_CLEARCOAT", self.clearcoat),
            ("HAS_CLEARCOAT_TEXTURES", self.clearcoat_textures),
            ("HAS_CLEARCOAT_NORMAL_MAPS", self.clearcoat_normal_maps),
            ("HAS_SHEEN", self.sheen),
            ("HAS_SHEEN_TEXTURES", self.sheen_textures),
            ("HAS_IRIDESCENCE", self.iridescence),
            ("HAS_IRIDESCENCE_TEXTURES", self.iridescence_textures),
            ("HAS_ANISOTROPY", self.anisotropy),
            ("HAS_DIFFUSE_TRANSMISSION", self.diffuse_transmission),
            ("HAS_DIFFUSE_TRANSMISSION_TEXTURES", self.diffuse_transmission_textures),
            ("HAS_DISPERSION", self.dispersion),
            ("HAS_AREA_LIGHTS", self.area_lights),
            ("HAS_POINT_LIGHTS", self.point_lights),
            ("HAS_SPOT_LIGHTS", self.spot_lights),
            ("HAS_DIRECTIONAL_LIGHTS", self.directional_lights),
            ("HAS_BACKGROUND", self.background),
            ("HAS_ENVIRONMENT_MAP", self.environment_map),
            ("HAS_SPHERES", self.spheres),
            ("HAS_SHADING_NORMALS", self.shading_normals),
            ("HAS_VERTEX_ATTRIBUTES", self.vertex_attributes),
            ("HAS_TEXTURES", self.textures),
            ("HAS_ALPHA_MASK", self.alpha_mask),
            ("HAS_ONE_SIDED", self.one_sided),
            ("HAS_NORMAL_MAPS", self.normal_maps),
            ("HAS_EMISSIVE_TEXTURES", self.emissive_textures),
            ("HAS_METALLIC_ROUGHNESS_TEXTURES", self.metallic_roughness_textures),
            ("HAS_TRANSMISSION_TEXTURES", self.transmission_textures),
            ("HAS_SPECULAR_TEXTURES", self.specular_textures),
            ("COUNT_RAYS", self.count_rays),
        ] {
            d = d.flag(name, on);
        }
        if !self.spheres {
            d = d.value("BVH_NO_SPHERES", 1);
        }
        if self.instances {
            d = d.value("BVH_INSTANCES", 1);
        }
        d
    }
}

fn list(items: &[(&str, bool)]) -> String {
    let on: Vec<&str> = items.iter().filter(|(_, b)| *b).map(|(n, _)| *n).collect();
    let off: Vec<&str> = items.iter().filter(|(_, b)| !*b).map(|(n, _)| *n).collect();
    let mut s = if on.is_empty() { "none".to_string() } else { on.join(", ") };
    if !off.is_empty() {
        s += &format!(" (compiled out: {})", off.join(", "));
    }
    s
}

impl fmt::Display for FeatureSet {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let variant = if self.generic { "generic (--generic: every feature compiled in)" } else { "specialised" };
        writeln!(f, "kernels: {variant}")?;
        let mats = [
            ("diffuse", self.diffuse),
            ("phong", self.phong),
            ("ggx", self.ggx),
            ("mirror", self.mirror),
            ("dielectric", self.dielectric),
            ("partial transmission", self.partial_transmission),
            ("rough dielectric", self.rough_dielectric),
            ("absorbing volume", self.volume),
            ("clear coat", self.clearcoat),
            ("sheen", self.sheen),
            ("iridescence", self.iridescence),
            ("anisotropic GGX", self.anisotropy),
            ("diffuse transmission", self.diffuse_transmission),
            ("dispersion", self.dispersion),
        ];
        writeln!(f, "  materials: {}", list(&mats))?;
        let lights = [
            ("area", self.area_lights),
            ("point", self.point_lights),
            ("spot", self.spot_lights),
            ("directional", self.directional_lights),
            ("background", self.background),
            ("environment map", self.environment_map),
        ];
        writeln!(f, "  lights: {}", list(&lights))?;
        writeln!(
            f,
            "  geometry: {}",
            list(&[("triangles", true), ("spheres", self.spheres), ("instances", self.instances)])
        )?;
        let normals = match (self.scene_has_shading_normals, self.shading_normals) {
            (true, _) => "interpolated (smooth shading)",
            (false, true) => "compiled in, none in the scene (flat shading)",
            (false, false) => "none in the scene (flat shading)",
        };
        writeln!(f, "  shading normals: {normals}")?;
        let surface = [
            ("vertex colours / texture coordinates", self.vertex_attributes),
            ("base-colour textures", self.textures),
            ("alpha cut-outs / blending", self.alpha_mask),
            ("one-sided surfaces", self.one_sided),
            ("normal maps", self.normal_maps),
            ("emissive textures", self.emissive_textures),
            ("metallic-roughness textures", self.metallic_roughness_textures),
            ("clear-coat textures", self.clearcoat_textures),
            ("clear-coat normal maps", self.clearcoat_normal_maps),
            ("sheen textures", self.sheen_textures),
            ("iridescence textures", self.iridescence_textures),
            ("diffuse-transmission textures", self.diffuse_transmission_textures),
            ("transmission textures", self.transmission_textures),
            ("specular textures", self.specular_textures),
        ];
        writeln!(f, "  surface detail: {}", list(&surface))?;
        write!(f, "  ray counter: {}", if self.count_rays { "on (--profile)" } else { "off" })
    }
}

/// `(name, bytes)` of buffers as a table with MiB, and the total.
pub fn buffer_table(buffers: &[(String, u64)]) -> String {
    let w = buffers.iter().map(|(n, _)| n.len()).max().unwrap_or(6).max(6);
    let mib = |b: u64| b as f64 / (1024.0 * 1024.0);
    let mut s = format!("  {:<w$} {:>10}\n", "buffer", "MiB");
    for (n, b) in buffers {
        s += &format!("  {n:<w$} {:>10.3}\n", mib(*b));
    }
    let total: u64 = buffers.iter().map(|(_, b)| b).sum();
    s += &format!("  {:<w$} {:>10.3}\n", "total", mib(total));
    s
}
