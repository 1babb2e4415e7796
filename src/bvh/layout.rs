//! GPU layout of the BVH. The builder makes a BVH2 whose nodes hold both children's boxes
//! (Aila & Laine, "Understanding the Efficiency of Ray Traversal on GPUs", HPG 2009),
//! quantised to 8 bits per coordinate on a per-node grid (32 bytes per node,
//! [`GpuNode`]); the GPU reads its 4-wide form ([`widen`], [`GpuNode4`], 64 bytes: a node
//! and its grandchildren's boxes), and 48-byte primitives in leaf order. Mirrored by
//! `glsl/bvh.glsl`.
//!
//! Both arrays are sequences of 16-byte elements (`uvec4`/`vec4`/`u64vec2` in GLSL,
//! std430 stride 16); the Rust structs below are made of 4-word members only, so they
//! have exactly the GLSL byte layout. docs/bvh.md compares this layout with a 64-byte node
//! of float boxes and the 4-wide form with the BVH2 on lavapipe.
//!
//! Child references (`u32`):
//! * bit 31 clear: index of an internal node in the node array (of the BVH2, or of the
//!   4-wide array in a [`GpuNode4`]);
//! * bit 31 set: a leaf, `LEAF_FLAG | first << 3 | count`, covering
//!   `prims[first .. first + count]`, `count <= MAX_LEAF_PRIMS` (0 only for the empty
//!   second child of a root over fewer than two primitives, and [`EMPTY_REF`]).
//!
//! Node 0 is the root. It is always an internal node.
//!
//! Instancing (two levels): a scene's shared meshes each have their own tree, in object
//! space, appended after the top-level tree's nodes and primitives with absolute indices
//! (so a mesh's tree is traversed with the same code). The top-level tree's primitives
//! are world-space triangles, spheres and *instances*; an instance primitive names the
//! root node of its mesh's tree and its *record*: two primitive slots after all
//! primitives holding the instance's world-to-object and object-to-world transforms
//! ([`GpuPrim::instance_record`]). The traversal moves the ray into object space to
//! descend into the mesh's tree (unnormalised direction, so distances `t` are the same in
//! both spaces) and back when that tree is done (glsl/bvh.glsl, docs/bvh.md).

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use super::aabb::Aabb;

/// Bit 31 of a child reference: the child is a leaf.
pub const LEAF_FLAG: u32 = 0x8000_0000;
/// Largest number of primitives in one leaf (3 bits of the child reference hold it).
pub const MAX_LEAF_PRIMS: usize = 4;
/// Largest number of primitives a BVH can hold (28 bits of first-primitive index).
pub const MAX_PRIMS: usize = 1 << 28;
/// Largest number of internal-node levels on any root-to-leaf path of the BVH2 (the root
/// is level 1). The builder guarantees the bound; the traversal stack's size follows from
/// it ([`MAX_STACK`]).
pub const MAX_DEPTH: u32 = 32;
/// Bit 31 of a primitive's id word (`GpuPrim::a[3]` bits): the primitive is a sphere.
pub const SPHERE_FLAG: u32 = 0x8000_0000;

/// Bit 30 of a primitive's id word: the primitive is an instance (bits 0..29 its index in
/// `Scene::instances`).
pub const INSTANCE_FLAG: u32 = 0x4000_0000;
/// Largest number of instances (the id bits below [`INSTANCE_FLAG`]), and of triangles.
pub const MAX_IDS: usize = INSTANCE_FLAG as usize;
/// Traversal stack entries for one tree: a visit of a [`GpuNode4`] pushes at most three
/// of its four children, and a path has at most [`MAX_WIDE_DEPTH`] such visits
/// (`BVH_STACK_SIZE` in glsl/bvh.glsl).
pub const MAX_STACK: usize = 3 * MAX_WIDE_DEPTH as usize;
/// Traversal stack entries with instances: a top-level path and a mesh tree's path,
/// [`MAX_STACK`] each, plus what entering the instance pushes: the leaf the lane went on
/// to when the instance's leaf was set aside, the rest of the instance's leaf and the
/// marker that moves the ray back to world space (`BVH_STACK_SIZE` with `BVH_INSTANCES`).
pub const MAX_STACK_INSTANCED: usize = 2 * MAX_STACK + 3;

