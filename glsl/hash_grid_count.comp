#version 460
// Hash-grid build, pass 1 of 4 (see hash_grid.glsl, src/render/hash_grid.rs): one
// invocation per light-vertex slot; slot i of path p = i / slots is valid when
// i % slots < lv_count[p]. A valid slot counts itself into its bucket,
// grid_start[b] += 1 (grid_start is zeroed before and scanned after), and keeps its
// bucket and its arrival rank in the bucket, grid_keys[i] = (b, rank), for the scatter.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64) in;

layout(std430, binding = 0) readonly buffer LvABuf { vec4 lv_a[]; };
layout(std430, binding = 1) readonly buffer LvCountBuf { uint lv_count[]; };
layout(std430, binding = 2) buffer GridStartBuf { uint grid_start[]; };
layout(std430, binding = 3) writeonly buffer GridKeysBuf { uvec2 grid_keys[]; };

#include "hash_grid.glsl"
HASH_GRID_BUILD_PUSH;

void main() {
    uint slot = hash_grid_group_index() * 64u + gl_LocalInvocationID.x;
    if (slot >= push.light_paths * push.slots) return;
    uint path = slot / push.slots;
    if (slot - path * push.slots >= lv_count[path]) return;
    uint b = hash_grid_point_bucket(lv_a[2u * slot].xyz, push.origin, push.radius, push.num_buckets);
    uint rank = atomicAdd(grid_start[b], 1u);
    grid_keys[slot] = uvec2(b, rank);
}
