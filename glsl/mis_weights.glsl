// The MIS weight of each technique that completes a path (Georgiev 2012, as SmallVCM's
// vertexcm.hxx; "eq. N" is equation N of that report): emitter hits, next-event
// estimation, vertex connections, connections to the camera and merges. Each completes
// the subpath quantities of glsl/subpath.glsl; every weight is 1 / (w_light + 1 +
// w_camera) (eq. 37, the balance heuristic). The debug kernel tests/mis_weights.comp
// calls the same functions along fixed paths and checks that the weights of all the
// techniques that can sample a path sum to 1.
//
// Needs scene.glsl, push.glsl, light_vertex_store.glsl (LightVertex) and subpath.glsl.
#ifndef MIS_WEIGHTS_GLSL
#define MIS_WEIGHTS_GLSL

// Camera subpath hits an emitter (area light or background; eq. 42-43, docs/smallvcm.md
// 4.4.8), pdfs without the pick probability (`direct_pdf`: next-event estimation's from the
// previous vertex, st.from_p, which for area lights depends on it: lights.glsl
// area_light_direct_pdf_a), and the picks (`direct_pick`: next-event estimation's at the
// previous vertex, nee_light_prob; `emission_pick`: the light subpaths', light_pick_prob;
// the same without the light tree): weight 1 / (1 + w_camera), 1 for the primary ray. Without connections
// (ppm, bpm) only purely specular camera paths may see emitters, with weight 1.
float mis_weight_hit(SubpathState st, float direct_pdf, float emission_pdf, float direct_pick, float emission_pick,
                     bool use_vc) {
    if (st.len == 1u) return 1.0;
    if (!use_vc) return st.specular ? 1.0 : 0.0;
    float w_camera = direct_pdf * direct_pick * st.dvcm + emission_pdf * emission_pick * st.dvc;
    return 1.0 / (1.0 + w_camera);
}

// Next-event estimation at a camera vertex with BSDF `b` towards light sample `ls` (eq.
// 44-45, docs/smallvcm.md 4.4.9):
// returns the MIS weight, with f the BSDF value (zero: no contribution) and cos_x the
// cosine that multiplies it (bsdf_cos).
// `pick` is the probability that picked the light here, `emission_pick` the one a light
// subpath starts on it with (they differ with the light tree).
float nee_eval(SubpathState st, Bsdf b, LightSample ls, float pick, float emission_pick, out vec3 f, out float cos_x) {
    float pf, pr;
    f = bsdf_eval(b, ls.wi, pf, pr);
    cos_x = bsdf_cos(b, ls.wi);
    if (max3(f) <= 0.0) return 0.0;
    pf = ls.delta ? 0.0 : pf * b.cont_prob;
    pr *= cont_prob_from(b, ls.wi);
    float w_light = pf / (pick * ls.pdf_w);
    float cos_g = bsdf_cos_geometric(b, ls.wi);
    float w_camera = (ls.emission_pdf_w * cos_g / (ls.pdf_w * ls.cos_light)) * (push.mis_vm + st.dvcm + st.dvc * pr);
#if LIGHT_TREE
    w_camera *= emission_pick / pick;
#endif
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
    // The camera side's next-event pdf of the sky at a light vertex from it (dvcm_at).
    float sky_pdf_w = lpr;
    cpf *= b.cont_prob; cpr *= cont_prob_from(b, dir);
    lpf *= lb.cont_prob; lpr *= cont_prob_from(lb, -dir);
    g = bsdf_cos(b, dir) * bsdf_cos(lb, -dir) / dist2;
    float cos_c = bsdf_cos_geometric(b, dir);
    float cos_l = bsdf_cos_geometric(lb, dir);
    float camera_pdf_a = cpf * cos_l / dist2;  // camera BSDF sampling the light vertex
    float light_pdf_a = lpf * cos_c / dist2;   // light BSDF sampling the camera vertex
    float w_light = camera_pdf_a * (push.mis_vm + dvcm_at(v.dvcm, v.sky_first_hit, sky_pdf_w) + v.dvc * lpr);
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
    // The camera vertex's next-event pdf of the sky at a light vertex from it (dvcm_at).
    float sky_pdf_w = pf;
    pf *= b.cont_prob;
    // The reverse pdf is that of the light subpath continuing from the merged vertex
    // (which lies at the light vertex), so its continuation probability is the light
    // vertex's BSDF's, as in SmallVCM's RangeQuery (the two differ where a merge spans two
    // materials).
    pr *= bsdf_init(v.material, v.n, v.ns, v.wo, true, v.tint).cont_prob;
    float w_light = dvcm_at(v.dvcm, v.sky_first_hit, sky_pdf_w) * push.mis_vc + v.dvm * pf;
    float w_camera = st.dvcm * push.mis_vc + st.dvm * pr;
    w = 1.0 / (w_light + 1.0 + w_camera);
    return f;
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
    // The camera side's next-event pdf of the sky at a vertex from it (dvcm_at).
    float sky_pdf_w = pr;
    pr *= cont_prob_from(b, to_cam);
    float cos_cam = dot(params.cam_forward.xyz, -to_cam);
    float plane = params.cam_pos.w;
    // Pdf of the camera generating this point, per unit area at p (pixel area 1).
    float image_to_solid = plane * plane / (cos_cam * cos_cam * cos_cam);
    camera_pdf_a = image_to_solid * bsdf_cos_geometric(b, to_cam) / (dist * dist);
    importance = image_to_solid * bsdf_cos(b, to_cam) / (dist * dist);
    float n_l = float(push.light_paths);
    w = 1.0;
    if (!weight_one) {
        float w_light = (camera_pdf_a / n_l) * (push.mis_vm + dvcm_at(st.dvcm, st.sky_first_hit, sky_pdf_w) + st.dvc * pr);
        w = 1.0 / (w_light + 1.0);
    }
    return true;
}

#endif
