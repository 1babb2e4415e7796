// What the light-subpath kernels share (light_subpath.comp, camera_subpath.comp and the
// debug kernel tests/mis_weights.comp): the push constants, the film with its splat sums,
// the light-vertex store and the transport state of vcm.glsl.
//
// The store (src/render/passes/light_subpaths.rs) holds an iteration's light vertices
// compacted in path order: light subpath p's vertices are the store's vertices
// lv_offset_at(p) .. lv_offset_at(p + 1) - 1, and lv_offset_at(N_L) is the iteration's
// total. Vertex i is two vec4 of light_vertices_a and LV_B_STRIDE vec4 of
// light_vertices_b (glsl/vcm.glsl, lv_load), read through lv_a_at / lv_b_at.
// LV_TEXEL 1 (the camera kernel with texel reads, src/render/reads.rs): the store and the
// offsets as uniform texel buffers (uvec4 texels, uint texels for the offsets); LV_TEXEL 0:
// by device address (DEVICE_ADDRESSES, glsl/addresses.glsl) or as storage buffers.
//
// LV_SCRATCH 1 (the light kernel when it stores vertices): the light subpaths of one
// chunk write their vertices to fixed scratch slots, light subpath first_path + q to
// slots [q S, q S + S) with S = lv_slots() (lv_store), and their vertex counts to
// light_vertex_chunk_counts[q]; light_vertex_compact.comp then moves them into the store.
// LV_CACHE 1: the camera kernel connects to vertices drawn from the whole store
// (camera_subpath.comp). The Rust side sets LV_TEXEL and LV_CACHE
// (src/render/variants.rs); each kernel sets LV_SCRATCH before including this file.
#ifndef LIGHT_VERTEX_STORE_GLSL
#define LIGHT_VERTEX_STORE_GLSL
#if !defined(LV_TEXEL) || !defined(LV_CACHE) || !defined(LV_SCRATCH)
#error "LV_TEXEL and LV_CACHE (src/render/variants.rs) and LV_SCRATCH (the kernel) must be defined"
#endif
#define HAS_SPLAT 1
#include "push.glsl"
#include "film.glsl"
#if LV_TEXEL
#extension GL_EXT_samplerless_texture_functions : require
uniform utextureBuffer light_vertices_a;
uniform utextureBuffer light_vertices_b;
uniform utextureBuffer light_vertex_offsets;
vec4 lv_a_at(uint i) { return uintBitsToFloat(texelFetch(light_vertices_a, int(i))); }
vec4 lv_b_at(uint i) { return uintBitsToFloat(texelFetch(light_vertices_b, int(i))); }
uint lv_offset_at(uint p) { return texelFetch(light_vertex_offsets, int(p)).x; }
#else
#if DEVICE_ADDRESSES
#define lv_a FRAME_LIGHT_VERTICES_A
#define lv_b FRAME_LIGHT_VERTICES_B
#define lv_offsets FRAME_LIGHT_VERTEX_OFFSETS
#else
layout(std430) readonly buffer light_vertices_a { vec4 lv_a[]; };
layout(std430) readonly buffer light_vertices_b { vec4 lv_b[]; };
layout(std430) readonly buffer light_vertex_offsets { uint lv_offsets[]; };
#endif
vec4 lv_a_at(uint i) { return lv_a[i]; }
vec4 lv_b_at(uint i) { return lv_b[i]; }
uint lv_offset_at(uint p) { return lv_offsets[p]; }
#endif
#if LV_SCRATCH
#if DEVICE_ADDRESSES
#define lv_scratch_a FRAME_LIGHT_SCRATCH_A
#define lv_scratch_b FRAME_LIGHT_SCRATCH_B
#else
layout(std430) writeonly buffer light_vertex_scratch_a { vec4 lv_scratch_a[]; };
layout(std430) writeonly buffer light_vertex_scratch_b { vec4 lv_scratch_b[]; };
#endif
layout(std430) writeonly buffer light_vertex_chunk_counts { uint lv_chunk_count[]; };
#endif
#include "vcm.glsl"
#endif
