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
use super::layout::{decode_ref, GpuBvh, GpuNode, GpuPrim, LEAF_FLAG, MAX_DEPTH};

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

/// Work done by one traversal (CPU mirror; the GPU does the same).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TraversalCounts {
    /// Internal nodes visited (each tests two boxes).
    pub nodes: u32,
    /// Primitive tests.
    pub prims: u32,
}

/// "Stack empty" (`BVH_DONE` in GLSL; has the leaf bit set, so it ends the node loop).
const DONE: u32 = 0xffff_ffff;

/// Pops the next stack entry whose entry distance is not beyond `tmax` (`BVH_POP`).
#[inline]
fn pop(stack: &[u32], stack_t: &[f32], sp: &mut usize, tmax: f32) -> u32 {
    while *sp > 0 {
        *sp -= 1;
        if stack_t[*sp] <= tmax {
            return stack[*sp];
        }
    }
    DONE
}

/// The traversal of `bvh_traverse` in glsl/bvh.glsl: descend through internal nodes
/// (nearer child first, the farther one pushed with its entry distance) until a leaf,
/// test the leaf, pop the next entry whose entry distance is not beyond the closest hit.
fn traverse(
    nodes: &[GpuNode],
    prims: &[GpuPrim],
    ray: &Ray,
    tmin: f32,
    tmax: &mut f32,
    any: bool,
    counts: &mut TraversalCounts,
) -> Option<Best> {
    let o = ray.o;
    let d = ray.d;
    let inv_d = safe_inv(d);
    let sh = RayShear::new(d);
    let mut stack = [0u32; MAX_DEPTH as usize];
    let mut stack_t = [0f32; MAX_DEPTH as usize];
    let mut sp = 0usize;
    let mut cur = 0u32;
    let mut best = None;
    loop {
        while cur & LEAF_FLAG == 0 {
            counts.nodes += 1;
            let n = &nodes[cur as usize];
            let [b0, b1] = n.boxes();
            let h0 = ray_box(b0.min, b0.max, o, inv_d, tmin, *tmax);
            let h1 = ray_box(b1.min, b1.max, o, inv_d, tmin, *tmax);
            cur = match (h0, h1) {
                (Some(t0), Some(t1)) => {
                    let swap = t1 < t0;
                    stack[sp] = n.child(usize::from(!swap));
                    stack_t[sp] = if swap { t0 } else { t1 };
                    sp += 1;
                    n.child(usize::from(swap))
                }
                (Some(_), None) => n.child(0),
                (None, Some(_)) => n.child(1),
                (None, None) => pop(&stack, &stack_t, &mut sp, *tmax),
            };
        }
        if cur == DONE {
            break;
        }
        let Err((first, count)) = decode_ref(cur) else { unreachable!() };
        let leaf = prims.iter().enumerate().skip(first as usize);
        for (slot, p) in leaf.take(count as usize) {
            counts.prims += 1;
            let hit = if p.is_sphere() {
                let c = Vec3::new(p.a[0], p.a[1], p.a[2]);
                intersect_sphere(o, d, c, p.b[0], tmin, *tmax).map(|t| (t, 0.0, 0.0))
            } else {
                intersect_triangle(o, &sh, &p.vertices(), tmin, *tmax)
            };
            if let Some((t, u, v)) = hit {
                *tmax = t;
                best = Some(Best { slot, u, v });
                if any {
                    return best;
                }
            }
        }
        cur = pop(&stack, &stack_t, &mut sp, *tmax);
        if cur == DONE {
            break;
        }
    }
    best
}

/// Closest hit in `[tmin, tmax]` over flattened BVH arrays.
pub fn closest_hit(nodes: &[GpuNode], prims: &[GpuPrim], ray: &Ray, tmin: f32, tmax: f32) -> Option<Hit> {
    closest_hit_counted(nodes, prims, ray, tmin, tmax).0
}

/// [`closest_hit`] and the work it took.
pub fn closest_hit_counted(
    nodes: &[GpuNode],
    prims: &[GpuPrim],
    ray: &Ray,
    tmin: f32,
    tmax: f32,
) -> (Option<Hit>, TraversalCounts) {
    let mut t = tmax;
    let mut counts = TraversalCounts::default();
    let hit = traverse(nodes, prims, ray, tmin, &mut t, false, &mut counts).map(|b| {
        let p = &prims[b.slot];
        Hit { t, prim: p.id(), u: b.u, v: b.v, is_sphere: p.is_sphere(), material: p.material() }
    });
    (hit, counts)
}

/// Whether anything is hit in `[tmin, tmax]` (shadow rays).
pub fn any_hit(nodes: &[GpuNode], prims: &[GpuPrim], ray: &Ray, tmin: f32, tmax: f32) -> bool {
    any_hit_counted(nodes, prims, ray, tmin, tmax).0
}

/// [`any_hit`] and the work it took.
pub fn any_hit_counted(
    nodes: &[GpuNode],
    prims: &[GpuPrim],
    ray: &Ray,
    tmin: f32,
    tmax: f32,
) -> (bool, TraversalCounts) {
    let mut t = tmax;
    let mut counts = TraversalCounts::default();
    let hit = traverse(nodes, prims, ray, tmin, &mut t, true, &mut counts).is_some();
    (hit, counts)
}

impl GpuBvh {
    /// CPU mirror of `trace_closest` in glsl/bvh.glsl.
    pub fn closest_hit(&self, ray: &Ray, tmin: f32, tmax: f32) -> Option<Hit> {
        closest_hit(&self.nodes, &self.prims, ray, tmin, tmax)
    }

    /// CPU mirror of `trace_any` in glsl/bvh.glsl.
    pub fn any_hit(&self, ray: &Ray, tmin: f32, tmax: f32) -> bool {
        any_hit(&self.nodes, &self.prims, ray, tmin, tmax)
    }
}

impl Bvh {
    /// Same as [`GpuBvh::closest_hit`] (the arrays are the same).
    pub fn closest_hit(&self, ray: &Ray, tmin: f32, tmax: f32) -> Option<Hit> {
        closest_hit(&self.nodes, &self.prims, ray, tmin, tmax)
    }

    pub fn any_hit(&self, ray: &Ray, tmin: f32, tmax: f32) -> bool {
        any_hit(&self.nodes, &self.prims, ray, tmin, tmax)
    }
}
