//! glTF materials mapped to vkvcm's material model: metallic/roughness to diffuse + GGX
//! (+ mirror), `KHR_materials_transmission`/`KHR_materials_ior` to smooth or rough glass
//! (beside diffuse + GGX where it transmits partially),
//! `KHR_materials_emissive_strength`, `KHR_materials_volume` (absorption inside
//! transmissive meshes), `KHR_materials_clearcoat`, and vkvcm's own `VKVCM_materials_phong`.

use super::extensions::{
    ext_f32, ext_vec3, material_extension, non_negative, EXT_MATERIALS_PHONG, KHR_MATERIALS_ANISOTROPY,
    KHR_MATERIALS_CLEARCOAT, KHR_MATERIALS_DIFFUSE_TRANSMISSION, KHR_MATERIALS_DISPERSION, KHR_MATERIALS_IRIDESCENCE,
    KHR_MATERIALS_SHEEN,
};
use super::Importer;
use crate::scene::{AlphaMode, DiffuseTransmission, LayerTextures, Material, GLTF_DIELECTRIC_F0};
use anyhow::{bail, Result};
use glam::Vec3;

/// The attenuation coefficient (per unit length) of a channel that KHR_materials_volume's
/// attenuationColor makes black: finite (exp(-0 x it) stays 1 for a segment of length 0),
/// and large enough that any segment longer than 1e-25 transmits nothing.
pub const MAX_ATTENUATION: f32 = 1e30;

/// Which of a material's textures its mapping reads (the others are warned of).
#[derive(Clone, Copy, Default)]
struct TexturesRead {
    base_color: bool,
    metallic_roughness: bool,
}

/// The alpha and alpha mode of `m` whose baseColorFactor alpha is `factor`. glTF 2.0
/// section 3.9.4 ("Alpha Coverage"): alpha = baseColorFactor alpha (times the texture's
/// and COLOR_0's); OPAQUE ignores it, MASK cuts out where it is below alphaCutoff
/// (default 0.5), BLEND composites: here stochastically, each ray meeting the surface
/// with probability alpha (alphaCutoff is ignored, per spec).
fn alpha(m: &gltf::Material, factor: f32, label: &str) -> Result<(f32, AlphaMode)> {
    let mode = match m.alpha_mode() {
        gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
        gltf::material::AlphaMode::Mask => {
            let cutoff = m.alpha_cutoff().unwrap_or(0.5);
            if !(cutoff >= 0.0 && cutoff.is_finite()) {
                bail!("{label}: alphaCutoff {cutoff} must be a finite number >= 0");
            }
            AlphaMode::Mask { cutoff }
        }
        gltf::material::AlphaMode::Blend => AlphaMode::Blend,
    };
    Ok((factor.clamp(0.0, 1.0), mode))
}

