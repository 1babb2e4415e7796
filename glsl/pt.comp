#version 460
// Path tracing (push.paths_per_invocation pixel samples per invocation: path
// regeneration, common.glsl regen_stride): BSDF sampling with next-event
// estimation, combined by the balance heuristic; Russian roulette as bsdf.glsl says.
// Variants (src/render/variants.rs, PtKernel): NEE=1 the estimator, NEE=0 pure BSDF
// sampling (emitter hits only, weight 1), for tests.
#extension GL_GOOGLE_include_directive : require

#ifndef NEE
#error "NEE must be defined (src/render/variants.rs)"
#endif

layout(local_size_x = WORKGROUP_SIZE) in;

#include "scene.glsl"
#include "push.glsl"
#include "film.glsl"

void main() {
    uint stride = regen_stride(push.count, push.paths_per_invocation);
    uint pixel = invocation_index();
    if (pixel >= stride) return;
    float pick = 1.0 / float(light_count());
    uint max_len = max_path_length();
    uint min_len = min_path_length();
    uint rng, len;
    vec3 o, d, thr, L;
    float last_pdf;
    bool last_specular;
    bool alive = false;
    bool started = false;
    // One loop iteration = one vertex of the current path; a path that ends adds its
    // pixel's value to the film, and the next one starts in the same iteration.
    while (true) {
        if (!alive) {
            if (started) {
                film_add(pixel, L);
                pixel += stride;
                if (pixel >= push.count) break;
            }
            started = true;
            rng = rng_init(params.misc.x, push.iteration, pixel, 0u);
            o = params.cam_pos.xyz;
            d = camera_sample(pixel, rng);
            thr = vec3(1.0);
            L = vec3(0.0);
            last_pdf = 1.0;
            last_specular = true;
            len = 1u;
        }
        alive = false;
        Hit h;
        if (!trace_closest(o, d, 0.0, 1e30, h)) {
            uint bg = background_light();
            if (bg != NO_LIGHT && len >= min_len) {
                float dpdf, epdf;
                vec3 Le = background_radiance(bg, d, dpdf, epdf);
                float wgt = (NEE == 0 || last_specular) ? 1.0 : balance(last_pdf, pick * dpdf);
                L += thr * Le * wgt;
            }
            continue;
        }
        Surface s = surface_at(h, o, d);
        if (s.light != NO_LIGHT && len >= min_len) {
            float dpdf_a, epdf;
            vec3 Le = area_light_radiance(s.light, h.u, h.v, d, dpdf_a, epdf);
            if (max3(Le) > 0.0) {
                float cos_l = abs(dot(s.ng, d));
                float dpdf_w = dpdf_a * h.t * h.t / cos_l;
                float wgt = (NEE == 0 || last_specular) ? 1.0 : balance(last_pdf, pick * dpdf_w);
                L += thr * Le * wgt;
            }
        }
        if (len >= max_len) continue;
        Bsdf b = bsdf_init(s.material, s.ng, s.ns, -d, false, s.tint);
        if (!b.valid) continue;
#if NEE
        if (!b.delta && len + 1u >= min_len) {
            LightSample ls = light_illuminate(pick_light(rng), s.p, rnd2(rng));
            if (ls.ok) {
                float pf, pr;
                vec3 f = bsdf_eval(b, ls.wi, pf, pr);
                if (max3(f) > 0.0) {
                    if (light_sample_visible(s.p, s.ng, ls)) {
                        float wgt = ls.delta ? 1.0 : balance(pick * ls.pdf_w, pf * b.cont_prob);
                        float cos_x = bsdf_cos(b, ls.wi);
                        L += thr * f * ls.radiance * (wgt * cos_x / (pick * ls.pdf_w));
                    }
                }
            }
        }
#endif
        BsdfSample bs = bsdf_sample(b, vec3(rnd2(rng), rnd(rng)));
        if (!bs.ok) continue;
        if (rnd(rng) >= b.cont_prob) continue;
        thr *= bs.weight / b.cont_prob;
        last_pdf = bs.pdf * b.cont_prob;
        last_specular = bs.specular;
        o = offset_ray(s.p, s.ng, bs.wi, scene_radius());
        d = bs.wi;
        if (max3(thr) <= 0.0) continue;
        len++;
        alive = true;
    }
    COUNT_RAYS_FLUSH();
}
