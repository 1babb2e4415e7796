#version 460
// Debug kernel: the MIS weights of all techniques that can sample one path sum to 1.
// One invocation per random path y_0 (on a light) ... y_k (the eye), k <= max path length:
//  1. Sample a path with one randomly chosen technique (s light vertices, t = k + 1 - s
//     camera vertices): a light subpath (light_emit + scatter) and a camera subpath
//     (camera_sample + scatter), joined by an emitter hit (s = 0), next-event estimation
//     (s = 1), a vertex connection (2 <= s < k) or a connection to the camera (t = 1).
//     Joins that would contribute nothing (zero BSDF, occluded, off the image) reject the
//     path.
//  2. Re-run the production MIS recursion (glsl/subpath.glsl: mis_light_start,
//     mis_camera_start, mis_on_hit, mis_on_scatter) along the fixed vertex sequence from
//     both ends, with the pdfs evaluated for the path's own directions.
//  3. Evaluate the weight of every technique that can sample the path with the production
//     weight functions (mis_weight_hit, nee_eval, connection_eval,
//     camera_connection_eval, merge_eval), as the kernels would: s = 0 when y_0 can be
//     hit, s = 1 when y_1 is not specular, s >= 2 and t >= 2 when both joined vertices
//     are not specular, t = 1 when y_{k-1} is not specular, and (merging on) a merge at
//     every non-specular inner vertex. Connection techniques need push.mis_vc > 0 (bpt,
//     vcm), merges push.mis_vm > 0 (bpm, vcm), as in glsl/camera_subpath.comp.
// Output: OUT_STRIDE floats per path (layout below); tests/mis_weights.rs checks them.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64) in;
#include "scene.glsl"
#define HAS_SPLAT 1
#include "push.glsl"
#include "film.glsl"
#define STORE_TEXEL_READS 0
#define LV_SCRATCH 0
#include "light_vertex_store.glsl"
#include "subpath.glsl"
#include "mis_weights.glsl"

// Per path: [0] 1 if a path was built, else 0; [1] k (segments); [2] generating s;
// [3] number of techniques that can sample the path; [4] sum of their weights;
// [5] number of weights that are negative or not finite; [6] specular inner vertices;
// [7] light kind of y_0; [8 + s] weight of connection technique s (s = 0..k; -1 if it
// does not apply); [8 + MAXV + i] weight of merging at y_i (i = 1..k-1; -1 if none);
// [31] 1 if y_0 lies on an area light that next-event estimation at y_1 samples by solid
// angle (lights.glsl area_light_by_solid_angle), else 0.
layout(std430) buffer mis_results { float result[]; };

#define MAXV 12u  // vertices y_0..y_k, k <= 11
#define OUT_STRIDE 32u

vec3 vp[MAXV];    // position (y_0 of an infinite light: unused)
vec3 vn[MAXV];    // geometric normal (y_0: the area light's normal, else 0)
vec3 vns[MAXV];   // shading normal (y_1..y_{k-1})
Tint vtint[MAXV]; // the tint (y_1..y_{k-1})
uint vmat[MAXV];  // material
bool vdelta[MAXV];
bool infinite0;   // y_0 lies on an infinite light (directional, background)
vec3 dir0;        // infinite lights: direction of travel from y_0 to y_1

// Unit direction from y_i to y_j (adjacent vertices).
vec3 dir_to(uint i, uint j) {
    if (infinite0 && i == 0u) return dir0;
    if (infinite0 && j == 0u) return -dir0;
    return normalize(vp[j] - vp[i]);
}

