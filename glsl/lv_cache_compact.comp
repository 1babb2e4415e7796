#version 460
// Light-vertex cache (src/render/bidir.rs, Connect::Cache), after the prefix scan of the
// per-path vertex counts: one invocation per light subpath q writes the store slots of
// its lv_count[q] vertices to lv_dense[lv_prefix[q] ..], in order. camera_subpath.comp
// then finds the i-th of all stored vertices with one load, lv_dense[i], instead of a
// binary search over N_L + 1 prefix sums (16 dependent loads per draw at 256x256; bpt
// 1.065x samples per CPU-second on lavapipe: docs/performance.md, "Third round").
// The order, and hence every draw, is the same as the search's: deterministic.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64) in;

layout(std430, binding = 0) readonly buffer LvCountBuf { uint lv_count[]; };
layout(std430, binding = 1) readonly buffer LvPrefixBuf { uint lv_prefix[]; };
layout(std430, binding = 2) writeonly buffer LvDenseBuf { uint lv_dense[]; };

// Mirrored by CompactPush in src/render/bidir.rs.
layout(push_constant) uniform CompactPush {
    uint light_paths;
    uint slots;  // light-vertex store slots per path (lv_slots())
} push;

#include "common.glsl"

void main() {
    uint q = invocation_index();
    if (q >= push.light_paths) return;
    uint n = lv_count[q];
    uint base = lv_prefix[q];
    for (uint k = 0u; k < n; ++k) lv_dense[base + k] = q * push.slots + k;
}
