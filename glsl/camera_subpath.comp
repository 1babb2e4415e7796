#version 460
// The camera-subpaths pass of bpt, ppm, bpm and vcm (src/render/passes/camera_subpaths.rs),
// SmallVCM's VertexCM camera pass: push.paths_per_invocation pixel samples per invocation
// (path regeneration, common.glsl regen_stride). Traces a camera subpath; at each vertex
// adds emitter hits, connections to the lights (next-event estimation) and to light
// vertices (VERTEX_CONNECTION: to those of light subpath p = this pixel, or with
// CACHE_CONNECTIONS > 0 to that many drawn from all light subpaths), and merges with the
// light vertices within the radius found in the hash grid (VERTEX_MERGING), each
// weighted by the recursive MIS of glsl/subpath.glsl and glsl/mis_weights.glsl. Then
// takes this pixel's splats (the light subpaths' connections to the camera) and adds the
// sum to the film.
// bpt: VERTEX_CONNECTION; bpm: VERTEX_MERGING; vcm: both; ppm: VERTEX_MERGING with
// MERGE_FIRST_VERTEX_ONLY (merging at the first non-specular vertex, without MIS). The
// switches are the fields of CameraKernel (src/render/passes/camera_subpaths.rs); AOV
// (AovKernel) also sums the AOVs (glsl/aov.glsl).
#extension GL_GOOGLE_include_directive : require

#if !defined(VERTEX_CONNECTION) || !defined(VERTEX_MERGING) || !defined(MERGE_FIRST_VERTEX_ONLY) || \
    !defined(CACHE_CONNECTIONS) || !defined(STORE_TEXEL_READS) || !defined(SOBOL)
#error "the switches of CameraKernel (src/render/passes/camera_subpaths.rs) must be defined"
#endif

layout(local_size_x = WORKGROUP_SIZE) in;
#include "scene.glsl"
#define HAS_SPLAT 1
#include "push.glsl"
#include "film.glsl"
#define LV_SCRATCH 0
#include "light_vertex_store.glsl"
#include "subpath.glsl"
#include "mis_weights.glsl"
#include "path_sampler.glsl"
#include "aov.glsl"
#include "roulette.glsl"

// Set by light_vertex_compact.comp (layout there): the earliest iteration of the batch
// whose light vertices did not fit the store.
layout(std430) readonly buffer light_vertex_status { uint lv_first_overflow; uint lv_most_vertices; };

#if VERTEX_MERGING
#if STORE_TEXEL_READS
uniform utextureBuffer grid_start;
uniform utextureBuffer grid_points;
uint grid_start_at(uint b) { return texelFetch(grid_start, int(b)).x; }
uvec4 grid_point_at(uint j) { return texelFetch(grid_points, int(j)); }
#else
layout(std430) readonly buffer grid_start { uint bucket_start[]; };
#if DEVICE_ADDRESSES
#define bucket_points FRAME_GRID_POINTS
#else
layout(std430) readonly buffer grid_points { uvec4 bucket_points[]; };
#endif
uint grid_start_at(uint b) { return bucket_start[b]; }
uvec4 grid_point_at(uint j) { return bucket_points[j]; }
#endif
#include "hash_grid.glsl"
#endif

// Next-event estimation of a constant sky: a direction drawn from the BSDF (its
// non-delta lobes), the sky's integrand but for visibility (lights.glsl
// sky_light_sample), as pt's connect_to_sky.
LightSample connect_to_sky(SubpathState st, uint li, Bsdf b, inout PathSampler ps) {
    return sky_sample_from_bsdf(li, bsdf_sample(b, sample_3d(ps, DIM3_SKY(st.len))));
}

// Next-event estimation: one light sample, weighted against reaching the light by BSDF
// sampling and by the light subpaths (eq. 44-45).
vec3 connect_to_lights(SubpathState st, Surface s, Bsdf b, inout PathSampler ps) {
    float pick;
    uint li = nee_pick_light(sample_1d(ps, DIM1_PICK(st.len)), s.p, s.ng, pick);
    if (li == NO_LIGHT) return vec3(0.0);
    LightSample ls = is_constant_background(light_at(li)) ? connect_to_sky(st, li, b, ps)
                                                          : light_illuminate(li, s.p, sample_2d(ps, DIM2_LIGHT(st.len)));
    if (!ls.ok) return vec3(0.0);
    vec3 f;
    float cos_x;
    float w = nee_eval(st, b, ls, pick, light_pick_prob(li), f, cos_x);
    if (max3(f) <= 0.0) return vec3(0.0);
    if (!light_sample_visible(s.p, s.ng, ls)) return vec3(0.0);
    vec3 tr = segment_transmittance(s.material, s.ng, NO_MATERIAL, vec3(0.0), ls.wi, ls.dist);
    return (w * cos_x / (pick * ls.pdf_w)) * tr * ls.radiance * f;
}

