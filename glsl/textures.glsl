// Surface detail: per-vertex attributes (texture coordinates, colours), base-colour,
// metallic-roughness, normal and emissive textures, and what they make of a point on a
// triangle: its tint (`Tint`: the base-colour texel's linear colour times the vertex
// colour, multiplying the material's base colour, and the metallic-roughness texel,
// multiplying its metallic and roughness factors: glsl/bsdf.glsl), its shading normal,
// its emission and its alpha (the material's alpha factor times the texel's and the
// vertex colour's: cut-outs, alpha_visible, which the traversal calls at every candidate
// hit).
//
// Bindings (src/render/scene_gpu.rs): vertex_attributes (GpuVertexAttributes, three per
// triangle that has attributes, at the triangle's first-vertex index p2.w), with
// HAS_TEXTURES texture_refs (GpuTextureRef per textured material) and texture_texels
// (RGBA8, R in the lowest byte, four texels per uvec4, all images one after another);
// with DEVICE_ADDRESSES vertex_attributes and texture_texels by address (scene.glsl).
//
// Sampling is done in software, the same on every device: texel (i, j) covers
// [i, i+1) x [j, j+1) of the texture's coordinates times its size, (0, 0) is the image's
// top-left corner (glTF); nearest takes the texel under the point, linear interpolates
// the four texels around it bilinearly; the wrap modes are glTF's (OpenGL's) REPEAT,
// CLAMP_TO_EDGE and MIRRORED_REPEAT, applied to the integer texel coordinates. RGB is
// sRGB-decoded per texel before filtering (glTF: base colour and emissive textures are
// sRGB), except for TEXTURE_LINEAR references (normal and metallic-roughness textures,
// whose texels are linear values). No mip-maps: the pixel samples of a render average
// the texture over each pixel.
//
// Requires: types.glsl, features.glsl, material_at / material_surface and triangle_at
// (scene.glsl).
#ifndef TEXTURES_GLSL
#define TEXTURES_GLSL

#if HAS_VERTEX_ATTRIBUTES
#if SCENE_CHUNKS
// Three 16-byte elements per vertex, in field order (glsl/scene.glsl, SCENE_CHUNKS).
GpuVertexAttributes vertex_attribute_at(uint i) {
    GpuVertexAttributes a;
    a.uv = uintBitsToFloat(scene_chunked_elem(CHUNK_VERTEX_ATTRIBUTES, 3u * i));
    a.color = uintBitsToFloat(scene_chunked_elem(CHUNK_VERTEX_ATTRIBUTES, 3u * i + 1u));
    a.tangent = uintBitsToFloat(scene_chunked_elem(CHUNK_VERTEX_ATTRIBUTES, 3u * i + 2u));
    return a;
}
#else
#if DEVICE_ADDRESSES
#define vertex_attribute_data SCENE_VERTEX_ATTRIBUTES
#else
layout(std430) readonly buffer vertex_attributes { GpuVertexAttributes vertex_attribute_data[]; };
#endif
GpuVertexAttributes vertex_attribute_at(uint i) { return vertex_attribute_data[i]; }
#endif
#endif

#if HAS_TEXTURES
layout(std430) readonly buffer texture_refs { GpuTextureRef texture_ref_data[]; };
#if DEVICE_ADDRESSES
#define texture_texel_data SCENE_TEXTURE_TEXELS
#else
layout(std430) readonly buffer texture_texels { uvec4 texture_texel_data[]; };
#endif

// The sRGB transfer function's inverse (IEC 61966-2-1).
float srgb_to_linear(float c) { return c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4); }

// Texel `i` of the image whose texels start at `first`: RGB (sRGB-decoded unless
// `linear`) and alpha.
vec4 texel_rgba(uint first, uint i, bool linear) {
    uint k = first + i;
    uint w = texture_texel_data[k >> 2][k & 3u];
    vec4 c = vec4((uvec4(w, w >> 8, w >> 16, w >> 24) & 0xffu)) / 255.0;
    if (linear) return c;
    return vec4(srgb_to_linear(c.r), srgb_to_linear(c.g), srgb_to_linear(c.b), c.a);
}