// Next-event estimation's light sample for the fixed y_0 as seen from x = y_1 (camera-side
// BSDF b): the production light_illuminate, with its area branch repeated for a given
// point instead of a sampled one (the pdf of the point by solid angle or by area, as
// light_illuminate chooses at x), a map's pdfs taken along the fixed direction and a
// constant background's sample the production sky_light_sample with b's pdf (the pdfs of
// the other lights do not depend on the sample).
LightSample light_sample_fixed(uint li, vec3 x, Bsdf b) {
    uint kind = light_kind(light_at(li));
    if (is_constant_background(light_at(li))) return sky_light_sample(li, -dir0, sky_nee_pdf_w(b, -dir0));
    LightSample s = light_illuminate(li, x, vec2(0.5));
    if (kind == LIGHT_AREA) {
        GpuLight l = light_at(li);
        vec3 d = vp[0] - x;
        float d2 = dot(d, d);
        s.dist = sqrt(d2);
        s.wi = d / s.dist;
        s.cos_light = dot(area_light_normal(l), -s.wi);
        s.pdf_w = area_light_pdf_w(l, triangle_solid_angle(l, x), d2, s.cos_light);
        s.emission_pdf_w = s.cos_light * INV_PI / l.d.w;
        s.light_point = vp[0];
        s.ok = s.cos_light > EPS_COSINE_LIGHT && max3(s.radiance) > 0.0;
    } else if (kind == LIGHT_BACKGROUND) {
        // A map's pdfs depend on the direction.
        s.wi = -dir0;
        float dp, ep;
        s.radiance = background_radiance(li, s.wi, dp, ep);
        s.pdf_w = dp;
        s.emission_pdf_w = ep;
        s.ok = dp > 0.0 && max3(s.radiance) > 0.0;
    }
    return s;
}

void write_out(uint base, uint i, float v) { result[base + i] = v; }

