//! KHR_materials_clearcoat's clearcoatNormalTexture (glsl/lobes/clearcoat.glsl): the coat
//! shades with its own normal map while the base keeps its normal.
mod common;

use common::scenes::*;
use common::{image_mean, with_gpu, TestRender};
use glam::{Vec3, Vec4};
use vkvcm::render::Algorithm;
use vkvcm::scene::{Material, Scene, TextureRef};
use vkvcm_tools::stats::welch_test;

/// Family-wise false-alarm rate of each image comparison (Šidák-corrected per pixel).
const ALPHA: f64 = 1e-3;
const W: u32 = 20;
const H: u32 = 20;

fn normal_map() -> TextureRef {
    TextureRef {
        image: 0,
        wrap_s: vkvcm::scene::Wrap::Repeat,
        wrap_t: vkvcm::scene::Wrap::Repeat,
        filter: vkvcm::scene::Filter::Nearest,
        tex_coord: 0,
        transform: TextureRef::IDENTITY,
    }
}

/// A normal map's texel for the unit normal (x, y, z) of tangent space.
fn texel(n: Vec3) -> [u8; 4] {
    let c = |x: f32| ((x * 0.5 + 0.5) * 255.0).round() as u8;
    [c(n.x), c(n.y), c(n.z), 255]
}

/// glossy_floor_scene with `left` and `right` on floors that carry flat vertex normals,
/// texture coordinates and tangents (+x, bitangent +y), under one normal-map texel
/// `t` (image 0).
fn mapped_floor_scene(left: Material, right: Material, t: [u8; 4]) -> Scene {
    let mut sc = glossy_floor_scene(left, right);
    for tri in sc.triangles.iter_mut().filter(|t| t.material < 2) {
        tri.n = Some([Vec3::Z; 3]);
        tri.attributes = Some(Box::new(vkvcm::scene::VertexAttributes {
            uv: [Some([glam::Vec2::ZERO, glam::Vec2::X, glam::Vec2::Y]), None],
            color: None,
            tangent: Some([Vec4::new(1.0, 0.0, 0.0, 1.0); 3]),
        }));
    }
    sc.images = vec![vkvcm::scene::TextureImage { name: "normals".into(), width: 1, height: 1, texels: vec![t] }];
    sc
}

fn coat(name: &str, base: Material, roughness: f32) -> Material {
    Material { name: name.into(), clearcoat: 1.0, clearcoat_roughness: roughness, ..base }
}

fn coat_mapped(m: Material) -> Material {
    Material { clearcoat_normal_texture: Some(normal_map()), clearcoat_normal_scale: 1.0, ..m }
}

/// The tilted normal of the tests: 20 degrees towards +x.
fn tilted() -> Vec3 {
    let a = 20f32.to_radians();
    Vec3::new(a.sin(), 0.0, a.cos())
}

/// Coats over a black base (the coat alone) on floors of glossy_floor_scene, roughness
/// 0.2 (left) and 0.5 (right), with a clearcoatNormalTexture tilting the coat's normal 20
/// degrees: per pixel as the same coats without their own map over a base whose
/// normalTexture is that map (the path where the coat shades with the base's normal: with
/// a black base, the two describe the same surface), by PT and by LT (light subpaths: the
/// coat's adjoint cosine). And the coat's highlight moves: the
/// image differs from the one with a flat coat normal map (texel (0, 0, 1)) in at least
/// 20 pixels. Sabotages: see the commit message.
#[test]
fn coat_normal_map_tilts_the_coat() {
    let black = Material::default();
    let t = texel(tilted());
    let own = mapped_floor_scene(
        coat_mapped(coat("left", black.clone(), 0.2)),
        coat_mapped(coat("right", black.clone(), 0.5)),
        t,
    );
    let base_mapped = |m: Material| Material { normal_texture: Some(normal_map()), normal_scale: 1.0, ..m };
    let via_base = mapped_floor_scene(
        base_mapped(coat("left", black.clone(), 0.2)),
        base_mapped(coat("right", black.clone(), 0.5)),
        t,
    );
    let flat = mapped_floor_scene(
        coat_mapped(coat("left", black.clone(), 0.2)),
        coat_mapped(coat("right", black, 0.5)),
        texel(Vec3::Z),
    );
    with_gpu(|gpu| {
        let a = TestRender::new(Algorithm::Pt, W, H, 1024).seed(31).max_path_length(4).stats(gpu, &own);
        for (what, algo, x, y) in [
            (
                "PT",
                Algorithm::Pt,
                a.clone(),
                TestRender::new(Algorithm::Pt, W, H, 1024).seed(32).max_path_length(4).stats(gpu, &via_base),
            ),
            (
                "LT",
                Algorithm::Lt,
                TestRender::new(Algorithm::Lt, W, H, 1024).seed(34).max_path_length(4).stats(gpu, &own),
                TestRender::new(Algorithm::Lt, W, H, 1024).seed(35).max_path_length(4).stats(gpu, &via_base),
            ),
        ] {
            eprintln!("{what} ({algo:?}): coat's own map {:.5}, the base's map {:.5}", image_mean(&x), image_mean(&y));
            let t = welch_test(&x, &y, ALPHA).unwrap();
            assert!(t.passed(), "{what}: coat normal map vs the base's: {t}");
        }
        let c = TestRender::new(Algorithm::Pt, W, H, 1024).seed(33).max_path_length(4).stats(gpu, &flat);
        let t = welch_test(&a, &c, ALPHA).unwrap();
        eprintln!("tilted vs flat coat normal: {t}");
        assert!(!t.passed() && t.failed >= 20, "the coat's normal map does not move its highlight: {t}");
    });
}