/// Encodes a leaf child reference.
pub fn leaf_ref(first: u32, count: u32) -> u32 {
    debug_assert!((first as usize) < MAX_PRIMS && count as usize <= MAX_LEAF_PRIMS);
    LEAF_FLAG | (first << 3) | count
}

/// Decodes a child reference: `Ok(node index)` or `Err((first prim, count))` for a leaf.
pub fn decode_ref(r: u32) -> Result<u32, (u32, u32)> {
    if r & LEAF_FLAG == 0 {
        Ok(r)
    } else {
        Err(((r & !LEAF_FLAG) >> 3, r & 7))
    }
}

/// One BVH2 node, 32 bytes:
///
/// * `a = (grid.x, grid.y, grid.z, child ref 0)`,
/// * `b = (q0, q1, q2, child ref 1)`,
///
/// where `grid` and `q` are [`quantize_boxes`]'s words: per axis a grid origin and a
/// power-of-two step, and the two children's boxes as 8-bit grid coordinates.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct GpuNode {
    pub a: [u32; 4],
    pub b: [u32; 4],
}

impl GpuNode {
    /// A node over two child boxes (quantised conservatively) and child references.
    pub fn new(boxes: [Aabb; 2], children: [u32; 2]) -> GpuNode {
        let w = quantize_boxes(boxes);
        GpuNode { a: [w[0], w[1], w[2], children[0]], b: [w[3], w[4], w[5], children[1]] }
    }

    /// Decoded box of child `i` (0 or 1), exactly as the GPU decodes it.
    pub fn bounds(&self, i: usize) -> Aabb {
        self.boxes()[i]
    }

    /// Both decoded child boxes.
    pub fn boxes(&self) -> [Aabb; 2] {
        dequantize_boxes([self.a[0], self.a[1], self.a[2], self.b[0], self.b[1], self.b[2]])
    }

    /// Child reference `i` (0 or 1), see [`decode_ref`].
    pub fn child(&self, i: usize) -> u32 {
        [self.a[3], self.b[3]][i]
    }

    /// Replaces both child references (the boxes stay).
    pub fn set_children(&mut self, children: [u32; 2]) {
        self.a[3] = children[0];
        self.b[3] = children[1];
    }
}

/// The reference of an empty slot of a [`GpuNode4`]: a leaf of no primitives (the one
/// leaf reference with first primitive 0 and count 0; the builder makes it only for the
/// missing second child of a root over fewer than two primitives, which is empty too).
pub const EMPTY_REF: u32 = LEAF_FLAG;

/// One node of the uploaded 4-wide BVH, 64 bytes: two pairs of (box, child reference),
/// each encoded as a [`GpuNode`] (its own grid, 8-bit boxes). Made by [`widen`] from a
/// BVH2 node n: pair k is child k's own node (n's grandchildren) when child k is internal,
/// else child k's box and [`EMPTY_REF`]. So a traversal visits every other BVH2 level and
/// tests up to four boxes per visit.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct GpuNode4 {
    pub pairs: [GpuNode; 2],
}

impl GpuNode4 {
    /// The four decoded child boxes, exactly as the GPU decodes them.
    pub fn boxes(&self) -> [Aabb; 4] {
        let [a, b] = self.pairs[0].boxes();
        let [c, d] = self.pairs[1].boxes();
        [a, b, c, d]
    }

    /// Child reference `i` (0..4): an internal node's index in the 4-wide array, a leaf,
    /// or [`EMPTY_REF`].
    pub fn child(&self, i: usize) -> u32 {
        self.pairs[i / 2].child(i % 2)
    }
}

