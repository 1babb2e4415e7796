// vkvcm's material model, written once for every estimator: Lambert + normalised Phong
// lobe + GGX microfacet reflection + Fresnel-weighted mirror / smooth dielectric.
// Component choice and Russian roulette follow SmallVCM (Georgiev & Davidovic), as
// docs/smallvcm.md 2.4 states: component probabilities proportional to luminance
// albedo (but for an opaque material's GGX lobe and the diffuse lobe under its coat,
// weighted by Fresnel at the fixed direction: fresnel_lobe_weights; SmallVCM's
// materials have neither, so their rule is unchanged), continuation probability = clamp(max RGB of (diffuse + phong + glossy +
// F mirror) + (1 - F), 0, 1) (glossy is zero for SmallVCM's materials, so their rule is
// unchanged). pt.comp does not use this continuation probability (Cycles' rule there).
//
// GGX lobe (`glossy`, used for glTF metallic/roughness): Trowbridge-Reitz distribution D
// as in Walter, Marschner, Li, Torrance, "Microfacet Models for Refraction through Rough
// Surfaces" (EGSR 2007); Smith height-correlated masking-shadowing
// G2 = 1 / (1 + Lambda(wo) + Lambda(wi)) as in Heitz, "Understanding the Masking-
// Shadowing Function in Microfacet-Based BRDFs" (JCGT 2014); Schlick's Fresnel with
// F0 = the lobe's colour (a metal's colour, or 0.04 for a dielectric coat). It is
// sampled by the normals visible from wo, D_wo(h) = G1(wo) D(h) max(0, wo.h) / (n.wo)
// (Heitz, "Sampling the GGX Distribution of Visible Normals", JCGT 2018), drawn as
// Dupuy & Benyoub's spherical caps ("Sampling Visible GGX Normals with Spherical Caps",
// HPG 2023): pdf(wi | wo) = D_wo(h) / (4 wo.h) = G1(wo) D(h) / (4 n.wo), and the reverse
// pdf, sampling wo from wi, G1(wi) D(h) / (4 n.wi). f, being reciprocal, needs no
// adjoint correction. KHR_materials_anisotropy makes it anisotropic where the point's
// tint has a strength (glsl/lobes/anisotropy.glsl; HAS_ANISOTROPY).
//
// Shading normals (interpolated vertex normals) follow Veach's thesis (1997), ch. 5.3:
// every lobe is evaluated and sampled about the shading normal n, while the geometric
// normal ng decides the side: a direction is a reflection only if it lies on wo's side
// of the geometric surface and a refraction only if it lies on the other side, so no ray
// leaks through the surface; wo below the shading hemisphere makes the BSDF black (as
// Mitsuba 3 does). The cosine that multiplies f is |n.wi| for camera subpaths (radiance:
// the incident direction is wi); for light subpaths (importance) it is
// |n.wo| |ng.wi| / |ng.wo| (Veach eq. 5.19, the adjoint BSDF with shading normals: the
// incident radiance comes from wo), `bsdf_cos`. Pdf conversions between solid angle and
// area, and hence every MIS quantity, use geometric cosines (`bsdf_cos_geometric`): they
// are the densities the estimators sample with. Without shading normals (n == ng) both
// cosines are |ng.wi|, bit for bit.
//
// Rough dielectric (`rough`, glTF KHR_materials_transmission with roughness > 0; a
// dielectric, phong.w = IOR >= 0, whose emission.w = GGX alpha > 0): Walter et al. 2007's
// BSDF, reflection and transmission through GGX microfacets, with the exact dielectric
// Fresnel F(wo.h) and Smith's separable shadowing G1(wo) G1(wi) (their eq. 23; Mitsuba 3's
// `roughdielectric`, the reference of tests/render_environment.rs). It is clear glass's
// only component (probability 1, no other lobe is evaluated; continuation probability 1
// as for smooth glass: F + (1 - F)); partial transmission adds lobes beside it (below).
// It is not delta, so every estimator connects to it,
// NEE reaches it and photons are stored on it and merged. With eta = eta_o / eta_i (the
// IORs on wo's and on wi's side), the half vector is h = wo + wi (reflection) or
// eta wo + wi (transmission, Walter's generalised h_t), normalised and turned to wo's side:
//   reflection:   f = F D G / (4 |n.wo| |n.wi|), pdf = F G1(wo) D / (4 |n.wo|)
//   transmission: f = (1 - F) D G |wo.h| |wi.h| s / (|n.wo| |n.wi| (eta wo.h + wi.h)^2),
//                 pdf = (1 - F) G1(wo) D |wo.h| |wi.h| / (|n.wo| (eta wo.h + wi.h)^2)
// (Walter's eq. 21 and 17 divided through by eta_i^2, with h drawn from the normals
// visible from wo as the GGX lobe), where s = eta^2 for radiance and 1 for importance
// (light subpaths: the adjoint BSDF, Veach 1997, 5.2; the same rule as the smooth
// refraction's `scale`). A sample's weight f |n.wi| / pdf is then G1(wi) (times s and the
// tint): bounded, where Walter's D(h) (n.h) sampling divides by |n.wo| and |n.h| and gave
// grazing views large weights. The reverse pdfs swap wo and wi: for reflection G1(wi) /
// |n.wi| in place of G1(wo) / |n.wo|, for transmission G1(wi) |wi.h| / |n.wi| times
// eta^2 |wo.h| (the Fresnel term of a refracted pair is the same both ways). Sampling: h
// from the normals visible from wo (ggx_sample_h), then reflection with probability
// F(wo.h), else refraction about h. The geometric
// normal decides reflection or transmission (the shading-normal rules above: a direction
// on wo's side is a reflection, on the other side a transmission, and the shading normal
// must agree or the BSDF is 0); a sample whose side is not the event drawn is rejected, so
// bsdf_eval's pdf is the density that bsdf_sample draws. Single-scattering microfacets
// lose the energy of paths that would bounce between microfacets (more with roughness);
// they never add any (tests/render_rough_glass.rs). Roughness 0 stays the smooth delta
// dielectric, bit for bit.
//
// Tinted transmission (glTF KHR_materials_transmission): the transmitted part of smooth
// and rough glass, f and hence the sample weight, in both directions, is multiplied by
// the material's transmission colour (`transmission_colour`, the base colour); the
// reflected part and every pdf are not (the component and event probabilities stay the
// Fresnel terms, so the sampling is the clear glass's and the MIS weights are exact).
//
// Partial transmission (glTF KHR_materials_transmission with transmissionFactor t < 1, or
// metallic m > 0): glTF's BSDF is linear in t and m, mix(mix(opaque dielectric, glass, t),
// metal, m), so it is the glass with weight w = (1 - m) t plus, with weight 1 - w, the
// metallic/roughness lobes of metallic m / (1 - w) (`Material::transmissive`, src/scene/mod.rs).
// A dielectric's glass weight w is transmission.w: its interface components (the
// Fresnel-weighted mirror reflection and refraction of smooth glass, or the rough
// dielectric) are weighted by w, and its diffuse, Phong and GGX lobes by 1 - w; the
// component probabilities are proportional to the weighted albedos, so f, pdf and the
// reverse pdf are those of the mixture. Each part conserves energy, so the mixture does.
// The lobes reflect on both sides of the surface (wo outside or inside the dielectric,
// `lobe_side`). Clear glass has w = 1, and its other lobes, which then have no weight,
// are uploaded black (src/render/scene_gpu.rs), so without HAS_PARTIAL_TRANSMISSION no
// weight is applied.
//
// Components no material of the scene has are compiled out (HAS_DIFFUSE, HAS_PHONG,
// HAS_GGX, HAS_MIRROR, HAS_DIELECTRIC, HAS_ROUGH_DIELECTRIC: glsl/features.glsl); the
// branches taken and the arithmetic done for the components present are the same as with
// all of them.
//
// A point's material is its material's, varied by the point's tint (glsl/textures.glsl,
// `Tint`): the base colour (`diffuse_colour` etc.) and, with a metallic-roughness
// texture, the lobes that depend on metallic and roughness (`point_material`). The tint
// is a property of the point, so bsdf_init, bsdf_eval and bsdf_sample all see the same
// lobes, and the component probabilities and pdfs stay exact.
//
// Layers over the whole material (the sheen and the clear coat, glsl/lobes/) wrap the
// base at the end of this file: bsdf_init, bsdf_eval and bsdf_sample are the base's
// (base_bsdf_*) with the layers applied.
//
// Diffuse transmission (glTF KHR_materials_diffuse_transmission, glsl/lobes/
// diffuse_transmission.glsl) is part of an opaque material's diffuse lobe: lobes_eval and
// base_bsdf_sample take a wi on the other side of the surface as its transmission.
//
// Requires: `material_at(i)` (GpuMaterial) declared by the kernel (scene.glsl), common.glsl, types.glsl,
// textures.glsl (Tint).
#ifndef BSDF_GLSL
#define BSDF_GLSL

