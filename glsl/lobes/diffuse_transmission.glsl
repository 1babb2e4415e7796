// Diffuse transmission (glTF KHR_materials_diffuse_transmission) through an opaque
// material: the diffuse lobe of the material's dielectric part becomes the extension's
//   mix(diffuse_brdf(base), diffuse_btdf(diffuseTransmissionColor), diffuseTransmission),
// a Lambertian reflection (1 - t) base / pi on wo's side of the surface plus a Lambertian
// transmission t c / pi on the other side, both under the diffuse lobe's interface weight
// (diffuse_fresnel_weight, at |n.wi| for the transmission: the light leaves through the
// interface of the other face, so the weight stays symmetric in wo and wi and the
// transmission reciprocal: no adjoint). t = diffuseTransmissionFactor x the A of its
// texture, c = diffuseTransmissionColorFactor x the RGB of its texture (sRGB) x
// (1 - metallic): the metal part transmits nothing. For a white base and colour the
// diffuse component's albedo at wo is 1 - E(cos_o) whatever t is: reflected plus
// transmitted never exceed what the interface lets in.
//
// Thin-walled: the transmitted ray leaves the surface on the far side; no volume is
// entered (KHR_materials_volume beside it is ignored with a warning: the importer).
// A surface that transmits is two-sided: the camera sees its back (Material::one_sided is
// false, src/scene/gltf_import/materials.rs), and the layers over it (sheen, clear coat)
// face both sides (`transmits_diffusely`), so light crossing it is scaled by the layer on
// the side it is seen from.
//
// Sampling: within the diffuse component (probability proportional to the luminance of
// (1 - t) base + t c, times 1 - F at the fixed direction, fresnel_lobe_weights), the
// transmission with probability prob_dt = lum(t c) / lum((1 - t) base + t c), which
// depends on the point alone, then the diffuse lobe's direction (glsl/bsdf.glsl,
// sample_diffuse) in the other hemisphere. So pdf(wi | wo) = P_d(wo) prob_dt
// diffuse_pdf(|n.wi|) and the reverse pdf is P_d(wi) prob_dt diffuse_pdf(|n.wo|).
//
// Requires: glsl/bsdf.glsl up to base_bsdf_init (Bsdf, diffuse_fresnel_weight, diffuse_pdf,
// luminance).
#ifndef DIFFUSE_TRANSMISSION_GLSL
#define DIFFUSE_TRANSMISSION_GLSL

#if HAS_DIFFUSE_TRANSMISSION

// The transmitted colour t c (the header) of material `m` at a point of tint `tint`; zero
// on a dielectric (none is uploaded there: Material::has_diffuse_transmission).
vec3 diffuse_transmission_colour(GpuMaterial m, Tint tint) {
    float t = m.diffuse_transmission.w * tint.diffuse_transmission.a;
    float metallic = clamp(m.diffuse_transmission_maps.z * tint.metallic, 0.0, 1.0);
    return m.diffuse_transmission.rgb * tint.diffuse_transmission.rgb * (t * (1.0 - metallic));
}

// Sets b's diffuse transmission (dt_reflect = 1 - t, dt_colour = t c, prob_dt) for the
// material `m` whose diffuse lobe has colour `diffuse`; returns the diffuse component's
// colour (1 - t) diffuse + t c.
vec3 diffuse_transmission_init(inout Bsdf b, GpuMaterial m, vec3 diffuse) {
    b.dt_reflect = 1.0;
    b.dt_colour = vec3(0.0);
    b.prob_dt = 0.0;
    if (m.phong.w >= 0.0 || m.diffuse_transmission.w <= 0.0) return diffuse;
    b.dt_reflect = 1.0 - m.diffuse_transmission.w * b.tint.diffuse_transmission.a;
    b.dt_colour = diffuse_transmission_colour(m, b.tint);
    vec3 reflected = diffuse * b.dt_reflect;
    float a_t = luminance(b.dt_colour);
    float total = luminance(reflected) + a_t;
    b.prob_dt = total > 0.0 ? a_t / total : 0.0;
    return reflected + b.dt_colour;
}

// The transmission for wo and wi on opposite sides, with cos_o = n.wo > 0 and cos_i =
// |n.wi| > 0 (n on wo's side), `rev_d` the diffuse component's probability at wi: f and
// both pdfs.
vec3 diffuse_transmission_eval(Bsdf b, GpuMaterial m, float cos_o, float cos_i, float rev_d, out float pdf_fwd,
                               out float pdf_rev) {
    pdf_fwd = b.prob_diffuse * b.prob_dt * diffuse_pdf(b, m, cos_i);
    pdf_rev = rev_d * b.prob_dt * diffuse_pdf(b, m, cos_o);
    float f0 = m.mirror.w;
    float w = f0 > 0.0 ? diffuse_fresnel_weight(f0, m.glossy.w, cos_o, cos_i) : 1.0;
    return b.dt_colour * (INV_PI * w);
}

#endif

// Whether the surface transmits diffusely at this point: then the layers over the base face
// both of its sides (the header).
bool transmits_diffusely(Bsdf b) {
#if HAS_DIFFUSE_TRANSMISSION
    return b.prob_dt > 0.0;
#else
    return false;
#endif
}

#endif
