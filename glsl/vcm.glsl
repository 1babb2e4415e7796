// The light-transport state shared by the bidirectional estimators (lt, bpt, and later
// ppm, bpm, vcm): subpath state with the recursive MIS quantities dVCM, dVC, dVM of
// Georgiev et al., "Implementing Vertex Connection and Merging" (2012), and the light-
// vertex store. Technique weights follow docs/smallvcm.md 4.4 (balance heuristic).
//
// Included by light_vertex_store.glsl, which provides what it requires: scene.glsl,
// film.glsl with HAS_SPLAT, `push` (GpuPush), the store read through lv_a_at / lv_b_at
// and, in the light kernel (LV_SCRATCH), the scratch slots lv_scratch_a[] / lv_scratch_b[].
#ifndef VCM_GLSL
#define VCM_GLSL

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
};

// A light vertex's layout (the same in the scratch slots the light kernel writes and in
// the compacted store, glsl/light_vertex_store.glsl), vertex i:
//   a[2i] = (position, dVCM)      a[2i+1] = (throughput, dVC)
//   b[Bi] = (wo, dVM)             b[Bi+1] = (normal, material | length << 24)
//   with HAS_SHADING_NORMALS or HAS_METALLIC_ROUGHNESS_TEXTURES:
//                                 b[Bi+2] = (shading normal, tint.metallic)
//   with HAS_VERTEX_ATTRIBUTES:   b[Bi+LV_TINT] = (tint.rgb, tint.roughness)
// B = 2 + the two (src/render/passes/light_subpaths.rs, LightVertexPlan, sizes the store
// the same way; light_vertex_compact.comp copies B vec4 per vertex). The point's metallic
// and roughness (a metallic-roughness texture's texel) fill the two vec4s' spare w, so a
// scene with that texture needs the normal slot even without shading normals.
#define LV_NORMAL_SLOTS ((HAS_SHADING_NORMALS != 0 || HAS_METALLIC_ROUGHNESS_TEXTURES != 0) ? 1u : 0u)
#define LV_TINT (2u + LV_NORMAL_SLOTS)
#define LV_B_STRIDE (LV_TINT + (HAS_VERTEX_ATTRIBUTES != 0 ? 1u : 0u))
struct LightVertex {
    vec3 p;
    vec3 thr;
    vec3 wo;   // direction towards the previous vertex
    vec3 n;    // geometric normal
    vec3 ns;   // shading normal (== n for flat shading)
    Tint tint; // the point's tint (1 without attributes)
    uint material;
    uint len;        // segments from the light
    float dvcm, dvc, dvm;
};

// Scratch slots per light subpath: a light subpath stores at most max path length - 1
// vertices.
uint lv_slots() { return max_path_length() - 1u; }

#if LV_SCRATCH
// Writes `v` to scratch slot `slot` (the light kernel).
void lv_store(uint slot, LightVertex v) {
    lv_scratch_a[2u * slot] = vec4(v.p, v.dvcm);
    lv_scratch_a[2u * slot + 1u] = vec4(v.thr, v.dvc);
    lv_scratch_b[LV_B_STRIDE * slot] = vec4(v.wo, v.dvm);
    lv_scratch_b[LV_B_STRIDE * slot + 1u] = vec4(v.n, uintBitsToFloat(v.material | (v.len << 24)));
#if HAS_SHADING_NORMALS || HAS_METALLIC_ROUGHNESS_TEXTURES
    lv_scratch_b[LV_B_STRIDE * slot + 2u] = vec4(v.ns, v.tint.metallic);
#endif
#if HAS_VERTEX_ATTRIBUTES
    lv_scratch_b[LV_B_STRIDE * slot + LV_TINT] = vec4(v.tint.rgb, v.tint.roughness);
#endif
}
#endif

// Vertex `slot` of the compacted store.
LightVertex lv_load(uint slot) {
    LightVertex v;
    vec4 a0 = lv_a_at(2u * slot), a1 = lv_a_at(2u * slot + 1u);
    vec4 b0 = lv_b_at(LV_B_STRIDE * slot), b1 = lv_b_at(LV_B_STRIDE * slot + 1u);
    v.p = a0.xyz; v.dvcm = a0.w;
    v.thr = a1.xyz; v.dvc = a1.w;
    v.wo = b0.xyz; v.dvm = b0.w;
    v.n = b1.xyz;
#if HAS_SHADING_NORMALS
    v.ns = lv_b_at(LV_B_STRIDE * slot + 2u).xyz;
#else
    v.ns = v.n;
#endif
    v.tint = no_tint();
#if HAS_VERTEX_ATTRIBUTES
    v.tint.rgb = lv_b_at(LV_B_STRIDE * slot + LV_TINT).xyz;
#endif
#if HAS_METALLIC_ROUGHNESS_TEXTURES
    v.tint.roughness = lv_b_at(LV_B_STRIDE * slot + LV_TINT).w;
    v.tint.metallic = lv_b_at(LV_B_STRIDE * slot + 2u).w;
#endif
    uint info = floatBitsToUint(b1.w);
    v.material = info & 0xffffffu;
    v.len = info >> 24;
    return v;
}

