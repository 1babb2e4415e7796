// Scene buffers shared by every render kernel (the bindings scene_params, bvh_nodes,
// bvh_prims, triangles, spheres, materials, lights and shading_normals, bound by name:
// src/render/scene_gpu.rs; with HAS_ENVIRONMENT_MAP also env_texels and env_distribution,
// declared by glsl/environment.glsl; with HAS_VERTEX_ATTRIBUTES / HAS_TEXTURES
// vertex_attributes, texture_refs and texture_texels, declared by glsl/textures.glsl;
// with DEVICE_ADDRESSES scene_addresses, through which the kernels reach
// vertex_attributes, texture_texels, env_texels and env_distribution instead),
// the camera, and the conversion of a BVH hit into a shading point.
// Scene features the scene lacks compile out (glsl/features.glsl): spheres, shading
// normals, area lights (then no surface is an emitter) and the background.
#ifndef SCENE_GLSL
#define SCENE_GLSL

#include "features.glsl"
#include "types.glsl"
#include "common.glsl"

layout(std430) readonly buffer scene_params { GpuParams params; };
// A GpuTriangle from its 16 bytes read as a uvec4 (texel and chunked reads).
GpuTriangle triangle_of(uvec4 v) {
    GpuTriangle t;
    t.material = v.x;
    t.light = v.y;
    t.first_vertex = v.z;
    t._pad = v.w;
    return t;
}
// The scene's buffers that can outgrow one binding (vertex attributes, texels, the
// environment map) are reached by device address where the device has it
// (DEVICE_ADDRESSES: the binding scene_addresses holds them, src/render/scene_gpu.rs);
// glsl/textures.glsl and glsl/environment.glsl read them through these arrays.
#if DEVICE_ADDRESSES
#include "buffer_reference.glsl"
layout(std430) readonly buffer scene_addresses { GpuSceneAddresses scene_address; };
layout(buffer_reference, std430, buffer_reference_align = 16) buffer VertexAttributeArray {
    GpuVertexAttributes v[];
};
#define SCENE_VERTEX_ATTRIBUTES ARRAY_AT(VertexAttributeArray, scene_address.vertex_attributes)
#define SCENE_TEXTURE_TEXELS ARRAY_AT(Uvec4s, scene_address.texture_texels)
#define SCENE_ENV_TEXELS ARRAY_AT(Vec4s, scene_address.env_texels)
#define SCENE_ENV_DISTRIBUTION ARRAY_AT(Floats, scene_address.env_distribution)
#endif
// SCENE_CHUNKS (a scene whose BVH or geometry is larger than one binding,
// src/render/scene_gpu.rs CHUNKED): the BVH nodes, BVH primitives, triangles and shading
// normals, and the vertex attributes, are arrays of 16-byte elements in chunks of
// 2^SCENE_CHUNK_SHIFT elements, each chunk its own buffer; the binding scene_chunks holds
// the chunks' addresses, each array's from scene_address.chunk_first[CHUNK_...].
#ifndef SCENE_CHUNKS
#define SCENE_CHUNKS 0
#endif
#if SCENE_CHUNKS
#define CHUNK_NODES 0
#define CHUNK_PRIMS 1
#define CHUNK_TRIANGLES 2
#define CHUNK_SHADING_NORMALS 3
#define CHUNK_VERTEX_ATTRIBUTES 4
layout(std430) readonly buffer scene_chunks { uvec2 scene_chunk[]; };
// Element i of the chunked array `array` (CHUNK_...).
uvec4 scene_chunked_elem(uint array, uint i) {
    uvec2 chunk = scene_chunk[scene_address.chunk_first[array] + (i >> SCENE_CHUNK_SHIFT)];
    return ARRAY_AT(Uvec4s, chunk)[i & ((1u << SCENE_CHUNK_SHIFT) - 1u)];
}
GpuTriangle triangle_at(uint i) { return triangle_of(scene_chunked_elem(CHUNK_TRIANGLES, i)); }
vec4 shading_normal_at(uint i) { return uintBitsToFloat(scene_chunked_elem(CHUNK_SHADING_NORMALS, i)); }
#endif
// The BVH: bvh.glsl declares it (64-bit loads, faster on lavapipe than vec4 arrays:
// docs/bvh.md; with TEXEL_READS uniform texel buffers).
#define BVH_DECLARES_BUFFERS
// The rest, read through triangle_at(i), sphere_at(i), material_at(i), light_at(i)
// and shading_normal_at(i). TEXEL_READS (src/render/reads.rs): as uniform texel buffers of
// uvec4 texels, one per vec4 of the struct in field order (each struct is whole vec4s:
// src/render/gpu_types.rs); else as storage buffers.
#ifndef TEXEL_READS
#define TEXEL_READS 0
#endif
#if TEXEL_READS
#extension GL_EXT_samplerless_texture_functions : require
#define BVH_TEXEL 1
uniform utextureBuffer spheres;
uniform utextureBuffer materials;
uniform utextureBuffer lights;
vec4 texel_vec4(utextureBuffer b, uint i) { return uintBitsToFloat(texelFetch(b, int(i))); }
#if !SCENE_CHUNKS
uniform utextureBuffer triangles;
uniform utextureBuffer shading_normals;
GpuTriangle triangle_at(uint i) { return triangle_of(texelFetch(triangles, int(i))); }
vec4 shading_normal_at(uint i) { return texel_vec4(shading_normals, i); }
#endif
GpuSphere sphere_at(uint i) {
    GpuSphere s;
    s.center_radius = texel_vec4(spheres, 2u * i);
    s.info = texelFetch(spheres, int(2u * i + 1u));
    return s;
}
// GpuMaterial's vec4s, in field order.
#define MATERIAL_TEXELS 23u
GpuMaterial material_at(uint i) {
    GpuMaterial m;
    uint k = MATERIAL_TEXELS * i;
    m.diffuse = texel_vec4(materials, k);
    m.phong = texel_vec4(materials, k + 1u);
    m.mirror = texel_vec4(materials, k + 2u);
    m.emission = texel_vec4(materials, k + 3u);
    m.glossy = texel_vec4(materials, k + 4u);
    m.surface = texel_vec4(materials, k + 5u);
    m.maps = texel_vec4(materials, k + 6u);
    m.base_metallic = texel_vec4(materials, k + 7u);
    m.f0_roughness = texel_vec4(materials, k + 8u);
    m.medium = texel_vec4(materials, k + 9u);
    m.transmission = texel_vec4(materials, k + 10u);
    m.coat = texel_vec4(materials, k + 11u);
    m.layers = texel_vec4(materials, k + 12u);
    m.specular = texel_vec4(materials, k + 13u);
    m.sheen = texel_vec4(materials, k + 14u);
    m.sheen_maps = texel_vec4(materials, k + 15u);
    m.iridescence = texel_vec4(materials, k + 16u);
    m.iridescence_maps = texel_vec4(materials, k + 17u);
    m.anisotropy = texel_vec4(materials, k + 18u);
    m.diffuse_transmission = texel_vec4(materials, k + 19u);
    m.diffuse_transmission_maps = texel_vec4(materials, k + 20u);
    m.coat_normal = texel_vec4(materials, k + 21u);
    m.dispersion = texel_vec4(materials, k + 22u);
    return m;
}
vec4 material_surface(uint i) { return texel_vec4(materials, MATERIAL_TEXELS * i + 5u); }
vec4 material_maps(uint i) { return texel_vec4(materials, MATERIAL_TEXELS * i + 6u); }
vec4 material_medium(uint i) { return texel_vec4(materials, MATERIAL_TEXELS * i + 9u); }
vec4 material_coat(uint i) { return texel_vec4(materials, MATERIAL_TEXELS * i + 11u); }
vec4 material_layers(uint i) { return texel_vec4(materials, MATERIAL_TEXELS * i + 12u); }
vec4 material_sheen_maps(uint i) { return texel_vec4(materials, MATERIAL_TEXELS * i + 15u); }
vec4 material_iridescence_maps(uint i) { return texel_vec4(materials, MATERIAL_TEXELS * i + 17u); }
vec4 material_anisotropy(uint i) { return texel_vec4(materials, MATERIAL_TEXELS * i + 18u); }
vec4 material_diffuse_transmission_maps(uint i) { return texel_vec4(materials, MATERIAL_TEXELS * i + 20u); }
vec4 material_coat_normal(uint i) { return texel_vec4(materials, MATERIAL_TEXELS * i + 21u); }
vec4 material_dispersion(uint i) { return texel_vec4(materials, MATERIAL_TEXELS * i + 22u); }
GpuLight light_at(uint i) {
    GpuLight l;
    l.a = texel_vec4(lights, 5u * i);
    l.b = texel_vec4(lights, 5u * i + 1u);
    l.c = texel_vec4(lights, 5u * i + 2u);
    l.d = texel_vec4(lights, 5u * i + 3u);
    l.radiance = texel_vec4(lights, 5u * i + 4u);
    return l;
}
#else
layout(std430) readonly buffer spheres { GpuSphere sphere_data[]; };
layout(std430) readonly buffer materials { GpuMaterial material_data[]; };
layout(std430) readonly buffer lights { GpuLight light_data[]; };
#if !SCENE_CHUNKS
layout(std430) readonly buffer triangles { GpuTriangle triangle_data[]; };
layout(std430) readonly buffer shading_normals { vec4 shading_normal_data[]; };
GpuTriangle triangle_at(uint i) { return triangle_data[i]; }
vec4 shading_normal_at(uint i) { return shading_normal_data[i]; }
#endif
GpuSphere sphere_at(uint i) { return sphere_data[i]; }
GpuMaterial material_at(uint i) { return material_data[i]; }
vec4 material_surface(uint i) { return material_data[i].surface; }
vec4 material_maps(uint i) { return material_data[i].maps; }
vec4 material_medium(uint i) { return material_data[i].medium; }
vec4 material_coat(uint i) { return material_data[i].coat; }
vec4 material_layers(uint i) { return material_data[i].layers; }
vec4 material_sheen_maps(uint i) { return material_data[i].sheen_maps; }
vec4 material_iridescence_maps(uint i) { return material_data[i].iridescence_maps; }
vec4 material_anisotropy(uint i) { return material_data[i].anisotropy; }
vec4 material_diffuse_transmission_maps(uint i) { return material_data[i].diffuse_transmission_maps; }
vec4 material_coat_normal(uint i) { return material_data[i].coat_normal; }
vec4 material_dispersion(uint i) { return material_data[i].dispersion; }
GpuLight light_at(uint i) { return light_data[i]; }
#endif

