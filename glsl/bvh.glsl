// BVH traversal: closest hit and any hit over the BVH built by src/bvh (binned SAH, BVH2
// nodes holding both children's boxes as in Aila & Laine, "Understanding the Efficiency
// of Ray Traversal on GPUs", HPG 2009, quantised to 8 bits), uploaded in its 4-wide form:
// each node holds its grandchildren's boxes, so a visit tests up to four boxes and a ray
// visits every other BVH2 level. Mirrored on the CPU by src/bvh/traverse.rs; layout in
// src/bvh/layout.rs; measurements in docs/bvh.md.
//
// The two buffers are the bindings `bvh_nodes` and `bvh_prims` (bound by name,
// src/gpu/reflect.rs). The including kernel provides them in one of two ways, before
// `#include "bvh.glsl"`:
//
// 1. (fast) `#define BVH_DECLARES_BUFFERS` and let this file declare them, as arrays of
//    u64vec2 with `#define BVH_INT64 1` (64-bit loads: on lavapipe a 64-bit gather moves
//    twice the data of a 32-bit one per instruction; needs shaderInt64), as uvec4 arrays
//    without (devices without shaderInt64: the same bits); with `#define BVH_TEXEL 1` as
//    uniform texel buffers of uvec4 texels (utextureBuffer) instead (src/render/reads.rs).
//
// 2. (compatible) declare them itself as vec4 arrays with these names:
//
//      layout(std430) readonly buffer bvh_nodes { vec4 bvh_node_data[]; };
//      layout(std430) readonly buffer bvh_prims { vec4 bvh_prim_data[]; };
//
// 3. With SCENE_CHUNKS (glsl/scene.glsl) and BVH_DECLARES_BUFFERS: read by device address
//    in chunks, for scenes larger than one binding.
//
// Optional: `#define BVH_NO_SPHERES` when the scene has no spheres (GpuBvh::glsl_defines
// says so): the sphere test is compiled out. `#define BVH_INSTANCES` when it has instances
// (the two-level BVH below).
//
// Provides: struct Hit, trace_closest(o, d, tmin, tmax, out Hit), trace_any(o, d, tmin,
// tmax), and the ray/primitive tests of intersect.glsl.
//
// Node i = elements 4i .. 4i+3 (64 bytes): two pairs of (box, child ref), children 0, 1
// then 2, 3, each pair two elements (grid.x, grid.y, grid.z, ref0) (q0, q1, q2, ref1)
// (GpuNode4 in src/bvh/layout.rs). Per axis a grid word holds an origin (the float with
// its low 8 bits cleared) and a power-of-two step (biased exponent in the low 8 bits);
// q0..q2 hold the pair's box coordinates as bytes: (c0.lo.xyz, c1.lo.x) (c0.hi.xyz,
// c1.hi.x) (c1.lo.yz, c1.hi.yz), each decoding to origin + q * step (the builder rounds
// them outwards). Child refs: bit 31 clear = internal node index; bit 31 set = leaf
// (first prim << 3 | count); BVH_EMPTY (a leaf of no primitives) = no child.
// Prim i = elements 3i .. 3i+2 (48 bytes), in leaf order:
//   triangle: (v0, id) (v1, material) (v2, 0)
//   sphere:   (center, id | BVH_SPHERE_FLAG) (radius, 0, 0, material) (0)
//   instance: (root node, record slot, 0, instance | BVH_INSTANCE_FLAG) (0) (0)
// id = original index in the scene's triangle list, or sphere list for spheres.
//
// Instances (src/bvh/layout.rs, "Instancing"): each shared mesh has its own tree in object
// space, after the top-level tree in both arrays, with absolute indices. An instance's
// record, two prim slots, holds the rows (m0, m1, m2, translation) of its world-to-object
// then its object-to-world matrix. Meeting an instance in a leaf, the traversal pushes
// the rest of the leaf and a BVH_RETURN marker (entry distance -inf: never culled), moves
// the ray into object space (the direction is not normalised, so t means the same in
// both spaces) and descends from the mesh's root; popping the marker moves the ray back.
//
// Stack: BVH_STACK_SIZE entries; the traversal pushes at most three per node visited,
// and a path visits at most 16 nodes (the builder's BVH2 has at most MAX_DEPTH = 32
// levels; MAX_STACK in src/bvh/layout.rs); with instances a top-level path and a mesh
// path plus the three entries entering an instance pushes (bvh_traverse;
// MAX_STACK_INSTANCED).
// Ray/box test: Ize, "Robust BVH Ray Traversal", JCGT 2013 (exit distance widened), on
// boxes the builder padded and quantised outwards.
#ifndef VKVCM_BVH_GLSL
#define VKVCM_BVH_GLSL