/// The 4-wide form of a flattened BVH2 (`nodes`, possibly several trees: the top-level
/// tree at node 0 and, with instances, the mesh trees whose roots are `roots`): one
/// [`GpuNode4`] per BVH2 node at an even depth of its tree (a tree's root at depth 0),
/// numbered in depth-first order from node 0 then from each of `roots`. Returns the nodes
/// and, for each BVH2 node, its index in them (`u32::MAX` for the odd depths).
///
/// Of a tree's internal nodes at even depth all but the root have an internal parent at
/// odd depth, and that parent has at most two children, so a tree of I internal nodes
/// gets at most (2 I + 1) / 3 wide nodes ([`max_wide_nodes`]). A BVH2 of depth at most
/// [`MAX_DEPTH`] has at most [`MAX_WIDE_DEPTH`] levels of wide nodes.
pub fn widen(nodes: &[GpuNode], roots: &[u32]) -> (Vec<GpuNode4>, Vec<u32>) {
    let mut index = vec![u32::MAX; nodes.len()];
    let mut order = Vec::new();
    let mut stack = Vec::new();
    for &root in std::iter::once(&0).chain(roots) {
        // A mesh placed by several instances is one tree.
        if index[root as usize] != u32::MAX {
            continue;
        }
        stack.push(root);
        while let Some(n) = stack.pop() {
            index[n as usize] = order.len() as u32;
            order.push(n);
            let node = &nodes[n as usize];
            // Grandchildren in reverse, so they are numbered in child order.
            for k in (0..2).rev() {
                if let Ok(c) = decode_ref(node.child(k)) {
                    let child = &nodes[c as usize];
                    for j in (0..2).rev() {
                        if let Ok(g) = decode_ref(child.child(j)) {
                            stack.push(g);
                        }
                    }
                }
            }
        }
    }
    let remap = |r: u32| match decode_ref(r) {
        Ok(g) => index[g as usize],
        Err(_) => r,
    };
    let wide = order
        .iter()
        .map(|&n| {
            let node = &nodes[n as usize];
            let pairs = [0, 1].map(|k| match decode_ref(node.child(k)) {
                Ok(c) => {
                    let mut pair = nodes[c as usize];
                    pair.set_children([remap(pair.child(0)), remap(pair.child(1))]);
                    pair
                }
                Err(_) => {
                    let b = node.bounds(k);
                    GpuNode::new([b, b], [node.child(k), EMPTY_REF])
                }
            });
            GpuNode4 { pairs }
        })
        .collect();
    (wide, index)
}

/// Most levels of [`GpuNode4`]s on a root-to-leaf path: the BVH2's even depths.
pub const MAX_WIDE_DEPTH: u32 = MAX_DEPTH.div_ceil(2);

/// An upper bound on the [`GpuNode4`]s of the BVH of `prims` primitive slots (triangles,
/// spheres, and three per instance: its primitive and its two-slot record) over
/// `trees` trees (1 + the number of shared meshes), known before the build: each tree
/// over p primitives has at most max(p, 1) internal nodes, hence at most (2 max(p, 1) + 1)
/// / 3 wide nodes ([`widen`]).
pub fn max_wide_nodes(prims: u64, trees: u64) -> u64 {
    (2 * (prims + trees) + trees).div_ceil(3)
}

/// Decoded value of grid coordinate `q`: `origin + q * step`. `step` is a power of two and
/// `q < 256`, so the product is exact and only the addition rounds, identically on the CPU
/// and the GPU (with or without a fused multiply-add).
#[inline]
fn dequant(origin: f32, step: f32, q: u32) -> f32 {
    origin + q as f32 * step
}

/// A grid word: the origin is the word with its low 8 bits cleared (a float), the step
/// is `2^(e - 127)` with the biased exponent `e` in the low 8 bits.
#[inline]
fn grid_of(word: u32) -> (f32, f32) {
    (f32::from_bits(word & !0xff), f32::from_bits((word & 0xff) << 23))
}