#if HAS_ALPHA_MASK
#define BVH_ALPHA_TEST
#endif
#if HAS_ONE_SIDED
#define BVH_FACE_TEST
// Whether a triangle of `material` is there for a ray meeting its back side (the side
// its winding's normal points away from): not when the material is one-sided.
bool back_face_visible(uint material) {
    return (floatBitsToUint(material_medium(material).w) & MATERIAL_ONE_SIDED) == 0u;
}
#endif
#include "bvh.glsl"
#include "textures.glsl"

// COUNT_RAYS (profiling): every trace_closest / trace_any call of the kernel is counted in
// a private counter, and COUNT_RAYS_FLUSH(), the last statement of a kernel's main, adds
// it to the 64-bit count in stats[2] (low word) and stats[3] (high word) with one atomic
// per invocation (the carry: the add that wraps the low word increments the high one).
#if COUNT_RAYS
uint rays_traced = 0u;
bool trace_closest_counted(vec3 o, vec3 d, float tmin, float tmax, out Hit h) {
    rays_traced += 1u;
    return trace_closest(o, d, tmin, tmax, h);
}
bool trace_any_counted(vec3 o, vec3 d, float tmin, float tmax) {
    rays_traced += 1u;
    return trace_any(o, d, tmin, tmax);
}
bool trace_closest_culling_counted(vec3 o, vec3 d, float tmin, float tmax, bool cull, out Hit h) {
    rays_traced += 1u;
    return trace_closest_culling(o, d, tmin, tmax, cull, h);
}
bool trace_any_culling_counted(vec3 o, vec3 d, float tmin, float tmax, bool cull) {
    rays_traced += 1u;
    return trace_any_culling(o, d, tmin, tmax, cull);
}
#define trace_closest trace_closest_counted
#define trace_any trace_any_counted
#define trace_closest_culling trace_closest_culling_counted
#define trace_any_culling trace_any_culling_counted
#define COUNT_RAYS_FLUSH()                                                \
    if (rays_traced > 0u) {                                               \
        uint old_rays_ = atomicAdd(stats[2], rays_traced);                \
        if (old_rays_ + rays_traced < old_rays_) atomicAdd(stats[3], 1u); \
    }