impl Importer<'_> {
    /// Index of glTF's default material (for primitives and spheres without one), added
    /// to the scene's materials on first use.
    pub(super) fn default_material(&mut self) -> u32 {
        if let Some(i) = self.default_material {
            return i;
        }
        // glTF's default material: baseColor 1, metallic 1, roughness 1, one-sided.
        let mut m = Material::metallic_roughness(Vec3::ONE, 1.0, 1.0);
        m.name = "gltf-default".into();
        m.one_sided = true;
        let i = self.scene.materials.len() as u32;
        self.scene.materials.push(m);
        self.default_material = Some(i);
        i
    }

    /// The vkvcm material of `m`: `VKVCM_materials_phong` if present, else for a
    /// transmissive material that is not fully metallic glass of the material's roughness,
    /// beside metallic/roughness lobes where it transmits partially
    /// ([`Material::transmissive`]), else the metallic/roughness mapping; the base colour
    /// may come from `baseColorTexture`, and on the metallic/roughness mapping metallic
    /// and roughness may vary by `metallicRoughnessTexture`; plus emission (with `emissiveTexture`), alpha and the
    /// alpha mode. The other textures are reported as warnings (the constant factors are
    /// used).
    pub(super) fn convert_material(&mut self, m: &gltf::Material) -> Result<Material> {
        let index = m.index().unwrap_or(0);
        let name = m.name().map(str::to_string).unwrap_or_else(|| format!("material{index}"));
        let label = format!("material {index} '{name}'");
        let pbr = m.pbr_metallic_roughness();
        let bc = pbr.base_color_factor();
        let base = Vec3::new(bc[0], bc[1], bc[2]).clamp(Vec3::ZERO, Vec3::ONE);
        let metallic = pbr.metallic_factor().clamp(0.0, 1.0);
        let roughness = pbr.roughness_factor().clamp(0.0, 1.0);

        let phong_ext = m.extensions().and_then(|e| e.get(EXT_MATERIALS_PHONG));
        let mut read = TexturesRead::default();
        let mut out = if let Some(v) = phong_ext {
            self.phong_material(v, index, &label)?
        } else if let Some(t) = m.transmission().filter(|t| t.transmission_factor() > 0.0 && metallic < 1.0) {
            // Glass of weight (1 - metallic) transmission beside the metallic/roughness
            // lobes (Material::transmissive). Its transmitted part and the lobes are tinted
            // by the base colour, and so by baseColorTexture where a triangle has its
            // coordinates; its reflection is not.
            let ior = ior(m, &label)?.unwrap_or(1.5);
            let dielectric_f0 = self.dielectric_f0(m, &label)?;
            let mut glass =
                Material::transmissive(base, metallic, roughness, t.transmission_factor(), ior, dielectric_f0);
            if let Some(info) = pbr.base_color_texture() {
                glass.base_color_texture = self.base_color_texture(&info, &label)?;
                read.base_color = true;
            }
            let transmission = match t.transmission_texture() {
                Some(info) => self.info_texture(&info, &label, "KHR_materials_transmission.transmissionTexture")?,
                None => None,
            };
            let factors =
                LayerTextures { transmission, base, metallic, roughness, dielectric_f0, ..Default::default() };
            glass.layer_textures = self.layer_textures(m, factors, &label)?;
            glass
        } else {
            self.metallic_roughness_material(m, base, metallic, roughness, &mut read, &label)?
        };
        self.warn_unread_textures(m, phong_ext.is_some(), read, &label);

        // The normal map bends the shading normal of every lobe, so it applies to every
        // material kind but the VKVCM_materials_phong one (SmallVCM's exact materials).
        if let (Some(info), None) = (m.normal_texture(), phong_ext) {
            if let Some((t, scale)) = self.normal_texture(&info, &label)? {
                out.normal_texture = Some(t);
                out.normal_scale = scale;
            }
        }
        (out.alpha, out.alpha_mode) = alpha(m, bc[3], &label)?;
        self.set_emission(m, &mut out, &label)?;
        if phong_ext.is_none() {
            self.set_clearcoat(m, &mut out, &label)?;
            self.set_sheen(m, &mut out, &label)?;
            self.set_iridescence(m, &mut out, &label)?;
            self.set_anisotropy(m, &mut out, &label)?;
            self.set_diffuse_transmission(m, &mut out, metallic, &label)?;
        }
        // Also on VKVCM_materials_phong's glass (an IOR >= 0), whose interface is the same.
        self.set_dispersion(m, &mut out, &label)?;
        // glTF's doubleSided false (the default) is back-face culling: the camera does not
        // see the back side of such a surface (glsl/scene.glsl, trace_camera_segment and
        // visible_to_camera; light meets both sides). A dielectric stays two-sided: its
        // refracted rays leave through the back side, and so does a diffuse transmission.
        out.one_sided = !m.double_sided() && out.ior < 0.0 && !out.has_diffuse_transmission();
        // KHR_materials_volume describes the inside of a transmissive mesh; on an opaque
        // material, or one that emits (whose surface bounds no medium:
        // Material::medium_attenuation), it has nothing to apply to.
        if out.ior >= 0.0 {
            out.attenuation = self.volume_attenuation(m, &label)?;
        }
        if m.volume().is_some() {
            if out.ior < 0.0 {
                self.warnings.warn("KHR_materials_volume without transmission is ignored", label.clone());
            } else if out.attenuation != Vec3::ZERO && out.emission != Vec3::ZERO {
                self.warnings.warn("KHR_materials_volume on an emissive material is ignored", label.clone());
            }
        }
        out.name = name;
        Ok(out)
    }

    /// The material of vkvcm's `VKVCM_materials_phong` extension `v` (SmallVCM's
    /// materials) on material `index`.
    fn phong_material(&mut self, v: &serde_json::Value, index: usize, label: &str) -> Result<Material> {
        let ctx = format!("materials[{index}].extensions.{EXT_MATERIALS_PHONG}");
        if !v.is_object() {
            bail!("{ctx} must be an object");
        }
        let c = |f: &str| -> Result<Vec3> { non_negative(ext_vec3(v, f, Vec3::ZERO, &ctx)?, &format!("{ctx}.{f}")) };
        let exponent = ext_f32(v, "exponent", 1.0, &ctx)?;
        if exponent < 0.0 {
            bail!("{ctx}.exponent must not be negative");
        }
        let phong = Material {
            name: String::new(),
            diffuse: c("diffuse")?,
            phong: c("phong")?,
            phong_exponent: exponent,
            mirror: c("mirror")?,
            ior: ext_f32(v, "ior", -1.0, &ctx)?,
            emission: Vec3::ZERO,
            glossy: Vec3::ZERO,
            roughness: 1.0,
            ..Material::default()
        };
        // SmallVCM's glass is a mirror and an IOR; lobes beside it would need a glass
        // weight, which the extension does not have.
        if phong.is_dielectric() && (phong.diffuse != Vec3::ZERO || phong.phong != Vec3::ZERO) {
            self.warnings.warn(
                "the diffuse and phong lobes of a VKVCM_materials_phong dielectric (ior >= 0) are ignored",
                label,
            );
        }
        Ok(phong)
    }

    /// The metallic/roughness mapping of `m` (its factors, clamped: `base`, `metallic`,
    /// `roughness`), with its base colour and metallic-roughness textures.
    fn metallic_roughness_material(
        &mut self,
        m: &gltf::Material,
        base: Vec3,
        metallic: f32,
        roughness: f32,
        read: &mut TexturesRead,
        label: &str,
    ) -> Result<Material> {
        let pbr = m.pbr_metallic_roughness();
        if m.transmission().is_some_and(|t| t.transmission_factor() > 0.0) {
            // glTF: transmission replaces the dielectric part, which metallic 1 leaves none of.
            self.warnings.warn(
                "KHR_materials_transmission on a fully metallic material (metallicFactor 1, glTF's default) \
                 transmits nothing",
                label,
            );
        }
        let dielectric_f0 = self.dielectric_f0(m, label)?;
        // glTF 2.0 section 3.9.2: roughness = roughnessFactor x G, metallic =
        // metallicFactor x B of the metallicRoughnessTexture (linear).
        let texture = match pbr.metallic_roughness_texture() {
            Some(info) => {
                read.metallic_roughness = true;
                self.metallic_roughness_texture(&info, label)?
            }
            None => None,
        };
        let mut mr = match texture {
            Some(t) => Material::metallic_roughness_textured(base, metallic, roughness, dielectric_f0, t),
            None => Material::metallic_roughness_with_f0(base, metallic, roughness, dielectric_f0),
        };
        // A smooth metal (a mirror) has no dielectric part for the specular textures to vary.
        if mr.mirror == Vec3::ZERO {
            let factors = LayerTextures { base, metallic, roughness, dielectric_f0, ..Default::default() };
            mr.layer_textures = self.layer_textures(m, factors, label)?;
        }
        if let Some(info) = pbr.base_color_texture() {
            mr.base_color_texture = self.base_color_texture(&info, label)?;
            read.base_color = true;
        }
        Ok(mr)
    }

    /// Warns of the textures of `m` that are not read (`phong`: it is a
    /// `VKVCM_materials_phong` material); baseColorTexture and metallicRoughnessTexture
    /// only where the material's mapping did not use them (`read`).
    fn warn_unread_textures(&mut self, m: &gltf::Material, phong: bool, read: TexturesRead, label: &str) {
        let pbr = m.pbr_metallic_roughness();
        let mut textures = Vec::new();
        if pbr.base_color_texture().is_some() && !read.base_color {
            textures.push("baseColorTexture");
        }
        if pbr.metallic_roughness_texture().is_some() && !read.metallic_roughness {
            textures.push("metallicRoughnessTexture");
        }
        if m.normal_texture().is_some() && phong {
            textures.push("normalTexture");
        }
        // occlusionTexture is read silently as nothing: ambient occlusion is what light
        // transport computes from the geometry, and a baked map would darken it twice, so
        // there is nothing missing to warn about.
        // transmissionTexture is read wherever transmission applies (a material that is
        // not fully metallic); elsewhere, as its factor, it has nothing to vary.
        for t in textures {
            self.warnings.warn("textures are not supported (the constant factors are used)", format!("{label} {t}"));
        }
    }

    /// Sets the clear coat of `out` from `m`'s KHR_materials_clearcoat: clearcoatFactor and
    /// clearcoatRoughnessFactor (both default 0, clamped to [0, 1] as glTF's factors) and
    /// their textures, and clearcoatNormalTexture (with its `scale`, default 1).
    fn set_clearcoat(&mut self, m: &gltf::Material, out: &mut Material, label: &str) -> Result<()> {
        let Some((v, ctx)) = material_extension(m, KHR_MATERIALS_CLEARCOAT, label)? else {
            return Ok(());
        };
        out.clearcoat = ext_f32(v, "clearcoatFactor", 0.0, &ctx)?.clamp(0.0, 1.0);
        out.clearcoat_roughness = ext_f32(v, "clearcoatRoughnessFactor", 0.0, &ctx)?.clamp(0.0, 1.0);
        if let Some(info) = v.get("clearcoatTexture") {
            out.clearcoat_texture = self.json_texture(info, label, "KHR_materials_clearcoat.clearcoatTexture")?;
        }
        if let Some(info) = v.get("clearcoatRoughnessTexture") {
            let slot = "KHR_materials_clearcoat.clearcoatRoughnessTexture";
            out.clearcoat_roughness_texture = self.json_texture(info, label, slot)?;
        }
        if let Some(info) = v.get("clearcoatNormalTexture") {
            let slot = "KHR_materials_clearcoat.clearcoatNormalTexture";
            out.clearcoat_normal_texture = self.json_texture(info, label, slot)?;
            out.clearcoat_normal_scale = ext_f32(info, "scale", 1.0, &format!("{ctx}.clearcoatNormalTexture"))?;
        }
        Ok(())
    }

    /// Sets the sheen of `out` from `m`'s KHR_materials_sheen: sheenColorFactor (default
    /// black: no sheen) and sheenRoughnessFactor (default 0), clamped to [0, 1] as glTF's
    /// factors, and their textures.
    fn set_sheen(&mut self, m: &gltf::Material, out: &mut Material, label: &str) -> Result<()> {
        let Some((v, ctx)) = material_extension(m, KHR_MATERIALS_SHEEN, label)? else {
            return Ok(());
        };
        out.sheen_color = ext_vec3(v, "sheenColorFactor", Vec3::ZERO, &ctx)?.clamp(Vec3::ZERO, Vec3::ONE);
        out.sheen_roughness = ext_f32(v, "sheenRoughnessFactor", 0.0, &ctx)?.clamp(0.0, 1.0);
        if let Some(info) = v.get("sheenColorTexture") {
            out.sheen_color_texture = self.json_texture(info, label, "KHR_materials_sheen.sheenColorTexture")?;
        }
        if let Some(info) = v.get("sheenRoughnessTexture") {
            out.sheen_roughness_texture =
                self.json_texture(info, label, "KHR_materials_sheen.sheenRoughnessTexture")?;
        }
        Ok(())
    }

    /// Sets the thin film of `out` from `m`'s KHR_materials_iridescence: iridescenceFactor
    /// (default 0: none, clamped to [0, 1]), iridescenceIor (default 1.3, at least 1),
    /// iridescenceThicknessMinimum and Maximum (nm, default 100 and 400, not negative),
    /// and their textures. A smooth metal, a mirror in vkvcm's model (no Fresnel term to
    /// replace), becomes the GGX lobe of the smallest width with the mirror's colour as F0.
    fn set_iridescence(&mut self, m: &gltf::Material, out: &mut Material, label: &str) -> Result<()> {
        let Some((v, ctx)) = material_extension(m, KHR_MATERIALS_IRIDESCENCE, label)? else {
            return Ok(());
        };
        out.iridescence = ext_f32(v, "iridescenceFactor", 0.0, &ctx)?.clamp(0.0, 1.0);
        out.iridescence_ior = ext_f32(v, "iridescenceIor", 1.3, &ctx)?;
        if out.iridescence_ior < 1.0 {
            bail!("{ctx}.iridescenceIor must be at least 1, is {}", out.iridescence_ior);
        }
        let min = ext_f32(v, "iridescenceThicknessMinimum", 100.0, &ctx)?;
        let max = ext_f32(v, "iridescenceThicknessMaximum", 400.0, &ctx)?;
        non_negative(Vec3::new(min, max, 0.0), &format!("{ctx}'s thickness minimum and maximum"))?;
        (out.iridescence_thickness_min, out.iridescence_thickness_max) = (min, max);
        if let Some(info) = v.get("iridescenceTexture") {
            out.iridescence_texture = self.json_texture(info, label, "KHR_materials_iridescence.iridescenceTexture")?;
        }
        if let Some(info) = v.get("iridescenceThicknessTexture") {
            out.iridescence_thickness_texture =
                self.json_texture(info, label, "KHR_materials_iridescence.iridescenceThicknessTexture")?;
        }
        if out.has_iridescence() && out.ior < 0.0 && out.glossy == Vec3::ZERO && out.mirror != Vec3::ZERO {
            (out.glossy, out.roughness, out.mirror) = (out.mirror, 0.0, Vec3::ZERO);
        }
        Ok(())
    }

    /// Sets the anisotropy of `out`'s GGX lobe from `m`'s KHR_materials_anisotropy:
    /// anisotropyStrength (default 0, clamped to [0, 1]), anisotropyRotation (default 0)
    /// and anisotropyTexture. A smooth metal, a mirror otherwise, becomes a GGX lobe of
    /// the smallest width, which the anisotropy widens along its direction. The rough
    /// dielectric (transmission) and the clear coat stay isotropic (docs/scene-format.md).
    fn set_anisotropy(&mut self, m: &gltf::Material, out: &mut Material, label: &str) -> Result<()> {
        let Some((v, ctx)) = material_extension(m, KHR_MATERIALS_ANISOTROPY, label)? else {
            return Ok(());
        };
        out.anisotropy_strength = ext_f32(v, "anisotropyStrength", 0.0, &ctx)?.clamp(0.0, 1.0);
        out.anisotropy_rotation = ext_f32(v, "anisotropyRotation", 0.0, &ctx)?;
        if let Some(info) = v.get("anisotropyTexture") {
            out.anisotropy_texture = self.json_texture(info, label, "KHR_materials_anisotropy.anisotropyTexture")?;
        }
        if out.anisotropy_strength > 0.0 && out.ior < 0.0 && out.glossy == Vec3::ZERO && out.mirror != Vec3::ZERO {
            out.glossy = std::mem::take(&mut out.mirror);
            out.roughness = 0.0;
        }
        if out.anisotropy_strength > 0.0 && out.ior >= 0.0 {
            self.warnings.warn(
                "the transmitted and refracted light stays isotropic (the anisotropy applies to the reflection lobe)",
                &ctx,
            );
        }
        Ok(())
    }

    /// Sets the diffuse transmission of `out` from `m`'s KHR_materials_diffuse_transmission:
    /// diffuseTransmissionFactor (default 0: none) and diffuseTransmissionColorFactor
    /// (default white), clamped to [0, 1] as glTF's factors, and their textures. `metallic`
    /// is the material's metallic factor (its metal part transmits nothing). On a material
    /// with KHR_materials_transmission it is ignored with a warning.
    fn set_diffuse_transmission(
        &mut self,
        m: &gltf::Material,
        out: &mut Material,
        metallic: f32,
        label: &str,
    ) -> Result<()> {
        let Some((v, ctx)) = material_extension(m, KHR_MATERIALS_DIFFUSE_TRANSMISSION, label)? else {
            return Ok(());
        };
        let factor = ext_f32(v, "diffuseTransmissionFactor", 0.0, &ctx)?.clamp(0.0, 1.0);
        let color = ext_vec3(v, "diffuseTransmissionColorFactor", Vec3::ONE, &ctx)?.clamp(Vec3::ZERO, Vec3::ONE);
        let slot = |name: &str| format!("{KHR_MATERIALS_DIFFUSE_TRANSMISSION}.{name}");
        let mut texture = None;
        if let Some(info) = v.get("diffuseTransmissionTexture") {
            texture = self.json_texture(info, label, &slot("diffuseTransmissionTexture"))?;
        }
        let mut color_texture = None;
        if let Some(info) = v.get("diffuseTransmissionColorTexture") {
            color_texture = self.json_texture(info, label, &slot("diffuseTransmissionColorTexture"))?;
        }
        if out.is_dielectric() {
            if factor > 0.0 {
                self.warnings.warn(
                    "KHR_materials_diffuse_transmission beside KHR_materials_transmission is ignored (vkvcm \
                     transmits diffusely through opaque materials only)",
                    label,
                );
            }
            return Ok(());
        }
        out.diffuse_transmission =
            Some(Box::new(DiffuseTransmission { factor, color, metallic, texture, color_texture }));
        Ok(())
    }

    /// Sets the dispersion of `out` from `m`'s KHR_materials_dispersion: `dispersion`
    /// (20 / Abbe number, default 0: none; an error below 0 or not finite). The extension
    /// builds on KHR_materials_volume's refraction, which vkvcm's glass always has (a
    /// transmissive mesh is a closed volume: docs/scene-format.md), so it applies to every
    /// transmissive material, with KHR_materials_volume or without; on a material that does
    /// not transmit it is ignored with a warning. It applies to `VKVCM_materials_phong`'s
    /// glass too.
    fn set_dispersion(&mut self, m: &gltf::Material, out: &mut Material, label: &str) -> Result<()> {
        let Some((v, ctx)) = material_extension(m, KHR_MATERIALS_DISPERSION, label)? else {
            return Ok(());
        };
        let dispersion = ext_f32(v, "dispersion", 0.0, &ctx)?;
        if !(dispersion >= 0.0 && dispersion.is_finite()) {
            bail!("{ctx}.dispersion must be a finite number >= 0, is {dispersion}");
        }
        if dispersion > 0.0 && !out.is_dielectric() {
            self.warnings.warn(
                "KHR_materials_dispersion without KHR_materials_transmission is ignored (it disperses the \
                 refracted light)",
                label,
            );
            return Ok(());
        }
        out.dispersion = dispersion;
        Ok(())
    }

    /// Sets the emission of `out` from `m`'s emissive factor, strength and texture.
    fn set_emission(&mut self, m: &gltf::Material, out: &mut Material, label: &str) -> Result<()> {
        let strength = m.emissive_strength().unwrap_or(1.0);
        let ef = m.emissive_factor();
        out.emission = non_negative(Vec3::from_array(ef) * strength, &format!("{label} emission"))?;
        if !out.emission.is_finite() {
            bail!("{label}: emission is not finite");
        }
        // glTF: emitted radiance = emissiveFactor x emissiveTexture (x strength); the
        // factor defaults to 0, so a texture without a factor emits nothing.
        if let Some(info) = m.emissive_texture() {
            if out.emission != Vec3::ZERO {
                out.emissive_texture = self.emissive_texture(&info, label)?;
            }
        }
        Ok(())
    }

    /// The attenuation coefficient of KHR_materials_volume on a transmissive material
    /// (Beer-Lambert absorption, glTF KHR_materials_volume: light that travels
    /// attenuationDistance d inside the volume is tinted by attenuationColor c, so the
    /// coefficient is -ln(c) / d per channel). No extension, or d infinite (its default):
    /// zero. A channel with c = 0 absorbs everything: its coefficient is MAX_ATTENUATION,
    /// finite so that a segment of length 0 keeps exp(-0) = 1. thicknessFactor and
    /// thicknessTexture serve rasterisers that have no closed mesh to trace: ignored.
    fn volume_attenuation(&mut self, m: &gltf::Material, label: &str) -> Result<Vec3> {
        let Some(v) = m.volume() else { return Ok(Vec3::ZERO) };
        let d = v.attenuation_distance();
        let c = Vec3::from_array(v.attenuation_color());
        if d.is_nan() || d <= 0.0 {
            bail!("{label}: KHR_materials_volume attenuationDistance must be > 0, is {d}");
        }
        if !c.is_finite() || c.min_element() < 0.0 {
            bail!("{label}: KHR_materials_volume attenuationColor must be finite and >= 0, is {c}");
        }
        if d.is_infinite() {
            return Ok(Vec3::ZERO);
        }
        let c = c.min(Vec3::ONE);
        Ok(Vec3::from_array(c.to_array().map(|c| {
            if c > 0.0 {
                (-c.ln() / d).min(MAX_ATTENUATION)
            } else {
                MAX_ATTENUATION
            }
        })))
    }

    /// The F0 of the dielectric part of a metallic/roughness material: 0.04, or
    /// ((ior - 1) / (ior + 1))^2 with KHR_materials_ior, times KHR_materials_specular's
    /// specularColorFactor (the product clamped to 1) and specularFactor (the extension's
    /// `dielectric_f0`). Its f90 = specularFactor is taken as 1 (vkvcm's Schlick terms
    /// reach 1 at grazing angles), which is exact for specularFactor 0 and 1 and
    /// approximated, with a warning, in between; its textures are read by `layer_textures`.
    fn dielectric_f0(&mut self, m: &gltf::Material, label: &str) -> Result<Vec3> {
        let f0 = ior_f0(m, label)?;
        let Some(sp) = m.specular() else { return Ok(Vec3::splat(f0)) };
        let factor = sp.specular_factor();
        let color = Vec3::from_array(sp.specular_color_factor());
        if !(factor.is_finite() && factor >= 0.0 && color.is_finite() && color.min_element() >= 0.0) {
            bail!("{label}: KHR_materials_specular factors must be finite and >= 0");
        }
        let factor = factor.min(1.0);
        if factor > 0.0 && factor < 1.0 {
            self.warnings.warn(
                "KHR_materials_specular specularFactor between 0 and 1 scales F0 but not f90 (approximated)",
                label.to_string(),
            );
        }
        Ok((Vec3::splat(f0) * color).min(Vec3::ONE) * factor)
    }

    /// `factors` (a material's factors, and its transmissionTexture where the transmissive
    /// mapping read one) with `m`'s KHR_materials_specular specularTexture (A) and
    /// specularColorTexture (RGB, sRGB) and the factors they multiply; `None` without any
    /// of these textures.
    fn layer_textures(
        &mut self,
        m: &gltf::Material,
        factors: LayerTextures,
        label: &str,
    ) -> Result<Option<Box<LayerTextures>>> {
        let mut out = factors;
        // dielectric_f0 has checked the IOR and the factors.
        out.specular_f0 = Vec3::splat(ior_f0(m, label)?);
        out.specular_factor = 1.0;
        if let Some(sp) = m.specular() {
            if let Some(info) = sp.specular_texture() {
                out.specular = self.info_texture(&info, label, "KHR_materials_specular.specularTexture")?;
            }
            if let Some(info) = sp.specular_color_texture() {
                let slot = "KHR_materials_specular.specularColorTexture";
                out.specular_color = self.info_texture(&info, label, slot)?;
            }
            out.specular_f0 *= Vec3::from_array(sp.specular_color_factor());
            out.specular_factor = sp.specular_factor().min(1.0);
        }
        if out.transmission.is_none() && out.specular.is_none() && out.specular_color.is_none() {
            return Ok(None);
        }
        Ok(Some(Box::new(out)))
    }
}

