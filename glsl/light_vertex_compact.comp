#version 460
// The light-subpaths pass, last step of each chunk (src/render/passes/light_subpaths.rs).
// The light kernel has written the chunk's vertices to scratch slots (light subpath
// first_path + q to slots [q S, q S + S)) and their counts to light_vertex_chunk_counts,
// which exclusive_scan.comp has turned into the chunk's prefix sums (entry `count`: the
// chunk's total). One invocation per light subpath q of the chunk copies its vertices
// into the light-vertex store behind those of every earlier light subpath and writes its
// offset, light_vertex_offsets[first_path + q]; the chunk's last invocation writes the
// next chunk's first offset. So the store holds exactly the vertices traced, in path
// order, whatever the chunking: the image does not depend on it.
//
// The store's capacity is estimated before the render (docs/design.md, "The light-vertex
// store"). Vertices past it are not written; the last chunk of an iteration records the
// iteration's total in light_vertex_status, and when it did not fit, the iteration's
// index: the camera kernel then leaves that iteration (and every later one of the batch)
// out of the film, and the renderer grows the store and renders them again.
#extension GL_GOOGLE_include_directive : require

#if !defined(DEVICE_ADDRESSES) || !defined(WORKGROUP_SIZE)
#error "DEVICE_ADDRESSES and WORKGROUP_SIZE must be defined (src/render/passes/light_subpaths.rs)"
#endif

layout(local_size_x = WORKGROUP_SIZE) in;

#include "addresses.glsl"
#if DEVICE_ADDRESSES
#define scratch_a FRAME_LIGHT_SCRATCH_A
#define scratch_b FRAME_LIGHT_SCRATCH_B
#define store_a FRAME_LIGHT_VERTICES_A
#define store_b FRAME_LIGHT_VERTICES_B
#define offsets FRAME_LIGHT_VERTEX_OFFSETS
#else
layout(std430) readonly buffer light_vertex_scratch_a { vec4 scratch_a[]; };
layout(std430) readonly buffer light_vertex_scratch_b { vec4 scratch_b[]; };
layout(std430) writeonly buffer light_vertices_a { vec4 store_a[]; };
layout(std430) writeonly buffer light_vertices_b { vec4 store_b[]; };
layout(std430) buffer light_vertex_offsets { uint offsets[]; };
#endif
layout(std430) readonly buffer light_vertex_chunk_counts { uint chunk_prefix[]; };
// Mirrored by StoreStatus in src/render/passes/light_subpaths.rs.
layout(std430) buffer light_vertex_status {
    uint lv_first_overflow;  // the earliest iteration whose vertices did not fit (~0u: none)
    uint lv_most_vertices;   // the most vertices an iteration stored (saturating)
};

// Mirrored by CompactPush in src/render/passes/light_subpaths.rs.
layout(push_constant) uniform CompactPush {
    uint first_path;   // the chunk's first light subpath
    uint count;        // light subpaths in the chunk
    uint light_paths;  // N_L
    uint capacity;     // vertices the store holds
    uint slots;        // scratch slots per light subpath (lv_slots())
    uint b_stride;     // vec4 per vertex in light_vertices_b (LV_B_STRIDE)
    uint iteration;
} push;

#include "common.glsl"

// a + b, or ~0u when it would wrap: a total past 2^32 - 1 is past any capacity anyway.
uint saturating_add(uint a, uint b) {
    uint s = a + b;
    return s < a ? 0xffffffffu : s;
}

void main() {
    uint q = invocation_index();
    if (q >= push.count) return;
    uint p = push.first_path + q;
    // The chunk's first offset: written by the previous chunk's dispatch.
    uint base = push.first_path == 0u ? 0u : offsets[push.first_path];
    uint first = saturating_add(base, chunk_prefix[q]);
    uint n = chunk_prefix[q + 1u] - chunk_prefix[q];
    if (q > 0u || p == 0u) offsets[p] = first;
    if (q + 1u == push.count) {
        uint end = saturating_add(base, chunk_prefix[push.count]);
        offsets[p + 1u] = end;
        if (p + 1u == push.light_paths) {
            atomicMax(lv_most_vertices, end);
            if (end > push.capacity) atomicMin(lv_first_overflow, push.iteration);
        }
    }
    for (uint k = 0u; k < n; ++k) {
        uint dst = first + k;
        if (dst >= push.capacity) break;
        uint src = q * push.slots + k;
        store_a[2u * dst] = scratch_a[2u * src];
        store_a[2u * dst + 1u] = scratch_a[2u * src + 1u];
        for (uint j = 0u; j < push.b_stride; ++j) store_b[push.b_stride * dst + j] = scratch_b[push.b_stride * src + j];
    }
}
