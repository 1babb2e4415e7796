#version 460
// Hash-grid build, pass 3 of 4: one invocation per light path; each of its stored
// vertices goes to its place in its bucket, bucket_points[bucket_start[b] + rank] =
// (position bits, slot), with (b, rank) from the count pass (no atomics here). The
// position is read here, where the path's slots are read in order, rather than gathered
// by the sort pass. The order inside a bucket is the count's atomics' arrival order,
// arbitrary; hash_grid_sort.comp makes it ascending by slot.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = WORKGROUP_SIZE) in;

layout(std430) readonly buffer grid_start { uint bucket_start[]; };

#include "common.glsl"
#include "addresses.glsl"
#include "hash_grid.glsl"
HASH_GRID_BUILD_BUFFERS;
HASH_GRID_BUILD_PUSH;

void main() {
    uint path = invocation_index();
    if (path >= push.light_paths) return;
    uint n = min(lv_count[path], push.slots);
    for (uint slot = path * push.slots; slot < path * push.slots + n; ++slot) {
        uvec2 key = vertex_keys[slot];
        bucket_points[bucket_start[key.x] + key.y] = uvec4(floatBitsToUint(lv_a[2u * slot].xyz), slot);
    }
}
