// The light-transport state shared by the bidirectional estimators (lt, bpt, and later
// ppm, bpm, vcm): subpath state with the recursive MIS quantities dVCM, dVC, dVM of
// Georgiev et al., "Implementing Vertex Connection and Merging" (2012), and the light-
// vertex store. Technique weights follow ../shared/SCENES.md 4.4 (balance heuristic).
//
// Requires: scene.glsl, film.glsl with HAS_SPLAT, `push` (GpuPush), and the buffers
//   lv_a[] / lv_b[] (vec4, two per vertex), lv_count[] (uint per light path).
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
};

// Light vertex storage: path p owns slots [p * S, p * S + S) with S = max path length - 1
// (a light subpath stores at most that many vertices), so a camera subpath finds the
// vertices of "its" light subpath p = pixel index without search, as in SmallVCM.
//   lv_a[2i] = (position, dVCM)      lv_a[2i+1] = (throughput, dVC)
//   lv_b[2i] = (wo, dVM)             lv_b[2i+1] = (normal, material | length << 24)
struct LightVertex {
    vec3 p;
    vec3 thr;
    vec3 wo;   // direction towards the previous vertex
    vec3 n;    // geometric normal
    uint material;
    uint len;        // segments from the light
    float dvcm, dvc, dvm;
};

uint lv_slots() { return max_path_length() - 1u; }

void lv_store(uint slot, LightVertex v) {
    lv_a[2u * slot] = vec4(v.p, v.dvcm);
    lv_a[2u * slot + 1u] = vec4(v.thr, v.dvc);
    lv_b[2u * slot] = vec4(v.wo, v.dvm);
    lv_b[2u * slot + 1u] = vec4(v.n, uintBitsToFloat(v.material | (v.len << 24)));
}

LightVertex lv_load(uint slot) {
    LightVertex v;
    vec4 a0 = lv_a[2u * slot], a1 = lv_a[2u * slot + 1u];
    vec4 b0 = lv_b[2u * slot], b1 = lv_b[2u * slot + 1u];
    v.p = a0.xyz; v.dvcm = a0.w;
    v.thr = a1.xyz; v.dvc = a1.w;
    v.wo = b0.xyz; v.dvm = b0.w;
    v.n = b1.xyz;
    uint info = floatBitsToUint(b1.w);
    v.material = info & 0xffffffu;
    v.len = info >> 24;
    return v;
}

// MIS update on reaching a new vertex at distance `dist` with |cos| `cos_fix` there.
void mis_on_hit(inout SubpathState st, float dist, float cos_fix, bool first_from_infinite) {
    if (!first_from_infinite) st.dvcm *= dist * dist;
    float inv = 1.0 / max(cos_fix, 1e-30);
    st.dvcm *= inv;
    st.dvc *= inv;
    st.dvm *= inv;
}

// Samples the continuation at a vertex: Russian roulette, throughput and MIS update.
// Returns false when the subpath ends.
bool scatter(inout SubpathState st, Bsdf b, vec3 p, vec3 ng, inout uint rng) {
    BsdfSample bs = bsdf_sample(b, vec3(rnd2(rng), rnd(rng)));
    if (!bs.ok) return false;
    if (rnd(rng) >= b.cont_prob) return false;
    float pdf = bs.pdf * b.cont_prob;
    float pdf_rev = bs.pdf_rev * b.cont_prob;
    if (bs.specular) {
        st.dvcm = 0.0;
        st.dvc *= bs.cos_wi;
        st.dvm *= bs.cos_wi;
    } else {
        float k = bs.cos_wi / pdf;
        st.dvc = k * (st.dvc * pdf_rev + st.dvcm + push.mis_vm);
        st.dvm = k * (st.dvm * pdf_rev + st.dvcm * push.mis_vc + 1.0);
        st.dvcm = 1.0 / pdf;
        st.specular = false;
    }
    st.thr *= bs.weight / b.cont_prob;
    st.o = offset_ray(p, ng, bs.wi, scene_radius());
    st.d = bs.wi;
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

// Connects a light-subpath point (a surface vertex with BSDF `b`, or when `b_valid` is
// false an area-light point whose emission towards the camera is `le_cos_weight`) to the
// camera and splats the contribution. `weight_one` disables MIS (pure light tracing).
void connect_to_camera(SubpathState st, vec3 p, vec3 ng, Bsdf b, bool weight_one) {
    vec2 raster;
    if (!camera_raster(p, raster)) return;
    vec3 to_cam = params.cam_pos.xyz - p;
    float dist = length(to_cam);
    to_cam /= dist;
    float pf, pr;
    vec3 f = bsdf_eval(b, to_cam, pf, pr);
    if (max3(f) <= 0.0) return;
    pr *= b.cont_prob;
    float cos_cam = dot(params.cam_forward.xyz, -to_cam);
    float cos_x = abs(dot(b.n, to_cam));
    float plane = params.cam_pos.w;
    // Pdf of the camera generating this point, per unit area at p (pixel area 1).
    float image_to_solid = plane * plane / (cos_cam * cos_cam * cos_cam);
    float camera_pdf_a = image_to_solid * cos_x / (dist * dist);
    float n_l = float(push.light_paths);
    float w = 1.0;
    if (!weight_one) {
        float w_light = (camera_pdf_a / n_l) * (push.mis_vm + st.dvcm + st.dvc * pr);
        w = 1.0 / (w_light + 1.0);
    }
    vec3 contrib = (w / n_l) * st.thr * f * camera_pdf_a;
    if (max3(contrib) <= 0.0) return;
    if (!visible(p, ng, params.cam_pos.xyz, vec3(0.0))) return;
    uint pixel = uint(raster.y) * image_width() + uint(raster.x);
    splat_add(pixel, contrib);
}

#endif
