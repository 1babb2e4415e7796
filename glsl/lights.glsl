// Light sources, written once for every estimator: direct-illumination sampling (next-
// event estimation) and the pdfs of hitting an emitter, with the quantities the MIS of
// docs/smallvcm.md 4.4 needs. A light is picked by the selection table of
// src/render/light_selection.rs (by power, or uniformly: --light-selection), and every
// pdf that includes the pick uses `light_pick_prob` of the light picked or hit; with
// --light-selection tree next-event estimation picks area lights by the light tree
// (`nee_pick_light`, `nee_light_prob`), light subpaths still by the table.
//
// Light kinds the scene lacks are compiled out (HAS_AREA_LIGHTS, HAS_POINT_LIGHTS,
// HAS_SPOT_LIGHTS, HAS_DIRECTIONAL_LIGHTS, HAS_BACKGROUND: glsl/features.glsl): each kind
// has its own `if (kind == ...)` block, and the blocks present do the same arithmetic in
// every variant.
//
// Requires: `light_at(i)` (GpuLight, scene.glsl), `params` (GpuParams), common.glsl, types.glsl.
#ifndef LIGHTS_GLSL
#define LIGHTS_GLSL

#include "features.glsl"
#if HAS_ENVIRONMENT_MAP
#include "environment.glsl"
#endif

#define EPS_COSINE_LIGHT 1e-6

uint light_kind(GpuLight l) { return floatBitsToUint(l.radiance.w); }
bool light_is_delta(uint kind) { return kind == LIGHT_POINT || kind == LIGHT_SPOT || kind == LIGHT_DIRECTIONAL; }
bool light_is_infinite(uint kind) { return kind == LIGHT_DIRECTIONAL || kind == LIGHT_BACKGROUND; }
// The emitting side of an area light: its triangle's geometric normal (p1-p0)x(p2-p0).
vec3 area_light_normal(GpuLight l) { return normalize(cross(l.b.xyz, l.c.xyz)); }

// ---- Solid-angle sampling of triangle lights (Arvo 1995, "Stratified sampling of
// spherical triangles", in the form of pbrt-v4's SampleSphericalTriangle): next-event
// estimation draws the direction uniformly in the solid angle the triangle subtends at the
// shading point, which removes the 1/d^2 and the light's cosine from the estimate (large
// or near lights). Below a solid angle of SPHERICAL_MIN_SR float32 loses the angles, and
// near a hemisphere the arc construction degenerates: there the point is drawn by area, as
// pbrt-v4 does (its MinSphericalSampleArea and MaxSphericalSampleArea). The choice depends
// on the shading point, so the direct pdf of a light point does too (area_light_direct_pdf_a).
#define SPHERICAL_MIN_SR 3e-4
#define SPHERICAL_MAX_SR 6.22

// The solid angle of area light l's triangle seen from x (Van Oosterom & Strackee 1983,
// tan(omega / 2) = |a.(b x c)| / (1 + a.b + b.c + c.a) for the unit vectors a, b, c).
float triangle_solid_angle(GpuLight l, vec3 x) {
    vec3 a = normalize(l.a.xyz - x);
    vec3 b = normalize(l.a.xyz + l.b.xyz - x);
    vec3 c = normalize(l.a.xyz + l.c.xyz - x);
    return abs(2.0 * atan(dot(a, cross(b, c)), 1.0 + dot(a, b) + dot(a, c) + dot(b, c)));
}

bool area_light_by_solid_angle(float omega) { return omega > SPHERICAL_MIN_SR && omega < SPHERICAL_MAX_SR; }

// The angle between unit vectors, accurate for small angles (pbrt-v4's AngleBetween).
float angle_between(vec3 v1, vec3 v2) {
    if (dot(v1, v2) < 0.0) return PI - 2.0 * asin(min(1.0, length(v1 + v2) * 0.5));
    return 2.0 * asin(min(1.0, length(v2 - v1) * 0.5));
}

