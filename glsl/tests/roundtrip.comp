#version 460
// Test kernel: out[i] = a[i] * SCALE + b[i] (SCALE is a per-variant #define).
layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer A { float a[]; };
layout(std430, binding = 1) readonly buffer B { float b[]; };
layout(std430, binding = 2) writeonly buffer O { float o[]; };
layout(push_constant) uniform Push { uint n; } pc;
#include "tests/scale_add.glsl"
#include "common.glsl"
void main() {
    uint i = invocation_index();
    if (i < pc.n) o[i] = scale_add(a[i], b[i]);
}