// One vertex connection, unweighted by the light vertex's throughput (eq. 40-41).
vec3 connect_vertices(SubpathState st, Surface s, Bsdf b, LightVertex v) {
#if HAS_DISPERSION
    if (!channels_meet(s.tint.channel, v.tint.channel)) return vec3(0.0);
#endif
    vec3 fc, fl;
    float g;
    float w = connection_eval(st, s.p, b, v, fc, fl, g);
    if (max3(fc) <= 0.0 || max3(fl) <= 0.0) return vec3(0.0);
    if (!visible(s.p, s.ng, v.p, v.n)) return vec3(0.0);
    vec3 dir = v.p - s.p;
    float dist = length(dir);
    vec3 tr = segment_transmittance(s.material, s.ng, v.material, v.n, dir / dist, dist);
    return (w * g) * tr * fc * fl;
}

#if CACHE_CONNECTIONS > 0
// Light-vertex cache (Davidovic et al. 2014, "Progressive Light Transport Simulation on
// the GPU: Survey and Improvements", sec. on the connection strategy): instead of the M_p
// stored vertices of light subpath p = this pixel, each non-delta camera vertex connects
// to n_c = CACHE_CONNECTIONS vertices drawn uniformly from all M = sum_q M_q stored
// vertices of the iteration, each contribution weighted by M / (N_L n_c). Unbiased: with
// C(v) the (MIS-weighted) connection contribution, E[(M / N_L) C(v_i)] over uniform i is
// (1 / N_L) sum_q sum_k C(v_qk), the mean over the N_L independent, identically
// distributed light subpaths of the per-path sum that the SmallVCM layout takes from one
// path, whose expectation is the connection technique's term. The MIS weights are the
// usual bpt/vcm ones: each technique still estimates its own weighted term without bias
// and the weights of all techniques that sample a path still sum to one. (Davidovic et al.
// also count the cache's connections in the weights; measured, that changes the error by
// -1.6% to +4%, so they are SmallVCM's: docs/estimators.md.) Drawing uniformly over vertices (not a path, then one of its
// vertices) keeps the weight M / (N_L n_c) the same for every vertex. Deterministic: the
// store holds the vertices in path order and the draws use this pixel's PCG stream.

// The connections of camera vertex `s` to the cache, times light throughput and weight
// (the caller multiplies by the camera throughput).
vec3 connect_cache(SubpathState st, Surface s, Bsdf b, inout PathSampler ps) {
    uint max_len = max_path_length();
    uint min_len = min_path_length();
    // Light vertices have len >= 1: no path of this camera vertex fits (no draws).
    if (st.len + 2u > max_len) return vec3(0.0);
    uint total = lv_offset_at(push.light_paths);
    if (total == 0u) return vec3(0.0);
    vec3 sum = vec3(0.0);
    for (uint k = 0u; k < uint(CACHE_CONNECTIONS); ++k) {
        LightVertex v = lv_load(rnd_below(total, ps.rng));
        uint len = v.len + 1u + st.len;
        if (len < min_len || len > max_len) continue;  // a draw that contributes 0
        sum += v.thr * connect_vertices(st, s, b, v);
    }
    return sum * (float(total) / (float(push.light_paths) * float(CACHE_CONNECTIONS)));
}
#endif

#if VERTEX_MERGING
// Merging (vertex merging / photon density estimation) at camera vertex `s` with every
// light vertex within the radius: sum of w * f_camera * throughput_light; the caller
// scales by 1 / (pi r^2 N_L). Buckets are visited once each and hold ascending slot
// indices, so the sum's order, and hence the image, is deterministic. Candidates are
// read from grid_points (position bits, slot), contiguous per bucket: the radius test,
// which rejects most of them, loads no index and nothing from the light-vertex store.
vec3 merge(SubpathState st, Surface s, Bsdf b) {
    float r = push.radius;
    float r2 = r * r;
    vec3 origin = params.scene_sphere.xyz - vec3(params.scene_sphere.w);
    uint buckets[8];
    uint nb = hash_grid_query_cells(s.p, origin, r, push.grid_buckets, buckets);
    vec3 sum = vec3(0.0);
    uint max_len = max_path_length();
    uint min_len = min_path_length();
    for (uint i = 0u; i < nb; ++i) {
        uint bucket = buckets[i];
        for (uint j = grid_start_at(bucket); j < grid_start_at(bucket + 1u); ++j) {
            uvec4 e = grid_point_at(j);
            vec3 d = uintBitsToFloat(e.xyz) - s.p;
            if (dot(d, d) > r2) continue;
            LightVertex v = lv_load(e.w);
#if HAS_DISPERSION
            if (!channels_meet(s.tint.channel, v.tint.channel)) continue;
#endif
            uint total = v.len + st.len;
            if (total > max_len || total < min_len) continue;
            float w;
            vec3 f = merge_eval(st, b, v, w);
            if (max3(f) <= 0.0) continue;
            if (MERGE_FIRST_VERTEX_ONLY != 0) w = 1.0;
            sum += w * f * v.thr;
        }
    }
    return sum;
}
#endif