// v made orthogonal to the unit vector w, normalized.
vec3 orthogonal_to(vec3 v, vec3 w) { return normalize(v - dot(v, w) * w); }

// A direction drawn uniformly in the solid angle of triangle l seen from x (Arvo 1995:
// u.x picks the sub-triangle's area, u.y the point along its arc), returned as the
// barycentrics (b1, b2) of the point it meets, as sample_triangle's.
vec2 sample_spherical_triangle(GpuLight l, vec3 x, vec2 u) {
    vec3 p0 = l.a.xyz, p1 = l.a.xyz + l.b.xyz, p2 = l.a.xyz + l.c.xyz;
    vec3 a = normalize(p0 - x), b = normalize(p1 - x), c = normalize(p2 - x);
    vec3 n_ab = normalize(cross(a, b)), n_bc = normalize(cross(b, c)), n_ca = normalize(cross(c, a));
    // The spherical triangle's angles at a, b, c.
    float alpha = angle_between(n_ab, -n_ca);
    float beta = angle_between(n_bc, -n_ab);
    float gamma = angle_between(n_ca, -n_bc);
    // The sub-triangle of area A' = u.x A: the point c' on arc a-c that bounds it.
    float ap_pi = mix(PI, alpha + beta + gamma, u.x);
    float cos_alpha = cos(alpha), sin_alpha = sin(alpha);
    float sin_phi = sin(ap_pi) * cos_alpha - cos(ap_pi) * sin_alpha;
    float cos_phi = cos(ap_pi) * cos_alpha + sin(ap_pi) * sin_alpha;
    float k1 = cos_phi + cos_alpha;
    float k2 = sin_phi - sin_alpha * dot(a, b);
    float cos_bp = (k2 + (k2 * cos_phi - k1 * sin_phi) * cos_alpha) / ((k2 * sin_phi + k1 * cos_phi) * sin_alpha);
    cos_bp = clamp(cos_bp, -1.0, 1.0);
    float sin_bp = sqrt(max(0.0, 1.0 - cos_bp * cos_bp));
    vec3 cp = cos_bp * a + sin_bp * orthogonal_to(c, a);
    // The direction along the arc from b to c', uniform in the sub-triangle's area.
    float cos_t = 1.0 - u.y * (1.0 - dot(cp, b));
    float sin_t = sqrt(max(0.0, 1.0 - cos_t * cos_t));
    vec3 w = cos_t * b + sin_t * orthogonal_to(cp, b);
    // The barycentrics of the point it meets (Moller & Trumbore), clamped into the triangle.
    vec3 e1 = l.b.xyz, e2 = l.c.xyz;
    vec3 s1 = cross(w, e2);
    float divisor = dot(s1, e1);
    if (divisor == 0.0) return vec2(1.0 / 3.0);
    vec3 s = x - p0;
    float b1 = clamp(dot(s, s1) / divisor, 0.0, 1.0);
    float b2 = clamp(dot(w, cross(s, e1)) / divisor, 0.0, 1.0);
    float sum = b1 + b2;
    if (sum > 1.0) { b1 /= sum; b2 /= sum; }
    return vec2(b1, b2);
}

// The solid-angle pdf of light_illuminate's direction towards a point of area light l at
// squared distance d2 and light cosine cos_l, given the triangle's solid angle omega at
// the shading point (no pick probability).
float area_light_pdf_w(GpuLight l, float omega, float d2, float cos_l) {
    return area_light_by_solid_angle(omega) ? 1.0 / omega : d2 / (cos_l * l.d.w);
}

