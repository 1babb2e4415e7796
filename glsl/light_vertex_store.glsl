// What the light-subpath kernels share (light_subpath.comp, camera_subpath.comp and the
// debug kernel tests/mis_weights.comp): the push constants, the film with its splat sums,
// the light-vertex store and the transport state of vcm.glsl.
//
// The store: light_vertices_a, light_vertices_b (vec4, two each per vertex) and the binding
// light_vertex_counts (uint per light subpath), read through lv_a_at(i), lv_b_at(i),
// lv_count_at(p). LV_TEXEL 1 (the camera kernel with texel reads, src/render/reads.rs):
// as uniform texel buffers (uvec4 texels, uint texels for the counts); LV_TEXEL 0: the
// vertices by device address (DEVICE_ADDRESSES, glsl/addresses.glsl) or as storage
// buffers, which the light kernel writes (lv_store in vcm.glsl). LV_CACHE 1: the
// kernel connects to (or fills) the light-vertex cache (src/render/passes/
// light_vertex_cache.rs). The Rust side always sets both (src/render/variants.rs).
#ifndef LIGHT_VERTEX_STORE_GLSL
#define LIGHT_VERTEX_STORE_GLSL
#if !defined(LV_TEXEL) || !defined(LV_CACHE)
#error "LV_TEXEL and LV_CACHE must be defined (src/render/variants.rs)"
#endif
#define HAS_SPLAT 1
#include "push.glsl"
#include "film.glsl"
#if LV_TEXEL
#extension GL_EXT_samplerless_texture_functions : require
uniform utextureBuffer light_vertices_a;
uniform utextureBuffer light_vertices_b;
uniform utextureBuffer light_vertex_counts;
vec4 lv_a_at(uint i) { return uintBitsToFloat(texelFetch(light_vertices_a, int(i))); }
vec4 lv_b_at(uint i) { return uintBitsToFloat(texelFetch(light_vertices_b, int(i))); }
uint lv_count_at(uint p) { return texelFetch(light_vertex_counts, int(p)).x; }
#else
#if DEVICE_ADDRESSES
#define lv_a FRAME_LIGHT_VERTICES_A
#define lv_b FRAME_LIGHT_VERTICES_B
#else
layout(std430) buffer light_vertices_a { vec4 lv_a[]; };
layout(std430) buffer light_vertices_b { vec4 lv_b[]; };
#endif
layout(std430) buffer light_vertex_counts { uint lv_count[]; };
vec4 lv_a_at(uint i) { return lv_a[i]; }
vec4 lv_b_at(uint i) { return lv_b[i]; }
uint lv_count_at(uint p) { return lv_count[p]; }
#endif
#include "vcm.glsl"
#endif
