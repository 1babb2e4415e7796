//! Textures that vary the factors of KHR_materials_transmission (transmissionTexture, R)
//! and KHR_materials_specular (specularTexture, A; specularColorTexture, RGB, sRGB) per
//! point (glsl/textures.glsl `surface_tint`, glsl/bsdf.glsl `point_material`).
//!
//! Each test renders a floor of one textured material whose two halves read two different
//! texels (a 2 x 1 image, nearest filtering, each half's texture coordinates inside one
//! texel), and the same floor with, per half, the material whose constant factors are the
//! textured products: the two must agree per pixel (PT, Welch's test), and BPT on the
//! textured floor must agree with PT on the constant one (light vertices carry the point's
//! multipliers; the pdfs of the varied lobes). Statistics as in tests/render_clearcoat.rs:
//! K = iterations independent samples per pixel, the per-pixel tests Šidák-corrected so
//! that each comparison has false-failure probability 1e-3 (tests/common
//! `assert_textures_match_factors`). Lavapipe, validation on.

mod common;

use common::scenes::glossy_floor_scene;
use common::with_gpu;
use glam::{Vec2, Vec3};
use vkvcm::render::features::FeatureSet;
use vkvcm::scene::{Filter, LayerTextures, Material, Scene, TextureImage, TextureRef, VertexAttributes, Wrap};

const W: u32 = 20;
const H: u32 = 20;

/// Texel (0, 0) or (1, 0) of the 2 x 1 test image, nearest.
fn texture() -> TextureRef {
    TextureRef {
        image: 0,
        wrap_s: Wrap::ClampToEdge,
        wrap_t: Wrap::ClampToEdge,
        filter: Filter::Nearest,
        tex_coord: 0,
        transform: TextureRef::IDENTITY,
    }
}

/// tests/common's glossy floor with `textured` on both halves, the left half's texture
/// coordinates inside texel 0 and the right half's inside texel 1 of the 2 x 1 image
/// `texels`.
fn textured_floor(textured: Material, texels: [[u8; 4]; 2]) -> Scene {
    let mut sc = glossy_floor_scene(textured, Material::default());
    for t in sc.triangles.iter_mut().filter(|t| t.material < 2) {
        let u = if t.material == 0 { 0.25 } else { 0.75 };
        t.material = 0;
        t.attributes = Some(Box::new(VertexAttributes {
            uv: [Some([Vec2::new(u, 0.3), Vec2::new(u, 0.5), Vec2::new(u, 0.7)]), None],
            color: None,
            tangent: None,
        }));
    }
    sc.images = vec![TextureImage { name: "layers".into(), width: 2, height: 1, texels: texels.to_vec() }];
    sc.name = "two-texel floor".into();
    sc
}

/// The floor of `left` and `right` (constant factors) with the same texture coordinates
/// as `textured_floor` (which the materials do not read).
fn constant_floor(left: Material, right: Material, texels: [[u8; 4]; 2]) -> Scene {
    let mut sc = textured_floor(Material::default(), texels);
    sc.materials[0] = left;
    sc.materials[1] = right;
    let right_half = |t: &vkvcm::scene::Triangle| t.p.iter().all(|p| p.x >= 0.0) && t.p.iter().all(|p| p.z == 0.0);
    for t in sc.triangles.iter_mut().filter(|t| t.material == 0) {
        if right_half(t) {
            t.material = 1;
        }
    }
    sc
}

/// transmissionTexture's R multiplies transmissionFactor: rough glass (roughness 0.4, not
/// metallic, transmissionFactor 1: clear glass where the texel is 1) under texels R = 64
/// and 204 renders as glass of transmissionFactor 64/255 and 204/255, whose lobes beside
/// the glass the factor alone would not have. Sabotage: reading the texel's G (the other
/// half's value) fails it.
#[test]
fn transmission_texture_scales_the_factor() {
    let base = Vec3::new(0.8, 0.5, 0.3);
    let glass = |t: f32| Material::transmissive(base, 0.0, 0.4, t, 1.5, Vec3::splat(0.04));
    let mut textured = glass(1.0);
    textured.layer_textures = Some(Box::new(LayerTextures {
        transmission: Some(texture()),
        base,
        metallic: 0.0,
        roughness: 0.4,
        dielectric_f0: Vec3::splat(0.04),
        specular_f0: Vec3::splat(0.04),
        specular_factor: 1.0,
        ..Default::default()
    }));
    let texels = [[64, 204, 0, 255], [204, 64, 0, 255]];
    let tex = textured_floor(textured, texels);
    let f = FeatureSet::new(&tex, false);
    assert!(f.transmission_textures && f.partial_transmission && f.diffuse && f.ggx && !f.specular_textures, "{f}");
    let constant = constant_floor(glass(64.0 / 255.0), glass(204.0 / 255.0), texels);
    with_gpu(|gpu| common::assert_textures_match_factors(gpu, &tex, &constant, W, H));
}

/// The sRGB transfer function's inverse (IEC 61966-2-1), as the kernels decode texels.
fn srgb(c: u8) -> f32 {
    let c = c as f32 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// specularTexture's A multiplies specularFactor and specularColorTexture's RGB (sRGB)
/// specularColorFactor: a dielectric (red, roughness 0.3) of specularColorFactor 25 and
/// specularFactor 0.9 under texels (255, 128, 40, 100) and (60, 255, 200, 230) renders as
/// the dielectric whose F0 is min(0.04 x 25 x the decoded colour, 1) x 0.9 x A / 255 per
/// half (the first texel's R reaches the clamp). Sabotage: the colour texture read as
/// linear fails it.
#[test]
fn specular_textures_scale_the_factors() {
    let base = Vec3::new(0.7, 0.1, 0.1);
    let (color_factor, factor) = (25.0, 0.9);
    let mut textured = Material::metallic_roughness_with_f0(base, 0.0, 0.3, Vec3::ONE * factor);
    textured.layer_textures = Some(Box::new(LayerTextures {
        specular: Some(texture()),
        specular_color: Some(texture()),
        base,
        metallic: 0.0,
        roughness: 0.3,
        dielectric_f0: Vec3::ONE * factor,
        specular_f0: Vec3::splat(0.04 * color_factor),
        specular_factor: factor,
        ..Default::default()
    }));
    let texels = [[255, 128, 40, 100], [60, 255, 200, 230]];
    let f0 = |t: [u8; 4]| {
        let c = Vec3::new(srgb(t[0]), srgb(t[1]), srgb(t[2]));
        (Vec3::splat(0.04 * color_factor) * c).min(Vec3::ONE) * (factor * t[3] as f32 / 255.0)
    };
    let tex = textured_floor(textured, texels);
    let f = FeatureSet::new(&tex, false);
    assert!(f.specular_textures && !f.transmission_textures && !f.partial_transmission, "{f}");
    let constant_of = |t| Material::metallic_roughness_with_f0(base, 0.0, 0.3, f0(t));
    let constant = constant_floor(constant_of(texels[0]), constant_of(texels[1]), texels);
    with_gpu(|gpu| common::assert_textures_match_factors(gpu, &tex, &constant, W, H));
}
