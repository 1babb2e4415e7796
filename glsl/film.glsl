// The film: per pixel and colour channel, the sum of each iteration's value and the sum
// of its square (for per-pixel variance: error estimates and statistical tests), each a
// 128-bit unsigned fixed-point number with FILM_FRACTION_BITS = 32 bits after the point:
// one uvec4, .x the least significant word, added word by word with uaddCarry (no 64-bit
// integers, which SwiftShader lacks). Integer sums do not depend on the order of the adds,
// so the shards of a render, rendered anywhere and added on the host, give the bits of one
// render (docs/distributed.md). Each pixel has one writer per dispatch: no atomics.
//
// Range and resolution: a value (and its square, computed in float32) is rounded to the
// nearest 2^-32 (roundEven: exact and the same on every device); a value at or above
// FILM_MAX = 2^32 is rejected and counted in stats[4] (overflowing samples). Below it a
// value adds < 2^64 units and a square < 2^96, and at most 2^32 iterations are added (the
// iteration index is 32-bit), so neither sum reaches 2^128: they never wrap.
//
// FILM_SUMS[]: uvec4, FILM_UVEC4_PER_PIXEL = 6 per pixel (sums of R, G, B, then sums of
// their squares), reached by device address (DEVICE_ADDRESSES, glsl/addresses.glsl) or as
// the binding `film`; the binding `film_stats` (stats[], uint: [0] rejected samples, [1]
// overflowing splats, [2..3] the 64-bit count of traced rays when profiling: COUNT_RAYS in
// glsl/scene.glsl, [4] overflowing samples), src/render/film.rs; with HAS_SPLAT also the
// splat sums (below).
#ifndef FILM_GLSL
#define FILM_GLSL
#include "addresses.glsl"

#if DEVICE_ADDRESSES
#define FILM_SUMS FRAME_FILM
#else
layout(std430) buffer film { uvec4 film_sums[]; };
#define FILM_SUMS film_sums
#endif
layout(std430) buffer film_stats { uint stats[]; };

#define FILM_UVEC4_PER_PIXEL 6u
#define FILM_SCALE 4294967296.0
#define FILM_MAX 4294967296.0

// x (a whole number below 2^96 as a float) as 128-bit words, exactly: from 2^24 on,
// x = m 2^shift with its 24-bit significand m, which spans at most two words.
uvec4 film_fixed(float x) {
    uvec4 w = uvec4(0u);
    if (x < 16777216.0) {
        w.x = uint(x);
        return w;
    }
    uint bits = floatBitsToUint(x);
    uint m = (bits & 0x7FFFFFu) | 0x800000u;
    int shift = int(bits >> 23) - 150;  // 127 bias + 23 fraction bits; >= 1 here
    int word = shift >> 5, bit = shift & 31;
    w[word] = m << bit;
    if (bit != 0 && word < 3) w[word + 1] = m >> (32 - bit);
    return w;
}

// a + b in 128 bits (never carries out of .w: see the range above).
uvec4 film_add128(uvec4 a, uvec4 b) {
    uvec4 s;
    uint c0, c1, c2, c3;
    s.x = uaddCarry(a.x, b.x, c0);
    s.y = uaddCarry(a.y, b.y, c1);
    s.y = uaddCarry(s.y, c0, c0);
    s.z = uaddCarry(a.z, b.z, c2);
    s.z = uaddCarry(s.z, c1 + c0, c1);
    s.w = a.w + b.w + c2 + c1;
    return s;
}

// Adds this iteration's value `v` of `pixel`; rejects (and counts) NaN, Inf and negative
// values, and values out of the film's range, instead of adding them.
void film_add(uint pixel, vec3 v) {
    if (!finite3(v) || any(lessThan(v, vec3(0.0)))) {
        atomicAdd(stats[0], 1u);
        return;
    }
    if (max3(v) >= FILM_MAX) {
        atomicAdd(stats[4], 1u);
        return;
    }
    uint i = FILM_UVEC4_PER_PIXEL * pixel;
    for (uint c = 0u; c < 3u; ++c) {
        // `precise`: the products are rounded as written, on every device alike.
        precise float q = roundEven(v[c] * FILM_SCALE);
        precise float q2 = roundEven((v[c] * v[c]) * FILM_SCALE);
        FILM_SUMS[i + c] = film_add128(FILM_SUMS[i + c], film_fixed(q));
        FILM_SUMS[i + 3u + c] = film_add128(FILM_SUMS[i + 3u + c], film_fixed(q2));
    }
}

