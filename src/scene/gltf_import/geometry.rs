//! Geometry: mesh primitives (morphed and skinned as stored, then triangulated) into
//! world-space triangles, and the spheres of vkvcm's `VKVCM_spheres` node extension.

use super::accessors::{
    read_color, read_indices, read_tangents, read_vec2, read_vec3, Formats, COLOR_FORMATS, COLOR_TARGET_FORMATS,
    NORMAL_FORMATS, NORMAL_TARGET_FORMATS, POSITION_FORMATS, POSITION_TARGET_FORMATS, TANGENT_FORMATS,
    TANGENT_TARGET_FORMATS, TEXCOORD_FORMATS, TEXCOORD_TARGET_FORMATS,
};
use super::extensions::{ext_vec3, EXT_SPHERES};
use super::Importer;
use crate::scene::{transform_tangent, Sphere, Triangle, VertexAttributes};
use anyhow::{anyhow, bail, Context, Result};
use glam::{Mat3, Mat4, Vec2, Vec3, Vec4};
use gltf::mesh::{Mode, Semantic};
use serde_json::Value;

/// How a mesh's vertices reach world space.
pub(super) enum Placement {
    /// By the node's world transform (re-centred, f32).
    Rigid(Mat4),
    /// By a skin: the joint matrices of [`Importer::joint_matrices`], blended per vertex
    /// (the node's own transform is not used: glTF 2.0 section 3.7.3.2).
    Skinned(Vec<Mat4>),
}

