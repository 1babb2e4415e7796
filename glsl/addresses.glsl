// Buffer device addresses of the frame's large buffers (src/render/addresses.rs): with
// DEVICE_ADDRESSES 1 the binding `frame_addresses` holds them (GpuAddresses) and the
// kernels reach those buffers through GL_EXT_buffer_reference, limited by memory rather
// than by maxStorageBufferRange; with 0 the buffers are bound as storage buffers.
#ifndef ADDRESSES_GLSL
#define ADDRESSES_GLSL
#ifndef DEVICE_ADDRESSES
#error "DEVICE_ADDRESSES must be defined (src/render/variants.rs)"
#endif
#include "types.glsl"
#if DEVICE_ADDRESSES
#include "buffer_reference.glsl"
layout(std430) readonly buffer frame_addresses { GpuAddresses addresses; };
// Each frame buffer as an array of its element type (the splat sums' type depends on
// SPLAT_ATOMICS_64: glsl/film.glsl).
#define FRAME_FILM ARRAY_AT(Uvec4s, addresses.film)
#define FRAME_LIGHT_VERTICES_A ARRAY_AT(Vec4s, addresses.light_vertices_a)
#define FRAME_LIGHT_VERTICES_B ARRAY_AT(Vec4s, addresses.light_vertices_b)
#define FRAME_GRID_KEYS ARRAY_AT(Uvec2s, addresses.grid_keys)
#define FRAME_GRID_POINTS ARRAY_AT(Uvec4s, addresses.grid_points)
#define FRAME_LIGHT_VERTEX_OFFSETS ARRAY_AT(Uints, addresses.light_vertex_offsets)
#define FRAME_LIGHT_SCRATCH_A ARRAY_AT(Vec4s, addresses.light_scratch_a)
#define FRAME_LIGHT_SCRATCH_B ARRAY_AT(Vec4s, addresses.light_scratch_b)
#endif
#endif