#include "features.glsl"

#define EPS_COSINE 1e-6

struct Bsdf {
    vec3 n;          // shading normal: for opaque materials on the side of wo; for dielectrics outward
    vec3 ng;         // geometric normal, oriented as n
    vec3 wo;         // the fixed direction (towards the previous vertex), unit
    uint material;
    float prob_diffuse, prob_phong, prob_glossy, prob_reflect, prob_refract;
    float prob_rough; // the rough dielectric (1 for its materials, else 0)
    float cont_prob;        // Russian roulette's continuation probability at wo
    bool cont_prob_varies;  // ... which depends on wo (cont_prob_from)
    // The base's continuation probability (before a sheen or a coat) as a function of its
    // Fresnel term F (base_cont_prob): max3(lobes + F mirror) + (1 - F) transmit + rough.
    vec3 cont_lobes, cont_mirror;
    float cont_transmit, cont_rough;
    float ior;       // a dielectric's IOR (phong.w); negative for opaque materials
    float fresnel;   // reflectance F (1 for non-dielectrics; unused by the rough dielectric)
    float eta_ratio; // eta on the wo side / eta on the other side (dielectrics)
    bool valid;
    bool delta;      // only specular components
    bool from_light; // fixed direction belongs to a light subpath (adjoint BSDF)
    Tint tint;       // the surface point's tint (glsl/textures.glsl)
#if defined(AOV) && AOV
    vec3 albedo;     // the components' colours summed (the AOV albedo, glsl/aov.glsl)
#endif
#if HAS_PARTIAL_TRANSMISSION
    float interface_weight;  // a dielectric's glass weight; 1 on opaque materials
    float lobes_weight;      // 1 - the glass weight on a dielectric; 1 on opaque materials
#endif
#if HAS_CLEARCOAT
    // The clear coat (glsl/lobes/clearcoat.glsl): its factor, GGX alpha, its sampling
    // probability at wo, and the base's albedo its sampling probabilities use.
    float coat_weight, coat_alpha, prob_coat, coat_base_albedo;
    vec3 coat_n;  // the coat's shading normal, on b.ng's side (b.n without its own normal map)
#endif
#if HAS_SHEEN
    // The sheen (glsl/lobes/sheen.glsl): its colour, max(colour), roughness, its sampling
    // probability at wo, and the base's albedo its sampling probabilities use.
    vec3 sheen_colour;
    float sheen_max, sheen_roughness, prob_sheen, sheen_base_albedo;
#endif
#if HAS_IRIDESCENCE
    // E_avg of the iridescent Fresnel term of the diffuse lobe's interface (0 where the
    // material has no iridescence or no such interface; glsl/lobes/iridescence.glsl).
    vec3 interface_e_avg;
#endif
#if HAS_DIFFUSE_TRANSMISSION
    // The diffuse transmission (glsl/lobes/diffuse_transmission.glsl): 1 - its factor (the
    // reflection's weight), its colour, and its probability within the diffuse component.
    float dt_reflect;
    vec3 dt_colour;
    float prob_dt;
#endif
};

// The material's colours at a point with tint `tint` (the header of glsl/textures.glsl):
// diffuse and mirror are multiplied by it; of the GGX F0 only the part above the
// untinted dielectric reflectance (surface.w) is (glTF: F0 = mix(0.04, base, metallic)).
// Without attributes the tint is exactly 1 and the colours are the material's own.
vec3 diffuse_colour(GpuMaterial m, vec3 tint) {
#if HAS_VERTEX_ATTRIBUTES
    if (tint != vec3(1.0)) return m.diffuse.rgb * tint;
#endif
    return m.diffuse.rgb;
}
vec3 mirror_colour(GpuMaterial m, vec3 tint) {
#if HAS_VERTEX_ATTRIBUTES
    // A dielectric's reflection is not tinted (glTF KHR_materials_transmission).
    if (tint != vec3(1.0) && m.phong.w < 0.0) return m.mirror.rgb * tint;
#endif
    return m.mirror.rgb;
}
vec3 glossy_colour(GpuMaterial m, vec3 tint) {
#if HAS_VERTEX_ATTRIBUTES
    if (tint != vec3(1.0)) return vec3(m.surface.w) + (m.glossy.rgb - vec3(m.surface.w)) * tint;
#endif
    return m.glossy.rgb;
}

// The colour of a dielectric's transmitted part (glTF KHR_materials_transmission: the
// BTDF is multiplied by the base colour, the reflection is not), times the point's tint
// as the other colours; 1 for clear glass.
vec3 transmission_colour(GpuMaterial m, vec3 tint) {
#if HAS_VERTEX_ATTRIBUTES
    if (tint != vec3(1.0)) return m.transmission.rgb * tint;
#endif
    return m.transmission.rgb;
}

// dispersed_ior: a dispersive glass's IOR for the channel a subpath carries.
#include "lobes/dispersion.glsl"

// The material `material` at a point of tint `tint`. Where a metallic-roughness texture
// gave the point a metallic or roughness other than the factors
// (HAS_METALLIC_ROUGHNESS_TEXTURES), the lobes that depend on them are glTF's at the
// point's metallic = factor x texel B and roughness = factor x texel G (glTF 2.0 section
// 3.9.2; Material::metallic_roughness_lobes in src/scene/mod.rs computes the same for
// the factors): diffuse (1 - metallic) base, GGX F0 mix(dielectric F0, base, metallic)
// of which mean(dielectric F0) (1 - metallic) is untinted, GGX alpha roughness^2 (at
// least MIN_GGX_ALPHA). The diffuse lobe's interface F0 (mirror.w) does not depend on
// them. Where KHR_materials_specular's textures vary the dielectric F0
// (HAS_SPECULAR_TEXTURES), it is min(F0(IOR) x specularColorFactor x colour texel, 1) x
// specularFactor x texel A, and the interface F0 its largest component
// (Material::metallic_roughness_with_f0). Where a transmissionTexture varies the glass
// weight (HAS_TRANSMISSION_TEXTURES), w = (1 - metallic) transmissionFactor x texel R
// and the lobes beside it have metallic / (1 - w) (Material::transmissive). Elsewhere
// the material's own values, bit for bit. A dispersive glass has the IOR of the point's
// channel (HAS_DISPERSION, glsl/lobes/dispersion.glsl).
GpuMaterial point_material(uint material, Tint tint) {
    GpuMaterial m = material_at(material);
#if HAS_METALLIC_ROUGHNESS_TEXTURES || HAS_TRANSMISSION_TEXTURES || HAS_SPECULAR_TEXTURES
    if (tint.roughness != 1.0 || tint.metallic != 1.0 || tint.transmission != 1.0 || tint.specular != vec4(1.0)) {
        vec3 base = m.base_metallic.rgb;
        vec3 f0 = m.f0_roughness.rgb;
        float metallic = m.base_metallic.w * tint.metallic;
        float roughness = m.f0_roughness.w * tint.roughness;
#if HAS_SPECULAR_TEXTURES
        if (tint.specular != vec4(1.0)) {
            f0 = min(m.specular.rgb * tint.specular.rgb, vec3(1.0)) * (m.specular.w * tint.specular.a);
            m.mirror.w = max3(f0);
        }
#endif
#if HAS_PARTIAL_TRANSMISSION
        // A transmissive material's factors are the file's: its glass weight at the point
        // (tint.transmission is 1 without a transmission texture), then the metallic of
        // the lobes beside the glass.
        if (m.phong.w >= 0.0) {
            float w = m.transmission.w * tint.transmission;
            m.transmission.w = w;
            metallic = w < 1.0 ? min(metallic / (1.0 - w), 1.0) : 0.0;
            m.mirror.w = max3(f0);
        }
#endif
        m.diffuse.rgb = base * (1.0 - metallic);
        m.glossy.rgb = f0 + (base - f0) * metallic;
        m.glossy.w = max(roughness * roughness, MIN_GGX_ALPHA);
        m.surface.w = (f0.r + f0.g + f0.b) / 3.0 * (1.0 - metallic);
    }
#endif
#if HAS_DISPERSION
    m.phong.w = dispersed_ior(m, tint);
#endif
    return m;
}

