// KHR_materials_anisotropy: the GGX lobe of glTF's metallic/roughness model (`glossy`,
// glsl/bsdf.glsl) made anisotropic. At a point with anisotropy direction t (world, from
// the vertex tangents: glsl/textures.glsl, anisotropy_at; made orthogonal to the shading
// normal n here), b = cross(n, t) and strength s, the lobe's widths are
//   alpha_t = mix(alpha, 1, s^2) along t,  alpha_b = alpha across it
// (the glTF extension's definition; alpha = roughness^2 as for the isotropic lobe). In the
// frame (t, b, n), with h = (hx, hy, hz) and w = (wx, wy, wz), the anisotropic GGX
// distribution and Smith's Lambda are (Heitz, "Understanding the Masking-Shadowing
// Function in Microfacet-Based BRDFs", JCGT 2014, eq. 85 and 86 with the GGX Lambda of
// eq. 72 at the projected width):
//   D(h) = 1 / (pi alpha_t alpha_b (hx^2 / alpha_t^2 + hy^2 / alpha_b^2 + hz^2)^2)
//   Lambda(w) = (sqrt(1 + (alpha_t^2 wx^2 + alpha_b^2 wy^2) / wz^2) - 1) / 2
// and the lobe is the isotropic one's with these: f = F(wo.h) D G2 / (4 n.wo n.wi),
// G2 = 1 / (1 + Lambda(wo) + Lambda(wi)), symmetric in wo and wi (no adjoint). Sampling
// draws the normals visible from wo as the isotropic lobe does (Heitz, "Sampling the GGX
// Distribution of Visible Normals", JCGT 2018: stretch wo by (alpha_t, alpha_b, 1) to the
// configuration of width 1, draw there by Dupuy & Benyoub's spherical caps, unstretch the
// normal), so pdf(wi | wo) = G1(wo) D(h) / (4 n.wo) and the reverse pdf
// G1(wi) D(h) / (4 n.wi), G1 = 1 / (1 + Lambda). With s = 0, or where t is (nearly)
// parallel to n, the isotropic lobe's own code runs: strength 0 is the isotropic lobe, bit
// for bit. The clear coat (glTF leaves it isotropic) and the rough dielectric's
// transmission (its Walter sampler; the importer warns) stay isotropic.
//
// Requires: glsl/bsdf.glsl up to ggx_eval (included from there).
#ifndef ANISOTROPY_GLSL
#define ANISOTROPY_GLSL

#if HAS_GGX && HAS_ANISOTROPY
// The anisotropic frame at a point of anisotropy `an` (Tint.anisotropy) about the unit
// normal `n` of the lobe, and the widths (alpha_t, alpha_b) for the isotropic width `a`;
// false where the lobe is isotropic there (the caller then runs the isotropic code).
bool anisotropic_frame(vec3 n, vec4 an, float a, out vec3 t, out vec3 b, out vec2 ab) {
    t = an.xyz - n * dot(n, an.xyz);
    float tl = length(t);
    b = vec3(0.0);
    ab = vec2(a);
    if (an.w <= 0.0 || !(tl > 1e-6)) return false;
    t /= tl;
    b = cross(n, t);
    ab = vec2(mix(a, 1.0, an.w * an.w), a);
    return true;
}

// D(h) for h = (hx, hy, hz) in the frame (t, b, n), hz > 0.
float ggx_anisotropic_d(vec3 h, vec2 ab) {
    vec3 s = vec3(h.x / ab.x, h.y / ab.y, h.z);
    float q = dot(s, s);
    return INV_PI / (ab.x * ab.y * q * q);
}

// Smith's Lambda at w = (wx, wy, wz) in the frame, wz > 0.
float ggx_anisotropic_lambda(vec3 w, vec2 ab) {
    float t2 = (ab.x * ab.x * w.x * w.x + ab.y * ab.y * w.y * w.y) / (w.z * w.z);
    return 0.5 * (sqrt(1.0 + t2) - 1.0);
}

// The GGX lobe at anisotropy `an` (ggx_eval's arguments otherwise): f and both pdfs.
vec3 ggx_anisotropic_eval(vec3 n, vec4 an, vec3 wo, vec3 wi, float cos_o, float cos_i, vec3 f0, float a,
                          out float pdf_fwd, out float pdf_rev) {
    vec3 t, b;
    vec2 ab;
    if (!anisotropic_frame(n, an, a, t, b, ab)) return ggx_eval(n, wo, wi, cos_o, cos_i, f0, a, pdf_fwd, pdf_rev);
    pdf_fwd = 0.0;
    pdf_rev = 0.0;
    vec3 h;
    if (!ggx_reflection_h(n, wo, wi, h)) return vec3(0.0);
    float d = ggx_anisotropic_d(vec3(dot(t, h), dot(b, h), dot(n, h)), ab);
    float lo = ggx_anisotropic_lambda(vec3(dot(t, wo), dot(b, wo), cos_o), ab);
    float li = ggx_anisotropic_lambda(vec3(dot(t, wi), dot(b, wi), cos_i), ab);
    return ggx_lobe(schlick(f0, dot(wo, h)), d, lo, li, cos_o, cos_i, pdf_fwd, pdf_rev);
}

// A half vector drawn from the normals visible from `wo` at anisotropy `an` (ggx_sample_h's
// arguments otherwise): ggx_sample_h's spherical caps in the configuration stretched by
// (alpha_t, alpha_b) along (t, b) (ggx_sample_h_stretched).
vec3 ggx_anisotropic_sample_h(vec3 n, vec4 an, vec3 wo, float a, vec2 u) {
    vec3 t, b;
    vec2 ab;
    if (!anisotropic_frame(n, an, a, t, b, ab)) return ggx_sample_h(n, wo, a, u);
    return ggx_sample_h_stretched(t, b, n, ab, wo, u);
}
#endif

#endif
