//! The light tree of `--light-selection tree`: next-event estimation picks an emissive
//! triangle by a stochastic descent that weighs each child by its importance at the
//! shading point (position and normal), after Conty Estevez & Kulla, "Importance Sampling
//! of Many Lights with Adaptive Tree Splitting" (2018), in the form of pbrt-v4's
//! `BVHLightSampler` (its `LightBounds::Importance`, `DirectionCone::Union` and the
//! surface-area-orientation split cost, SAOH). Written here from the paper and pbrt-v4's
//! description; the GLSL half is glsl/light_tree.glsl.
//!
//! Only area lights are in the tree. The other lights (point, spot, directional, the
//! background) keep their power probability: next-event estimation goes into the tree
//! with probability `p_tree`, the area lights' share of the power, and otherwise picks
//! one of the others from an alias table over them alone (area lights weight 0), so
//! each of them is picked with its power probability as before. Light subpaths still
//! start by the global power table (src/render/light_selection.rs): the emission pdf
//! keeps the global pick, the direct (NEE) pdf takes the tree's (glsl/lights.glsl).
//!
//! GPU layout (16-byte elements, buffer `light_tree`): element 0 the header
//! `(node count, first light entry, p_tree bits, 0)`; then 4 elements per node
//! ([`GpuTreeNode`]), the root first; then one entry per light
//! `(leaf node or NO_NODE, others' alias, others' threshold bits, pick probability bits)`
//! where the probability is that of a non-area light (area lights: unused).

use glam::{Quat, Vec3};

use super::light_selection::{light_power, LightDistribution};
use crate::scene::{Light, Scene};

/// A missing child or leaf (u32::MAX, as glsl/light_tree.glsl's NO_NODE).
pub const NO_NODE: u32 = u32::MAX;

/// Splits are searched over this many bins per axis (pbrt-v4 uses 12).
const BINS: usize = 12;

/// A cone of directions: its axis and the cosine of its half-angle (-1: every direction).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cone {
    pub axis: Vec3,
    pub cos_theta: f32,
}

impl Cone {
    /// The smallest cone (as pbrt-v4's `Union`, not always minimal) holding both.
    pub fn union(a: Cone, b: Cone) -> Cone {
        let (ta, tb) = (a.cos_theta.clamp(-1.0, 1.0).acos(), b.cos_theta.clamp(-1.0, 1.0).acos());
        let td = angle_between(a.axis, b.axis);
        if (td + tb).min(std::f32::consts::PI) <= ta {
            return a;
        }
        if (td + ta).min(std::f32::consts::PI) <= tb {
            return b;
        }
        let theta_o = 0.5 * (ta + td + tb);
        let axis = a.axis.cross(b.axis);
        if theta_o >= std::f32::consts::PI || axis.length_squared() == 0.0 {
            return Cone { axis: a.axis, cos_theta: -1.0 };
        }
        let w = Quat::from_axis_angle(axis.normalize(), theta_o - ta) * a.axis;
        Cone { axis: w.normalize(), cos_theta: theta_o.cos() }
    }
}

fn angle_between(a: Vec3, b: Vec3) -> f32 {
    if a.dot(b) < 0.0 {
        std::f32::consts::PI - 2.0 * ((a + b).length() * 0.5).min(1.0).asin()
    } else {
        2.0 * ((b - a).length() * 0.5).min(1.0).asin()
    }
}

/// What a node bounds: its lights' box, total power, normal cone and the emission
/// spread around the normals (cos_theta_e: 0 for one-sided cosine emitters).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightBounds {
    pub min: Vec3,
    pub max: Vec3,
    pub power: f32,
    pub cone: Cone,
    pub cos_theta_e: f32,
}

impl LightBounds {
    fn union(a: &LightBounds, b: &LightBounds) -> LightBounds {
        LightBounds {
            min: a.min.min(b.min),
            max: a.max.max(b.max),
            power: a.power + b.power,
            cone: Cone::union(a.cone, b.cone),
            cos_theta_e: a.cos_theta_e.min(b.cos_theta_e),
        }
    }

    /// pbrt-v4's split cost: power times the orientation measure M_Omega times the box's
    /// surface area, stretched by `kr` (the box's longest extent over the split axis').
    fn cost(&self, kr: f32) -> f32 {
        use std::f32::consts::PI;
        let theta_o = self.cone.cos_theta.clamp(-1.0, 1.0).acos();
        let theta_e = self.cos_theta_e.clamp(-1.0, 1.0).acos();
        let theta_w = (theta_o + theta_e).min(PI);
        let sin_o = theta_o.sin();
        let m_omega = 2.0 * PI * (1.0 - theta_o.cos())
            + PI / 2.0
                * (2.0 * theta_w * sin_o - (theta_o - 2.0 * theta_w).cos() - 2.0 * theta_o * sin_o + theta_o.cos());
        let d = self.max - self.min;
        let area = 2.0 * (d.x * d.y + d.y * d.z + d.z * d.x);
        self.power * m_omega * kr * area
    }
}

