//! Binned SAH build (Wald, "On fast Construction of SAH-based Bounding Volume Hierarchies",
//! RT 2007) over one unified primitive list: all triangles, then all spheres.
//!
//! * Each node bins the primitives' centroids into `bins` equal intervals of the
//!   centroid bounds on each of the three axes, and evaluates the SAH at the `bins - 1`
//!   planes between bins: `C = C_trav + C_isect (A_L N_L + A_R N_R) / A`, against the
//!   leaf cost `C_isect N` (allowed only for `N <= max_leaf`). Defaults: 16 bins,
//!   `C_trav = 1`, `C_isect = 1`, `max_leaf = 4` (see [`BuildOptions`]).
//! * Primitives whose centroids coincide are split in the middle of their current order.
//! * Depth bound: a split whose children could no longer be finished within
//!   [`MAX_DEPTH`] internal levels by median splits is replaced by a median split (sort
//!   by centroid on the widest axis, halve), which needs `ceil(log2(n / max_leaf))`
//!   levels for `n` primitives. So no path exceeds [`MAX_DEPTH`] levels and the GLSL
//!   traversal stack cannot overflow.
//! * Primitives with non-finite bounds (NaN or infinite coordinates or radius, or
//!   coordinates so close to `f32::MAX` that the centroid or the padded box overflows) are
//!   left out and counted in [`BuildStats::skipped_non_finite`].
//! * The two subtrees of large nodes are built on separate threads
//!   (`std::thread::scope`) up to [`BuildOptions::threads`]; so is the final flattening.
//! * Flattening pads every box ([`Aabb::padded`]) and quantises it outwards to 8 bits per
//!   coordinate ([`super::layout::quantize_boxes`]).

use std::time::Instant;

use glam::Vec3;

use super::aabb::Aabb;
use super::intersect::{sphere_is_finite, triangle_is_finite};
use super::layout::{decode_ref, leaf_ref, GpuBvh, GpuNode, GpuPrim, MAX_DEPTH, MAX_LEAF_PRIMS, MAX_PRIMS};
use crate::scene::{Sphere, Triangle};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SplitMethod {
    /// Binned surface area heuristic (the default).
    Sah,
    /// Object median on the widest centroid axis (a baseline for tests).
    Median,
}

#[derive(Clone, Debug)]
pub struct BuildOptions {
    pub method: SplitMethod,
    /// SAH bins per axis (2..=64).
    pub bins: usize,
    /// Largest leaf (1..=[`MAX_LEAF_PRIMS`]).
    pub max_leaf: usize,
    /// SAH cost of visiting an internal node (two box tests).
    pub traversal_cost: f32,
    /// SAH cost of one primitive test.
    pub intersection_cost: f32,
    /// Worker threads; 0 = `std::thread::available_parallelism()`.
    pub threads: usize,
}

impl Default for BuildOptions {
    fn default() -> Self {
        BuildOptions {
            method: SplitMethod::Sah,
            bins: 16,
            max_leaf: MAX_LEAF_PRIMS,
            traversal_cost: 1.0,
            intersection_cost: 1.0,
            threads: 0,
        }
    }
}

/// Figures of one build.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BuildStats {
    pub triangles: usize,
    pub spheres: usize,
    /// Primitives left out because of non-finite bounds.
    pub skipped_non_finite: usize,
    /// Internal nodes (= the length of the node array).
    pub nodes: usize,
    pub leaves: usize,
    /// Most internal-node levels on a root-to-leaf path (root = 1), `<= MAX_DEPTH`.
    pub max_depth: u32,
    /// SAH cost of the tree with the build's cost constants, relative to the root box.
    pub sah_cost: f64,
    pub build_seconds: f64,
}

/// A built BVH, already flattened to the GPU layout (see [`super::layout`]).
#[derive(Clone, Debug)]
pub struct Bvh {
    pub nodes: Vec<GpuNode>,
    /// Primitives in leaf order.
    pub prims: Vec<GpuPrim>,
    pub stats: BuildStats,
}

