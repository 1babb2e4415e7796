//! Binned SAH build (Wald, "On fast Construction of SAH-based Bounding Volume Hierarchies",
//! RT 2007) over one unified primitive list: all triangles, then all spheres.
//!
//! * Each node bins the primitives' centroids into `bins` equal intervals of the
//!   centroid bounds on each of the three axes, and evaluates the SAH at the `bins - 1`
//!   planes between bins: `C = C_trav + C_isect (A_L N_L + A_R N_R) / A`, against the
//!   leaf cost `C_isect N` (allowed only for `N <= max_leaf`). Defaults: 16 bins,
//!   `C_trav = 1`, `C_isect = 1`, `max_leaf = 4` (see [`BuildOptions`]).
//! * Leaves ([`LeafRule`]): in a tree of at least [`SIZE_LEAF_RULE_MIN_PRIMS`]
//!   primitives every node of at most `max_leaf` primitives is a leaf without an SAH
//!   test; in smaller trees the SAH decides down to single primitives.
//! * Primitives whose centroids coincide are split in the middle of their current order.
//! * Depth bound: a split whose children could no longer be finished within
//!   [`MAX_DEPTH`] internal levels by median splits is replaced by a median split (sort
//!   by centroid on the widest axis, halve), which needs `ceil(log2(n / max_leaf))`
//!   levels for `n` primitives. So no path exceeds [`MAX_DEPTH`] levels and the GLSL
//!   traversal stack cannot overflow.
//! * Primitives with non-finite bounds (NaN or infinite coordinates or radius, or
//!   coordinates so close to `f32::MAX` that the centroid or the padded box overflows) are
//!   left out and counted in [`BuildStats::skipped_non_finite`].
//! * Each node is written in the GPU layout when it is made: its boxes padded
//!   ([`Aabb::padded`]) and quantised outwards to 8 bits per coordinate
//!   ([`super::layout::quantize_boxes`]). Nodes are in depth-first preorder (a node, its
//!   first subtree, its second subtree).
//! * Parallel (rayon) without changing the tree: the two subtrees of a node with many
//!   primitives are built as two tasks ([`rayon::join`]) into separate node lists with
//!   child references relative to the parent, joined in preorder afterwards, so node
//!   indices follow from the tree alone, not from which task finished first; near-root
//!   nodes bin their primitives in parallel chunks whose bins are merged exactly (box
//!   unions and counts); the primitive references, the root bounds and the primitive
//!   array are made with parallel iterators that keep the input order. Every split is
//!   the serial build's, so the node and primitive arrays are identical for any number of
//!   threads. docs/bvh.md, "Build", has the details.

use std::time::Instant;

use glam::{Vec3, Vec3A};
use rayon::prelude::*;

use super::aabb::Aabb;
use super::intersect::{sphere_is_finite, triangle_is_finite};
use super::layout::{
    decode_ref, leaf_ref, widen, GpuBvh, GpuNode, GpuPrim, MAX_DEPTH, MAX_IDS, MAX_LEAF_PRIMS, MAX_PRIMS,
};
use crate::activity::Activity;
use crate::scene::{Instance, Scene, SharedMesh, Sphere, Triangle};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SplitMethod {
    /// Binned surface area heuristic (the default).
    Sah,
    /// Object median on the widest centroid axis (a baseline for tests).
    Median,
}

/// When a node of few primitives becomes a leaf.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum LeafRule {
    /// [`LeafRule::Size`] for a tree of at least [`SIZE_LEAF_RULE_MIN_PRIMS`] primitives,
    /// else [`LeafRule::Sah`] (docs/bvh.md, "Leaves": on 1M-triangle meshes the size rule
    /// builds 13-22% faster at the same trace speed; on a 4k-triangle scene it
    /// traces 13-17% slower, and such a build takes milliseconds either way).
    Auto,
    /// A node of at most `max_leaf` primitives becomes a leaf when the SAH says a leaf
    /// costs no more than its best split (so splits go down to single primitives).
    Sah,
    /// Every node of at most `max_leaf` primitives becomes a leaf, without binning it (as
    /// Embree's builders do below their leaf size: fewer nodes, a cheaper build).
    Size,
}

/// Primitives from which [`LeafRule::Auto`] uses the size rule.
pub const SIZE_LEAF_RULE_MIN_PRIMS: usize = 1 << 19;

#[derive(Clone, Debug)]
pub struct BuildOptions {
    pub method: SplitMethod,
    pub leaf_rule: LeafRule,
    /// SAH bins per axis (2..=64).
    pub bins: usize,
    /// Largest leaf (1..=[`MAX_LEAF_PRIMS`]).
    pub max_leaf: usize,
    /// SAH cost of visiting an internal node (two box tests).
    pub traversal_cost: f32,
    /// SAH cost of one primitive test.
    pub intersection_cost: f32,
    /// Threads: 0 = the current rayon pool (the global one has a thread per core, or
    /// `RAYON_NUM_THREADS`), n = a pool of n threads for this build. The tree is the same
    /// for any number.
    pub threads: usize,
}

