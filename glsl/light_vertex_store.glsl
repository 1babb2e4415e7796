// The light-vertex store: an iteration's light vertices, written by the light-subpaths
// pass and read by the camera-subpaths pass (src/render/light_vertex_store.rs has the
// Rust side: its sizes, buffers, status and growth).
//
// The store holds the vertices compacted in path order: light subpath p's vertices are
// the store's vertices lv_offset_at(p) .. lv_offset_at(p + 1) - 1, and lv_offset_at(N_L)
// is the iteration's total. The camera kernel reads it as uniform texel buffers with
// STORE_TEXEL_READS (uvec4 texels, uint texels for the offsets; src/render/reads.rs), else
// by device address (DEVICE_ADDRESSES, glsl/addresses.glsl) or as storage buffers.
//
// With LV_SCRATCH (set by the light kernel when it stores vertices) the light subpaths of
// one chunk write their vertices to fixed scratch slots instead, light subpath
// first_path + q to slots [q S, q S + S) with S = lv_slots() (lv_store), and their vertex
// counts to light_vertex_chunk_counts[q]; light_vertex_compact.comp then moves them into
// the store.
#ifndef LIGHT_VERTEX_STORE_GLSL
#define LIGHT_VERTEX_STORE_GLSL
#if !defined(STORE_TEXEL_READS) || !defined(LV_SCRATCH)
#error "STORE_TEXEL_READS (src/render/passes/camera_subpaths.rs) and LV_SCRATCH (the kernel) must be defined"
#endif
#if STORE_TEXEL_READS
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

// A light vertex's layout (the same in the scratch slots the light kernel writes and in
// the compacted store), vertex i:
//   a[2i] = (position, dVCM)      a[2i+1] = (throughput, dVC)
//   b[Bi] = (wo, dVM)             b[Bi+1] = (normal, lv_info: material | sky_first_hit << 23 | length << 24)
//   with HAS_SHADING_NORMALS or HAS_METALLIC_ROUGHNESS_TEXTURES:
//                                 b[Bi+2] = (shading normal, tint.metallic)
//   with HAS_VERTEX_ATTRIBUTES:   b[Bi+LV_TINT] = (tint.rgb, tint.roughness)
//   with HAS_CLEARCOAT_TEXTURES:  b[Bi+LV_COAT] = (tint.coat, tint.coat_roughness, 0, 0)
//   with HAS_CLEARCOAT_NORMAL_MAPS: b[Bi+LV_COAT_NORMAL] = (tint.coat_normal, 0)
//   with HAS_TRANSMISSION_TEXTURES: b[Bi+LV_TRANSMISSION] = (tint.transmission, 0, 0, 0)
//   with HAS_SPECULAR_TEXTURES:   b[Bi+LV_SPECULAR] = tint.specular
//   with HAS_SHEEN_TEXTURES:      b[Bi+LV_SHEEN] = tint.sheen
//   with HAS_IRIDESCENCE_TEXTURES: b[Bi+LV_IRIDESCENCE] = (tint.iridescence, 0, 0)
//   with HAS_ANISOTROPY:          b[Bi+LV_ANISOTROPY] = tint.anisotropy
//   with HAS_DIFFUSE_TRANSMISSION_TEXTURES: b[Bi+LV_DIFFUSE_TRANSMISSION] = tint.diffuse_transmission
//   with HAS_DISPERSION:          b[Bi+LV_CHANNEL] = (tint.channel (bits), 0, 0, 0)
// B = 2 + the others (src/render/light_vertex_store.rs, LightVertexPlan, sizes the store
// the same way; light_vertex_compact.comp copies B vec4 per vertex). The point's metallic
// and roughness (a metallic-roughness texture's texel) fill the two vec4s' spare w, so a
// scene with that texture needs the normal slot even without shading normals.
#define LV_NORMAL_SLOTS ((HAS_SHADING_NORMALS != 0 || HAS_METALLIC_ROUGHNESS_TEXTURES != 0) ? 1u : 0u)
#define LV_TINT (2u + LV_NORMAL_SLOTS)
#define LV_COAT (LV_TINT + (HAS_VERTEX_ATTRIBUTES != 0 ? 1u : 0u))
#define LV_COAT_NORMAL (LV_COAT + (HAS_CLEARCOAT_TEXTURES != 0 ? 1u : 0u))
#define LV_TRANSMISSION (LV_COAT_NORMAL + (HAS_CLEARCOAT_NORMAL_MAPS != 0 ? 1u : 0u))
#define LV_SPECULAR (LV_TRANSMISSION + (HAS_TRANSMISSION_TEXTURES != 0 ? 1u : 0u))
#define LV_SHEEN (LV_SPECULAR + (HAS_SPECULAR_TEXTURES != 0 ? 1u : 0u))
#define LV_IRIDESCENCE (LV_SHEEN + (HAS_SHEEN_TEXTURES != 0 ? 1u : 0u))
#define LV_ANISOTROPY (LV_IRIDESCENCE + (HAS_IRIDESCENCE_TEXTURES != 0 ? 1u : 0u))
#define LV_DIFFUSE_TRANSMISSION (LV_ANISOTROPY + (HAS_ANISOTROPY != 0 ? 1u : 0u))
#define LV_CHANNEL (LV_DIFFUSE_TRANSMISSION + (HAS_DIFFUSE_TRANSMISSION_TEXTURES != 0 ? 1u : 0u))
#define LV_B_STRIDE (LV_CHANNEL + (HAS_DISPERSION != 0 ? 1u : 0u))
struct LightVertex {
    vec3 p;
    vec3 thr;
    vec3 wo;   // direction towards the previous vertex
    vec3 n;    // geometric normal
    vec3 ns;   // shading normal (== n for flat shading)
    Tint tint; // the point's tint (1 without attributes)
    uint material;
    uint len;        // segments from the light
    float dvcm, dvc, dvm;
    bool sky_first_hit; // SubpathState.sky_first_hit (glsl/subpath.glsl)
};

