#version 460
// Debug kernel: the environment map's sampling and evaluation (glsl/environment.glsl).
// Invocation k < push.count draws direction k of a stratified set with env_sample
// (stratum k % n, k / n of an n x n grid, n = push.light_paths, jittered) and writes
// (dir.xyz, pdf_w or -1 where it failed) and (radiance.rgb, pdf_w of env_eval along dir);
// invocation k also
// draws a uniform direction on the sphere and writes (dir.xyz, env_eval's pdf_w) and
// (radiance.rgb, 0). tests/render_environment.rs checks the histogram of the sampled
// directions against the pdf, the pdf's normalisation, and sampling against evaluation.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64) in;
#include "scene.glsl"
#include "push.glsl"

layout(std430) buffer env_results { vec4 result[]; };

void main() {
    uint k = gl_GlobalInvocationID.x;
    if (k >= push.count) return;
    uint n = push.light_paths;
    uint rng = rng_init(params.misc.x, 0u, k, 7u);
    GpuLight l = light_at(background_light());
    vec2 u = (vec2(float(k % n), float(k / n)) + rnd2(rng)) / float(n);
    vec3 dir;
    float pdf;
    bool ok;
    vec3 le = env_sample(l, u, dir, pdf, ok);
    float pdf_eval;
    env_eval(l, dir, pdf_eval);
    result[4u * k] = vec4(dir, ok ? pdf : -1.0);
    result[4u * k + 1u] = vec4(le, pdf_eval);
    vec3 d = sample_uniform_sphere(rnd2(rng));
    float pdf_u;
    vec3 le_u = env_eval(l, d, pdf_u);
    result[4u * k + 2u] = vec4(d, pdf_u);
    result[4u * k + 3u] = vec4(le_u, 0.0);
}
