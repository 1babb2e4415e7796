// AOVs (`--aov`, src/render/aov.rs), summed by the camera kernels when compiled with
// AOV=1, with Intel Open Image Denoise's conventions (its documentation, "Albedo" and
// "Normal" inputs): the albedo and shading normal of the first non-specular surface a
// camera path reaches, passing through perfectly specular (delta) surfaces, the albedo
// times the specular throughput before it (a mirror's or glass's colour, a medium's
// transmittance); averaged over the pixel's samples, 0 where a sample reaches none (the
// background, or a path ended before one). Depth and position are the first hit's.
// Per pixel three vec4 sums in the binding `aov`: (albedo, samples), (normal, first
// hits), (camera-relative position, depth = distance along the camera ray). Each pixel
// has one writer per dispatch (as the film, glsl/film.glsl), so no atomics.
#ifndef AOV_GLSL
#define AOV_GLSL
#ifndef AOV
#error "AOV must be defined (AovKernel, src/render/aov.rs)"
#endif
#if AOV
layout(std430) buffer aov { vec4 aov_sums[]; };

// One camera path's AOV sample.
struct AovSample {
    vec3 albedo;
    vec3 normal;
    vec3 position;
    float depth;
    bool hit;   // the camera ray hit a surface
    bool found; // a non-specular surface was reached: albedo and normal are set
};

AovSample aov_start() {
    AovSample a;
    a.albedo = vec3(0.0);
    a.normal = vec3(0.0);
    a.position = vec3(0.0);
    a.depth = 0.0;
    a.hit = false;
    a.found = false;
    return a;
}

// The camera ray's hit at distance `t`, point `p`.
void aov_first_hit(inout AovSample a, float t, vec3 p) {
    a.hit = true;
    a.depth = t;
    a.position = p;
}

// A surface with BSDF `b` reached with throughput `thr` (through specular surfaces only,
// while nothing is found): a specular one is passed through, the first other one (or one
// that reflects nothing: albedo 0) sets the albedo and normal.
void aov_surface(inout AovSample a, Bsdf b, vec3 thr) {
    if (a.found || (b.valid && b.delta)) return;
    a.found = true;
    a.albedo = b.valid ? thr * b.albedo : vec3(0.0);
    a.normal = b.n;
}

// Adds the sample of a finished path to its pixel.
void aov_add(uint pixel, AovSample a) {
    uint i = 3u * pixel;
    aov_sums[i] += vec4(a.albedo, 1.0);
    aov_sums[i + 1u] += vec4(a.normal, a.hit ? 1.0 : 0.0);
    if (a.hit) aov_sums[i + 2u] += vec4(a.position, a.depth);
}
#endif
#endif
