// The clear coat (glTF KHR_materials_clearcoat): a GGX microfacet layer of F0 0.04 (IOR
// 1.5) and width alpha = clearcoatRoughness^2 over the rest of the material (the base:
// everything of glsl/bsdf.glsl), layered as the extension writes it:
//   f = (1 - c(v)) f_base + c(v) f_coat,   c(v) = clearcoat x F_coat(|n.v|),
// with F_coat Schlick's Fresnel of F0 0.04 and f_coat = D G2 / (4 |n.wo| |n.wi|), the GGX
// lobe of glsl/bsdf.glsl (`ggx_eval`) with F = 1 (glTF's specular_brdf: V D). v is the
// direction towards the viewer: wo on camera subpaths and wi on light subpaths (the
// adjoint BSDF, Veach 1997, 3.7: f is not symmetric, so the light subpath evaluates
// f(wi, wo)). Since f_coat alone reflects at most what it receives and the base too, the
// blend never adds energy (tests/render_clearcoat.rs). The coat faces the outside of a
// dielectric (the side of its outward normal) and both sides of an opaque surface; on a
// dielectric seen from inside c is 0 (light diffusely transmitted through an opaque
// surface meets the coat of the side it is seen from: glsl/lobes/diffuse_transmission.glsl).
// Emission is not dimmed by it.
//
// The coat's shading normal m is its own where it has a normal map (clearcoatNormalTexture,
// HAS_CLEARCOAT_NORMAL_MAPS: Tint.coat_normal, carried by light vertices), else the
// base's n. c(v) and f_coat are taken about m; since the estimators multiply f by the
// base's cosine (bsdf_cos: |n.wi| on camera subpaths, |n.wo| |ng.wi| / |ng.wo| on light
// subpaths, Veach 1997, 5.3), the coat's term is multiplied by |m.wi| / |n.wi| (camera) or
// |m.wo| / |n.wo| (light), so that each subpath transports f_coat |m.w|, the coat's own
// shading-normal BSDF and its adjoint.
//
// Sampling: the coat with probability p(d) = c(d) / (c(d) + (1 - c(d)) A), the base with
// 1 - p(d), where d is the fixed direction and A a direction-free luminance albedo of the
// base (`base_albedo_luminance`); the base then picks among its own components as without a
// coat. p depends on d alone, so the reverse pdf (the density of drawing wo from wi) is
// p(wi) pdf_coat(wo | wi) + (1 - p(wi)) pdf_base(wo | wi), exactly what a vertex with
// fixed direction wi draws. A base of zero albedo leaves the coat alone (p = 1).
//
// Requires: glsl/bsdf.glsl up to its wrappers (Bsdf, point_material, bsdf_wo_seen,
// base_albedo_luminance, schlick, ggx_eval, ggx_sample_h, bsdf_cos, bsdf_cos_geometric, BsdfSample, no_sample,
// and bsdf_eval declared).
#ifndef CLEARCOAT_GLSL
#define CLEARCOAT_GLSL

#if HAS_CLEARCOAT

#define COAT_F0 0.04

// c(d): the coat's blend factor seen from unit direction d (0 where the coat does not
// face d: the inside of a dielectric, or d off the side that the normals face).
float coat_blend(Bsdf b, vec3 d) {
    // bsdf_init turns an opaque material's normals to wo's side and leaves a dielectric's
    // outward: in both cases the coat faces the side of b.ng.
    // A surface that transmits diffusely is opaque and coated on both sides: d's own.
    if (dot(b.ng, d) <= 0.0 && !transmits_diffusely(b)) return 0.0;
    return b.coat_weight * schlick(COAT_F0, min(abs(dot(b.coat_n, d)), 1.0));
}

// The probability of sampling the coat at a vertex whose fixed direction is d.
float coat_prob(Bsdf b, vec3 d) {
    float c = coat_blend(b, d);
    float den = c + (1.0 - c) * b.coat_base_albedo;
    return den > 0.0 ? c / den : 0.0;
}

// The continuation probability `p` of the base under the coat, were `d` the vertex's
// fixed direction: the coat's share c(d) continues, p of the rest.
float coat_cont_prob(Bsdf b, vec3 d, float p) {
    if (b.coat_weight <= 0.0 || !bsdf_seen(b, d)) return p;
    float c = coat_blend(b, d);
    return clamp(p * (1.0 - c) + c, 0.0, 1.0);
}