/// One node as the kernels read it (glsl/light_tree.glsl `tree_node`): the box with the
/// power in `.w` of the first two, the cone's axis with cos_theta_e, and the links.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuTreeNode {
    /// (min.xyz, power)
    pub min_power: [f32; 4],
    /// (max.xyz, cos_theta_o)
    pub max_cos_o: [f32; 4],
    /// (axis.xyz, cos_theta_e)
    pub axis_cos_e: [f32; 4],
    /// (child 0, child 1, parent, light): a leaf has children NO_NODE; the root's parent
    /// is NO_NODE; light is NO_NODE in inner nodes.
    pub links: [u32; 4],
}

/// The tree of a scene's area lights and the selection of the others.
#[derive(Clone, Debug, PartialEq)]
pub struct LightTree {
    pub nodes: Vec<GpuTreeNode>,
    /// Per light of `Scene::lights`: its leaf (NO_NODE for non-area lights).
    pub leaf: Vec<u32>,
    /// The probability of going into the tree.
    pub p_tree: f32,
    /// The alias table over the non-area lights (area lights weight 0), and each light's
    /// pick probability outside the tree, (1 - p_tree) times its share there.
    pub others: LightDistribution,
    pub other_prob: Vec<f32>,
}

/// The bounds of area light `i` of `scene` (None for other kinds and dark lights).
fn area_bounds(scene: &Scene, light: &Light, radius: f32) -> Option<LightBounds> {
    let Light::Area { triangle, .. } = *light else { return None };
    let t = scene.triangles.get(triangle as usize)?;
    let n = (t.p[1] - t.p[0]).cross(t.p[2] - t.p[0]);
    let power = light_power(light, &scene.triangles, radius) as f32;
    if !power.is_finite() || power <= 0.0 || n.length_squared() == 0.0 {
        return None;
    }
    Some(LightBounds {
        min: t.p[0].min(t.p[1]).min(t.p[2]),
        max: t.p[0].max(t.p[1]).max(t.p[2]),
        power,
        cone: Cone { axis: n.normalize(), cos_theta: 1.0 },
        cos_theta_e: 0.0,
    })
}

impl LightTree {
    /// The tree over `scene`'s area lights of positive power; None when it has none.
    pub fn new(scene: &Scene) -> Option<LightTree> {
        let (_, radius) = scene.bounding_sphere();
        let power: Vec<f64> = scene.lights.iter().map(|l| light_power(l, &scene.triangles, radius)).collect();
        let mut items: Vec<(u32, LightBounds)> = Vec::new();
        for (i, l) in scene.lights.iter().enumerate() {
            if let Some(b) = area_bounds(scene, l, radius) {
                items.push((i as u32, b));
            }
        }
        if items.is_empty() {
            return None;
        }
        let positive = |x: f64| if x.is_finite() && x > 0.0 { x } else { 0.0 };
        let total: f64 = power.iter().map(|&x| positive(x)).sum();
        let in_tree: f64 = items.iter().map(|(i, _)| positive(power[*i as usize])).sum();
        let p_tree = (in_tree / total) as f32;
        let is_area = |l: &Light| matches!(l, Light::Area { .. });
        let other_weights: Vec<f64> =
            scene.lights.iter().zip(&power).map(|(l, &p)| if is_area(l) { 0.0 } else { p }).collect();
        let others = LightDistribution::from_weights(&other_weights);
        let other_prob = scene
            .lights
            .iter()
            .zip(&others.prob)
            .map(|(l, &q)| if is_area(l) { 0.0 } else { (1.0 - p_tree) * q })
            .collect();
        let mut tree =
            LightTree { nodes: Vec::new(), leaf: vec![NO_NODE; scene.lights.len()], p_tree, others, other_prob };
        tree.build(&mut items, NO_NODE);
        Some(tree)
    }

    /// Appends the subtree of `items` (depth first, the node before its children) and
    /// returns its index.
    fn build(&mut self, items: &mut [(u32, LightBounds)], parent: u32) -> u32 {
        let bounds = items[1..].iter().fold(items[0].1, |b, (_, x)| LightBounds::union(&b, x));
        let index = self.nodes.len() as u32;
        self.nodes.push(GpuTreeNode {
            min_power: [bounds.min.x, bounds.min.y, bounds.min.z, bounds.power],
            max_cos_o: [bounds.max.x, bounds.max.y, bounds.max.z, bounds.cone.cos_theta],
            axis_cos_e: [bounds.cone.axis.x, bounds.cone.axis.y, bounds.cone.axis.z, bounds.cos_theta_e],
            links: [NO_NODE, NO_NODE, parent, NO_NODE],
        });
        if items.len() == 1 {
            self.nodes[index as usize].links[3] = items[0].0;
            self.leaf[items[0].0 as usize] = index;
            return index;
        }
        let mid = split(items, &bounds);
        let (left, right) = items.split_at_mut(mid);
        let c0 = self.build(left, index);
        let c1 = self.build(right, index);
        self.nodes[index as usize].links[0] = c0;
        self.nodes[index as usize].links[1] = c1;
        index
    }

