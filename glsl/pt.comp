#version 460
// Path tracing (push.paths_per_invocation pixel samples per invocation: path
// regeneration, common.glsl regen_stride): BSDF sampling with next-event
// estimation, combined by the balance heuristic (Veach 1997, 9.2; the power heuristic
// lowers no error here: docs/performance.md, "Tried and not kept"). MIS pdfs
// are the BSDF's and the light's only: Russian roulette is not in them.
// Russian roulette as Cycles' (glsl/roulette.glsl), not bsdf.glsl's per-vertex albedo
// rule (which the light subpaths of lt/bpt/vcm keep).
// Absorbing media (glsl/medium.glsl) multiply the throughput of every traced segment and
// the contribution of every light sample by their transmittance; no pdf has it.
// A constant sky's next-event directions come from the BSDF (connect_to_sky), and pass
// specular surfaces as paths of their own (SKY_THROUGH_SPECULAR below).
// Variants (PtKernel, src/render/passes/camera_subpaths.rs): NEE=1 the estimator, NEE=0 pure BSDF
// sampling (emitter hits only, weight 1), for tests; SOBOL: where the random numbers come
// from (glsl/path_sampler.glsl; `--sampler`); AOV: the AOVs are summed too (glsl/aov.glsl).
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require

#if !defined(NEE) || !defined(SOBOL)
#error "NEE and SOBOL must be defined (PtKernel, src/render/passes/camera_subpaths.rs)"
#endif

// Where the scene has specular (delta) surfaces, a constant sky's next-event sample is a
// path of its own through them (a sky branch: connect_to_sky, main), not a shadow ray
// that they block: else the sky seen through glass would be the continuation's alone and
// the visible sky half each, a split that costs more variance than the light sample
// saves (docs/performance.md, "A constant sky").
#define SKY_THROUGH_SPECULAR (NEE == 1 && HAS_BACKGROUND && (HAS_DIELECTRIC || HAS_MIRROR))

layout(local_size_x = WORKGROUP_SIZE) in;

#include "scene.glsl"
#include "push.glsl"
#include "film.glsl"
#include "path_sampler.glsl"
#include "aov.glsl"
#include "roulette.glsl"

// The state of the path being traced.
struct PtPath {
    vec3 o, d;          // ray origin (already offset) and direction
    vec3 thr;           // throughput
    uint len;           // segments so far
    // The surface the current segment leaves (its material and geometric normal; the
    // camera: NO_MATERIAL), for the segment's transmittance (glsl/medium.glsl).
    uint from_material;
    vec3 from_ng;       // (and its NEE pick, with the light tree: nee_light_prob)
    vec3 from_p;        // the vertex it leaves: an emitter hit's NEE pdf depends on it
    float last_pdf;     // solid-angle pdf of the last BSDF sample, for MIS at emitters
    bool last_specular;
    float eta_scale;    // refraction's radiance scaling, undone for the roulette
    // Whether next-event estimation ran at the last non-delta vertex, and where: a
    // constant sky that the path finds after it (through delta vertices only) is weighed
    // against that vertex's light sample (add_background).
    bool sky_nee;
    vec3 sky_nee_p, sky_nee_ng;
#if HAS_DISPERSION
    uint channel;       // the colour channel the path carries, or NO_CHANNEL (glsl/lobes/dispersion.glsl)
#endif
};

// Starts the path of `pixel`.
void start_path(uint pixel, out PtPath path, out PathSampler ps) {
    ps = path_sampler(pixel);
    path.o = params.cam_pos.xyz;
    path.d = camera_sample_at(pixel, sample_2d(ps, DIM2_PIXEL));
    path.thr = vec3(1.0);
    path.last_pdf = 1.0;
    path.eta_scale = 1.0;
    path.last_specular = true;
    path.len = 1u;
    path.from_material = NO_MATERIAL;
    path.from_ng = vec3(0.0);
    path.from_p = params.cam_pos.xyz;
    path.sky_nee = false;
#if HAS_DISPERSION
    path.channel = NO_CHANNEL;
#endif
}