/// Quantises two child boxes conservatively to 8 bits per coordinate.
///
/// Per axis the node has a grid: an origin `o <= min(lo0, lo1)` (the minimum rounded
/// towards -inf to 16 mantissa bits, freeing the low 8 bits of its float for the step's
/// biased exponent) and a power-of-two step chosen so that 255 steps cover the node.
/// Each box coordinate becomes `q` in 0..=255 with `o + q * step` (decoded in f32 exactly
/// as the GPU does) `<=` the lower and `>=` the upper bound, so decoded boxes contain the
/// input boxes. Returns six words: the x, y, z grid words, then the bytes (low byte first)
/// `(c0.lo.x, c0.lo.y, c0.lo.z, c1.lo.x)`, `(c0.hi.x, c0.hi.y, c0.hi.z, c1.hi.x)`,
/// `(c1.lo.y, c1.lo.z, c1.hi.y, c1.hi.z)`.
///
/// The boxes must be finite (the builder guarantees it).
pub fn quantize_boxes(boxes: [Aabb; 2]) -> [u32; 6] {
    let mut grid = [0u32; 3];
    let mut q = [[[0u32; 3]; 2]; 2]; // [child][lo, hi][axis]
    for a in 0..3 {
        let lo = boxes[0].min[a].min(boxes[1].min[a]);
        let hi = boxes[0].max[a].max(boxes[1].max[a]);
        let bits = lo.to_bits();
        let obits = if lo >= 0.0 || bits & 0xff == 0 {
            bits & !0xff // towards zero = towards -inf
        } else {
            (bits | 0xff) + 1 // negative: away from zero
        };
        let origin = f32::from_bits(obits);
        // Smallest step with 255 steps covering the node, with slack for the rounding of
        // the decode; grown below if a bound still does not fit.
        let need = ((hi as f64 - origin as f64) + hi.abs() as f64 * 1e-6 + 1e-38) / 255.0;
        let mut biased = (ceil_log2(need) + 127).clamp(1, 254) as u32;
        'grid: loop {
            let step = f32::from_bits(biased << 23);
            // The step is a power of two, 2^(biased - 127), so dividing by it is
            // multiplying by its exact reciprocal, made from its exponent (in f64, without
            // overflow or underflow).
            let inv_step = f64::from_bits(((1023 + 127 - biased) as u64) << 52);
            for c in 0..2 {
                let (blo, bhi) = (boxes[c].min[a], boxes[c].max[a]);
                let mut ql = floor_to_byte((blo as f64 - origin as f64) * inv_step);
                while ql > 0 && dequant(origin, step, ql) > blo {
                    ql -= 1;
                }
                let mut qh = ceil_to_byte((bhi as f64 - origin as f64) * inv_step);
                while dequant(origin, step, qh) < bhi {
                    if qh == 255 {
                        assert!(biased < 254, "box not representable: {boxes:?}");
                        biased += 1;
                        continue 'grid;
                    }
                    qh += 1;
                }
                q[c][0][a] = ql;
                q[c][1][a] = qh;
            }
            break;
        }
        grid[a] = obits | biased;
    }
    let pack = |b: [u32; 4]| b[0] | b[1] << 8 | b[2] << 16 | b[3] << 24;
    [
        grid[0],
        grid[1],
        grid[2],
        pack([q[0][0][0], q[0][0][1], q[0][0][2], q[1][0][0]]),
        pack([q[0][1][0], q[0][1][1], q[0][1][2], q[1][1][0]]),
        pack([q[1][0][1], q[1][0][2], q[1][1][1], q[1][1][2]]),
    ]
}

/// `ceil(log2(x))` for a positive normal `x`, exactly, from the bits: the exponent, plus one
/// unless `x` is a power of two. (`f64::log2` is a libm call on baseline x86-64, a large
/// share of the build's time, and may round `log2` of a value just above a power of two
/// down to that power.)
#[inline]
fn ceil_log2(x: f64) -> i32 {
    let bits = x.to_bits();
    let exponent = ((bits >> 52) & 0x7ff) as i32 - 1023;
    exponent + i32::from(bits & ((1 << 52) - 1) != 0)
}