// Fresnel reflectance of a smooth dielectric; cos_i > 0 means the incident direction is
// outside (pbrt's FrDielectric).
float fresnel_dielectric(float cos_i, float ior) {
    float eta = 1.0 / ior;  // eta_i / eta_t, outside -> inside
    if (cos_i < 0.0) { cos_i = -cos_i; eta = ior; }
    float sin2_t = eta * eta * max(0.0, 1.0 - cos_i * cos_i);
    if (sin2_t >= 1.0) return 1.0;  // total internal reflection
    float cos_t = sqrt(max(0.0, 1.0 - sin2_t));
    float r_par = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    float r_perp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    return 0.5 * (r_par * r_par + r_perp * r_perp);
}

// Schlick's Fresnel reflectance for F0 = `f0` at cos(theta) = `c`, per channel and scalar.
vec3 schlick(vec3 f0, float c) {
    float s = 1.0 - c;
    float s2 = s * s;
    return f0 + (vec3(1.0) - f0) * (s2 * s2 * s);
}
float schlick(float f0, float c) { return schlick(vec3(f0), c).x; }

// specular_fresnel: Schlick's, or the thin film's where the material is iridescent.
#include "lobes/iridescence.glsl"

// GGX (Trowbridge-Reitz) normal distribution D(h) for cos(theta_h) = `ch` > 0, width
// `a` (Walter et al. 2007, eq. 33, written with cos only).
float ggx_d(float ch, float a) {
    float a2 = a * a;
    float t = ch * ch * (a2 - 1.0) + 1.0;
    return a2 * INV_PI / (t * t);
}

// Smith's Lambda for GGX at a direction with cos(theta) = `c` > 0 (Heitz 2014, eq. 72).
float ggx_lambda(float c, float a) {
    float c2 = c * c;
    float tan2 = max(0.0, 1.0 - c2) / c2;
    return 0.5 * (sqrt(1.0 + a * a * tan2) - 1.0);
}

// A half vector drawn from the GGX normals visible from `wo` (n.wo > 0) in the frame
// (t, b, n), widths `ab` along t and b, uniform `u`: density D_wo(h) = G1(wo) D(h)
// max(0, wo.h) / (n.wo) (the header). Dupuy & Benyoub 2023: in the configuration
// stretched to width 1 the visible normals are h = c + wo', with c uniform on the
// spherical cap z >= -wo'.z of the unit sphere; unstretch.
vec3 ggx_sample_h_stretched(vec3 t, vec3 b, vec3 n, vec2 ab, vec3 wo, vec2 u) {
    vec3 v = normalize(vec3(ab.x * dot(wo, t), ab.y * dot(wo, b), dot(wo, n)));
    float phi = 2.0 * PI * u.x;
    float z = (1.0 - u.y) * (1.0 + v.z) - v.z;
    float r = sqrt(clamp(1.0 - z * z, 0.0, 1.0));
    vec3 h = vec3(r * cos(phi), r * sin(phi), z) + v;
    return normalize(ab.x * h.x * t + ab.y * h.y * b + max(h.z, 0.0) * n);
}

// The same for the isotropic width `a` about n.
vec3 ggx_sample_h(vec3 n, vec3 wo, float a, vec2 u) {
    vec3 t, b;
    make_frame(n, t, b);
    return ggx_sample_h_stretched(t, b, n, vec2(a), wo, u);
}

// Smith's G1 = 1 / (1 + Lambda) for GGX at |cos(theta)| = `c` > 0.
float ggx_g1(float c, float a) { return 1.0 / (1.0 + ggx_lambda(c, a)); }

// The half vector h of the reflection pair (wo, wi) about n; false where h, wo or wi is
// (nearly) below its partner (n.h, wo.h, wi.h < EPS_COSINE): the lobe is 0 there.
bool ggx_reflection_h(vec3 n, vec3 wo, vec3 wi, out vec3 h) {
    vec3 hs = wo + wi;
    float hl = length(hs);
    h = vec3(0.0);
    if (hl < 1e-7) return false;
    h = hs / hl;
    return dot(n, h) >= EPS_COSINE && dot(wo, h) >= EPS_COSINE && dot(wi, h) >= EPS_COSINE;
}

// The GGX lobe's f = F D G2 / (4 cos_o cos_i), G2 = 1 / (1 + Lambda(wo) + Lambda(wi)), and
// its visible-normal pdfs G1(wo) D / (4 cos_o) (fwd) and G1(wi) D / (4 cos_i) (rev), from
// F = `fr`, D = `d` and the Lambdas: isotropic (ggx_eval) and anisotropic alike.
vec3 ggx_lobe(vec3 fr, float d, float lambda_o, float lambda_i, float cos_o, float cos_i, out float pdf_fwd,
              out float pdf_rev) {
    pdf_fwd = d / ((1.0 + lambda_o) * 4.0 * cos_o);
    pdf_rev = d / ((1.0 + lambda_i) * 4.0 * cos_i);
    return fr * (d / (1.0 + lambda_o + lambda_i) / (4.0 * cos_o * cos_i));
}

// The GGX lobe for unit wo, wi above the surface (cos_o, cos_i > 0): f, and the pdfs of
// sampling wi given wo (fwd) and wo given wi (rev) by the visible normals (ggx_sample_h),
// without the component probability.
vec3 ggx_eval(vec3 n, vec3 wo, vec3 wi, float cos_o, float cos_i, vec3 f0, float a, out float pdf_fwd,
              out float pdf_rev) {
    pdf_fwd = 0.0;
    pdf_rev = 0.0;
    vec3 h;
    if (!ggx_reflection_h(n, wo, wi, h)) return vec3(0.0);
    return ggx_lobe(schlick(f0, dot(wo, h)), ggx_d(dot(n, h), a), ggx_lambda(cos_o, a), ggx_lambda(cos_i, a), cos_o,
                    cos_i, pdf_fwd, pdf_rev);
}

// The GGX lobe made anisotropic by KHR_materials_anisotropy (Tint.anisotropy).
#include "lobes/anisotropy.glsl"

// The directional albedo E(c) = f0 A + B of the GGX lobe with Schlick's F of F0 f0
// (F = f0 (1 - s) + s, s = (1 - wo.h)^5, so E is linear in f0) and width `a` at
// cos(theta) = `c`: (A, B) by the bilinear interpolation of a table by quadrature
// (src/render/ggx_albedo.rs), cosines at (i / (MU - 1))^2, roughnesses sqrt(a) at
// j / (R - 1). The scene's texel buffer ggx_albedo_table (src/render/albedo_tables.rs)
// holds per cell (i, j) the pairs at rows i and i + 1, then per j < R - 1 and row i the
// pairs' cosine-weighted integrals up to row i at j and j + 1 (ggx_albedo_cumulative).
// A texel buffer: on lavapipe it costs less than a storage buffer or a private array
// (docs/performance.md, "Tried and not kept").
#extension GL_EXT_samplerless_texture_functions : require
uniform utextureBuffer ggx_albedo_table;
#define GGX_ALBEDO_CELL(k) uintBitsToFloat(texelFetch(ggx_albedo_table, k))
vec2 ggx_albedo_terms(float c, float a) {
    float x = sqrt(clamp(c, 0.0, 1.0)) * float(GGX_ALBEDO_MU - 1);
    float y = sqrt(clamp(a, 0.0, 1.0)) * float(GGX_ALBEDO_R - 1);
    int i = min(int(x), GGX_ALBEDO_MU - 2), j = min(int(y), GGX_ALBEDO_R - 2);
    int k = j * (GGX_ALBEDO_MU - 1) + i;
    vec4 lo = GGX_ALBEDO_CELL(k), hi = GGX_ALBEDO_CELL(k + GGX_ALBEDO_MU - 1);
    vec4 e = mix(lo, hi, y - float(j));
    return mix(e.xy, e.zw, x - float(i));
}
float ggx_albedo(float f0, float c, float a) {
    vec2 e = ggx_albedo_terms(c, a);
    return f0 * e.x + e.y;
}