#include "intersect.glsl"

#ifdef BVH_INSTANCES
#define BVH_STACK_SIZE 99
#else
#define BVH_STACK_SIZE 48
#endif
#define BVH_EMPTY 0x80000000u
#define BVH_INSTANCE_FLAG 0x40000000u
#define BVH_RETURN 0xfffffffeu
#define BVH_NO_INSTANCE 0xffffffffu
#define BVH_LEAF_FLAG 0x80000000u
#define BVH_SPHERE_FLAG 0x80000000u
#define BVH_DONE 0xffffffffu
#define BVH_ROBUST_SCALE 1.000002

// Optional: `#define BVH_ALPHA_TEST` and define alpha_visible (glsl/textures.glsl): a
// candidate hit at distance t it rejects is not a hit (cut-outs, stochastic
// transparency), for closest and any hits alike.
#ifdef BVH_ALPHA_TEST
bool alpha_visible(uint id, uint material, float u, float v, float t);
#endif
// Optional: `#define BVH_FACE_TEST` and define back_face_visible (glsl/scene.glsl): in a
// traversal with `cull_back_faces`, a candidate triangle hit on the back side (the ray
// along the winding's normal cross(v1 - v0, v2 - v0), in the space the triangle is stored
// in) is not a hit when back_face_visible(material) is false: one-sided surfaces, for
// closest and any hits alike. In an instance's object space the test gives glTF's facing
// in world space for mirroring transforms too, since the glTF front side is the
// object-space one.
#ifdef BVH_FACE_TEST
bool back_face_visible(uint material);
#endif

#ifndef BVH_TEXEL
#define BVH_TEXEL 0
#endif
#ifndef BVH_INT64
#define BVH_INT64 1
#endif
#if defined(BVH_DECLARES_BUFFERS) && defined(SCENE_CHUNKS) && SCENE_CHUNKS
// In chunks, by device address (glsl/scene.glsl, SCENE_CHUNKS).
uvec4 bvh_node_elem(uint i) {
    return scene_chunked_elem(CHUNK_NODES, i);
}
uvec4 bvh_prim_elem(uint i) {
    return scene_chunked_elem(CHUNK_PRIMS, i);
}
#elif defined(BVH_DECLARES_BUFFERS) && BVH_TEXEL
#extension GL_EXT_samplerless_texture_functions : require
// Uniform texel buffers of uvec4 texels (scene.glsl's TEXEL_READS).
uniform utextureBuffer bvh_nodes;
uniform utextureBuffer bvh_prims;
uvec4 bvh_node_elem(uint i) {
    return texelFetch(bvh_nodes, int(i));
}
uvec4 bvh_prim_elem(uint i) {
    return texelFetch(bvh_prims, int(i));
}
#elif defined(BVH_DECLARES_BUFFERS) && !BVH_INT64
layout(std430) readonly buffer bvh_nodes {
    uvec4 bvh_node_data[];
};
layout(std430) readonly buffer bvh_prims {
    uvec4 bvh_prim_data[];
};
uvec4 bvh_node_elem(uint i) {
    return bvh_node_data[i];
}
uvec4 bvh_prim_elem(uint i) {
    return bvh_prim_data[i];
}
#elif defined(BVH_DECLARES_BUFFERS)
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
layout(std430) readonly buffer bvh_nodes {
    u64vec2 bvh_node_data[];
};
layout(std430) readonly buffer bvh_prims {
    u64vec2 bvh_prim_data[];
};
uvec4 bvh_node_elem(uint i) {
    u64vec2 v = bvh_node_data[i];
    return uvec4(unpackUint2x32(v.x), unpackUint2x32(v.y));
}
uvec4 bvh_prim_elem(uint i) {
    u64vec2 v = bvh_prim_data[i];
    return uvec4(unpackUint2x32(v.x), unpackUint2x32(v.y));
}
#else
uvec4 bvh_node_elem(uint i) {
    return floatBitsToUint(bvh_node_data[i]);
}
uvec4 bvh_prim_elem(uint i) {
    return floatBitsToUint(bvh_prim_data[i]);
}
#endif

