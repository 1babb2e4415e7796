// The image-based environment light: an equirectangular (latitude-longitude) radiance map
// at infinity, importance-sampled by a piecewise-constant 2D distribution (pbrt's
// Distribution2D: a marginal over rows, a conditional per row; Pharr, Jakob, Humphreys,
// "Physically Based Rendering", 4th ed., 2.4.7 and 12.5). The map, its distribution and
// their layout are built by src/render/environment.rs; docs/environment.md states the
// conventions.
//
// Map coordinates (Mitsuba 3's envmap, so that both render the same image): in the map's
// frame +Y is up; a unit direction d has
//   u = atan2(d.x, -d.z) / 2pi (mod 1),   v = acos(d.y) / pi,
// so u = 0 looks along -Z, u = 1/4 along +X, v = 0 is the zenith. Texel (i, j) of the
// W x H image is the radiance at u = (i + 1/2) / W, v = j / (H - 1) (rows at the poles),
// and the radiance between texels is bilinear, periodic in u. The map's frame is the
// world's turned about +Y by the light's rotation.
//
// Sampling: cell (i, j), i < W, j < H - 1, is the bilinear patch between texels
// (i, j), (i + 1 mod W, j), (i, j + 1), (i + 1 mod W, j + 1); its probability is
// proportional to the mean luminance of its four texels times sin(theta) at its centre,
// positive wherever the radiance is, and uniform inside the cell in (u, v). The solid-angle
// pdf is pdf_uv / (2 pi^2 sin(theta)).
//
// Bindings (by device address with DEVICE_ADDRESSES, glsl/scene.glsl): env_texels[j * W + i] = (rgb radiance of texel (i, j), pdf_uv of cell (i, j));
// env_distribution = the marginal CDF over rows (H entries: 0 ... 1), then per row j the
// conditional CDF over its W cells (W + 1 entries at H + j * (W + 1)).
// The background GpuLight carries: a.x, a.y = W, H (uint bits; W = 0: no map, a constant
// background), b.x, b.y = cos, sin of the rotation; radiance.rgb scales the map.
//
// Requires: common.glsl (PI, INV_PI), types.glsl (GpuLight); with DEVICE_ADDRESSES
// scene.glsl (SCENE_ENV_TEXELS, SCENE_ENV_DISTRIBUTION).
#ifndef ENVIRONMENT_GLSL
#define ENVIRONMENT_GLSL

#if DEVICE_ADDRESSES
#define env_texel_data SCENE_ENV_TEXELS
#define env_cdf SCENE_ENV_DISTRIBUTION
#else
layout(std430) readonly buffer env_texels { vec4 env_texel_data[]; };
layout(std430) readonly buffer env_distribution { float env_cdf[]; };
#endif

bool env_has_map(GpuLight l) { return floatBitsToUint(l.a.x) != 0u; }

// World direction -> the map's frame (the inverse of the rotation about +Y).
vec3 env_to_map(GpuLight l, vec3 d) {
    float c = l.b.x, s = l.b.y;
    return vec3(c * d.x - s * d.z, d.y, s * d.x + c * d.z);
}

vec3 env_to_world(GpuLight l, vec3 d) {
    float c = l.b.x, s = l.b.y;
    return vec3(c * d.x + s * d.z, d.y, -s * d.x + c * d.z);
}

// The map's radiance (not yet scaled by radiance.rgb) along world direction `dir`, and the
// solid-angle pdf with which env_sample produces it.
vec3 env_eval(GpuLight l, vec3 dir, out float pdf_w) {
    uint w = floatBitsToUint(l.a.x), h = floatBitsToUint(l.a.y);
    vec3 d = env_to_map(l, dir);
    float u = atan(d.x, -d.z) * (0.5 * INV_PI);
    u -= floor(u);
    float v = acos(clamp(d.y, -1.0, 1.0)) * INV_PI;
    // Bilinear between texel centres: x in texel units from texel 0's centre.
    float x = u * float(w) - 0.5;
    float x0f = floor(x);
    float fx = x - x0f;
    int x0 = int(x0f);
    uint i0 = uint(x0 < 0 ? x0 + int(w) : x0) % w;
    uint i1 = (i0 + 1u) % w;
    float y = v * float(h - 1u);
    uint j0 = min(uint(y), h - 2u);
    float fy = y - float(j0);
    vec4 t00 = env_texel_data[j0 * w + i0];
    vec4 t10 = env_texel_data[j0 * w + i1];
    vec4 t01 = env_texel_data[(j0 + 1u) * w + i0];
    vec4 t11 = env_texel_data[(j0 + 1u) * w + i1];
    vec3 top = mix(t00.rgb, t10.rgb, fx);
    vec3 bottom = mix(t01.rgb, t11.rgb, fx);
    float sin_theta = sqrt(max(d.x * d.x + d.z * d.z, 0.0));
    // The cell's pdf_uv is stored with its top-left texel.
    pdf_w = sin_theta > 0.0 ? t00.a / (2.0 * PI * PI * sin_theta) : 0.0;
    return mix(top, bottom, fy);
}

// The first index k in [first, first + n) with cdf[k + 1] > x (cdf[first] = 0, cdf[first + n] = 1):
// the cell that the piecewise-constant CDF maps `x` into.
uint env_find_cell(uint first, uint n, float x) {
    uint lo = 0u, hi = n - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) >> 1u;
        if (env_cdf[first + mid + 1u] > x) hi = mid;
        else lo = mid + 1u;
    }
    return lo;
}

// A world direction towards the map drawn with density pdf_w (solid angle), and the
// map's radiance along it (not yet scaled). `ok` is false where the pdf vanishes.
vec3 env_sample(GpuLight l, vec2 rnd_uv, out vec3 dir, out float pdf_w, out bool ok) {
    uint w = floatBitsToUint(l.a.x), h = floatBitsToUint(l.a.y);
    uint rows = h - 1u;
    uint j = env_find_cell(0u, rows, rnd_uv.y);
    float r0 = env_cdf[j], r1 = env_cdf[j + 1u];
    float ty = clamp((rnd_uv.y - r0) / max(r1 - r0, 1e-30), 0.0, 1.0);
    uint row = h + j * (w + 1u);
    uint i = env_find_cell(row, w, rnd_uv.x);
    float c0 = env_cdf[row + i], c1 = env_cdf[row + i + 1u];
    float tx = clamp((rnd_uv.x - c0) / max(c1 - c0, 1e-30), 0.0, 1.0);
    // Cell (i, j) spans texel centres i .. i + 1 in u and rows j .. j + 1 in v.
    float u = (float(i) + 0.5 + tx) / float(w);
    float v = (float(j) + ty) / float(rows);
    float theta = v * PI, phi = u * 2.0 * PI;
    float st = sin(theta);
    vec3 d = vec3(sin(phi) * st, cos(theta), -cos(phi) * st);
    dir = env_to_world(l, d);
    // The radiance and pdf from the same lookup the hit path uses, so that a sampled
    // direction and a hit along it agree exactly.
    vec3 le = env_eval(l, dir, pdf_w);
    ok = pdf_w > 0.0;
    return le;
}

#endif