// ---- The stages of a vertex, in the order main() runs them.

// The path left the scene: the segment's transmittance and the background's emission,
// weighted against next-event estimation.
void add_background(inout PtPath path, inout vec3 L) {
    path.thr *= segment_transmittance(path.from_material, path.from_ng, NO_MATERIAL, vec3(0.0), path.d, 1e30);
    uint bg = background_light();
    if (bg != NO_LIGHT && path.len >= min_path_length()) {
        float dpdf, epdf;
        vec3 Le = background_radiance(bg, path.d, dpdf, epdf);
        float wgt = (NEE == 0 || path.last_specular) ? 1.0 : balance(path.last_pdf, nee_light_prob(bg, path.from_p, path.from_ng) * dpdf);
        // A constant sky's light samples are distributed as the BSDF samples and, with
        // SKY_THROUGH_SPECULAR, pass the delta vertices as they do (connect_to_sky): the
        // balance heuristic weighs each 1 / (1 + pick), pick the sky's at the last
        // non-delta vertex.
        if (is_constant_background(light_at(bg)))
            wgt = path.sky_nee ? 1.0 / (1.0 + nee_light_prob(bg, path.sky_nee_p, path.sky_nee_ng)) : 1.0;
        L += path.thr * Le * wgt;
    }
}

// The path hit an emitter at surface `s`: its emission, weighted against next-event
// estimation.
void add_emission(PtPath path, Hit h, Surface s, inout vec3 L) {
    if (s.light != NO_LIGHT && path.len >= min_path_length()) {
        float dpdf_a, epdf;
        vec3 Le = area_light_radiance(s.light, h.u, h.v, path.d, path.from_p, s.p, dpdf_a, epdf);
        if (max3(Le) > 0.0) {
            float cos_l = abs(dot(s.ng, path.d));
            float dpdf_w = dpdf_a * h.t * h.t / cos_l;
            float pick = nee_light_prob(s.light, path.from_p, path.from_ng);
            float wgt = (NEE == 0 || path.last_specular) ? 1.0 : balance(path.last_pdf, pick * dpdf_w);
            L += path.thr * Le * wgt;
        }
    }
}

#if HAS_DISPERSION
// The path reached surface `s`: a dispersive glass makes a path without a colour channel
// choose one (glsl/lobes/dispersion.glsl); the point carries the path's channel.
void take_channel(inout PtPath path, inout Surface s, inout PathSampler ps) {
    if (channel_needed(path.channel, s.material)) choose_channel(path.channel, path.thr, sample_1d(ps, DIM1_CHANNEL));
    s.tint.channel = path.channel;
}
#endif

#if NEE
#if HAS_BACKGROUND
// Next-event estimation of a constant sky, picked with probability `pick`: a direction
// drawn from the BSDF, the sky's integrand but for visibility, so that the light sample
// is distributed as the BSDF sample is (which finds the sky too: add_background) and the
// balance heuristic weighs them 1 / (1 + pick) each per unit of pick. A cosine about the
// normal weighs a glossy lobe's samples against diffuse ones instead (docs/performance.md,
// "A constant sky"). A specular direction is left to the BSDF sample (weight 1 there).
// With SKY_THROUGH_SPECULAR the sample becomes `branch`, a path that main traces through
// delta vertices to the sky (add_background weighs it); returns whether it did.
bool connect_to_sky(PtPath path, Surface s, BsdfSample bs, uint sky, float pick, inout vec3 L, out PtPath branch) {
    branch = path;
    if (!bs.ok || bs.specular) return false;
#if SKY_THROUGH_SPECULAR
    branch.thr *= bs.weight;
    branch.last_pdf = bs.pdf;
    branch.last_specular = false;
    branch.o = offset_ray(s.p, s.ng, bs.wi, scene_radius());
    branch.d = bs.wi;
    branch.from_material = s.material;
    branch.from_ng = s.ng;
    branch.from_p = s.p;
    branch.sky_nee = true;
    branch.sky_nee_p = s.p;
    branch.sky_nee_ng = s.ng;
    branch.len++;
    return true;
#else
    LightSample ls;
    ls.wi = bs.wi;
    ls.dist = 1e30;
    if (!light_sample_visible(s.p, s.ng, ls)) return false;
    vec3 tr = segment_transmittance(s.material, s.ng, NO_MATERIAL, vec3(0.0), bs.wi, ls.dist);
    // f cos / (pick pdf) x balance(pick pdf, pdf), pdf the BSDF's: bs.weight / (1 + pick).
    L += path.thr * tr * bs.weight * light_at(sky).radiance.rgb / (1.0 + pick);
    return false;
#endif
}
#endif