impl Bvh {
    /// The buffers to upload (a copy; see [`Bvh::into_gpu`]).
    pub fn to_gpu(&self) -> GpuBvh {
        GpuBvh {
            nodes: self.nodes.clone(),
            prims: self.prims.clone(),
            num_triangles: self.stats.triangles as u32,
            num_spheres: self.stats.spheres as u32,
        }
    }

    pub fn into_gpu(self) -> GpuBvh {
        GpuBvh {
            nodes: self.nodes,
            prims: self.prims,
            num_triangles: self.stats.triangles as u32,
            num_spheres: self.stats.spheres as u32,
        }
    }

    /// A box around everything in the BVH: the union of the root's (padded, quantised)
    /// child boxes.
    pub fn bounds(&self) -> Aabb {
        let [a, b] = self.nodes[0].boxes();
        a.union(&b)
    }
}

/// Builds with the default options (binned SAH, 16 bins, leaves of at most 4).
///
/// Panics if there are more than 2^28 primitives.
pub fn build(triangles: &[Triangle], spheres: &[Sphere]) -> Bvh {
    build_with(triangles, spheres, &BuildOptions::default())
}

/// A primitive's box and its unified index (triangles first, then spheres). 32 bytes.
#[derive(Clone, Copy, Debug)]
struct PrimRef {
    min: Vec3,
    id: u32,
    max: Vec3,
    _pad: u32,
}

impl PrimRef {
    /// Twice the centroid (the factor 2 is irrelevant to binning and saves a multiply).
    #[inline]
    fn c2(&self) -> Vec3 {
        self.min + self.max
    }

    fn aabb(&self) -> Aabb {
        Aabb { min: self.min, max: self.max }
    }
}

#[derive(Clone, Copy, Debug)]
struct Node {
    boxes: [Aabb; 2],
    children: [u32; 2],
}

const MAX_BINS: usize = 64;
/// Subtrees with at least this many primitives may be built on another thread.
const PARALLEL_MIN_PRIMS: usize = 32 * 1024;

/// Builds a BVH over `triangles` then `spheres` with the given options.
///
/// Panics if there are more than 2^28 primitives or options are out of range.
pub fn build_with(triangles: &[Triangle], spheres: &[Sphere], opts: &BuildOptions) -> Bvh {
    let start = Instant::now();
    assert!((2..=MAX_BINS).contains(&opts.bins), "bins out of range");
    assert!((1..=MAX_LEAF_PRIMS).contains(&opts.max_leaf), "max_leaf out of range");
    let total = triangles.len() + spheres.len();
    assert!(total <= MAX_PRIMS, "too many primitives for the BVH ({total})");
    let nt = triangles.len();

    let mut refs: Vec<PrimRef> = Vec::with_capacity(total);
    let mut bounds = Aabb::EMPTY;
    let mut cbounds = Aabb::EMPTY;
    let mut skipped = 0usize;
    let mut push = |min: Vec3, max: Vec3, id: usize| {
        let r = PrimRef { min, id: id as u32, max, _pad: 0 };
        // The centroid sum or the padded box (see Aabb::padded) can overflow for
        // coordinates near f32::MAX: skip those too.
        let padded = r.aabb().padded();
        if !(r.c2().is_finite() && padded.min.is_finite() && padded.max.is_finite()) {
            return false;
        }
        bounds.grow(&r.aabb());
        cbounds.grow_point(r.c2());
        refs.push(r);
        true
    };
    for (i, t) in triangles.iter().enumerate() {
        if !triangle_is_finite(t) {
            skipped += 1;
            continue;
        }
        let min = t.p[0].min(t.p[1]).min(t.p[2]);
        let max = t.p[0].max(t.p[1]).max(t.p[2]);
        skipped += usize::from(!push(min, max, i));
    }
    for (i, s) in spheres.iter().enumerate() {
        if !sphere_is_finite(s) {
            skipped += 1;
            continue;
        }
        let r = Vec3::splat(s.radius.abs());
        skipped += usize::from(!push(s.center - r, s.center + r, nt + i));
    }

    let threads =
        if opts.threads == 0 { std::thread::available_parallelism().map_or(1, |n| n.get()) } else { opts.threads };
    let ctx = Ctx { opts };
    let mut nodes: Vec<Node> = Vec::with_capacity(refs.len() / 2 + 1);
    let root = ctx.build_node(&mut refs, 0, bounds, cbounds, 1, threads, true, &mut nodes);
    debug_assert_eq!(root, 0);

    let prims: Vec<GpuPrim> = refs
        .iter()
        .map(|r| {
            let id = r.id as usize;
            if id < nt {
                let t = &triangles[id];
                GpuPrim::triangle(t.p, id as u32, t.material)
            } else {
                let s = &spheres[id - nt];
                GpuPrim::sphere(s.center, s.radius.abs(), (id - nt) as u32, s.material)
            }
        })
        .collect();
    drop(refs);
    // Pad and quantise the boxes (in parallel: it is a sizeable part of the build).
    let mut gpu_nodes = vec![GpuNode::default(); nodes.len()];
    let chunk = nodes.len().div_ceil(threads).max(1024);
    std::thread::scope(|s| {
        for (dst, src) in gpu_nodes.chunks_mut(chunk).zip(nodes.chunks(chunk)) {
            s.spawn(move || {
                for (d, n) in dst.iter_mut().zip(src) {
                    *d = GpuNode::new(n.boxes.map(|b| b.padded()), n.children);
                }
            });
        }
    });
    drop(nodes);

    let mut bvh = Bvh {
        nodes: gpu_nodes,
        prims,
        stats: BuildStats {
            triangles: triangles.len(),
            spheres: spheres.len(),
            skipped_non_finite: skipped,
            ..Default::default()
        },
    };
    let (leaves, max_depth, sah_cost) = tree_stats(&bvh, opts.traversal_cost as f64, opts.intersection_cost as f64);
    bvh.stats.nodes = bvh.nodes.len();
    bvh.stats.leaves = leaves;
    bvh.stats.max_depth = max_depth;
    bvh.stats.sah_cost = sah_cost;
    bvh.stats.build_seconds = start.elapsed().as_secs_f64();
    assert!(max_depth <= MAX_DEPTH, "BVH depth bound violated: {max_depth}");
    bvh
}