#else
#define COUNT_RAYS_FLUSH()
#endif

#include "bsdf.glsl"
#include "lights.glsl"
#include "medium.glsl"

uint image_width() { return params.dims.x; }
uint image_height() { return params.dims.y; }
uint light_count() { return params.dims.z; }
uint max_path_length() { return params.dims.w; }
uint min_path_length() { return params.misc.y; }
#if HAS_BACKGROUND
uint background_light() { return params.misc.z; }
#else
uint background_light() { return NO_LIGHT; }
#endif
float scene_radius() { return params.scene_sphere.w; }

// ---- Pinhole camera: the image plane lies at `cam_pos.w` pixels, so a pixel has unit
// area; raster (0, 0) is the top-left corner.
vec3 camera_direction(vec2 raster) {
    vec3 d = params.cam_forward.xyz * params.cam_pos.w
           + params.cam_right.xyz * (raster.x - 0.5 * float(image_width()))
           + params.cam_up.xyz * (0.5 * float(image_height()) - raster.y);
    return normalize(d);
}

// The primary ray of this iteration's sample of `pixel`, jittered uniformly inside it.
vec3 camera_sample_at(uint pixel, vec2 u) {
    uint w = image_width();
    return camera_direction(vec2(float(pixel % w), float(pixel / w)) + u);
}
vec3 camera_sample(uint pixel, inout uint rng) { return camera_sample_at(pixel, rnd2(rng)); }