// Next-event estimation at a non-delta vertex: one light sample, weighted against BSDF
// sampling. Returns a constant sky where it picks one, with its probability in `pick`,
// for draw_bsdf_samples; else NO_LIGHT.
uint connect_to_lights(PtPath path, Surface s, Bsdf b, inout PathSampler ps, inout vec3 L, out float pick) {
    uint li = nee_pick_light(sample_1d(ps, DIM1_PICK(path.len)), s.p, s.ng, pick);
    if (li == NO_LIGHT) return NO_LIGHT;
#if HAS_BACKGROUND
    if (is_constant_background(light_at(li))) return li;
#endif
    LightSample ls = light_illuminate(li, s.p, sample_2d(ps, DIM2_LIGHT(path.len)));
    if (!ls.ok) return NO_LIGHT;
    float pf, pr;
    vec3 f = bsdf_eval(b, ls.wi, pf, pr);
    if (max3(f) <= 0.0) return NO_LIGHT;
    if (!light_sample_visible(s.p, s.ng, ls)) return NO_LIGHT;
    float wgt = ls.delta ? 1.0 : balance(pick * ls.pdf_w, pf);
    float cos_x = bsdf_cos(b, ls.wi);
    vec3 tr = segment_transmittance(s.material, s.ng, NO_MATERIAL, vec3(0.0), ls.wi, ls.dist);
    L += path.thr * tr * f * ls.radiance * (wgt * cos_x / (pick * ls.pdf_w));
    return NO_LIGHT;
}
#endif

// The vertex's BSDF samples, at one call site (with bsdf_sample inlined twice SwiftShader
// crashed on the generic kernel, which has every lobe): where next-event estimation
// picked a constant sky (`sky`, with probability `pick`), first the sky's light sample
// (connect_to_sky, which may make it `branch`: returns whether it did); then the
// continuation `bs`, from dimension `dim` (DIM3_BSDF, or DIM3_SKY_BRANCH on a branch).
bool draw_bsdf_samples(PtPath path, Surface s, Bsdf b, uint sky, float pick, uint dim, inout PathSampler ps,
                       inout vec3 L, out BsdfSample bs, out PtPath branch) {
    bool branched = false;
    branch = path;
    [[dont_unroll]] for (uint k = sky != NO_LIGHT ? 0u : 1u; k < 2u; k++) {
        bs = bsdf_sample(b, sample_3d(ps, k == 0u ? DIM3_SKY(path.len) : dim));
#if NEE && HAS_BACKGROUND
        if (k == 0u) branched = connect_to_sky(path, s, bs, sky, pick, L, branch);
#endif
    }
    return branched;
}

// Takes the BSDF sample `bs` as the next direction and plays Russian roulette (not on a
// sky branch: `roulette` false); false when the path ends.
bool continue_path(inout PtPath path, Surface s, Bsdf b, BsdfSample bs, bool roulette, inout PathSampler ps) {
    if (!bs.ok) return false;
    path.thr *= bs.weight;
    path.eta_scale = roulette_eta_scale(path.eta_scale, b, bs.wi);
    path.last_pdf = bs.pdf;
    path.last_specular = bs.specular;
    if (max3(path.thr) <= 0.0) return false;
    // Russian roulette (glsl/roulette.glsl); not part of the MIS pdfs (as pbrt-v4).
    float p = roulette ? roulette_continuation(path.thr, path.eta_scale, path.len) : 1.0;
    if (p < 1.0) {
        if (sample_1d(ps, DIM1_ROULETTE(path.len)) >= p) return false;
        path.thr /= p;
    }
    path.o = offset_ray(s.p, s.ng, bs.wi, scene_radius());
    path.d = bs.wi;
    path.from_material = s.material;
    path.from_ng = s.ng;
    path.from_p = s.p;
    path.len++;
    return true;
}

