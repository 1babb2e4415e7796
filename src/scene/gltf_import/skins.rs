//! Skins (glTF 2.0 section 3.7.3): a skinned mesh is rendered in the pose that its
//! joints' node transforms give (the file's static pose; animations are not applied). For
//! the usual file, whose joints are at rest, that is the bind pose.
//!
//! Per vertex, with joint matrices J_j = world(joint_j) · inverseBindMatrix_j, the
//! skinning matrix is M = sum_k w_k J_{j_k} over the vertex's JOINTS_n/WEIGHTS_n
//! influences (section 3.7.3.3), and the vertex goes to M · p; the transform of the
//! skinned mesh's own node is not used (section 3.7.3.2: "only the joint transforms are
//! applied to the skinned mesh; the transform of the skinned mesh node MUST be ignored").
//! Normals go by the inverse transpose of M.

use super::accessors::{read_mat4, read_vec4, JOINTS_FORMATS, WEIGHTS_FORMATS};
use super::Importer;
use anyhow::{bail, Context, Result};
use glam::{DMat4, Mat4};
use gltf::mesh::Semantic;

impl Importer<'_> {
    /// The joint matrices of `skin` (used by the node `label`), re-centred like every world
    /// transform and rounded to f32: `rebase · world(joint_j) · inverseBindMatrix_j`, composed
    /// in f64. Without `inverseBindMatrices` each is the identity (section 3.7.3.1). A joint
    /// outside the rendered scene is placed by its own ancestors.
    pub(super) fn joint_matrices(&mut self, skin: &gltf::Skin, label: &str) -> Result<Vec<Mat4>> {
        let si = skin.index();
        let joints: Vec<usize> = skin.joints().map(|n| n.index()).collect();
        let ibm = match skin.inverse_bind_matrices() {
            Some(acc) => {
                let m = read_mat4(&self.buffers, &acc, "inverseBindMatrices")
                    .with_context(|| format!("skin {si} (on {label})"))?;
                if m.len() < joints.len() {
                    bail!(
                        "skin {si} (on {label}): inverseBindMatrices accessor {} has {} matrices for {} joints",
                        acc.index(),
                        m.len(),
                        joints.len()
                    );
                }
                m
            }
            None => vec![DMat4::IDENTITY; joints.len()],
        };
        let mut out = Vec::with_capacity(joints.len());
        for (j, &node) in joints.iter().enumerate() {
            let world = self.world_of(node).with_context(|| format!("skin {si} (on {label}) joint {j}"))?;
            let m = (self.rebase * world * ibm[j]).as_mat4();
            if !m.is_finite() {
                bail!("skin {si} (on {label}): the matrix of joint {j} (node {node}) is not finite");
            }
            out.push(m);
        }
        Ok(out)
    }

    /// The world transform (f64, not re-centred) of node `index`: from the node walk when
    /// the node is in the rendered scene, else composed from its ancestors (its first parent
    /// in document order each time). A parent chain that loops is an error.
    fn world_of(&self, index: usize) -> Result<DMat4> {
        if let Some(w) = self.node_world[index] {
            return Ok(w);
        }
        let n = self.doc.nodes().len();
        let mut parent = vec![None; n];
        for node in self.doc.nodes() {
            for c in node.children() {
                parent[c.index()].get_or_insert(node.index());
            }
        }
        let mut chain = vec![index];
        while let Some(p) = parent[*chain.last().unwrap_or(&index)] {
            if chain.len() > n {
                bail!("node {index}: its ancestors form a cycle (the node hierarchy is not a tree)");
            }
            chain.push(p);
        }
        let nodes: Vec<gltf::Node> = self.doc.nodes().collect();
        Ok(chain.iter().rev().fold(DMat4::IDENTITY, |acc, &i| acc * super::local_transform_f64(&nodes[i])))
    }

    /// Per vertex of `prim` (`vertex_count` vertices), the skinning matrix
    /// `sum_k w_k joints[j_k]` over every JOINTS_n/WEIGHTS_n pair (section 3.7.3.3), the
    /// weights divided by their sum (float and quantized weights need not sum to exactly 1).
    /// `None` (with a warning) when the primitive has no JOINTS_0/WEIGHTS_0. Errors: a
    /// JOINTS_n without its WEIGHTS_n, counts other than the vertex count, negative or
    /// non-finite weights, and joint indices with non-zero weight past the skin's joints.
    /// A vertex whose weights are all 0 stays as stored, in world coordinates (warning).
    pub(super) fn skin_vertex_matrices(
        &mut self,
        prim: &gltf::Primitive,
        joints: &[Mat4],
        vertex_count: usize,
        where_: &str,
    ) -> Result<Option<Vec<Mat4>>> {
        let mut sums = vec![Mat4::ZERO; vertex_count];
        let mut weight_sums = vec![0.0f64; vertex_count];
        let mut set = 0;
        loop {
            let (ja, wa) = (prim.get(&Semantic::Joints(set)), prim.get(&Semantic::Weights(set)));
            let (ja, wa) = match (ja, wa) {
                (Some(j), Some(w)) => (j, w),
                (None, None) => break,
                (Some(_), None) => bail!("{where_}: JOINTS_{set} without WEIGHTS_{set}"),
                (None, Some(_)) => bail!("{where_}: WEIGHTS_{set} without JOINTS_{set}"),
            };
            let js = read_vec4(&self.buffers, &ja, &format!("JOINTS_{set}"), &JOINTS_FORMATS)
                .with_context(|| where_.to_string())?;
            let ws = read_vec4(&self.buffers, &wa, &format!("WEIGHTS_{set}"), &WEIGHTS_FORMATS)
                .with_context(|| where_.to_string())?;
            for (what, acc, len) in [("JOINTS", &ja, js.len()), ("WEIGHTS", &wa, ws.len())] {
                if len != vertex_count {
                    bail!(
                        "{where_}: {what}_{set} accessor {} has {len} elements, the primitive has {vertex_count} vertices",
                        acc.index()
                    );
                }
            }
            for (v, (j4, w4)) in js.iter().zip(&ws).enumerate() {
                for k in 0..4 {
                    let (j, w) = (j4[k], w4[k]);
                    if !(w >= 0.0 && w.is_finite()) {
                        bail!("{where_}: WEIGHTS_{set} accessor {} vertex {v} has weight {w} (weights must be finite and not negative)", wa.index());
                    }
                    if w == 0.0 {
                        continue;
                    }
                    let Some(m) = joints.get(j as usize) else {
                        bail!(
                            "{where_}: JOINTS_{set} accessor {} vertex {v} names joint {j}, but the skin has {} joints",
                            ja.index(),
                            joints.len()
                        );
                    };
                    sums[v] += *m * w as f32;
                    weight_sums[v] += w;
                }
            }
            set += 1;
        }
        if set == 0 {
            self.warnings.warn(
                "skinned node whose primitive has no JOINTS_0/WEIGHTS_0 (its vertices are used as stored, unskinned)",
                where_.to_string(),
            );
            return Ok(None);
        }
        let rest = self.rebase.as_mat4();
        let mut unweighted = false;
        let out = sums
            .into_iter()
            .zip(weight_sums)
            .map(|(m, s)| {
                if s > 0.0 {
                    m * (1.0 / s) as f32
                } else {
                    unweighted = true;
                    rest
                }
            })
            .collect();
        if unweighted {
            self.warnings
                .warn("skinned vertices whose weights are all 0 (used as stored, unskinned)", where_.to_string());
        }
        Ok(Some(out))
    }
}