/// Leaves, most internal levels on a path, and the SAH cost (relative to the root box)
/// of a flattened BVH.
pub fn tree_stats(bvh: &Bvh, c_trav: f64, c_isect: f64) -> (usize, u32, f64) {
    let root_area = bvh.bounds().half_area();
    let inv = if root_area > 0.0 { 1.0 / root_area } else { 0.0 };
    let mut leaves = 0;
    let mut max_depth = 0;
    let mut cost = c_trav * if root_area > 0.0 { 1.0 } else { 0.0 };
    let mut stack = vec![(0u32, 1u32)];
    while let Some((ni, level)) = stack.pop() {
        max_depth = max_depth.max(level);
        let n = &bvh.nodes[ni as usize];
        let boxes = n.boxes();
        for (i, b) in boxes.iter().enumerate() {
            let area = b.half_area() * inv;
            match decode_ref(n.child(i)) {
                Ok(c) => {
                    cost += c_trav * area;
                    stack.push((c, level + 1));
                }
                Err((_, count)) => {
                    if count > 0 {
                        leaves += 1;
                        cost += c_isect * count as f64 * area;
                    }
                }
            }
        }
    }
    (leaves, max_depth, cost)
}

/// Internal levels a subtree over `n` primitives needs when built by median splits.
fn median_levels(n: usize, max_leaf: usize) -> u32 {
    let mut levels = 0;
    let mut n = n;
    while n > max_leaf {
        n = n.div_ceil(2);
        levels += 1;
    }
    levels
}

struct Ctx<'a> {
    opts: &'a BuildOptions,
}

/// A chosen split: `refs[..nl]` left, `refs[nl..]` right, already partitioned.
struct Split {
    nl: usize,
    boxes: [Aabb; 2],
    cboxes: [Aabb; 2],
}

#[derive(Clone, Copy)]
struct Bin {
    bounds: Aabb,
    count: u32,
}

