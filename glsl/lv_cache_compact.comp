#version 460
// Light-vertex cache (src/render/passes/light_vertex_cache.rs), after the prefix scan of
// the per-path vertex counts: one invocation per light subpath q writes the store slots
// of its lv_count[q] vertices to lv_dense[lv_prefix[q] ..], in order. camera_subpath.comp
// then finds the i-th of all stored vertices with one load, lv_dense[i], instead of a
// binary search over N_L + 1 prefix sums (faster on lavapipe: docs/performance.md,
// "Third round"). The order, and hence every draw, is the same as the search's:
// deterministic.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = WORKGROUP_SIZE) in;

layout(std430) readonly buffer light_vertex_counts { uint lv_count[]; };
layout(std430) readonly buffer light_vertex_prefix { uint lv_prefix[]; };
#include "addresses.glsl"
#if DEVICE_ADDRESSES
#define lv_dense FRAME_LIGHT_VERTEX_DENSE
#else
layout(std430) writeonly buffer light_vertex_dense { uint lv_dense[]; };
#endif

// Mirrored by CompactPush in src/render/passes/light_vertex_cache.rs.
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
