// A path's random numbers, by sample dimension (the variant's SOBOL,
// src/render/variants.rs). SOBOL=1: point `index` (the render's iteration) of the
// Owen-scrambled Sobol sequence `key` of the path's pixel, one scrambled dimension per use
// (common.glsl, "Quasi-random numbers"); a dimension serves the same purpose in every
// iteration's path, so the stratification of a pixel's samples across iterations carries
// over to its estimate. SOBOL=0: a PCG stream per path and iteration, drawn in the order
// of the calls (the dimension is not used). Either way `rng` is that PCG stream, for draws
// that are no dimension (the light-vertex cache's). Camera paths only: pt.comp and
// camera_subpath.comp (light subpaths draw from a PCG stream: light_subpath.comp).
#ifndef PATH_SAMPLER_GLSL
#define PATH_SAMPLER_GLSL

#if !defined(SOBOL)
#error "SOBOL must be defined (src/render/variants.rs)"
#endif

struct PathSampler {
    uint rng;    // PCG stream of this path in this iteration
    uint key;    // Sobol sequence of this pixel (SOBOL=1)
    uint index;  // its point: the iteration
};

// The sampler of the camera path of `pixel` in this iteration. rng_init's streams: 0 the
// PCG streams of camera paths (1: light subpaths'), 2 the keys of the pixels' sequences
// (with iteration 0: one sequence for the whole render).
PathSampler path_sampler(uint pixel) {
    PathSampler ps;
    ps.rng = rng_init(params.misc.x, push.iteration, pixel, 0u);
    ps.key = rng_init(params.misc.x, 0u, pixel, 2u);
    ps.index = push.iteration;
    return ps;
}

// Sample dimensions. A path's vertex `len` is the one its len-th segment hits (the
// camera's first hit has len 1). 2-D: the pixel jitter is 0; vertex len has its light
// sample (next-event estimation) len. 3-D: vertex len's BSDF sample len, the direction
// (xy) stratified together with the lobe (z) that it is drawn for, so that a lobe's share
// of a pixel's samples keeps their directions stratified (docs/performance.md measures it
// against a 1-D lobe); pt's vertex len draws its next-event sample of a constant sky from
// the BSDF too, as 3-D dimension DIM3_SKY(len), and where that sample passes a delta
// vertex len (a sky branch, pt.comp) its BSDF sample is DIM3_SKY_BRANCH(len); two branches
// of one path that pass vertices of the same len share it (each is unbiased alone). 1-D:
// vertex len has its light pick 2 len and its Russian roulette 2 len + 1. Each kind
// scrambles its numbers apart from the others (common.glsl). Each is drawn only when used:
// an unused dimension costs nothing and leaves the others as they are.
#define DIM2_PIXEL 0u
#define DIM2_LIGHT(len) (len)
#define DIM3_BSDF(len) (len)
#define DIM3_SKY(len) (0x40000000u | (len))
#define DIM3_SKY_BRANCH(len) (0x20000000u | (len))
#define DIM1_PICK(len) (2u * (len))
#define DIM1_ROULETTE(len) (2u * (len) + 1u)
// The colour channel a path chooses at its first dispersive vertex, whichever that is (once
// per path; glsl/lobes/dispersion.glsl): a dimension of its own that no vertex's reaches.
#define DIM1_CHANNEL 0xfffffff0u

vec2 sample_2d(inout PathSampler ps, uint dim) {
#if SOBOL
    return sobol2(ps.key, ps.index, dim);
#else
    return rnd2(ps.rng);
#endif
}

float sample_1d(inout PathSampler ps, uint dim) {
#if SOBOL
    return sobol1(ps.key, ps.index, dim);
#else
    return rnd(ps.rng);
#endif
}

// A BSDF sample's direction and lobe (bsdf_sample's argument): DIM3_BSDF(len) or DIM3_SKY(len).
vec3 sample_3d(inout PathSampler ps, uint dim) {
#if SOBOL
    return sobol3(ps.key, ps.index, dim);
#else
    return vec3(rnd2(ps.rng), rnd(ps.rng));
#endif
}

#endif
