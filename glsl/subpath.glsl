// The state of a subpath being traced, camera or light, with the recursive MIS
// quantities of Georgiev, "Implementing Vertex Connection and Merging" (2012), as
// SmallVCM's vertexcm.hxx keeps them; "eq. N" is equation N of that report.
//
// dvcm, dvc, dvm are partial sums over the subpath's earlier vertices of how much more
// likely the other techniques are to sample the path than this one: the weights of
// glsl/mis_weights.glsl finish them at the vertex where a path is completed (eq. 37:
// w = 1 / (w_light + 1 + w_camera)). Per iteration the kernels take push.mis_vm =
// eta = pi r^2 N_L when merging is on (else 0) and push.mis_vc = 1 / eta when vertex
// connections are on (else 0): each technique's count of samples in the balance
// heuristic (src/render/radius.rs).
//
// Used by light_subpath.comp, camera_subpath.comp and the debug kernel
// tests/mis_weights.comp, which include scene.glsl and push.glsl first.
#ifndef SUBPATH_GLSL
#define SUBPATH_GLSL

struct SubpathState {
    vec3 o;            // ray origin (already offset) and direction
    vec3 d;
    vec3 thr;          // path throughput
    uint len;          // segments so far
    float dvcm, dvc, dvm;
    bool specular;     // all scattering events so far were specular (camera: since the eye)
    bool finite_light; // light subpaths: started on a finite light
    // The surface the current segment leaves (material, geometric normal; NO_MATERIAL at
    // the camera and at a light), for the segment's transmittance (glsl/medium.glsl).
    uint from_material;
    vec3 from_ng;
    float from_pdf_w;  // the solid-angle pdf the segment's direction was sampled with there
                       // (the BSDF's, without roulette; 0: specular, the camera, a light)
    // The vertex the current segment leaves (the camera, the light point, a surface point):
    // the direct pdf of an emitter hit depends on it (lights.glsl area_light_direct_pdf_a),
    // and with the light tree its pick too, on it and from_ng (nee_light_prob).
    vec3 from_p;
    uint light;        // light subpaths: the light they start on
    // Light subpaths from a constant sky, at their first hit y1: dvcm leaves out
    // next-event estimation's pdf of the sky's direction at y1, the BSDF's given the
    // direction on the camera side (sky_nee_pdf_w), which each technique that completes
    // the path there knows (dvcm_at) and the scatter from y1 puts in (take_sample).
    bool sky_first_hit;
    float eta_scale;   // camera subpaths: undoes refraction's radiance scaling for the roulette
#if HAS_DISPERSION
    uint channel;      // the colour channel the subpath carries, or NO_CHANNEL (glsl/lobes/dispersion.glsl)
#endif
};

// Light subpath start (eq. 31-33; delta lights eq. 48-50; docs/smallvcm.md 4.4.2).
// `emission_pdf` and `direct_pdf` include the light-pick probability.
void mis_light_start(inout SubpathState st, float emission_pdf, float direct_pdf, float cos_light, bool delta,
                     bool finite) {
    st.dvcm = direct_pdf / emission_pdf;
    st.dvc = delta ? 0.0 : (finite ? cos_light : 1.0) / emission_pdf;
    st.dvm = st.dvc * push.mis_vc;
}

// Next-event estimation's solid-angle pdf of the direction `wi` towards a constant sky at
// a vertex with BSDF `b` whose wo is the camera side's: the BSDF's own (its non-delta
// lobes; lights.glsl sky_light_sample).
float sky_nee_pdf_w(Bsdf b, vec3 wi) {
    float pf, pr;
    bsdf_eval(b, wi, pf, pr);
    return pf;
}

// Next-event estimation's sample of constant sky `li` from the BSDF sample `bs`: its
// direction with its pdf where bs is a non-delta direction, else none (lights.glsl
// sky_light_sample).
LightSample sky_sample_from_bsdf(uint li, BsdfSample bs) {
    return sky_light_sample(li, bs.wi, bs.ok && !bs.specular ? bs.pdf : 0.0);
}

// Light subpaths from an area light or a constant background: next-event estimation
// samples the start point y0 (the direction st.d) with a pdf that depends on the receiving
// point (solid-angle sampling: lights.glsl), so the direct pdf that mis_light_start took
// (light_emit's: the area sampler's 1 / area) is replaced at the first hit y1, once it is
// known (with mis_on_hit, before anything uses dvcm). A constant background's pdf there
// also depends on the direction towards the camera side: light_emit's 1 / (4 pi) is taken
// out and st.sky_first_hit set (dvcm_at). Other lights: nothing to do. With the light
// tree (LIGHT_TREE) the pick of the direct pdf is also y1's (nee_light_prob at y1 and its
// geometric normal n1), not the selection table's that started the subpath.
void mis_light_first_hit(inout SubpathState st, vec3 y1, vec3 n1) {
#if LIGHT_TREE
    st.dvcm *= nee_light_prob(st.light, y1, n1) / light_pick_prob(st.light);
#endif
    GpuLight l = light_at(st.light);
    if (is_constant_background(l)) {
        st.dvcm /= INV_4PI;
        st.sky_first_hit = true;
    }
    if (light_kind(l) != LIGHT_AREA) return;
    st.dvcm *= area_light_direct_pdf_a(st.light, y1, st.from_p) * l.d.w;
}

