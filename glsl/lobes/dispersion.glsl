// KHR_materials_dispersion: glass whose IOR depends on the colour channel. The extension
// (its non-normative implementation note, what glTF viewers do) gives R, G and B their own
// IOR, (ior - s, ior, ior + s) with s = (ior - 1) 0.025 dispersion, at least 1
// (Material::dispersion_iors, GpuMaterial.dispersion.xyz).
//
// vkvcm carries RGB along a path, but a dispersive interface refracts each channel its own
// way, so a subpath that meets one carries one channel only. Each subpath (pt's path, the
// light and camera subpaths of the other estimators) starts with none (NO_CHANNEL: all
// three). Where it first reaches a point of a dispersive material, before anything is
// evaluated there, it draws channel c uniformly from {R, G, B} and multiplies its
// throughput by 3 e_c (only c survives; E[3 e_c] = 1 per channel, so unbiased):
// `choose_channel`. From then on the point's tint carries c (Tint.channel, set on every
// surface the subpath reaches and stored with its light vertices), and `point_material`
// (glsl/bsdf.glsl) gives a dispersive glass the IOR n_c: its Fresnel term and refraction,
// smooth or rough. Other materials do not depend on the channel, so a subpath's vertices
// before the choice hold for all three.
//
// A connection or merge of a camera vertex of channel a with a light vertex of channel b
// contributes nothing when both have chosen and a != b: the product of the throughputs
// carries both masks, 9 e_a e_b, zero then, so `channels_meet` only skips the work (the
// shadow ray) before it; the subpaths choose independently, so E[9 e_a e_b] = 1 per
// channel, the undispersed expectation. The MIS weights are
// unchanged: every technique evaluates each dispersive vertex of a path with the path's
// channel, so the weights of a (path, channel) still sum to 1; the channel probabilities
// are left out of them (unbiased, possibly not the best weighting: docs/scene-format.md).
//
// Requires: types.glsl, textures.glsl (Tint), scene.glsl's material_dispersion.
#ifndef DISPERSION_GLSL
#define DISPERSION_GLSL

#if HAS_DISPERSION
// The IOR of glass `m` for the channel of `tint`: the material's own (green's) without a
// channel or dispersion.
float dispersed_ior(GpuMaterial m, Tint tint) {
    if (tint.channel == NO_CHANNEL || m.dispersion.w <= 0.0) return m.phong.w;
    return m.dispersion[tint.channel];
}

// Whether a subpath of channel `channel` (NO_CHANNEL: none yet) that reaches a point of
// material `material` must choose its channel there: a dispersive glass and no channel.
// The caller draws choose_channel's `u` only then, so no random number is drawn elsewhere.
bool channel_needed(uint channel, uint material) {
    return channel == NO_CHANNEL && material_dispersion(material).w > 0.0;
}
// The subpath's channel c from `u` (uniform in [0, 1)), its throughput `thr` times 3 e_c.
void choose_channel(inout uint channel, inout vec3 thr, float u) {
    channel = min(uint(u * 3.0), 2u);
    vec3 keep = vec3(0.0);
    keep[channel] = 3.0;
    thr *= keep;
}

// Whether a camera vertex of channel `a` may meet a light vertex of channel `b`: unless
// both have chosen different channels.
bool channels_meet(uint a, uint b) { return a == NO_CHANNEL || b == NO_CHANNEL || a == b; }
#endif

#endif
