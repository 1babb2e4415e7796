//! Khronos glTF sample models (tests/khronos/, unmodified glTF-Embedded copies: licences
//! in tests/khronos/README.md) render out of the box: none has a light and most have no
//! camera, so each gets the default camera and the white sky, with one warning each, and
//! renders a non-black image with every camera estimator family (pt, bpt, vcm) under
//! validation. Features vkvcm does not read yet (textures, vertex colours) are warnings,
//! not errors.

mod common;

use common::with_gpu;
use vkvcm::render::{self, Algorithm, Budget, RenderSettings};

const MODELS: [&str; 6] =
    ["Box", "BoxTextured", "BoxVertexColors", "TextureCoordinateTest", "OrientationTest", "SimpleMeshes"];

#[test]
fn sample_models_render_with_the_defaults() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/khronos");
    with_gpu(|gpu| {
        for name in MODELS {
            let path = dir.join(format!("{name}.gltf"));
            let scene = vkvcm::scene::load_named_with(path.to_str().unwrap(), &Default::default())
                .unwrap_or_else(|e| panic!("{name}: {e:#}"));
            let w = &scene.report.warnings;
            assert_eq!(w.iter().filter(|w| w.contains("white sky")).count(), 1, "{name}: {w:?}");
            for algo in [Algorithm::Pt, Algorithm::Bpt, Algorithm::Vcm] {
                let s = RenderSettings::new(algo, 32, 32, Budget::Iterations(4));
                let out = render::render(gpu, &scene, &s, None, &mut |_| {}).unwrap();
                assert_eq!(out.rejected_samples, 0, "{name} {}: rejected samples", algo.name());
                let lit = out.pixels.iter().filter(|p| p.iter().sum::<f32>() > 0.0).count();
                // The sky is white (radiance 1): a pixel that sees the model darker than the
                // sky shows the model is in view.
                let model = out.pixels.iter().filter(|p| p.iter().sum::<f32>() < 2.9).count();
                assert!(lit > 0 && model > 16, "{name} {}: {lit} lit pixels, {model} on the model", algo.name());
            }
        }
    });
}
