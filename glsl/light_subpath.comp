#version 460
// The light-subpaths pass (src/render/passes/light_subpaths.rs), SmallVCM's VertexCM light
// pass: one dispatch per chunk of push.count light subpaths from push.first_path on,
// push.paths_per_invocation per invocation (path regeneration, common.glsl
// regen_stride). Samples an emitter and traces; at every non-delta vertex stores the
// vertex in the chunk's scratch slots (STORE_VERTICES; light_vertex_compact.comp then
// moves them into the light-vertex store) and connects it to the camera
// (CONNECT_TO_CAMERA, a splat). LIGHT_TRACE_ONLY: pure light tracing (weight 1), which
// also connects the emitting point of area lights to the camera so that directly
// visible emitters are rendered. The switches are the fields of LightKernel
// (src/render/passes/light_subpaths.rs).
// A light subpath's random numbers are a PCG stream that depends on its index and the
// iteration only, so the image does not depend on the chunks. (Not a Sobol sequence per
// light subpath as the camera's per pixel: a pixel receives different light subpaths'
// contributions in every iteration, so stratifying a light subpath over iterations does
// not stratify a pixel's estimate.)
#extension GL_GOOGLE_include_directive : require

#if !defined(STORE_VERTICES) || !defined(CONNECT_TO_CAMERA) || !defined(LIGHT_TRACE_ONLY)
#error "the switches of LightKernel (src/render/passes/light_subpaths.rs) must be defined"
#endif

layout(local_size_x = WORKGROUP_SIZE) in;
#include "scene.glsl"
#define HAS_SPLAT 1
#include "push.glsl"
#include "film.glsl"
// The light kernel writes the store's scratch slots and reads nothing of the store.
#define STORE_TEXEL_READS 0
#define LV_SCRATCH STORE_VERTICES
#include "light_vertex_store.glsl"
#include "subpath.glsl"
#include "mis_weights.glsl"

// Starts light subpath `path`: samples its emitter (and with LIGHT_TRACE_ONLY connects
// the emitting point to the camera); false when it has nothing to trace.
bool start_path(uint path, out SubpathState st, out uint rng) {
    rng = rng_init(params.misc.x, push.iteration, path, 1u);
#if HAS_DISPERSION
    st.channel = NO_CHANNEL;
#endif
    uint nl = light_count();
    uint li = pick_light(rng);
    float pick = light_pick_prob(li);
    vec2 u_pos = rnd2(rng);
    vec2 u_dir = rnd2(rng);
    LightEmission e = light_emit(li, u_pos, u_dir);
    float emission_pdf = e.emission_pdf_w * pick;
    float direct_pdf = e.direct_pdf * pick;
    st.len = 1u;
    if (!(max3(e.energy) > 0.0 && emission_pdf > 0.0)) return false;
#if LIGHT_TRACE_ONLY
    // The emitting point itself, seen by the camera (area lights only; the others
    // cannot be seen). Estimator: Le W_e G / (pick pdf_A) / N_L.
    if (nl > 0u && e.finite && !e.delta && dot(e.normal, e.normal) > 0.0) {
        vec2 raster;
        if (camera_raster(e.pos, raster)) {
            vec3 to_cam = params.cam_pos.xyz - e.pos;
            float dist = length(to_cam);
            to_cam /= dist;
            float cos_l = dot(e.normal, to_cam);
            // The camera is on the emitting (front) side: camera_segment_clear suffices.
            if (cos_l > EPS_COSINE_LIGHT && camera_segment_clear(e.pos, e.normal)) {
                float cos_cam = dot(params.cam_forward.xyz, -to_cam);
                float plane = params.cam_pos.w;
                float we_g = plane * plane / (cos_cam * cos_cam * cos_cam) * cos_l / (dist * dist);
                vec3 le = e.energy / e.cos_light;  // radiance
                splat_add(uint(raster.y) * image_width() + uint(raster.x),
                          le * we_g / (direct_pdf * float(push.light_paths)));
            }
        }
    }
#endif
    st.o = e.normal != vec3(0.0) ? offset_ray(e.pos, e.normal, e.dir, scene_radius()) : e.pos;
    st.d = e.dir;
    st.thr = e.energy / emission_pdf;
    st.finite_light = e.finite;
    st.specular = true;
    st.from_material = NO_MATERIAL;
    st.from_ng = vec3(0.0);
    st.from_pdf_w = 0.0;
    st.sky_first_hit = false;
    st.from_p = e.pos;
    st.light = li;
    st.eta_scale = 1.0;
    mis_light_start(st, emission_pdf, direct_pdf, e.cos_light, e.delta, e.finite);
    return true;
}

// ---- The stages of a light vertex, in the order main() runs them.