void main() {
    // Pixels push.first_path .. + push.count: a submission budget splits the pass
    // (src/gpu/batch.rs); each pixel keeps its index, so the image does not change.
    uint stride = regen_stride(push.count, push.paths_per_invocation);
    uint q = invocation_index();
    if (q >= stride) return;
    uint pixel = push.first_path + q;
    uint end = push.first_path + push.count;
    uint max_len = max_path_length();
    PtPath path;
    PathSampler ps;
    start_path(pixel, path, ps);
    vec3 L = vec3(0.0);
#if AOV
    AovSample aov = aov_start();
#endif
    bool alive = true;
#if SKY_THROUGH_SPECULAR
    // `path` is a sky branch (connect_to_sky) while `held`, the path it left, waits.
    bool on_branch = false, held_alive = false;
    PtPath held;
#else
    const bool on_branch = false;
#endif
    // One loop iteration = one vertex of the current path; a path that ends adds its
    // pixel's value to the film, and the next one starts in the same iteration.
    while (true) {
#if SKY_THROUGH_SPECULAR
        if (!alive && on_branch) {
            // The branch ended: back to the path it left.
            path = held;
            alive = held_alive;
            on_branch = false;
        }
#endif
        if (!alive) {
            film_add(pixel, L);
#if AOV
            aov_add(pixel, aov);
            aov = aov_start();
#endif
            pixel += stride;
            if (pixel >= end) break;
            start_path(pixel, path, ps);
            L = vec3(0.0);
        }
        alive = false;
        Hit h;
        if (!trace_path_segment(path.o, path.d, path.len == 1u, h)) {
            add_background(path, L);
            continue;
        }
        Surface s = surface_at(h, path.o, path.d);
        path.thr *= segment_transmittance(path.from_material, path.from_ng, s.material, s.ng, path.d, h.t);
        // A branch is the sky's light sample: emitters are the continuation's.
        if (!on_branch) add_emission(path, h, s, L);
        if (path.len >= max_len) continue;
#if HAS_DISPERSION
        take_channel(path, s, ps);
#endif
        Bsdf b = bsdf_init(s.material, s.ng, s.ns, -path.d, false, s.tint);
#if AOV
        if (!on_branch) {
            if (path.len == 1u) aov_first_hit(aov, h.t, s.p);
            aov_surface(aov, b, path.thr);
        }
#endif
        // A branch passes delta vertices only.
        if (!b.valid || (on_branch && !b.delta)) continue;
        uint sky = NO_LIGHT;
        float sky_pick = 0.0;
        if (!b.delta) {
            path.sky_nee = NEE == 1 && path.len + 1u >= min_path_length();
            path.sky_nee_p = s.p;
            path.sky_nee_ng = s.ng;
        }
#if !SKY_THROUGH_SPECULAR
        else path.sky_nee = false;
#endif
#if NEE
        if (!b.delta && path.len + 1u >= min_path_length()) sky = connect_to_lights(path, s, b, ps, L, sky_pick);
#endif
        BsdfSample bs;
        PtPath branch;
        bool branched = draw_bsdf_samples(path, s, b, sky, sky_pick,
                                          on_branch ? DIM3_SKY_BRANCH(path.len) : DIM3_BSDF(path.len), ps, L, bs,
                                          branch);
        // A specular component's direction is not the sky sample's (connect_to_sky): the
        // sky it finds, also through delta vertices, is the continuation's alone.
        if (bs.specular && !b.delta) path.sky_nee = false;
        alive = continue_path(path, s, b, bs, !on_branch, ps);
#if SKY_THROUGH_SPECULAR
        if (branched) {
            held = path;
            held_alive = alive;
            path = branch;
            alive = on_branch = true;
        }
#endif
    }
    COUNT_RAYS_FLUSH();
}