// ---- MIS bookkeeping (docs/smallvcm.md 4.4). "eq. N" below is equation N of Georgiev,
// "Implementing Vertex Connection and Merging" (2012), as SmallVCM's vertexcm.hxx tags
// them; every weight is 1 / (w_light + 1 + w_camera) (eq. 37). Every technique's weight
// is a small function below, used by the production kernels and by the debug kernel
// glsl/tests/mis_weights.comp, which checks that the weights of all techniques that can
// sample one path sum to 1 (docs/estimators.md).

// Light subpath start (eq. 31-33; delta lights eq. 48-50; docs/smallvcm.md 4.4.2).
// `emission_pdf` and `direct_pdf` include the light-pick probability.
void mis_light_start(inout SubpathState st, float emission_pdf, float direct_pdf, float cos_light, bool delta,
                     bool finite) {
    st.dvcm = direct_pdf / emission_pdf;
    st.dvc = delta ? 0.0 : (finite ? cos_light : 1.0) / emission_pdf;
    st.dvm = st.dvc * push.mis_vc;
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
// solid-angle pdfs of that direction and of the reverse one, both times the
// Russian-roulette continuation probability.
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
        mis_on_scatter(st, 0.0, 0.0, cos_wi, true);
        return;
    }
    float pf, pr;
    bsdf_eval(b, wi, pf, pr);
    mis_on_scatter(st, pf * b.cont_prob, pr * b.cont_prob, cos_wi, false);
}

// Camera subpath hits an emitter (area light or background; eq. 42-43, docs/smallvcm.md
// 4.4.8), pdfs without the pick probability: weight 1 / (1 + w_camera), 1 for the primary ray. Without connections
// (ppm, bpm) only purely specular camera paths may see emitters, with weight 1.
float mis_weight_hit(SubpathState st, float direct_pdf, float emission_pdf, float pick, bool use_vc) {
    if (st.len == 1u) return 1.0;
    if (!use_vc) return st.specular ? 1.0 : 0.0;
    float w_camera = direct_pdf * pick * st.dvcm + emission_pdf * pick * st.dvc;
    return 1.0 / (1.0 + w_camera);
}

// Next-event estimation at a camera vertex with BSDF `b` towards light sample `ls` (eq.
// 44-45, docs/smallvcm.md 4.4.9):
// returns the MIS weight, with f the BSDF value (zero: no contribution) and cos_x the
// cosine that multiplies it (bsdf_cos).
float nee_eval(SubpathState st, Bsdf b, LightSample ls, float pick, out vec3 f, out float cos_x) {
    float pf, pr;
    f = bsdf_eval(b, ls.wi, pf, pr);
    cos_x = bsdf_cos(b, ls.wi);
    if (max3(f) <= 0.0) return 0.0;
    pf = ls.delta ? 0.0 : pf * b.cont_prob;
    pr *= b.cont_prob;
    float w_light = pf / (pick * ls.pdf_w);
    float cos_g = bsdf_cos_geometric(b, ls.wi);
    float w_camera = (ls.emission_pdf_w * cos_g / (ls.pdf_w * ls.cos_light)) * (push.mis_vm + st.dvcm + st.dvc * pr);
    return 1.0 / (w_light + 1.0 + w_camera);
}

// Vertex connection between camera vertex `p` (BSDF `b`, state `st`) and light vertex
// `v` (eq. 40-41, docs/smallvcm.md 4.4.11): returns the MIS weight with both BSDF values
// and g, the product of their cosines (bsdf_cos) over the squared distance (fc or fl
// zero: no contribution). Visibility is the caller's.
float connection_eval(SubpathState st, vec3 p, Bsdf b, LightVertex v, out vec3 fc, out vec3 fl, out float g) {
    fl = vec3(0.0);
    g = 0.0;
    vec3 dir = v.p - p;
    float dist2 = dot(dir, dir);
    float dist = sqrt(dist2);
    dir /= dist;
    float cpf, cpr;
    fc = bsdf_eval(b, dir, cpf, cpr);
    if (max3(fc) <= 0.0) return 0.0;
    Bsdf lb = bsdf_init(v.material, v.n, v.ns, v.wo, true, v.tint);
    float lpf, lpr;
    fl = bsdf_eval(lb, -dir, lpf, lpr);
    if (max3(fl) <= 0.0) return 0.0;
    cpf *= b.cont_prob; cpr *= b.cont_prob;
    lpf *= lb.cont_prob; lpr *= lb.cont_prob;
    g = bsdf_cos(b, dir) * bsdf_cos(lb, -dir) / dist2;
    float cos_c = bsdf_cos_geometric(b, dir);
    float cos_l = bsdf_cos_geometric(lb, dir);
    float camera_pdf_a = cpf * cos_l / dist2;  // camera BSDF sampling the light vertex
    float light_pdf_a = lpf * cos_c / dist2;   // light BSDF sampling the camera vertex
    float w_light = camera_pdf_a * (push.mis_vm + v.dvcm + v.dvc * lpr);
    float w_camera = light_pdf_a * (push.mis_vm + st.dvcm + st.dvc * cpr);
    return 1.0 / (w_light + 1.0 + w_camera);
}