/// `floor(x)` clamped to `0..=255` (NaN: 0), without libm's `floor` (not inlined on
/// baseline x86-64): for `0 <= x < 255` truncation is the floor.
#[inline]
fn floor_to_byte(x: f64) -> u32 {
    if x >= 255.0 {
        255
    } else if x > 0.0 {
        x as u32
    } else {
        0
    }
}

/// `ceil(x)` clamped to `0..=255` (NaN: 0), as [`floor_to_byte`].
#[inline]
fn ceil_to_byte(x: f64) -> u32 {
    if x >= 255.0 {
        255
    } else if x > 0.0 {
        let t = x as u32;
        t + u32::from((t as f64) < x)
    } else {
        0
    }
}

/// Decodes [`quantize_boxes`]'s words (as `bvh_load_node` in glsl/bvh.glsl does).
pub fn dequantize_boxes(w: [u32; 6]) -> [Aabb; 2] {
    let g = [grid_of(w[0]), grid_of(w[1]), grid_of(w[2])];
    let byte = |word: u32, k: u32| (word >> (8 * k)) & 0xff;
    let d = |a: usize, q: u32| dequant(g[a].0, g[a].1, q);
    [
        Aabb {
            min: Vec3::new(d(0, byte(w[3], 0)), d(1, byte(w[3], 1)), d(2, byte(w[3], 2))),
            max: Vec3::new(d(0, byte(w[4], 0)), d(1, byte(w[4], 1)), d(2, byte(w[4], 2))),
        },
        Aabb {
            min: Vec3::new(d(0, byte(w[3], 3)), d(1, byte(w[5], 0)), d(2, byte(w[5], 1))),
            max: Vec3::new(d(0, byte(w[4], 3)), d(1, byte(w[5], 2)), d(2, byte(w[5], 3))),
        },
    ]
}

/// One primitive, 48 bytes, in leaf order.
///
/// * Triangle: `a = (v0, id)`, `b = (v1, material)`, `c = (v2, 0)`.
/// * Sphere: `a = (center, id | SPHERE_FLAG)`, `b = (radius, 0, 0, material)`, `c = 0`.
/// * Instance: `a = (root node, record slot, 0, instance | INSTANCE_FLAG)`, `b = c = 0`.
/// * Instance record (two slots): the rows of the world-to-object then the
///   object-to-world affine matrix, each row `(m0, m1, m2, translation)`.
///
/// `id` is the primitive's original index in `Scene::triangles` (triangles) or in
/// `Scene::spheres` (spheres); `id` and `material` are `u32`s stored bit-cast.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuPrim {
    pub a: [f32; 4],
    pub b: [f32; 4],
    pub c: [f32; 4],
}

impl GpuPrim {
    pub fn triangle(p: [Vec3; 3], id: u32, material: u32) -> GpuPrim {
        assert!((id as usize) < MAX_IDS, "triangle index too large");
        GpuPrim {
            a: [p[0].x, p[0].y, p[0].z, f32::from_bits(id)],
            b: [p[1].x, p[1].y, p[1].z, f32::from_bits(material)],
            c: [p[2].x, p[2].y, p[2].z, 0.0],
        }
    }

    pub fn sphere(center: Vec3, radius: f32, id: u32, material: u32) -> GpuPrim {
        assert!(id & SPHERE_FLAG == 0, "sphere index too large");
        GpuPrim {
            a: [center.x, center.y, center.z, f32::from_bits(id | SPHERE_FLAG)],
            b: [radius, 0.0, 0.0, f32::from_bits(material)],
            c: [0.0; 4],
        }
    }