// Starts the camera subpath of `pixel`.
void start_path(uint pixel, out SubpathState st, out PathSampler ps) {
    ps = path_sampler(pixel);
    st.o = params.cam_pos.xyz;
    st.d = camera_sample_at(pixel, sample_2d(ps, DIM2_PIXEL));
    st.thr = vec3(1.0);
    st.eta_scale = 1.0;
    st.len = 1u;
    st.specular = true;
    st.finite_light = true;
    st.from_material = NO_MATERIAL;
    st.from_ng = vec3(0.0);
    st.from_pdf_w = 0.0;
    st.sky_first_hit = false;
    st.from_p = params.cam_pos.xyz;
    st.light = NO_LIGHT;
#if HAS_DISPERSION
    st.channel = NO_CHANNEL;
#endif
    mis_camera_start(st, st.d);
}

// ---- The stages of a camera vertex, in the order main() runs them.

// The subpath left the scene: the segment's transmittance and the background's emission
// (eq. 42-43).
void add_background(inout SubpathState st, inout vec3 L) {
    st.thr *= segment_transmittance(st.from_material, st.from_ng, NO_MATERIAL, vec3(0.0), st.d, 1e30);
    uint bg = background_light();
    if (bg != NO_LIGHT && st.len >= min_path_length()) {
        float dpdf, epdf;
        vec3 le = background_radiance(bg, st.d, dpdf, epdf);
        // A constant sky's next-event samples are the BSDF's (connect_to_sky).
        if (is_constant_background(light_at(bg))) dpdf = st.from_pdf_w;
        L += st.thr * le * mis_weight_hit(st, dpdf, epdf, nee_light_prob(bg, st.from_p, st.from_ng), light_pick_prob(bg),
                                            VERTEX_CONNECTION != 0);
    }
}

// The subpath reached surface `s` of hit `h`: the segment's transmittance
// (glsl/medium.glsl) and the MIS update of the new vertex (eq. 31-36), which the
// emission, connections and merges at `s` use.
void reach_surface(inout SubpathState st, Hit h, Surface s) {
    st.thr *= segment_transmittance(st.from_material, st.from_ng, s.material, s.ng, st.d, h.t);
    mis_on_hit(st, h.t, abs(dot(s.ng, st.d)), false);
}

#if HAS_DISPERSION
// The subpath reached surface `s`: a dispersive glass makes a subpath without a colour
// channel choose one (glsl/lobes/dispersion.glsl); the point carries the subpath's channel.
void take_channel(inout SubpathState st, inout Surface s, inout PathSampler ps) {
    if (channel_needed(st.channel, s.material)) choose_channel(st.channel, st.thr, sample_1d(ps, DIM1_CHANNEL));
    s.tint.channel = st.channel;
}
#endif

// The subpath hit an emitter (eq. 42-43).
void add_emission(SubpathState st, Hit h, Surface s, inout vec3 L) {
    if (s.light != NO_LIGHT && st.len >= min_path_length()) {
        float dpdf_a, epdf;
        vec3 le = area_light_radiance(s.light, h.u, h.v, st.d, st.from_p, s.p, dpdf_a, epdf);
        if (max3(le) > 0.0) {
            float direct_pick = nee_light_prob(s.light, st.from_p, st.from_ng);
            L += st.thr * le * mis_weight_hit(st, dpdf_a, epdf, direct_pick, light_pick_prob(s.light), VERTEX_CONNECTION != 0);
        }
    }
}