impl Ctx<'_> {
    /// Builds the subtree over `refs` (which start at `offset` in the final primitive
    /// order) and returns its child reference. A node created here is at internal level
    /// `level`. `force_split`: make an internal node even for few primitives (the root).
    #[allow(clippy::too_many_arguments)]
    fn build_node(
        &self,
        refs: &mut [PrimRef],
        offset: usize,
        bounds: Aabb,
        cbounds: Aabb,
        level: u32,
        threads: usize,
        force_split: bool,
        nodes: &mut Vec<Node>,
    ) -> u32 {
        let n = refs.len();
        let max_leaf = self.opts.max_leaf;
        // Below MAX_DEPTH only leaves: the depth guard made sure n <= max_leaf here.
        if n <= max_leaf && !force_split && (self.opts.method == SplitMethod::Median || level > MAX_DEPTH) {
            return leaf_ref(offset as u32, n as u32);
        }
        if n <= 1 {
            if !force_split {
                return leaf_ref(offset as u32, n as u32);
            }
            // Root over 0 or 1 primitive: one leaf and an empty one.
            let empty = Aabb { min: Vec3::ZERO, max: Vec3::ZERO };
            let b0 = if n == 1 { bounds } else { empty };
            nodes.push(Node {
                boxes: [b0, empty],
                children: [leaf_ref(offset as u32, n as u32), leaf_ref((offset + n) as u32, 0)],
            });
            return 0;
        }

        let split = match self.opts.method {
            SplitMethod::Sah => match self.sah_split(refs, &bounds, &cbounds, level, !force_split && n <= max_leaf) {
                SahResult::Leaf => return leaf_ref(offset as u32, n as u32),
                SahResult::Split(s) => s,
                SahResult::Median => median_split(refs, &cbounds),
            },
            SplitMethod::Median => median_split(refs, &cbounds),
        };

        let index = nodes.len();
        nodes.push(Node { boxes: split.boxes, children: [0, 0] });
        let nl = split.nl;
        let (left, right) = refs.split_at_mut(nl);
        let children = if threads > 1 && n >= PARALLEL_MIN_PRIMS {
            let tl = threads / 2;
            let tr = threads - tl;
            let (lref, lnodes, rref) = std::thread::scope(|s| {
                let h = s.spawn(|| {
                    let mut v = Vec::with_capacity(left.len() / 2 + 1);
                    let r =
                        self.build_node(left, offset, split.boxes[0], split.cboxes[0], level + 1, tl, false, &mut v);
                    (r, v)
                });
                let rref =
                    self.build_node(right, offset + nl, split.boxes[1], split.cboxes[1], level + 1, tr, false, nodes);
                let (lref, lnodes) = h.join().expect("BVH build thread panicked");
                (lref, lnodes, rref)
            });
            // Append the left subtree after the right one, relocating its node indices.
            let base = nodes.len() as u32;
            let reloc = |r: u32| if decode_ref(r).is_ok() { r + base } else { r };
            nodes.extend(lnodes.into_iter().map(|mut nd| {
                nd.children = nd.children.map(reloc);
                nd
            }));
            [reloc(lref), rref]
        } else {
            let lref = self.build_node(left, offset, split.boxes[0], split.cboxes[0], level + 1, 1, false, nodes);
            let rref = self.build_node(right, offset + nl, split.boxes[1], split.cboxes[1], level + 1, 1, false, nodes);
            [lref, rref]
        };
        nodes[index].children = children;
        index as u32
    }

    /// Binned SAH on all three axes. `leaf_allowed`: compare with the leaf cost.
    fn sah_split(
        &self,
        refs: &mut [PrimRef],
        bounds: &Aabb,
        cbounds: &Aabb,
        level: u32,
        leaf_allowed: bool,
    ) -> SahResult {
        let n = refs.len();
        let nb = self.opts.bins;
        let ext = cbounds.extent();
        let mut scale = [0.0f32; 3];
        let mut any_axis = false;
        for a in 0..3 {
            let s = nb as f32 / ext[a];
            if ext[a] > 0.0 && s.is_finite() {
                scale[a] = s;
                any_axis = true;
            }
        }
        if !any_axis {
            // All centroids coincide: SAH cannot separate them.
            return if leaf_allowed { SahResult::Leaf } else { SahResult::Median };
        }
        let cmin = cbounds.min;
        let bin_of = |c: f32, a: usize| -> usize {
            // `as` saturates (and maps NaN to 0); clamp the top.
            (((c - cmin[a]) * scale[a]) as usize).min(nb - 1)
        };

        let empty = Bin { bounds: Aabb::EMPTY, count: 0 };
        let mut bins = [[empty; MAX_BINS]; 3];
        for r in refs.iter() {
            let c = r.c2();
            let b = r.aabb();
            for a in 0..3 {
                if scale[a] > 0.0 {
                    let bin = &mut bins[a][bin_of(c[a], a)];
                    bin.count += 1;
                    bin.bounds.grow(&b);
                }
            }
        }

        let ct = self.opts.traversal_cost as f64;
        let ci = self.opts.intersection_cost as f64;
        let parea = bounds.half_area();
        // Costs multiplied by the parent's area (valid when that area is 0).
        let mut best: Option<(f64, usize, usize)> = None;
        for a in 0..3 {
            if scale[a] == 0.0 {
                continue;
            }
            let bins = &bins[a][..nb];
            let mut right_area = [0.0f64; MAX_BINS];
            let mut acc = Aabb::EMPTY;
            for i in (1..nb).rev() {
                acc.grow(&bins[i].bounds);
                right_area[i] = acc.half_area();
            }
            let mut acc = Aabb::EMPTY;
            let mut nl = 0usize;
            for i in 1..nb {
                acc.grow(&bins[i - 1].bounds);
                nl += bins[i - 1].count as usize;
                let nr = n - nl;
                if nl == 0 || nr == 0 {
                    continue;
                }
                let cost = ct * parea + ci * (acc.half_area() * nl as f64 + right_area[i] * nr as f64);
                if best.is_none_or(|(c, _, _)| cost < c) {
                    best = Some((cost, a, i));
                }
            }
        }
        let Some((cost, axis, plane)) = best else {
            return if leaf_allowed { SahResult::Leaf } else { SahResult::Median };
        };
        if leaf_allowed && ci * n as f64 * parea <= cost {
            return SahResult::Leaf;
        }

        // Depth guard: both children must still fit below MAX_DEPTH.
        let nl: usize = bins[axis][..plane].iter().map(|b| b.count as usize).sum();
        let nr = n - nl;
        let max_leaf = self.opts.max_leaf;
        if level + median_levels(nl, max_leaf) > MAX_DEPTH || level + median_levels(nr, max_leaf) > MAX_DEPTH {
            return SahResult::Median;
        }

        // Partition in place, collecting the children's boxes and centroid boxes.
        let mut boxes = [Aabb::EMPTY; 2];
        let mut cboxes = [Aabb::EMPTY; 2];
        let mut i = 0;
        let mut j = n;
        while i < j {
            let c = refs[i].c2();
            if bin_of(c[axis], axis) < plane {
                boxes[0].grow(&refs[i].aabb());
                cboxes[0].grow_point(c);
                i += 1;
            } else {
                j -= 1;
                boxes[1].grow(&refs[i].aabb());
                cboxes[1].grow_point(c);
                refs.swap(i, j);
            }
        }
        debug_assert_eq!(i, nl);
        SahResult::Split(Split { nl, boxes, cboxes })
    }
}

enum SahResult {
    Leaf,
    Split(Split),
    /// No useful SAH split (coincident centroids) or the depth guard fired.
    Median,
}

/// Object median on the widest centroid axis: the lower half by centroid goes left.
fn median_split(refs: &mut [PrimRef], cbounds: &Aabb) -> Split {
    let n = refs.len();
    let e = cbounds.extent();
    let axis = if e.x >= e.y && e.x >= e.z {
        0
    } else if e.y >= e.z {
        1
    } else {
        2
    };
    let nl = n / 2;
    if e[axis] > 0.0 {
        refs.select_nth_unstable_by(nl, |a, b| a.c2()[axis].total_cmp(&b.c2()[axis]));
    }
    let mut boxes = [Aabb::EMPTY; 2];
    let mut cboxes = [Aabb::EMPTY; 2];
    for (k, r) in refs.iter().enumerate() {
        let s = usize::from(k >= nl);
        boxes[s].grow(&r.aabb());
        cboxes[s].grow_point(r.c2());
    }
    Split { nl, boxes, cboxes }
}
