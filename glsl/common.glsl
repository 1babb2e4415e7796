// Constants, random numbers, frames and the ray-offset rule shared by every kernel.
#ifndef COMMON_GLSL
#define COMMON_GLSL

#define PI 3.14159265358979
#define INV_PI 0.318309886183791
#define INV_4PI 0.0795774715459477
// The largest float below 1: a remapped random number stays in [0, 1).
#define ONE_MINUS_EPSILON 0.99999994

float luminance(vec3 c) { return dot(c, vec3(0.212671, 0.715160, 0.072169)); }
float max3(vec3 v) { return max(v.x, max(v.y, v.z)); }

// ---- Random numbers: a PCG-style hash (O'Neill, "PCG", 2014; Jarzynski & Olano,
// "Hash Functions for GPU Rendering", JCGT 2020) seeds a 32-bit PCG stream per
// (seed, iteration, path). Same inputs -> same numbers on every device.
uint pcg_hash(uint v) {
    uint state = v * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

uint rng_init(uint seed, uint iteration, uint index, uint stream) {
    return pcg_hash(seed ^ pcg_hash(iteration ^ pcg_hash(index ^ pcg_hash(stream))));
}

// The next 32 random bits of the stream: one PCG step (LCG advance, then the RXS-M-XS
// output permutation, which is pcg_hash of the old state).
uint rnd_u32(inout uint state) {
    uint word = pcg_hash(state);
    state = state * 747796405u + 2891336453u;
    return word;
}

// The top 24 bits of `x` as a float in [0, 1) (exact).
float fixed_to_unit(uint x) { return float(x >> 8) * (1.0 / 16777216.0); }

// Uniform in [0, 1) with 24 random bits.
float rnd(inout uint state) { return fixed_to_unit(rnd_u32(state)); }

// Uniform integer in [0, n), n >= 1, exactly: multiply-shift with rejection (Lemire,
// "Fast Random Integer Generation in an Interval", ACM TOMACS 2019). Rejects with
// probability below n / 2^32.
uint rnd_below(uint n, inout uint state) {
    uint threshold = (0u - n) % n;
    for (;;) {
        uint hi, lo;
        umulExtended(rnd_u32(state), n, hi, lo);
        if (lo >= threshold) return hi;
    }
}

vec2 rnd2(inout uint s) { float a = rnd(s); return vec2(a, rnd(s)); }

// ---- Quasi-random numbers: Owen-scrambled Sobol points, padded (Burley, "Practical
// Hash-based Owen Scrambling", JCGT 9(4), 2020; pbrt-v4's PaddedSobolSampler). Every
// sample dimension `dim` of a sequence `key` (one per pixel) has its own shuffle of the
// sample index and its own scrambles; a 2-D dimension takes Sobol's first two
// dimensions, whose first 2^k points form a (0, k, 2)-net, so each pixel's first 2^k
// samples stratify every such pair; a 3-D one Sobol's first three (a (1, k, 3)-net), for
// a choice drawn together with the 2-D sample it selects for. Each point is uniform on
// [0, 1)^d and different dims are independent, so an estimator stays unbiased; the
// samples of one pixel are not independent across iterations (they are stratified).

// Laine & Karras' hash-based nested uniform scramble of the reversed bits, with
// Burley's constants: flips each bit of `x` by a hash of the bits below it.
uint lk_permutation(uint x, uint seed) {
    x += seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return x;
}

// Owen scramble of a [0, 1) fixed-point value `x` (bit 31 = 1/2).
uint owen_scramble(uint x, uint seed) { return bitfieldReverse(lk_permutation(bitfieldReverse(x), seed)); }

// Sobol's dimension 1 in bit-reversed form: bit i (from the top of the result) is the
// XOR of the index bits j whose positions contain i's (i AND j == i), the generator
// matrix being Pascal's triangle mod 2.
uint sobol1_reversed(uint index) {
    uint x = index;
    x ^= (x & 0xaaaaaaaau) >> 1;
    x ^= (x & 0xccccccccu) >> 2;
    x ^= (x & 0xf0f0f0f0u) >> 4;
    x ^= (x & 0xff00ff00u) >> 8;
    x ^= (x & 0xffff0000u) >> 16;
    return x;
}

// Sobol's dimensions 0 and 1 of the shuffled index `i`, scrambled by seeds drawn from
// `seed`. Sobol dimension 0 of i is bitfieldReverse(i); owen_scramble(bitfieldReverse(y),
// s) = bitfieldReverse(lk_permutation(y, s)).
vec2 sobol_xy(uint i, uint seed) {
    return vec2(fixed_to_unit(bitfieldReverse(lk_permutation(i, pcg_hash(seed + 1u)))),
                fixed_to_unit(bitfieldReverse(lk_permutation(sobol1_reversed(i), pcg_hash(seed + 2u)))));
}

// Point `index` of dimension pair `dim` of sequence `key`.
vec2 sobol2(uint key, uint index, uint dim) {
    uint seed = pcg_hash(key ^ pcg_hash(dim));
    return sobol_xy(owen_scramble(index, seed), seed);
}

// Sobol's dimension 2 (primitive polynomial x^2 + x + 1, initial direction numbers 1, 3:
// Joe and Kuo's table), one direction number per index bit, most significant bit = 1/2.
const uint SOBOL_DIM2[32] = uint[32](
    0x80000000u, 0xc0000000u, 0x60000000u, 0x90000000u, 0xe8000000u, 0x5c000000u, 0x8e000000u, 0xc5000000u,
    0x68800000u, 0x9cc00000u, 0xee600000u, 0x55900000u, 0x80680000u, 0xc09c0000u, 0x60ee0000u, 0x90550000u,
    0xe8808000u, 0x5cc0c000u, 0x8e606000u, 0xc5909000u, 0x6868e800u, 0x9c9c5c00u, 0xeeee8e00u, 0x5555c500u,
    0x8000e880u, 0xc0005cc0u, 0x60008e60u, 0x9000c590u, 0xe8006868u, 0x5c009c9cu, 0x8e00eeeeu, 0xc5005555u);

// Point `index` of 3-D dimension `dim` of sequence `key`: Sobol's first three dimensions
// under one shuffle of the index, each with its own scramble (the seed's `dim ^ constant`
// keeps them apart from the 2-D and 1-D dimensions of the same number).
vec3 sobol3(uint key, uint index, uint dim) {
    uint seed = pcg_hash(key ^ pcg_hash(dim ^ 0x5bd1e995u));
    uint i = owen_scramble(index, seed);
    uint z = 0u;
    for (uint j = 0u, bits = i; bits != 0u; bits >>= 1, j++) {
        if ((bits & 1u) != 0u) z ^= SOBOL_DIM2[j];
    }
    return vec3(sobol_xy(i, seed), fixed_to_unit(owen_scramble(z, pcg_hash(seed + 3u))));
}

// Point `index` of 1-D dimension `dim` of sequence `key` (scrambled van der Corput). Its
// shuffle and scramble differ from those of 2-D dimension `dim` (two scrambles of the
// same points would be correlated).
float sobol1(uint key, uint index, uint dim) {
    uint seed = pcg_hash(key ^ pcg_hash(~dim));
    uint i = owen_scramble(index, seed);
    return fixed_to_unit(bitfieldReverse(lk_permutation(i, pcg_hash(seed + 1u))));
}

// ---- Orthonormal basis around a unit vector (Duff et al., "Building an Orthonormal
// Basis, Revisited", JCGT 2017).
void make_frame(vec3 n, out vec3 t, out vec3 b) {
    float s = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (s + n.z);
    float c = n.x * n.y * a;
    t = vec3(1.0 + s * n.x * n.x * a, s * c, -s * n.x);
    b = vec3(c, s + n.y * n.y * a, -n.y);
}

vec3 to_world(vec3 l, vec3 n) {
    vec3 t, b;
    make_frame(n, t, b);
    return l.x * t + l.y * b + l.z * n;
}

// ---- Sampling.
vec3 sample_cosine_hemisphere(vec2 u) {  // local, z up; pdf = cos / pi
    float r = sqrt(u.x);
    float phi = 2.0 * PI * u.y;
    return vec3(r * cos(phi), r * sin(phi), sqrt(max(0.0, 1.0 - u.x)));
}

vec3 sample_uniform_sphere(vec2 u) {  // pdf = 1 / (4 pi)
    float z = 1.0 - 2.0 * u.x;
    float r = sqrt(max(0.0, 1.0 - z * z));
    float phi = 2.0 * PI * u.y;
    return vec3(r * cos(phi), r * sin(phi), z);
}

vec2 sample_concentric_disc(vec2 u) {  // unit disc, pdf = 1 / pi (Shirley & Chiu 1997)
    vec2 o = 2.0 * u - 1.0;
    if (o.x == 0.0 && o.y == 0.0) return vec2(0.0);
    float r, theta;
    if (abs(o.x) > abs(o.y)) { r = o.x; theta = (PI / 4.0) * (o.y / o.x); }
    else { r = o.y; theta = (PI / 2.0) - (PI / 4.0) * (o.x / o.y); }
    return r * vec2(cos(theta), sin(theta));
}

vec2 sample_triangle(vec2 u) {  // barycentrics (b1, b2), uniform in area
    float su = sqrt(u.x);
    return vec2(1.0 - su, u.y * su);
}

// ---- Ray origins. A new ray leaves p along the side of the geometric normal `n`
// that `dir` points to, offset by a distance proportional to the magnitude of the
// coordinates (a fixed number of float ulps) plus a fraction of the scene's size, so the
// rule holds at any scale (docs/numerics.md). RAY_EPS is relative.
#define RAY_EPS 1.0e-5
vec3 offset_ray(vec3 p, vec3 n, vec3 dir, float scene_radius) {
    float eps = (max3(abs(p)) + 0.01 * scene_radius) * RAY_EPS;
    return p + (dot(n, dir) >= 0.0 ? eps : -eps) * n;
}

// The float nearest to the 64-bit integer hi 2^32 + lo (ties to even), as a 64-bit
// integer-to-float conversion rounds, without 64-bit integers: the top 24 significant
// bits, rounded by the bits below them (film.glsl's 32-bit splats;
// tests/render_atomics.rs checks it against the 64-bit conversion).
float u64_words_to_float(uint lo, uint hi) {
    if (hi == 0u) return float(lo);
    int shift = findMSB(hi) + 9;  // bits below the 24 kept: (32 + msb + 1) - 24
    uint mant, rest, half_unit;
    bool rest_above_half, rest_is_half;
    if (shift < 32) {
        mant = (hi << (32 - shift)) | (lo >> shift);
        rest = lo & ((1u << shift) - 1u);
        half_unit = 1u << (shift - 1);
        rest_above_half = rest > half_unit;
        rest_is_half = rest == half_unit;
    } else {
        // shift in 32..40: the rest is (hi's low s = shift - 32 bits, lo) and half a unit
        // 2^(shift - 1), as (high, low) words.
        int s = shift - 32;
        mant = hi >> s;
        uint rest_hi = hi & ((1u << s) - 1u);
        uint half_hi = s == 0 ? 0u : 1u << (s - 1);
        uint half_lo = s == 0 ? 0x80000000u : 0u;
        rest_above_half = rest_hi > half_hi || (rest_hi == half_hi && lo > half_lo);
        rest_is_half = rest_hi == half_hi && lo == half_lo;
    }
    if (rest_above_half || (rest_is_half && (mant & 1u) == 1u)) mant += 1u;
    return ldexp(float(mant), shift);
}

// Balance-heuristic weight (Veach 1997, sec. 9.2) of a technique with pdf a against one
// with pdf b. The VCM family weighs its techniques through the recursive quantities of
// glsl/subpath.glsl instead; path tracing uses this directly.
float balance(float a, float b) { return a / (a + b); }

bool finite3(vec3 v) { return !any(isnan(v)) && !any(isinf(v)); }

// Index of this invocation in a 1-D problem dispatched as a 2-D grid of workgroups
// (gpu::groups_2d), so that problems beyond 65,535 workgroups (the guaranteed
// maxComputeWorkGroupCount[0]) fit.
uint invocation_index() {
    return gl_GlobalInvocationID.y * (gl_NumWorkGroups.x * gl_WorkGroupSize.x) + gl_GlobalInvocationID.x;
}

// Index of this workgroup in a dispatch folded into 2-D the same way (kernels whose
// workgroups, not invocations, are the unit of work: exclusive_scan.comp).
uint workgroup_index() {
    return gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
}

// Path regeneration (Novak, Havran & Dachsbacher, "Path Regeneration for Interactive Path
// Tracing", Eurographics 2010 short papers): a dispatch over `paths` paths with `k` paths
// per invocation has regen_stride(paths, k) = ceil(paths / k) invocations, and invocation
// i traces paths i, i + stride, i + 2 stride, ... (below `paths`), starting the next one
// in the same loop iteration in which the current one ends. A SIMD group then runs until
// its lanes' total work is done instead of once per path until its longest path is.
// Each path keeps its own index, random sequence and outputs, so the image does not
// depend on k (tests/render_regen.rs). src/render/regen.rs chooses k.
uint regen_stride(uint paths, uint k) {
    // ceil(paths / k) without overflow for any k (--paths-per-invocation takes any u32).
    return paths == 0u ? 0u : (paths - 1u) / max(k, 1u) + 1u;
}

#endif
