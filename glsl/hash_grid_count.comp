#version 460
// Hash-grid build, pass 1 of 4 (see hash_grid.glsl, src/render/passes/hash_grid.rs): one
// invocation per light path p, over its lv_count[p] stored vertices (slots p * slots + k).
// Each counts itself into its bucket, bucket_start[b] += 1 (grid_start is zeroed before and
// scanned after), and keeps its bucket and its arrival rank in the bucket,
// vertex_keys[slot] = (b, rank), for the scatter. (One invocation per path rather than per
// slot: most slots are empty; ppm's grid build on lavapipe, docs/performance.md.)
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = WORKGROUP_SIZE) in;

layout(std430) buffer grid_start { uint bucket_start[]; };

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
        uint b = hash_grid_point_bucket(lv_a[2u * slot].xyz, push.origin, push.radius, push.num_buckets);
        uint rank = atomicAdd(bucket_start[b], 1u);
        vertex_keys[slot] = uvec2(b, rank);
    }
}
