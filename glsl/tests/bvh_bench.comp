#version 460
// Traversal benchmark kernel (src/bench/traverse.rs): one ray per invocation, writes the hit
// primitive (closest hit; 0xffffffff = miss) or 1/0 (any hit, MODE 1).
#ifndef LOCAL_SIZE
#define LOCAL_SIZE 64
#endif
layout(local_size_x = LOCAL_SIZE) in;

#define BVH_DECLARES_BUFFERS

struct BenchRay {
    vec4 o;  // w unused
    vec4 d;
};
layout(std430) readonly buffer bench_rays { BenchRay rays[]; };
layout(std430) writeonly buffer bench_results { uint results[]; };

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
