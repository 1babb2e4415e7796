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
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require
layout(std430) readonly buffer frame_addresses { GpuAddresses addresses; };
#endif
#endif