#if STORE_VERTICES
// Writes the subpath's vertex at surface `s` to scratch slot `slot`.
void store_vertex(uint slot, SubpathState st, Surface s) {
    LightVertex v;
    v.p = s.p; v.thr = st.thr; v.wo = -st.d; v.n = s.ng; v.ns = s.ns; v.tint = s.tint;
    v.material = s.material; v.len = st.len;
    v.dvcm = st.dvcm; v.dvc = st.dvc; v.dvm = st.dvm; v.sky_first_hit = st.sky_first_hit;
    lv_store(slot, v);
}
#endif

// Connects a light-subpath surface vertex to the camera and splats the contribution,
// weighted by eq. 46-47 (docs/smallvcm.md 4.4.10). `weight_one` disables MIS (pure light
// tracing).
// p lies on a sphere when `sphere`, else on a triangle of winding normal ng.
void connect_to_camera(SubpathState st, vec3 p, vec3 ng, bool sphere, Bsdf b, bool weight_one) {
    float w, camera_pdf_a, importance;
    vec3 f;
    vec2 raster;
    if (!camera_connection_eval(st, p, b, weight_one, w, f, camera_pdf_a, importance, raster)) return;
    if (max3(f) <= 0.0) return;
    vec3 to_cam = params.cam_pos.xyz - p;
    float dist = length(to_cam);
    vec3 tr = segment_transmittance(b.material, ng, NO_MATERIAL, vec3(0.0), to_cam / dist, dist);
    vec3 contrib = (w / float(push.light_paths)) * st.thr * tr * f * importance;
    if (max3(contrib) <= 0.0) return;
    if (!visible_to_camera(p, ng, b.material, sphere)) return;
    uint pixel = uint(raster.y) * image_width() + uint(raster.x);
    splat_add(pixel, contrib);
}

// Samples the next direction (Russian roulette, throughput and MIS update); false when
// the subpath ends.
bool continue_path(inout SubpathState st, Bsdf b, Surface s, inout uint rng) {
    vec3 u_bsdf = vec3(rnd2(rng), rnd(rng));
    if (!scatter(st, b, s.p, s.ng, u_bsdf, rnd(rng))) return false;
    st.len++;
    return true;
}

// Ends the chunk's light subpath `q` with `stored` vertices in its scratch slots.
void finish_path(uint q, uint stored) {
#if STORE_VERTICES
    lv_chunk_count[q] = stored;  // scanned before light_vertex_compact.comp
#endif
}

void main() {
    uint stride = regen_stride(push.count, push.paths_per_invocation);
    uint q = invocation_index();  // the light subpath's index in the chunk
    if (q >= stride) return;
    uint max_len = max_path_length();
    SubpathState st;
    uint rng;
    uint stored = 0u;
    bool alive = start_path(push.first_path + q, st, rng);
    // One loop iteration = one segment of the current subpath; a subpath that ends is
    // finished and the next one started in the same iteration.
    while (true) {
        if (!alive) {
            finish_path(q, stored);
            q += stride;
            if (q >= push.count) break;
            stored = 0u;
            alive = start_path(push.first_path + q, st, rng);
            if (!alive) continue;
        }
        alive = false;
        // A vertex at length len only makes paths of len + 1 segments or more (stored
        // for connections and merges, or connected to the camera): with max_len = 1
        // there is nothing to trace (and no slot to store in: lv_slots() = 0).
        if (st.len + 1u > max_len) continue;
        Hit h;
        if (!trace_closest(st.o, st.d, 0.0, 1e30, h)) continue;
        Surface s = surface_at(h, st.o, st.d);
        // The segment's transmittance (glsl/medium.glsl) before the vertex is stored: light
        // vertices (connections, merges) carry it in their throughput.
        st.thr *= segment_transmittance(st.from_material, st.from_ng, s.material, s.ng, st.d, h.t);
#if HAS_DISPERSION
        // A dispersive glass: the subpath's colour channel (glsl/lobes/dispersion.glsl).
        if (channel_needed(st.channel, s.material)) choose_channel(st.channel, st.thr, rnd(rng));
        s.tint.channel = st.channel;
#endif
        Bsdf b = bsdf_init(s.material, s.ng, s.ns, -st.d, true, s.tint);
        if (!b.valid) continue;
        if (st.len == 1u) mis_light_first_hit(st, s.p, s.ng);
        mis_on_hit(st, h.t, abs(dot(s.ng, st.d)), st.len == 1u && !st.finite_light);
        if (!b.delta) {
#if STORE_VERTICES
            store_vertex(q * lv_slots() + stored, st, s);
            stored += 1u;
#endif
#if CONNECT_TO_CAMERA
            if (st.len + 1u >= min_path_length())
                connect_to_camera(st, s.p, s.ng, h.is_sphere, b, LIGHT_TRACE_ONLY != 0);
#endif
        }
        if (st.len + 2u > max_len) continue;
        alive = continue_path(st, b, s, rng);
    }
    COUNT_RAYS_FLUSH();
}