impl Importer<'_> {
    /// Adds the triangles of every primitive of `mesh`, placed by `placement`. Morph
    /// targets are applied first, at the weights `node_weights` (the node's `weights`) or
    /// else the mesh's `weights` (glTF 2.0 section 3.7.2.2: none given means all 0), then
    /// the skin, if any. Triangles that are degenerate after the transform are counted in
    /// the report and dropped; a mirroring transform keeps each triangle's geometric normal
    /// on the authored side.
    pub(super) fn add_mesh(
        &mut self,
        mesh: &gltf::Mesh,
        placement: &Placement,
        node_weights: Option<&[f32]>,
        label: &str,
    ) -> Result<()> {
        let weights = node_weights.or(mesh.weights());
        for prim in mesh.primitives() {
            let where_ = format!("mesh {} primitive {} (on {label})", mesh.index(), prim.index());
            self.add_primitive(&prim, mesh.index(), placement, weights, &where_)?;
        }
        Ok(())
    }

    /// [`Importer::add_mesh`] for one primitive (`where_` names it in messages); one of an
    /// unsupported mode or without POSITION is skipped with a warning.
    fn add_primitive(
        &mut self,
        prim: &gltf::Primitive,
        mesh: usize,
        placement: &Placement,
        weights: Option<&[f32]>,
        where_: &str,
    ) -> Result<()> {
        let mode = prim.mode();
        if !matches!(mode, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
            let name = match mode {
                Mode::Points => "POINTS",
                Mode::Lines => "LINES",
                Mode::LineLoop => "LINE_LOOP",
                Mode::LineStrip => "LINE_STRIP",
                _ => "?",
            };
            self.warnings.warn(format!("primitive mode {name} is not supported (primitive skipped)"), where_);
            return Ok(());
        }
        let Some(pos_acc) = prim.get(&Semantic::Positions) else {
            self.warnings.warn("primitive without POSITION (skipped)", where_);
            return Ok(());
        };
        let (mut positions, mut normals) = self.read_positions_and_normals(prim, &pos_acc, where_)?;
        self.apply_morph_targets(prim, weights, &mut positions, normals.as_mut(), where_)?;
        let material = match prim.material().index() {
            Some(i) => i as u32,
            None => self.default_material(),
        };
        let (uvs, colors) = self.vertex_attributes(prim, mesh, weights, positions.len(), where_)?;
        let normal_map = self.texture_sets_present(material, &uvs, where_);
        // An anisotropic GGX lobe needs tangents as a normal map does: the primitive's, or
        // generated on its anisotropyTexture's set (TEXCOORD_0 without one).
        let mat = &self.scene.materials[material as usize];
        let anisotropic = mat.has_anisotropy();
        let anisotropy_set = mat.anisotropy_texture.as_ref().map_or(0, |t| t.tex_coord as usize);
        let tangent_set = normal_map.or((anisotropic && uvs[anisotropy_set].is_some()).then_some(anisotropy_set));
        let tangents = match (normal_map.is_some() || anisotropic, prim.get(&Semantic::Tangents)) {
            (true, Some(acc)) => Some(self.read_morphed_tangents(prim, &acc, weights, positions.len(), where_)?),
            _ => None,
        };
        if anisotropic && tangents.is_none() && tangent_set.is_none() {
            self.warnings.warn(
                format!(
                    "KHR_materials_anisotropy without TANGENT or TEXCOORD_{anisotropy_set} to generate tangents from (the GGX lobe is isotropic there)"
                ),
                where_,
            );
        }
        let indices: Vec<u32> = match &prim.indices() {
            Some(a) => {
                let idx = read_indices(&self.buffers, a).with_context(|| where_.to_string())?;
                if let Some((k, &v)) = idx.iter().enumerate().find(|(_, &v)| v as usize >= positions.len()) {
                    bail!(
                        "{where_}: index accessor {} element {k} = {v} is out of range (POSITION accessor {} has {} vertices)",
                        a.index(),
                        pos_acc.index(),
                        positions.len()
                    );
                }
                idx
            }
            None => (0..positions.len() as u32).collect(),
        };
        let world = self.world_vertices(prim, placement, &positions, normals, tangents, where_)?;
        let tris = self.triangle_list(mode, &indices, where_);
        let first_triangle = self.scene.triangles.len();
        self.push_triangles(&tris, &world, &uvs, colors.as_deref(), material, where_);
        if let (Some(set), None) = (tangent_set, &world.2) {
            super::tangents::generate(&mut self.scene.triangles[first_triangle..], set)
                .with_context(|| format!("{where_}: generating tangents"))?;
        }
        Ok(())
    }

    /// The POSITION and NORMAL (if any) of a primitive, checked to be as many.
    fn read_positions_and_normals(
        &self,
        prim: &gltf::Primitive,
        pos_acc: &gltf::Accessor,
        where_: &str,
    ) -> Result<(Vec<Vec3>, Option<Vec<Vec3>>)> {
        let q = self.quantized;
        let positions =
            read_vec3(&self.buffers, pos_acc, "POSITION", &POSITION_FORMATS, q).with_context(|| where_.to_string())?;
        let Some(a) = prim.get(&Semantic::Normals) else { return Ok((positions, None)) };
        let n = read_vec3(&self.buffers, &a, "NORMAL", &NORMAL_FORMATS, q).with_context(|| where_.to_string())?;
        if n.len() != positions.len() {
            bail!(
                "{where_}: NORMAL accessor {} has {} elements, POSITION accessor {} has {}",
                a.index(),
                n.len(),
                pos_acc.index(),
                positions.len()
            );
        }
        Ok((positions, Some(n)))
    }

    /// Warns of each texture of `material` on texture coordinates the primitive lacks
    /// (`uvs`); returns the set of its normal map (else of its clear coat's normal map) when
    /// the primitive has it: MikkTSpace's tangents are generated on that set.
    fn texture_sets_present(&mut self, material: u32, uvs: &[Option<Vec<Vec2>>; 2], where_: &str) -> Option<usize> {
        // A texture on texture coordinates the primitive lacks cannot apply: the kernels
        // find that set missing (NaN) and use the factors alone, while the material's
        // other textures on the set it has still apply.
        let mat = &self.scene.materials[material as usize];
        let layers = mat.layer_textures.as_deref();
        let dt = mat.diffuse_transmission.as_deref();
        let textures = [
            ("baseColorTexture", mat.base_color_texture.as_ref(), "the texture is not applied"),
            ("emissiveTexture", mat.emissive_texture.as_ref(), "the emissive factor alone applies"),
            (
                "metallicRoughnessTexture",
                mat.metallic_roughness_texture.as_ref().map(|t| &t.texture),
                "the metallic and roughness factors alone apply",
            ),
            ("clearcoatTexture", mat.clearcoat_texture.as_ref(), "the clear coat factor alone applies"),
            (
                "clearcoatNormalTexture",
                mat.clearcoat_normal_texture.as_ref(),
                "the clear coat shades with the base's normal",
            ),
            (
                "clearcoatRoughnessTexture",
                mat.clearcoat_roughness_texture.as_ref(),
                "the clear coat roughness alone applies",
            ),
            (
                "transmissionTexture",
                layers.and_then(|l| l.transmission.as_ref()),
                "the transmission factor alone applies",
            ),
            ("specularTexture", layers.and_then(|l| l.specular.as_ref()), "the specular factor alone applies"),
            ("sheenColorTexture", mat.sheen_color_texture.as_ref(), "the sheen colour factor alone applies"),
            ("sheenRoughnessTexture", mat.sheen_roughness_texture.as_ref(), "the sheen roughness factor alone applies"),
            ("iridescenceTexture", mat.iridescence_texture.as_ref(), "the iridescence factor alone applies"),
            (
                "iridescenceThicknessTexture",
                mat.iridescence_thickness_texture.as_ref(),
                "the film is the thickness maximum thick",
            ),
            ("anisotropyTexture", mat.anisotropy_texture.as_ref(), "the anisotropy strength and rotation alone apply"),
            (
                "diffuseTransmissionTexture",
                dt.and_then(|d| d.texture.as_ref()),
                "the diffuse transmission factor alone applies",
            ),
            (
                "diffuseTransmissionColorTexture",
                dt.and_then(|d| d.color_texture.as_ref()),
                "the diffuse transmission colour factor alone applies",
            ),
            (
                "specularColorTexture",
                layers.and_then(|l| l.specular_color.as_ref()),
                "the specular colour factor alone applies",
            ),
        ];
        for (slot, texture, what) in textures {
            if let Some(k) = texture.map(|t| t.tex_coord).filter(|&k| uvs[k as usize].is_none()) {
                self.warnings
                    .warn(format!("{slot} on TEXCOORD_{k}, which the primitive does not have ({what})"), where_);
            }
        }
        // A normal map needs its texture coordinates, and tangents: the primitive's
        // TANGENT, or MikkTSpace's (glTF 2.0 section 3.7.2.1) generated after.
        let coat_normal = mat.clearcoat_normal_texture.as_ref().filter(|_| mat.clearcoat > 0.0);
        match mat.normal_texture.as_ref().map(|t| t.tex_coord as usize) {
            None => coat_normal.map(|t| t.tex_coord as usize).filter(|&k| uvs[k].is_some()),
            Some(k) if uvs[k].is_none() => {
                self.warnings.warn(
                    format!("normalTexture on TEXCOORD_{k}, which the primitive does not have (the normal map is not applied)"),
                    where_,
                );
                None
            }
            other => other,
        }
    }

    /// The primitive's TANGENT (accessor `acc`, one per vertex of `vertices`), morphed
    /// at `weights` and checked finite.
    fn read_morphed_tangents(
        &self,
        prim: &gltf::Primitive,
        acc: &gltf::Accessor,
        weights: Option<&[f32]>,
        vertices: usize,
        where_: &str,
    ) -> Result<Vec<Vec4>> {
        let mut t =
            read_tangents(&self.buffers, acc, &TANGENT_FORMATS, self.quantized).with_context(|| where_.to_string())?;
        if t.len() != vertices {
            bail!(
                "{where_}: TANGENT accessor {} has {} elements, the primitive has {vertices} vertices",
                acc.index(),
                t.len()
            );
        }
        self.morph_tangents(prim, weights, &mut t, where_)?;
        if let Some(i) = t.iter().position(|v| !v.is_finite()) {
            bail!("{where_}: TANGENT accessor {} element {i} is not finite (after morphing)", acc.index());
        }
        Ok(t)
    }

    /// The vertices in world space by `placement`, with per vertex whether its transform
    /// mirrors.
    fn world_vertices(
        &mut self,
        prim: &gltf::Primitive,
        placement: &Placement,
        positions: &[Vec3],
        normals: Option<Vec<Vec3>>,
        tangents: Option<Vec<Vec4>>,
        where_: &str,
    ) -> Result<WorldVertices> {
        // Skinned: per vertex, the matrix that takes it to world space.
        let vertex_matrices = match placement {
            Placement::Rigid(_) => None,
            Placement::Skinned(joints) => self.skin_vertex_matrices(prim, joints, positions.len(), where_)?,
        };
        Ok(match vertex_matrices {
            None => {
                let world = match placement {
                    Placement::Rigid(world) => *world,
                    // A skinned node whose primitive has no JOINTS_0/WEIGHTS_0 (warned):
                    // its vertices as stored, in world coordinates.
                    Placement::Skinned(_) => self.rebase.as_mat4(),
                };
                let normal_matrix = Mat3::from_mat4(world).inverse().transpose();
                let flip = Mat3::from_mat4(world).determinant() < 0.0;
                let p: Vec<Vec3> = positions.iter().map(|v| world.transform_point3(*v)).collect();
                let n = normals.map(|ns| ns.iter().map(|v| (normal_matrix * *v).normalize_or_zero()).collect());
                let t = tangents
                    .as_ref()
                    .map(|ts| ts.iter().map(|t| transform_tangent(Mat3::from_mat4(world), *t)).collect());
                (p, n, t, vec![flip; positions.len()])
            }
            Some(ms) => {
                let p: Vec<Vec3> = positions.iter().zip(&ms).map(|(v, m)| m.transform_point3(*v)).collect();
                let n: Option<Vec<Vec3>> = normals.map(|ns| {
                    ns.iter()
                        .zip(&ms)
                        .map(|(v, m)| (Mat3::from_mat4(*m).inverse().transpose() * *v).normalize_or_zero())
                        .collect()
                });
                let t = tangents
                    .as_ref()
                    .map(|ts| ts.iter().zip(&ms).map(|(t, m)| transform_tangent(Mat3::from_mat4(*m), *t)).collect());
                let flips = ms.iter().map(|m| Mat3::from_mat4(*m).determinant() < 0.0).collect();
                (p, n, t, flips)
            }
        })
    }

    /// The triangles (vertex indices) of a primitive of `mode` with `indices`.
    fn triangle_list(&mut self, mode: Mode, indices: &[u32], where_: &str) -> Vec<[u32; 3]> {
        match mode {
            Mode::Triangles => {
                if !indices.len().is_multiple_of(3) {
                    self.warnings.warn(
                        "TRIANGLES primitive whose vertex/index count is not a multiple of 3 (trailing vertices ignored)",
                        where_,
                    );
                }
                indices.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()
            }
            Mode::TriangleStrip => (0..indices.len().saturating_sub(2))
                .map(|i| {
                    if i % 2 == 0 {
                        [indices[i], indices[i + 1], indices[i + 2]]
                    } else {
                        [indices[i + 1], indices[i], indices[i + 2]]
                    }
                })
                .collect(),
            _ => (1..indices.len().saturating_sub(1)).map(|i| [indices[i], indices[i + 1], indices[0]]).collect(),
        }
    }

    /// Adds the triangles `tris` of world-space vertices `world` with their attributes;
    /// degenerate ones are counted in the report and dropped.
    fn push_triangles(
        &mut self,
        tris: &[[u32; 3]],
        world: &WorldVertices,
        uvs: &[Option<Vec<Vec2>>; 2],
        colors: Option<&[Vec4]>,
        material: u32,
        where_: &str,
    ) {
        let (world_p, world_n, world_t, flips) = world;
        for &t in tris {
            // A mirroring transform reverses the winding; keep the geometric normal on
            // the side the author meant by swapping vertices 1 and 2 (with all their
            // attributes). A skinned triangle follows the transform of its first vertex.
            let t = if flips[t[0] as usize] { [t[0], t[2], t[1]] } else { t };
            let p = t.map(|i| world_p[i as usize]);
            let mut n = world_n.as_ref().map(|ns| t.map(|i| ns[i as usize]));
            let area2 = (p[1] - p[0]).cross(p[2] - p[0]);
            let zero_area = area2.length_squared().partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater);
            if !p.iter().all(|q| q.is_finite()) || zero_area || !area2.normalize().is_finite() {
                self.scene.report.degenerate_triangles += 1;
                continue;
            }
            if let Some(ns) = &n {
                if ns.iter().any(|v| *v == Vec3::ZERO || !v.is_finite()) {
                    self.warnings.warn(
                        "zero-length or invalid vertex normals (that triangle uses its geometric normal)",
                        where_,
                    );
                    n = None;
                }
            }
            let attributes = (uvs.iter().any(Option::is_some) || colors.is_some() || world_t.is_some()).then(|| {
                Box::new(VertexAttributes {
                    uv: [0, 1].map(|k| uvs[k].as_ref().map(|uv| t.map(|i| uv[i as usize]))),
                    color: colors.map(|c| t.map(|i| c[i as usize])),
                    tangent: world_t.as_ref().map(|ts| t.map(|i| ts[i as usize])),
                })
            });
            self.scene.triangles.push(Triangle { p, n, material, attributes });
        }
    }

    /// The TEXCOORD_0, TEXCOORD_1 and COLOR_0 of `prim` (`vertices` of them each, when
    /// present), with their morph-target displacements at `weights` (glTF 2.0 section
    /// 3.7.2.2, as positions), checked for count and finiteness; colours are clamped to
    /// [0, 1] (glTF: COLOR_0 is within it) with a warning. Other TEXCOORD_n and COLOR_n are
    /// not read (warning). `mesh`: the mesh's index.
    #[allow(clippy::type_complexity)]
    fn vertex_attributes(
        &mut self,
        prim: &gltf::Primitive,
        mesh: usize,
        weights: Option<&[f32]>,
        vertices: usize,
        where_: &str,
    ) -> Result<([Option<Vec<Vec2>>; 2], Option<Vec<Vec4>>)> {
        let q = self.quantized;
        let check_count = |acc: &gltf::Accessor, what: &str, n: usize| -> Result<()> {
            if n != vertices {
                bail!(
                    "{where_}: {what} accessor {} has {n} elements, the primitive has {vertices} vertices",
                    acc.index()
                );
            }
            Ok(())
        };
        let not_finite = |acc: &gltf::Accessor, what: &str, k: usize| {
            anyhow!("{where_}: {what} accessor {} element {k} is not finite", acc.index())
        };
        let mut uvs: [Option<Vec<Vec2>>; 2] = [None, None];
        for (k, slot) in uvs.iter_mut().enumerate() {
            let Some(acc) = prim.get(&Semantic::TexCoords(k as u32)) else { continue };
            let what = format!("TEXCOORD_{k}");
            let mut uv =
                read_vec2(&self.buffers, &acc, &what, &TEXCOORD_FORMATS, q).with_context(|| where_.to_string())?;
            check_count(&acc, &what, uv.len())?;
            for (target, w, target_acc) in self.morph_displacements(prim, mesh, weights, &what, where_)? {
                let target_what = format!("morph target {target} {what}");
                let d = read_vec2(&self.buffers, &target_acc, &target_what, &TEXCOORD_TARGET_FORMATS, q)
                    .with_context(|| where_.to_string())?;
                check_count(&target_acc, &target_what, d.len())?;
                for (v, dv) in uv.iter_mut().zip(d) {
                    *v += w * dv;
                }
            }
            if let Some(i) = uv.iter().position(|v| !v.is_finite()) {
                return Err(not_finite(&acc, &what, i));
            }
            *slot = Some(uv);
        }
        let colors = match prim.get(&Semantic::Colors(0)) {
            None => None,
            Some(acc) => {
                let mut c =
                    read_color(&self.buffers, &acc, "COLOR_0", &COLOR_FORMATS).with_context(|| where_.to_string())?;
                check_count(&acc, "COLOR_0", c.len())?;
                for (target, w, d) in self.morph_displacements(prim, mesh, weights, "COLOR_0", where_)? {
                    let what = format!("morph target {target} COLOR_0");
                    let vec3 = d.dimensions() == gltf::accessor::Dimensions::Vec3;
                    let dc = read_color(&self.buffers, &d, &what, &COLOR_TARGET_FORMATS)
                        .with_context(|| where_.to_string())?;
                    check_count(&d, &what, dc.len())?;
                    for (v, dv) in c.iter_mut().zip(dc) {
                        // A VEC3 displacement leaves alpha alone (read_color gives it alpha 1).
                        *v += w * if vec3 { dv.truncate().extend(0.0) } else { dv };
                    }
                }
                if let Some(i) = c.iter().position(|v| !v.is_finite()) {
                    return Err(not_finite(&acc, "COLOR_0", i));
                }
                if c.iter().any(|v| v.min_element() < 0.0 || v.max_element() > 1.0) {
                    self.warnings.warn("COLOR_0 values outside [0, 1] are clamped", where_.to_string());
                }
                Some(c.into_iter().map(|v| v.clamp(Vec4::ZERO, Vec4::ONE)).collect())
            }
        };
        for (sem, _) in prim.attributes() {
            let name = match sem {
                Semantic::TexCoords(k) if k > 1 => format!("TEXCOORD_{k}"),
                Semantic::Colors(k) if k > 0 => format!("COLOR_{k}"),
                _ => continue,
            };
            self.warnings.warn(
                "vertex attributes TEXCOORD_n (n > 1) and COLOR_n (n > 0) are not read (ignored)",
                format!("{where_} {name}"),
            );
        }
        Ok((uvs, colors))
    }

    /// The morph targets of `prim` (of mesh `mesh`) that displace `attribute` (TEXCOORD_0,
    /// TEXCOORD_1 or COLOR_0, which gltf-json does not have: `Importer::morph_attributes`)
    /// with a weight other than 0: (target index, weight, the displacements' accessor).
    /// The weights are those of [`Importer::apply_morph_targets`], which has checked their
    /// count.
    fn morph_displacements<'a>(
        &'a self,
        prim: &gltf::Primitive,
        mesh: usize,
        weights: Option<&[f32]>,
        attribute: &str,
        where_: &str,
    ) -> Result<Vec<(usize, f32, gltf::Accessor<'a>)>> {
        let Some(weights) = weights else { return Ok(Vec::new()) };
        let mut out = Vec::new();
        for a in &self.morph_attributes {
            if a.mesh != mesh || a.primitive != prim.index() || a.name != attribute {
                continue;
            }
            let w = *weights.get(a.target).ok_or_else(|| anyhow!("{where_}: {} has no weight", a.path()))?;
            let acc = a.accessor.and_then(|i| self.doc.accessors().nth(i));
            let acc = acc.ok_or_else(|| anyhow!("{where_}: {} has no accessor", a.path()))?;
            if w != 0.0 {
                out.push((a.target, w, acc));
            }
        }
        Ok(out)
    }

    /// Adds the morph targets' TANGENT displacements (xyz; the sign w stays) of `prim` at
    /// `weights` to its `tangents`.
    fn morph_tangents(
        &self,
        prim: &gltf::Primitive,
        weights: Option<&[f32]>,
        tangents: &mut [Vec4],
        where_: &str,
    ) -> Result<()> {
        let Some(weights) = weights else { return Ok(()) };
        for (ti, (target, &w)) in prim.morph_targets().zip(weights).enumerate() {
            let (Some(acc), true) = (target.tangents(), w != 0.0) else { continue };
            let what = format!("morph target {ti} TANGENT");
            let d = read_vec3(&self.buffers, &acc, &what, &TANGENT_TARGET_FORMATS, self.quantized)
                .with_context(|| where_.to_string())?;
            if d.len() != tangents.len() {
                bail!(
                    "{where_}: {what} accessor {} has {} elements, the primitive has {} vertices",
                    acc.index(),
                    d.len(),
                    tangents.len()
                );
            }
            for (t, dt) in tangents.iter_mut().zip(d) {
                *t += (w * dt).extend(0.0);
            }
        }
        Ok(())
    }

    /// Adds the morph-target displacements of `prim` to `positions` (and `normals`, when
    /// both the primitive and a target have them) at the `weights` in force (glTF 2.0
    /// section 3.7.2.2: p = p0 + sum_i w_i d_i; `None`: every weight is 0). A weight count
    /// other than the primitive's target count is an error, as is a target accessor whose
    /// count differs from POSITION's. TANGENT displacements are applied where tangents are
    /// read (`morph_tangents`), TEXCOORD_0/1 and COLOR_0 ones in `vertex_attributes`.
    fn apply_morph_targets(
        &self,
        prim: &gltf::Primitive,
        weights: Option<&[f32]>,
        positions: &mut [Vec3],
        mut normals: Option<&mut Vec<Vec3>>,
        where_: &str,
    ) -> Result<()> {
        let targets: Vec<_> = prim.morph_targets().collect();
        if targets.is_empty() {
            return Ok(());
        }
        let zeros = vec![0.0; targets.len()];
        let weights = weights.unwrap_or(&zeros);
        if weights.len() != targets.len() {
            bail!(
                "{where_}: {} morph target weight(s) (node or mesh weights), but the primitive has {} morph target(s)",
                weights.len(),
                targets.len()
            );
        }
        let q = self.quantized;
        for (ti, (target, &w)) in targets.iter().zip(weights).enumerate() {
            let ctx = || format!("{where_}, morph target {ti}");
            if !w.is_finite() {
                bail!("{}: weight {w} is not finite", ctx());
            }
            let apply = |acc: &gltf::Accessor, what: &str, formats: &Formats, out: &mut [Vec3]| -> Result<()> {
                let d = read_vec3(&self.buffers, acc, what, formats, q).with_context(ctx)?;
                if d.len() != out.len() {
                    bail!(
                        "{}: {what} accessor {} has {} elements, the primitive has {} vertices",
                        ctx(),
                        acc.index(),
                        d.len(),
                        out.len()
                    );
                }
                for (v, dv) in out.iter_mut().zip(d) {
                    *v += w * dv;
                }
                Ok(())
            };
            if let Some(acc) = target.positions() {
                apply(&acc, "morph target POSITION", &POSITION_TARGET_FORMATS, positions)?;
            }
            if let (Some(acc), Some(ns)) = (target.normals(), normals.as_deref_mut()) {
                apply(&acc, "morph target NORMAL", &NORMAL_TARGET_FORMATS, ns)?;
            }
        }
        Ok(())
    }

    /// Adds the spheres of a node's `VKVCM_spheres` payload `v`, transformed by `world`
    /// (which must scale uniformly); `ni` is the node's index.
    pub(super) fn add_spheres(&mut self, v: &Value, world: Mat4, ni: usize) -> Result<()> {
        let ctx = format!("nodes[{ni}].extensions.{EXT_SPHERES}");
        let list =
            v.get("spheres").and_then(Value::as_array).ok_or_else(|| anyhow!("{ctx}.spheres must be an array"))?;
        let m3 = Mat3::from_mat4(world);
        let s = [m3.x_axis.length(), m3.y_axis.length(), m3.z_axis.length()];
        let smax = s[0].max(s[1]).max(s[2]);
        let gram = m3.transpose() * m3;
        let uniform = smax > 0.0
            && (gram - Mat3::from_diagonal(Vec3::splat(smax * smax)))
                .to_cols_array()
                .iter()
                .all(|x| x.abs() <= 1e-5 * smax * smax);
        if !uniform {
            bail!(
                "{ctx}: spheres need a uniform scale, but the node's world matrix scales by ({}, {}, {}) or shears",
                s[0],
                s[1],
                s[2]
            );
        }
        for (k, sp) in list.iter().enumerate() {
            let c = format!("{ctx}.spheres[{k}]");
            if sp.get("center").is_none() {
                bail!("{c}.center is missing");
            }
            let center = ext_vec3(sp, "center", Vec3::ZERO, &c)?;
            let radius = sp
                .get("radius")
                .and_then(Value::as_f64)
                .filter(|r| *r > 0.0 && r.is_finite())
                .ok_or_else(|| anyhow!("{c}.radius must be a positive number"))? as f32;
            let material = match sp.get("material") {
                None => self.default_material(),
                Some(m) => {
                    let n = self.doc.materials().len() as u64;
                    let i = m.as_u64().ok_or_else(|| anyhow!("{c}.material must be a material index"))?;
                    if i >= n {
                        bail!("{c}.material = {i} is out of range ({n} materials)");
                    }
                    i as u32
                }
            };
            self.scene.spheres.push(Sphere { center: world.transform_point3(center), radius: radius * smax, material });
        }
        Ok(())
    }
}

/// A primitive's vertices in world space: positions, normals, tangents, and whether the
/// transform of each mirrors.
type WorldVertices = (Vec<Vec3>, Option<Vec<Vec3>>, Option<Vec<Vec4>>, Vec<bool>);
