//! Tangents for normal maps where a primitive has none: glTF 2.0 (section 3.7.2.1, "When
//! tangents are not specified, client implementations SHOULD calculate tangents using
//! default MikkTSpace algorithms with the specified vertex positions, normals, and texture
//! coordinates associated with the normal texture") — Morten Mikkelsen's MikkTSpace, by
//! the `bevy_mikktspace` crate, in world space.

use crate::scene::Triangle;
use anyhow::{anyhow, Result};
use glam::{Vec3, Vec4};

/// The triangles of one primitive (world space, each with attributes holding texture
/// coordinate set `set`) as MikkTSpace's geometry, and the tangents it writes back.
struct Faces<'a> {
    triangles: &'a [Triangle],
    set: usize,
    tangents: Vec<[Vec4; 3]>,
}

impl Faces<'_> {
    fn uv(&self, face: usize) -> [glam::Vec2; 3] {
        self.triangles[face].attributes.as_ref().and_then(|a| a.uv[self.set]).unwrap_or_default()
    }
}

impl bevy_mikktspace::Geometry for Faces<'_> {
    fn num_faces(&self) -> usize {
        self.triangles.len()
    }
    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }
    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        self.triangles[face].p[vert].to_array()
    }
    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        let t = &self.triangles[face];
        // Without vertex normals: the facet's (the shading normal is the geometric one).
        let n = t.n.map_or_else(|| (t.p[1] - t.p[0]).cross(t.p[2] - t.p[0]).normalize_or_zero(), |n| n[vert]);
        n.to_array()
    }
    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        // MikkTSpace's bitangent points towards increasing v of the coordinates it is
        // given, and a normal map's +Y is up in its image (glTF 2.0, material.normalTexture:
        // "+X is right and +Y is up"), which is decreasing v in glTF's coordinates (origin
        // at the image's top-left). So it is given v flipped, as the OpenGL-style texture
        // space normal maps are baked in: for an unmirrored layout the bitangent is then
        // cross(normal, tangent) (w = +1), as Mitsuba 3's normalmap and the glTF sample
        // viewer's derivative tangents have it.
        let [u, v] = self.uv(face)[vert].to_array();
        [u, 1.0 - v]
    }
    fn set_tangent(&mut self, tangent_space: Option<bevy_mikktspace::TangentSpace>, face: usize, vert: usize) {
        // A vertex MikkTSpace cannot give a tangent (degenerate texture coordinates) gets
        // none: the kernels then leave its shading normal unmapped.
        let t = tangent_space.map_or(Vec4::ZERO, |ts| Vec4::from_array(ts.tangent_encoded()));
        self.tangents[face][vert] = t;
    }
}

/// Writes MikkTSpace tangents into the attributes of `triangles` (one primitive's, all
/// with texture coordinate set `set`).
pub(super) fn generate(triangles: &mut [Triangle], set: usize) -> Result<()> {
    let mut faces = Faces { triangles, set, tangents: vec![[Vec4::ZERO; 3]; triangles.len()] };
    bevy_mikktspace::generate_tangents(&mut faces).map_err(|e| anyhow!("MikkTSpace: {e:?}"))?;
    let Faces { tangents, .. } = faces;
    for (t, tangent) in triangles.iter_mut().zip(tangents) {
        if let Some(a) = t.attributes.as_mut() {
            a.tangent = Some(tangent.map(|v| if v.truncate() == Vec3::ZERO { Vec4::ZERO } else { v }));
        }
    }
    Ok(())
}
