// Arrays reached by buffer device address (GL_EXT_buffer_reference): the element types
// of the buffers that the frame (glsl/addresses.glsl) and the scene (glsl/scene.glsl) reach
// by address where the device has it (DEVICE_ADDRESSES). ARRAY_AT(Vec4s, a)[i] is vec4 i
// of the buffer at address a (a uvec2: low, high words).
#ifndef BUFFER_REFERENCE_GLSL
#define BUFFER_REFERENCE_GLSL
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require
layout(buffer_reference, std430, buffer_reference_align = 16) buffer Vec4s { vec4 v[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) buffer Uvec4s { uvec4 v[]; };
layout(buffer_reference, std430, buffer_reference_align = 8) buffer Uvec2s { uvec2 v[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) buffer Uints { uint v[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) buffer Floats { float v[]; };
#define ARRAY_AT(type, address) type(address).v
#endif