// ---- Splats (light tracing's camera connections land on any pixel from any invocation):
// per pixel three 64-bit fixed-point sums with SPLAT_SCALE = 2^24 units per 1.0, added by
// integer atomics, so the sum is exact and independent of order (deterministic). Each
// splat is rounded to the nearest unit (error <= 3e-8). A splat above SPLAT_MAX = 2^27 is
// rejected and counted in stats[1], so a sum of one iteration overflows only past
// 2^64 / 2^24 / 2^27 = 2^13 such splats in one pixel. The camera kernel (or
// accumulate.comp) takes the sums into the film once per iteration and zeroes them.
//
// SPLAT_ATOMICS_64 (src/render/atomics.rs, always set by the Rust side): 1 adds uint64
// values with 64-bit atomics; 0 keeps the same 64-bit sums as (low, high) pairs of 32-bit
// words (the same bytes, little-endian) and needs no 64-bit integer in the shader: an
// add to the low word returns its old value, which says whether it wrapped, and the high
// part plus that carry goes to the high word. Every add contributes exactly its value
// modulo 2^64 whatever the order, so both give the same sums, and both round them to the
// nearest float when taken: the same image.
#ifdef HAS_SPLAT
#ifndef SPLAT_ATOMICS_64
#error "SPLAT_ATOMICS_64 must be defined (src/render/variants.rs)"
#endif
#define SPLAT_SCALE 16777216.0
#define SPLAT_MAX 134217728.0

// The sums are reached by device address or as the binding `splat`, like the film's.
#if SPLAT_ATOMICS_64
#extension GL_EXT_shader_atomic_int64 : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#if DEVICE_ADDRESSES
layout(buffer_reference, std430, buffer_reference_align = 8) buffer SplatSums { uint64_t v[]; };
#define splat_sums ARRAY_AT(SplatSums, addresses.splat)
#else
layout(std430) buffer splat { uint64_t splat_sums[]; };
#endif
#else
#if DEVICE_ADDRESSES
layout(buffer_reference, std430, buffer_reference_align = 4) buffer SplatWords { uint v[]; };
#define splat_words ARRAY_AT(SplatWords, addresses.splat)
#else
layout(std430) buffer splat { uint splat_words[]; };
#endif
#endif

void splat_add(uint pixel, vec3 v) {
    if (!finite3(v) || any(lessThan(v, vec3(0.0)))) {
        atomicAdd(stats[0], 1u);
        return;
    }
    if (max3(v) > SPLAT_MAX) {
        atomicAdd(stats[1], 1u);
        return;
    }
    for (int c = 0; c < 3; ++c) {
        uint i = 3u * pixel + uint(c);
#if SPLAT_ATOMICS_64
        uint64_t q = uint64_t(v[c] * SPLAT_SCALE + 0.5);
        if (q != 0ul) atomicAdd(splat_sums[i], q);
#else
        // f < 2^52 is a whole float from here on: its high and low 32 bits are exact.
        float f = floor(v[c] * SPLAT_SCALE + 0.5);
        uint hi = uint(floor(f * (1.0 / 4294967296.0)));
        uint lo = uint(f - float(hi) * 4294967296.0);
        if (lo != 0u) {
            uint old = atomicAdd(splat_words[2u * i], lo);
            if (old + lo < old) hi += 1u;  // the low word wrapped
        }
        if (hi != 0u) atomicAdd(splat_words[2u * i + 1u], hi);
#endif
    }
}

// The pixel's splat sum of this iteration, zeroing it.
vec3 splat_take(uint pixel) {
    vec3 v;
    for (int c = 0; c < 3; ++c) {
        uint i = 3u * pixel + uint(c);
#if SPLAT_ATOMICS_64
        v[c] = float(splat_sums[i]) * (1.0 / SPLAT_SCALE);
        splat_sums[i] = 0ul;
#else
        v[c] = u64_words_to_float(splat_words[2u * i], splat_words[2u * i + 1u]) * (1.0 / SPLAT_SCALE);
        splat_words[2u * i] = 0u;
        splat_words[2u * i + 1u] = 0u;
#endif
    }
    return v;
}
#endif

#endif
