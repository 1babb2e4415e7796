#version 460
// Traversal benchmark kernel (src/bvh/bench.rs): one ray per invocation, writes the hit
// primitive (closest hit; 0xffffffff = miss) or 1/0 (any hit, MODE 1).
#ifndef LOCAL_SIZE
#define LOCAL_SIZE 64
#endif
layout(local_size_x = LOCAL_SIZE) in;

#define BVH_NODES_BINDING 0
#define BVH_PRIMS_BINDING 1

struct BenchRay {
    vec4 o;  // w unused
    vec4 d;
};
layout(std430, binding = 2) readonly buffer Rays { BenchRay rays[]; };
layout(std430, binding = 3) writeonly buffer Results { uint results[]; };

layout(push_constant) uniform Push { uint count; } pc;

#include "bvh.glsl"

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) {
        return;
    }
    BenchRay r = rays[i];
#if MODE == 1
    results[i] = trace_any(r.o.xyz, r.d.xyz, 0.0, 1e30) ? 1u : 0u;
#else
    Hit h;
    trace_closest(r.o.xyz, r.d.xyz, 0.0, 1e30, h);
    results[i] = h.prim;
#endif
}
