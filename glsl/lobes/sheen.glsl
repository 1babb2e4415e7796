// The sheen (glTF KHR_materials_sheen): the "Charlie" microfacet lobe of Estevez & Kulla
// 2017 ("Production Friendly Microfacet Sheen BRDF"), D(h) = (2 + 1/a) sin(theta_h)^(1/a)
// / (2 pi) with a = sheenRoughness^2 and V = 1 / ((1 + L(n.wo) + L(n.wi)) 4 |n.wo| |n.wi|),
// L the paper's fit of Smith's Lambda, over the rest of the material (the base: all of
// glsl/bsdf.glsl), layered as the extension writes it:
//   f = sheenColor D V + f_base (1 - max(sheenColor) max(E(n.wo), E(n.wi))),
// E the lobe's directional albedo (sheenColor 1), interpolated in a table computed by
// quadrature (src/render/sheen_albedo.rs, written and checked by tests/render_sheen.rs).
// The paper's Lambda fit lets E exceed 1 at grazing angles for roughness below about 0.27
// (up to 2.9 at cos 0.001, roughness 0.07): there the lobe is divided by max(1, E(n.wo),
// E(n.wi)), and E taken at most 1, so that the sum never adds energy. Both terms are
// symmetric in wo and wi: the adjoint BSDF is the same.
// The sheen faces the side of b.ng (as the clear coat) and uses the base's shading normal.
//
// Sampling: the cosine-weighted hemisphere about n with probability p(d) = s(d) / (s(d) +
// (1 - s(d)) A), s(d) = max(sheenColor) min(E(n.d), 1), A the base's direction-free
// luminance albedo (base_albedo_luminance), d the fixed direction; the base with 1 - p(d).
// p depends on d alone, so the reverse pdf is p(wi) cos_o / pi + (1 - p(wi)) pdf_base_rev.
//
// Requires: glsl/bsdf.glsl up to its wrappers (as glsl/lobes/clearcoat.glsl).
#ifndef SHEEN_GLSL
#define SHEEN_GLSL

#if HAS_SHEEN

// The paper's Lambda: its fit L(x) with coefficients interpolated between r = 1 and r = 0
// by (1 - a)^2, mirrored about cos 0.5.
float sheen_lambda_fit(float x, float a) {
    float t = (1.0 - a) * (1.0 - a);
    float pa = mix(21.5473, 25.3245, t), pb = mix(3.82987, 3.32435, t), pc = mix(0.19823, 0.16801, t);
    float pd = mix(-1.97760, -1.27393, t), pe = mix(-4.32054, -4.85967, t);
    return pa / (1.0 + pb * pow(x, pc)) + pd * x + pe;
}
float sheen_lambda(float c, float a) {
    return c < 0.5 ? exp(sheen_lambda_fit(c, a)) : exp(2.0 * sheen_lambda_fit(0.5, a) - sheen_lambda_fit(1.0 - c, a));
}

// E(c, r): the table's bilinear interpolation, cosines at (i / (MU - 1))^2. The scene's
// texel buffer sheen_albedo_table (src/render/albedo_tables.rs) holds per cell (i, j) E at
// cosines i and i + 1 of roughness j, then of roughness j + 1: one texel per lookup.
uniform utextureBuffer sheen_albedo_table;
float sheen_albedo(float c, float r) {
    float x = sqrt(clamp(c, 0.0, 1.0)) * float(SHEEN_ALBEDO_MU - 1);
    float y = clamp((r - MIN_SHEEN_ROUGHNESS) / (1.0 - MIN_SHEEN_ROUGHNESS), 0.0, 1.0) * float(SHEEN_ALBEDO_R - 1);
    int i = min(int(x), SHEEN_ALBEDO_MU - 2), j = min(int(y), SHEEN_ALBEDO_R - 2);
    float fx = x - float(i), fy = y - float(j);
    vec4 e = uintBitsToFloat(texelFetch(sheen_albedo_table, j * (SHEEN_ALBEDO_MU - 1) + i));
    return mix(mix(e.x, e.y, fx), mix(e.z, e.w, fx), fy);
}

// E seen from unit direction d, 0 where the sheen does not face d (on a surface that
// transmits diffusely it faces both sides, glsl/lobes/diffuse_transmission.glsl).
float sheen_albedo_at(Bsdf b, vec3 d) {
    // A surface that transmits diffusely has the sheen on both sides: d's own.
    if (dot(b.ng, d) <= 0.0 && !transmits_diffusely(b)) return 0.0;
    return sheen_albedo(abs(dot(b.n, d)), b.sheen_roughness);
}

// The probability of sampling the sheen at a vertex whose fixed direction is d.
float sheen_prob(Bsdf b, vec3 d) {
    float s = b.sheen_max * min(sheen_albedo_at(b, d), 1.0);
    float den = s + (1.0 - s) * b.sheen_base_albedo;
    return den > 0.0 ? s / den : 0.0;
}