// Integer texel coordinate `i` wrapped into [0, n) by `mode` (0 repeat, 1 clamp to edge,
// 2 mirrored repeat: ... 1 0 | 0 1 ... n-1 | n-1 ... 0 | 0 ...).
int wrap_texel(int i, int n, uint mode) {
    if (mode == 1u) return clamp(i, 0, n - 1);
    if (mode == 2u) {
        int p = 2 * n;
        int m = ((i % p) + p) % p;
        return m < n ? m : p - 1 - m;
    }
    return ((i % n) + n) % n;
}

// Texture reference `ref` at texture coordinates `uv` (finite): linear RGBA (normal maps,
// TEXTURE_LINEAR, as stored).
vec4 texture_sample(uint ref, vec2 uv) {
    GpuTextureRef t = texture_ref_data[ref];
    bool lin = (t.image.w & TEXTURE_LINEAR) != 0u;
    vec3 h = vec3(uv, 1.0);
    vec2 st = vec2(dot(t.row0.xyz, h), dot(t.row1.xyz, h));
    int w = int(t.image.y);
    int ht = int(t.image.z);
    uint ms = t.image.w & 3u;
    uint mt = (t.image.w >> 2) & 3u;
    // Texel space, kept where floor() fits an int (beyond that nothing is resolved anyway).
    vec2 x = clamp(st * vec2(w, ht), vec2(-8388608.0), vec2(8388608.0));
    if ((t.image.w & TEXTURE_NEAREST) != 0u) {
        ivec2 i = ivec2(floor(x));
        return texel_rgba(t.image.x, uint(wrap_texel(i.y, ht, mt) * w + wrap_texel(i.x, w, ms)), lin);
    }
    vec2 y = x - 0.5;
    vec2 y0 = floor(y);
    vec2 f = y - y0;
    ivec2 i0 = ivec2(y0);
    int xa = wrap_texel(i0.x, w, ms), xb = wrap_texel(i0.x + 1, w, ms);
    int ya = wrap_texel(i0.y, ht, mt), yb = wrap_texel(i0.y + 1, ht, mt);
    vec4 c00 = texel_rgba(t.image.x, uint(ya * w + xa), lin);
    vec4 c10 = texel_rgba(t.image.x, uint(ya * w + xb), lin);
    vec4 c01 = texel_rgba(t.image.x, uint(yb * w + xa), lin);
    vec4 c11 = texel_rgba(t.image.x, uint(yb * w + xb), lin);
    return mix(mix(c00, c10, f.x), mix(c01, c11, f.x), f.y);
}
#endif

#if HAS_TEXTURES
// The texture coordinates that texture reference `ref` reads (its set, TEXCOORD_0 or _1)
// at barycentric weights (w0, u, v) of the triangle with vertex attributes a0, a1, a2;
// false where the triangle has no such coordinates (NaN) or they are not finite.
bool texture_uv(uint ref, GpuVertexAttributes a0, GpuVertexAttributes a1, GpuVertexAttributes a2, float w0,
                float u, float v, out vec2 uv) {
    bool uv1 = (texture_ref_data[ref].image.w & TEXTURE_UV1) != 0u;
    vec2 t0 = uv1 ? a0.uv.zw : a0.uv.xy;
    vec2 t1 = uv1 ? a1.uv.zw : a1.uv.xy;
    vec2 t2 = uv1 ? a2.uv.zw : a2.uv.xy;
    uv = w0 * t0 + u * t1 + v * t2;
    return !any(isnan(uv)) && !any(isinf(uv));
}
#endif

#if HAS_VERTEX_ATTRIBUTES
// The per-vertex attributes of triangle `tri` (from its first_vertex index); false,
// with a0..a2 unset, where it has none.
bool triangle_attributes(uint tri, out GpuVertexAttributes a0, out GpuVertexAttributes a1,
                         out GpuVertexAttributes a2) {
    uint first = triangle_at(tri).first_vertex;
    if (first == 0xffffffffu) return false;
    a0 = vertex_attribute_at(first);
    a1 = vertex_attribute_at(first + 1u);
    a2 = vertex_attribute_at(first + 2u);
    return true;
}
#endif