// Solid-angle pdf of the camera generating direction `d` (pixel area 1): dist^2 / cos^3.
float camera_pdf_w(vec3 d) {
    float c = dot(d, params.cam_forward.xyz);
    return params.cam_pos.w * params.cam_pos.w / (c * c * c);
}

// The inverse of camera_direction, for connections to the camera.
// Raster position of world point x, false when behind the camera or off the image.
bool camera_raster(vec3 x, out vec2 raster) {
    vec3 d = x - params.cam_pos.xyz;
    float z = dot(d, params.cam_forward.xyz);
    if (z <= 0.0) return false;
    vec3 q = d * (params.cam_pos.w / z);
    raster = vec2(dot(q, params.cam_right.xyz) + 0.5 * float(image_width()),
                  0.5 * float(image_height()) - dot(q, params.cam_up.xyz));
    return raster.x >= 0.0 && raster.y >= 0.0 && raster.x < float(image_width()) && raster.y < float(image_height());
}

// ---- Shading point of a hit.
struct Surface {
    vec3 p;
    vec3 ng;        // geometric normal (triangles: (p1-p0)x(p2-p0); spheres: outward)
    vec3 ns;        // shading normal (== ng unless the mesh has normals), same side as ng
    Tint tint;      // multiplies the material's factors (glsl/textures.glsl; else 1)
    uint material;
    uint light;     // light index or NO_LIGHT
};

#ifdef BVH_INSTANCES
// An object-space normal n of an instance in world space, unnormalised: the transpose of
// the linear part of its world-to-object rows w0..w2, i.e. the inverse transpose of the
// placement.
vec3 instance_normal(vec3 w0, vec3 w1, vec3 w2, vec3 n) {
    return n.x * w0 + n.y * w1 + n.z * w2;
}
#endif