    /// An instance primitive of the top-level tree (see [`GpuPrim`]); `root` and `record`
    /// may be placeholders that the builder sets once the arrays are joined.
    pub fn instance(instance: u32, root: u32, record: u32) -> GpuPrim {
        assert!((instance as usize) < MAX_IDS, "instance index too large");
        GpuPrim {
            a: [f32::from_bits(root), f32::from_bits(record), 0.0, f32::from_bits(instance | INSTANCE_FLAG)],
            b: [0.0; 4],
            c: [0.0; 4],
        }
    }

    /// The two record slots of an instance placed by `object_to_world`.
    pub fn instance_record(object_to_world: glam::Affine3A) -> [GpuPrim; 2] {
        let rows = |m: glam::Affine3A| {
            let l = glam::Mat3::from(m.matrix3);
            let t = m.translation;
            [0, 1, 2].map(|r| {
                let row = l.row(r);
                [row.x, row.y, row.z, t[r]]
            })
        };
        let [w0, w1, w2] = rows(object_to_world.inverse());
        let [o0, o1, o2] = rows(object_to_world);
        [GpuPrim { a: w0, b: w1, c: w2 }, GpuPrim { a: o0, b: o1, c: o2 }]
    }

    /// Whether this is an instance primitive.
    pub fn is_instance(&self) -> bool {
        self.a[3].to_bits() & (SPHERE_FLAG | INSTANCE_FLAG) == INSTANCE_FLAG
    }

    /// An instance primitive's mesh root node and record slot.
    pub fn instance_target(&self) -> (u32, u32) {
        (self.a[0].to_bits(), self.a[1].to_bits())
    }

    pub fn is_sphere(&self) -> bool {
        self.a[3].to_bits() & SPHERE_FLAG != 0
    }

    /// Original index in `Scene::triangles`, `Scene::spheres` or `Scene::instances` (see
    /// [`Self::is_sphere`], [`Self::is_instance`]).
    pub fn id(&self) -> u32 {
        self.a[3].to_bits() & !(SPHERE_FLAG | INSTANCE_FLAG)
    }

    pub fn material(&self) -> u32 {
        self.b[3].to_bits()
    }

    pub fn vertices(&self) -> [Vec3; 3] {
        [
            Vec3::new(self.a[0], self.a[1], self.a[2]),
            Vec3::new(self.b[0], self.b[1], self.b[2]),
            Vec3::new(self.c[0], self.c[1], self.c[2]),
        ]
    }
}

/// The flattened BVH as uploaded: bind `nodes` and `prims` as two storage buffers (see
/// glsl/bvh.glsl for what the kernel declares). `nodes` is the 4-wide form of the build's
/// BVH2 ([`widen`]); instance primitives name their mesh's root in it.
#[derive(Clone, Debug, Default)]
pub struct GpuBvh {
    pub nodes: Vec<GpuNode4>,
    pub prims: Vec<GpuPrim>,
    /// Triangles and spheres of the input (including skipped ones).
    pub num_triangles: u32,
    pub num_spheres: u32,
    /// Instances in the top-level tree (their records follow the primitives).
    pub num_instances: u32,
}

impl GpuBvh {
    /// Optional defines for kernels including glsl/bvh.glsl: `BVH_NO_SPHERES` when the
    /// BVH holds no sphere (the sphere test is then compiled out), `BVH_INSTANCES` when it
    /// holds instances.
    pub fn glsl_defines(&self) -> Vec<(&'static str, String)> {
        let mut d = Vec::new();
        if !self.primitives().iter().any(|p| p.is_sphere()) {
            d.push(("BVH_NO_SPHERES", "1".to_string()));
        }
        if self.num_instances > 0 {
            d.push(("BVH_INSTANCES", "1".to_string()));
        }
        d
    }

    /// The primitive slots without the instance records that follow them.
    pub fn primitives(&self) -> &[GpuPrim] {
        &self.prims[..self.prims.len() - 2 * self.num_instances as usize]
    }

    /// Bytes of the two buffers.
    pub fn size_bytes(&self) -> usize {
        std::mem::size_of_val(self.nodes.as_slice()) + std::mem::size_of_val(self.prims.as_slice())
    }
}
