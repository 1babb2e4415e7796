#version 460
// Hash-grid build, pass 3 of 4: one invocation per light path; each of its stored
// vertices i goes to its place in its bucket, bucket_points[bucket_start[b] + rank] =
// (position bits, i), with (b, rank) from the count pass (no atomics here). The
// position is read here, where the path's vertices are read in order, rather than
// gathered by the sort pass. The order inside a bucket is the count's atomics' arrival order,
// arbitrary; hash_grid_sort.comp makes it ascending by slot.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = WORKGROUP_SIZE) in;

layout(std430) readonly buffer grid_start { uint bucket_start[]; };

#include "common.glsl"
#include "addresses.glsl"
#include "hash_grid.glsl"
HASH_GRID_BUILD_BUFFERS
HASH_GRID_BUILD_PUSH;

void main() {
    uint path = invocation_index();
    if (path >= push.light_paths) return;
    uint end = min(lv_offsets[path + 1u], push.capacity);
    for (uint i = min(lv_offsets[path], end); i < end; ++i) {
        uvec2 key = vertex_keys[i];
        bucket_points[bucket_start[key.x] + key.y] = uvec4(floatBitsToUint(lv_a[2u * i].xyz), i);
    }
}
