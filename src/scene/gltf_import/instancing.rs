//! Instancing: a mesh placed by several rigid nodes, or by a node's
//! `EXT_mesh_gpu_instancing` transforms, is stored once in object space
//! ([`crate::scene::SharedMesh`]) and placed by instances ([`crate::scene::Instance`]);
//! the BVH then has two levels (src/bvh/layout.rs, "Instancing").
//!
//! A mesh is shared only where that renders the same image as flattening it: placements
//! by skinned nodes, or by nodes with their own morph weights, are flattened, and so are
//! meshes with an emitting material (area lights are world-space triangles). With
//! [`super::LoadOptions::flatten_instances`] every mesh is flattened.

use super::accessors::{read_vec3, Formats, BYTE_N, FLOAT, SHORT_N, UBYTE_N, USHORT_N};
use super::extensions::EXT_MESH_GPU_INSTANCING;
use super::geometry::Placement;
use super::Importer;
use crate::scene::{Instance, SharedMesh};
use anyhow::{bail, Context, Result};
use glam::{Affine3A, DMat4, DQuat, DVec3, Mat4, Vec3};
use serde_json::Value;

/// EXT_mesh_gpu_instancing's TRANSLATION and SCALE (FLOAT VEC3).
const VEC3_FORMATS: Formats = Formats { core: &[FLOAT], quantized: &[FLOAT] };
/// Its ROTATION (VEC4: FLOAT, or normalized BYTE/SHORT, as animation rotations).
const ROTATION_FORMATS: Formats =
    Formats { core: &[FLOAT, BYTE_N, SHORT_N, UBYTE_N, USHORT_N], quantized: &[FLOAT, BYTE_N, SHORT_N] };

/// What the importer gathers about instancing during the node walk.
#[derive(Default)]
pub(super) struct Instancing {
    /// Per glTF mesh: stored once and instanced.
    pub shared: Vec<bool>,
    /// Placements of shared meshes met in node order: glTF mesh index, object-to-world
    /// matrix (re-centred, f32) and the node's label.
    pub placements: Vec<(usize, Mat4, String)>,
    /// The local EXT_mesh_gpu_instancing transforms of each node with a mesh that has
    /// them, by node index (read once, in [`Importer::choose_shared_meshes`]).
    pub gpu_transforms: std::collections::HashMap<usize, Vec<DMat4>>,
}

