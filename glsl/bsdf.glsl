// vkvcm's material model, written once for every estimator: Lambert + normalised Phong
// lobe + GGX microfacet reflection + Fresnel-weighted mirror / smooth dielectric.
// Component choice and Russian roulette follow SmallVCM (Georgiev & Davidovic), as
// docs/smallvcm.md 2.4 states: component probabilities proportional to luminance
// albedo, continuation probability = clamp(max RGB of (diffuse + phong + glossy +
// F mirror) + (1 - F), 0, 1) (glossy is zero for SmallVCM's materials, so their rule is
// unchanged). pt.comp does not use this continuation probability (pbrt-v4's rule there).
//
// GGX lobe (`glossy`, used for glTF metallic/roughness): Trowbridge-Reitz distribution D
// as in Walter, Marschner, Li, Torrance, "Microfacet Models for Refraction through Rough
// Surfaces" (EGSR 2007); Smith height-correlated masking-shadowing
// G2 = 1 / (1 + Lambda(wo) + Lambda(wi)) as in Heitz, "Understanding the Masking-
// Shadowing Function in Microfacet-Based BRDFs" (JCGT 2014); Schlick's Fresnel with
// F0 = the lobe's colour (a metal's colour, or 0.04 for a dielectric coat). It is
// sampled by D(h) cos(theta_h) (Walter 2007), not by the visible normals (Heitz 2018):
// pdf(wi | wo) = D(h) cos(theta_h) / (4 |wo.h|), and since wo.h = wi.h for a reflection
// the reverse pdf has the same form with wi.h. f, being reciprocal, needs no adjoint
// correction.
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
// Components no material of the scene has are compiled out (HAS_DIFFUSE, HAS_PHONG,
// HAS_GGX, HAS_MIRROR, HAS_DIELECTRIC: glsl/features.glsl); the branches taken and the
// arithmetic done for the components present are the same as with all of them.
//
// A point's material is its material's, varied by the point's tint (glsl/textures.glsl,
// `Tint`): the base colour (`diffuse_colour` etc.) and, with a metallic-roughness
// texture, the lobes that depend on metallic and roughness (`point_material`). The tint
// is a property of the point, so bsdf_init, bsdf_eval and bsdf_sample all see the same
// lobes, and the component probabilities and pdfs stay exact.
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
    float cont_prob;
    float fresnel;   // reflectance F (1 for non-dielectrics)
    float eta_ratio; // eta on the wo side / eta on the other side (dielectrics)
    bool valid;
    bool delta;      // only specular components
    bool from_light; // fixed direction belongs to a light subpath (adjoint BSDF)
    Tint tint;       // the surface point's tint (glsl/textures.glsl)
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
    if (tint != vec3(1.0)) return m.mirror.rgb * tint;
#endif
    return m.mirror.rgb;
}
vec3 glossy_colour(GpuMaterial m, vec3 tint) {
#if HAS_VERTEX_ATTRIBUTES
    if (tint != vec3(1.0)) return vec3(m.surface.w) + (m.glossy.rgb - vec3(m.surface.w)) * tint;
#endif
    return m.glossy.rgb;
}