impl Default for BuildOptions {
    fn default() -> Self {
        BuildOptions {
            method: SplitMethod::Sah,
            leaf_rule: LeafRule::Auto,
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
    /// Instances in the top-level tree (their meshes' triangles count in `triangles`).
    pub instances: usize,
    /// Primitives left out because of non-finite bounds.
    pub skipped_non_finite: usize,
    /// Internal nodes (= the length of the node array; with instances, of every tree).
    pub nodes: usize,
    pub leaves: usize,
    /// Most internal-node levels on a root-to-leaf path (root = 1), `<= MAX_DEPTH`; with
    /// instances, of the top-level tree (each mesh tree has its own, also bounded).
    pub max_depth: u32,
    /// SAH cost of the (top-level) tree with the build's cost constants, relative to the
    /// root box; an instance counts as one primitive.
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
        self.clone().into_gpu()
    }

    /// The buffers to upload: the nodes in their 4-wide form ([`widen`]), each instance
    /// primitive pointed at its mesh's root in it.
    pub fn into_gpu(self) -> GpuBvh {
        let n_prims = self.prims.len() - 2 * self.stats.instances;
        let roots: Vec<u32> =
            self.prims[..n_prims].iter().filter(|p| p.is_instance()).map(|p| p.instance_target().0).collect();
        let (nodes, index) = widen(&self.nodes, &roots);
        let mut prims = self.prims;
        for p in prims[..n_prims].iter_mut().filter(|p| p.is_instance()) {
            let (root, record) = p.instance_target();
            *p = GpuPrim::instance(p.id(), index[root as usize], record);
        }
        GpuBvh {
            nodes,
            prims,
            num_triangles: self.stats.triangles as u32,
            num_spheres: self.stats.spheres as u32,
            num_instances: self.stats.instances as u32,
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
    /// Marks a left-out primitive while the references are made (ids are below 2^28).
    const SKIPPED: PrimRef = PrimRef { min: Vec3::ZERO, id: u32::MAX, max: Vec3::ZERO, _pad: 0 };

    /// The reference of a primitive with box `[min, max]` and unified index `id`, or `None`
    /// where the centroid sum or the padded box (see [`Aabb::padded`]) overflows
    /// (coordinates near `f32::MAX`).
    fn new(min: Vec3, max: Vec3, id: usize) -> Option<PrimRef> {
        let r = PrimRef { min, id: id as u32, max, _pad: 0 };
        let padded = r.aabb().padded();
        (r.c2().is_finite() && padded.min.is_finite() && padded.max.is_finite()).then_some(r)
    }

    /// `None` for a triangle with a non-finite coordinate (or an overflowing box).
    fn of_triangle(t: &Triangle, id: usize) -> Option<PrimRef> {
        if !triangle_is_finite(t) {
            return None;
        }
        PrimRef::new(t.p[0].min(t.p[1]).min(t.p[2]), t.p[0].max(t.p[1]).max(t.p[2]), id)
    }

    /// `None` for a sphere with a non-finite centre or radius (or an overflowing box).
    fn of_sphere(s: &Sphere, id: usize) -> Option<PrimRef> {
        if !sphere_is_finite(s) {
            return None;
        }
        let r = Vec3::splat(s.radius.abs());
        PrimRef::new(s.center - r, s.center + r, id)
    }

    /// `None` for a box with a non-finite coordinate (an instance of an empty mesh).
    fn of_box(b: &Aabb, id: usize) -> Option<PrimRef> {
        if !(b.min.is_finite() && b.max.is_finite()) {
            return None;
        }
        PrimRef::new(b.min, b.max, id)
    }

    /// Twice the centroid (the factor 2 is irrelevant to binning and saves a multiply).
    #[inline]
    fn c2(&self) -> Vec3A {
        Vec3A::from(self.min) + Vec3A::from(self.max)
    }

    #[inline]
    fn bounds(&self) -> Bounds {
        Bounds { min: self.min.into(), max: self.max.into() }
    }

    fn aabb(&self) -> Aabb {
        Aabb { min: self.min, max: self.max }
    }
}

/// The builder's working box: an [`Aabb`] in SIMD registers. Growing a box only takes
/// minima and maxima, which are exact, so a box is the same whatever order (or thread)
/// grew it (up to the sign of a zero coordinate, which only comparisons see, and they do
/// not); areas go through [`Aabb::half_area`].
#[derive(Clone, Copy, Debug)]
struct Bounds {
    min: Vec3A,
    max: Vec3A,
}

impl Bounds {
    const EMPTY: Bounds = Bounds { min: Vec3A::INFINITY, max: Vec3A::NEG_INFINITY };

    #[inline]
    fn grow(&mut self, o: &Bounds) {
        self.min = self.min.min(o.min);
        self.max = self.max.max(o.max);
    }

    #[inline]
    fn grow_point(&mut self, p: Vec3A) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    fn union(mut self, o: &Bounds) -> Bounds {
        self.grow(o);
        self
    }

    fn aabb(&self) -> Aabb {
        Aabb { min: self.min.into(), max: self.max.into() }
    }

    #[inline]
    fn half_area(&self) -> f64 {
        self.aabb().half_area()
    }
}

const MAX_BINS: usize = 64;
/// Nodes with at least this many primitives build their two subtrees as two rayon tasks
/// (`rayon::join`). Only the speed depends on it, not the tree.
const PARALLEL_SUBTREE_MIN_PRIMS: usize = 8 * 1024;
/// Nodes with at least this many primitives bin them in parallel, in chunks of
/// [`PARALLEL_BIN_CHUNK`] (the near-root nodes, where there are fewer subtrees than
/// threads). Only the speed depends on it, not the tree.
const PARALLEL_BIN_MIN_PRIMS: usize = 128 * 1024;
const PARALLEL_BIN_CHUNK: usize = 32 * 1024;

/// Builds a BVH over `triangles` then `spheres` with the given options, on
/// [`BuildOptions::threads`] threads (the tree does not depend on the number).
///
/// Panics if there are more than 2^28 primitives or options are out of range.
pub fn build_with(triangles: &[Triangle], spheres: &[Sphere], opts: &BuildOptions) -> Bvh {
    let total = triangles.len() + spheres.len();
    assert!(total <= MAX_PRIMS, "too many primitives for the BVH ({total})");
    in_pool(opts, || build_in_pool(triangles, spheres, &[], opts))
}

/// The BVH of a scene: over its world-space triangles and spheres, and with instances the
/// two-level BVH (one tree per shared mesh in object space, instances as primitives of
/// the top-level tree; src/bvh/layout.rs, "Instancing"). Without instances it is
/// [`build_with`] over [`Scene::world_triangles`].
///
/// Panics if the joined arrays exceed 2^28 primitives or options are out of range.
pub fn build_scene(scene: &Scene, opts: &BuildOptions) -> Bvh {
    build_instanced(&scene.triangles, &scene.spheres, &scene.meshes, &scene.instances, opts)
}

/// [`build_scene`] over a scene's parts: `triangles` holds the world-space triangles,
/// then the shared meshes' (`meshes`), which `instances` place.
pub fn build_instanced(
    triangles: &[Triangle],
    spheres: &[Sphere],
    meshes: &[SharedMesh],
    instances: &[Instance],
    opts: &BuildOptions,
) -> Bvh {
    let world = &triangles[..SharedMesh::world_triangle_count(meshes, triangles.len())];
    if instances.is_empty() {
        return build_with(world, spheres, opts);
    }
    assert!(instances.len() < MAX_IDS, "too many instances ({})", instances.len());
    let mut bvh = in_pool(opts, || {
        // Mesh trees in parallel (each is the same tree for any number of threads).
        let trees: Vec<Bvh> = meshes.par_iter().map(|m| build_in_pool(&triangles[m.range()], &[], &[], opts)).collect();
        // Each instance's world box: the corners of its mesh tree's root box, transformed.
        let boxes: Vec<Aabb> = instances
            .iter()
            .map(|inst| {
                let b = trees[inst.mesh as usize].bounds();
                let mut world = Aabb::EMPTY;
                for k in 0..8 {
                    let c = Vec3::new(
                        if k & 1 == 0 { b.min.x } else { b.max.x },
                        if k & 2 == 0 { b.min.y } else { b.max.y },
                        if k & 4 == 0 { b.min.z } else { b.max.z },
                    );
                    world.grow_point(inst.object_to_world.transform_point3(c));
                }
                world
            })
            .collect();
        let mut top = build_in_pool(world, spheres, &boxes, opts);
        join_instanced(&mut top, meshes, instances, trees);
        top
    });
    bvh.stats.triangles = triangles.len();
    bvh
}

/// Appends the mesh trees to the top-level tree `top` (node and primitive indices offset,
/// triangle ids made indices into the scene's triangles), then the instance records, and
/// points each instance primitive at its mesh's root and its record.
fn join_instanced(top: &mut Bvh, meshes: &[SharedMesh], instances: &[Instance], trees: Vec<Bvh>) {
    let mut roots = Vec::with_capacity(trees.len());
    for (tree, mesh) in trees.into_iter().zip(meshes) {
        let node_base = top.nodes.len() as u32;
        let prim_base = top.prims.len() as u32;
        assert!(
            top.prims.len() + tree.prims.len() + 2 * instances.len() <= MAX_PRIMS,
            "too many primitives for the BVH"
        );
        roots.push(node_base);
        let offset = |r: u32| match decode_ref(r) {
            Ok(node) => node + node_base,
            Err((first, count)) => leaf_ref(first + prim_base, count),
        };
        top.nodes.extend(tree.nodes.into_iter().map(|mut n| {
            n.set_children([0, 1].map(|i| offset(n.child(i))));
            n
        }));
        top.prims
            .extend(tree.prims.into_iter().map(|p| GpuPrim::triangle(p.vertices(), p.id() + mesh.first, p.material())));
        top.stats.leaves += tree.stats.leaves;
        top.stats.skipped_non_finite += tree.stats.skipped_non_finite;
    }
    let record_base = top.prims.len() as u32;
    for inst in instances {
        top.prims.extend(GpuPrim::instance_record(inst.object_to_world));
    }
    let n_top = top.prims.len() - 2 * instances.len();
    for p in top.prims[..n_top].iter_mut().filter(|p| p.is_instance()) {
        let k = p.id();
        *p = GpuPrim::instance(k, roots[instances[k as usize].mesh as usize], record_base + 2 * k);
    }
    top.stats.nodes = top.nodes.len();
    top.stats.instances = instances.len();
}

/// Runs `f` on [`BuildOptions::threads`] threads (0: the current pool) and sets the build
/// time.
fn in_pool(opts: &BuildOptions, f: impl FnOnce() -> Bvh + Send) -> Bvh {
    let start = Instant::now();
    assert!((2..=MAX_BINS).contains(&opts.bins), "bins out of range");
    assert!((1..=MAX_LEAF_PRIMS).contains(&opts.max_leaf), "max_leaf out of range");
    let mut bvh = if opts.threads == 0 {
        f()
    } else {
        match rayon::ThreadPoolBuilder::new().num_threads(opts.threads).build() {
            Ok(pool) => pool.install(f),
            Err(e) => {
                log::warn!("BVH build: no pool of {} threads ({e}); building on the global pool", opts.threads);
                f()
            }
        }
    };
    bvh.stats.build_seconds = start.elapsed().as_secs_f64();
    bvh
}

/// [`build_with`] on the current rayon pool (options already checked), with `instances`
/// (world boxes) as further primitives after the spheres: their primitives name the
/// instance, [`join_instanced`] sets the rest.
fn build_in_pool(triangles: &[Triangle], spheres: &[Sphere], instances: &[Aabb], opts: &BuildOptions) -> Bvh {
    let nt = triangles.len();
    let ns = spheres.len();
    // Progress: primitives placed in subtrees (see Builder::build_node).
    let total = nt + ns + instances.len();
    let activity = Activity::begin(|| format!("building the BVH ({total} primitives)"), Some(total as u64));
    // Primitive references in input order (rayon's collect keeps the order). An indexed
    // collect writes each reference in place; the rare non-finite primitive is marked and
    // removed afterwards (a filtering collect would gather pieces and copy them again).
    let mut refs: Vec<PrimRef> = triangles
        .par_iter()
        .enumerate()
        .map(|(i, t)| PrimRef::of_triangle(t, i).unwrap_or(PrimRef::SKIPPED))
        .chain(spheres.par_iter().enumerate().map(|(i, s)| PrimRef::of_sphere(s, nt + i).unwrap_or(PrimRef::SKIPPED)))
        .chain(
            instances.par_iter().enumerate().map(|(i, b)| PrimRef::of_box(b, nt + ns + i).unwrap_or(PrimRef::SKIPPED)),
        )
        .collect();
    if refs.par_iter().any(|r| r.id == PrimRef::SKIPPED.id) {
        refs.retain(|r| r.id != PrimRef::SKIPPED.id);
    }
    let skipped = total - refs.len();
    let (bounds, cbounds) = refs
        .par_iter()
        .fold(
            || (Bounds::EMPTY, Bounds::EMPTY),
            |(mut b, mut c), r| {
                b.grow(&r.bounds());
                c.grow_point(r.c2());
                (b, c)
            },
        )
        .reduce(|| (Bounds::EMPTY, Bounds::EMPTY), |(b0, c0), (b1, c1)| (b0.union(&b1), c0.union(&c1)));

    let leaves_by_size = match opts.leaf_rule {
        LeafRule::Auto => refs.len() >= SIZE_LEAF_RULE_MIN_PRIMS,
        LeafRule::Sah => false,
        LeafRule::Size => true,
    };
    let builder = Builder { opts, leaves_by_size, activity: &activity };
    let mut worker = Worker::new(refs.len());
    let root = builder.build_node(&mut refs, 0, bounds, cbounds, 1, true, &mut worker);
    debug_assert_eq!(root, 0);
    let nodes = worker.nodes.into_nodes();

    let prims: Vec<GpuPrim> = refs
        .par_iter()
        .map(|r| {
            let id = r.id as usize;
            if id < nt {
                let t = &triangles[id];
                GpuPrim::triangle(t.p, id as u32, t.material)
            } else if id < nt + ns {
                let s = &spheres[id - nt];
                GpuPrim::sphere(s.center, s.radius.abs(), (id - nt) as u32, s.material)
            } else {
                GpuPrim::instance((id - nt - ns) as u32, 0, 0)
            }
        })
        .collect();
    drop(refs);

    let mut bvh = Bvh {
        nodes,
        prims,
        stats: BuildStats {
            triangles: triangles.len(),
            spheres: spheres.len(),
            instances: instances.len(),
            skipped_non_finite: skipped,
            ..Default::default()
        },
    };
    let (leaves, max_depth, sah_cost) = tree_stats(&bvh, opts.traversal_cost as f64, opts.intersection_cost as f64);
    bvh.stats.nodes = bvh.nodes.len();
    bvh.stats.leaves = leaves;
    bvh.stats.max_depth = max_depth;
    bvh.stats.sah_cost = sah_cost;
    assert!(max_depth <= MAX_DEPTH, "BVH depth bound violated: {max_depth}");
    bvh
}

/// Leaves, most internal levels on a path, and the SAH cost (relative to the root box)
/// of a flattened BVH (one tree, nodes in preorder, as a build makes them).
///
/// The cost sums each node's children in node order, in parallel over fixed chunks of
/// nodes whose sums are added in order, so it is the same number for any thread count.
pub fn tree_stats(bvh: &Bvh, c_trav: f64, c_isect: f64) -> (usize, u32, f64) {
    let root_area = bvh.bounds().half_area();
    let inv = if root_area > 0.0 { 1.0 / root_area } else { 0.0 };
    // Levels: a parent precedes its children in preorder.
    let mut level = vec![0u32; bvh.nodes.len()];
    level[0] = 1;
    let mut max_depth = 0;
    for (i, n) in bvh.nodes.iter().enumerate() {
        max_depth = max_depth.max(level[i]);
        for k in 0..2 {
            if let Ok(c) = decode_ref(n.child(k)) {
                level[c as usize] = level[i] + 1;
            }
        }
    }
    const CHUNK: usize = 4096;
    let per_chunk: Vec<(usize, f64)> = bvh
        .nodes
        .par_chunks(CHUNK)
        .map(|nodes| {
            let (mut leaves, mut cost) = (0usize, 0.0f64);
            for n in nodes {
                for (i, b) in n.boxes().iter().enumerate() {
                    let area = b.half_area() * inv;
                    match decode_ref(n.child(i)) {
                        Ok(_) => cost += c_trav * area,
                        Err((_, count)) => {
                            if count > 0 {
                                leaves += 1;
                                cost += c_isect * count as f64 * area;
                            }
                        }
                    }
                }
            }
            (leaves, cost)
        })
        .collect();
    let mut leaves = 0;
    let mut cost = c_trav * if root_area > 0.0 { 1.0 } else { 0.0 };
    for (l, c) in per_chunk {
        leaves += l;
        cost += c;
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

/// A node of the GPU layout over two child boxes (padded, then quantised).
fn gpu_node(boxes: [Bounds; 2], children: [u32; 2]) -> GpuNode {
    GpuNode::new(boxes.map(|b| b.aabb().padded()), children)
}

/// `f` applied to a child reference if it is an internal node's (leaves unchanged).
fn map_internal(r: u32, f: impl Fn(u32) -> u32) -> u32 {
    if decode_ref(r).is_ok() {
        f(r)
    } else {
        r
    }
}

/// The nodes of a subtree in depth-first preorder (a node, then its first child's
/// subtree, then its second child's), which is the order the serial recursion creates
/// them in. Held as consecutive pieces, so that subtrees built by other tasks are joined
/// by moving their pieces, not their nodes.
///
/// While building, an internal child reference is relative: the child's position minus
/// its parent's. A piece thus does not depend on where it ends up, and
/// [`NodeList::into_nodes`] turns the references into node indices when it concatenates
/// the pieces.
struct NodeList {
    pieces: Vec<Vec<GpuNode>>,
    len: usize,
}

impl NodeList {
    fn with_capacity(capacity: usize) -> NodeList {
        NodeList { pieces: vec![Vec::with_capacity(capacity)], len: 0 }
    }

    fn len(&self) -> usize {
        self.len
    }

    /// Appends a node; returns its position.
    fn push(&mut self, node: GpuNode) -> usize {
        let pos = self.len;
        self.pieces.last_mut().expect("a NodeList always has a piece").push(node);
        self.len += 1;
        pos
    }

    /// The node at position `pos`.
    fn node_mut(&mut self, pos: usize) -> &mut GpuNode {
        let mut start = self.len;
        for piece in self.pieces.iter_mut().rev() {
            start -= piece.len();
            if pos >= start {
                return &mut piece[pos - start];
            }
        }
        unreachable!("node position {pos} beyond the list ({})", self.len)
    }

    /// Appends `other`'s nodes (moving its pieces).
    fn append(&mut self, other: NodeList) {
        if self.pieces.last().is_some_and(Vec::is_empty) {
            self.pieces.pop();
        }
        self.pieces.extend(other.pieces.into_iter().filter(|p| !p.is_empty()));
        self.pieces.push(Vec::new());
        self.len += other.len;
    }

    /// The nodes in one array, child references made absolute (in parallel over pieces).
    fn into_nodes(mut self) -> Vec<GpuNode> {
        self.pieces.retain(|p| !p.is_empty());
        let absolute = |piece: &mut [GpuNode], start: usize| {
            for (k, node) in piece.iter_mut().enumerate() {
                let pos = (start + k) as u32;
                node.set_children([0, 1].map(|i| map_internal(node.child(i), |rel| pos + rel)));
            }
        };
        if self.pieces.len() == 1 {
            let mut nodes = self.pieces.pop().expect("one piece");
            const CHUNK: usize = 64 * 1024;
            nodes.par_chunks_mut(CHUNK).enumerate().for_each(|(c, chunk)| absolute(chunk, c * CHUNK));
            return nodes;
        }
        let mut nodes = vec![GpuNode::default(); self.len];
        let mut jobs = Vec::with_capacity(self.pieces.len());
        let mut rest = nodes.as_mut_slice();
        let mut start = 0;
        for piece in &self.pieces {
            let (dst, tail) = rest.split_at_mut(piece.len());
            jobs.push((dst, piece, start));
            start += piece.len();
            rest = tail;
        }
        jobs.into_par_iter().for_each(|(dst, piece, start)| {
            dst.copy_from_slice(piece);
            absolute(dst, start);
        });
        nodes
    }
}

/// What one build task owns: the nodes it has made and its bin scratch (reused from node
/// to node, so that nodes allocate nothing).
struct Worker {
    nodes: NodeList,
    bins: Box<Bins>,
}

impl Worker {
    /// A worker for a subtree over `prims` primitives. A subtree of at least
    /// [`PARALLEL_SUBTREE_MIN_PRIMS`] makes only its root node itself (the rest comes
    /// from the tasks it starts); a smaller one makes about one node per two primitives.
    fn new(prims: usize) -> Worker {
        let capacity = if prims >= PARALLEL_SUBTREE_MIN_PRIMS { 1 } else { prims / 2 + 1 };
        Worker { nodes: NodeList::with_capacity(capacity), bins: Bins::new() }
    }
}

/// Where a centroid falls: `count` equal intervals of the node's centroid bounds on each
/// axis. `scale` is 0 on an axis whose centroids (nearly) coincide: everything falls into
/// bin 0 there, and `active` is false.
struct BinGrid {
    cmin: Vec3A,
    scale: Vec3A,
    count: usize,
    active: [bool; 3],
}

impl BinGrid {
    /// `None` when the centroids coincide on every axis.
    fn new(cbounds: &Bounds, count: usize) -> Option<BinGrid> {
        let ext = cbounds.max - cbounds.min;
        let mut scale = [0.0f32; 3];
        let mut active = [false; 3];
        for a in 0..3 {
            let s = count as f32 / ext[a];
            if ext[a] > 0.0 && s.is_finite() {
                scale[a] = s;
                active[a] = true;
            }
        }
        active.contains(&true).then(|| BinGrid { cmin: cbounds.min, scale: Vec3A::from(scale), count, active })
    }

    /// The bin of doubled centroid `c2` on each axis.
    #[inline]
    fn bin_of(&self, c2: Vec3A) -> [usize; 3] {
        ((c2 - self.cmin) * self.scale).to_array().map(|x| self.clamp(x))
    }

    /// The bin of doubled centroid coordinate `c2` on axis `a` (as [`Self::bin_of`]).
    #[inline]
    fn bin_on(&self, c2: f32, a: usize) -> usize {
        self.clamp((c2 - self.cmin[a]) * self.scale[a])
    }

    /// Grid coordinate `x` to its bin: truncated, clamped to the bins. (`as i32` saturates
    /// and maps NaN to 0; it is a shorter instruction sequence than `as usize`, with the
    /// same result here.)
    #[inline]
    fn clamp(&self, x: f32) -> usize {
        ((x as i32).max(0) as usize).min(self.count - 1)
    }
}

/// A node's bins on all three axes: the boxes and counts of the primitives whose
/// centroid falls into each. Only the grid's first `count` bins per axis are used.
struct Bins {
    boxes: [[Bounds; MAX_BINS]; 3],
    counts: [[u32; MAX_BINS]; 3],
}

impl Bins {
    fn new() -> Box<Bins> {
        Box::new(Bins { boxes: [[Bounds::EMPTY; MAX_BINS]; 3], counts: [[0; MAX_BINS]; 3] })
    }

    fn clear(&mut self, count: usize) {
        for a in 0..3 {
            self.boxes[a][..count].fill(Bounds::EMPTY);
            self.counts[a][..count].fill(0);
        }
    }

    /// Adds `refs` to the (cleared or partly filled) bins of `grid`.
    fn add(&mut self, grid: &BinGrid, refs: &[PrimRef]) {
        for r in refs {
            let b = r.bounds();
            for (a, bin) in grid.bin_of(r.c2()).into_iter().enumerate() {
                self.counts[a][bin] += 1;
                self.boxes[a][bin].grow(&b);
            }
        }
    }

    /// Adds `o`'s first `count` bins to these (exact: box unions and integer sums).
    fn merge(&mut self, o: &Bins, count: usize) {
        for a in 0..3 {
            for i in 0..count {
                self.counts[a][i] += o.counts[a][i];
                self.boxes[a][i].grow(&o.boxes[a][i]);
            }
        }
    }
}

struct Builder<'a> {
    opts: &'a BuildOptions,
    /// The leaf rule resolved for this tree: every node of at most `max_leaf` primitives
    /// is a leaf ([`LeafRule::Size`]).
    leaves_by_size: bool,
    activity: &'a Activity,
}

/// A chosen split: `refs[..nl]` left, `refs[nl..]` right, already partitioned.
struct Split {
    nl: usize,
    boxes: [Bounds; 2],
    cboxes: [Bounds; 2],
}

impl Builder<'_> {
    /// Builds the subtree over `refs` (which start at `offset` in the final primitive
    /// order) into `w` and returns its child reference: a leaf, or the position in
    /// `w.nodes` of its root. A node created here is at internal level `level`.
    /// `force_split`: make an internal node even for few primitives (the root).
    #[allow(clippy::too_many_arguments)]
    fn build_node(
        &self,
        refs: &mut [PrimRef],
        offset: usize,
        bounds: Bounds,
        cbounds: Bounds,
        level: u32,
        force_split: bool,
        w: &mut Worker,
    ) -> u32 {
        let n = refs.len();
        let max_leaf = self.opts.max_leaf;
        // Below MAX_DEPTH only leaves: the depth guard made sure n <= max_leaf here.
        let leaf_without_sah = self.opts.method == SplitMethod::Median || self.leaves_by_size || level > MAX_DEPTH;
        if n <= max_leaf && !force_split && leaf_without_sah {
            return leaf_ref(offset as u32, n as u32);
        }
        if n <= 1 {
            if !force_split {
                return leaf_ref(offset as u32, n as u32);
            }
            // Root over 0 or 1 primitive: one leaf and an empty one.
            let empty = Bounds { min: Vec3A::ZERO, max: Vec3A::ZERO };
            let b0 = if n == 1 { bounds } else { empty };
            let children = [leaf_ref(offset as u32, n as u32), leaf_ref((offset + n) as u32, 0)];
            return w.nodes.push(gpu_node([b0, empty], children)) as u32;
        }

        let split = match self.opts.method {
            SplitMethod::Sah => {
                match self.sah_split(refs, &bounds, &cbounds, level, !force_split && n <= max_leaf, &mut w.bins) {
                    SahResult::Leaf => return leaf_ref(offset as u32, n as u32),
                    SahResult::Split(s) => s,
                    SahResult::Median => median_split(refs, &cbounds),
                }
            }
            SplitMethod::Median => median_split(refs, &cbounds),
        };

        let nl = split.nl;
        let (left, right) = refs.split_at_mut(nl);
        if n >= PARALLEL_SUBTREE_MIN_PRIMS {
            // Both subtrees as rayon tasks, each into its own node list; then this node
            // and the two lists in preorder, as the serial branch below would lay them out.
            let subtree = |refs: &mut [PrimRef], offset: usize, side: usize| {
                let mut sub = Worker::new(refs.len());
                let r =
                    self.build_node(refs, offset, split.boxes[side], split.cboxes[side], level + 1, false, &mut sub);
                // Progress: each primitive is counted once, by the one subtree task of
                // it that builds serially.
                if refs.len() < PARALLEL_SUBTREE_MIN_PRIMS {
                    self.activity.advance(refs.len() as u64);
                }
                (r, sub.nodes)
            };
            let ((lref, lnodes), (rref, rnodes)) =
                rayon::join(|| subtree(left, offset, 0), || subtree(right, offset + nl, 1));
            // Relative references: the left subtree starts right after this node, the
            // right one after the left one.
            let left_len = lnodes.len() as u32;
            let children = [map_internal(lref, |p| 1 + p), map_internal(rref, |p| 1 + left_len + p)];
            let pos = w.nodes.push(gpu_node(split.boxes, children));
            w.nodes.append(lnodes);
            w.nodes.append(rnodes);
            pos as u32
        } else {
            let pos = w.nodes.push(gpu_node(split.boxes, [0, 0]));
            let lref = self.build_node(left, offset, split.boxes[0], split.cboxes[0], level + 1, false, w);
            let rref = self.build_node(right, offset + nl, split.boxes[1], split.cboxes[1], level + 1, false, w);
            let relative = |r: u32| map_internal(r, |p| p - pos as u32);
            w.nodes.node_mut(pos).set_children([relative(lref), relative(rref)]);
            pos as u32
        }
    }

    /// Binned SAH on all three axes. `leaf_allowed`: compare with the leaf cost. `bins`:
    /// scratch.
    fn sah_split(
        &self,
        refs: &mut [PrimRef],
        bounds: &Bounds,
        cbounds: &Bounds,
        level: u32,
        leaf_allowed: bool,
        bins: &mut Bins,
    ) -> SahResult {
        let n = refs.len();
        let nb = self.opts.bins;
        let Some(grid) = BinGrid::new(cbounds, nb) else {
            // All centroids coincide: SAH cannot separate them.
            return if leaf_allowed { SahResult::Leaf } else { SahResult::Median };
        };
        if n >= PARALLEL_BIN_MIN_PRIMS {
            // Near the root, per-chunk bins merged (the same bins: the merge is exact).
            let bins = refs
                .par_chunks(PARALLEL_BIN_CHUNK)
                .map(|chunk| {
                    let mut b = Bins::new();
                    b.add(&grid, chunk);
                    b
                })
                .reduce_with(|mut a, b| {
                    a.merge(&b, nb);
                    a
                })
                .expect("a node has primitives");
            return self.split_from_bins(refs, bounds, level, leaf_allowed, &grid, &bins);
        }
        bins.clear(nb);
        bins.add(&grid, refs);
        self.split_from_bins(refs, bounds, level, leaf_allowed, &grid, bins)
    }

    /// The best split of `refs` (or a leaf, or a median split) from their `bins` on
    /// `grid`; partitions `refs` when it splits.
    fn split_from_bins(
        &self,
        refs: &mut [PrimRef],
        bounds: &Bounds,
        level: u32,
        leaf_allowed: bool,
        grid: &BinGrid,
        bins: &Bins,
    ) -> SahResult {
        let n = refs.len();
        let nb = grid.count;
        let ct = self.opts.traversal_cost as f64;
        let ci = self.opts.intersection_cost as f64;
        let parea = bounds.half_area();
        // Costs multiplied by the parent's area (valid when that area is 0). Only the
        // planes just after an occupied bin are evaluated: a plane after an empty bin has
        // the same two sides, hence bit for bit the same cost, as the plane before that
        // bin (or an empty side), and the strict `<` keeps the first of equal costs.
        let mut best: Option<(f64, usize, usize)> = None;
        let mut occupied = [0usize; MAX_BINS];
        // right_area[j]: area of the occupied bins after occupied[j].
        let mut right_area = [0.0f64; MAX_BINS];
        for a in 0..3 {
            if !grid.active[a] {
                continue;
            }
            let (boxes, counts) = (&bins.boxes[a][..nb], &bins.counts[a][..nb]);
            let mut m = 0;
            for (i, &c) in counts.iter().enumerate() {
                occupied[m] = i;
                m += usize::from(c > 0);
            }
            let planes = m.saturating_sub(1);
            let mut acc = Bounds::EMPTY;
            for j in (0..planes).rev() {
                acc.grow(&boxes[occupied[j + 1]]);
                right_area[j] = acc.half_area();
            }
            let mut acc = Bounds::EMPTY;
            let mut nl = 0usize;
            for j in 0..planes {
                let bin = occupied[j];
                acc.grow(&boxes[bin]);
                nl += counts[bin] as usize;
                let nr = n - nl;
                let cost = ct * parea + ci * (acc.half_area() * nl as f64 + right_area[j] * nr as f64);
                if best.is_none_or(|(c, _, _)| cost < c) {
                    best = Some((cost, a, bin + 1));
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
        let nl: usize = bins.counts[axis][..plane].iter().map(|&c| c as usize).sum();
        let nr = n - nl;
        let max_leaf = self.opts.max_leaf;
        if level + median_levels(nl, max_leaf) > MAX_DEPTH || level + median_levels(nr, max_leaf) > MAX_DEPTH {
            return SahResult::Median;
        }

        // The children's boxes are the unions of their bins' boxes (exact: minima and
        // maxima), so the partition only collects the centroid boxes.
        let (mut lbox, mut rbox) = (Bounds::EMPTY, Bounds::EMPTY);
        for (bin, b) in bins.boxes[axis][..nb].iter().enumerate() {
            if bin < plane {
                lbox.grow(b);
            } else {
                rbox.grow(b);
            }
        }
        // Partition in place. (Serial: the order it leaves the primitives in is part of
        // the tree.)
        let (mut lc, mut rc) = (Bounds::EMPTY, Bounds::EMPTY);
        let mut i = 0;
        let mut j = n;
        while i < j {
            let c = refs[i].c2();
            if grid.bin_on(c[axis], axis) < plane {
                lc.grow_point(c);
                i += 1;
            } else {
                rc.grow_point(c);
                j -= 1;
                refs.swap(i, j);
            }
        }
        debug_assert_eq!(i, nl);
        SahResult::Split(Split { nl, boxes: [lbox, rbox], cboxes: [lc, rc] })
    }
}

enum SahResult {
    Leaf,
    Split(Split),
    /// No useful SAH split (coincident centroids) or the depth guard fired.
    Median,
}

/// Object median on the widest centroid axis: the lower half by centroid goes left.
fn median_split(refs: &mut [PrimRef], cbounds: &Bounds) -> Split {
    let n = refs.len();
    let e = cbounds.max - cbounds.min;
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
    let mut boxes = [Bounds::EMPTY; 2];
    let mut cboxes = [Bounds::EMPTY; 2];
    for (k, r) in refs.iter().enumerate() {
        let s = usize::from(k >= nl);
        boxes[s].grow(&r.bounds());
        cboxes[s].grow_point(r.c2());
    }
    Split { nl, boxes, cboxes }
}
