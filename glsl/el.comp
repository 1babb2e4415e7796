#version 460
// Eye light (`el`): |cos(normal, view ray)| of the first hit times its tint (texture and
// vertex colour, glsl/textures.glsl), a preview and not a radiance estimate (as
// SmallVCM's EyeLight). Back faces are not distinguished. AOV (AovKernel): the AOVs of
// the first hit, whatever its material (el traces no further; glsl/aov.glsl).
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = WORKGROUP_SIZE) in;
#include "scene.glsl"
#include "push.glsl"
#include "film.glsl"
#include "aov.glsl"

void main() {
    uint pixel = invocation_index();
    if (pixel >= push.count) return;
    uint rng = rng_init(params.misc.x, push.iteration, pixel, 0u);
    vec3 d = camera_sample(pixel, rng);
    Hit h;
    vec3 v = vec3(0.0);
#if AOV
    AovSample aov = aov_start();
#endif
    if (trace_camera_segment(params.cam_pos.xyz, d, h)) {
        Surface s = surface_at(h, params.cam_pos.xyz, d);
        v = abs(dot(s.ns, d)) * s.tint.rgb;
#if AOV
        aov_first_hit(aov, h.t, s.p);
        Bsdf b = bsdf_init(s.material, s.ng, s.ns, -d, false, s.tint);
        b.delta = false;
        aov_surface(aov, b, vec3(1.0));
#endif
    }
    film_add(pixel, v);
#if AOV
    aov_add(pixel, aov);
#endif
    COUNT_RAYS_FLUSH();
}