Surface surface_at(Hit h, vec3 o, vec3 d) {
    Surface s;
#if HAS_SPHERES
    if (h.is_sphere) {
        GpuSphere sp = sphere_at(h.prim);
        vec3 c = sp.center_radius.xyz;
        float r = sp.center_radius.w;
        vec3 n = normalize(o + h.t * d - c);
        s.p = c + r * n;  // re-projected onto the surface
        s.ng = n;
        s.ns = n;
        s.tint = no_tint();
        s.material = sp.info.x;
        s.light = sp.info.y;
    } else
#endif
    {
        // The vertices are the hit BVH primitive's (stored once, in leaf order); the rest
        // is the triangle's, in scene order.
        GpuTriangle tri = triangle_at(h.prim);
        vec3 p0 = uintBitsToFloat(bvh_prim_elem(3u * h.slot).xyz);
        vec3 e1 = uintBitsToFloat(bvh_prim_elem(3u * h.slot + 1u).xyz) - p0;
        vec3 e2 = uintBitsToFloat(bvh_prim_elem(3u * h.slot + 2u).xyz) - p0;
        s.p = p0 + h.u * e1 + h.v * e2;
        s.ng = normalize(cross(e1, e2));
        s.ns = s.ng;
        s.material = tri.material;
#ifdef BVH_INSTANCES
        // A shared mesh's triangle is in object space: the point goes to the world by the
        // object-to-world rows; normals by instance_normal (which keeps the authored side
        // for mirroring instances too, as the importer's vertex swap does for flattened
        // meshes). Vertex
        // normals are mapped and normalised before they are interpolated, tangents
        // likewise (normal_mapped): what the flattened mesh stores.
        uint record = h.instance_record;
        uint w2o = 3u * record;
        bool instanced = record != BVH_NO_INSTANCE;
        // The record is read only for an instance's hit (past the arrays otherwise, which
        // an array read by address must not be).
        vec3 w0 = vec3(0.0), w1 = vec3(0.0), w2 = vec3(0.0);
        if (instanced) {
            w0 = uintBitsToFloat(bvh_prim_elem(w2o).xyz);
            w1 = uintBitsToFloat(bvh_prim_elem(w2o + 1u).xyz);
            w2 = uintBitsToFloat(bvh_prim_elem(w2o + 2u).xyz);
            s.p = bvh_apply_rows(w2o + 3u, s.p, 1.0);
            s.ng = normalize(instance_normal(w0, w1, w2, cross(e1, e2)));
            s.ns = s.ng;
        }
#else
        uint record = BVH_NO_INSTANCE;
#endif
#if HAS_CLEARCOAT_NORMAL_MAPS
        vec3 coat_n = vec3(0.0);  // none: the coat shades with the base's normal
#endif
#if HAS_SHADING_NORMALS
        uint first_normal = tri.first_vertex;
        if (first_normal != 0xffffffffu) {
            vec3 n0 = shading_normal_at(first_normal).xyz;
            vec3 n1 = shading_normal_at(first_normal + 1u).xyz;
            vec3 n2 = shading_normal_at(first_normal + 2u).xyz;
#ifdef BVH_INSTANCES
            if (instanced) {
                n0 = instance_normal(w0, w1, w2, n0);
                n1 = instance_normal(w0, w1, w2, n1);
                n2 = instance_normal(w0, w1, w2, n2);
                // Zero normals (a triangle without them, flat) stay zero.
                n0 = dot(n0, n0) > 0.0 ? normalize(n0) : n0;
                n1 = dot(n1, n1) > 0.0 ? normalize(n1) : n1;
                n2 = dot(n2, n2) > 0.0 ? normalize(n2) : n2;
            }
#endif
            vec3 n = (1.0 - h.u - h.v) * n0 + h.u * n1 + h.v * n2;
            float len = length(n);
            vec3 ns = len > 0.0 ? n / len : s.ng;
#if HAS_CLEARCOAT_NORMAL_MAPS
            // The coat's own normal map bends the interpolated normal (the base's does too).
            vec4 cn = material_coat_normal(s.material);
            coat_n = normal_mapped_by(floatBitsToUint(cn.x), cn.y, h.prim, record, h.u, h.v, ns);
            coat_n = floatBitsToUint(cn.x) == NO_TEXTURE ? vec3(0.0) : (dot(coat_n, s.ng) < 0.0 ? -coat_n : coat_n);
#endif
#if HAS_NORMAL_MAPS
            ns = normal_mapped(h.prim, record, s.material, h.u, h.v, ns);
#endif
            // On the geometric normal's side (glsl/bsdf.glsl decides sides by ng).
            s.ns = dot(ns, s.ng) < 0.0 ? -ns : ns;
        }
#endif
        s.tint = surface_tint(h.prim, s.material, h.u, h.v);
#if HAS_ANISOTROPY
        s.tint.anisotropy = anisotropy_at(h.prim, record, s.material, h.u, h.v, s.ns);
#endif
#if HAS_CLEARCOAT_NORMAL_MAPS
        s.tint.coat_normal = coat_n;
#endif
#if HAS_AREA_LIGHTS
        s.light = tri.light;
#else
        s.light = NO_LIGHT;  // only area lights make surfaces emitters
#endif
    }
    return s;
}

