#version 460
// Debug kernel: the light tree's descent against its pdf (glsl/light_tree.glsl, through
// lights.glsl's nee_pick_light and nee_light_prob). Invocation k < push.count serves query
// q = k / M and draw j = k % M (M = push.light_paths): the query is a random point in
// [-3, 3] x [-3, 3] x [0, 3] with a random unit normal (or none, q % 4 == 3); the draw
// picks with u = (j + 1/2) / M and writes (light bits, the descent's probability,
// nee_light_prob of that light, nee_light_prob of light j when j < #lights).
// tests/render_light_tree.rs checks the frequencies and the probabilities.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64) in;
#include "scene.glsl"
#include "push.glsl"

layout(std430) buffer tree_results { vec4 result[]; };

void main() {
    uint k = gl_GlobalInvocationID.x;
    if (k >= push.count) return;
    uint m = push.light_paths;
    uint q = k / m, j = k % m;
    uint rng = rng_init(params.misc.x, 0u, q, 5u);
    vec3 x = vec3(6.0 * rnd(rng) - 3.0, 6.0 * rnd(rng) - 3.0, 3.0 * rnd(rng));
    vec3 n = q % 4u == 3u ? vec3(0.0) : sample_uniform_sphere(rnd2(rng));
    float prob;
    uint li = nee_pick_light((float(j) + 0.5) / float(m), x, n, prob);
    float pdf = li == NO_LIGHT ? 0.0 : nee_light_prob(li, x, n);
    float pdf_j = j < light_count() ? nee_light_prob(j, x, n) : 0.0;
    result[k] = vec4(uintBitsToFloat(li), prob, pdf, pdf_j);
}