// A surface point's tint: what its textures and vertex colour multiply the material's
// factors by. rgb: the base colour (the base-colour texel's linear colour times COLOR_0);
// roughness and metallic: the roughness and metallic factors (the metallicRoughnessTexture
// texel's linear G and B, glTF 2.0 section 3.9.2). All 1 where the point has none, and
// then the material is its own, bit for bit (glsl/bsdf.glsl). Surfaces and light vertices
// carry it (glsl/scene.glsl, glsl/light_vertex_store.glsl).
struct Tint {
    vec3 rgb;
    float roughness;
    float metallic;
    float coat;            // multiplies the clear coat factor (clearcoatTexture's R)
    float coat_roughness;  // multiplies its roughness (clearcoatRoughnessTexture's G)
    float transmission;    // multiplies transmissionFactor (transmissionTexture's R)
    vec4 specular;         // rgb: multiplies specularColorFactor (specularColorTexture's RGB),
                           // a: specularFactor (specularTexture's A)
    vec4 sheen;            // rgb: multiplies sheenColorFactor (sheenColorTexture's RGB),
                           // a: sheenRoughnessFactor (sheenRoughnessTexture's A)
    vec2 iridescence;      // x: multiplies iridescenceFactor (iridescenceTexture's R),
                           // y: the film thickness between minimum and maximum (its thickness texture's G)
    vec4 anisotropy;       // xyz: the GGX lobe's anisotropy direction (world, unit), w: its
                           // strength, 0: isotropic (anisotropy_at)
    vec4 diffuse_transmission;  // rgb: multiplies diffuseTransmissionColorFactor
                                // (diffuseTransmissionColorTexture's RGB), a:
                                // diffuseTransmissionFactor (diffuseTransmissionTexture's A)
    vec3 coat_normal;      // the clear coat's shading normal (its normal map), on the side
                           // of the winding's normal; 0: the base's (glsl/lobes/clearcoat.glsl)
#if HAS_DISPERSION
    uint channel;          // the colour channel (0-2) the subpath carries, or NO_CHANNEL: the
                           // glass's IOR there (glsl/lobes/dispersion.glsl). Not a texture's
                           // value: the subpath's, set where it reaches the point.
#endif
};

Tint no_tint() {
#if HAS_DISPERSION
    return Tint(vec3(1.0), 1.0, 1.0, 1.0, 1.0, 1.0, vec4(1.0), vec4(1.0), vec2(1.0), vec4(0.0), vec4(1.0), vec3(0.0),
                NO_CHANNEL);
#else
    return Tint(vec3(1.0), 1.0, 1.0, 1.0, 1.0, 1.0, vec4(1.0), vec4(1.0), vec2(1.0), vec4(0.0), vec4(1.0), vec3(0.0));
#endif
}

// The tint (rgb) and alpha (times the material's alpha factor) of triangle `tri` with
// material `material` at barycentric weights (u, v): (1, 1, 1, factor) where it has no
// attributes.
vec4 surface_tint_alpha(uint tri, uint material, float u, float v) {
    vec4 r = vec4(1.0, 1.0, 1.0, material_surface(material).y);
#if HAS_VERTEX_ATTRIBUTES
    GpuVertexAttributes a0, a1, a2;
    if (!triangle_attributes(tri, a0, a1, a2)) return r;
    float w0 = 1.0 - u - v;
    // A constant colour (white where there is none) is taken as it is, not interpolated.
    vec4 color = (a0.color == a1.color && a0.color == a2.color) ? a0.color
                                                               : w0 * a0.color + u * a1.color + v * a2.color;
    r *= color;
#if HAS_TEXTURES
    uint ref = floatBitsToUint(material_surface(material).x);
    vec2 uv;
    // Without such coordinates the factor alone applies.
    if (ref != NO_TEXTURE && texture_uv(ref, a0, a1, a2, w0, u, v, uv)) r *= texture_sample(ref, uv);
#endif
#endif
    return r;
}