// The pdf, per unit area at the light, with which light_illuminate at x samples point y
// of area light `index` (no pick probability; 0 behind the light): what the MIS weights
// of an emitter hit and of a light subpath's start need (glsl/mis_weights.glsl,
// glsl/subpath.glsl).
float area_light_direct_pdf_a(uint index, vec3 x, vec3 y) {
    GpuLight l = light_at(index);
    vec3 d = y - x;
    float d2 = dot(d, d);
    float cos_l = dot(area_light_normal(l), -d) * inversesqrt(d2);
    if (cos_l <= EPS_COSINE_LIGHT) return 0.0;
    return area_light_pdf_w(l, triangle_solid_angle(l, x), d2, cos_l) * cos_l / d2;
}

// Picks a light with probability light_pick_prob (Walker's alias method, one random
// number: slot i = floor(u n); the fraction u n - i below the slot's threshold (d.y)
// keeps light i, else its alias (d.z) is taken). Uniform selection's table keeps every
// slot whole: min(floor(u n), n - 1), SmallVCM's draw.
uint pick_light_at(float u) {
    uint n = params.dims.z;
    float x = u * float(n);
    uint i = min(uint(x), n - 1u);
    GpuLight l = light_at(i);
    return x - float(i) < l.d.y ? i : floatBitsToUint(l.d.z);
}

uint pick_light(inout uint rng) { return pick_light_at(rnd(rng)); }

// The probability that pick_light picks light `index`.
float light_pick_prob(uint index) { return light_at(index).d.x; }

// Next-event estimation's pick of a light for shading point x with geometric normal n
// (n = 0: none), with its probability `prob`: the selection table's (as light subpaths
// start), or with LIGHT_TREE the light tree's for area lights (glsl/light_tree.glsl),
// which depends on x and n; NO_LIGHT where the tree has no light that can shine on x.
// nee_light_prob is the same probability for a given light: the direct pdf of an
// emitter hit takes it at the previous vertex, its emission pdf light_pick_prob.
#ifndef LIGHT_TREE
#define LIGHT_TREE 0
#endif
#if LIGHT_TREE
#include "light_tree.glsl"
#endif

uint nee_pick_light(float u, vec3 x, vec3 n, out float prob) {
#if LIGHT_TREE
    return tree_nee_pick(u, x, n, prob);
#else
    uint li = pick_light_at(u);
    prob = light_pick_prob(li);
    return li;
#endif
}

float nee_light_prob(uint index, vec3 x, vec3 n) {
#if LIGHT_TREE
    return tree_nee_prob(index, x, n);
#else
    return light_pick_prob(index);
#endif
}

// Spot falloff between the outer and inner cone (smoothstep in cos, as glTF suggests).
float spot_falloff(GpuLight l, vec3 dir_from_light) {
    float c = dot(dir_from_light, l.b.xyz);
    float ci = l.b.w, co = l.c.w;
    if (c <= co) return 0.0;
    if (c >= ci) return 1.0;
    float t = (c - co) / max(ci - co, 1e-12);
    return t * t * (3.0 - 2.0 * t);
}

struct LightSample {
    vec3 wi;            // unit direction from the shading point to the light
    float dist;         // distance to the light point (infinite lights: a huge value)
    vec3 radiance;      // Le (area, background), I (point, spot) or E (directional)
    float pdf_w;        // solid-angle pdf of this direction (delta: the factor that
                        // turns radiance into incident radiance: d^2 or 1), no pick prob
    float emission_pdf_w;  // pdf of emitting this ray from the light (SmallVCM's emissionPdfW)
    float cos_light;    // cosine at the light (1 for point-like and infinite lights)
    vec3 light_point;   // the sampled point on the light (finite lights)
    vec3 light_normal;  // its normal (area lights), for the shadow-ray offset
    bool delta;
    bool ok;
};

// A background without a map.
bool is_constant_background(GpuLight l) {
#if HAS_ENVIRONMENT_MAP
    return light_kind(l) == LIGHT_BACKGROUND && !env_has_map(l);
#else
    return light_kind(l) == LIGHT_BACKGROUND;
#endif
}