// The shadow ray between a (normal na) and b (normal nb), each end offset along its
// normal unless the normal is zero: origin o, unit direction d and length tmax; false
// when the ends coincide (nothing to test).
bool shadow_ray(vec3 a, vec3 na, vec3 b, vec3 nb, out vec3 o, out vec3 d, out float tmax) {
    vec3 ab = b - a;
    o = dot(na, na) > 0.0 ? offset_ray(a, na, ab, scene_radius()) : a;
    vec3 e = dot(nb, nb) > 0.0 ? offset_ray(b, nb, -ab, scene_radius()) : b;
    vec3 de = e - o;
    tmax = length(de);
    d = de / tmax;
    return tmax > 0.0;
}

// Shadow ray between two points, each offset off its surface (`na`, `nb` may be zero
// for point-like ends). True when nothing blocks it.
bool visible(vec3 a, vec3 na, vec3 b, vec3 nb) {
    vec3 o, d;
    float tmax;
    if (!shadow_ray(a, na, b, nb, o, d, tmax)) return true;
    return !trace_any(o, d, 0.0, tmax);
}

// What the camera sees. glTF's doubleSided false is back-face culling, a rule of what is
// seen: the camera does not see the back side of a one-sided surface (BVH_FACE_TEST),
// it sees what lies behind it. The rule applies to the segment at the camera, in every
// estimator alike: camera rays, and connections of light-subpath vertices to the camera,
// traced from the camera. Every other segment meets both sides of every surface, so
// light transport between surfaces stays reciprocal (culling every ray would make a
// surface block light in one direction and pass it in the other, and light tracing
// would then disagree with path tracing).
bool trace_camera_segment(vec3 o, vec3 d, out Hit h) {
    return trace_closest_culling(o, d, 0.0, 1e30, HAS_ONE_SIDED != 0, h);
}
// The closest hit along a path's next segment from o: trace_camera_segment's rule when
// the segment starts at the camera, trace_closest's otherwise. One traversal for both:
// a SIMD group whose lanes hold new paths (camera segments) and continuing ones traces
// all of them at once, where `from_camera ? trace_camera_segment(..) : trace_closest(..)`
// would run two traversals, each with only part of the lanes active (on lavapipe a
// SIMD group's pass through a traversal costs about as much with one lane active as with
// eight).
bool trace_path_segment(vec3 o, vec3 d, bool from_camera, out Hit h) {
    return trace_closest_culling(o, d, 0.0, 1e30, from_camera && HAS_ONE_SIDED != 0, h);
}
// Whether nothing the camera sees lies between it and point p (normal ng, p offset off
// its surface along it): the segment traced from the camera.
bool camera_segment_clear(vec3 p, vec3 ng) {
    vec3 o, d;
    float tmax;
    if (!shadow_ray(params.cam_pos.xyz, vec3(0.0), p, ng, o, d, tmax)) return true;
    return !trace_any_culling(o, d, 0.0, tmax, HAS_ONE_SIDED != 0);
}
// Whether the camera sees point p (winding normal ng, `material`; on a triangle unless
// `sphere`): not from the back side of a one-sided triangle, else camera_segment_clear.
bool visible_to_camera(vec3 p, vec3 ng, uint material, bool sphere) {
#if HAS_ONE_SIDED
    if (!sphere && dot(params.cam_pos.xyz - p, ng) < 0.0 && !back_face_visible(material)) return false;
#endif
    return camera_segment_clear(p, ng);
}

// Shadow ray for a direct-illumination sample taken at p (geometric normal ng): towards
// an infinite light along ls.wi, else to ls.light_point; one trace_any call site for
// both.
bool light_sample_visible(vec3 p, vec3 ng, LightSample ls) {
    vec3 o, d;
    float tmax;
    if (ls.dist >= 1e29) {
        o = offset_ray(p, ng, ls.wi, scene_radius());
        d = ls.wi;
        tmax = 1e30;
    } else if (!shadow_ray(p, ng, ls.light_point, ls.light_normal, o, d, tmax)) {
        return true;
    }
    return !trace_any(o, d, 0.0, tmax);
}

#endif
