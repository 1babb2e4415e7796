// The film: per pixel a running sum of each iteration's value and a running sum of its
// square (for per-pixel variance: error estimates and statistical tests), both float32
// with Kahan compensation (Kahan 1965), so long renders lose no precision without float64.
// Each pixel has one writer per dispatch, so the result is deterministic.
// The film's sums (FILM_SUMS[]: vec4, four per pixel: sum, its compensation, sum of
// squares, its compensation) are reached by device address (DEVICE_ADDRESSES,
// glsl/addresses.glsl) or as the binding `film`; the binding `film_stats` (stats[], uint:
// [0] rejected samples, [1] overflowing splats, [2..3] the 64-bit count of traced rays
// when profiling: COUNT_RAYS in glsl/scene.glsl), src/render/film.rs; with HAS_SPLAT also
// the splat sums (below).
#ifndef FILM_GLSL
#define FILM_GLSL
#include "addresses.glsl"

#if DEVICE_ADDRESSES
#define FILM_SUMS FRAME_FILM
#else
layout(std430) buffer film { vec4 film_sums[]; };
#define FILM_SUMS film_sums
#endif
layout(std430) buffer film_stats { uint stats[]; };

// Kahan step: adds `v` to the sum at FILM_SUMS[i] with compensation at FILM_SUMS[i + 1].
// `precise` forbids the compiler from reassociating these operations, which would cancel
// the compensation to zero (seen on lavapipe: 2048 iterations of a constant 0.5294118
// summed to 0.5294181 without it; tests/render_pt.rs catches this).
void film_kahan_add(uint i, vec4 v) {
    vec4 sum = FILM_SUMS[i];
    vec4 c = FILM_SUMS[i + 1u];
    precise vec4 y = v - c;
    precise vec4 t = sum + y;
    precise vec4 comp = (t - sum) - y;
    FILM_SUMS[i + 1u] = comp;
    FILM_SUMS[i] = t;
}

// Adds this iteration's value `v` of `pixel`; rejects (and counts) NaN, Inf and negative
// values instead of adding them.
void film_add(uint pixel, vec3 v) {
    if (!finite3(v) || any(lessThan(v, vec3(0.0)))) {
        atomicAdd(stats[0], 1u);
        return;
    }
    film_kahan_add(4u * pixel, vec4(v, 0.0));
    film_kahan_add(4u * pixel + 2u, vec4(v * v, 0.0));
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