struct Hit {
    float t;          // distance in units of |d|
    uint prim;        // original triangle index, or sphere index when is_sphere
    float u;          // barycentric weight of v1 (triangles; 0 for spheres)
    float v;          // barycentric weight of v2
    bool is_sphere;
    uint material;
    uint slot;             // the primitive's slot in bvh_prims (its vertices, in leaf order)
    uint instance_record;  // the instance's record slot (BVH_INSTANCES), else BVH_NO_INSTANCE
};

// An instance record's rows applied to p: a point with w = 1, a direction with w = 0
// (the CPU mirror's apply_rows, same operation order).
vec3 bvh_apply_rows(uint record, vec3 p, float w) {
    vec4 r0 = uintBitsToFloat(bvh_prim_elem(record));
    vec4 r1 = uintBitsToFloat(bvh_prim_elem(record + 1u));
    vec4 r2 = uintBitsToFloat(bvh_prim_elem(record + 2u));
    return vec3(r0.x * p.x + r0.y * p.y + r0.z * p.z + r0.w * w,
                r1.x * p.x + r1.y * p.y + r1.z * p.z + r1.w * w,
                r2.x * p.x + r2.y * p.y + r2.z * p.z + r2.w * w);
}

// 1/d with components below 1e-30 in magnitude clamped to +-1e-30 (no 0 * inf NaNs; the
// builder pads node boxes so a ray on a box plane and parallel to it still enters).
vec3 bvh_safe_inv(vec3 d) {
    vec3 s = vec3(d.x < 0.0 ? -1e-30 : 1e-30, d.y < 0.0 ? -1e-30 : 1e-30,
                  d.z < 0.0 ? -1e-30 : 1e-30);
    return vec3(1.0) / mix(d, s, lessThan(abs(d), vec3(1e-30)));
}

// Slab test: true when [tmin, tmax] overlaps the box; tn = entry distance.
bool bvh_ray_box(vec3 lo, vec3 hi, vec3 o, vec3 inv_d, float tmin, float tmax,
                 out float tn) {
    vec3 t0 = (lo - o) * inv_d;
    vec3 t1 = (hi - o) * inv_d;
    vec3 tl = min(t0, t1);
    vec3 th = max(t0, t1);
    tn = max(max(tl.x, tl.y), max(tl.z, tmin));
    float tf = min(min(th.x, th.y), min(th.z, tmax));
    return tn <= tf * BVH_ROBUST_SCALE;
}

