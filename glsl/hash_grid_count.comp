#version 460
// Hash-grid build, pass 1 of 4 (see hash_grid.glsl, src/render/passes/hash_grid.rs): one
// invocation per light path p, over its stored vertices i = lv_offsets[p] ..
// lv_offsets[p + 1] - 1 (below the store's capacity). Each counts itself into its bucket,
// bucket_start[b] += 1 (grid_start is zeroed before and scanned after), and keeps its
// bucket and its arrival rank in the bucket, vertex_keys[i] = (b, rank), for the scatter.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = WORKGROUP_SIZE) in;

layout(std430) buffer grid_start { uint bucket_start[]; };

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
        uint b = hash_grid_point_bucket(lv_a[2u * i].xyz, push.origin, push.radius, push.num_buckets);
        uint rank = atomicAdd(bucket_start[b], 1u);
        vertex_keys[i] = uvec2(b, rank);
    }
}
