//! GPU layout of the BVH: 64-byte BVH2 nodes that hold both children's boxes (Aila &
//! Laine, "Understanding the Efficiency of Ray Traversal on GPUs", HPG 2009) and 48-byte
//! primitives in leaf order. Mirrored by `glsl/bvh.glsl`, which reads both buffers as
//! `vec4` arrays (std430: a `vec4[]` has a 16-byte stride, so the Rust structs below, made
//! of `[f32; 4]` members only, have exactly the GLSL byte layout).
//!
//! Child references (`u32`, stored bit-cast in a float lane of the node):
//! * bit 31 clear: index of an internal node in the node array;
//! * bit 31 set: a leaf, `LEAF_FLAG | first << 3 | count`, covering
//!   `prims[first .. first + count]`, `count <= MAX_LEAF_PRIMS` (0 only for the empty
//!   second child of a root over fewer than two primitives).
//!
//! Node 0 is the root. It is always an internal node.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use super::build::Aabb;

/// Bit 31 of a child reference: the child is a leaf.
pub const LEAF_FLAG: u32 = 0x8000_0000;
/// Largest number of primitives in one leaf (3 bits of the child reference hold it).
pub const MAX_LEAF_PRIMS: usize = 4;
/// Largest number of primitives a BVH can hold (28 bits of first-primitive index).
pub const MAX_PRIMS: usize = 1 << 28;
/// Largest number of internal-node levels on any root-to-leaf path (the root is level 1).
/// The GLSL traversal stack (`BVH_STACK_SIZE` in glsl/bvh.glsl) has this many entries:
/// it pushes at most one entry per internal level. The builder guarantees the bound.
pub const MAX_DEPTH: u32 = 32;
/// Bit 31 of a primitive's id word (`GpuPrim::a[3]` bits): the primitive is a sphere.
pub const SPHERE_FLAG: u32 = 0x8000_0000;

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

/// How a node's 64 bytes are arranged (both layouts hold the same data). The GLSL side
/// selects with `#define BVH_NODE_LAYOUT` (0 or 1; default [`NodeLayout::DEFAULT`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NodeLayout {
    /// `BVH_NODE_LAYOUT 0`: child 0 min (w = child 0 ref), child 0 max (w = child 1 ref),
    /// child 1 min (w = 0), child 1 max (w = 0).
    Boxes = 0,
    /// `BVH_NODE_LAYOUT 1`: Aila & Laine's arrangement: (c0.lo.x, c0.hi.x, c0.lo.y,
    /// c0.hi.y), (c1.lo.x, c1.hi.x, c1.lo.y, c1.hi.y), (c0.lo.z, c0.hi.z, c1.lo.z,
    /// c1.hi.z), (child 0 ref, child 1 ref, 0, 0).
    Interleaved = 1,
}

impl NodeLayout {
    /// The layout `glsl/bvh.glsl` uses when `BVH_NODE_LAYOUT` is not defined.
    pub const DEFAULT: NodeLayout = NodeLayout::Boxes;
}

/// One BVH2 node: the boxes of both children and the two child references (64 bytes,
/// arrangement given by [`NodeLayout`]).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuNode {
    pub a: [f32; 4],
    pub b: [f32; 4],
    pub c: [f32; 4],
    pub d: [f32; 4],
}

impl GpuNode {
    pub fn new(layout: NodeLayout, boxes: [Aabb; 2], children: [u32; 2]) -> GpuNode {
        let [l, r] = boxes;
        let bits = |x: u32| f32::from_bits(x);
        match layout {
            NodeLayout::Boxes => GpuNode {
                a: [l.min.x, l.min.y, l.min.z, bits(children[0])],
                b: [l.max.x, l.max.y, l.max.z, bits(children[1])],
                c: [r.min.x, r.min.y, r.min.z, 0.0],
                d: [r.max.x, r.max.y, r.max.z, 0.0],
            },
            NodeLayout::Interleaved => GpuNode {
                a: [l.min.x, l.max.x, l.min.y, l.max.y],
                b: [r.min.x, r.max.x, r.min.y, r.max.y],
                c: [l.min.z, l.max.z, r.min.z, r.max.z],
                d: [bits(children[0]), bits(children[1]), 0.0, 0.0],
            },
        }
    }

    /// Box of child `i` (0 or 1).
    pub fn bounds(&self, layout: NodeLayout, i: usize) -> Aabb {
        match layout {
            NodeLayout::Boxes => {
                let (lo, hi) = if i == 0 { (self.a, self.b) } else { (self.c, self.d) };
                Aabb { min: Vec3::new(lo[0], lo[1], lo[2]), max: Vec3::new(hi[0], hi[1], hi[2]) }
            }
            NodeLayout::Interleaved => {
                let xy = if i == 0 { self.a } else { self.b };
                let z = if i == 0 { [self.c[0], self.c[1]] } else { [self.c[2], self.c[3]] };
                Aabb { min: Vec3::new(xy[0], xy[2], z[0]), max: Vec3::new(xy[1], xy[3], z[1]) }
            }
        }
    }

    /// Child reference `i` (0 or 1), see [`decode_ref`].
    pub fn child(&self, layout: NodeLayout, i: usize) -> u32 {
        match layout {
            NodeLayout::Boxes => [self.a[3], self.b[3]][i].to_bits(),
            NodeLayout::Interleaved => self.d[i].to_bits(),
        }
    }
}

/// One primitive, 48 bytes, in leaf order.
///
/// * Triangle: `a = (v0, id)`, `b = (v1, material)`, `c = (v2, 0)`.
/// * Sphere: `a = (center, id | SPHERE_FLAG)`, `b = (radius, 0, 0, material)`, `c = 0`.
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
        assert!(id & SPHERE_FLAG == 0, "triangle index too large");
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

    pub fn is_sphere(&self) -> bool {
        self.a[3].to_bits() & SPHERE_FLAG != 0
    }

    /// Original index in `Scene::triangles` or `Scene::spheres` (see [`Self::is_sphere`]).
    pub fn id(&self) -> u32 {
        self.a[3].to_bits() & !SPHERE_FLAG
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
/// glsl/bvh.glsl for what the kernel declares).
#[derive(Clone, Debug, Default)]
pub struct GpuBvh {
    pub nodes: Vec<GpuNode>,
    pub prims: Vec<GpuPrim>,
    pub layout: NodeLayout,
    /// Triangles and spheres of the input (including skipped ones).
    pub num_triangles: u32,
    pub num_spheres: u32,
}

impl Default for NodeLayout {
    fn default() -> Self {
        NodeLayout::DEFAULT
    }
}

impl GpuBvh {
    /// Defines a kernel including glsl/bvh.glsl must be compiled with for this layout.
    pub fn glsl_defines(&self) -> Vec<(&'static str, String)> {
        vec![("BVH_NODE_LAYOUT", (self.layout as u32).to_string())]
    }

    /// Bytes of the two buffers.
    pub fn size_bytes(&self) -> usize {
        std::mem::size_of_val(self.nodes.as_slice()) + std::mem::size_of_val(self.prims.as_slice())
    }
}
