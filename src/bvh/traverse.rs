//! CPU traversal of the flattened BVH: over the uploaded 4-wide nodes ([`GpuBvh`]) the
//! same algorithm, order and float operations as `trace_closest` / `trace_any` in
//! glsl/bvh.glsl, so it is the reference for the GPU tests and a debugging aid; over the
//! builder's BVH2 ([`Bvh`]) the same loop with two children per node, a second traversal
//! of the same tree that the tests compare with the first.
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
use super::layout::{
    decode_ref, leaf_ref, GpuBvh, GpuNode, GpuNode4, GpuPrim, EMPTY_REF, LEAF_FLAG, MAX_STACK_INSTANCED,
};

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
    /// Internal nodes visited (each tests two boxes in a BVH2, four in the 4-wide form).
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

/// The ray a traversal is following: world space, or an instance's object space.
#[derive(Clone, Copy)]
pub struct TraversalRay {
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

/// The traversal stack: child references and their entry distances.
pub struct Stack {
    refs: [u32; MAX_STACK_INSTANCED],
    t: [f32; MAX_STACK_INSTANCED],
    sp: usize,
}

impl Stack {
    fn new() -> Stack {
        Stack { refs: [0; MAX_STACK_INSTANCED], t: [0.0; MAX_STACK_INSTANCED], sp: 0 }
    }

    fn push(&mut self, r: u32, t: f32) {
        self.refs[self.sp] = r;
        self.t[self.sp] = t;
        self.sp += 1;
    }