// Next-event estimation's sample of a constant background (one without a map) is a
// direction `wi` drawn from the BSDF at the receiving point, with that BSDF's solid-angle
// pdf `pdf_w` (its non-delta lobes; glsl/pt.comp connect_to_sky, glsl/camera_subpath.comp
// connect_to_sky): the background's radiance is the same everywhere, so the BSDF is the
// integrand but for visibility. Its direct pdf is therefore the BSDF's at the vertex the
// ray leaves (sky_nee_pdf_w, glsl/subpath.glsl), which light subpaths know only once the
// camera side's direction at their first hit is (SubpathState.sky_first_hit).
LightSample sky_light_sample(uint index, vec3 wi, float pdf_w) {
    LightSample s;
    s.wi = wi;
    s.dist = 1e30;
    s.radiance = light_at(index).radiance.rgb;
    s.pdf_w = pdf_w;
    float r_scene = params.scene_sphere.w;
    s.emission_pdf_w = INV_4PI / (PI * r_scene * r_scene);
    s.cos_light = 1.0;
    s.light_point = vec3(0.0);
    s.light_normal = vec3(0.0);
    s.delta = false;
    s.ok = pdf_w > 0.0 && max3(s.radiance) > 0.0;
    return s;
}

// A light sample for the point x; not for a constant background (sky_light_sample).
LightSample light_illuminate(uint index, vec3 x, vec2 u) {
    GpuLight l = light_at(index);
    uint kind = light_kind(l);
    LightSample s;
    s.ok = false;
    s.delta = light_is_delta(kind);
    s.cos_light = 1.0;
    s.light_normal = vec3(0.0);
    s.radiance = l.radiance.rgb;
    float r_scene = params.scene_sphere.w;
#if HAS_AREA_LIGHTS
    if (kind == LIGHT_AREA) {
        vec3 nl = area_light_normal(l);
        // One-sided: from behind, the whole triangle emits away.
        if (dot(nl, x - l.a.xyz) <= 0.0) return s;
        float omega = triangle_solid_angle(l, x);
        vec2 bc = area_light_by_solid_angle(omega) ? sample_spherical_triangle(l, x, u) : sample_triangle(u);
        vec3 p = l.a.xyz + bc.x * l.b.xyz + bc.y * l.c.xyz;
        vec3 d = p - x;
        float d2 = dot(d, d);
        s.dist = sqrt(d2);
        s.wi = d / s.dist;
        s.cos_light = dot(nl, -s.wi);
        // (Written so that a NaN from a degenerate spherical triangle also rejects.)
        if (!(s.cos_light > EPS_COSINE_LIGHT)) return s;
        s.pdf_w = area_light_pdf_w(l, omega, d2, s.cos_light);
        s.emission_pdf_w = s.cos_light * INV_PI / l.d.w;
        s.light_point = p;
        s.light_normal = nl;
#if HAS_EMISSIVE_TEXTURES
        s.radiance *= emission_tint(floatBitsToUint(l.a.w), bc.x, bc.y);
#endif
#if HAS_ALPHA_MASK
        s.radiance *= emitter_presence(floatBitsToUint(l.a.w), bc.x, bc.y);
#endif
    }
#endif
#if HAS_POINT_LIGHTS || HAS_SPOT_LIGHTS
    if (kind == LIGHT_POINT || kind == LIGHT_SPOT) {
        vec3 d = l.a.xyz - x;
        float d2 = dot(d, d);
        s.dist = sqrt(d2);
        s.wi = d / s.dist;
        s.pdf_w = d2;
#if HAS_POINT_LIGHTS
        if (kind == LIGHT_POINT) s.emission_pdf_w = INV_4PI;
#endif
#if HAS_SPOT_LIGHTS
        if (kind == LIGHT_SPOT) {
            s.radiance *= spot_falloff(l, -s.wi);
            s.emission_pdf_w = 1.0 / (2.0 * PI * (1.0 - l.c.w));
        }
#endif
        s.light_point = l.a.xyz;
    }
#endif
#if HAS_DIRECTIONAL_LIGHTS
    if (kind == LIGHT_DIRECTIONAL) {
        s.wi = -l.b.xyz;
        s.dist = 1e30;
        s.pdf_w = 1.0;
        s.emission_pdf_w = 1.0 / (PI * r_scene * r_scene);
    }
#endif
#if HAS_BACKGROUND
    if (kind == LIGHT_BACKGROUND) {
        // A constant background's samples are sky_light_sample's.
        if (is_constant_background(l)) return s;
#if HAS_ENVIRONMENT_MAP
        s.dist = 1e30;
        bool ok;
        s.radiance *= env_sample(l, u, s.wi, s.pdf_w, ok);
        if (!ok) return s;
        s.emission_pdf_w = s.pdf_w / (PI * r_scene * r_scene);
#endif
    }
#endif
    s.ok = max3(s.radiance) > 0.0;
    return s;
}

