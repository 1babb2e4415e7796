//! Light sources: one area light per emitting triangle, `KHR_lights_punctual` lights and
//! vkvcm's `VKVCM_background`.

use super::extensions::{ext_vec3, non_negative, EXT_BACKGROUND};
use super::Importer;
use crate::scene::Light;
use anyhow::{bail, Result};
use glam::{Mat4, Vec3};

impl Importer<'_> {
    /// Adds a `KHR_lights_punctual` light placed by `world` (it shines along the node's
    /// -Z); color * intensity becomes the intensity (point, spot) or irradiance
    /// (directional). Lights are kept aside and appended by [`Importer::collect_lights`].
    pub(super) fn add_light(
        &mut self,
        light: &gltf::khr_lights_punctual::Light,
        world: Mat4,
        label: &str,
    ) -> Result<()> {
        use gltf::khr_lights_punctual::Kind;
        let li = light.index();
        let power = Vec3::from_array(light.color()) * light.intensity();
        if !power.is_finite() || power.min_element() < 0.0 {
            bail!("light {li}: color * intensity must be finite and non-negative, is {power}");
        }
        if light.range().is_some() {
            self.warnings.warn(
                "light range is ignored (lights fall off with the inverse square law only)",
                format!("light {li} on {label}"),
            );
        }
        let position = world.transform_point3(Vec3::ZERO);
        let direction = world.transform_vector3(Vec3::NEG_Z).normalize();
        let l = match light.kind() {
            Kind::Point => Light::Point { position, intensity: power },
            Kind::Spot { inner_cone_angle, outer_cone_angle } => {
                if !direction.is_finite() {
                    bail!("light {li} on {label}: degenerate node orientation");
                }
                Light::Spot {
                    position,
                    direction,
                    intensity: power,
                    cos_inner: inner_cone_angle.cos(),
                    cos_outer: outer_cone_angle.cos(),
                }
            }
            Kind::Directional => {
                if !direction.is_finite() {
                    bail!("light {li} on {label}: degenerate node orientation");
                }
                Light::Directional { direction, irradiance: power }
            }
        };
        self.punctual.push(l);
        Ok(())
    }

    /// The scene's light list, in this order: area lights (in triangle order), punctual
    /// lights (in node order), the background. Emissive spheres are not light sources (a
    /// warning); a scene without any light gets a warning.
    pub(super) fn collect_lights(&mut self) -> Result<()> {
        for (i, t) in self.scene.triangles.iter().enumerate() {
            let e = self.scene.materials[t.material as usize].emission;
            if e.max_element() > 0.0 {
                self.scene.lights.push(Light::Area { triangle: i as u32, radiance: e });
            }
        }
        for s in &self.scene.spheres {
            let m = &self.scene.materials[s.material as usize];
            if m.emission.max_element() > 0.0 {
                self.warnings.warn(
                    "emissive spheres are not light sources (emission on spheres is ignored for lighting)",
                    format!("material {}", m.name),
                );
            }
        }
        self.scene.lights.append(&mut self.punctual);
        if let Some(bg) = self.doc.extensions().and_then(|e| e.get(EXT_BACKGROUND)) {
            let ctx = format!("extensions.{EXT_BACKGROUND}");
            let radiance = non_negative(ext_vec3(bg, "radiance", Vec3::ZERO, &ctx)?, &ctx)?;
            self.scene.lights.push(Light::Background { radiance });
        }
        if self.scene.lights.is_empty() {
            // A file without lights is lit as glTF viewers light it by default.
            self.warnings.warn("no light source: a uniform white sky (background radiance 1) lights the scene", "");
            self.scene.lights.push(Light::Background { radiance: Vec3::ONE });
        }
        Ok(())
    }
}