// The cosine-weighted integrals 2 int_0^mu_i (A, B)(mu) mu dmu up to row i (mu_i =
// (i / (MU - 1))^2) at roughness cell j, `fy` of the way to j + 1: exact for
// ggx_albedo_terms' interpolation.
vec2 ggx_albedo_cumulative(int i, int j, float fy) {
    vec4 k = GGX_ALBEDO_CELL((GGX_ALBEDO_MU - 1) * GGX_ALBEDO_R + j * GGX_ALBEDO_MU + i);
    return mix(k.xy, k.zw, fy);
}

// E_avg = 2 int_0^1 E(mu) mu dmu of ggx_albedo, exact for its interpolation.
float ggx_albedo_average(float f0, float a) {
    float y = sqrt(clamp(a, 0.0, 1.0)) * float(GGX_ALBEDO_R - 1);
    int j = min(int(y), GGX_ALBEDO_R - 2);
    vec2 avg = ggx_albedo_cumulative(GGX_ALBEDO_MU - 1, j, y - float(j));
    return f0 * avg.x + avg.y;
}

// 1 - E_avg: the diffuse lobe's normalisation under the interface (diffuse_fresnel_weight).
float coupled_diffuse_norm(float f0, float a) { return max(1.0 - ggx_albedo_average(f0, a), 1e-6); }

// The weight of a diffuse lobe under a dielectric interface of Schlick F0 `f0` and GGX
// width `a` (glTF's metallic/roughness dielectric): (1 - E(cos_o)) (1 - E(cos_i)) /
// (1 - E_avg), E the interface's directional albedo (ggx_albedo). The coupled
// matte-specular weighting of Kelemen and Szirmay-Kalos, "A Microfacet Based Coupled
// Specular-Matte BRDF Model with Importance Sampling" (Eurographics 2001): symmetric in wo
// and wi (so reciprocal, no adjoint), and for a white base the diffuse albedo at wo is
// exactly 1 - E(cos_o), what the GGX lobe does not reflect, so a white dielectric of any
// roughness reflects everything. glTF's reference `fresnel_mix` weights the diffuse lobe
// by 1 - F(wo.h) instead, which reflects up to 1.7 times what a white smooth surface
// receives at grazing angles; Schlick's F(cos) in place of E, exact when smooth, leaves a
// rough one too dark there (docs/scene-format.md).
float diffuse_fresnel_weight(float f0, float a, float cos_o, float cos_i) {
    return (1.0 - ggx_albedo(f0, cos_o, a)) * (1.0 - ggx_albedo(f0, cos_i, a)) / coupled_diffuse_norm(f0, a);
}

// That diffuse lobe is sampled by its weight's factor in wi: the pdf cos_i (1 - E(cos_i)) /
// (pi (1 - E_avg)), so that f cos_i / pdf is (1 - E(cos_o)) base whatever wi. A cosine's
// pdf leaves 1 - E(cos_i), from 0 at grazing angles to 0.96, in the weight
// (docs/performance.md, "A constant sky").
float coupled_diffuse_pdf(float f0, float a, float c) {
    return c * (1.0 - ggx_albedo(f0, c, a)) * INV_PI / coupled_diffuse_norm(f0, a);
}

// The unnormalised CDF of coupled_diffuse_pdf at cosine row i (roughness cell j, fy):
// int_0^{q_i} (1 - E) dq = q_i - f0 K_A - K_B, q_i = (i / (MU - 1))^4.
float coupled_diffuse_cdf(int i, int j, float fy, float f0) {
    return pow(float(i) / float(GGX_ALBEDO_MU - 1), 4.0) - dot(vec2(f0, 1.0), ggx_albedo_cumulative(i, j, fy));
}

// A direction (local, z up) with coupled_diffuse_pdf: u.x picks cos^2 by inverting the
// cumulative integral of 1 - E, exactly for its interpolation (linear in x = sqrt(cos)
// between rows: in q = x^4 = cos^2, d(CDF)/dq = 1 - E), found by bisection over the rows
// and then within the row by Newton's method in q, kept in the row (two steps: within a
// row the CDF is nearly linear in q); u.y the azimuth.
vec3 sample_coupled_diffuse(float f0, float a, vec2 u) {
    float y = sqrt(clamp(a, 0.0, 1.0)) * float(GGX_ALBEDO_R - 1);
    int j = min(int(y), GGX_ALBEDO_R - 2);
    float fy = y - float(j);
    const float h = 1.0 / float(GGX_ALBEDO_MU - 1);
    float target = u.x * coupled_diffuse_norm(f0, a);
    int lo = 0, hi = GGX_ALBEDO_MU - 1;
    while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (coupled_diffuse_cdf(mid, j, fy, f0) <= target) lo = mid;
        else hi = mid;
    }
    float r = target - coupled_diffuse_cdf(lo, j, fy, f0);
    // Within row lo, 1 - E = alpha + beta x.
    int k = j * (GGX_ALBEDO_MU - 1) + lo;
    vec4 e = mix(GGX_ALBEDO_CELL(k), GGX_ALBEDO_CELL(k + GGX_ALBEDO_MU - 1), fy);
    float w0 = 1.0 - f0 * e.x - e.y, w1 = 1.0 - f0 * e.z - e.w;
    float x0 = float(lo) * h, q0 = pow(x0, 4.0), q1 = pow(x0 + h, 4.0);
    float beta = (w1 - w0) / h, alpha = w0 - beta * x0;
    float q = clamp(q0 + r / max(0.5 * (w0 + w1), 1e-6), q0, q1);
    for (int n = 0; n < 2; n++) {
        float x = sqrt(sqrt(q));
        float g = alpha * (q - q0) + 0.8 * beta * (x * q - x0 * q0) - r;
        q = clamp(q - g / max(alpha + beta * x, 1e-6), q0, q1);
    }
    float c = sqrt(q);
    float phi = 2.0 * PI * u.y;
    float st = sqrt(max(0.0, 1.0 - c * c));
    return vec3(st * cos(phi), st * sin(phi), c);
}

// The diffuse lobe's sampling pdf at cos(theta) = `c` on its side, and its sample (local, z
// up): coupled_diffuse_pdf's under a dielectric interface (diffuse_fresnel_weight), else
// the cosine's (also under an iridescent film, whose coupling takes the film's F per
// channel). A diffuse transmission takes the same pdf at |cos|.
bool diffuse_is_coupled(Bsdf b, GpuMaterial m) {
#if HAS_IRIDESCENCE
    if (b.interface_e_avg != vec3(0.0)) return false;
#endif
    return m.mirror.w > 0.0;
}
float diffuse_pdf(Bsdf b, GpuMaterial m, float c) {
    return diffuse_is_coupled(b, m) ? coupled_diffuse_pdf(m.mirror.w, m.glossy.w, c) : c * INV_PI;
}
vec3 sample_diffuse(Bsdf b, GpuMaterial m, vec2 u) {
    return diffuse_is_coupled(b, m) ? sample_coupled_diffuse(m.mirror.w, m.glossy.w, u) : sample_cosine_hemisphere(u);
}

#if HAS_GGX
// The selection weights of an opaque material's diffuse and GGX lobes when the fixed
// direction has cos(theta) = `c` (> 0, shading normal), instead of SmallVCM's luminance
// albedos, which pick the 4% coat as seldom at grazing angles as at normal incidence,
// where it reflects most. A constant sky's next-event samples come from the BSDF too
// (lights.glsl sky_light_sample), so the lobe choice sets the variance of both: the
// diffuse lobe's directional albedo (1 - E_d(c)) base (diffuse_fresnel_weight's integral
// over wi) and, for the GGX lobe, sqrt(E(c) F(c)) of its albedo E (ggx_albedo) and
// Schlick's F. The albedo alone draws too few GGX samples at grazing angles, where a
// rough lobe's spread and lose some below the horizon, F too many; between them the
// variance is within 3% of the best split's but near normal incidence on rough lobes
// (scripts/lobe_choice_variance.py; docs/performance.md, "A constant sky"). A lobe that
// is absent stays at 0.
void fresnel_lobe_weights(GpuMaterial m, Tint tint, float c, inout float a_d, inout float a_g) {
#if HAS_IRIDESCENCE
    // The same estimates with the film's Fresnel term (glsl/lobes/iridescence.glsl).
    if (iridescence_at(m, tint).x > 0.0) {
        if (a_g > 0.0) a_g = luminance(specular_fresnel(m, tint, glossy_colour(m, tint.rgb), c));
        if (m.mirror.w > 0.0) a_d *= 1.0 - luminance(specular_fresnel(m, tint, vec3(m.mirror.w), c));
        return;
    }
#endif
    float f0 = m.mirror.w;
    vec2 e = ggx_albedo_terms(c, m.glossy.w);
    vec3 f0g = glossy_colour(m, tint.rgb);
    if (a_g > 0.0) a_g = luminance(sqrt((f0g * e.x + e.y) * schlick(f0g, c)));
    if (f0 > 0.0) a_d *= 1.0 - (f0 * e.x + e.y);
}
#endif