// Radiance leaving an area light at the point y of barycentric weights (u, v) of its
// triangle (a hit's) towards `-dir` (the ray direction that hit it, from the vertex x),
// with the pdfs of producing that point by direct sampling from x (area measure, no pick
// probability: area_light_direct_pdf_a) and by emission sampling (solid angle).
vec3 area_light_radiance(uint index, float u, float v, vec3 dir, vec3 x, vec3 y, out float direct_pdf_a,
                         out float emission_pdf_w) {
    GpuLight l = light_at(index);
    vec3 nl = area_light_normal(l);
    float c = dot(nl, -dir);
    direct_pdf_a = 0.0;
    emission_pdf_w = 0.0;
    if (c <= EPS_COSINE_LIGHT) return vec3(0.0);
    direct_pdf_a = area_light_direct_pdf_a(index, x, y);
    emission_pdf_w = c * INV_PI / l.d.w;
#if HAS_EMISSIVE_TEXTURES
    return l.radiance.rgb * emission_tint(floatBitsToUint(l.a.w), u, v);
#else
    return l.radiance.rgb;
#endif
}

// The background seen along `dir` (a ray direction that left the scene), with its direct
// (solid angle) and emission pdfs. A constant background's direct pdf is the BSDF's at the
// vertex the ray left (sky_light_sample), the caller's: 0 here.
vec3 background_radiance(uint index, vec3 dir, out float direct_pdf_w, out float emission_pdf_w) {
    float r = params.scene_sphere.w;
    GpuLight l = light_at(index);
#if HAS_ENVIRONMENT_MAP
    if (env_has_map(l)) {
        vec3 le = l.radiance.rgb * env_eval(l, dir, direct_pdf_w);
        emission_pdf_w = direct_pdf_w / (PI * r * r);
        return le;
    }
#endif
    direct_pdf_w = 0.0;
    emission_pdf_w = INV_4PI / (PI * r * r);
    return l.radiance.rgb;
}

// ---- Emission: a ray leaving a light (light subpaths). Pdfs exclude the pick
// probability. `direct_pdf` is the pdf of choosing the start point by direct sampling
// (area measure for area lights, 1 for delta lights, solid angle for the background),
// as SmallVCM's directPdfA; for area lights it is the area sampler's 1 / area and for a
// constant background the uniform 1 / (4 pi), which a light subpath's first hit replaces
// by the pdf from that point (mis_light_first_hit, glsl/subpath.glsl).
struct LightEmission {
    vec3 pos;
    vec3 dir;
    vec3 energy;        // emitted radiance/intensity times cos (area lights)
    float emission_pdf_w;
    float direct_pdf;
    float cos_light;
    vec3 normal;        // area lights: the emitting side's normal; else 0
    bool delta;
    bool finite;
};