#define HAS_TINT_TEXTURES                                                                                   \
    (HAS_METALLIC_ROUGHNESS_TEXTURES || HAS_CLEARCOAT_TEXTURES || HAS_SHEEN_TEXTURES || HAS_IRIDESCENCE_TEXTURES || \
     HAS_DIFFUSE_TRANSMISSION_TEXTURES || HAS_TRANSMISSION_TEXTURES || HAS_SPECULAR_TEXTURES)

#if HAS_TINT_TEXTURES
// A triangle's vertex attributes (`ok` false where it has none) at barycentric weights
// (u, v), read once for all the textures of a point.
struct PointAttributes {
    GpuVertexAttributes a0, a1, a2;
    float u, v;
    bool ok;
};

PointAttributes point_attributes(uint tri, float u, float v) {
    PointAttributes pa;
    pa.u = u;
    pa.v = v;
    pa.ok = triangle_attributes(tri, pa.a0, pa.a1, pa.a2);
    return pa;
}

// The texel of texture `ref` at the point; false where there is no texture
// (NO_TEXTURE) or the triangle lacks its coordinates (the factor alone applies).
bool point_texel(uint ref, PointAttributes pa, out vec4 texel) {
    vec2 uv;
    texel = vec4(1.0);
    if (ref == NO_TEXTURE || !pa.ok || !texture_uv(ref, pa.a0, pa.a1, pa.a2, 1.0 - pa.u - pa.v, pa.u, pa.v, uv))
        return false;
    texel = texture_sample(ref, uv);
    return true;
}
#endif

// The tint of triangle `tri` with material `material` at barycentric weights (u, v):
// its base colour's (surface_tint_alpha) and the texels of the material's other
// textures at the point's texture coordinates (each where the material has the texture
// and the triangle its coordinates; else the factors alone apply). Linear texels but
// the colours' (sRGB), as glTF and its extensions say:
// * metallicRoughnessTexture (glTF 2.0 section 3.9.2): roughness = factor x G,
//   metallic = factor x B (R is unused);
// * KHR_materials_clearcoat: factor x clearcoatTexture's R, roughness x
//   clearcoatRoughnessTexture's G;
// * KHR_materials_sheen: colour factor x sheenColorTexture's RGB, roughness x
//   sheenRoughnessTexture's A;
// * KHR_materials_iridescence: factor x iridescenceTexture's R, thickness
//   mix(minimum, maximum, iridescenceThicknessTexture's G);
// * KHR_materials_diffuse_transmission: factor x diffuseTransmissionTexture's A, colour
//   factor x diffuseTransmissionColorTexture's RGB;
// * KHR_materials_transmission: factor x transmissionTexture's R;
// * KHR_materials_specular: colour factor x specularColorTexture's RGB, factor x
//   specularTexture's A.
Tint surface_tint(uint tri, uint material, float u, float v) {
    Tint t = no_tint();
#if HAS_VERTEX_ATTRIBUTES
    t.rgb = surface_tint_alpha(tri, material, u, v).rgb;
#endif
#if HAS_TINT_TEXTURES
    PointAttributes pa = point_attributes(tri, u, v);
    vec4 texel;
#endif
#if HAS_METALLIC_ROUGHNESS_TEXTURES
    if (point_texel(floatBitsToUint(material_maps(material).w), pa, texel)) {
        t.roughness = texel.g;
        t.metallic = texel.b;
    }
#endif
#if HAS_CLEARCOAT_TEXTURES
    vec4 coat = material_coat(material);
    if (point_texel(floatBitsToUint(coat.z), pa, texel)) t.coat = texel.r;
    if (point_texel(floatBitsToUint(coat.w), pa, texel)) t.coat_roughness = texel.g;
#endif
#if HAS_SHEEN_TEXTURES
    vec4 sheen_maps = material_sheen_maps(material);
    if (point_texel(floatBitsToUint(sheen_maps.x), pa, texel)) t.sheen.rgb = texel.rgb;
    if (point_texel(floatBitsToUint(sheen_maps.y), pa, texel)) t.sheen.a = texel.a;
#endif
#if HAS_IRIDESCENCE_TEXTURES
    vec4 iridescence_maps = material_iridescence_maps(material);
    if (point_texel(floatBitsToUint(iridescence_maps.x), pa, texel)) t.iridescence.x = texel.r;
    if (point_texel(floatBitsToUint(iridescence_maps.y), pa, texel)) t.iridescence.y = texel.g;
#endif
#if HAS_DIFFUSE_TRANSMISSION_TEXTURES
    vec4 dt_maps = material_diffuse_transmission_maps(material);
    if (point_texel(floatBitsToUint(dt_maps.x), pa, texel)) t.diffuse_transmission.a = texel.a;
    if (point_texel(floatBitsToUint(dt_maps.y), pa, texel)) t.diffuse_transmission.rgb = texel.rgb;
#endif
#if HAS_TRANSMISSION_TEXTURES || HAS_SPECULAR_TEXTURES
    vec4 layers = material_layers(material);
#endif
#if HAS_TRANSMISSION_TEXTURES
    if (point_texel(floatBitsToUint(layers.x), pa, texel)) t.transmission = texel.r;
#endif
#if HAS_SPECULAR_TEXTURES
    if (point_texel(floatBitsToUint(layers.y), pa, texel)) t.specular.a = texel.a;
    if (point_texel(floatBitsToUint(layers.z), pa, texel)) t.specular.rgb = texel.rgb;
#endif
    return t;
}