#include "lobes/diffuse_transmission.glsl"

// `ng`: geometric normal (for a dielectric it must point outwards); `ns`: shading normal
// on the same side as ng (== ng for flat shading); `tint`: the point's tint (Surface.tint).
// The base's continuation probability for the Fresnel term `fresnel` of its interface
// (1 on opaque materials): the largest channel of its albedo plus what the interface
// transmits, at most 1.
float base_cont_prob(Bsdf b, float fresnel) {
    return clamp(max3(b.cont_lobes + fresnel * b.cont_mirror) + (1.0 - fresnel) * b.cont_transmit + b.cont_rough, 0.0,
                 1.0);
}

Bsdf base_bsdf_init(uint material, vec3 ng, vec3 ns, vec3 wo, bool from_light, Tint tint) {
    Bsdf b;
    GpuMaterial m = point_material(material, tint);
    float ior = m.phong.w;
    b.material = material;
    b.wo = wo;
    b.from_light = from_light;
    b.tint = tint;
    b.ior = ior;
    b.cont_prob_varies = false;
#if HAS_IRIDESCENCE
    b.interface_e_avg = vec3(0.0);
    if (m.mirror.w > 0.0 && iridescence_at(m, tint).x > 0.0) b.interface_e_avg = iridescence_average(m, tint, m.mirror.w);
#endif
    float c = dot(ng, wo);
    // wo must lie off the geometric surface and, on the same side, above the shading one.
    b.valid = abs(c) >= EPS_COSINE && (c >= 0.0 ? dot(ns, wo) : -dot(ns, wo)) >= EPS_COSINE;
#if HAS_DIELECTRIC
    if (ior < 0.0) {
#endif
        // Opaque surfaces reflect on both sides.
        b.n = c >= 0.0 ? ns : -ns;
        b.ng = c >= 0.0 ? ng : -ng;
        b.fresnel = 1.0;
        b.eta_ratio = 1.0;
#if HAS_DIELECTRIC
    } else {
        b.n = ns;
        b.ng = ng;
        b.fresnel = fresnel_dielectric(dot(ns, wo), ior);
        b.eta_ratio = c >= 0.0 ? 1.0 / ior : ior;
    }
#endif
    // Albedos of the components; an absent one is 0 in every material, so leaving it (and
    // its zero terms in the sums below) out changes nothing.
    float a_d = 0.0, a_p = 0.0, a_g = 0.0, a_r = 0.0, a_t = 0.0;
    vec3 albedo = vec3(0.0);
#if HAS_DIFFUSE
    vec3 diffuse = diffuse_colour(m, tint.rgb);
#if HAS_DIFFUSE_TRANSMISSION
    diffuse = diffuse_transmission_init(b, m, diffuse);
#endif
    a_d = luminance(diffuse);
    albedo += diffuse;
#endif
#if HAS_PHONG
    a_p = luminance(m.phong.rgb);
    albedo += m.phong.rgb;
#endif
#if HAS_GGX
    vec3 glossy = glossy_colour(m, tint.rgb);
    a_g = luminance(glossy);
    albedo += glossy;
    // Opaque materials only: a dielectric's interface components also change with the
    // direction, and lobes_eval's reverse probabilities assume only these two do.
    if (ior < 0.0 && b.valid) fresnel_lobe_weights(m, tint, dot(b.n, wo), a_d, a_g);
#endif
#if HAS_PARTIAL_TRANSMISSION
    // Partial transmission (the header): the lobes so far carry 1 - the glass weight, the
    // interface's components the glass weight.
    b.interface_weight = 1.0;
    b.lobes_weight = 1.0;
    if (ior >= 0.0) {
        b.interface_weight = m.transmission.w;
        b.lobes_weight = 1.0 - m.transmission.w;
        a_d *= b.lobes_weight;
        a_p *= b.lobes_weight;
        a_g *= b.lobes_weight;
        albedo *= b.lobes_weight;
    }
#endif
#if HAS_ROUGH_DIELECTRIC
    bool rough = ior >= 0.0 && m.emission.w > 0.0;
#else
    bool rough = false;
#endif
    // The rough dielectric beside partial transmission's lobes: a component of albedo 1
    // times the glass weight (Fresnel draws the event within it); it has no mirror or
    // refraction component of its own.
    float a_rough = 0.0;
#if HAS_ROUGH_DIELECTRIC && HAS_PARTIAL_TRANSMISSION
    if (rough && b.lobes_weight > 0.0) a_rough = b.interface_weight;
#endif
    b.cont_lobes = albedo;
    b.cont_mirror = vec3(0.0);
#if HAS_MIRROR
    vec3 mirror = mirror_colour(m, tint.rgb);
    a_r = b.fresnel * luminance(mirror);
#if HAS_PARTIAL_TRANSMISSION
    a_r *= b.interface_weight;
    mirror *= b.interface_weight;
    if (a_rough > 0.0) {
        a_r = 0.0;
        mirror = vec3(0.0);
    }
#endif
    albedo += b.fresnel * mirror;
    b.cont_mirror = mirror;
#endif
#if HAS_DIELECTRIC
    a_t = ior < 0.0 ? 0.0 : 1.0 - b.fresnel;
#if HAS_PARTIAL_TRANSMISSION
    a_t *= b.interface_weight;
    if (a_rough > 0.0) a_t = 0.0;
#endif
#endif
    b.prob_rough = 0.0;
    if (rough && a_rough == 0.0) {
        // Clear rough glass: the material's only component (the header).
        b.prob_diffuse = 0.0;
        b.prob_phong = 0.0;
        b.prob_glossy = 0.0;
        b.prob_reflect = 0.0;
        b.prob_refract = 0.0;
        b.prob_rough = 1.0;
        b.cont_lobes = b.cont_mirror = vec3(0.0);
        b.cont_transmit = 0.0;
        b.cont_rough = 1.0;
        b.cont_prob = 1.0;
        b.delta = false;
#if defined(AOV) && AOV
        b.albedo = vec3(1.0);
#endif
        return b;
    }
    float total = a_d + a_p + a_g + a_r + a_t;
#if HAS_PARTIAL_TRANSMISSION
    total += a_rough;
#endif
    if (total < 1e-9) {
        b.valid = false;
        total = 1.0;
    }
    b.prob_diffuse = a_d / total;
    b.prob_phong = a_p / total;
    b.prob_glossy = a_g / total;
    b.prob_reflect = a_r / total;
    b.prob_refract = a_t / total;
    // Russian roulette: the albedo's largest channel plus the interface's transmission.
    b.cont_transmit = 1.0;
    b.cont_rough = 0.0;
#if HAS_PARTIAL_TRANSMISSION
    b.prob_rough = a_rough / total;
    b.cont_transmit = ior < 0.0 || a_rough > 0.0 ? 0.0 : b.interface_weight;
    b.cont_rough = a_rough;
#endif
    b.cont_prob = base_cont_prob(b, b.fresnel);
    // A dielectric's Fresnel term F(wo) weighs its reflection and refraction.
    b.cont_prob_varies = ior >= 0.0;
    b.delta = b.prob_diffuse == 0.0 && b.prob_phong == 0.0 && b.prob_glossy == 0.0 && b.prob_rough == 0.0;
#if defined(AOV) && AOV
    // Rough glass beside other lobes and transmission count as colour 1 (OIDN's glass).
    b.albedo = albedo + vec3(a_t + a_rough);
#endif
    return b;
}