LightEmission light_emit(uint index, vec2 u_pos, vec2 u_dir) {
    GpuLight l = light_at(index);
    uint kind = light_kind(l);
    LightEmission e;
    e.delta = light_is_delta(kind);
    e.finite = !light_is_infinite(kind);
    e.cos_light = 1.0;
    e.normal = vec3(0.0);
    e.energy = l.radiance.rgb;
    vec3 c = params.scene_sphere.xyz;
    float r = params.scene_sphere.w;
#if HAS_AREA_LIGHTS
    if (kind == LIGHT_AREA) {
        vec2 bc = sample_triangle(u_pos);
        e.pos = l.a.xyz + bc.x * l.b.xyz + bc.y * l.c.xyz;
        e.normal = area_light_normal(l);
        vec3 local = sample_cosine_hemisphere(u_dir);
        local.z = max(local.z, EPS_COSINE_LIGHT);
        e.dir = to_world(local, e.normal);
        e.cos_light = local.z;
        float pdf_a = 1.0 / l.d.w;
        e.emission_pdf_w = pdf_a * e.cos_light * INV_PI;
        e.direct_pdf = pdf_a;
        e.energy *= e.cos_light;
#if HAS_EMISSIVE_TEXTURES
        e.energy *= emission_tint(floatBitsToUint(l.a.w), bc.x, bc.y);
#endif
#if HAS_ALPHA_MASK
        e.energy *= emitter_presence(floatBitsToUint(l.a.w), bc.x, bc.y);
#endif
    }
#endif
#if HAS_POINT_LIGHTS
    if (kind == LIGHT_POINT) {
        e.pos = l.a.xyz;
        e.dir = sample_uniform_sphere(u_dir);
        e.emission_pdf_w = INV_4PI;
        e.direct_pdf = 1.0;
    }
#endif
#if HAS_SPOT_LIGHTS
    if (kind == LIGHT_SPOT) {
        // Uniform in the outer cone.
        float co = l.c.w;
        float ct = 1.0 - u_dir.x * (1.0 - co);
        float st = sqrt(max(0.0, 1.0 - ct * ct));
        float phi = 2.0 * PI * u_dir.y;
        e.pos = l.a.xyz;
        e.dir = to_world(vec3(st * cos(phi), st * sin(phi), ct), l.b.xyz);
        e.emission_pdf_w = 1.0 / (2.0 * PI * (1.0 - co));
        e.direct_pdf = 1.0;
        e.energy *= spot_falloff(l, e.dir);
    }
#endif
#if HAS_DIRECTIONAL_LIGHTS || HAS_BACKGROUND
    if (kind == LIGHT_DIRECTIONAL || kind == LIGHT_BACKGROUND) {
        // Directional and background: a disc of the scene's bounding-sphere radius,
        // perpendicular to the direction, placed before the scene.
#if HAS_DIRECTIONAL_LIGHTS
        if (kind == LIGHT_DIRECTIONAL) {
            e.dir = l.b.xyz;
            e.emission_pdf_w = 1.0 / (PI * r * r);
            e.direct_pdf = 1.0;
        }
#endif
#if HAS_BACKGROUND
        if (kind == LIGHT_BACKGROUND) {
#if HAS_ENVIRONMENT_MAP
            if (env_has_map(l)) {
                // Photons travel away from the sampled direction towards the map.
                vec3 to_map;
                bool ok;
                e.energy *= env_sample(l, u_dir, to_map, e.direct_pdf, ok);
                e.dir = -to_map;
                if (!ok) {
                    e.energy = vec3(0.0);
                    e.direct_pdf = 1.0;
                }
            } else
#endif
            {
                e.dir = sample_uniform_sphere(u_dir);
                e.direct_pdf = INV_4PI;
            }
            e.emission_pdf_w = e.direct_pdf / (PI * r * r);
        }
#endif
        vec2 disc = sample_concentric_disc(u_pos);
        vec3 t, b;
        make_frame(e.dir, t, b);
        e.pos = c + r * (disc.x * t + disc.y * b) - r * e.dir;
    }
#endif
    return e;
}

#endif