// Decodes the pair of (box, child ref) at elements e, e + 1.
void bvh_load_pair(uint e, out vec3 lo0, out vec3 hi0, out vec3 lo1, out vec3 hi1,
                   out uint c0, out uint c1) {
    uvec4 a = bvh_node_elem(e);
    uvec4 b = bvh_node_elem(e + 1u);
    vec3 o = uintBitsToFloat(a.xyz & 0xffffff00u);
    vec3 s = uintBitsToFloat((a.xyz & 0xffu) << 23);
    const uvec4 shifts = uvec4(0u, 8u, 16u, 24u);
    vec4 q0 = vec4(ivec4((uvec4(b.x) >> shifts) & 0xffu));
    vec4 q1 = vec4(ivec4((uvec4(b.y) >> shifts) & 0xffu));
    vec4 q2 = vec4(ivec4((uvec4(b.z) >> shifts) & 0xffu));
    // q * s is exact (8-bit integer times a power of two): one rounding, as on the CPU.
    lo0 = o + q0.xyz * s;
    hi0 = o + q1.xyz * s;
    lo1 = o + vec3(q0.w, q2.xy) * s;
    hi1 = o + vec3(q1.w, q2.zw) * s;
    c0 = a.w;
    c1 = b.w;
}

// Pops the next entry whose entry distance is not beyond tmax (or BVH_DONE); with
// instances, a BVH_RETURN marker moves the ray back to world space.
#ifdef BVH_INSTANCES
#define BVH_POP_RETURN_MARKER()            \
    if (stack[sp] == BVH_RETURN) {         \
        o = world_o;                       \
        d = world_d;                       \
        inv_d = bvh_safe_inv(d);           \
        sh = ray_shear(d);                 \
        record = BVH_NO_INSTANCE;          \
        continue;                          \
    }
#else
#define BVH_POP_RETURN_MARKER()
#endif
#define BVH_POP()                                \
    {                                            \
        cur = BVH_DONE;                          \
        while (sp > 0u) {                        \
            sp--;                                \
            if (stack_t[sp] <= tmax) {           \
                BVH_POP_RETURN_MARKER()          \
                cur = stack[sp];                 \
                break;                           \
            }                                    \
        }                                        \
    }

#define BVH_INF uintBitsToFloat(0x7f800000u)
// Orders (ka, ca), (kb, cb) by key.
#define BVH_SORT2(ka, ca, kb, cb)      \
    {                                  \
        bool sw = kb < ka;             \
        float tk = ka;                 \
        uint tc = ca;                  \
        ka = sw ? kb : ka;             \
        ca = sw ? cb : ca;             \
        kb = sw ? tk : kb;             \
        cb = sw ? tc : cb;             \
    }
#define BVH_PUSH(c, k)     \
    {                      \
        stack[sp] = c;     \
        stack_t[sp] = k;   \
        sp++;              \
    }