// Merging camera vertex (BSDF `b`, state `st`) with light vertex `v` (eq. 38-39,
// docs/smallvcm.md 4.4.12): returns the camera BSDF value towards v's predecessor, and in
// `w` the MIS weight. The light vertices estimate the flux per unit of geometric area, so
// with shading normals f is scaled by |n.wo| / |ng.wo| at the camera vertex: the outgoing
// radiance integrates f L |n.wi| over directions (Veach 5.3), the density gives L |ng.wi|.
vec3 merge_eval(SubpathState st, Bsdf b, LightVertex v, out float w) {
    float pf, pr;
    vec3 f = bsdf_eval(b, v.wo, pf, pr);
#if HAS_SHADING_NORMALS
    if (b.n != b.ng) f *= abs(dot(b.n, v.wo)) / abs(dot(b.ng, v.wo));
#endif
    pf *= b.cont_prob;
    // The reverse pdf is that of the light subpath continuing from the merged vertex
    // (which lies at the light vertex), so its continuation probability is the light
    // vertex's BSDF's, as in SmallVCM's RangeQuery (the two differ where a merge spans two
    // materials).
    pr *= bsdf_init(v.material, v.n, v.ns, v.wo, true, v.tint).cont_prob;
    float w_light = v.dvcm * push.mis_vc + v.dvm * pf;
    float w_camera = st.dvcm * push.mis_vc + st.dvm * pr;
    w = 1.0 / (w_light + 1.0 + w_camera);
    return f;
}

// Samples the continuation at a vertex from `u_bsdf` (bsdf_sample's direction and lobe)
// and `u_roulette`: Russian roulette, throughput and MIS update. `ng` is the vertex's
// geometric normal as the surface gives it (not turned to wo). Returns false when the
// subpath ends.
bool scatter(inout SubpathState st, Bsdf b, vec3 p, vec3 ng, vec3 u_bsdf, float u_roulette) {
    BsdfSample bs = bsdf_sample(b, u_bsdf);
    if (!bs.ok) return false;
    if (u_roulette >= b.cont_prob) return false;
    mis_on_scatter(st, bs.pdf * b.cont_prob, bs.pdf_rev * b.cont_prob, bs.cos_wi, bs.specular);
    st.thr *= bs.weight / b.cont_prob;
    st.o = offset_ray(p, ng, bs.wi, scene_radius());
    st.d = bs.wi;
    st.from_material = b.material;
    st.from_ng = ng;
    return max3(st.thr) > 0.0;
}

// ---- Camera projection for connections to the eye.
// Raster position of world point x, false when behind the camera or off the image.
bool camera_raster(vec3 x, out vec2 raster) {
    vec3 d = x - params.cam_pos.xyz;
    float z = dot(d, params.cam_forward.xyz);
    if (z <= 0.0) return false;
    vec3 q = d * (params.cam_pos.w / z);
    raster = vec2(dot(q, params.cam_right.xyz) + 0.5 * float(image_width()),
                  0.5 * float(image_height()) - dot(q, params.cam_up.xyz));
    return raster.x >= 0.0 && raster.y >= 0.0 && raster.x < float(image_width()) && raster.y < float(image_height());
}

// A light vertex at p (BSDF `b`, state `st`) seen by the camera: returns the MIS weight
// of this light-to-camera connection (1 when `weight_one`: pure light tracing), with the
// BSDF value f towards the camera (zero: no contribution), the camera's pdf per unit area
// at p, the importance factor that multiplies f (that pdf with bsdf_cos in place of the
// geometric cosine) and the raster position. False when p is behind the camera or off the
// image.
bool camera_connection_eval(SubpathState st, vec3 p, Bsdf b, bool weight_one, out float w, out vec3 f,
                            out float camera_pdf_a, out float importance, out vec2 raster) {
    w = 0.0;
    f = vec3(0.0);
    camera_pdf_a = 0.0;
    importance = 0.0;
    if (!camera_raster(p, raster)) return false;
    vec3 to_cam = params.cam_pos.xyz - p;
    float dist = length(to_cam);
    to_cam /= dist;
    float pf, pr;
    f = bsdf_eval(b, to_cam, pf, pr);
    if (max3(f) <= 0.0) return true;
    pr *= b.cont_prob;
    float cos_cam = dot(params.cam_forward.xyz, -to_cam);
    float plane = params.cam_pos.w;
    // Pdf of the camera generating this point, per unit area at p (pixel area 1).
    float image_to_solid = plane * plane / (cos_cam * cos_cam * cos_cam);
    camera_pdf_a = image_to_solid * bsdf_cos_geometric(b, to_cam) / (dist * dist);
    importance = image_to_solid * bsdf_cos(b, to_cam) / (dist * dist);
    float n_l = float(push.light_paths);
    w = 1.0;
    if (!weight_one) {
        float w_light = (camera_pdf_a / n_l) * (push.mis_vm + st.dvcm + st.dvc * pr);
        w = 1.0 / (w_light + 1.0);
    }
    return true;
}

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

#endif
