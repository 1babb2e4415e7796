// Iridescence (glTF KHR_materials_iridescence): a thin dielectric film over the base, whose
// interference replaces the Fresnel term of the metallic/roughness reflection,
//   F = mix(F_schlick(F0, c), F_iridescence(F0, c), iridescence),
// c the cosine of the direction with the half vector (the GGX lobe) or the normal (the
// diffuse lobe's interface, below). F_iridescence is Belcour & Barla, "A Practical
// Extension to Microfacet Theory for the Modeling of Varying Iridescence" (SIGGRAPH 2017),
// in the approximation the extension writes out: Schlick reflectances at the air-film
// and film-base interfaces (the base's IOR from F0, no extinction), phase shifts 0 or pi,
// the first two orders of the Airy sum, and the spectral integral against the CIE XYZ
// sensitivities fitted by Gaussians in Fourier space, converted to linear Rec. 709.
// The optical path difference is 2 n_film d cos(theta_film), the angle inside the film, as
// Belcour & Barla and the Khronos sample renderer (the extension's text has the outer
// angle). The result is clamped to [0, 1] per channel: the fit can leave the gamut of a
// reflectance (tests/render_iridescence.rs measures how far), and F > 1 would add energy.
//
// Where it applies (docs/scene-format.md, "Iridescence"): the GGX lobe (`glossy`, the
// metallic/roughness specular reflection, metal and dielectric), with F_iridescence
// evaluated at the lobe's F0 = mix(F0_dielectric, base, metallic), which is glTF's
// mix(F_iridescence(F0_dielectric), F_iridescence(base), metallic) at metallic 0 and 1; and
// the interface over the diffuse lobe, whose Kelemen coupling (diffuse_fresnel_weight)
// takes the same F per channel at the interface's F0, so the pair still reflects at most
// what it receives. Not the smooth or rough glass (their Fresnel is exact, not Schlick's),
// the clear coat (the film lies under it, glTF) or the Phong lobe.
//
// Requires: glsl/bsdf.glsl up to `schlick` (GpuMaterial, Tint, luminance).
#ifndef IRIDESCENCE_GLSL
#define IRIDESCENCE_GLSL

#if HAS_IRIDESCENCE

// CIE XYZ to linear Rec. 709 (sRGB primaries, D65), columns as GLSL's mat3 takes them.
const mat3 IRIDESCENCE_XYZ_TO_REC709 = mat3(3.2404542, -0.9692660, 0.0556434, -1.5371385, 1.8760108, -0.2040259,
                                            -0.4985314, 0.0415560, 1.0572252);

// The XYZ sensitivities' Fourier transforms at optical path difference `opd` (nm), phase
// shifted by `shift`, in Rec. 709: Belcour & Barla's Gaussian fit (their supplemental
// code), normalised so that opd 0 gives white.
vec3 iridescence_sensitivity(float opd, vec3 shift) {
    float phase = 2.0 * PI * opd * 1e-9;
    const vec3 val = vec3(5.4856e-13, 4.4201e-13, 5.2481e-13);
    const vec3 pos = vec3(1.6810e+06, 1.7953e+06, 2.2084e+06);
    const vec3 var = vec3(4.3278e+09, 9.3046e+09, 6.6121e+09);
    vec3 xyz = val * sqrt(2.0 * PI * var) * cos(pos * phase + shift) * exp(-phase * phase * var);
    xyz.x += 9.7470e-14 * sqrt(2.0 * PI * 4.5282e+09) * cos(2.2399e+06 * phase + shift.x) *
             exp(-4.5282e+09 * phase * phase);
    return IRIDESCENCE_XYZ_TO_REC709 * (xyz / 1.0685e-7);
}

