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
// sample (next-event estimation) 2 len and its BSDF direction 2 len + 1. 1-D (other
// scrambles than the 2-D dimensions of the same number: sobol1): vertex len has its light
// pick 3 len, its BSDF lobe 3 len + 1 and its Russian roulette 3 len + 2. Each is drawn
// only when used: an unused dimension costs nothing and leaves the others as they are.
#define DIM2_PIXEL 0u
#define DIM2_LIGHT(len) (2u * (len))
#define DIM2_BSDF(len) (2u * (len) + 1u)
#define DIM1_PICK(len) (3u * (len))
#define DIM1_LOBE(len) (3u * (len) + 1u)
#define DIM1_ROULETTE(len) (3u * (len) + 2u)
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

// The BSDF sample of vertex `len`: direction and lobe (bsdf_sample's argument).
vec3 sample_bsdf_at(inout PathSampler ps, uint len) {
    vec2 u = sample_2d(ps, DIM2_BSDF(len));
    return vec3(u, sample_1d(ps, DIM1_LOBE(len)));
}

#endif
