#version 460
// Hash-grid build, pass 3 of 4: one invocation per light path; each of its stored
// vertices goes to its place in its bucket, grid_points[grid_start[b] + rank] =
// (position bits, slot), with (b, rank) from the count pass (no atomics here). The
// position is read here, where the path's slots are read in order, rather than gathered
// by the sort pass. The order inside a bucket is the count's atomics' arrival order,
// arbitrary; hash_grid_sort.comp makes it ascending by slot.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64) in;

layout(std430, binding = 0) readonly buffer LvABuf { vec4 lv_a[]; };
layout(std430, binding = 1) readonly buffer LvCountBuf { uint lv_count[]; };
layout(std430, binding = 2) readonly buffer GridStartBuf { uint grid_start[]; };
layout(std430, binding = 3) readonly buffer GridKeysBuf { uvec2 grid_keys[]; };
layout(std430, binding = 4) writeonly buffer GridPointsBuf { uvec4 grid_points[]; };

#include "hash_grid.glsl"
HASH_GRID_BUILD_PUSH;

void main() {
    uint path = hash_grid_group_index() * 64u + gl_LocalInvocationID.x;
    if (path >= push.light_paths) return;
    uint n = min(lv_count[path], push.slots);
    for (uint slot = path * push.slots; slot < path * push.slots + n; ++slot) {
        uvec2 key = grid_keys[slot];
        grid_points[grid_start[key.x] + key.y] = uvec4(floatBitsToUint(lv_a[2u * slot].xyz), slot);
    }
}
