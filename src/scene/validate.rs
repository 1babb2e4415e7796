//! Checks of a loaded [`Scene`] beyond the file format: can it be rendered at all
//! ([`check_renderable`], an error), and is the camera plausibly placed
//! ([`camera_warnings`], warnings). Rules and reasons: docs/robustness.md, "Input
//! validation".

use super::{Light, Scene};
use anyhow::{bail, Result};
use glam::Vec3;

/// The most materials a scene may have: a light vertex packs its material index into 23
/// bits beside its flags (glsl/light_vertex_store.glsl, `lv_info`).
pub const MAX_MATERIALS: usize = 1 << 23;

/// Refuses a scene that every estimator would render black or cannot render: no light
/// source with non-zero power (emissive triangles, punctual lights, `VKVCM_background`, `VKVCM_environment`;
/// emissive spheres do not count, they are not lights), or no geometry (no triangle and
/// no sphere; the renderer needs a BVH), or more than [`MAX_MATERIALS`] materials.
/// [`super::load_named_with`] applies it;
/// [`super::load_with`] does not, so tools and tests can still inspect such files.
pub fn check_renderable(scene: &Scene) -> Result<()> {
    let powered = |l: &Light| match l {
        Light::Area { radiance, .. } => radiance.max_element() > 0.0,
        Light::Point { intensity, .. } | Light::Spot { intensity, .. } => intensity.max_element() > 0.0,
        Light::Directional { irradiance, .. } => irradiance.max_element() > 0.0,
        Light::Background { radiance } => radiance.max_element() > 0.0,
        Light::Environment(e) => e.scale.max_element() > 0.0 && e.map.texels.iter().any(|t| t.iter().any(|&c| c > 0.0)),
    };
    if scene.triangles.is_empty() && scene.spheres.is_empty() {
        let skipped = scene.report.degenerate_triangles;
        let note = if skipped > 0 { format!("; {skipped} degenerate triangle(s) were skipped") } else { String::new() };
        bail!("no geometry: the scene has no triangle and no sphere to render{note}");
    }
    if scene.materials.len() > MAX_MATERIALS {
        bail!("too many materials: {} (at most {MAX_MATERIALS})", scene.materials.len());
    }
    if !scene.lights.iter().any(powered) {
        let why = if scene.lights.is_empty() {
            "no emissive material, KHR_lights_punctual light, VKVCM_background or VKVCM_environment"
        } else {
            "every light has zero power"
        };
        bail!("no emitter: the image would be black ({why})");
    }
    Ok(())
}

/// Warnings (kind, detail) when the camera looks like it sits inside geometry:
/// * strictly inside an opaque sphere (exact test; a dielectric sphere is fine, the
///   camera then looks out through glass);
/// * every one of a 5x5 grid of rays through the (square) image first hits the *back* of
///   a triangle (geometric normal pointing away from the camera) or of a sphere: the
///   signature of a camera inside a closed, outward-facing mesh.
///
/// Warnings, not errors: vkvcm's opaque surfaces are two-sided, so a room modelled as an
/// outward-facing box still renders correctly from inside (only one-sided emitters facing
/// outward then light nothing the camera sees); the grid can also miss an opening.
pub fn camera_warnings(scene: &Scene) -> Vec<(String, String)> {
    let mut out = Vec::new();
    let cam = &scene.camera;
    let o = cam.position;
    let inside_sphere = |c: Vec3, r: f32| (o - c).length_squared() < r * r * (1.0 - 1e-5);
    for (k, s) in scene.spheres.iter().enumerate() {
        let opaque = scene.materials.get(s.material as usize).is_none_or(|m| m.ior < 0.0);
        if opaque && inside_sphere(s.center, s.radius) {
            out.push((
                "the camera is inside an opaque sphere (it sees only that sphere's inside)".to_string(),
                format!("sphere {k}, centre {}, radius {}", s.center, s.radius),
            ));
        }
    }
    if scene.triangles.is_empty() && scene.spheres.is_empty() {
        return out;
    }
    let right = cam.forward.cross(cam.up);
    let half = (cam.yfov * 0.5).tan();
    const N: usize = 5;
    let mut back = 0;
    for i in 0..N {
        for j in 0..N {
            let u = (i as f32 + 0.5) / N as f32 * 2.0 - 1.0;
            let v = (j as f32 + 0.5) / N as f32 * 2.0 - 1.0;
            let d = (cam.forward + (right * u + cam.up * v) * half).normalize_or_zero();
            if d == Vec3::ZERO {
                return out;
            }
            match first_hit_is_back(scene, o, d) {
                Some(true) => back += 1,
                _ => return out,
            }
        }
    }
    if back == N * N {
        out.push((
            "the camera seems to be inside closed geometry: all 25 test rays through the image hit the back of a surface first"
                .to_string(),
            format!("camera at {o}"),
        ));
    }
    out
}

/// Whether the nearest surface along `o + t d` (t > 0) is hit from behind; `None`: no hit.
/// Instanced meshes are not tested (the check is a hint, and instanced scenes are large).
/// Triangles by Moller-Trumbore ("Fast, Minimum Storage Ray/Triangle Intersection", 1997),
/// brute force (a one-off of 25 rays at load time).
fn first_hit_is_back(scene: &Scene, o: Vec3, d: Vec3) -> Option<bool> {
    let mut best = f32::INFINITY;
    let mut back = None;
    for t in scene.world_triangles() {
        let [p0, p1, p2] = t.p;
        let (e1, e2) = (p1 - p0, p2 - p0);
        let pv = d.cross(e2);
        let det = e1.dot(pv);
        if det.abs() < 1e-20 {
            continue;
        }
        let inv = 1.0 / det;
        let s = o - p0;
        let u = s.dot(pv) * inv;
        if !(0.0..=1.0).contains(&u) {
            continue;
        }
        let q = s.cross(e1);
        let v = d.dot(q) * inv;
        if v < 0.0 || u + v > 1.0 {
            continue;
        }
        let dist = e2.dot(q) * inv;
        if dist > 1e-6 && dist < best {
            best = dist;
            back = Some(d.dot(e1.cross(e2)) > 0.0);
        }
    }
    for s in &scene.spheres {
        let oc = o - s.center;
        let b = oc.dot(d);
        let c = oc.length_squared() - s.radius * s.radius;
        let disc = b * b - c;
        if disc < 0.0 {
            continue;
        }
        let sq = disc.sqrt();
        let dist = if -b - sq > 1e-6 { -b - sq } else { -b + sq };
        if dist > 1e-6 && dist < best {
            best = dist;
            back = Some(c < 0.0);
        }
    }
    back
}
