#version 460
// The accumulate pass of estimators without a camera kernel (pure light tracing): adds
// each pixel's splat sum of this iteration to the film and zeroes it.
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = WORKGROUP_SIZE) in;
#include "common.glsl"
#define HAS_SPLAT 1
#include "push.glsl"
#include "film.glsl"

void main() {
    uint pixel = invocation_index();
    if (pixel >= push.count) return;
    film_add(pixel, splat_take(pixel));
}
