// Absorbing media inside closed dielectric meshes (glTF KHR_materials_volume), by
// Beer-Lambert's law: a path segment of length l through a medium of attenuation
// coefficient sigma (per channel, GpuMaterial.medium.rgb = -ln(attenuationColor) /
// attenuationDistance) transmits exp(-sigma l).
//
// Where the medium is: inside a closed mesh of a material with sigma != 0, the side of
// its surface opposite the geometric normal (the winding's normal, outward; a sphere's
// outward normal), the side a refracted ray enters. A segment is inside when one of its
// ends lies on such a surface and the segment leaves that end towards the inside
// (dot(d, ng) < 0 there). Both ends are asked, so every segment kind gets the same factor
// whichever way it is traced: camera and light subpath segments (the end they start from,
// and the surface they hit from inside), connections between two vertices, next-event
// and camera connections (the surface end; a light's or the camera's end has no
// material, NO_MATERIAL). With a closed mesh whose inside holds nothing else, both rules
// give the same answer; a segment between an object inside the medium and the medium's
// boundary is attenuated too; one between two other surfaces inside (or from a light
// inside to such a surface) is not: media are not tracked along a path, so there are no
// nested media. No scattering; the outside is vacuum.
//
// The factor is deterministic: it multiplies throughputs and contributions only and is no
// part of any pdf, forward or reverse, so every MIS weight stays what it was. Merging
// needs nothing more: a light vertex's throughput carries its subpath's segments.
//
// Requires: material_medium(i) (glsl/scene.glsl), features.glsl, types.glsl.
#ifndef MEDIUM_GLSL
#define MEDIUM_GLSL

#include "features.glsl"

#define NO_MATERIAL 0xffffffffu

// The attenuation coefficient of the medium that a segment leaving a surface of material
// `material` (geometric normal `ng`, as the winding gives it) along `d` enters: the
// material's when d points inside (against ng), else zero. NO_MATERIAL: zero.
vec3 medium_entered(uint material, vec3 ng, vec3 d) {
#if HAS_VOLUME
    if (material != NO_MATERIAL && dot(ng, d) < 0.0) return material_medium(material).rgb;
#endif
    return vec3(0.0);
}

// Transmittance of the segment from a (material `ma`, geometric normal `nga`) to b
// (`mb`, `ngb`) along unit `d` over `len` (an escaping segment: 1e30): exp(-sigma len)
// with sigma the medium that a enters, else the one that b enters going back (-d).
// Exactly 1 where neither end bounds a medium and without HAS_VOLUME.
vec3 segment_transmittance(uint ma, vec3 nga, uint mb, vec3 ngb, vec3 d, float len) {
#if HAS_VOLUME
    vec3 sigma = medium_entered(ma, nga, d);
    if (sigma == vec3(0.0)) sigma = medium_entered(mb, ngb, -d);
    // sigma 0 gives exp(-0) = 1 exactly; a huge sigma (a black attenuationColor) times a
    // huge length gives exp(-inf) = 0.
    if (sigma != vec3(0.0)) return exp(-sigma * len);
#endif
    return vec3(1.0);
}

#endif