    /// The buffer the kernels read (the module's header).
    pub fn gpu_elements(&self) -> Vec<[u32; 4]> {
        let first_light = 1 + 4 * self.nodes.len() as u32;
        let mut out = vec![[self.nodes.len() as u32, first_light, self.p_tree.to_bits(), 0]];
        for n in &self.nodes {
            out.extend_from_slice(bytemuck::cast_slice::<GpuTreeNode, [u32; 4]>(std::slice::from_ref(n)));
        }
        for i in 0..self.leaf.len() {
            out.push([
                self.leaf[i],
                self.others.alias[i],
                self.others.threshold[i].to_bits(),
                self.other_prob[i].to_bits(),
            ]);
        }
        out
    }

    /// Elements of [`LightTree::gpu_elements`] for a scene of `lights` lights of which
    /// `area` are area lights, at most (the plan's bound).
    pub fn max_elements(lights: u64, area: u64) -> u64 {
        1 + 4 * (2 * area).saturating_sub(1) + lights
    }
}

/// Orders `items` for a split and returns the size of the first part: the cheapest
/// binned SAOH split over the three axes of the centroids' box, else (all centroids in
/// one bin) the middle.
fn split(items: &mut [(u32, LightBounds)], bounds: &LightBounds) -> usize {
    let centroid = |b: &LightBounds| 0.5 * (b.min + b.max);
    let (cmin, cmax) = items
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), (_, b)| (lo.min(centroid(b)), hi.max(centroid(b))));
    let extent = bounds.max - bounds.min;
    let mut best: Option<(f32, usize, usize)> = None; // (cost, axis, bins below the split)
    for axis in 0..3 {
        let (lo, hi) = (cmin[axis], cmax[axis]);
        if hi <= lo {
            continue;
        }
        let bin = |b: &LightBounds| (((centroid(b)[axis] - lo) / (hi - lo) * BINS as f32) as usize).min(BINS - 1);
        let mut bins: [Option<LightBounds>; BINS] = [None; BINS];
        for (_, b) in items.iter() {
            let k = bin(b);
            bins[k] = Some(bins[k].map_or(*b, |x| LightBounds::union(&x, b)));
        }
        let kr = extent.max_element() / extent[axis].max(f32::MIN_POSITIVE);
        let merge = |s: &[Option<LightBounds>]| {
            s.iter()
                .flatten()
                .fold(None, |acc: Option<LightBounds>, b| Some(acc.map_or(*b, |a| LightBounds::union(&a, b))))
        };
        for k in 1..BINS {
            let (Some(a), Some(b)) = (merge(&bins[..k]), merge(&bins[k..])) else { continue };
            let cost = a.cost(kr) + b.cost(kr);
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, k));
            }
        }
    }
    let Some((_, axis, k)) = best else { return items.len() / 2 };
    let (lo, hi) = (cmin[axis], cmax[axis]);
    let below = |b: &LightBounds| ((((centroid(b)[axis] - lo) / (hi - lo)) * BINS as f32) as usize).min(BINS - 1) < k;
    let mut mid = 0;
    for i in 0..items.len() {
        if below(&items[i].1) {
            items.swap(i, mid);
            mid += 1;
        }
    }
    if mid == 0 || mid == items.len() {
        items.len() / 2
    } else {
        mid
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cone_union_holds_both() {
        let a = Cone { axis: Vec3::Z, cos_theta: 1.0 };
        let b = Cone { axis: Vec3::X, cos_theta: 1.0 };
        let u = Cone::union(a, b);
        assert!((u.cos_theta - std::f32::consts::FRAC_PI_4.cos()).abs() < 1e-5, "{u:?}");
        for w in [Vec3::Z, Vec3::X] {
            assert!(u.axis.dot(w) >= u.cos_theta - 1e-5);
        }
        // Opposite axes: the whole sphere.
        assert_eq!(Cone::union(a, Cone { axis: -Vec3::Z, cos_theta: 1.0 }).cos_theta, -1.0);
        // One inside the other.
        let wide = Cone { axis: Vec3::Z, cos_theta: 0.0 };
        assert_eq!(Cone::union(wide, Cone { axis: Vec3::new(0.0, 0.6, 0.8), cos_theta: 0.99 }), wide);
    }
}
