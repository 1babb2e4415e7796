// vkvcm's material model, written once for every estimator: Lambert + normalised Phong
// lobe + Fresnel-weighted mirror / smooth dielectric. Component choice and Russian
// roulette follow SmallVCM (Georgiev & Davidovic), as ../shared/SCENES.md 2.4 states:
// component probabilities proportional to luminance albedo, continuation probability =
// clamp(max RGB of (diffuse + phong + F mirror) + (1 - F), 0, 1).
//
// Requires: `materials[]` (GpuMaterial) declared by the kernel, common.glsl, types.glsl.
#ifndef BSDF_GLSL
#define BSDF_GLSL

#define EPS_COSINE 1e-6

struct Bsdf {
    vec3 n;          // normal: for opaque materials on the side of wo; for dielectrics outward
    vec3 wo;         // the fixed direction (towards the previous vertex), unit
    uint material;
    float prob_diffuse, prob_phong, prob_reflect, prob_refract;
    float cont_prob;
    float fresnel;   // reflectance F (1 for non-dielectrics)
    float eta_ratio; // eta on the wo side / eta on the other side (dielectrics)
    bool valid;
    bool delta;      // only specular components
    bool from_light; // fixed direction belongs to a light subpath (adjoint BSDF)
};

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

// `ng`: geometric normal (for a dielectric it must point outwards).
Bsdf bsdf_init(uint material, vec3 ng, vec3 wo, bool from_light) {
    Bsdf b;
    GpuMaterial m = materials[material];
    float ior = m.phong.w;
    b.material = material;
    b.wo = wo;
    b.from_light = from_light;
    float c = dot(ng, wo);
    b.valid = abs(c) >= EPS_COSINE;
    if (ior < 0.0) {
        b.n = c >= 0.0 ? ng : -ng;  // opaque surfaces reflect on both sides
        b.fresnel = 1.0;
        b.eta_ratio = 1.0;
    } else {
        b.n = ng;
        b.fresnel = fresnel_dielectric(c, ior);
        b.eta_ratio = c >= 0.0 ? 1.0 / ior : ior;
    }
    float a_d = luminance(m.diffuse.rgb);
    float a_p = luminance(m.phong.rgb);
    float a_r = b.fresnel * luminance(m.mirror.rgb);
    float a_t = ior < 0.0 ? 0.0 : 1.0 - b.fresnel;
    float total = a_d + a_p + a_r + a_t;
    if (total < 1e-9) {
        b.valid = false;
        total = 1.0;
    }
    b.prob_diffuse = a_d / total;
    b.prob_phong = a_p / total;
    b.prob_reflect = a_r / total;
    b.prob_refract = a_t / total;
    b.cont_prob = clamp(max3(m.diffuse.rgb + m.phong.rgb + b.fresnel * m.mirror.rgb) + (1.0 - b.fresnel), 0.0, 1.0);
    b.delta = b.prob_diffuse == 0.0 && b.prob_phong == 0.0;
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
    GpuMaterial m = materials[b.material];
    vec3 f = vec3(0.0);
    if (b.prob_diffuse > 0.0) {
        f += m.diffuse.rgb * INV_PI;
        pdf_fwd += b.prob_diffuse * cos_i * INV_PI;
        pdf_rev += b.prob_diffuse * cos_o * INV_PI;
    }
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
    return f;
}

struct BsdfSample {
    vec3 wi;
    vec3 weight;     // f |cos wi| / pdf (the path-throughput factor, before roulette)
    float pdf;       // solid-angle pdf (component probability for specular events)
    float pdf_rev;
    float cos_wi;    // |cos| at wi
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
    GpuMaterial m = materials[b.material];
    float cos_o = dot(b.n, b.wo);
    float x = u.z;
    if (x < b.prob_diffuse + b.prob_phong) {
        if (x < b.prob_diffuse) {
            s.wi = to_world(sample_cosine_hemisphere(u.xy), b.n);
        } else {
            float e = m.diffuse.w;
            vec3 r = 2.0 * cos_o * b.n - b.wo;
            float ct = pow(u.x, 1.0 / (e + 1.0));
            float st = sqrt(max(0.0, 1.0 - ct * ct));
            float phi = 2.0 * PI * u.y;
            s.wi = to_world(vec3(st * cos(phi), st * sin(phi), ct), r);
        }
        vec3 f = bsdf_eval(b, s.wi, s.pdf, s.pdf_rev);
        s.cos_wi = dot(b.n, s.wi);
        if (s.pdf <= 0.0 || s.cos_wi < EPS_COSINE) return s;
        s.weight = f * (s.cos_wi / s.pdf);
        s.ok = true;
        return s;
    }
    s.specular = true;
    if (x < b.prob_diffuse + b.prob_phong + b.prob_reflect) {
        s.wi = 2.0 * dot(b.n, b.wo) * b.n - b.wo;
        s.pdf = b.prob_reflect;
        s.pdf_rev = b.prob_reflect;
        s.cos_wi = abs(dot(b.n, s.wi));
        // f |cos| / pdf with f = F mirror / |cos|.
        s.weight = b.fresnel * m.mirror.rgb / b.prob_reflect;
    } else {
        // Refraction: wo and the normal decide the side; eta_ratio = eta_o / eta_t.
        float c = dot(b.n, b.wo);
        vec3 n = c >= 0.0 ? b.n : -b.n;
        float ci = abs(c);
        float eta = b.eta_ratio;
        float sin2_t = eta * eta * max(0.0, 1.0 - ci * ci);
        if (sin2_t >= 1.0) return s;
        float ct = sqrt(1.0 - sin2_t);
        s.wi = normalize(-eta * b.wo + (eta * ci - ct) * n);
        s.pdf = b.prob_refract;
        s.pdf_rev = b.prob_refract;
        s.cos_wi = ct;
        // Radiance is scaled by (eta_o / eta_t)^2 crossing the boundary; the adjoint
        // (light subpath) transport is not (Veach 1997, 5.2).
        float scale = b.from_light ? 1.0 : eta * eta;
        s.weight = vec3((1.0 - b.fresnel) * scale / b.prob_refract);
    }
    s.ok = s.pdf > 0.0;
    return s;
}

#endif
