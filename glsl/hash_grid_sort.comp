#version 460
// Hash-grid build, pass 4 of 4: sorts each bucket's slots ascending, so the build (and
// every sum over a bucket) is deterministic whatever order the count pass's atomics
// took. One invocation per bucket; a bucket holds about (light vertices / buckets)
// entries, a few. Up to 16 entries: Batcher's odd-even merge sorting network in
// registers (63 compare-exchanges, no divergence between invocations: on lavapipe ~35%
// faster than insertion sort at SmallVCM's table size); up to SMALL: insertion sort;
// above: heapsort, so a pathological bucket (a radius so large that thousands of
// vertices share a cell) costs O(n log n) in its invocation, not O(n^2).
// Then the bucket's entries are written out as grid_points[i] = (position bits, slot):
// the merge query reads one contiguous uvec4 per candidate from there instead of
// grid_indices[i] and then the scattered lv_a[2 slot] (on lavapipe bpm +6-10%, vcm
// +7-9% samples per CPU-second: docs/performance.md, "Performance work"). The position is
// stored as bits (uvec4), so no float operation can touch it (the slot in a float
// would be a denormal).
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require

layout(local_size_x = 64) in;

layout(std430, binding = 0) readonly buffer GridStartBuf { uint grid_start[]; };
layout(std430, binding = 1) buffer GridIndicesBuf { uint grid_indices[]; };
layout(std430, binding = 2) readonly buffer LvABuf { vec4 lv_a[]; };
layout(std430, binding = 3) writeonly buffer GridPointsBuf { uvec4 grid_points[]; };

#include "hash_grid.glsl"
HASH_GRID_BUILD_PUSH;

const uint SMALL = 32u;

// Restores the max-heap property below `root` in grid_indices[base .. base + n).
void sift_down(uint base, uint root, uint n) {
    uint v = grid_indices[base + root];
    for (;;) {
        uint child = 2u * root + 1u;
        if (child >= n) break;
        uint c = grid_indices[base + child];
        if (child + 1u < n) {
            uint c2 = grid_indices[base + child + 1u];
            if (c2 > c) {
                child += 1u;
                c = c2;
            }
        }
        if (c <= v) break;
        grid_indices[base + root] = c;
        root = child;
    }
    grid_indices[base + root] = v;
}

// Sorts grid_indices[begin .. begin + n) ascending.
void sort_bucket(uint begin, uint n) {
    if (n <= 1u) return;
    if (n <= 16u) {
        // Padding with ~0u sorts to the end and is not written back.
        uint v[16];
        [[unroll]] for (uint i = 0u; i < 16u; ++i) v[i] = i < n ? grid_indices[begin + i] : 0xffffffffu;
#define CE(a, b) { uint lo = min(v[a], v[b]); v[b] = max(v[a], v[b]); v[a] = lo; }
        CE(0, 1) CE(2, 3) CE(0, 2) CE(1, 3) CE(1, 2) CE(4, 5) CE(6, 7) CE(4, 6)
        CE(5, 7) CE(5, 6) CE(0, 4) CE(2, 6) CE(2, 4) CE(1, 5) CE(3, 7) CE(3, 5)
        CE(1, 2) CE(3, 4) CE(5, 6) CE(8, 9) CE(10, 11) CE(8, 10) CE(9, 11) CE(9, 10)
        CE(12, 13) CE(14, 15) CE(12, 14) CE(13, 15) CE(13, 14) CE(8, 12) CE(10, 14) CE(10, 12)
        CE(9, 13) CE(11, 15) CE(11, 13) CE(9, 10) CE(11, 12) CE(13, 14) CE(0, 8) CE(4, 12)
        CE(4, 8) CE(2, 10) CE(6, 14) CE(6, 10) CE(2, 4) CE(6, 8) CE(10, 12) CE(1, 9)
        CE(5, 13) CE(5, 9) CE(3, 11) CE(7, 15) CE(7, 11) CE(3, 5) CE(7, 9) CE(11, 13)
        CE(1, 2) CE(3, 4) CE(5, 6) CE(7, 8) CE(9, 10) CE(11, 12) CE(13, 14)
#undef CE
        [[unroll]] for (uint i = 0u; i < 16u; ++i) if (i < n) grid_indices[begin + i] = v[i];
        return;
    }
    if (n <= SMALL) {
        uint end = begin + n;
        for (uint i = begin + 1u; i < end; ++i) {
            uint v = grid_indices[i];
            uint j = i;
            while (j > begin && grid_indices[j - 1u] > v) {
                grid_indices[j] = grid_indices[j - 1u];
                j -= 1u;
            }
            if (j != i) grid_indices[j] = v;
        }
        return;
    }
    for (uint i = n / 2u; i > 0u; --i) sift_down(begin, i - 1u, n);
    for (uint m = n - 1u; m > 0u; --m) {
        uint top = grid_indices[begin];
        grid_indices[begin] = grid_indices[begin + m];
        grid_indices[begin + m] = top;
        sift_down(begin, 0u, m);
    }
}

void main() {
    uint b = hash_grid_group_index() * 64u + gl_LocalInvocationID.x;
    if (b >= push.num_buckets) return;
    uint begin = grid_start[b];
    uint end = grid_start[b + 1u];
    sort_bucket(begin, end - begin);
    for (uint i = begin; i < end; ++i) {
        uint slot = grid_indices[i];
        grid_points[i] = uvec4(floatBitsToUint(lv_a[2u * slot].xyz), slot);
    }
}