/// The coat's own normal map over bases that keep their flat normal: left a red
/// dielectric (glTF roughness 0.6) under a coat of roughness 0.3, right a Lambertian
/// yellow under a coat of roughness 0.15, both coats tilted 20 degrees by their map. PT
/// with NEE against PT without and BPT (light vertices carry the coat's normal). Not LT:
/// its samples of the coats' narrow highlights are rare and large (heavy-tailed), so its
/// per-pixel means there converge slowly from below with too small a variance estimate
/// and no per-pixel test of it is fair at a test's cost (at 16,384 iterations some highlight
/// pixels are still half PT's value, with or without any normal map; LT's image mean is
/// PT's within 0.2%).
#[test]
fn coat_normal_map_estimators_agree() {
    let sc = mapped_floor_scene(
        coat_mapped(coat("left", Material::metallic_roughness(Vec3::new(0.8, 0.2, 0.1), 0.0, 0.6), 0.3)),
        coat_mapped(coat("right", Material { diffuse: Vec3::new(0.7, 0.6, 0.1), ..Default::default() }, 0.15)),
        texel(tilted()),
    );
    with_gpu(|gpu| {
        let pt = TestRender::new(Algorithm::Pt, W, H, 2048).seed(41).max_path_length(4).stats(gpu, &sc);
        assert!(image_mean(&pt) > 0.02, "the scene rendered (almost) black");
        for (what, other) in [
            (
                "PT without NEE",
                TestRender::new(Algorithm::Pt, W, H, 2048).seed(42).max_path_length(4).nee(false).stats(gpu, &sc),
            ),
            ("BPT", TestRender::new(Algorithm::Bpt, W, H, 1024).seed(43).max_path_length(4).stats(gpu, &sc)),
        ] {
            eprintln!("image mean PT {:.5}, {what} {:.5}", image_mean(&pt), image_mean(&other));
            let t = welch_test(&pt, &other, ALPHA).unwrap();
            assert!(t.passed(), "PT vs {what}: {t}");
        }
    });
}

/// The switch is on only with a coated material's map and tangents.
#[test]
fn coat_normal_map_features() {
    use vkvcm::render::features::FeatureSet;
    let m = coat_mapped(coat("c", Material::default(), 0.3));
    let f = FeatureSet::new(&mapped_floor_scene(m.clone(), Material::default(), texel(Vec3::Z)), false);
    assert!(f.clearcoat_normal_maps && f.shading_normals && !f.normal_maps, "{f}");
    let f = FeatureSet::new(&glossy_floor_scene(m.clone(), Material::default()), false);
    assert!(!f.clearcoat_normal_maps, "without tangents: {f}");
    let uncoated = Material { clearcoat: 0.0, ..m };
    let f = FeatureSet::new(&mapped_floor_scene(uncoated, Material::default(), texel(Vec3::Z)), false);
    assert!(!f.clearcoat_normal_maps, "without a coat: {f}");
}
