// The push constants of the render kernels: GpuPush (glsl/types.glsl, mirrored by
// src/render/gpu_types.rs), set per dispatch by the passes in src/render/passes/.
#ifndef PUSH_GLSL
#define PUSH_GLSL
#include "types.glsl"
layout(push_constant) uniform PushBlock { GpuPush push; };
#endif