#if HAS_ROUGH_DIELECTRIC
// The rough dielectric (the header): f(wo, wi) for wi on either side of the surface, with
// the pdfs of sampling wi given wo (fwd) and wo given wi (rev).
vec3 rough_dielectric_eval(Bsdf b, vec3 wi, out float pdf_fwd, out float pdf_rev) {
    pdf_fwd = 0.0;
    pdf_rev = 0.0;
    GpuMaterial m = material_at(b.material);
    float ior = m.phong.w;
#if HAS_DISPERSION
    ior = dispersed_ior(m, b.tint);
#endif
    float a = m.emission.w;
    // Normals turned to wo's side of the geometric surface (b.valid: wo is off it, and above
    // the shading surface on that side).
    float side = dot(b.ng, b.wo) >= 0.0 ? 1.0 : -1.0;
    vec3 n = side * b.n;
    float cos_o = dot(n, b.wo);
    float cos_i = dot(n, wi);
    float g_i = side * dot(b.ng, wi);
    if (cos_o < EPS_COSINE || g_i == 0.0) return vec3(0.0);
    float g = ggx_g1(cos_o, a) * ggx_g1(abs(cos_i), a);
    if (g_i > 0.0) {
        // Reflection: wi on wo's side, above the shading surface too.
        if (cos_i < EPS_COSINE) return vec3(0.0);
        vec3 hs = b.wo + wi;
        float hl = length(hs);
        if (hl < 1e-7) return vec3(0.0);
        vec3 h = hs / hl;
        float ch = dot(n, h);
        float oh = dot(b.wo, h);
        float ih = dot(wi, h);
        if (ch < EPS_COSINE || oh < EPS_COSINE || ih < EPS_COSINE) return vec3(0.0);
        float fr = fresnel_dielectric(side * oh, ior);
        float d = ggx_d(ch, a);
        // Visible normals from wo (fwd) or from wi (rev).
        pdf_fwd = fr * ggx_g1(cos_o, a) * d / (4.0 * cos_o);
        pdf_rev = fr * ggx_g1(cos_i, a) * d / (4.0 * cos_i);
        return vec3(fr * d * g / (4.0 * cos_o * cos_i));
    }
    // Transmission: wi on the other side, below the shading surface too.
    if (cos_i > -EPS_COSINE) return vec3(0.0);
    float eta = b.eta_ratio;  // eta_o / eta_i
    vec3 hs = eta * b.wo + wi;
    float hl = length(hs);
    if (hl < 1e-7) return vec3(0.0);
    vec3 h = hs / hl;
    if (dot(n, h) < 0.0) h = -h;
    float ch = dot(n, h);
    float oh = dot(b.wo, h);
    float ih = dot(wi, h);
    // Both directions must see the microfacet from their own side.
    if (ch < EPS_COSINE || oh < EPS_COSINE || ih > -EPS_COSINE) return vec3(0.0);
    float t = 1.0 - fresnel_dielectric(side * oh, ior);
    if (t <= 0.0) return vec3(0.0);
    // (eta wo.h + wi.h)^2 = |eta wo + wi|^2 (h is that vector normalised, up to sign),
    // without the cancellation of the sum of two terms of opposite signs.
    float den2 = hl * hl;
    float d = ggx_d(ch, a);
    // h drawn from the normals visible from wo, D_wo(h) = G1(wo) D(h) wo.h / (n.wo), times
    // the refraction's Jacobian |wi.h| / den2; the reverse draws -h from those visible from
    // wi, G1(wi) D(h) |wi.h| / |n.wi|, times eta^2 |wo.h| / den2.
    pdf_fwd = t * ggx_g1(cos_o, a) * d * oh / cos_o * -ih / den2;
    pdf_rev = t * ggx_g1(-cos_i, a) * d * -ih / -cos_i * eta * eta * oh / den2;
    // Radiance is scaled by (eta_o / eta_i)^2 crossing the boundary; importance is not.
    float scale = b.from_light ? 1.0 : eta * eta;
    return transmission_colour(m, b.tint.rgb) * (t * d * g * oh * -ih * scale / (cos_o * -cos_i * den2));
}
#endif

// The sign that turns the Bsdf's normals to wo's side of the geometric surface, where the
// reflection lobes (diffuse, Phong, GGX, mirror) are evaluated and sampled. bsdf_init
// turns an opaque material's normals there already; a dielectric's stay outward (its
// refraction needs the side), which only its partial transmission's lobes must undo.
float lobe_side(Bsdf b) {
#if HAS_PARTIAL_TRANSMISSION
    return dot(b.ng, b.wo) >= 0.0 ? 1.0 : -1.0;
#else
    return 1.0;
#endif
}

#if HAS_GGX
// An opaque material's diffuse and GGX selection probabilities with `c` the fixed
// direction's cosine (fresnel_lobe_weights), for the reverse pdfs; the other components'
// weights (Phong, mirror: luminance albedos) do not depend on it.
void lobe_probs_at(Bsdf b, GpuMaterial m, float c, inout float p_d, inout float p_g) {
    float a_d = 0.0, a_g = 0.0, rest = 0.0;
#if HAS_DIFFUSE_TRANSMISSION
    a_d = luminance(diffuse_colour(m, b.tint.rgb) * b.dt_reflect + b.dt_colour);
#elif HAS_DIFFUSE
    a_d = luminance(diffuse_colour(m, b.tint.rgb));
#endif
    a_g = luminance(glossy_colour(m, b.tint.rgb));
#if HAS_PHONG
    rest += luminance(m.phong.rgb);
#endif
#if HAS_MIRROR
    rest += luminance(mirror_colour(m, b.tint.rgb));
#endif
    fresnel_lobe_weights(m, b.tint, c, a_d, a_g);
    float total = a_d + a_g + rest;
    if (total < 1e-9) return;
    p_d = a_d / total;
    p_g = a_g / total;
}
#endif

// The diffuse, Phong and GGX lobes: f(wo, wi) and the pdfs with their component
// probabilities (bsdf_eval).
vec3 lobes_eval(Bsdf b, vec3 wi, out float pdf_fwd, out float pdf_rev) {
    pdf_fwd = 0.0;
    pdf_rev = 0.0;
    float side = lobe_side(b);
    vec3 n = side * b.n;
    float cos_o = dot(n, b.wo);
    float cos_i = dot(n, wi);
#if HAS_DIFFUSE_TRANSMISSION
    // wi on the other side: a diffuse transmission, evaluated at |n.wi| (the other lobes
    // only reflect).
    bool through = cos_i < 0.0 && b.prob_dt > 0.0;
    if (through) cos_i = -cos_i;
#else
    const bool through = false;
#endif
    if (b.delta || cos_o < EPS_COSINE || cos_i < EPS_COSINE) return vec3(0.0);
#if HAS_SHADING_NORMALS
    // A reflection: wi on wo's side of the geometric surface (no light leaks); a
    // transmission: on the other side.
    vec3 ng = side * b.ng;
    if ((through ? -dot(ng, wi) : dot(ng, wi)) <= 0.0 || dot(ng, b.wo) <= 0.0) return vec3(0.0);
#endif
    GpuMaterial m = point_material(b.material, b.tint);
    vec3 f = vec3(0.0);
    // The component probabilities of sampling wo from wi (the reverse pdf): bsdf_init's,
    // but for the lobes whose selection weight depends on the fixed direction.
    float rev_d = b.prob_diffuse, rev_g = b.prob_glossy;
#if HAS_GGX
    if (m.phong.w < 0.0) lobe_probs_at(b, m, cos_i, rev_d, rev_g);
#endif
#if HAS_DIFFUSE_TRANSMISSION
    if (through) return diffuse_transmission_eval(b, m, cos_o, cos_i, rev_d, pdf_fwd, pdf_rev);
#endif
#if HAS_DIFFUSE
    if (b.prob_diffuse > 0.0) {
        vec3 colour = diffuse_colour(m, b.tint.rgb);
        float p_d = b.prob_diffuse;
#if HAS_DIFFUSE_TRANSMISSION
        // The reflection's share of the diffuse component (the transmission has the rest).
        colour *= b.dt_reflect;
        p_d *= 1.0 - b.prob_dt;
        rev_d *= 1.0 - b.prob_dt;
#endif
        float f0 = m.mirror.w;
        if (f0 > 0.0) {
#if HAS_IRIDESCENCE
            // The iridescent interface: diffuse_fresnel_weight per channel with the film's
            // F and its E_avg (glsl/lobes/iridescence.glsl).
            if (b.interface_e_avg != vec3(0.0)) {
                vec3 w = (1.0 - specular_fresnel(m, b.tint, vec3(f0), cos_o)) *
                         (1.0 - specular_fresnel(m, b.tint, vec3(f0), cos_i)) / (1.0 - b.interface_e_avg);
                f += colour * w * INV_PI;
            } else
#endif
            f += colour * (INV_PI * diffuse_fresnel_weight(f0, m.glossy.w, cos_o, cos_i));
        } else {
            f += colour * INV_PI;
        }
        pdf_fwd += p_d * diffuse_pdf(b, m, cos_i);
        pdf_rev += rev_d * diffuse_pdf(b, m, cos_o);
    }
#endif
#if HAS_PHONG
    if (b.prob_phong > 0.0) {
        float e = m.diffuse.w;
        vec3 r = 2.0 * cos_o * n - b.wo;
        float cos_r = dot(r, wi);
        if (cos_r > EPS_COSINE) {
            float v = pow(cos_r, e);
            f += m.phong.rgb * (e + 2.0) * 0.5 * INV_PI * v;
            float p = b.prob_phong * (e + 1.0) * 0.5 * INV_PI * v;
            pdf_fwd += p;
            pdf_rev += p;
        }
    }
#endif
#if HAS_GGX
    if (b.prob_glossy > 0.0) {
        float pf, pr;
        vec3 f0 = glossy_colour(m, b.tint.rgb);
        vec3 film = vec3(1.0);
#if HAS_IRIDESCENCE
        // The film's Fresnel term at the half vector (glsl/lobes/iridescence.glsl) times the
        // microfacet term taken with F = 1 (Schlick's with F0 = 1).
        if (iridescence_at(m, b.tint).x > 0.0) {
            film = specular_fresnel(m, b.tint, f0, max(dot(b.wo, normalize(b.wo + wi)), 0.0));
            f0 = vec3(1.0);
        }
#endif
#if HAS_ANISOTROPY
        if (b.tint.anisotropy.w > 0.0) {
            f += film * ggx_anisotropic_eval(n, b.tint.anisotropy, b.wo, wi, cos_o, cos_i, f0, m.glossy.w, pf, pr);
        } else
#endif
        f += film * ggx_eval(n, b.wo, wi, cos_o, cos_i, f0, m.glossy.w, pf, pr);
        pdf_fwd += b.prob_glossy * pf;
        pdf_rev += rev_g * pr;
    }
#endif
#if HAS_PARTIAL_TRANSMISSION
    f *= b.lobes_weight;
#endif
    return f;
}