// The material `material` at a point of tint `tint`. Where a metallic-roughness texture
// gave the point a metallic or roughness other than the factors
// (HAS_METALLIC_ROUGHNESS_TEXTURES), the lobes that depend on them are glTF's at the
// point's metallic = factor x texel B and roughness = factor x texel G (glTF 2.0 section
// 3.9.2; Material::metallic_roughness_lobes in src/scene/mod.rs computes the same for
// the factors): diffuse (1 - metallic) base, GGX F0 mix(dielectric F0, base, metallic)
// of which mean(dielectric F0) (1 - metallic) is untinted, GGX alpha roughness^2 (at
// least MIN_GGX_ALPHA). The diffuse lobe's interface F0 (mirror.w) does not depend on
// them. Elsewhere the material's own values, bit for bit.
GpuMaterial point_material(uint material, Tint tint) {
    GpuMaterial m = material_at(material);
#if HAS_METALLIC_ROUGHNESS_TEXTURES
    if (tint.roughness != 1.0 || tint.metallic != 1.0) {
        vec3 base = m.base_metallic.rgb;
        vec3 f0 = m.f0_roughness.rgb;
        float metallic = m.base_metallic.w * tint.metallic;
        float roughness = m.f0_roughness.w * tint.roughness;
        m.diffuse.rgb = base * (1.0 - metallic);
        m.glossy.rgb = f0 + (base - f0) * metallic;
        m.glossy.w = max(roughness * roughness, MIN_GGX_ALPHA);
        m.surface.w = (f0.r + f0.g + f0.b) / 3.0 * (1.0 - metallic);
    }
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

// The GGX lobe for unit wo, wi above the surface (cos_o, cos_i > 0): f, and the pdfs of
// sampling wi given wo (fwd) and wo given wi (rev) by D(h) cos(theta_h), without the
// component probability.
vec3 ggx_eval(vec3 n, vec3 wo, vec3 wi, float cos_o, float cos_i, vec3 f0, float a, out float pdf_fwd,
              out float pdf_rev) {
    pdf_fwd = 0.0;
    pdf_rev = 0.0;
    vec3 hs = wo + wi;
    float hl = length(hs);
    if (hl < 1e-7) return vec3(0.0);
    vec3 h = hs / hl;
    float ch = dot(n, h);
    float oh = dot(wo, h);
    float ih = dot(wi, h);
    if (ch < EPS_COSINE || oh < EPS_COSINE || ih < EPS_COSINE) return vec3(0.0);
    float d = ggx_d(ch, a);
    float g2 = 1.0 / (1.0 + ggx_lambda(cos_o, a) + ggx_lambda(cos_i, a));
    vec3 fr = schlick(f0, oh);
    pdf_fwd = d * ch / (4.0 * oh);
    pdf_rev = d * ch / (4.0 * ih);
    return fr * (d * g2 / (4.0 * cos_o * cos_i));
}

// The weight of a diffuse lobe under a dielectric interface of Schlick F0 `f0` (glTF's
// metallic/roughness dielectric): (1 - F(cos_o)) (1 - F(cos_i)) / (1 - E_avg), with
// E_avg = 2 int_0^1 F(mu) mu dmu = f0 + (1 - f0) / 21 the cosine-weighted average of F.
// The coupled matte-specular weighting of Kelemen and Szirmay-Kalos, "A Microfacet Based
// Coupled Specular-Matte BRDF Model with Importance Sampling" (Eurographics 2001), with
// Schlick's F standing in for the specular lobe's albedo: symmetric in wo and wi (so
// reciprocal, no adjoint), and for a white base the diffuse albedo at wo is exactly
// 1 - F(cos_o), so diffuse + specular never exceed 1. glTF's reference `fresnel_mix`
// weights the diffuse lobe by 1 - F(wo.h) instead, which reflects up to 1.7 times what a
// white smooth surface receives at grazing angles (docs/scene-format.md).
float diffuse_fresnel_weight(float f0, float cos_o, float cos_i) {
    return (1.0 - schlick(f0, cos_o)) * (1.0 - schlick(f0, cos_i)) / (1.0 - (f0 + (1.0 - f0) / 21.0));
}

// `ng`: geometric normal (for a dielectric it must point outwards); `ns`: shading normal
// on the same side as ng (== ng for flat shading); `tint`: the point's tint (Surface.tint).
Bsdf bsdf_init(uint material, vec3 ng, vec3 ns, vec3 wo, bool from_light, Tint tint) {
    Bsdf b;
    GpuMaterial m = point_material(material, tint);
    float ior = m.phong.w;
    b.material = material;
    b.wo = wo;
    b.from_light = from_light;
    b.tint = tint;
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
#endif
#if HAS_MIRROR
    vec3 mirror = mirror_colour(m, tint.rgb);
    a_r = b.fresnel * luminance(mirror);
    albedo += b.fresnel * mirror;
#endif
#if HAS_DIELECTRIC
    a_t = ior < 0.0 ? 0.0 : 1.0 - b.fresnel;
#endif
    float total = a_d + a_p + a_g + a_r + a_t;
    if (total < 1e-9) {
        b.valid = false;
        total = 1.0;
    }
    b.prob_diffuse = a_d / total;
    b.prob_phong = a_p / total;
    b.prob_glossy = a_g / total;
    b.prob_reflect = a_r / total;
    b.prob_refract = a_t / total;
    b.cont_prob = clamp(max3(albedo) + (1.0 - b.fresnel), 0.0, 1.0);
    b.delta = b.prob_diffuse == 0.0 && b.prob_phong == 0.0 && b.prob_glossy == 0.0;
    return b;
}

// Non-specular part: f(wo, wi) and the solid-angle pdfs of sampling wi given wo (fwd)
// and wo given wi (rev), both including the component probability but not Russian
// roulette. Zero when either direction is below the surface.
vec3 bsdf_eval(Bsdf b, vec3 wi, out float pdf_fwd, out float pdf_rev) {
    pdf_fwd = 0.0;
    pdf_rev = 0.0;
    float cos_o = dot(b.n, b.wo);
    float cos_i = dot(b.n, wi);
    if (b.delta || cos_o < EPS_COSINE || cos_i < EPS_COSINE) return vec3(0.0);
#if HAS_SHADING_NORMALS
    // A reflection: wi on wo's side of the geometric surface (no light leaks).
    if (dot(b.ng, wi) <= 0.0 || dot(b.ng, b.wo) <= 0.0) return vec3(0.0);
#endif
    GpuMaterial m = point_material(b.material, b.tint);
    vec3 f = vec3(0.0);
#if HAS_DIFFUSE
    if (b.prob_diffuse > 0.0) {
        float f0 = m.mirror.w;
        if (f0 > 0.0) {
            f += diffuse_colour(m, b.tint.rgb) * (INV_PI * diffuse_fresnel_weight(f0, cos_o, cos_i));
        } else {
            f += diffuse_colour(m, b.tint.rgb) * INV_PI;
        }
        pdf_fwd += b.prob_diffuse * cos_i * INV_PI;
        pdf_rev += b.prob_diffuse * cos_o * INV_PI;
    }
#endif
#if HAS_PHONG
    if (b.prob_phong > 0.0) {
        float e = m.diffuse.w;
        vec3 r = 2.0 * cos_o * b.n - b.wo;
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
        f += ggx_eval(b.n, b.wo, wi, cos_o, cos_i, glossy_colour(m, b.tint.rgb), m.glossy.w, pf, pr);
        pdf_fwd += b.prob_glossy * pf;
        pdf_rev += b.prob_glossy * pr;
    }
#endif
    return f;
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

BsdfSample bsdf_sample(Bsdf b, vec3 u) {
    BsdfSample s;
    s.ok = false;
    s.specular = false;
    s.pdf = 0.0;
    s.pdf_rev = 0.0;
    s.weight = vec3(0.0);
    s.wi = vec3(0.0);
    s.cos_wi = 0.0;
    if (!b.valid) return s;
    GpuMaterial m = point_material(b.material, b.tint);
    float cos_o = dot(b.n, b.wo);
    float x = u.z;
    float p_nonspec = b.prob_diffuse + b.prob_phong + b.prob_glossy;
#if HAS_DIFFUSE || HAS_PHONG || HAS_GGX
    if (x < p_nonspec) {
        // An absent component has probability 0, so its branch is never taken.
#if HAS_DIFFUSE
        if (x < b.prob_diffuse) {
            s.wi = to_world(sample_cosine_hemisphere(u.xy), b.n);
        } else
#endif
#if HAS_GGX
        if (x >= b.prob_diffuse + b.prob_phong) {
            // GGX: half vector from D(h) cos(theta_h): tan^2(theta_h) = a^2 u / (1 - u)
            // (Walter et al. 2007, eq. 35-36), then reflect wo about it.
            float a = m.glossy.w;
            float t2 = a * a * u.x / max(1.0 - u.x, 1e-7);
            float ch = 1.0 / sqrt(1.0 + t2);
            float sh = sqrt(max(0.0, 1.0 - ch * ch));
            float phi = 2.0 * PI * u.y;
            vec3 h = to_world(vec3(sh * cos(phi), sh * sin(phi), ch), b.n);
            float oh = dot(b.wo, h);
            if (oh <= 0.0) return s;
            s.wi = 2.0 * oh * h - b.wo;
        } else
#endif
        {
#if HAS_PHONG
            float e = m.diffuse.w;
            vec3 r = 2.0 * cos_o * b.n - b.wo;
            float ct = pow(u.x, 1.0 / (e + 1.0));
            float st = sqrt(max(0.0, 1.0 - ct * ct));
            float phi = 2.0 * PI * u.y;
            s.wi = to_world(vec3(st * cos(phi), st * sin(phi), ct), r);
#else
            return s;  // unreachable: x < p_nonspec selects a present component
#endif
        }
        vec3 f = bsdf_eval(b, s.wi, s.pdf, s.pdf_rev);
        if (s.pdf <= 0.0 || dot(b.n, s.wi) < EPS_COSINE) return s;
        s.cos_wi = bsdf_cos_geometric(b, s.wi);
        s.weight = f * (bsdf_cos(b, s.wi) / s.pdf);
        s.ok = true;
        return s;
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
        s.weight = vec3((1.0 - b.fresnel) * scale * shading_correction(b, s.wi) / b.prob_refract);
#else
        // Without dielectrics prob_refract is 0: the generic kernel reaches this branch
        // only through rounding (x >= p_nonspec + prob_reflect) and fails (pdf 0) too.
        return s;
#endif
    }
    s.ok = s.pdf > 0.0;
    return s;
}

#endif
