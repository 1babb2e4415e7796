//! CPU traversal of the flattened BVH: the same algorithm, order and float operations as
//! `trace_closest` / `trace_any` in glsl/bvh.glsl, so it is the reference for the GPU
//! tests and a debugging aid.
//!
//! Ray/box test: slabs with `t = (b - o) * (1/d)` and the far distance widened by
//! [`BOX_ROBUST_SCALE`] (Ize, "Robust BVH Ray Traversal", JCGT 2(2), 2013, uses
//! `1 + 2 gamma(3)`; we allow more because Vulkan only bounds `1/x` to 2.5 ULP).
//! Direction components smaller than 1e-30 in magnitude are replaced by +-1e-30 before
//! the reciprocal, so `0 * inf` never produces a NaN; node boxes are padded
//! ([`super::Aabb::padded`]) so that a ray starting exactly on a box plane and parallel
//! to it still enters the box.

use glam::Vec3;

use super::build::Bvh;
use super::intersect::{intersect_sphere, intersect_triangle, Hit, Ray, RayShear};
use super::layout::{decode_ref, GpuBvh, GpuNode, GpuPrim, NodeLayout, MAX_DEPTH};

/// Factor applied to a box's exit distance (`BVH_ROBUST_SCALE` in glsl/bvh.glsl).
pub const BOX_ROBUST_SCALE: f32 = 1.000002;

/// `1/d` with tiny components clamped to +-1e-30 (`bvh_safe_inv` in GLSL).
pub fn safe_inv(d: Vec3) -> Vec3 {
    let f = |x: f32| {
        if x.abs() < 1e-30 {
            if x < 0.0 {
                -1e-30
            } else {
                1e-30
            }
        } else {
            x
        }
    };
    Vec3::ONE / Vec3::new(f(d.x), f(d.y), f(d.z))
}

/// Slab test; returns the entry distance when `[tmin, tmax]` overlaps the box.
#[inline]
pub fn ray_box(lo: Vec3, hi: Vec3, o: Vec3, inv_d: Vec3, tmin: f32, tmax: f32) -> Option<f32> {
    let t0 = (lo - o) * inv_d;
    let t1 = (hi - o) * inv_d;
    let tl = t0.min(t1);
    let th = t0.max(t1);
    let tn = tl.x.max(tl.y).max(tl.z.max(tmin));
    let tf = th.x.min(th.y).min(th.z.min(tmax));
    (tn <= tf * BOX_ROBUST_SCALE).then_some(tn)
}

/// What a leaf test reports: the slot in the primitive array and barycentrics.
struct Best {
    slot: usize,
    u: f32,
    v: f32,
}

fn traverse(
    nodes: &[GpuNode],
    prims: &[GpuPrim],
    layout: NodeLayout,
    ray: &Ray,
    tmin: f32,
    tmax: &mut f32,
    any: bool,
) -> Option<Best> {
    let o = ray.o;
    let d = ray.d;
    let inv_d = safe_inv(d);
    let sh = RayShear::new(d);
    let mut stack = [0u32; MAX_DEPTH as usize];
    let mut sp = 0usize;
    let mut cur = 0u32;
    let mut best = None;
    loop {
        match decode_ref(cur) {
            Ok(ni) => {
                let n = &nodes[ni as usize];
                let b0 = n.bounds(layout, 0);
                let b1 = n.bounds(layout, 1);
                let h0 = ray_box(b0.min, b0.max, o, inv_d, tmin, *tmax);
                let h1 = ray_box(b1.min, b1.max, o, inv_d, tmin, *tmax);
                let (c0, c1) = (n.child(layout, 0), n.child(layout, 1));
                match (h0, h1) {
                    (Some(t0), Some(t1)) => {
                        let (near, far) = if t1 < t0 { (c1, c0) } else { (c0, c1) };
                        stack[sp] = far;
                        sp += 1;
                        cur = near;
                        continue;
                    }
                    (Some(_), None) => {
                        cur = c0;
                        continue;
                    }
                    (None, Some(_)) => {
                        cur = c1;
                        continue;
                    }
                    (None, None) => {}
                }
            }
            Err((first, count)) => {
                let leaf = prims.iter().enumerate().skip(first as usize);
                for (slot, p) in leaf.take(count as usize) {
                    if p.is_sphere() {
                        let c = Vec3::new(p.a[0], p.a[1], p.a[2]);
                        if let Some(t) = intersect_sphere(o, d, c, p.b[0], tmin, *tmax) {
                            *tmax = t;
                            best = Some(Best { slot, u: 0.0, v: 0.0 });
                            if any {
                                return best;
                            }
                        }
                    } else if let Some((t, u, v)) = intersect_triangle(o, &sh, &p.vertices(), tmin, *tmax) {
                        *tmax = t;
                        best = Some(Best { slot, u, v });
                        if any {
                            return best;
                        }
                    }
                }
            }
        }
        if sp == 0 {
            break;
        }
        sp -= 1;
        cur = stack[sp];
    }
    best
}

/// Closest hit in `[tmin, tmax]` over flattened BVH arrays.
pub fn closest_hit(
    nodes: &[GpuNode],
    prims: &[GpuPrim],
    layout: NodeLayout,
    ray: &Ray,
    tmin: f32,
    tmax: f32,
) -> Option<Hit> {
    let mut t = tmax;
    let b = traverse(nodes, prims, layout, ray, tmin, &mut t, false)?;
    let p = &prims[b.slot];
    Some(Hit { t, prim: p.id(), u: b.u, v: b.v, is_sphere: p.is_sphere(), material: p.material() })
}

/// Whether anything is hit in `[tmin, tmax]` (shadow rays).
pub fn any_hit(nodes: &[GpuNode], prims: &[GpuPrim], layout: NodeLayout, ray: &Ray, tmin: f32, tmax: f32) -> bool {
    let mut t = tmax;
    traverse(nodes, prims, layout, ray, tmin, &mut t, true).is_some()
}

impl GpuBvh {
    /// CPU mirror of `trace_closest` in glsl/bvh.glsl.
    pub fn closest_hit(&self, ray: &Ray, tmin: f32, tmax: f32) -> Option<Hit> {
        closest_hit(&self.nodes, &self.prims, self.layout, ray, tmin, tmax)
    }

    /// CPU mirror of `trace_any` in glsl/bvh.glsl.
    pub fn any_hit(&self, ray: &Ray, tmin: f32, tmax: f32) -> bool {
        any_hit(&self.nodes, &self.prims, self.layout, ray, tmin, tmax)
    }
}

impl Bvh {
    /// Same as [`GpuBvh::closest_hit`] (the arrays are the same).
    pub fn closest_hit(&self, ray: &Ray, tmin: f32, tmax: f32) -> Option<Hit> {
        closest_hit(&self.nodes, &self.prims, self.layout, ray, tmin, tmax)
    }

    pub fn any_hit(&self, ray: &Ray, tmin: f32, tmax: f32) -> bool {
        any_hit(&self.nodes, &self.prims, self.layout, ray, tmin, tmax)
    }
}