/// The F0 of the material's IOR: 0.04, or ((ior - 1) / (ior + 1))^2 with KHR_materials_ior.
fn ior_f0(m: &gltf::Material, label: &str) -> Result<f32> {
    Ok(match ior(m, label)? {
        // 0.04 exactly (((1.5 - 1) / (1.5 + 1))^2 rounds to another f32).
        None => GLTF_DIELECTRIC_F0,
        Some(ior) => ((ior - 1.0) / (ior + 1.0)).powi(2),
    })
}

/// The material's KHR_materials_ior ior, if it has one; an error unless it is finite and
/// at least 1.
fn ior(m: &gltf::Material, label: &str) -> Result<Option<f32>> {
    match m.ior() {
        Some(ior) if !(ior >= 1.0 && ior.is_finite()) => {
            bail!("{label}: KHR_materials_ior ior = {ior} is not supported (need >= 1)")
        }
        other => Ok(other),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metallic_roughness_mapping() {
        let close = |a: Vec3, b: Vec3| (a - b).abs().max_element() < 1e-6;
        let m = Material::metallic_roughness(Vec3::splat(0.5), 0.0, 1.0);
        assert!(close(m.diffuse, Vec3::splat(0.5)));
        assert!(close(m.glossy, Vec3::splat(0.04)));
        assert_eq!(m.diffuse_fresnel_f0, 0.04);
        assert_eq!(m.roughness, 1.0);
        assert_eq!(m.phong, Vec3::ZERO);
        let m = Material::metallic_roughness(Vec3::new(1.0, 0.5, 0.25), 1.0, 0.0);
        assert_eq!(m.mirror, Vec3::new(1.0, 0.5, 0.25));
        assert_eq!(m.diffuse, Vec3::ZERO);
        assert_eq!(m.glossy, Vec3::ZERO);
        let m = Material::metallic_roughness(Vec3::new(1.0, 0.5, 0.25), 1.0, 0.5);
        assert!(close(m.glossy, Vec3::new(1.0, 0.5, 0.25)));
        assert_eq!(m.diffuse, Vec3::ZERO);
        assert_eq!(m.roughness, 0.5);
        let m = Material::metallic_roughness(Vec3::ONE, 0.5, 0.0);
        assert!(close(m.diffuse, Vec3::splat(0.5)));
        assert!(close(m.glossy, Vec3::splat(0.52)));
        assert_eq!(m.mirror, Vec3::ZERO);
        // The 0.04 default is KHR_materials_ior's default ior 1.5.
        assert_eq!(Material::metallic_roughness_with_f0(Vec3::splat(0.5), 0.25, 0.5, Vec3::splat(0.04)), {
            Material::metallic_roughness(Vec3::splat(0.5), 0.25, 0.5)
        });
        // No specular reflection (specularFactor 0): plain Lambert, no interface.
        let m = Material::metallic_roughness_with_f0(Vec3::splat(0.5), 0.0, 0.5, Vec3::ZERO);
        assert_eq!((m.glossy, m.diffuse_fresnel_f0, m.glossy_untinted), (Vec3::ZERO, 0.0, 0.0));
        // A coloured F0: the diffuse interface takes its largest component.
        let m = Material::metallic_roughness_with_f0(Vec3::splat(0.5), 0.0, 0.5, Vec3::new(0.08, 0.04, 0.0));
        assert_eq!(m.diffuse_fresnel_f0, 0.08);
        assert!(close(m.glossy, Vec3::new(0.08, 0.04, 0.0)));
    }
}