#if HAS_EMISSIVE_TEXTURES
// What multiplies the emitted radiance of triangle `tri` at barycentric weights (u, v):
// its material's emissive texture (glTF emissiveTexture, sRGB-decoded linear RGB) at the
// point's texture coordinates; 1 where the material has none or the triangle lacks the
// texture's coordinates. The area-light code (glsl/lights.glsl) applies it wherever
// radiance leaves a light: when a path hits it, when next-event estimation samples a
// point on it, and when a light subpath starts there. Light points are still chosen
// uniformly by area, so every pdf is unchanged and MIS stays exact.
vec3 emission_tint(uint tri, float u, float v) {
    uint ref = floatBitsToUint(material_maps(triangle_at(tri).material).z);
    if (ref == NO_TEXTURE) return vec3(1.0);
    GpuVertexAttributes a0, a1, a2;
    vec2 uv;
    if (!triangle_attributes(tri, a0, a1, a2) || !texture_uv(ref, a0, a1, a2, 1.0 - u - v, u, v, uv)) {
        return vec3(1.0);
    }
    return texture_sample(ref, uv).rgb;
}
#endif

#if HAS_NORMAL_MAPS || HAS_ANISOTROPY || HAS_CLEARCOAT_NORMAL_MAPS
// The tangent frame of triangle `tri` (with per-vertex attributes a0, a1, a2, read here)
// at (u, v) about the unit normal `n`: the interpolated tangent T made orthogonal to n and
// B = w cross(n, T) (w: the tangent's bitangent sign); false where the triangle has no
// attributes or no tangent. `record`: the instance record of a shared mesh's triangle
// (glsl/bvh.glsl), whose object-to-world rows map each vertex's tangent to world space as
// the importer does for flattened meshes (direction normalised, the bitangent sign
// flipped by a mirroring transform); BVH_NO_INSTANCE for world space.
bool tangent_frame(uint tri, uint record, float u, float v, vec3 n, out GpuVertexAttributes a0,
                   out GpuVertexAttributes a1, out GpuVertexAttributes a2, out vec3 tg, out vec3 b) {
    tg = vec3(0.0);
    b = vec3(0.0);
    if (!triangle_attributes(tri, a0, a1, a2)) return false;
#ifdef BVH_INSTANCES
    if (record != BVH_NO_INSTANCE) {
        vec3 r0 = uintBitsToFloat(bvh_prim_elem(3u * record + 3u).xyz);
        vec3 r1 = uintBitsToFloat(bvh_prim_elem(3u * record + 4u).xyz);
        vec3 r2 = uintBitsToFloat(bvh_prim_elem(3u * record + 5u).xyz);
        float sign_det = dot(r0, cross(r1, r2)) < 0.0 ? -1.0 : 1.0;
        vec4 ts[3] = vec4[3](a0.tangent, a1.tangent, a2.tangent);
        for (int k = 0; k < 3; k++) {
            vec3 tw = vec3(dot(r0, ts[k].xyz), dot(r1, ts[k].xyz), dot(r2, ts[k].xyz));
            ts[k] = vec4(dot(tw, tw) > 0.0 ? normalize(tw) : tw, ts[k].w * sign_det);
        }
        a0.tangent = ts[0];
        a1.tangent = ts[1];
        a2.tangent = ts[2];
    }
#endif
    vec4 t = (1.0 - u - v) * a0.tangent + u * a1.tangent + v * a2.tangent;
    if (any(isnan(t))) return false;
    tg = t.xyz - n * dot(n, t.xyz);
    float tl = length(tg);
    if (!(tl > 1e-8)) return false;
    tg /= tl;
    b = cross(n, tg) * (t.w < 0.0 ? -1.0 : 1.0);
    return true;
}
#endif

