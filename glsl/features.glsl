// Scene features a kernel is compiled with (src/render/features.rs derives them from the
// scene and the estimator; `--generic` defines them all to 1). Code for an absent feature
// is compiled out with `#if HAS_...`. Removing it never changes a result: an absent
// material component has zero albedo in every material (probability 0, contribution 0,
// and the sums it would add to get an exact +0), an absent light kind is never picked, and
// no random number is drawn by the removed code, so both variants consume the same random
// sequence. A kernel compiled without these defines gets every feature (the generic
// variant), as do the debug kernels under glsl/tests/.
#ifndef FEATURES_GLSL
#define FEATURES_GLSL

// Material components (glsl/bsdf.glsl).
#ifndef HAS_DIFFUSE
#define HAS_DIFFUSE 1
#endif
#ifndef HAS_PHONG
#define HAS_PHONG 1
#endif
#ifndef HAS_GGX
#define HAS_GGX 1
#endif
#ifndef HAS_MIRROR
#define HAS_MIRROR 1
#endif
#ifndef HAS_DIELECTRIC
#define HAS_DIELECTRIC 1
#endif
// The rough dielectric (glsl/bsdf.glsl): a dielectric whose GGX alpha is > 0.
#ifndef HAS_ROUGH_DIELECTRIC
#define HAS_ROUGH_DIELECTRIC 1
#endif
// A dielectric whose glass weight is below 1 (glsl/bsdf.glsl, "Partial transmission"):
// its diffuse, Phong and GGX lobes carry the rest, on both sides of the surface.
#ifndef HAS_PARTIAL_TRANSMISSION
#define HAS_PARTIAL_TRANSMISSION 1
#endif
// Absorbing media inside dielectrics (KHR_materials_volume; glsl/medium.glsl).
#ifndef HAS_VOLUME
#define HAS_VOLUME 1
#endif
#if HAS_VOLUME && !HAS_DIELECTRIC
#error "HAS_VOLUME needs HAS_DIELECTRIC (only a dielectric bounds a medium)"
#endif
#if HAS_PARTIAL_TRANSMISSION && !HAS_DIELECTRIC
#error "HAS_PARTIAL_TRANSMISSION needs HAS_DIELECTRIC"
#endif
#if HAS_ROUGH_DIELECTRIC && !HAS_DIELECTRIC
#error "HAS_ROUGH_DIELECTRIC needs HAS_DIELECTRIC (a rough dielectric is a dielectric)"
#endif
// A clear coat over some material (KHR_materials_clearcoat; glsl/lobes/clearcoat.glsl).
#ifndef HAS_CLEARCOAT
#define HAS_CLEARCOAT 1
#endif
// Coated materials whose coat factor or roughness a texture varies per point
// (glsl/textures.glsl `surface_tint`; light vertices carry the point's values).
#ifndef HAS_CLEARCOAT_TEXTURES
#define HAS_CLEARCOAT_TEXTURES 1
#endif
#if HAS_CLEARCOAT_TEXTURES && !HAS_CLEARCOAT
#error "HAS_CLEARCOAT_TEXTURES needs HAS_CLEARCOAT"
#endif
// Clear coats with their own normal map (clearcoatNormalTexture; surfaces and light
// vertices carry the coat's shading normal, Tint.coat_normal).
#ifndef HAS_CLEARCOAT_NORMAL_MAPS
#define HAS_CLEARCOAT_NORMAL_MAPS 1
#endif
// A sheen over some material (KHR_materials_sheen; glsl/lobes/sheen.glsl).
#ifndef HAS_SHEEN
#define HAS_SHEEN 1
#endif
// Sheens whose colour or roughness a texture varies per point (glsl/textures.glsl
// `surface_tint`; light vertices carry the point's values).
#ifndef HAS_SHEEN_TEXTURES
#define HAS_SHEEN_TEXTURES 1
#endif
#if HAS_SHEEN_TEXTURES && !HAS_SHEEN
#error "HAS_SHEEN_TEXTURES needs HAS_SHEEN"
#endif
// A thin-film iridescence over some material (KHR_materials_iridescence;
// glsl/lobes/iridescence.glsl).
#ifndef HAS_IRIDESCENCE
#define HAS_IRIDESCENCE 1
#endif
// Iridescent materials whose factor or film thickness a texture varies per point
// (glsl/textures.glsl `surface_tint`; light vertices carry the point's values).
#ifndef HAS_IRIDESCENCE_TEXTURES
#define HAS_IRIDESCENCE_TEXTURES 1
#endif
#if HAS_IRIDESCENCE_TEXTURES && !HAS_IRIDESCENCE
#error "HAS_IRIDESCENCE_TEXTURES needs HAS_IRIDESCENCE"
#endif
// Anisotropic GGX lobes (KHR_materials_anisotropy; glsl/lobes/anisotropy.glsl): surfaces
// and light vertices carry the point's anisotropy direction and strength (Tint.anisotropy).
#ifndef HAS_ANISOTROPY
#define HAS_ANISOTROPY 1
#endif
// Lambertian transmission through an opaque material (KHR_materials_diffuse_transmission;
// glsl/lobes/diffuse_transmission.glsl).
#ifndef HAS_DIFFUSE_TRANSMISSION
#define HAS_DIFFUSE_TRANSMISSION 1
#endif
// Diffuse transmissions whose factor or colour a texture varies per point
// (glsl/textures.glsl `surface_tint`; light vertices carry the point's values).
#ifndef HAS_DIFFUSE_TRANSMISSION_TEXTURES
#define HAS_DIFFUSE_TRANSMISSION_TEXTURES 1
#endif
#if HAS_DIFFUSE_TRANSMISSION_TEXTURES && !HAS_DIFFUSE_TRANSMISSION
#error "HAS_DIFFUSE_TRANSMISSION_TEXTURES needs HAS_DIFFUSE_TRANSMISSION"
#endif
#if HAS_DIFFUSE_TRANSMISSION && !HAS_DIFFUSE
#error "HAS_DIFFUSE_TRANSMISSION needs HAS_DIFFUSE"
#endif
// Glass whose IOR depends on the colour channel (KHR_materials_dispersion;
// glsl/lobes/dispersion.glsl): subpaths that meet it choose a channel (Tint.channel), light
// vertices carry it.
#ifndef HAS_DISPERSION
#define HAS_DISPERSION 1
#endif
#if HAS_DISPERSION && !HAS_DIELECTRIC
#error "HAS_DISPERSION needs HAS_DIELECTRIC (only glass disperses)"
#endif
// Light kinds (glsl/lights.glsl).
#ifndef HAS_AREA_LIGHTS
#define HAS_AREA_LIGHTS 1
#endif
#ifndef HAS_POINT_LIGHTS
#define HAS_POINT_LIGHTS 1
#endif
#ifndef HAS_SPOT_LIGHTS
#define HAS_SPOT_LIGHTS 1
#endif
#ifndef HAS_DIRECTIONAL_LIGHTS
#define HAS_DIRECTIONAL_LIGHTS 1
#endif
#ifndef HAS_BACKGROUND
#define HAS_BACKGROUND 1
#endif
// The background is an image (glsl/environment.glsl); else only constant backgrounds.
#ifndef HAS_ENVIRONMENT_MAP
#define HAS_ENVIRONMENT_MAP 1
#endif
// Geometry (glsl/scene.glsl; the BVH's own switch is BVH_NO_SPHERES).
#ifndef HAS_SPHERES
#define HAS_SPHERES 1
#endif
#ifndef HAS_SHADING_NORMALS
#define HAS_SHADING_NORMALS 1
#endif
// Surface detail (glsl/textures.glsl): per-vertex texture coordinates and colours (the
// tint), textures, alpha cut-outs.
#ifndef HAS_VERTEX_ATTRIBUTES
#define HAS_VERTEX_ATTRIBUTES 1
#endif
#if HAS_ANISOTROPY && !HAS_VERTEX_ATTRIBUTES
#error "HAS_ANISOTROPY needs HAS_VERTEX_ATTRIBUTES"
#endif
#ifndef HAS_TEXTURES
#define HAS_TEXTURES 1
#endif
#ifndef HAS_ALPHA_MASK
#define HAS_ALPHA_MASK 1
#endif
// One-sided surfaces (glTF doubleSided false): rays pass through their back side.
#ifndef HAS_ONE_SIDED
#define HAS_ONE_SIDED 1
#endif
#ifndef HAS_NORMAL_MAPS
#define HAS_NORMAL_MAPS 1
#endif
// Area lights whose radiance an emissive texture modulates (glsl/lights.glsl).
#ifndef HAS_EMISSIVE_TEXTURES
#define HAS_EMISSIVE_TEXTURES 1
#endif
// Materials whose metallic and roughness a metallicRoughnessTexture varies per point
// (glsl/textures.glsl `surface_tint`, glsl/bsdf.glsl `point_material`; light vertices
// carry the point's values, glsl/light_vertex_store.glsl).
#ifndef HAS_METALLIC_ROUGHNESS_TEXTURES
#define HAS_METALLIC_ROUGHNESS_TEXTURES 1
#endif
// Materials whose glass weight a transmissionTexture (KHR_materials_transmission) or
// whose dielectric F0 KHR_materials_specular's textures vary per point (glsl/textures.glsl
// `surface_tint`, glsl/bsdf.glsl `point_material`; light vertices carry the point's values).
#ifndef HAS_TRANSMISSION_TEXTURES
#define HAS_TRANSMISSION_TEXTURES 1
#endif
#if HAS_TRANSMISSION_TEXTURES && !HAS_PARTIAL_TRANSMISSION
#error "HAS_TRANSMISSION_TEXTURES needs HAS_PARTIAL_TRANSMISSION"
#endif
#ifndef HAS_SPECULAR_TEXTURES
#define HAS_SPECULAR_TEXTURES 1
#endif
// Profiling: count traced rays into stats[2..3] (glsl/scene.glsl, COUNT_RAYS_FLUSH).
#ifndef COUNT_RAYS
#define COUNT_RAYS 0
#endif

#if HAS_CLEARCOAT_NORMAL_MAPS && !(HAS_CLEARCOAT && HAS_SHADING_NORMALS)
#error "HAS_CLEARCOAT_NORMAL_MAPS needs HAS_CLEARCOAT and HAS_SHADING_NORMALS"
#endif
#endif
