#version 460
// Layout probe for tests/layout.rs: declares a runtime array of every shared struct so
// that their std430 member offsets and array strides appear in the SPIR-V.
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 1) in;
#include "types.glsl"
layout(std430, binding = 0) buffer A { GpuMaterial a_materials[]; };
layout(std430, binding = 1) buffer B { GpuTriangle a_triangles[]; };
layout(std430, binding = 2) buffer C { GpuSphere a_spheres[]; };
layout(std430, binding = 3) buffer D { GpuLight a_lights[]; };
layout(std430, binding = 4) buffer E { GpuParams a_params[]; };
layout(std430, binding = 5) buffer F { GpuPush a_push[]; };
layout(std430, binding = 6) buffer G { GpuTextureRef a_texture_refs[]; };
layout(std430, binding = 7) buffer H { GpuVertexAttributes a_vertex_attributes[]; };
layout(std430, binding = 8) buffer I { GpuAddresses a_addresses[]; };
layout(std430, binding = 9) buffer J { GpuSceneAddresses a_scene_addresses[]; };
void main() {
    // Touch every struct so none is optimised away.
    a_materials[1] = a_materials[0];
    a_triangles[1] = a_triangles[0];
    a_spheres[1] = a_spheres[0];
    a_lights[1] = a_lights[0];
    a_params[1] = a_params[0];
    a_push[1] = a_push[0];
    a_texture_refs[1] = a_texture_refs[0];
    a_vertex_attributes[1] = a_vertex_attributes[0];
    a_addresses[1] = a_addresses[0];
    a_scene_addresses[1] = a_scene_addresses[0];
}
