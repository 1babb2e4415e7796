#version 460
// Test kernel: point `index` of sequence `key`, dimension `dim`, as 24-bit fixed point,
// for each request (key, dim, index, kind): kind 0 sobol2 (x, y) and sobol1 (z), kind 1
// sobol3 (x, y, z) of common.glsl.
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 64) in;
layout(std430) readonly buffer test_input { uvec4 req[]; };
layout(std430) writeonly buffer test_output { uvec4 pts[]; };
layout(push_constant) uniform Push { uint n; } pc;
#include "common.glsl"
void main() {
    uint i = invocation_index();
    if (i >= pc.n) return;
    uvec4 r = req[i];
    vec3 p = r.w == 1u ? sobol3(r.x, r.z, r.y) : vec3(sobol2(r.x, r.z, r.y), sobol1(r.x, r.z, r.y));
    pts[i] = uvec4(uvec3(p * 16777216.0), 0u);
}
