//! Shared test helpers: a validated GPU (any validation message fails), small scenes.
#![allow(dead_code)]

pub mod corpus;
pub mod scenes;

use std::sync::Arc;

use vkvcm::gpu::{Gpu, GpuOptions};

/// Runs `f` with a validation-enabled GPU without a kernel cache
/// ([`GpuOptions::for_tests`]); fails if the layer said anything, including at device
/// destruction (leaked objects).
pub fn with_gpu<R>(f: impl FnOnce(&Arc<Gpu>) -> R) -> R {
    with_gpu_options(&GpuOptions::for_tests(), f)
}

/// [`with_gpu`] with `opts` (which must turn validation on).
pub fn with_gpu_options<R>(opts: &GpuOptions, f: impl FnOnce(&Arc<Gpu>) -> R) -> R {
    let gpu = Gpu::new(opts).expect("cannot open a Vulkan device for tests");
    assert!(gpu.validation_enabled());
    let messages = gpu.validation_messages();
    let r = f(&gpu);
    assert_eq!(Arc::strong_count(&gpu), 1, "a GPU object outlived the test body");
    drop(gpu);
    let list = messages.list();
    assert!(list.is_empty(), "Vulkan validation messages:\n{}", list.join("\n"));
    r
}

/// Per-pixel statistics of one render, from its per-iteration sums (K = iterations).
/// Pixels where `mask` is false are zeroed (equal means, zero variance: they pass).
pub fn render_stats(out: &vkvcm::render::RenderOutput, mask: Option<&[bool]>) -> vkvcm::image::stats::PixelStats {
    let (mut sum, mut sum_sq) = (out.sum.clone(), out.sum_sq.clone());
    if let Some(m) = mask {
        for i in 0..sum.len() {
            if !m[i] {
                sum[i] = [0.0; 3];
                sum_sq[i] = [0.0; 3];
            }
        }
    }
    vkvcm::image::stats::PixelStats::from_sums(out.width, out.height, out.iterations as usize, &sum, &sum_sq)
        .expect("render statistics")
}

/// The reference-scene x estimator cases of the tests that check an image does not depend
/// on a setting which must not change it (tests/render_regen.rs, tests/render_reads.rs):
/// every light-subpath and camera estimator on glm_c (area light: light tracing's emitter
/// connections), bpt there with both connection strategies; lt, bpt and vcm on gbs_s
/// (directional light); pt and vcm on gbs_b (camera paths that escape to the
/// background). `(scene name, estimator, where bpt and vcm connect)`.
pub fn invariance_cases() -> Vec<(&'static str, vkvcm::render::Algorithm, vkvcm::render::Connect)> {
    use vkvcm::render::Algorithm::*;
    use vkvcm::render::Connect;
    let d = |a: vkvcm::render::Algorithm| a.default_connect();
    vec![
        ("glm_c", Pt, d(Pt)),
        ("glm_c", Lt, d(Lt)),
        ("glm_c", Bpt, Connect::Path),
        ("glm_c", Bpt, d(Bpt)),
        ("glm_c", Ppm, d(Ppm)),
        ("glm_c", Bpm, d(Bpm)),
        ("glm_c", Vcm, d(Vcm)),
        ("gbs_s", Lt, d(Lt)),
        ("gbs_s", Bpt, d(Bpt)),
        ("gbs_s", Vcm, d(Vcm)),
        ("gbs_b", Pt, d(Pt)),
        ("gbs_b", Vcm, d(Vcm)),
    ]
}
