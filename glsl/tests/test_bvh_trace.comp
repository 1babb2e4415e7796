#version 460
// Test kernel for tests/bvh_gpu.rs: one ray per invocation, closest hit and any hit.
// BVH_VEC4 selects the compatible buffer declaration (vec4 arrays declared here) instead
// of letting bvh.glsl declare them.
layout(local_size_x = 64) in;

#ifdef BVH_VEC4
layout(std430) readonly buffer bvh_nodes { vec4 bvh_node_data[]; };
layout(std430) readonly buffer bvh_prims { vec4 bvh_prim_data[]; };
#else
#define BVH_DECLARES_BUFFERS
#endif

struct TestRay {
    vec4 o;  // w = tmin
    vec4 d;  // w = tmax
};
layout(std430) readonly buffer test_rays { TestRay rays[]; };

struct TestHit {
    float t;
    uint prim;
    float u;
    float v;
    uint flags;  // bit 0: closest hit found, bit 1: sphere, bit 2: any hit found
    uint material;
    uint instance_record;  // BVH_NO_INSTANCE for world-space primitives
    uint pad1;
};
layout(std430) writeonly buffer test_hits { TestHit hits[]; };

layout(push_constant) uniform Push { uint count; } pc;

#include "bvh.glsl"

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) {
        return;
    }
    TestRay r = rays[i];
    Hit h;
    bool found = trace_closest(r.o.xyz, r.d.xyz, r.o.w, r.d.w, h);
    bool any_found = trace_any(r.o.xyz, r.d.xyz, r.o.w, r.d.w);
    TestHit o;
    o.t = h.t;
    o.prim = h.prim;
    o.u = h.u;
    o.v = h.v;
    o.flags = (found ? 1u : 0u) | (h.is_sphere ? 2u : 0u) | (any_found ? 4u : 0u);
    o.material = h.material;
    o.instance_record = h.instance_record;
    o.pad1 = 0u;
    hits[i] = o;
}