// Non-specular part: f(wo, wi) and the solid-angle pdfs of sampling wi given wo (fwd)
// and wo given wi (rev), both including the component probability but not Russian
// roulette. Zero when either direction is below the surface (but for the rough
// dielectric, which transmits).
vec3 base_bsdf_eval(Bsdf b, vec3 wi, out float pdf_fwd, out float pdf_rev) {
#if HAS_ROUGH_DIELECTRIC
    if (b.prob_rough > 0.0) {
        vec3 f = rough_dielectric_eval(b, wi, pdf_fwd, pdf_rev);
#if HAS_PARTIAL_TRANSMISSION
        if (b.prob_rough < 1.0) {
            // Beside the lobes (partial transmission): the mixture's f and pdfs.
            float pf, pr;
            f = f * b.interface_weight + lobes_eval(b, wi, pf, pr);
            pdf_fwd = pdf_fwd * b.prob_rough + pf;
            pdf_rev = pdf_rev * b.prob_rough + pr;
        }
#endif
        return f;
    }
#endif
    return lobes_eval(b, wi, pdf_fwd, pdf_rev);
}

// Veach's adjoint correction |n.wo| |ng.wi| / (|ng.wo| |n.wi|) for light subpaths (eq.
// 5.19); exactly 1 for camera subpaths and for flat shading.
float shading_correction(Bsdf b, vec3 wi) {
#if HAS_SHADING_NORMALS
    if (b.from_light && b.n != b.ng)
        return abs(dot(b.n, b.wo)) * abs(dot(b.ng, wi)) / (abs(dot(b.ng, b.wo)) * abs(dot(b.n, wi)));
#endif
    return 1.0;
}

// The cosine that multiplies f(wo, wi) in the path throughput (the header's rule: |n.wi|
// for camera subpaths, |n.wo| |ng.wi| / |ng.wo| for light subpaths).
float bsdf_cos(Bsdf b, vec3 wi) { return abs(dot(b.n, wi)) * shading_correction(b, wi); }

// |ng.w|: the cosine of solid-angle <-> area conversions at this vertex (MIS).
float bsdf_cos_geometric(Bsdf b, vec3 w) { return abs(dot(b.ng, w)); }

struct BsdfSample {
    vec3 wi;
    vec3 weight;     // f bsdf_cos(wi) / pdf (the path-throughput factor, before roulette)
    float pdf;       // solid-angle pdf (component probability for specular events)
    float pdf_rev;
    float cos_wi;    // |ng.wi|, for the MIS quantities
    bool specular;
    bool ok;
};

// The whole BSDF, the coat included (below); the base's sampling values its samples by it.
vec3 bsdf_eval(Bsdf b, vec3 wi, out float pdf_fwd, out float pdf_rev);

// A failed sample (ok false, zero weight and pdfs), filled in by the samplers.
BsdfSample no_sample() {
    BsdfSample s;
    s.ok = false;
    s.specular = false;
    s.pdf = 0.0;
    s.pdf_rev = 0.0;
    s.weight = vec3(0.0);
    s.wi = vec3(0.0);
    s.cos_wi = 0.0;
    return s;
}

// Completes a sample whose non-specular direction s.wi a lobe drew: valued by the whole
// BSDF with both pdfs (every lobe that could have drawn it); not ok where none could.
BsdfSample valued_sample(Bsdf b, BsdfSample s) {
    vec3 f = bsdf_eval(b, s.wi, s.pdf, s.pdf_rev);
    if (s.pdf <= 0.0) return s;
    s.cos_wi = bsdf_cos_geometric(b, s.wi);
    s.weight = f * (bsdf_cos(b, s.wi) / s.pdf);
    s.ok = true;
    return s;
}

