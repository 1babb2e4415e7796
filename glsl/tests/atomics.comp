#version 460
#extension GL_EXT_shader_atomic_int64 : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
// Test kernel: histogram of keys[i] % BINS with 32-bit atomics, and a 64-bit atomic sum.
layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer Keys { uint keys[]; };
layout(std430, binding = 1) buffer Hist { uint hist[]; };
layout(std430, binding = 2) buffer Sum { uint64_t sum; };
layout(push_constant) uniform Push { uint n; uint bins; } pc;
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.n) return;
    atomicAdd(hist[keys[i] % pc.bins], 1u);
    atomicAdd(sum, uint64_t(keys[i]) << 20);
}
