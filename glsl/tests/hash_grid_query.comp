#version 460
// Test kernel: for each query point, the set of valid light-vertex slots within `radius`
// found through the hash grid (hash_grid.glsl) and its grid_points, as the camera kernel
// gathers merges.
// Writes count[q] and up to `max_out` slots at out_slots[q * max_out ..], in visit order.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64) in;

layout(std430) readonly buffer grid_start { uint bucket_start[]; };
layout(std430) readonly buffer grid_points { uvec4 bucket_points[]; };
layout(std430) readonly buffer queries { vec4 query_points[]; };
layout(std430) buffer out_count { uint counts[]; };
layout(std430) buffer out_slots { uint slots[]; };
// Per query: number of distinct buckets visited and number of candidates tested.
layout(std430) buffer out_stats { uvec2 stats[]; };

layout(push_constant) uniform Push {
    vec3 origin;
    float radius;
    uint num_buckets;
    uint num_queries;
    uint max_out;
} push;

#include "hash_grid.glsl"

void main() {
    uint qi = gl_GlobalInvocationID.x;
    if (qi >= push.num_queries) return;
    vec3 q = query_points[qi].xyz;
    float r2 = push.radius * push.radius;
    uint buckets[8];
    uint nb = hash_grid_query_cells(q, push.origin, push.radius, push.num_buckets, buckets);
    uint found = 0u;
    uint tested = 0u;
    for (uint i = 0u; i < nb; ++i) {
        uint b = buckets[i];
        for (uint j = bucket_start[b]; j < bucket_start[b + 1u]; ++j) {
            uvec4 e = bucket_points[j];
            vec3 d = uintBitsToFloat(e.xyz) - q;
            tested += 1u;
            if (dot(d, d) > r2) continue;
            uint slot = e.w;
            if (found < push.max_out) slots[qi * push.max_out + found] = slot;
            found += 1u;
        }
    }
    counts[qi] = found;
    stats[qi] = uvec2(nb, tested);
}
