#version 460
// Hash-grid build, pass 3 of 4: one invocation per light-vertex slot; a valid slot goes
// to its place in its bucket, grid_indices[grid_start[b] + rank] = slot, with (b, rank)
// from the count pass (no atomics here). The order inside a bucket is the count's atomics'
// arrival order, arbitrary; hash_grid_sort.comp makes it ascending.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64) in;

layout(std430, binding = 0) readonly buffer LvCountBuf { uint lv_count[]; };
layout(std430, binding = 1) readonly buffer GridStartBuf { uint grid_start[]; };
layout(std430, binding = 2) readonly buffer GridKeysBuf { uvec2 grid_keys[]; };
layout(std430, binding = 3) writeonly buffer GridIndicesBuf { uint grid_indices[]; };

#include "hash_grid.glsl"
HASH_GRID_BUILD_PUSH;

void main() {
    uint slot = hash_grid_group_index() * 64u + gl_LocalInvocationID.x;
    if (slot >= push.light_paths * push.slots) return;
    uint path = slot / push.slots;
    if (slot - path * push.slots >= lv_count[path]) return;
    uvec2 key = grid_keys[slot];
    grid_indices[grid_start[key.x] + key.y] = slot;
}