BsdfSample base_bsdf_sample(Bsdf b, vec3 u) {
    BsdfSample s = no_sample();
    if (!b.valid) return s;
    float x = u.z;
    float p_nonspec = b.prob_diffuse + b.prob_phong + b.prob_glossy;
#if HAS_ROUGH_DIELECTRIC
    // The rough dielectric is drawn for x in [p_nonspec, 1) (all of it without partial
    // transmission, where p_nonspec is 0), the lobes below.
    if (b.prob_rough > 0.0 && x >= p_nonspec) {
        // The rough dielectric (the header): h from the normals visible from wo about the
        // normal on wo's side, then reflection with probability F(wo.h) (x rescaled to
        // [0, 1)), else refraction.
        float x_rough = (x - p_nonspec) / b.prob_rough;
        GpuMaterial mr = material_at(b.material);
        float side = dot(b.ng, b.wo) >= 0.0 ? 1.0 : -1.0;
        vec3 h = ggx_sample_h(side * b.n, b.wo, mr.emission.w, u.xy);
        float oh = dot(b.wo, h);
        if (oh < EPS_COSINE) return s;
#if HAS_DISPERSION
        mr.phong.w = dispersed_ior(mr, b.tint);
#endif
        bool reflect_h = x_rough < fresnel_dielectric(side * oh, mr.phong.w);
        if (reflect_h) {
            s.wi = 2.0 * oh * h - b.wo;
        } else {
            float eta = b.eta_ratio;
            float sin2_t = eta * eta * max(0.0, 1.0 - oh * oh);
            if (sin2_t >= 1.0) return s;  // total internal reflection has F = 1
            float ct = sqrt(1.0 - sin2_t);
            s.wi = normalize(-eta * b.wo + (eta * oh - ct) * h);
        }
        // bsdf_eval's event (the geometric side of wi) must be the one drawn.
        if ((side * dot(b.ng, s.wi) > 0.0) != reflect_h) return s;
        return valued_sample(b, s);
    }
#endif
    GpuMaterial m = point_material(b.material, b.tint);
    vec3 n = lobe_side(b) * b.n;
    float cos_o = dot(n, b.wo);
#if HAS_DIFFUSE || HAS_PHONG || HAS_GGX
    if (x < p_nonspec) {
        bool through = false;  // a diffuse transmission, into the other hemisphere
        // An absent component has probability 0, so its branch is never taken.
#if HAS_DIFFUSE
        if (x < b.prob_diffuse) {
            s.wi = to_world(sample_diffuse(b, m, u.xy), n);
#if HAS_DIFFUSE_TRANSMISSION
            // x / prob_diffuse is uniform on [0, 1): the transmission with probability prob_dt.
            through = x < b.prob_diffuse * b.prob_dt;
            if (through) s.wi = -s.wi;
#endif
        } else
#endif
#if HAS_GGX
        if (x >= b.prob_diffuse + b.prob_phong) {
            // GGX: half vector from the normals visible from wo, then reflect wo about it.
#if HAS_ANISOTROPY
            vec3 h = ggx_anisotropic_sample_h(n, b.tint.anisotropy, b.wo, m.glossy.w, u.xy);
#else
            vec3 h = ggx_sample_h(n, b.wo, m.glossy.w, u.xy);
#endif
            float oh = dot(b.wo, h);
            if (oh <= 0.0) return s;
            s.wi = 2.0 * oh * h - b.wo;
        } else
#endif
        {
#if HAS_PHONG
            float e = m.diffuse.w;
            vec3 r = 2.0 * cos_o * n - b.wo;
            float ct = pow(u.x, 1.0 / (e + 1.0));
            float st = sqrt(max(0.0, 1.0 - ct * ct));
            float phi = 2.0 * PI * u.y;
            s.wi = to_world(vec3(st * cos(phi), st * sin(phi), ct), r);
#else
            return s;  // unreachable: x < p_nonspec selects a present component
#endif
        }
        if ((through ? -dot(n, s.wi) : dot(n, s.wi)) < EPS_COSINE) return s;
        return valued_sample(b, s);
    }
#endif
    s.specular = true;
#if HAS_MIRROR
    if (x < p_nonspec + b.prob_reflect) {
        s.wi = 2.0 * dot(b.n, b.wo) * b.n - b.wo;
#if HAS_SHADING_NORMALS
        if (dot(b.ng, s.wi) * dot(b.ng, b.wo) <= 0.0) return s;  // would leak through
#endif
        s.pdf = b.prob_reflect;
        s.pdf_rev = b.prob_reflect;
        s.cos_wi = bsdf_cos_geometric(b, s.wi);
        // f bsdf_cos / pdf with f = F mirror / |n.wi|.
        s.weight = b.fresnel * mirror_colour(m, b.tint.rgb) * shading_correction(b, s.wi) / b.prob_reflect;
#if HAS_PARTIAL_TRANSMISSION
        s.weight *= b.interface_weight;
#endif
    } else
#endif
    {
#if HAS_DIELECTRIC
        // Refraction: wo and the normal decide the side; eta_ratio = eta_o / eta_t.
        float c = dot(b.n, b.wo);
        vec3 n = c >= 0.0 ? b.n : -b.n;
        float ci = abs(c);
        float eta = b.eta_ratio;
        float sin2_t = eta * eta * max(0.0, 1.0 - ci * ci);
        if (sin2_t >= 1.0) return s;
        float ct = sqrt(1.0 - sin2_t);
        s.wi = normalize(-eta * b.wo + (eta * ci - ct) * n);
#if HAS_SHADING_NORMALS
        if (dot(b.ng, s.wi) * dot(b.ng, b.wo) >= 0.0) return s;  // would not cross the surface
#endif
        s.pdf = b.prob_refract;
        s.pdf_rev = b.prob_refract;
        // ct is |n.wi| before normalize's rounding: the geometric cosine when n == ng.
        s.cos_wi = b.n == b.ng ? ct : bsdf_cos_geometric(b, s.wi);
        // Radiance is scaled by (eta_o / eta_t)^2 crossing the boundary; the adjoint
        // (light subpath) transport is not (Veach 1997, 5.2). f = (1 - F) scale / |n.wi|.
        float scale = b.from_light ? 1.0 : eta * eta;
        s.weight = transmission_colour(m, b.tint.rgb) *
                   ((1.0 - b.fresnel) * scale * shading_correction(b, s.wi) / b.prob_refract);
#if HAS_PARTIAL_TRANSMISSION
        s.weight *= b.interface_weight;
#endif
#else
        // Without dielectrics prob_refract is 0: the generic kernel reaches this branch
        // only through rounding (x >= p_nonspec + prob_reflect) and fails (pdf 0) too.
        return s;
#endif
    }
    s.ok = s.pdf > 0.0;
    return s;
}

// For the layers of glsl/lobes/: whether wo is off the geometric surface and above the
// shading one on that side (bsdf_init's validity; the base may be invalid for its zero
// albedo alone), and a luminance albedo of the base that does not depend on directions
// (their sampling probabilities): its lobes' colours, plus the glass weight of a
// dielectric's interface (which reflects and transmits all it receives) or the mirror
// colour of an opaque material.
bool bsdf_seen(Bsdf b, vec3 d) {
    float c = dot(b.ng, d);
    return abs(c) >= EPS_COSINE && (c >= 0.0 ? dot(b.n, d) : -dot(b.n, d)) >= EPS_COSINE;
}
bool bsdf_wo_seen(Bsdf b) { return bsdf_seen(b, b.wo); }
float base_albedo_luminance(GpuMaterial m, Tint tint) {
    float lobes = luminance(diffuse_colour(m, tint.rgb) + m.phong.rgb + glossy_colour(m, tint.rgb));
    if (m.phong.w >= 0.0) return lobes * (1.0 - m.transmission.w) + m.transmission.w;
    return lobes + luminance(mirror_colour(m, tint.rgb));
}

// The material's BSDF: the base above (the lobes of this file) under the layers of
// glsl/lobes/ that the material has (glTF's order: the coat over the sheen over the
// base). Without such layers, the base's, bit for bit.
#include "lobes/sheen.glsl"
#include "lobes/clearcoat.glsl"

Bsdf bsdf_init(uint material, vec3 ng, vec3 ns, vec3 wo, bool from_light, Tint tint) {
    Bsdf b = base_bsdf_init(material, ng, ns, wo, from_light, tint);
#if HAS_SHEEN
    sheen_init(b, point_material(material, tint));
#endif
#if HAS_CLEARCOAT
    clearcoat_init(b, point_material(material, tint));
#endif
    return b;
}

// The continuation probability of the vertex of `b` were `d` its fixed direction
// (b.cont_prob is it at wo): the reverse pdfs of the MIS quantities include it, as the
// forward ones include b.cont_prob (a reverse pdf is the density of the path's other
// direction, sampled at this vertex from d). SmallVCM multiplies both by the vertex's own,
// exact where it does not depend on the direction; here it does under a clear coat or a
// sheen (their shares of the albedo depend on it) and on a dielectric (F).
float cont_prob_from(Bsdf b, vec3 d) {
    if (!b.cont_prob_varies) return b.cont_prob;
    float p = base_cont_prob(b, b.ior < 0.0 ? 1.0 : fresnel_dielectric(dot(b.n, d), b.ior));
#if HAS_SHEEN
    p = sheen_cont_prob(b, d, p);
#endif
#if HAS_CLEARCOAT
    p = coat_cont_prob(b, d, p);
#endif
    return p;
}

// f(wo, wi) of the non-specular part and the solid-angle pdfs of sampling wi given wo
// (fwd) and wo given wi (rev), both including the component probability but not Russian
// roulette.
vec3 bsdf_eval(Bsdf b, vec3 wi, out float pdf_fwd, out float pdf_rev) {
    vec3 f = base_bsdf_eval(b, wi, pdf_fwd, pdf_rev);
#if HAS_SHEEN
    if (b.sheen_max > 0.0) f = sheen_eval(b, wi, f, pdf_fwd, pdf_rev);
#endif
#if HAS_CLEARCOAT
    if (b.coat_weight > 0.0) f = clearcoat_eval(b, wi, f, pdf_fwd, pdf_rev);
#endif
    return f;
}

BsdfSample bsdf_sample(Bsdf b, vec3 u) {
#if HAS_CLEARCOAT
    if (b.prob_coat > 0.0) {
        if (u.z < b.prob_coat) return clearcoat_sample(b, u.xy);
        u.z = (u.z - b.prob_coat) / (1.0 - b.prob_coat);
    }
#endif
#if HAS_SHEEN
    if (b.prob_sheen > 0.0) {
        if (u.z < b.prob_sheen) return sheen_sample(b, u.xy);
        u.z = (u.z - b.prob_sheen) / (1.0 - b.prob_sheen);
    }
#endif
    BsdfSample s = base_bsdf_sample(b, u);
#if HAS_SHEEN
    if (s.ok && s.specular && b.sheen_max > 0.0) sheen_specular(b, s);
#endif
#if HAS_CLEARCOAT
    if (s.ok && s.specular && b.coat_weight > 0.0) clearcoat_specular(b, s);
#endif
    return s;
}

#endif
