// Bindings 8+ of the bidirectional kernels (light_subpath.comp, camera_subpath.comp,
// accumulate.comp). One layout for all of them, so they share one buffer list.
#ifndef VCM_BINDINGS_GLSL
#define VCM_BINDINGS_GLSL
#extension GL_EXT_shader_atomic_int64 : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#define HAS_SPLAT 1
layout(std430, binding = 8) buffer FilmBuf { vec4 film[]; };
layout(std430, binding = 9) buffer StatsBuf { uint stats[]; };
layout(std430, binding = 10) buffer SplatBuf { uint64_t splat[]; };
layout(std430, binding = 11) buffer LvABuf { vec4 lv_a[]; };
layout(std430, binding = 12) buffer LvBBuf { vec4 lv_b[]; };
layout(std430, binding = 13) buffer LvCountBuf { uint lv_count[]; };
layout(push_constant) uniform PushBlock { GpuPush push; };
#include "film.glsl"
#include "vcm.glsl"
// Light-vertex cache (src/render/bidir.rs, Connect::Cache): lv_prefix[] (N_L + 1 uint),
// bound after a kernel's other buffers; light_subpath.comp copies lv_count into it and an
// exclusive scan turns it into each path's first index among all stored vertices (entry
// N_L: their total) before camera_subpath.comp draws from it.
#ifndef LV_CACHE
#define LV_CACHE 0
#endif
#endif
