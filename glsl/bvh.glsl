// BVH traversal: closest hit and any hit over the BVH built by src/bvh (binned SAH, BVH2
// nodes holding both children's boxes as in Aila & Laine, "Understanding the Efficiency
// of Ray Traversal on GPUs", HPG 2009). Mirrored on the CPU by src/bvh/traverse.rs.
//
// The including kernel declares the two buffers, as vec4 arrays with these names, before
// `#include "bvh.glsl"` (bindings and set are the kernel's choice):
//
//   layout(std430, binding = 0) readonly buffer BvhNodes { vec4 bvh_nodes[]; };
//   layout(std430, binding = 1) readonly buffer BvhPrims { vec4 bvh_prims[]; };
//
// and compiles with the defines GpuBvh::glsl_defines() returns (BVH_NODE_LAYOUT; the
// default below matches NodeLayout::DEFAULT).
//
// Node i = bvh_nodes[4i .. 4i+3] (64 bytes). Child references are uints stored bit-cast:
// bit 31 clear = internal node index; bit 31 set = leaf (first prim << 3 | count).
//   BVH_NODE_LAYOUT 0: (c0.min, ref0) (c0.max, ref1) (c1.min, 0) (c1.max, 0)
//   BVH_NODE_LAYOUT 1: (c0.lo.x, c0.hi.x, c0.lo.y, c0.hi.y) (c1.lo.x, c1.hi.x, c1.lo.y,
//                      c1.hi.y) (c0.lo.z, c0.hi.z, c1.lo.z, c1.hi.z) (ref0, ref1, 0, 0)
// Prim i = bvh_prims[3i .. 3i+2] (48 bytes), in leaf order:
//   triangle: (v0, id) (v1, material) (v2, 0)
//   sphere:   (center, id | BVH_SPHERE_FLAG) (radius, 0, 0, material) (0)
// id = original index in the scene's triangle list, or sphere list for spheres.
//
// Stack: BVH_STACK_SIZE entries; the traversal pushes at most one per internal level and
// the builder guarantees at most MAX_DEPTH = 32 levels (src/bvh/layout.rs).
// Ray/box test: Ize, "Robust BVH Ray Traversal", JCGT 2013 (exit distance widened).
#ifndef VKVCM_BVH_GLSL
#define VKVCM_BVH_GLSL

#include "intersect.glsl"

#ifndef BVH_NODE_LAYOUT
#define BVH_NODE_LAYOUT 0
#endif
#define BVH_STACK_SIZE 32
#define BVH_LEAF_FLAG 0x80000000u
#define BVH_SPHERE_FLAG 0x80000000u
#define BVH_ROBUST_SCALE 1.000002

struct Hit {
    float t;          // distance in units of |d|
    uint prim;        // original triangle index, or sphere index when is_sphere
    float u;          // barycentric weight of v1 (triangles; 0 for spheres)
    float v;          // barycentric weight of v2
    bool is_sphere;
    uint material;
};

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

void bvh_load_node(uint n, out vec3 lo0, out vec3 hi0, out vec3 lo1, out vec3 hi1,
                   out uint c0, out uint c1) {
    vec4 a = bvh_nodes[4u * n];
    vec4 b = bvh_nodes[4u * n + 1u];
    vec4 c = bvh_nodes[4u * n + 2u];
    vec4 d = bvh_nodes[4u * n + 3u];
#if BVH_NODE_LAYOUT == 0
    lo0 = a.xyz;
    hi0 = b.xyz;
    lo1 = c.xyz;
    hi1 = d.xyz;
    c0 = floatBitsToUint(a.w);
    c1 = floatBitsToUint(b.w);
#else
    lo0 = vec3(a.x, a.z, c.x);
    hi0 = vec3(a.y, a.w, c.y);
    lo1 = vec3(b.x, b.z, c.z);
    hi1 = vec3(b.y, b.w, c.w);
    c0 = floatBitsToUint(d.x);
    c1 = floatBitsToUint(d.y);
#endif
}

// Shared traversal. Returns the primitive slot of the closest hit (or of the first hit
// when `any_hit`), -1 for none; tmax becomes the hit distance.
int bvh_traverse(vec3 o, vec3 d, float tmin, inout float tmax, const bool any_hit,
                 out float hu, out float hv) {
    vec3 inv_d = bvh_safe_inv(d);
    RayShear sh = ray_shear(d);
    uint stack[BVH_STACK_SIZE];
    uint sp = 0u;
    uint cur = 0u;
    int best = -1;
    hu = 0.0;
    hv = 0.0;
    while (true) {
        if ((cur & BVH_LEAF_FLAG) == 0u) {
            vec3 lo0, hi0, lo1, hi1;
            uint c0, c1;
            bvh_load_node(cur, lo0, hi0, lo1, hi1, c0, c1);
            float tn0, tn1;
            bool h0 = bvh_ray_box(lo0, hi0, o, inv_d, tmin, tmax, tn0);
            bool h1 = bvh_ray_box(lo1, hi1, o, inv_d, tmin, tmax, tn1);
            if (h0 && h1) {
                bool swap = tn1 < tn0;
                stack[sp] = swap ? c0 : c1;
                sp++;
                cur = swap ? c1 : c0;
                continue;
            }
            if (h0) {
                cur = c0;
                continue;
            }
            if (h1) {
                cur = c1;
                continue;
            }
        } else {
            uint first = (cur & ~BVH_LEAF_FLAG) >> 3;
            uint end = first + (cur & 7u);
            for (uint i = first; i < end; i++) {
                vec4 pa = bvh_prims[3u * i];
                vec4 pb = bvh_prims[3u * i + 1u];
                float t, u, v;
                bool hit;
                if ((floatBitsToUint(pa.w) & BVH_SPHERE_FLAG) != 0u) {
                    hit = intersect_sphere(o, d, pa.xyz, pb.x, tmin, tmax, t);
                    u = 0.0;
                    v = 0.0;
                } else {
                    vec4 pc = bvh_prims[3u * i + 2u];
                    hit = intersect_triangle(o, sh, pa.xyz, pb.xyz, pc.xyz, tmin, tmax, t,
                                             u, v);
                }
                if (hit) {
                    tmax = t;
                    best = int(i);
                    hu = u;
                    hv = v;
                    if (any_hit) {
                        return best;
                    }
                }
            }
        }
        if (sp == 0u) {
            break;
        }
        sp--;
        cur = stack[sp];
    }
    return best;
}

// Closest hit with tmin <= t <= tmax. On a miss returns false, h.t = tmax,
// h.prim = 0xffffffff.
bool trace_closest(vec3 o, vec3 d, float tmin, float tmax, out Hit h) {
    float t = tmax;
    float u, v;
    int slot = bvh_traverse(o, d, tmin, t, false, u, v);
    h.t = t;
    h.u = u;
    h.v = v;
    if (slot < 0) {
        h.prim = 0xffffffffu;
        h.is_sphere = false;
        h.material = 0u;
        return false;
    }
    uint id = floatBitsToUint(bvh_prims[3u * uint(slot)].w);
    h.prim = id & ~BVH_SPHERE_FLAG;
    h.is_sphere = (id & BVH_SPHERE_FLAG) != 0u;
    h.material = floatBitsToUint(bvh_prims[3u * uint(slot) + 1u].w);
    return true;
}

// Whether anything is hit with tmin <= t <= tmax (shadow rays; stops at the first hit).
bool trace_any(vec3 o, vec3 d, float tmin, float tmax) {
    float t = tmax;
    float u, v;
    return bvh_traverse(o, d, tmin, t, true, u, v) >= 0;
}

#endif
