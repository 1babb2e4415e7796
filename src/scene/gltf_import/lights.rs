//! Light sources: one area light per emitting triangle, `KHR_lights_punctual` lights and
//! vkvcm's `VKVCM_background` and `VKVCM_environment`.

use std::sync::Arc;

use super::extensions::{ext_f32, ext_vec3, non_negative, EXT_BACKGROUND, EXT_ENVIRONMENT};
use super::{sources, Importer, LoadOptions};
use crate::scene::{EnvironmentLight, EnvironmentMap, Light};
use anyhow::{anyhow, bail, Context, Result};
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
    /// lights (in node order), the background (`options.environment`, else the file's).
    /// Emissive spheres are not light sources (a warning). Without punctual lights and an
    /// environment, `options.default_environment` is added; a scene still without any light
    /// gets a uniform white sky and a warning. `options.no_environment` adds none.
    pub(super) fn collect_lights(&mut self, options: &LoadOptions) -> Result<()> {
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
        let has_punctual = !self.punctual.is_empty();
        self.scene.lights.append(&mut self.punctual);
        if options.no_environment {
            return Ok(());
        }
        if let Some(env) = &options.environment {
            self.scene.lights.push(Light::Environment(env.clone()));
        } else {
            let ext = self.doc.extensions();
            let background = ext.and_then(|e| e.get(EXT_BACKGROUND));
            let environment = ext.and_then(|e| e.get(EXT_ENVIRONMENT));
            if background.is_some() && environment.is_some() {
                bail!("the file has both {EXT_BACKGROUND} and {EXT_ENVIRONMENT}; a scene has one background");
            }
            if let Some(bg) = background {
                let ctx = format!("extensions.{EXT_BACKGROUND}");
                let radiance = non_negative(ext_vec3(bg, "radiance", Vec3::ZERO, &ctx)?, &ctx)?;
                self.scene.lights.push(Light::Background { radiance });
            }
            if let Some(env) = environment {
                let light = self.environment_light(env)?;
                self.scene.lights.push(Light::Environment(light));
            }
        }
        let has_environment = self.scene.lights.iter().any(Light::is_environment);
        if let (Some(env), false, false) = (&options.default_environment, has_punctual, has_environment) {
            // Emissive surfaces alone leave most of a model (DamagedHelmet, ToyCar) black:
            // viewers add their environment to them too.
            let with = if self.scene.lights.is_empty() { "" } else { " together with its emissive surfaces" };
            self.scene.report.lighting_note = Some(format!(
                "the file has no punctual light and no environment: the built-in {} lights the scene{with} (--env studio|sky|FILE|none chooses another)",
                env.map.source
            ));
            self.scene.lights.push(Light::Environment(env.clone()));
        }
        if self.scene.lights.is_empty() {
            // A file without lights is lit as glTF viewers light it by default.
            self.warnings.warn("no light source: a uniform white sky (background radiance 1) lights the scene", "");
            self.scene.lights.push(Light::Background { radiance: Vec3::ONE });
        }
        Ok(())
    }

    /// `VKVCM_environment`: `{"uri": "sky.hdr", "strength": 1, "rotation": 0}`; the URI
    /// (a relative path inside the scene's folder or a data URI) names a Radiance HDR or
    /// OpenEXR lat-long map, `strength` scales it, `rotation` turns it about +Y in degrees.
    fn environment_light(&self, env: &serde_json::Value) -> Result<EnvironmentLight> {
        let ctx = format!("extensions.{EXT_ENVIRONMENT}");
        let uri = env
            .get("uri")
            .and_then(|u| u.as_str())
            .ok_or_else(|| anyhow!("{ctx}.uri must be a string (the environment map's file or data URI)"))?;
        let shown: String = if uri.starts_with("data:") { "data URI".into() } else { uri.into() };
        let bytes = sources::load_uri(uri, self.base_dir, "environment map").with_context(|| format!("{ctx}.uri"))?;
        let map = EnvironmentMap::decode(&bytes, &shown).with_context(|| format!("{ctx}.uri"))?;
        let strength = ext_f32(env, "strength", 1.0, &ctx)?;
        if strength < 0.0 {
            bail!("{ctx}.strength must not be negative, is {strength}");
        }
        let rotation_deg = ext_f32(env, "rotation", 0.0, &ctx)?;
        Ok(EnvironmentLight { map: Arc::new(map), scale: Vec3::splat(strength), rotation_deg })
    }
}