// Shared traversal. Returns the primitive slot of the closest hit (or of the first hit
// found when `any_hit`), -1 for none; tmax becomes the hit distance, hrecord the record
// slot of the instance hit (BVH_NO_INSTANCE for world-space primitives).
//
// While-while with one postponed leaf (Aila & Laine, "Understanding the Efficiency of Ray
// Traversal on GPUs", HPG 2009, speculative traversal, without their subgroup vote): the
// node loop descends through internal nodes (nearest child first, the others pushed with
// their entry distances); a lane that reaches a leaf sets it aside and descends on to
// the next leaf, and the loop ends for a lane holding two leaves (or none left). The
// leaf loop then tests the set-aside leaf and, if cur is a leaf, that one too. The node
// loop runs until every lane of a SIMD group holds its leaves, so lanes that would wait
// for the group's slowest descent find their next leaf meanwhile (docs/bvh.md,
// "Traversal and robustness"). A leaf is set aside only in world space: a pop may pass
// an instance's BVH_RETURN marker, after which an object-space leaf would be tested
// with the world-space ray.
#ifdef BVH_INSTANCES
#define BVH_MAY_POSTPONE (record == BVH_NO_INSTANCE)
#else
#define BVH_MAY_POSTPONE true
#endif
int bvh_traverse(vec3 o, vec3 d, float tmin, inout float tmax, const bool any_hit, bool cull_back_faces,
                 out float hu, out float hv, out uint hrecord) {
    vec3 inv_d = bvh_safe_inv(d);
    RayShear sh = ray_shear(d);
    hrecord = BVH_NO_INSTANCE;
#ifdef BVH_INSTANCES
    vec3 world_o = o;
    vec3 world_d = d;
    uint record = BVH_NO_INSTANCE;
#endif
    uint stack[BVH_STACK_SIZE];
    float stack_t[BVH_STACK_SIZE];
    uint sp = 0u;
    uint cur = 0u;
    uint postponed = BVH_DONE;  // the leaf set aside, else BVH_DONE
    int best = -1;
    hu = 0.0;
    hv = 0.0;
    while (true) {
        while (true) {
            if ((cur & BVH_LEAF_FLAG) != 0u) {  // a leaf, or BVH_DONE
                if (cur == BVH_DONE || postponed != BVH_DONE || !BVH_MAY_POSTPONE) break;
                postponed = cur;
                BVH_POP();
                continue;
            }
            vec3 lo0, hi0, lo1, hi1, lo2, hi2, lo3, hi3;
            uint c0, c1, c2, c3;
            bvh_load_pair(4u * cur, lo0, hi0, lo1, hi1, c0, c1);
            bvh_load_pair(4u * cur + 2u, lo2, hi2, lo3, hi3, c2, c3);
            // Entry distances, +inf for a child missed or absent.
            float k0, k1, k2, k3;
            k0 = bvh_ray_box(lo0, hi0, o, inv_d, tmin, tmax, k0) && c0 != BVH_EMPTY ? k0 : BVH_INF;
            k1 = bvh_ray_box(lo1, hi1, o, inv_d, tmin, tmax, k1) && c1 != BVH_EMPTY ? k1 : BVH_INF;
            k2 = bvh_ray_box(lo2, hi2, o, inv_d, tmin, tmax, k2) && c2 != BVH_EMPTY ? k2 : BVH_INF;
            k3 = bvh_ray_box(lo3, hi3, o, inv_d, tmin, tmax, k3) && c3 != BVH_EMPTY ? k3 : BVH_INF;
            // Sorted by entry distance (a 5-comparator network, misses last): the nearest
            // next, the others pushed farthest first. Only the pushes branch: an
            // unconditional write to the stack costs a scatter on lavapipe.
            BVH_SORT2(k0, c0, k1, c1);
            BVH_SORT2(k2, c2, k3, c3);
            BVH_SORT2(k0, c0, k2, c2);
            BVH_SORT2(k1, c1, k3, c3);
            BVH_SORT2(k1, c1, k2, c2);
            if (k3 < BVH_INF) BVH_PUSH(c3, k3);
            if (k2 < BVH_INF) BVH_PUSH(c2, k2);
            if (k1 < BVH_INF) BVH_PUSH(c1, k1);
            if (k0 < BVH_INF) {
                cur = c0;
            } else {
                BVH_POP();
            }
        }
        if (postponed == BVH_DONE && cur == BVH_DONE) {
            break;
        }
        // The set-aside leaf, then cur while it is a leaf (cur is popped after its test).
        bool entered = false;
        while (true) {
            uint leaf;
            if (postponed != BVH_DONE) {
                leaf = postponed;
                postponed = BVH_DONE;
            } else if (cur != BVH_DONE && (cur & BVH_LEAF_FLAG) != 0u) {
                leaf = cur;
                cur = BVH_DONE;
            } else {
                break;
            }
            uint first = (leaf & ~BVH_LEAF_FLAG) >> 3;
            uint end = first + (leaf & 7u);
            for (uint i = first; i < end; i++) {
                uvec4 pa = bvh_prim_elem(3u * i);
#ifdef BVH_INSTANCES
                if ((pa.w & (BVH_SPHERE_FLAG | BVH_INSTANCE_FLAG)) == BVH_INSTANCE_FLAG) {
                    // Entered from world space only (no nesting). What is still to visit
                    // there goes under the return marker: cur (when this leaf was set
                    // aside; never culled), then the rest of this leaf.
                    if (cur != BVH_DONE) BVH_PUSH(cur, -BVH_INF);
                    if (i + 1u < end) BVH_PUSH(BVH_LEAF_FLAG | ((i + 1u) << 3) | (end - i - 1u), -BVH_INF);
                    BVH_PUSH(BVH_RETURN, -BVH_INF);
                    record = pa.y;
                    o = bvh_apply_rows(3u * record, world_o, 1.0);
                    d = bvh_apply_rows(3u * record, world_d, 0.0);
                    inv_d = bvh_safe_inv(d);
                    sh = ray_shear(d);
                    cur = pa.x;
                    entered = true;
                    break;
                }
#endif
                uvec4 pb = bvh_prim_elem(3u * i + 1u);
                float t, u, v;
                bool hit;
#ifndef BVH_NO_SPHERES
                if ((pa.w & BVH_SPHERE_FLAG) != 0u) {
                    hit = intersect_sphere(o, d, uintBitsToFloat(pa.xyz), uintBitsToFloat(pb.x),
                                           tmin, tmax, t);
                    u = 0.0;
                    v = 0.0;
                } else
#endif
                {
                    vec3 v0 = uintBitsToFloat(pa.xyz);
                    vec3 v1 = uintBitsToFloat(pb.xyz);
                    vec3 v2 = uintBitsToFloat(bvh_prim_elem(3u * i + 2u).xyz);
                    hit = intersect_triangle(o, sh, v0, v1, v2, tmin, tmax, t, u, v);
#ifdef BVH_FACE_TEST
                    if (cull_back_faces && hit && dot(d, cross(v1 - v0, v2 - v0)) > 0.0 && !back_face_visible(pb.w))
                        hit = false;
#endif
                }
#ifdef BVH_ALPHA_TEST
                if (hit && !alpha_visible(pa.w, pb.w, u, v, t)) hit = false;
#endif
                if (hit) {
                    tmax = t;
                    best = int(i);
                    hu = u;
                    hv = v;
#ifdef BVH_INSTANCES
                    hrecord = record;
#endif
                    if (any_hit) {
                        return best;
                    }
                }
            }
            if (entered) {
                break;
            }
            if (cur == BVH_DONE) {
                BVH_POP();
            }
        }
        if (!entered && cur == BVH_DONE) {
            break;
        }
    }
    return best;
}

