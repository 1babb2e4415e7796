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
use super::layout::{decode_ref, leaf_ref, GpuBvh, GpuNode, GpuPrim, LEAF_FLAG, MAX_STACK_INSTANCED};

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
    instance: Option<u32>,
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
/// Stack marker: the mesh tree of an instance is done, the ray goes back to world space
/// (`BVH_RETURN`; a leaf reference no leaf has, since leaves hold at most 4 primitives).
const RETURN: u32 = 0xffff_fffe;

/// An instance record's affine rows applied to a point (`w = 1`) or a direction (`w = 0`),
/// as `bvh_apply_rows` in GLSL.
fn apply_rows(rows: &GpuPrim, p: Vec3, w: f32) -> Vec3 {
    let r = |m: [f32; 4]| m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3] * w;
    Vec3::new(r(rows.a), r(rows.b), r(rows.c))
}

/// Pops the next entry whose entry distance is not beyond `tmax` (`BVH_POP`); at a
/// [`RETURN`] marker the ray goes back to world space (`space`: the current ray, the
/// world ray, the current instance).
#[inline]
fn pop(
    stack: &[u32],
    stack_t: &[f32],
    sp: &mut usize,
    tmax: f32,
    space: (&mut TraversalRay, &TraversalRay, &mut Option<u32>),
) -> u32 {
    let (r, world, instance) = space;
    while *sp > 0 {
        *sp -= 1;
        if stack_t[*sp] <= tmax {
            if stack[*sp] == RETURN {
                *r = *world;
                *instance = None;
                continue;
            }
            return stack[*sp];
        }
    }
    DONE
}

/// The ray a traversal is following: world space, or an instance's object space.
#[derive(Clone, Copy)]
struct TraversalRay {
    o: Vec3,
    d: Vec3,
    inv_d: Vec3,
    sh: RayShear,
}

impl TraversalRay {
    fn new(o: Vec3, d: Vec3) -> TraversalRay {
        TraversalRay { o, d, inv_d: safe_inv(d), sh: RayShear::new(d) }
    }
}

/// The traversal of `bvh_traverse` in glsl/bvh.glsl: descend through internal nodes
/// (nearer child first, the farther one pushed with its entry distance) until a leaf,
/// test the leaf, pop the next entry whose entry distance is not beyond the closest hit.
/// An instance primitive pushes the rest of its leaf and a [`RETURN`] marker, moves the
/// ray into the instance's object space and descends into its mesh's tree; popping the
/// marker moves the ray back.
fn traverse(
    nodes: &[GpuNode],
    prims: &[GpuPrim],
    ray: &Ray,
    tmin: f32,
    tmax: &mut f32,
    any: bool,
    counts: &mut TraversalCounts,
) -> Option<Best> {
    let world = TraversalRay::new(ray.o, ray.d);
    let mut r = TraversalRay::new(ray.o, ray.d);
    let mut instance: Option<u32> = None;
    let mut stack = [0u32; MAX_STACK_INSTANCED];
    let mut stack_t = [0f32; MAX_STACK_INSTANCED];
    let mut sp = 0usize;
    let mut cur = 0u32;
    let mut best = None;
    'outer: loop {
        while cur & LEAF_FLAG == 0 {
            counts.nodes += 1;
            let n = &nodes[cur as usize];
            let [b0, b1] = n.boxes();
            let h0 = ray_box(b0.min, b0.max, r.o, r.inv_d, tmin, *tmax);
            let h1 = ray_box(b1.min, b1.max, r.o, r.inv_d, tmin, *tmax);
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
                (None, None) => pop(&stack, &stack_t, &mut sp, *tmax, (&mut r, &world, &mut instance)),
            };
        }
        if cur == DONE {
            break;
        }
        let Err((first, count)) = decode_ref(cur) else { unreachable!() };
        for slot in first as usize..(first + count) as usize {
            let p = &prims[slot];
            if p.is_instance() {
                let end = first + count;
                if slot as u32 + 1 < end {
                    stack[sp] = leaf_ref(slot as u32 + 1, end - slot as u32 - 1);
                    stack_t[sp] = f32::NEG_INFINITY;
                    sp += 1;
                }
                stack[sp] = RETURN;
                stack_t[sp] = f32::NEG_INFINITY;
                sp += 1;
                let (root, record) = p.instance_target();
                let w2o = &prims[record as usize];
                r = TraversalRay::new(apply_rows(w2o, world.o, 1.0), apply_rows(w2o, world.d, 0.0));
                instance = Some(p.id());
                cur = root;
                continue 'outer;
            }
            counts.prims += 1;
            let hit = if p.is_sphere() {
                let c = Vec3::new(p.a[0], p.a[1], p.a[2]);
                intersect_sphere(r.o, r.d, c, p.b[0], tmin, *tmax).map(|t| (t, 0.0, 0.0))
            } else {
                intersect_triangle(r.o, &r.sh, &p.vertices(), tmin, *tmax)
            };
            if let Some((t, u, v)) = hit {
                *tmax = t;
                best = Some(Best { slot, u, v, instance });
                if any {
                    return best;
                }
            }
        }
        cur = pop(&stack, &stack_t, &mut sp, *tmax, (&mut r, &world, &mut instance));
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
        Hit { t, prim: p.id(), u: b.u, v: b.v, is_sphere: p.is_sphere(), material: p.material(), instance: b.instance }
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
