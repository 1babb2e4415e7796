#version 460
// Eye light (`el`): |cos(normal, view ray)| of the first hit times its tint (texture and
// vertex colour, glsl/textures.glsl), a preview and not a radiance estimate (as
// SmallVCM's EyeLight). Back faces are not distinguished.
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = WORKGROUP_SIZE) in;
#include "scene.glsl"
#include "push.glsl"
#include "film.glsl"

void main() {
    uint pixel = invocation_index();
    if (pixel >= push.count) return;
    uint rng = rng_init(params.misc.x, push.iteration, pixel, 0u);
    vec3 d = camera_sample(pixel, rng);
    Hit h;
    vec3 v = vec3(0.0);
    if (trace_camera_segment(params.cam_pos.xyz, d, h)) {
        Surface s = surface_at(h, params.cam_pos.xyz, d);
        v = abs(dot(s.ns, d)) * s.tint.rgb;
    }
    film_add(pixel, v);
    COUNT_RAYS_FLUSH();
}