// Closest hit with tmin <= t <= tmax. On a miss returns false, h.t = tmax,
// h.prim = 0xffffffff. `cull_back_faces`: see BVH_FACE_TEST.
bool trace_closest_culling(vec3 o, vec3 d, float tmin, float tmax, bool cull_back_faces, out Hit h) {
    float t = tmax;
    float u, v;
    uint record;
    int slot = bvh_traverse(o, d, tmin, t, false, cull_back_faces, u, v, record);
    h.t = t;
    h.u = u;
    h.v = v;
    h.slot = uint(slot);
    h.instance_record = record;
    if (slot < 0) {
        h.prim = 0xffffffffu;
        h.is_sphere = false;
        h.material = 0u;
        return false;
    }
    uint id = bvh_prim_elem(3u * uint(slot)).w;
    h.prim = id & ~BVH_SPHERE_FLAG;
    h.is_sphere = (id & BVH_SPHERE_FLAG) != 0u;
    h.material = bvh_prim_elem(3u * uint(slot) + 1u).w;
    return true;
}

// Whether anything is hit with tmin <= t <= tmax (shadow rays; stops at the first hit).
bool trace_any_culling(vec3 o, vec3 d, float tmin, float tmax, bool cull_back_faces) {
    float t = tmax;
    float u, v;
    uint record;
    return bvh_traverse(o, d, tmin, t, true, cull_back_faces, u, v, record) >= 0;
}

// Every surface on both sides.
bool trace_closest(vec3 o, vec3 d, float tmin, float tmax, out Hit h) {
    return trace_closest_culling(o, d, tmin, tmax, false, h);
}
bool trace_any(vec3 o, vec3 d, float tmin, float tmax) {
    return trace_any_culling(o, d, tmin, tmax, false);
}

#endif