void main() {
    uint idx = invocation_index();
    if (idx >= push.count) return;
    uint base = idx * OUT_STRIDE;
    for (uint i = 0u; i < OUT_STRIDE; ++i) result[base + i] = -1.0;
    write_out(base, 0u, 0.0);
    uint rng = rng_init(params.misc.x, push.iteration, idx, 7u);
    uint maxlen = min(max_path_length(), MAXV - 1u);
    uint k = min(1u + uint(rnd(rng) * float(maxlen)), maxlen);
    uint s_gen = k == 1u ? 0u : min(uint(rnd(rng) * float(k + 1u)), k);
    write_out(base, 1u, float(k));
    write_out(base, 2u, float(s_gen));
    for (uint i = 0u; i < MAXV; ++i) { vdelta[i] = false; vn[i] = vec3(0.0); vp[i] = vec3(0.0); vmat[i] = 0u; }
    infinite0 = false;
    dir0 = vec3(0.0);

    // ---- 1. Sample the path.
    uint li = pick_light(rng);
    // Every technique of the path meets this one light.
    float pick = light_pick_prob(li);
    vec2 u_pos = rnd2(rng);
    vec2 u_dir = rnd2(rng);
    if (s_gen >= 2u) {
        LightEmission e = light_emit(li, u_pos, u_dir);
        if (max3(e.energy) <= 0.0 || e.emission_pdf_w <= 0.0) return;
        vp[0] = e.pos;
        vn[0] = e.normal;
        infinite0 = !e.finite;
        dir0 = e.dir;
        SubpathState st;
        st.sky_first_hit = false;
        st.o = e.normal != vec3(0.0) ? offset_ray(e.pos, e.normal, e.dir, scene_radius()) : e.pos;
        st.d = e.dir;
        st.thr = e.energy / (e.emission_pdf_w * pick);
        st.len = 1u;
        for (uint i = 1u; i < s_gen; ++i) {
            Hit h;
            if (!trace_closest(st.o, st.d, 0.0, 1e30, h)) return;
            Surface s = surface_at(h, st.o, st.d);
            Bsdf b = bsdf_init(s.material, s.ng, s.ns, -st.d, true, s.tint);
            if (!b.valid) return;
            vp[i] = s.p; vn[i] = s.ng; vns[i] = s.ns; vtint[i] = s.tint; vmat[i] = s.material; vdelta[i] = b.delta;
            if (i + 1u < s_gen && !scatter(st, b, s.p, s.ng, vec3(rnd2(rng), rnd(rng)), rnd(rng))) return;
        }
    }
    vp[k] = params.cam_pos.xyz;
    if (s_gen < k) {
        uint pixels = image_width() * image_height();
        uint pixel = min(uint(rnd(rng) * float(pixels)), pixels - 1u);
        SubpathState st;
        st.sky_first_hit = false;
        st.o = params.cam_pos.xyz;
        st.from_p = params.cam_pos.xyz;
        st.d = camera_sample(pixel, rng);
        st.thr = vec3(1.0);
        st.len = 1u;
        for (uint j = 1u; j <= k - s_gen; ++j) {
            uint i = k - j;  // camera subpath length j reaches y_{k-j}
            Hit h;
            bool hit = trace_closest(st.o, st.d, 0.0, 1e30, h);
            if (i == 0u) {  // s = 0: the camera subpath must end on an emitter
                if (!hit) {
                    li = background_light();
                    if (li == NO_LIGHT) return;
                    infinite0 = true;
                    dir0 = -st.d;
                } else {
                    Surface s = surface_at(h, st.o, st.d);
                    if (s.light == NO_LIGHT) return;
                    float dp, ep;
                    if (max3(area_light_radiance(s.light, h.u, h.v, st.d, st.from_p, s.p, dp, ep)) <= 0.0) return;
                    li = s.light;
                    vp[0] = s.p;
                    vn[0] = s.ng;
                }
                break;
            }
            if (!hit) return;
            Surface s = surface_at(h, st.o, st.d);
            Bsdf b = bsdf_init(s.material, s.ng, s.ns, -st.d, false, s.tint);
            if (!b.valid) return;
            vp[i] = s.p; vn[i] = s.ng; vns[i] = s.ns; vtint[i] = s.tint; vmat[i] = s.material; vdelta[i] = b.delta;
            if (j < k - s_gen && !scatter(st, b, s.p, s.ng, vec3(rnd2(rng), rnd(rng)), rnd(rng))) return;
        }
    }
    // Join.
    if (s_gen == 1u) {
        if (vdelta[1]) return;
        Bsdf b = bsdf_init(vmat[1], vn[1], vns[1], dir_to(1u, 2u), false, vtint[1]);
        LightSample ls = is_constant_background(light_at(li)) ? sky_sample_from_bsdf(li, bsdf_sample(b, vec3(u_pos, rnd(rng))))
                                                              : light_illuminate(li, vp[1], u_pos);
        if (!ls.ok) return;
        if (ls.dist >= 1e29) {
            infinite0 = true;
            dir0 = -ls.wi;
        } else {
            vp[0] = ls.light_point;
            vn[0] = ls.light_normal;
        }
        float pf, pr;
        if (max3(bsdf_eval(b, ls.wi, pf, pr)) <= 0.0) return;
        if (!light_sample_visible(vp[1], vn[1], ls)) return;
    } else if (s_gen >= 2u && s_gen < k) {
        uint a = s_gen - 1u, c = s_gen;
        if (vdelta[a] || vdelta[c]) return;
        float pf, pr;
        Bsdf bl = bsdf_init(vmat[a], vn[a], vns[a], dir_to(a, a - 1u), true, vtint[a]);
        Bsdf bc = bsdf_init(vmat[c], vn[c], vns[c], dir_to(c, c + 1u), false, vtint[c]);
        if (max3(bsdf_eval(bl, dir_to(a, c), pf, pr)) <= 0.0) return;
        if (max3(bsdf_eval(bc, dir_to(c, a), pf, pr)) <= 0.0) return;
        if (!visible(vp[a], vn[a], vp[c], vn[c])) return;
    } else if (s_gen == k) {
        uint a = k - 1u;
        if (vdelta[a]) return;
        vec2 raster;
        if (!camera_raster(vp[a], raster)) return;
        float pf, pr;
        Bsdf bl = bsdf_init(vmat[a], vn[a], vns[a], dir_to(a, a - 1u), true, vtint[a]);
        if (max3(bsdf_eval(bl, dir_to(a, k), pf, pr)) <= 0.0) return;
        if (!visible(vp[a], vn[a], params.cam_pos.xyz, vec3(0.0))) return;
    }
    uint kind = light_kind(light_at(li));
    // The light the path ends on (an emitter hit may meet another than the one picked):
    // the light subpaths' pick, and next-event estimation's at y_1.
    pick = light_pick_prob(li);
    float nee_pick = nee_light_prob(li, vp[1], vn[1]);
    // The start of a light subpath leaving y_0 towards y_1: light_emit's pdfs, whose
    // only dependences on the sample are an area light's cosine and an environment map's
    // direction.
    LightEmission e = light_emit(li, vec2(0.5), vec2(0.5));
    vec3 d01 = dir_to(0u, 1u);
    if (kind == LIGHT_AREA) {
        e.cos_light = dot(vn[0], d01);
        if (e.cos_light <= EPS_COSINE_LIGHT) return;
        e.emission_pdf_w = e.direct_pdf * e.cos_light * INV_PI;
    } else if (kind == LIGHT_BACKGROUND && !is_constant_background(light_at(li))) {
        // A map's pdfs along the direction (a constant background's are light_emit's).
        float dp, ep;
        if (max3(background_radiance(li, -d01, dp, ep)) <= 0.0 || dp <= 0.0) return;
        e.direct_pdf = dp;
        e.emission_pdf_w = ep;
    }

    // ---- 2. The MIS quantities of the light subpath at y_1..y_{k-1} and of the camera
    // subpath at y_{k-1}..y_0, on arrival at each vertex.
    SubpathState L[MAXV];
    SubpathState C[MAXV];
    SubpathState st;
    st.len = 0u;
    st.specular = true;
    st.sky_first_hit = false;
    st.from_pdf_w = 0.0;
    st.finite_light = !infinite0;
    mis_light_start(st, e.emission_pdf_w * pick, e.direct_pdf * pick, e.cos_light, e.delta, e.finite);
    st.from_p = vp[0];
    st.light = li;
    st.d = dir_to(0u, 1u);
    for (uint i = 1u; i < k; ++i) {
        vec3 d = dir_to(i - 1u, i);
        st.len = i;
        if (i == 1u) mis_light_first_hit(st, vp[1], vn[1]);
        mis_on_hit(st, i == 1u && infinite0 ? 0.0 : distance(vp[i - 1u], vp[i]), abs(dot(vn[i], d)),
                   i == 1u && infinite0);
        L[i] = st;
        if (i + 1u < k) mis_on_scatter_to(st, bsdf_init(vmat[i], vn[i], vns[i], -d, true, vtint[i]), dir_to(i, i + 1u));
    }
    st.specular = true;
    st.sky_first_hit = false;
    st.from_pdf_w = 0.0;
    mis_camera_start(st, dir_to(k, k - 1u));
    for (uint j = 1u; j <= k; ++j) {
        uint i = k - j;
        vec3 d = dir_to(i + 1u, i);
        st.len = j;
        if (!(i == 0u && infinite0)) mis_on_hit(st, distance(vp[i + 1u], vp[i]), abs(dot(vn[i], d)), false);
        C[i] = st;
        if (i > 0u) mis_on_scatter_to(st, bsdf_init(vmat[i], vn[i], vns[i], -d, false, vtint[i]), dir_to(i, i - 1u));
    }

    // ---- 3. Every technique's weight.
    bool use_vc = push.mis_vc > 0.0;
    bool use_vm = push.mis_vm > 0.0;
    float sum = 0.0;
    uint n = 0u, bad = 0u, n_delta = 0u;
    for (uint i = 1u; i < k; ++i) n_delta += vdelta[i] ? 1u : 0u;
    float w;
    // s = 0: the camera subpath hits the emitter (area lights and the background).
    if (kind == LIGHT_AREA || kind == LIGHT_BACKGROUND) {
        float dp, ep;
        // (Any point of the light: these scenes' lights are untextured, only the side matters.)
        vec3 le = kind == LIGHT_AREA ? area_light_radiance(li, 0.0, 0.0, dir_to(1u, 0u), vp[1], vp[0], dp, ep) : background_radiance(li, dir_to(1u, 0u), dp, ep);
        // A constant sky's direct pdf: the BSDF sample's at y_1 (camera_subpath.comp add_background).
        if (is_constant_background(light_at(li))) dp = C[0].from_pdf_w;
        // Without connections only purely specular camera paths count an emitter hit.
        if (max3(le) > 0.0 && (use_vc || C[0].specular || k == 1u)) {
            w = mis_weight_hit(C[0], dp, ep, nee_pick, pick, use_vc);
            write_out(base, 8u, w);
            sum += w; n += 1u; bad += (w >= 0.0 && !isinf(w)) ? 0u : 1u;
        }
    }
    if (use_vc && k >= 2u) {
        // s = 1: next-event estimation at y_1.
        if (!vdelta[1]) {
            Bsdf b1 = bsdf_init(vmat[1], vn[1], vns[1], dir_to(1u, 2u), false, vtint[1]);
            LightSample ls = light_sample_fixed(li, vp[1], b1);
            vec3 f;
            float cos_x;
            w = nee_eval(C[1], b1, ls, nee_pick, pick, f, cos_x);
            if (!ls.ok || max3(f) <= 0.0) w = -2.0;  // cannot happen for a sampled path
            write_out(base, 9u, w);
            sum += w; n += 1u; bad += (w >= 0.0 && !isinf(w)) ? 0u : 1u;
        }
        // 2 <= s < k: connect light vertex y_{s-1} with camera vertex y_s.
        for (uint s = 2u; s < k; ++s) {
            if (vdelta[s - 1u] || vdelta[s]) continue;
            LightVertex v;
            v.p = vp[s - 1u]; v.n = vn[s - 1u]; v.ns = vns[s - 1u]; v.tint = vtint[s - 1u]; v.wo = dir_to(s - 1u, s - 2u); v.material = vmat[s - 1u];
            v.len = s - 1u; v.dvcm = L[s - 1u].dvcm; v.dvc = L[s - 1u].dvc; v.dvm = L[s - 1u].dvm;
            v.sky_first_hit = L[s - 1u].sky_first_hit;
            vec3 fc, fl;
            float g;
            w = connection_eval(C[s], vp[s], bsdf_init(vmat[s], vn[s], vns[s], dir_to(s, s + 1u), false, vtint[s]), v, fc, fl, g);
            if (max3(fc) <= 0.0 || max3(fl) <= 0.0) w = -2.0;
            write_out(base, 8u + s, w);
            sum += w; n += 1u; bad += (w >= 0.0 && !isinf(w)) ? 0u : 1u;
        }
        // t = 1: light vertex y_{k-1} connected to the camera.
        if (!vdelta[k - 1u]) {
            vec3 f;
            float pdf_a, importance;
            vec2 raster;
            Bsdf b = bsdf_init(vmat[k - 1u], vn[k - 1u], vns[k - 1u], dir_to(k - 1u, k - 2u), true, vtint[k - 1u]);
            if (!camera_connection_eval(L[k - 1u], vp[k - 1u], b, false, w, f, pdf_a, importance, raster) || max3(f) <= 0.0)
                w = -2.0;
            write_out(base, 8u + k, w);
            sum += w; n += 1u; bad += (w >= 0.0 && !isinf(w)) ? 0u : 1u;
        }
    }
    // Merging at every non-specular inner vertex y_i.
    if (use_vm) {
        for (uint i = 1u; i < k; ++i) {
            if (vdelta[i]) continue;
            LightVertex v;
            v.p = vp[i]; v.n = vn[i]; v.ns = vns[i]; v.tint = vtint[i]; v.wo = dir_to(i, i - 1u); v.material = vmat[i];
            v.len = i; v.dvcm = L[i].dvcm; v.dvc = L[i].dvc; v.dvm = L[i].dvm;
            v.sky_first_hit = L[i].sky_first_hit;
            vec3 f = merge_eval(C[i], bsdf_init(vmat[i], vn[i], vns[i], dir_to(i, i + 1u), false, vtint[i]), v, w);
            if (max3(f) <= 0.0) w = -2.0;
            write_out(base, 8u + MAXV + i, w);
            sum += w; n += 1u; bad += (w >= 0.0 && !isinf(w)) ? 0u : 1u;
        }
    }
    write_out(base, 0u, 1.0);
    write_out(base, 3u, float(n));
    write_out(base, 4u, sum);
    write_out(base, 5u, float(bad));
    write_out(base, 6u, float(n_delta));
    write_out(base, 7u, float(kind));
    write_out(base, 31u, kind == LIGHT_AREA && area_light_by_solid_angle(triangle_solid_angle(light_at(li), vp[1])) ? 1.0 : 0.0);
}