// Scratch slots per light subpath: a light subpath stores at most max path length - 1
// vertices.
uint lv_slots() { return max_path_length() - 1u; }

// A light vertex's material, sky_first_hit and length in one word (material indices are
// below 2^23: src/scene/validate.rs, MAX_MATERIALS).
#define LV_MATERIAL_MASK 0x7fffffu
#define LV_SKY_FIRST_HIT 0x800000u
uint lv_info(LightVertex v) { return v.material | (v.sky_first_hit ? LV_SKY_FIRST_HIT : 0u) | (v.len << 24); }

#if LV_SCRATCH
// Writes `v` to scratch slot `slot` (the light kernel).
void lv_store(uint slot, LightVertex v) {
    lv_scratch_a[2u * slot] = vec4(v.p, v.dvcm);
    lv_scratch_a[2u * slot + 1u] = vec4(v.thr, v.dvc);
    lv_scratch_b[LV_B_STRIDE * slot] = vec4(v.wo, v.dvm);
    lv_scratch_b[LV_B_STRIDE * slot + 1u] = vec4(v.n, uintBitsToFloat(lv_info(v)));
#if HAS_SHADING_NORMALS || HAS_METALLIC_ROUGHNESS_TEXTURES
    lv_scratch_b[LV_B_STRIDE * slot + 2u] = vec4(v.ns, v.tint.metallic);
#endif
#if HAS_VERTEX_ATTRIBUTES
    lv_scratch_b[LV_B_STRIDE * slot + LV_TINT] = vec4(v.tint.rgb, v.tint.roughness);
#endif
#if HAS_CLEARCOAT_TEXTURES
    lv_scratch_b[LV_B_STRIDE * slot + LV_COAT] = vec4(v.tint.coat, v.tint.coat_roughness, 0.0, 0.0);
#endif
#if HAS_TRANSMISSION_TEXTURES
    lv_scratch_b[LV_B_STRIDE * slot + LV_TRANSMISSION] = vec4(v.tint.transmission, 0.0, 0.0, 0.0);
#endif
#if HAS_SPECULAR_TEXTURES
    lv_scratch_b[LV_B_STRIDE * slot + LV_SPECULAR] = v.tint.specular;
#endif
#if HAS_SHEEN_TEXTURES
    lv_scratch_b[LV_B_STRIDE * slot + LV_SHEEN] = v.tint.sheen;
#endif
#if HAS_IRIDESCENCE_TEXTURES
    lv_scratch_b[LV_B_STRIDE * slot + LV_IRIDESCENCE] = vec4(v.tint.iridescence, 0.0, 0.0);
#endif
#if HAS_ANISOTROPY
    lv_scratch_b[LV_B_STRIDE * slot + LV_ANISOTROPY] = v.tint.anisotropy;
#endif
#if HAS_DIFFUSE_TRANSMISSION_TEXTURES
    lv_scratch_b[LV_B_STRIDE * slot + LV_DIFFUSE_TRANSMISSION] = v.tint.diffuse_transmission;
#endif
#if HAS_CLEARCOAT_NORMAL_MAPS
    lv_scratch_b[LV_B_STRIDE * slot + LV_COAT_NORMAL] = vec4(v.tint.coat_normal, 0.0);
#endif
#if HAS_DISPERSION
    lv_scratch_b[LV_B_STRIDE * slot + LV_CHANNEL] = vec4(uintBitsToFloat(v.tint.channel), 0.0, 0.0, 0.0);
#endif
}
#endif

