#version 460
// Exclusive prefix sum, one level of a multi-level scan (see src/render/hash_grid.rs).
// Blocks of 256 elements, one workgroup of 64 invocations (4 elements each) per block;
// no subgroup operations, so any subgroup width works.
//   ADD=0: data[offset + i] (i < n) becomes the exclusive scan inside its block, and the
//          block's total goes to sums[sums_offset + block].
//   ADD=1: data[offset + i] += sums[sums_offset + block] (the scanned block totals).
// `data` and `sums` may be the same buffer (scratch levels), hence no `restrict`.
#extension GL_GOOGLE_include_directive : require

#ifndef ADD
#define ADD 0
#endif

layout(local_size_x = 64) in;

layout(std430, binding = 0) buffer DataBuf { uint data[]; };
layout(std430, binding = 1) buffer SumsBuf { uint sums[]; };

layout(push_constant) uniform Push {
    uint n;
    uint offset;
    uint sums_offset;
} push;

#include "hash_grid.glsl"

const uint PER_THREAD = 4u;
const uint BLOCK = 64u * PER_THREAD;

#if !ADD
shared uint partial[2][64];
#endif

void main() {
    uint block = hash_grid_group_index();
    uint t = gl_LocalInvocationID.x;
    if (block * BLOCK >= push.n) return;  // folded-dispatch padding: whole workgroup
    uint first = block * BLOCK + t * PER_THREAD;  // index inside this level
#if ADD
    uint add = sums[push.sums_offset + block];
    for (uint k = 0u; k < PER_THREAD; ++k) {
        uint i = first + k;
        if (i < push.n) data[push.offset + i] += add;
    }
#else
    uint v[PER_THREAD];
    uint run = 0u;
    for (uint k = 0u; k < PER_THREAD; ++k) {
        uint i = first + k;
        uint x = i < push.n ? data[push.offset + i] : 0u;
        v[k] = run;
        run += x;
    }
    // Inclusive Hillis-Steele scan of the 64 thread totals, double-buffered.
    uint src = 0u;
    partial[0][t] = run;
    barrier();
    for (uint d = 1u; d < 64u; d <<= 1u) {
        uint s = partial[src][t];
        if (t >= d) s += partial[src][t - d];
        partial[1u - src][t] = s;
        src = 1u - src;
        barrier();
    }
    uint before = partial[src][t] - run;  // exclusive prefix of this thread's total
    for (uint k = 0u; k < PER_THREAD; ++k) {
        uint i = first + k;
        if (i < push.n) data[push.offset + i] = v[k] + before;
    }
    if (t == 63u) sums[push.sums_offset + block] = partial[src][63];
#endif
}