// A light vertex's dvcm for a technique that completes the path with `sky_pdf_w`, the
// pdf sky_nee_pdf_w of its direction towards the sky given the camera side's direction
// (read where sky_first_hit; else unused).
float dvcm_at(float dvcm, bool sky_first_hit, float sky_pdf_w) { return sky_first_hit ? dvcm * sky_pdf_w : dvcm; }

// The light subpath leaves its first hit from a constant sky: the camera side's direction
// is the new one, whose reverse pdf is `sky_pdf_w`.
void leave_sky_first_hit(inout SubpathState st, float sky_pdf_w) {
    st.dvcm = dvcm_at(st.dvcm, st.sky_first_hit, sky_pdf_w);
    st.sky_first_hit = false;
}

// Camera subpath start along the primary direction `d` (eq. 31-33; docs/smallvcm.md 4.4.3).
void mis_camera_start(inout SubpathState st, vec3 d) {
    st.dvcm = float(push.light_paths) / camera_pdf_w(d);
    st.dvc = 0.0;
    st.dvm = 0.0;
}

// MIS update on reaching a new vertex at distance `dist` with |cos| `cos_fix` there: the
// part of eq. 31-33 and 34-36 that needs the new vertex (docs/smallvcm.md 4.4.4).
void mis_on_hit(inout SubpathState st, float dist, float cos_fix, bool first_from_infinite) {
    if (!first_from_infinite) st.dvcm *= dist * dist;
    float inv = 1.0 / max(cos_fix, 1e-30);
    st.dvcm *= inv;
    st.dvc *= inv;
    st.dvm *= inv;
}

// MIS update after scattering into a direction with |cos| `cos_wi` (non-specular: eq.
// 34-36; specular: eq. 53-55; docs/smallvcm.md 4.4.5-4.4.6): `pdf` and `pdf_rev` are the
// solid-angle pdfs of that direction and of the reverse one, each times the
// Russian-roulette continuation probability of the vertex sampling it (b.cont_prob,
// cont_prob_from(b, wi)).
void mis_on_scatter(inout SubpathState st, float pdf, float pdf_rev, float cos_wi, bool specular) {
    if (specular) {
        st.dvcm = 0.0;
        st.dvc *= cos_wi;
        st.dvm *= cos_wi;
    } else {
        float k = cos_wi / pdf;
        st.dvc = k * (st.dvc * pdf_rev + st.dvcm + push.mis_vm);
        st.dvm = k * (st.dvm * pdf_rev + st.dvcm * push.mis_vc + 1.0);
        st.dvcm = 1.0 / pdf;
        st.specular = false;
    }
}

// The same update for a given direction `wi` out of a vertex with BSDF `b` (the pdfs are
// evaluated instead of sampled): for the debug kernel, which follows a fixed path. For a
// delta BSDF `wi` must be its specular direction.
void mis_on_scatter_to(inout SubpathState st, Bsdf b, vec3 wi) {
    float cos_wi = bsdf_cos_geometric(b, wi);
    if (b.delta) {
        leave_sky_first_hit(st, 0.0);
        mis_on_scatter(st, 0.0, 0.0, cos_wi, true);
        st.from_pdf_w = 0.0;
        return;
    }
    float pf, pr;
    bsdf_eval(b, wi, pf, pr);
    leave_sky_first_hit(st, pr);
    mis_on_scatter(st, pf * b.cont_prob, pr * cont_prob_from(b, wi), cos_wi, false);
    st.from_pdf_w = pf;
}

// Takes the BSDF sample `bs` (ok) at a vertex as the subpath's next direction, after
// Russian roulette that continues with probability `q` (from `u_roulette`): throughput
// and MIS update. `ng` is the vertex's geometric normal as the surface gives it (not
// turned to wo). Returns false when the subpath ends. The MIS quantities take SmallVCM's
// per-vertex probabilities (b.cont_prob, cont_prob_from) whatever `q` is: evaluated alike
// from either side, they keep every path's weights summing to one, and the light
// subpaths' roulette is that rule (scatter); the camera subpaths' is the throughput's
// (camera_subpath.comp, glsl/roulette.glsl).
bool take_sample(inout SubpathState st, Bsdf b, vec3 p, vec3 ng, BsdfSample bs, float q, float u_roulette) {
    if (u_roulette >= q) return false;
    float cont_rev = bs.specular ? 0.0 : cont_prob_from(b, bs.wi);  // specular: no pdfs
    leave_sky_first_hit(st, bs.specular ? 0.0 : bs.pdf_rev);
    mis_on_scatter(st, bs.pdf * b.cont_prob, bs.pdf_rev * cont_rev, bs.cos_wi, bs.specular);
    st.thr *= bs.weight / q;
    st.o = offset_ray(p, ng, bs.wi, scene_radius());
    st.d = bs.wi;
    st.from_material = b.material;
    st.from_ng = ng;
    st.from_pdf_w = bs.specular ? 0.0 : bs.pdf;
    st.from_p = p;
    return max3(st.thr) > 0.0;
}

// Samples the continuation at a vertex from `u_bsdf` (bsdf_sample's direction and lobe)
// and `u_roulette`, with SmallVCM's roulette (b.cont_prob): take_sample.
bool scatter(inout SubpathState st, Bsdf b, vec3 p, vec3 ng, vec3 u_bsdf, float u_roulette) {
    BsdfSample bs = bsdf_sample(b, u_bsdf);
    return bs.ok && take_sample(st, b, p, ng, bs, b.cont_prob, u_roulette);
}

#endif