#if HAS_ANISOTROPY
// The anisotropy of material `material` at (u, v) of triangle `tri` (Tint.anisotropy),
// about the unit shading normal `n` (KHR_materials_anisotropy): the direction
// (cos r, sin r) rotated by anisotropyRotation r, with an anisotropyTexture its texel's
// RG mapped to [-1, 1] and normalised, rotated by r, in the tangent frame (tangent_frame),
// and the strength anisotropyStrength (times the texel's B). Isotropic (strength 0)
// where the triangle has no tangent: the importer warns of primitives without TANGENT
// or texture coordinates to generate tangents from.
vec4 anisotropy_at(uint tri, uint record, uint material, float u, float v, vec3 n) {
    vec4 an = material_anisotropy(material);
    if (an.z <= 0.0) return vec4(0.0);
    GpuVertexAttributes a0, a1, a2;
    vec3 tg, b;
    if (!tangent_frame(tri, record, u, v, n, a0, a1, a2, tg, b)) return vec4(0.0);
    vec2 dir = vec2(1.0, 0.0);
    float strength = an.z;
#if HAS_TEXTURES
    uint ref = floatBitsToUint(an.w);
    vec2 uv;
    if (ref != NO_TEXTURE && texture_uv(ref, a0, a1, a2, 1.0 - u - v, u, v, uv)) {
        vec3 texel = texture_sample(ref, uv).rgb;
        vec2 d = texel.rg * 2.0 - 1.0;
        float dl = length(d);
        dir = dl > 0.0 ? d / dl : dir;
        strength *= texel.b;
    }
#endif
    // The rotation matrix [cos -sin; sin cos] applied to dir.
    vec2 r = vec2(an.x * dir.x - an.y * dir.y, an.y * dir.x + an.x * dir.y);
    return vec4(normalize(r.x * tg + r.y * b), strength);
}
#endif

