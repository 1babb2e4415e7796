#version 460
// Test kernel: for each 64-bit value (lo, hi), the float that a 64-bit conversion gives
// and the float that u64_words_to_float (common.glsl) gives, as bits.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
layout(local_size_x = 64) in;
layout(std430) readonly buffer test_input { uvec2 words[]; };
layout(std430) writeonly buffer test_output { uvec2 floats[]; };
layout(push_constant) uniform Push { uint n; } pc;
#include "common.glsl"
void main() {
    uint i = invocation_index();
    if (i >= pc.n) return;
    uvec2 w = words[i];
    uint64_t v = packUint2x32(w);
    floats[i] = uvec2(floatBitsToUint(float(v)), floatBitsToUint(u64_words_to_float(w.x, w.y)));
}
