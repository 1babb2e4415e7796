// Shared data layouts; mirrors src/render/gpu_types.rs field for field (checked by
// tests/layout.rs through SPIR-V reflection).
#ifndef TYPES_GLSL
#define TYPES_GLSL

#define LIGHT_AREA 0u
#define LIGHT_POINT 1u
#define LIGHT_SPOT 2u
#define LIGHT_DIRECTIONAL 3u
#define LIGHT_BACKGROUND 4u
#define NO_LIGHT 0xffffffffu
#define NO_TEXTURE 0xffffffffu
#define TEXTURE_NEAREST 16u
#define TEXTURE_UV1 32u
#define TEXTURE_LINEAR 64u
#define ALPHA_OPAQUE (-1.0)
#define ALPHA_BLEND (-2.0)
#define MIN_GGX_ALPHA 1e-3
#define MIN_SHEEN_ROUGHNESS 0.07  // src/render/gpu_types.rs, tests/common/sheen.rs
#define MATERIAL_ONE_SIDED 1u
#define NO_CHANNEL 3u  // a subpath that has chosen no colour channel (glsl/lobes/dispersion.glsl)

struct GpuMaterial {
    vec4 diffuse;   // rgb, w: Phong exponent
    vec4 phong;     // rgb, w: IOR (< 0: not a dielectric)
    vec4 mirror;    // rgb, w: F0 of the interface over the diffuse lobe (0: plain Lambert)
    vec4 emission;  // rgb radiance
    vec4 glossy;    // rgb: GGX lobe colour (Schlick F0), w: GGX alpha (>= 1e-3)
    vec4 surface;   // x: base-colour texture or NO_TEXTURE (bits), y: alpha factor,
                    // z: alpha cutoff of MASK (>= 0), ALPHA_OPAQUE or ALPHA_BLEND,
                    // w: untinted part of the GGX F0
    vec4 maps;      // x: normal map or NO_TEXTURE (bits), y: normal map scale,
                    // z: emissive texture or NO_TEXTURE (bits),
                    // w: metallic-roughness texture or NO_TEXTURE (bits)
    vec4 base_metallic;  // with a metallic-roughness texture: rgb base colour factor,
                         // w metallic factor (glsl/bsdf.glsl, point_material)
    vec4 f0_roughness;   // rgb: the dielectric's F0, w: roughness factor
    vec4 medium;         // rgb: attenuation coefficient inside a transmissive volume (0: none),
                         // w: flag bits (MATERIAL_ONE_SIDED)
    vec4 transmission;   // rgb: colour of a dielectric's transmitted part (1: clear); w: its glass weight (glsl/bsdf.glsl)
    vec4 coat;           // x: clear coat factor (0: none), y: its GGX alpha (glsl/lobes/clearcoat.glsl),
                         // z, w: its factor's and roughness's textures or NO_TEXTURE (bits)
    vec4 layers;         // transmission, specular and specular colour textures or NO_TEXTURE (bits), w reserved
    vec4 specular;       // rgb: F0 of the IOR x specularColorFactor, w: specularFactor (glsl/bsdf.glsl, point_material)
    vec4 sheen;          // rgb: sheenColorFactor (0: none), w: sheenRoughnessFactor (glsl/lobes/sheen.glsl)
    vec4 sheen_maps;     // x, y: sheen colour and roughness textures or NO_TEXTURE (bits), z, w reserved
    vec4 iridescence;    // x: iridescenceFactor (0: none), y: the film's IOR, z, w: its thickness
                         // minimum and maximum in nm (glsl/lobes/iridescence.glsl)
    vec4 iridescence_maps;  // x, y: iridescence and thickness textures or NO_TEXTURE (bits), z, w reserved
    vec4 anisotropy;     // x, y: cos, sin of the rotation, z: strength (0: none), w: texture or NO_TEXTURE (bits)
    vec4 diffuse_transmission;       // rgb: diffuseTransmissionColorFactor, w: diffuseTransmissionFactor (0: none;
                                     // glsl/lobes/diffuse_transmission.glsl)
    vec4 diffuse_transmission_maps;  // x, y: its factor's and colour's textures or NO_TEXTURE (bits),
                                     // z: the metallic factor, w reserved
    vec4 coat_normal;    // x: the clear coat's normal map or NO_TEXTURE (bits), y: its scale, z, w reserved
    vec4 dispersion;     // xyz: the glass's IORs for R, G, B, w: its dispersion (0: none; glsl/lobes/dispersion.glsl)
};

struct GpuTextureRef {
    uvec4 image;  // first texel, width, height, flags (wrap s: bits 0-1, t: 2-3, TEXTURE_*)
    vec4 row0;    // uv' = (dot(row0.xyz, (u, v, 1)), dot(row1.xyz, (u, v, 1)))
    vec4 row1;
};

struct GpuVertexAttributes {
    vec4 uv;     // xy: TEXCOORD_0, zw: TEXCOORD_1 (NaN: none)
    vec4 color;  // COLOR_0 (1: none)
    vec4 tangent;  // xyz tangent, w bitangent sign (NaN: none)
};

// A triangle's shading data; its vertices are the BVH primitive's (glsl/scene.glsl).
struct GpuTriangle {
    uint material;
    uint light;         // light index or NO_LIGHT
    uint first_vertex;  // first vertex in the per-vertex arrays, or 0xffffffff
    uint _pad;
};

struct GpuSphere {
    vec4 center_radius;
    uvec4 info;  // x: material, y: light
};

struct GpuLight {
    vec4 a;
    vec4 b;
    vec4 c;
    vec4 d;
    vec4 radiance;  // w: kind (bits)
};

struct GpuParams {
    vec4 cam_pos;       // w: image-plane distance (pixels)
    vec4 cam_forward;
    vec4 cam_right;
    vec4 cam_up;
    vec4 scene_sphere;  // centre, radius
    uvec4 dims;         // width, height, light count, max path length
    uvec4 misc;         // seed, min path length, background light, flags
};

struct GpuAddresses {
    uvec2 film;   // (low, high) words of the film's device address
    uvec2 splat;  // of the splat sums
    uvec2 light_vertices_a;
    uvec2 light_vertices_b;
    uvec2 grid_keys;
    uvec2 grid_points;
    uvec2 light_vertex_offsets;
    uvec2 light_scratch_a;
    uvec2 light_scratch_b;
};

// The scene's buffers reached by device address (src/render/scene_gpu.rs).
struct GpuSceneAddresses {
    uvec2 vertex_attributes;
    uvec2 texture_texels;
    uvec2 env_texels;
    uvec2 env_distribution;
    // SCENE_CHUNKS: where each chunked array's chunks start in scene_chunks
    // (CHUNK_NODES .. CHUNK_VERTEX_ATTRIBUTES, glsl/scene.glsl).
    uint chunk_first[8];
};

struct GpuPush {
    uint iteration;    // 0-based iteration index
    uint count;        // paths (pixels, light subpaths) in this dispatch
    float mis_vm;      // VM weight factor: eta = pi r^2 N_L when merging, else 0
    float mis_vc;      // VC weight factor: 1 / eta when connecting, else 0
    float radius;      // merge radius of this iteration
    uint light_paths;  // N_L, light subpaths per iteration
    uint grid_buckets; // buckets of the light-vertex hash grid (merging estimators)
    uint paths_per_invocation; // path regeneration (common.glsl regen_stride); 0 = 1
    uint first_path;   // the dispatch's first path: a light chunk's, or a camera piece's pixel
};

#endif
