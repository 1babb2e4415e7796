#version 460
// Test kernel: results[i] = texels[i].x, reading a uniform texel buffer of uvec4 texels.
#extension GL_EXT_samplerless_texture_functions : require
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 64) in;
layout(std430) writeonly buffer results { uint r[]; };
uniform utextureBuffer texels;
layout(push_constant) uniform Push { uint n; } pc;
#include "common.glsl"
void main() {
    uint i = invocation_index();
    if (i < pc.n) r[i] = texelFetch(texels, int(i)).x;
}