    /// Pops the next entry whose entry distance is not beyond `tmax` (`BVH_POP`); at a
    /// [`RETURN`] marker the ray goes back to world space (`space`: the current ray, the
    /// world ray, the current instance).
    fn pop(&mut self, tmax: f32, space: (&mut TraversalRay, &TraversalRay, &mut Option<u32>)) -> u32 {
        let (r, world, instance) = space;
        while self.sp > 0 {
            self.sp -= 1;
            if self.t[self.sp] <= tmax {
                if self.refs[self.sp] == RETURN {
                    *r = *world;
                    *instance = None;
                    continue;
                }
                return self.refs[self.sp];
            }
        }
        DONE
    }
}

/// An array of internal nodes: the step of the traversal at one of them.
pub trait NodeArray {
    /// Tests node `n`'s child boxes; pushes the hit children but the nearest, which it
    /// returns (`None`: no child hit).
    fn visit(&self, n: u32, r: &TraversalRay, tmin: f32, tmax: f32, stack: &mut Stack) -> Option<u32>;
}

/// The builder's BVH2: the nearer hit child next, the farther one pushed.
impl NodeArray for [GpuNode] {
    fn visit(&self, n: u32, r: &TraversalRay, tmin: f32, tmax: f32, stack: &mut Stack) -> Option<u32> {
        let n = &self[n as usize];
        let [b0, b1] = n.boxes();
        let h0 = ray_box(b0.min, b0.max, r.o, r.inv_d, tmin, tmax);
        let h1 = ray_box(b1.min, b1.max, r.o, r.inv_d, tmin, tmax);
        match (h0, h1) {
            (Some(t0), Some(t1)) => {
                let swap = t1 < t0;
                stack.push(n.child(usize::from(!swap)), if swap { t0 } else { t1 });
                Some(n.child(usize::from(swap)))
            }
            (Some(_), None) => Some(n.child(0)),
            (None, Some(_)) => Some(n.child(1)),
            (None, None) => None,
        }
    }
}

/// The uploaded 4-wide nodes, as glsl/bvh.glsl: the hit children sorted by entry
/// distance (a 5-comparator network, misses last), the nearest next, the others pushed
/// farthest first.
impl NodeArray for [GpuNode4] {
    fn visit(&self, n: u32, r: &TraversalRay, tmin: f32, tmax: f32, stack: &mut Stack) -> Option<u32> {
        let n = &self[n as usize];
        let boxes = n.boxes();
        let mut k = [f32::INFINITY; 4];
        let mut c = [0u32; 4];
        for i in 0..4 {
            c[i] = n.child(i);
            if let Some(t) = ray_box(boxes[i].min, boxes[i].max, r.o, r.inv_d, tmin, tmax) {
                if c[i] != EMPTY_REF {
                    k[i] = t;
                }
            }
        }
        for (a, b) in [(0, 1), (2, 3), (0, 2), (1, 3), (1, 2)] {
            if k[b] < k[a] {
                k.swap(a, b);
                c.swap(a, b);
            }
        }
        for i in (1..4).rev() {
            if k[i] < f32::INFINITY {
                stack.push(c[i], k[i]);
            }
        }
        (k[0] < f32::INFINITY).then_some(c[0])
    }
}

/// The traversal of `bvh_traverse` in glsl/bvh.glsl: descend through internal nodes
/// (nearest hit child first, the others pushed with their entry distances); the first
/// leaf reached is set aside (in world space only) and the descent goes on to the next
/// leaf; then the set-aside leaf is tested, and each leaf popped after it, and the next
/// entry is popped whose entry distance is not beyond the closest hit. An instance
/// primitive pushes what was still to visit in world space (the leaf after a set-aside
/// one, the rest of its own leaf) and a [`RETURN`] marker, moves the ray into the
/// instance's object space and descends into its mesh's tree; popping the marker moves
/// the ray back.
fn traverse<N: NodeArray + ?Sized>(
    nodes: &N,
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
    let mut stack = Stack::new();
    let mut cur = 0u32;
    let mut postponed = DONE;
    let mut best = None;
    'outer: loop {
        loop {
            if cur & LEAF_FLAG != 0 {
                if cur == DONE || postponed != DONE || instance.is_some() {
                    break;
                }
                postponed = cur;
                cur = stack.pop(*tmax, (&mut r, &world, &mut instance));
                continue;
            }
            counts.nodes += 1;
            cur = match nodes.visit(cur, &r, tmin, *tmax, &mut stack) {
                Some(next) => next,
                None => stack.pop(*tmax, (&mut r, &world, &mut instance)),
            };
        }
        if postponed == DONE && cur == DONE {
            break;
        }
        loop {
            let leaf = if postponed != DONE {
                std::mem::replace(&mut postponed, DONE)
            } else if cur != DONE && cur & LEAF_FLAG != 0 {
                std::mem::replace(&mut cur, DONE)
            } else {
                break;
            };
            let Err((first, count)) = decode_ref(leaf) else { unreachable!() };
            for slot in first as usize..(first + count) as usize {
                let p = &prims[slot];
                if p.is_instance() {
                    if cur != DONE {
                        stack.push(cur, f32::NEG_INFINITY);
                    }
                    let end = first + count;
                    if slot as u32 + 1 < end {
                        stack.push(leaf_ref(slot as u32 + 1, end - slot as u32 - 1), f32::NEG_INFINITY);
                    }
                    stack.push(RETURN, f32::NEG_INFINITY);
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
            if cur == DONE {
                cur = stack.pop(*tmax, (&mut r, &world, &mut instance));
            }
        }
        if cur == DONE {
            break;
        }
    }
    best
}

/// Closest hit in `[tmin, tmax]` over flattened BVH arrays (`nodes`: the BVH2's or the
/// uploaded 4-wide ones).
pub fn closest_hit<N: NodeArray + ?Sized>(
    nodes: &N,
    prims: &[GpuPrim],
    ray: &Ray,
    tmin: f32,
    tmax: f32,
) -> Option<Hit> {
    closest_hit_counted(nodes, prims, ray, tmin, tmax).0
}

/// [`closest_hit`] and the work it took.
pub fn closest_hit_counted<N: NodeArray + ?Sized>(
    nodes: &N,
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
pub fn any_hit<N: NodeArray + ?Sized>(nodes: &N, prims: &[GpuPrim], ray: &Ray, tmin: f32, tmax: f32) -> bool {
    any_hit_counted(nodes, prims, ray, tmin, tmax).0
}

/// [`any_hit`] and the work it took.
pub fn any_hit_counted<N: NodeArray + ?Sized>(
    nodes: &N,
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
        closest_hit(&self.nodes[..], &self.prims, ray, tmin, tmax)
    }

    /// CPU mirror of `trace_any` in glsl/bvh.glsl.
    pub fn any_hit(&self, ray: &Ray, tmin: f32, tmax: f32) -> bool {
        any_hit(&self.nodes[..], &self.prims, ray, tmin, tmax)
    }
}

impl Bvh {
    /// Closest hit over the BVH2 (the same hits as [`GpuBvh::closest_hit`] over its
    /// 4-wide form, possibly another primitive where two are hit at the same distance).
    pub fn closest_hit(&self, ray: &Ray, tmin: f32, tmax: f32) -> Option<Hit> {
        closest_hit(&self.nodes[..], &self.prims, ray, tmin, tmax)
    }

    pub fn any_hit(&self, ray: &Ray, tmin: f32, tmax: f32) -> bool {
        any_hit(&self.nodes[..], &self.prims, ray, tmin, tmax)
    }
}