#if VERTEX_CONNECTION
// Vertex connection at a non-delta vertex: next-event estimation, then the connections
// to light vertices.
void add_connections(SubpathState st, Surface s, Bsdf b, uint pixel, inout PathSampler ps, inout vec3 L) {
    if (st.len + 1u >= min_path_length()) L += st.thr * connect_to_lights(st, s, b, ps);
#if CACHE_CONNECTIONS > 0
    L += st.thr * connect_cache(st, s, b, ps);
#else
    // Light subpath p = this pixel (SmallVCM), modulo N_L when --light-paths asks for
    // fewer light subpaths than pixels.
    uint max_len = max_path_length();
    uint min_len = min_path_length();
    uint p = pixel % push.light_paths;
    uint end = lv_offset_at(p + 1u);
    for (uint i = lv_offset_at(p); i < end; ++i) {
        LightVertex v = lv_load(i);
        uint total = v.len + 1u + st.len;
        if (total < min_len) continue;
        if (total > max_len) break;
        L += st.thr * v.thr * connect_vertices(st, s, b, v);
    }
#endif
}
#endif

#if VERTEX_MERGING
// Vertex merging at a non-delta vertex: the light vertices within the radius, as a
// density estimate over pi r^2 N_L.
void add_merges(SubpathState st, Surface s, Bsdf b, inout vec3 L) {
    float norm = 1.0 / (PI * push.radius * push.radius * float(push.light_paths));
    L += st.thr * merge(st, s, b) * norm;
}
#endif

// Samples the next direction (Russian roulette as pt's, glsl/roulette.glsl; throughput
// and MIS update); false when the subpath ends.
bool continue_path(inout SubpathState st, Bsdf b, Surface s, inout PathSampler ps) {
    BsdfSample bs = bsdf_sample(b, sample_3d(ps, DIM3_BSDF(st.len)));
    if (!bs.ok) return false;
    st.eta_scale = roulette_eta_scale(st.eta_scale, b, bs.wi);
    float q = roulette_continuation(st.thr * bs.weight, st.eta_scale, st.len);
    if (!take_sample(st, b, s.p, s.ng, bs, q, sample_1d(ps, DIM1_ROULETTE(st.len)))) return false;
    st.len++;
    return true;
}

// This iteration's light vertices did not all fit the store: it is rendered again once
// the store has grown, so nothing of it may reach the film, splats included.
void leave_iteration_out(uint pixel, uint stride, uint end) {
    for (; pixel < end; pixel += stride) splat_take(pixel);
}

void main() {
    // Pixels push.first_path .. + push.count: a submission budget splits the pass
    // (src/gpu/batch.rs); each pixel keeps its index, so the image does not change.
    uint stride = regen_stride(push.count, push.paths_per_invocation);
    uint q = invocation_index();
    if (q >= stride) return;
    uint pixel = push.first_path + q;
    uint end = push.first_path + push.count;
    if (lv_first_overflow <= push.iteration) {
        leave_iteration_out(pixel, stride, end);
        return;
    }
    uint max_len = max_path_length();
    SubpathState st;
    PathSampler ps;
    start_path(pixel, st, ps);
    vec3 L = vec3(0.0);
#if AOV
    AovSample aov = aov_start();
#endif
    bool alive = true;
    // One loop iteration = one vertex of the current subpath; a subpath that ends adds
    // its pixel's value (and splats) to the film, and the next one starts in the same
    // iteration.
    while (true) {
        if (!alive) {
            film_add(pixel, L + splat_take(pixel));
#if AOV
            aov_add(pixel, aov);
            aov = aov_start();
#endif
            pixel += stride;
            if (pixel >= end) break;
            start_path(pixel, st, ps);
            L = vec3(0.0);
        }
        alive = false;
        Hit h;
        if (!trace_path_segment(st.o, st.d, st.len == 1u, h)) {
            add_background(st, L);
            continue;
        }
        Surface s = surface_at(h, st.o, st.d);
        reach_surface(st, h, s);
        add_emission(st, h, s, L);
        if (st.len >= max_len) continue;
#if HAS_DISPERSION
        take_channel(st, s, ps);
#endif
        Bsdf b = bsdf_init(s.material, s.ng, s.ns, -st.d, false, s.tint);
#if AOV
        if (st.len == 1u) aov_first_hit(aov, h.t, s.p);
        aov_surface(aov, b, st.thr);
#endif
        if (!b.valid) continue;
#if VERTEX_CONNECTION
        if (!b.delta) add_connections(st, s, b, pixel, ps, L);
#endif
#if VERTEX_MERGING
        if (!b.delta) {
            add_merges(st, s, b, L);
            if (MERGE_FIRST_VERTEX_ONLY != 0) continue;
        }
#endif
        alive = continue_path(st, b, s, ps);
    }
    COUNT_RAYS_FLUSH();
}