impl Importer<'_> {
    /// Decides which meshes are shared: those with two or more placements by nodes
    /// without a skin and without their own morph weights (each EXT_mesh_gpu_instancing
    /// transform counts as one), no emitting material, unless `flatten` is set.
    pub(super) fn choose_shared_meshes(&mut self, nodes: &[gltf::Node], flatten: bool) -> Result<()> {
        let doc = self.doc;
        let mut placements = vec![0usize; doc.meshes().len()];
        for node in nodes {
            let Some(mesh) = node.mesh() else { continue };
            let count = match gpu_instancing(node) {
                Some(v) => {
                    let transforms = self.gpu_instance_transforms(node, v)?;
                    let n = transforms.len();
                    self.instancing.gpu_transforms.insert(node.index(), transforms);
                    n
                }
                None => 1,
            };
            if node.skin().is_none() && node.weights().is_none() {
                placements[mesh.index()] += count;
            }
        }
        let emissive = |mesh: gltf::Mesh| {
            mesh.primitives()
                .any(|p| p.material().index().is_some_and(|i| self.scene.materials[i].emission != Vec3::ZERO))
        };
        self.instancing.shared = doc.meshes().map(|m| !flatten && placements[m.index()] >= 2 && !emissive(m)).collect();
        Ok(())
    }

    /// Whether `node`'s mesh is placed by instances (recorded here) rather than added.
    pub(super) fn place_instanced(&mut self, node: &gltf::Node, world: Mat4, label: &str) -> bool {
        let Some(mesh) = node.mesh() else { return false };
        if !self.instancing.shared[mesh.index()] || node.skin().is_some() || node.weights().is_some() {
            return false;
        }
        for m in self.node_placements(node, world) {
            self.instancing.placements.push((mesh.index(), m, label.to_string()));
        }
        true
    }

    /// `world`, or with EXT_mesh_gpu_instancing the node's world transform times each of
    /// its instance transforms (composed in f64 and re-centred, as node transforms are).
    pub(super) fn node_placements(&self, node: &gltf::Node, world: Mat4) -> Vec<Mat4> {
        let Some(local) = self.instancing.gpu_transforms.get(&node.index()) else { return vec![world] };
        let node_world = self.node_world[node.index()].unwrap_or(DMat4::IDENTITY);
        local.iter().map(|t| (self.rebase * node_world * *t).as_mat4()).collect()
    }

    /// Adds the shared meshes (object space, after every world-space triangle) and their
    /// instances. A placement whose matrix cannot be inverted would flatten to degenerate
    /// triangles: it is left out and counted with them.
    pub(super) fn add_shared_meshes(&mut self) -> Result<()> {
        let placements = std::mem::take(&mut self.instancing.placements);
        let mut mesh_of = vec![None; self.doc.meshes().len()];
        for (mi, world, label) in placements {
            let object_to_world = Affine3A::from_mat4(world);
            let det = object_to_world.matrix3.determinant();
            if !(det != 0.0 && det.is_finite() && object_to_world.inverse().is_finite()) {
                self.warnings.warn("an instance's transform is singular (instance skipped)", label);
                continue;
            }
            let mesh = match mesh_of[mi] {
                Some(m) => m,
                None => {
                    let gltf_mesh = self.doc.meshes().nth(mi).context("mesh index")?;
                    let first = self.scene.triangles.len();
                    let name = gltf_mesh.name().map_or(format!("mesh {mi}"), |n| format!("mesh {mi} '{n}'"));
                    self.add_mesh(&gltf_mesh, &Placement::Rigid(Mat4::IDENTITY), None, &format!("{name}, shared"))?;
                    let count = (self.scene.triangles.len() - first) as u32;
                    let m = self.scene.meshes.len() as u32;
                    self.scene.meshes.push(SharedMesh { name, first: first as u32, count });
                    mesh_of[mi] = Some(m);
                    m
                }
            };
            if self.scene.meshes[mesh as usize].count > 0 {
                self.scene.instances.push(Instance { mesh, object_to_world });
            }
        }
        Ok(())
    }

    /// The local TRS matrices of a node's EXT_mesh_gpu_instancing payload `v`: accessors
    /// TRANSLATION, ROTATION (unit quaternions, normalised here) and SCALE, each optional,
    /// all of the same count.
    fn gpu_instance_transforms(&self, node: &gltf::Node, v: &Value) -> Result<Vec<DMat4>> {
        let ctx = format!("node {} {EXT_MESH_GPU_INSTANCING}", node.index());
        let attributes = v.get("attributes").and_then(Value::as_object);
        let accessor = |name: &str| -> Result<Option<gltf::Accessor>> {
            match attributes.and_then(|a| a.get(name)) {
                None => Ok(None),
                Some(i) => {
                    let i = i.as_u64().with_context(|| format!("{ctx}: attribute {name} is not an accessor index"))?;
                    let acc = self.doc.accessors().nth(i as usize);
                    acc.map(Some).with_context(|| format!("{ctx}: attribute {name}: no accessor {i}"))
                }
            }
        };
        let q = self.quantized;
        let read3 = |name: &str| -> Result<Option<Vec<Vec3>>> {
            accessor(name)?
                .map(|a| read_vec3(&self.buffers, &a, name, &VEC3_FORMATS, q).with_context(|| ctx.clone()))
                .transpose()
        };
        let translation = read3("TRANSLATION")?;
        let scale = read3("SCALE")?;
        let rotation = accessor("ROTATION")?
            .map(|a| {
                super::accessors::read_rotations(&self.buffers, &a, &ROTATION_FORMATS, q).with_context(|| ctx.clone())
            })
            .transpose()?;
        let counts: Vec<usize> = [translation.as_ref().map(Vec::len), scale.as_ref().map(Vec::len)]
            .into_iter()
            .chain([rotation.as_ref().map(Vec::len)])
            .flatten()
            .collect();
        let Some(&n) = counts.first() else {
            bail!("{ctx}: no TRANSLATION, ROTATION or SCALE attribute");
        };
        if counts.iter().any(|&c| c != n) {
            bail!("{ctx}: the attributes' accessors have different counts ({counts:?})");
        }
        Ok((0..n)
            .map(|i| {
                let t = translation.as_ref().map_or(DVec3::ZERO, |t| t[i].as_dvec3());
                let s = scale.as_ref().map_or(DVec3::ONE, |s| s[i].as_dvec3());
                let r = rotation.as_ref().map_or(DQuat::IDENTITY, |r| {
                    let q = DQuat::from_array(r[i].map(f64::from));
                    if q.length_squared() > 0.0 {
                        q.normalize()
                    } else {
                        DQuat::IDENTITY
                    }
                });
                DMat4::from_scale_rotation_translation(s, r, t)
            })
            .collect())
    }
}

/// A node's EXT_mesh_gpu_instancing payload.
pub(super) fn gpu_instancing<'a>(node: &'a gltf::Node) -> Option<&'a Value> {
    node.extensions().and_then(|e| e.get(EXT_MESH_GPU_INSTANCING))
}
