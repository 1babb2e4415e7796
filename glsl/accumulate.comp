#version 460
// Stage 4 for estimators without a camera kernel (pure light tracing): adds each pixel's
// splat sum of this iteration to the film and zeroes it.
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 64) in;
#include "scene.glsl"
#include "vcm_bindings.glsl"

void main() {
    uint pixel = invocation_index();
    if (pixel >= push.count) return;
    film_add(pixel, splat_take(pixel));
}
