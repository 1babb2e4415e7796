//! Cameras: the perspective cameras of the walked nodes and the choice of the one that is
//! rendered (by name, else the first in node order). Orthographic cameras are not
//! supported: skipped with a warning when the camera is chosen by default, an error when
//! `LoadOptions::camera` names one.

use super::{Importer, LoadOptions};
use crate::scene::Camera;
use anyhow::{anyhow, bail, Result};
use glam::{DMat4, DVec3, Mat4, Vec3};

/// A perspective camera met during the node walk.
pub(super) struct CameraCandidate {
    node_name: Option<String>,
    camera_name: Option<String>,
    /// The node's world transform (re-centred, f32).
    world: Mat4,
    yfov: f32,
    /// glTF's `aspectRatio` (width / height), when given.
    aspect: Option<f32>,
    /// The node's index.
    node: usize,
}

impl Importer<'_> {
    /// Records the camera `cam` of `node` (placed by `world`) as a candidate; orthographic
    /// cameras are skipped with a warning.
    pub(super) fn add_camera(&mut self, node: &gltf::Node, cam: &gltf::Camera, world: Mat4, label: &str) {
        match cam.projection() {
            gltf::camera::Projection::Perspective(p) => self.cameras.push(CameraCandidate {
                node_name: node.name().map(str::to_string),
                camera_name: cam.name().map(str::to_string),
                world,
                yfov: p.yfov(),
                aspect: p.aspect_ratio(),
                node: node.index(),
            }),
            gltf::camera::Projection::Orthographic(_) => {
                self.orthographic.push((node.name().map(str::to_string), cam.name().map(str::to_string), node.index()));
                self.warnings.warn(
                    "orthographic cameras are not supported (skipped)",
                    format!("camera {} on {label}", cam.index()),
                )
            }
        }
    }

    /// The rendered camera: the candidate whose node or camera name is `options.camera`,
    /// else the first one, else (no camera in the file) a default camera framing the
    /// geometry ([`Camera::framing`], with a warning). Its up vector is made orthogonal to
    /// its forward vector; a degenerate transform or a yfov outside (0, pi) is an error, and
    /// so is a name that matches no perspective camera (the message says when it names an
    /// orthographic one, and lists the perspective cameras).
    pub(super) fn choose_camera(&mut self, options: &LoadOptions) -> Result<Camera> {
        let chosen = match &options.camera {
            // `--camera auto`: the framing camera, whatever cameras the file has.
            Some(want) if want == AUTO_CAMERA => return self.framing_camera(),
            Some(want) => self
                .cameras
                .iter()
                .find(|c| {
                    c.node_name.as_deref() == Some(want.as_str()) || c.camera_name.as_deref() == Some(want.as_str())
                })
                .ok_or_else(|| {
                    let names: Vec<String> = self
                        .cameras
                        .iter()
                        .map(|c| {
                            c.node_name.clone().or(c.camera_name.clone()).unwrap_or_else(|| format!("node {}", c.node))
                        })
                        .collect();
                    let names = if names.is_empty() { "none".to_string() } else { names.join(", ") };
                    let ortho = self.orthographic.iter().find(|(node_name, camera_name, _)| {
                        node_name.as_deref() == Some(want.as_str()) || camera_name.as_deref() == Some(want.as_str())
                    });
                    match ortho {
                        Some((_, _, node)) => anyhow!(
                            "camera '{want}' (node {node}) is orthographic: orthographic cameras are not supported (perspective cameras: {names})"
                        ),
                        None => anyhow!(
                            "no perspective camera named '{want}' (available: {names}; or {AUTO_CAMERA}, a camera that frames the scene)"
                        ),
                    }
                })?,
            None => {
                match self.cameras.first() {
                    Some(c) => c,
                    None => {
                        let camera = self.framing_camera()?;
                        self.warnings.warn(
                        "no perspective camera: a default camera frames the scene (from the front, +Z, turned 30 degrees right and 20 degrees up, 40-degree field of view; --look-from, --look-at, --fov change it)",
                        "",
                    );
                        return Ok(camera);
                    }
                }
            }
        };
        let w = chosen.world;
        let position = w.transform_point3(Vec3::ZERO);
        let forward = w.transform_vector3(Vec3::NEG_Z).normalize();
        let up_raw = w.transform_vector3(Vec3::Y);
        let up = (up_raw - forward * forward.dot(up_raw)).normalize();
        if !(position.is_finite() && forward.is_finite() && up.is_finite()) {
            bail!("camera node {} has a degenerate world transform", chosen.node);
        }
        if !(chosen.yfov > 0.0 && chosen.yfov < std::f32::consts::PI) {
            bail!("camera node {}: yfov {} is not in (0, pi)", chosen.node, chosen.yfov);
        }
        let aspect = chosen.aspect.filter(|a| *a > 0.0 && a.is_finite());
        if let Some(a) = chosen.aspect.filter(|a| !(*a > 0.0 && a.is_finite())) {
            bail!("camera node {}: aspectRatio {a} is not a positive number", chosen.node);
        }
        self.scene.report.camera_aspect = aspect;
        Ok(Camera { position, forward, up, yfov: chosen.yfov })
    }

    /// The camera that frames the scene's geometry ([`Camera::framing`]).
    fn framing_camera(&self) -> Result<Camera> {
        let (c, r) = self.scene.bounding_sphere();
        Camera::framing(c, r).ok_or_else(|| {
            anyhow!("no perspective camera in the default scene, and no geometry for a default camera to frame")
        })
    }
}

/// `--camera auto` (`LoadOptions::camera`): frame the scene even when the file has cameras.
pub const AUTO_CAMERA: &str = "auto";

/// World position of the camera the importer will choose (the one named `want`, else the
/// first perspective camera in traversal order), or the origin when there is none: the
/// scene is translated so that this point becomes (0, 0, 0). `order` is the node walk with
/// f64 world transforms, before re-centring.
pub(super) fn camera_origin(order: &[(gltf::Node, DMat4)], want: Option<&str>) -> DVec3 {
    let is_persp =
        |n: &gltf::Node| n.camera().is_some_and(|c| matches!(c.projection(), gltf::camera::Projection::Perspective(_)));
    let matches = |n: &gltf::Node| match want {
        None => true,
        Some(w) => n.name() == Some(w) || n.camera().and_then(|c| c.name().map(str::to_string)).as_deref() == Some(w),
    };
    order
        .iter()
        .find(|(n, _)| is_persp(n) && matches(n))
        .map(|(_, w)| w.transform_point3(DVec3::ZERO))
        .filter(|p| p.is_finite())
        .unwrap_or(DVec3::ZERO)
}