// F_iridescence of a film of index `film_ior` and thickness `thickness` (nm) in air over a
// base of Schlick F0 `f0`, at cosine `c` with the (micro)surface normal.
vec3 iridescence_fresnel(float film_ior, float thickness, vec3 f0, float c) {
    // A vanishing film is no film (the sample renderer's smoothstep over 0.03 nm).
    float n2 = mix(1.0, film_ior, smoothstep(0.0, 0.03, thickness));
    float sin2 = (1.0 - c * c) / (n2 * n2);
    if (sin2 >= 1.0) return vec3(1.0);  // total internal reflection into the film
    float c2 = sqrt(1.0 - sin2);
    // Air-film interface: Schlick reflectance, phase 0 entering a denser film, else pi.
    float r = (n2 - 1.0) / (n2 + 1.0);
    float r12 = schlick(r * r, c);
    float t121 = 1.0 - r12;
    float phi21 = n2 < 1.0 ? 0.0 : PI;
    // Film-base interface: the base's IOR from its F0 (no extinction), phase pi where the
    // base is the rarer medium.
    vec3 s = sqrt(clamp(f0, vec3(0.0), vec3(0.9999)));
    vec3 n3 = (1.0 + s) / (1.0 - s);
    vec3 q = (n3 - n2) / (n3 + n2);
    vec3 r23 = schlick(q * q, c2);
    vec3 phi = vec3(phi21) + mix(vec3(0.0), vec3(PI), lessThan(n3, vec3(n2)));
    float opd = 2.0 * n2 * thickness * c2;
    // The Airy sum: its mean (m = 0) and the first two interference orders.
    vec3 r123 = clamp(r12 * r23, vec3(1e-5), vec3(0.9999));
    vec3 rs = t121 * t121 * r23 / (1.0 - r123);
    vec3 result = r12 + rs;
    vec3 cm = rs - t121;
    vec3 sq = sqrt(r123);
    for (int k = 1; k <= 2; ++k) {
        cm *= sq;
        result += cm * 2.0 * iridescence_sensitivity(float(k) * opd, float(k) * phi);
    }
    return clamp(result, vec3(0.0), vec3(1.0));
}

// The iridescence factor and the film thickness (nm) of material `m` at a point of tint
// `tint`: iridescenceFactor x iridescenceTexture's R, and mix(thickness minimum, maximum,
// iridescenceThicknessTexture's G), the maximum without that texture (tint 1).
vec2 iridescence_at(GpuMaterial m, Tint tint) {
#if HAS_IRIDESCENCE_TEXTURES
    return vec2(m.iridescence.x * tint.iridescence.x, mix(m.iridescence.z, m.iridescence.w, tint.iridescence.y));
#else
    return vec2(m.iridescence.x, m.iridescence.w);
#endif
}

#endif

// The Fresnel term of the metallic/roughness reflection of Schlick F0 `f0` at cosine `c`,
// of material `m` at a point of tint `tint` (the header): Schlick's, mixed with the film's
// by the iridescence factor.
vec3 specular_fresnel(GpuMaterial m, Tint tint, vec3 f0, float c) {
    vec3 f = schlick(f0, c);
#if HAS_IRIDESCENCE
    vec2 k = iridescence_at(m, tint);
    if (k.x > 0.0) f = mix(f, iridescence_fresnel(m.iridescence.y, k.y, f0, c), k.x);
#endif
    return f;
}

#if HAS_IRIDESCENCE
// E_avg = 2 int_0^1 F(mu) mu dmu of specular_fresnel for F0 `f0`: the normalisation of the
// diffuse lobe's coupling (diffuse_fresnel_weight). The midpoint rule in mu over 16 cells:
// F changes slowly with mu (the path difference follows the film's cosine, which stays
// above sqrt(1 - 1 / n_film^2)); within 4e-4 of a fine quadrature for the films of
// tests/render_iridescence.rs.
vec3 iridescence_average(GpuMaterial m, Tint tint, float f0) {
    vec3 sum = vec3(0.0);
    for (int k = 0; k < 16; ++k) {
        float mu = (float(k) + 0.5) / 16.0;
        sum += specular_fresnel(m, tint, vec3(f0), mu) * mu;
    }
    return sum / 8.0;
}
#endif

#endif