// Adds the sheen to the base's Bsdf `b`: its colour and roughness, its sampling
// probability at wo, and the continuation probability and delta flag of the sum.
// The continuation probability `p` of the base under the sheen, were `d` the vertex's
// fixed direction: the sheen's share s = max(colour) E(d) continues, p of the rest.
float sheen_cont_prob(Bsdf b, vec3 d, float p) {
    if (b.sheen_max <= 0.0 || !bsdf_seen(b, d)) return p;
    float s = b.sheen_max * min(sheen_albedo_at(b, d), 1.0);
    return clamp(p * (1.0 - s) + s, 0.0, 1.0);
}

void sheen_init(inout Bsdf b, GpuMaterial m) {
    b.sheen_colour = m.sheen.rgb;
    b.sheen_roughness = m.sheen.w;
#if HAS_SHEEN_TEXTURES
    // The point's texels (glsl/textures.glsl); 1 where it has none.
    b.sheen_colour *= b.tint.sheen.rgb;
    b.sheen_roughness = max(b.sheen_roughness * b.tint.sheen.a, MIN_SHEEN_ROUGHNESS);
#endif
    b.sheen_max = max3(b.sheen_colour);
    b.prob_sheen = 0.0;
    b.sheen_base_albedo = 0.0;
    if (b.sheen_max <= 0.0 || !bsdf_wo_seen(b)) return;
    b.sheen_base_albedo = b.valid ? base_albedo_luminance(m, b.tint) : 0.0;
    b.prob_sheen = sheen_prob(b, b.wo);
    if (b.prob_sheen > 0.0) {
        b.valid = true;
        b.delta = false;
    }
    b.cont_prob = sheen_cont_prob(b, b.wo, b.cont_prob);
    b.cont_prob_varies = true;
}

// The base's scaling 1 - max(sheenColor) max(E(n.wo), E(n.wi)) (E at most 1).
float sheen_base_scale(Bsdf b, vec3 wi) {
    return 1.0 - b.sheen_max * min(max(sheen_albedo_at(b, b.wo), sheen_albedo_at(b, wi)), 1.0);
}

// The sum of the base's f and pdfs (bsdf_eval's, before the coat) with the sheen's.
vec3 sheen_eval(Bsdf b, vec3 wi, vec3 f_base, inout float pdf_fwd, inout float pdf_rev) {
    float p_o = b.prob_sheen;
    float p_i = sheen_prob(b, wi);
    vec3 f = f_base * sheen_base_scale(b, wi);
    pdf_fwd *= 1.0 - p_o;
    pdf_rev *= 1.0 - p_i;
    float cos_o = dot(b.n, b.wo);
    float cos_i = dot(b.n, wi);
    // A reflection on the sheen's side: both directions on it, geometrically too.
    if (cos_o >= EPS_COSINE && cos_i >= EPS_COSINE && dot(b.ng, b.wo) > 0.0 && dot(b.ng, wi) > 0.0) {
        float a = b.sheen_roughness * b.sheen_roughness;
        float ch = dot(b.n, normalize(b.wo + wi));
        float d = (2.0 + 1.0 / a) * pow(max(1.0 - ch * ch, 0.0), 0.5 / a) * (0.5 * INV_PI);
        float v = 1.0 / ((1.0 + sheen_lambda(cos_o, a) + sheen_lambda(cos_i, a)) * 4.0 * cos_o * cos_i);
        float cap = max(max(sheen_albedo(cos_o, b.sheen_roughness), sheen_albedo(cos_i, b.sheen_roughness)), 1.0);
        f += b.sheen_colour * (d * v / cap);
        pdf_fwd += p_o * cos_i * INV_PI;
        pdf_rev += p_i * cos_o * INV_PI;
    }
    return f;
}

// Draws wi from the cosine-weighted hemisphere about n, valued by the whole BSDF.
BsdfSample sheen_sample(Bsdf b, vec2 u) {
    BsdfSample s = no_sample();
    if (dot(b.n, b.wo) < EPS_COSINE) return s;
    s.wi = to_world(sample_cosine_hemisphere(u), b.n);
    if (dot(b.n, s.wi) < EPS_COSINE) return s;
    return valued_sample(b, s);
}

// A specular sample of the base (drawn with probability 1 - p(wo) times its own): the
// sheen's scaling on its weight, the sheen's choice on its pdfs.
void sheen_specular(Bsdf b, inout BsdfSample s) {
    s.weight *= sheen_base_scale(b, s.wi) / (1.0 - b.prob_sheen);
    s.pdf *= 1.0 - b.prob_sheen;
    s.pdf_rev *= 1.0 - sheen_prob(b, s.wi);
}

#endif
#endif