#if HAS_NORMAL_MAPS || HAS_CLEARCOAT_NORMAL_MAPS
// The unit shading normal `n` of triangle `tri` (with per-vertex attributes) at (u, v),
// bent by the normal map `ref` (NO_TEXTURE: none) of scale `scale` (glTF 2.0 section
// 3.9.3, normalTexture; the clear coat's clearcoatNormalTexture the same way): the
// texel's RGB as (x, y, z) * 2 - 1, x and y times the scale, in the tangent frame
// (tangent_frame) and n. Unchanged where there is no map or the triangle has no texture
// coordinates for it or no tangent.
vec3 normal_mapped_by(uint ref, float scale, uint tri, uint record, float u, float v, vec3 n) {
    if (ref == NO_TEXTURE) return n;
    GpuVertexAttributes a0, a1, a2;
    vec3 tg, b;
    vec2 uv;
    if (!tangent_frame(tri, record, u, v, n, a0, a1, a2, tg, b) || !texture_uv(ref, a0, a1, a2, 1.0 - u - v, u, v, uv))
        return n;
    vec3 m = texture_sample(ref, uv).xyz * 2.0 - 1.0;
    m.xy *= scale;
    vec3 bent = m.x * tg + m.y * b + m.z * n;
    float bl = length(bent);
    return bl > 0.0 ? bent / bl : n;
}
#endif

#if HAS_NORMAL_MAPS
// `n` bent by its material's normal map (normal_mapped_by).
vec3 normal_mapped(uint tri, uint record, uint material, float u, float v, vec3 n) {
    vec4 maps = material_maps(material);
    return normal_mapped_by(floatBitsToUint(maps.x), maps.y, tri, record, u, v, n);
}
#endif

// The probability that the surface is there at the point (alpha_visible's rules below):
// 1 or 0 for OPAQUE and MASK, alpha for BLEND (`blend` says which).
float surface_presence(uint id, uint material, float u, float v, out bool blend) {
    vec4 srf = material_surface(material);
    blend = srf.z == ALPHA_BLEND;
    if (srf.z == ALPHA_OPAQUE) return 1.0;
    float alpha = (id & BVH_SPHERE_FLAG) != 0u ? srf.y : surface_tint_alpha(id, material, u, v).a;
    if (!blend) return alpha >= srf.z ? 1.0 : 0.0;
    return alpha;
}

// Whether a candidate hit (primitive id `id` with the BVH's sphere flag, `material`, at
// (u, v), distance t along the ray) is there, for every ray:
// * alphaMode MASK (surface.z = its cutoff >= 0): false on the cut-away part, where alpha
//   is below the cutoff (glTF: MASK is opaque where alpha >= cutoff);
// * BLEND (ALPHA_BLEND): true with probability alpha, stochastic transparency (Enderton
//   et al. 2010): a ray that misses the surface passes straight through, so the expected
//   light through it is (1 - alpha) times what is behind and alpha times the surface's,
//   glTF's "over" compositing. Unbiased for every estimator: every technique meets the
//   surface with the same probability, so their contributions keep their expectations
//   and the MIS weights still sum to 1. The random number hashes the hit's barycentrics,
//   distance, primitive and the render's seed (as hashed alpha testing hashes its
//   coordinates, Wyman & McGuire 2017): the same ray decides alike whenever it is traced,
//   and the image is deterministic per seed;
// * else (OPAQUE) true.
// Spheres have no attributes: their alpha is the material's factor.
bool alpha_visible(uint id, uint material, float u, float v, float t) {
    bool blend;
    float presence = surface_presence(id, material, u, v, blend);
    if (!blend) return presence > 0.0;
    uint h = pcg_hash(id ^ pcg_hash(params.misc.x));
    h = pcg_hash(floatBitsToUint(t) ^ pcg_hash(floatBitsToUint(u) ^ pcg_hash(floatBitsToUint(v) ^ h)));
    return float(h >> 8) * (1.0 / 16777216.0) < presence;
}

// How much of an emitting triangle `tri` is there at barycentric weights (u, v), for
// light that leaves it without a ray meeting it first (next-event estimation's light
// samples and the start of light subpaths): its surface_presence, the probability that
// alpha_visible lets a ray meet it there, so a path that hits it collects the same
// expectation. A path that hits the light has passed alpha_visible already, so its
// radiance is not scaled. Light points are still sampled uniformly by area: the pdfs,
// and so the MIS weights, are unchanged.
float emitter_presence(uint tri, float u, float v) {
    bool blend;
    return surface_presence(tri, triangle_at(tri).material, u, v, blend);
}

#endif
