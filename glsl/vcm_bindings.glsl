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
// The light-vertex store, read through lv_a_at(i), lv_b_at(i), lv_count_at(p). LV_TEXEL
// (the camera kernel with texel reads, src/render/reads.rs): as uniform texel buffers
// (uvec4 texels, uint texels for the counts); else as storage buffers, which the light
// kernel writes.
#ifndef LV_TEXEL
#define LV_TEXEL 0
#endif
#if LV_TEXEL
#extension GL_EXT_samplerless_texture_functions : require
layout(binding = 11) uniform utextureBuffer lv_a_t;
layout(binding = 12) uniform utextureBuffer lv_b_t;
layout(binding = 13) uniform utextureBuffer lv_count_t;
vec4 lv_a_at(uint i) { return uintBitsToFloat(texelFetch(lv_a_t, int(i))); }
vec4 lv_b_at(uint i) { return uintBitsToFloat(texelFetch(lv_b_t, int(i))); }
uint lv_count_at(uint p) { return texelFetch(lv_count_t, int(p)).x; }
#else
layout(std430, binding = 11) buffer LvABuf { vec4 lv_a[]; };
layout(std430, binding = 12) buffer LvBBuf { vec4 lv_b[]; };
layout(std430, binding = 13) buffer LvCountBuf { uint lv_count[]; };
vec4 lv_a_at(uint i) { return lv_a[i]; }
vec4 lv_b_at(uint i) { return lv_b[i]; }
uint lv_count_at(uint p) { return lv_count[p]; }
#endif
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