// Adds the coat to the base's Bsdf `b` (bsdf_init): its weight, the coat's sampling
// probability at wo, and the continuation probability and delta flag of the blend.
void clearcoat_init(inout Bsdf b, GpuMaterial m) {
    b.coat_n = b.n;
#if HAS_CLEARCOAT_NORMAL_MAPS
    // Tint.coat_normal lies on the winding normal's side: turned as bsdf_init turned b.n.
    vec3 cn = b.tint.coat_normal;
    if (cn != vec3(0.0)) b.coat_n = dot(cn, b.ng) < 0.0 ? -cn : cn;
#endif
    b.coat_weight = m.coat.x;
    b.coat_alpha = m.coat.y;
#if HAS_CLEARCOAT_TEXTURES
    // The point's texels (glsl/textures.glsl): alpha = max((r t)^2, MIN_GGX_ALPHA), which
    // the stored max(r^2, MIN_GGX_ALPHA) times t^2 gives in both of max's cases.
    b.coat_weight *= b.tint.coat;
    if (b.tint.coat_roughness != 1.0) {
        b.coat_alpha = max(b.coat_alpha * b.tint.coat_roughness * b.tint.coat_roughness, MIN_GGX_ALPHA);
    }
#endif
    b.prob_coat = 0.0;
    b.coat_base_albedo = 0.0;
    if (b.coat_weight <= 0.0) return;
    if (!bsdf_wo_seen(b)) return;
    b.coat_base_albedo = b.valid ? base_albedo_luminance(m, b.tint) : 0.0;
    b.prob_coat = coat_prob(b, b.wo);
    if (b.prob_coat > 0.0) {
        b.valid = true;
        b.delta = false;
    }
    b.cont_prob = coat_cont_prob(b, b.wo, b.cont_prob);
    b.cont_prob_varies = true;
}

// The blend of the base's f and pdfs (bsdf_eval's, without the coat) with the coat's.
vec3 clearcoat_eval(Bsdf b, vec3 wi, vec3 f_base, inout float pdf_fwd, inout float pdf_rev) {
    float p_o = b.prob_coat;
    float p_i = coat_prob(b, wi);
    float c = coat_blend(b, b.from_light ? wi : b.wo);
    vec3 f = f_base * (1.0 - c);
    pdf_fwd *= 1.0 - p_o;
    pdf_rev *= 1.0 - p_i;
    float cos_o = dot(b.coat_n, b.wo);
    float cos_i = dot(b.coat_n, wi);
    // A reflection on the coat's side: both directions on it, geometrically too.
    if (c > 0.0 && cos_o >= EPS_COSINE && cos_i >= EPS_COSINE && dot(b.ng, b.wo) > 0.0 && dot(b.ng, wi) > 0.0) {
        float pf, pr;
        float r = 1.0;
#if HAS_CLEARCOAT_NORMAL_MAPS
        // The coat's cosine in place of the base's (the header).
        float base_cos = abs(dot(b.n, b.from_light ? b.wo : wi));
        r = base_cos >= EPS_COSINE ? (b.from_light ? cos_o : cos_i) / base_cos : 0.0;
#endif
        f += (c * r) * ggx_eval(b.coat_n, b.wo, wi, cos_o, cos_i, vec3(1.0), b.coat_alpha, pf, pr);
        pdf_fwd += p_o * pf;
        pdf_rev += p_i * pr;
    }
    return f;
}

// Draws wi from the coat's GGX lobe (h from the normals visible from wo, wo reflected
// about it), valued by the whole blend.
BsdfSample clearcoat_sample(Bsdf b, vec2 u) {
    BsdfSample s = no_sample();
    // Visible normals need wo above the coat (ggx_sample_h); clearcoat_eval gives the coat
    // no pdf otherwise either.
    if (dot(b.coat_n, b.wo) < EPS_COSINE) return s;
    vec3 h = ggx_sample_h(b.coat_n, b.wo, b.coat_alpha, u);
    float oh = dot(b.wo, h);
    if (oh <= 0.0) return s;
    s.wi = 2.0 * oh * h - b.wo;
    if (dot(b.coat_n, s.wi) < EPS_COSINE) return s;
    return valued_sample(b, s);
}

// A specular sample of the base (mirror or refraction, drawn with probability 1 - p(wo)
// times its own): the coat's (1 - c) on its weight, the coat's choice on its pdfs.
void clearcoat_specular(Bsdf b, inout BsdfSample s) {
    float c = coat_blend(b, b.from_light ? s.wi : b.wo);
    s.weight *= (1.0 - c) / (1.0 - b.prob_coat);
    s.pdf *= 1.0 - b.prob_coat;
    s.pdf_rev *= 1.0 - coat_prob(b, s.wi);
}

#endif
#endif
