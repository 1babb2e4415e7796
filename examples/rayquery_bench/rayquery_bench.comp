#version 460
// Closest hit with the driver's VK_KHR_ray_query (examples/rayquery_bench/): the same ray
// layout as glsl/tests/bvh_bench.comp; writes (t, primitive index) per ray, (-1, 0xffffffff)
// for a miss.
#extension GL_EXT_ray_query : require
#ifndef LOCAL_SIZE
#define LOCAL_SIZE 64
#endif
layout(local_size_x = LOCAL_SIZE) in;

struct BenchRay {
    vec4 o;  // w unused
    vec4 d;
};
layout(binding = 0) uniform accelerationStructureEXT tlas;
layout(std430, binding = 1) readonly buffer Rays { BenchRay rays[]; };
layout(std430, binding = 2) writeonly buffer Results { uvec2 results[]; };

layout(push_constant) uniform Push { uint count; } pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) {
        return;
    }
    BenchRay r = rays[i];
    rayQueryEXT q;
    // Opaque geometry: every candidate is committed during the traversal, so the loop
    // runs once and the committed hit is the closest one in [0, 1e30].
    rayQueryInitializeEXT(q, tlas, gl_RayFlagsOpaqueEXT, 0xff, r.o.xyz, 0.0, r.d.xyz, 1e30);
    while (rayQueryProceedEXT(q)) {
    }
    uvec2 res = uvec2(floatBitsToUint(-1.0), 0xffffffffu);
    if (rayQueryGetIntersectionTypeEXT(q, true) == gl_RayQueryCommittedIntersectionTriangleEXT) {
        res = uvec2(floatBitsToUint(rayQueryGetIntersectionTEXT(q, true)),
                    uint(rayQueryGetIntersectionPrimitiveIndexEXT(q, true)));
    }
    results[i] = res;
}
