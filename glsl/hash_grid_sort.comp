#version 460
// Hash-grid build, pass 4 of 4: sorts each bucket's entries bucket_points[i] = (position
// bits, slot) ascending by slot, so the build (and every sum over a bucket) is
// deterministic whatever order the count pass's atomics took. One invocation per bucket;
// a bucket holds about (light vertices / buckets) entries, a few. Up to 4 entries: a
// 5-comparator sorting network; up to 16: Batcher's odd-even merge sorting network
// (63 compare-exchanges); both in registers, without divergence between invocations
// that take the same one (faster than insertion sort on lavapipe, and most buckets need
// only the 4-network: docs/hash-grid.md); up to SMALL:
// insertion sort; above: heapsort, so a pathological bucket (a radius so large that
// thousands of vertices share a cell) costs O(n log n) in its invocation, not O(n^2).
// The merge query reads one contiguous uvec4 per candidate from grid_points (its radius
// test loads no index and nothing from the light-vertex store; a merge costs what its
// candidates load: docs/hash-grid.md). The
// position is stored as bits (uvec4), so no float operation can touch it (the slot in a
// float would be a denormal). Slots are unique, so comparing them orders entries fully.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require

layout(local_size_x = WORKGROUP_SIZE) in;

layout(std430) readonly buffer grid_start { uint bucket_start[]; };

#include "common.glsl"
#include "addresses.glsl"
#include "hash_grid.glsl"
HASH_GRID_BUILD_BUFFERS
HASH_GRID_BUILD_PUSH;

const uint SMALL = 32u;
// Padding that sorts after every entry and is not written back.
const uvec4 PAD = uvec4(0u, 0u, 0u, 0xffffffffu);

// Restores the max-heap property (by slot) below `root` in bucket_points[base .. base + n).
void sift_down(uint base, uint root, uint n) {
    uvec4 v = bucket_points[base + root];
    for (;;) {
        uint child = 2u * root + 1u;
        if (child >= n) break;
        uvec4 c = bucket_points[base + child];
        if (child + 1u < n) {
            uvec4 c2 = bucket_points[base + child + 1u];
            if (c2.w > c.w) {
                child += 1u;
                c = c2;
            }
        }
        if (c.w <= v.w) break;
        bucket_points[base + root] = c;
        root = child;
    }
    bucket_points[base + root] = v;
}

// Compare-exchange of v[a] and v[b] by slot.
#define CE(a, b) { bool sw = v[a].w > v[b].w; uvec4 lo = sw ? v[b] : v[a]; v[b] = sw ? v[a] : v[b]; v[a] = lo; }

// Sorts bucket_points[begin .. begin + n) ascending by slot.
void sort_bucket(uint begin, uint n) {
    if (n <= 1u) return;
    if (n <= 4u) {
        uvec4 v[4];
        [[unroll]] for (uint i = 0u; i < 4u; ++i) v[i] = i < n ? bucket_points[begin + i] : PAD;
        CE(0, 1) CE(2, 3) CE(0, 2) CE(1, 3) CE(1, 2)
        [[unroll]] for (uint i = 0u; i < 4u; ++i) if (i < n) bucket_points[begin + i] = v[i];
        return;
    }
    if (n <= 16u) {
        uvec4 v[16];
        [[unroll]] for (uint i = 0u; i < 16u; ++i) v[i] = i < n ? bucket_points[begin + i] : PAD;
        CE(0, 1) CE(2, 3) CE(0, 2) CE(1, 3) CE(1, 2) CE(4, 5) CE(6, 7) CE(4, 6)
        CE(5, 7) CE(5, 6) CE(0, 4) CE(2, 6) CE(2, 4) CE(1, 5) CE(3, 7) CE(3, 5)
        CE(1, 2) CE(3, 4) CE(5, 6) CE(8, 9) CE(10, 11) CE(8, 10) CE(9, 11) CE(9, 10)
        CE(12, 13) CE(14, 15) CE(12, 14) CE(13, 15) CE(13, 14) CE(8, 12) CE(10, 14) CE(10, 12)
        CE(9, 13) CE(11, 15) CE(11, 13) CE(9, 10) CE(11, 12) CE(13, 14) CE(0, 8) CE(4, 12)
        CE(4, 8) CE(2, 10) CE(6, 14) CE(6, 10) CE(2, 4) CE(6, 8) CE(10, 12) CE(1, 9)
        CE(5, 13) CE(5, 9) CE(3, 11) CE(7, 15) CE(7, 11) CE(3, 5) CE(7, 9) CE(11, 13)
        CE(1, 2) CE(3, 4) CE(5, 6) CE(7, 8) CE(9, 10) CE(11, 12) CE(13, 14)
        [[unroll]] for (uint i = 0u; i < 16u; ++i) if (i < n) bucket_points[begin + i] = v[i];
        return;
    }
    if (n <= SMALL) {
        uint end = begin + n;
        for (uint i = begin + 1u; i < end; ++i) {
            uvec4 v = bucket_points[i];
            uint j = i;
            while (j > begin && bucket_points[j - 1u].w > v.w) {
                bucket_points[j] = bucket_points[j - 1u];
                j -= 1u;
            }
            if (j != i) bucket_points[j] = v;
        }
        return;
    }
    for (uint i = n / 2u; i > 0u; --i) sift_down(begin, i - 1u, n);
    for (uint m = n - 1u; m > 0u; --m) {
        uvec4 top = bucket_points[begin];
        bucket_points[begin] = bucket_points[begin + m];
        bucket_points[begin + m] = top;
        sift_down(begin, 0u, m);
    }
}
#undef CE

void main() {
    uint b = invocation_index();
    if (b >= push.num_buckets) return;
    uint begin = bucket_start[b];
    sort_bucket(begin, bucket_start[b + 1u] - begin);
}
