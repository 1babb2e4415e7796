#version 460
// Exclusive prefix sum, one level of a multi-level scan (src/render/passes/exclusive_scan.rs).
// Blocks of WORKGROUP_SIZE x PER_THREAD elements, one workgroup (PER_THREAD elements per
// invocation) per block; no subgroup operations, so any subgroup width works. ADD,
// WORKGROUP_SIZE and PER_THREAD are set by the Rust side.
//   ADD=0: data[offset + i] (i < n) becomes the exclusive scan inside its block, and the
//          block's total goes to sums[sums_offset + block].
//   ADD=1: data[offset + i] += sums[sums_offset + block] (the scanned block totals).
// `data` and `sums` may be the same buffer (scratch levels), hence no `restrict`.
#extension GL_GOOGLE_include_directive : require

#if !defined(ADD) || !defined(WORKGROUP_SIZE) || !defined(PER_THREAD)
#error "ADD, WORKGROUP_SIZE and PER_THREAD must be defined (src/render/passes/exclusive_scan.rs)"
#endif

layout(local_size_x = WORKGROUP_SIZE) in;

layout(std430) buffer scan_data { uint data[]; };
layout(std430) buffer scan_block_sums { uint sums[]; };

layout(push_constant) uniform Push {
    uint n;
    uint offset;
    uint sums_offset;
} push;

#include "common.glsl"

const uint BLOCK = uint(WORKGROUP_SIZE) * uint(PER_THREAD);

#if !ADD
shared uint partial[2][WORKGROUP_SIZE];
#endif

void main() {
    uint block = workgroup_index();
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
    // Inclusive Hillis-Steele scan of the WORKGROUP_SIZE thread totals, double-buffered.
    uint src = 0u;
    partial[0][t] = run;
    barrier();
    for (uint d = 1u; d < uint(WORKGROUP_SIZE); d <<= 1u) {
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
    if (t == uint(WORKGROUP_SIZE) - 1u) sums[push.sums_offset + block] = partial[src][WORKGROUP_SIZE - 1];
#endif
}