// Vertex `slot` of the compacted store.
LightVertex lv_load(uint slot) {
    LightVertex v;
    vec4 a0 = lv_a_at(2u * slot), a1 = lv_a_at(2u * slot + 1u);
    vec4 b0 = lv_b_at(LV_B_STRIDE * slot), b1 = lv_b_at(LV_B_STRIDE * slot + 1u);
    v.p = a0.xyz; v.dvcm = a0.w;
    v.thr = a1.xyz; v.dvc = a1.w;
    v.wo = b0.xyz; v.dvm = b0.w;
    v.n = b1.xyz;
#if HAS_SHADING_NORMALS
    v.ns = lv_b_at(LV_B_STRIDE * slot + 2u).xyz;
#else
    v.ns = v.n;
#endif
    v.tint = no_tint();
#if HAS_VERTEX_ATTRIBUTES
    v.tint.rgb = lv_b_at(LV_B_STRIDE * slot + LV_TINT).xyz;
#endif
#if HAS_METALLIC_ROUGHNESS_TEXTURES
    v.tint.roughness = lv_b_at(LV_B_STRIDE * slot + LV_TINT).w;
    v.tint.metallic = lv_b_at(LV_B_STRIDE * slot + 2u).w;
#endif
#if HAS_CLEARCOAT_TEXTURES
    v.tint.coat = lv_b_at(LV_B_STRIDE * slot + LV_COAT).x;
    v.tint.coat_roughness = lv_b_at(LV_B_STRIDE * slot + LV_COAT).y;
#endif
#if HAS_TRANSMISSION_TEXTURES
    v.tint.transmission = lv_b_at(LV_B_STRIDE * slot + LV_TRANSMISSION).x;
#endif
#if HAS_SPECULAR_TEXTURES
    v.tint.specular = lv_b_at(LV_B_STRIDE * slot + LV_SPECULAR);
#endif
#if HAS_SHEEN_TEXTURES
    v.tint.sheen = lv_b_at(LV_B_STRIDE * slot + LV_SHEEN);
#endif
#if HAS_IRIDESCENCE_TEXTURES
    v.tint.iridescence = lv_b_at(LV_B_STRIDE * slot + LV_IRIDESCENCE).xy;
#endif
#if HAS_ANISOTROPY
    v.tint.anisotropy = lv_b_at(LV_B_STRIDE * slot + LV_ANISOTROPY);
#endif
#if HAS_DIFFUSE_TRANSMISSION_TEXTURES
    v.tint.diffuse_transmission = lv_b_at(LV_B_STRIDE * slot + LV_DIFFUSE_TRANSMISSION);
#endif
#if HAS_CLEARCOAT_NORMAL_MAPS
    v.tint.coat_normal = lv_b_at(LV_B_STRIDE * slot + LV_COAT_NORMAL).xyz;
#endif
#if HAS_DISPERSION
    v.tint.channel = floatBitsToUint(lv_b_at(LV_B_STRIDE * slot + LV_CHANNEL).x);
#endif
    uint info = floatBitsToUint(b1.w);
    v.material = info & LV_MATERIAL_MASK;
    v.sky_first_hit = (info & LV_SKY_FIRST_HIT) != 0u;
    v.len = info >> 24;
    return v;
}

#endif
