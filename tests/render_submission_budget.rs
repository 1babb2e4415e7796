//! The submission budget (src/gpu/batch.rs, docs/robustness.md "Watchdog resets"): with a
//! budget far below one pass's time, the passes over paths are split into pieces across
//! many queue submissions, and the image must not change: every path keeps its index,
//! random sequence and outputs, the film has one writer per pixel and the splats are
//! exact integer sums. pt on gbs_b (paths that escape to the background), vcm on glm_c
//! (area light; light chunks, store, grid and camera pass) and lt on gbs_s (splats only)
//! render 24x16 pixels for 2 iterations without a budget and with 0.05 ms; the per-pixel
//! sums and sums of squares must be bit-identical, and the budgeted render must have
//! made more submissions and more dispatches of the split kernels than iterations.
//! Lavapipe, validation on.
//!
//! Sabotage (done by hand, not kept): pt.comp and camera_subpath.comp starting each piece
//! at pixel 0 instead of `first_path` fails the image comparison (gbs_b pt).

mod common;

use common::with_gpu;
use vkvcm::render::{Algorithm, Budget, RenderOutput, RenderSettings, Renderer};

/// Renders `name` with `algo` and the budget `ms`; the output and the queue submissions.
fn render(gpu: &std::sync::Arc<vkvcm::gpu::Gpu>, name: &str, algo: Algorithm, ms: f64) -> (RenderOutput, u64) {
    let scene = vkvcm::scene::load_named(name).unwrap();
    let mut s = RenderSettings::new(algo, 24, 16, Budget::Iterations(2));
    s.submission_budget_ms = Some(ms);
    let mut r = Renderer::new(gpu, &scene, &s).unwrap();
    assert_eq!(r.has_submission_budget(), ms > 0.0, "lavapipe has timestamp queries: the budget applies");
    r.run(s.budget, None, &mut |_| {}).unwrap();
    (r.output().unwrap(), r.submissions())
}

/// Dispatches of `kernel` (a kernel file name) in the profile.
fn calls(out: &RenderOutput, kernel: &str) -> u64 {
    out.profile.kernels.iter().filter(|k| k.kernel.starts_with(kernel)).map(|k| k.calls).sum()
}

#[test]
fn a_budget_splits_submissions_and_keeps_the_image() {
    with_gpu(|gpu| {
        let cases = [
            ("gbs_b", Algorithm::Pt, "pt.comp"),
            ("glm_c", Algorithm::Vcm, "camera_subpath.comp"),
            ("gbs_s", Algorithm::Lt, "light_subpath.comp"),
        ];
        for (name, algo, split_kernel) in cases {
            let what = format!("{name} {algo:?}");
            let (whole, whole_submissions) = render(gpu, name, algo, 0.0);
            let (split, split_submissions) = render(gpu, name, algo, 0.05);
            assert!(whole.sum.iter().any(|p| p.iter().any(|&c| c > 0.0)), "{what}: black image");
            assert!(whole.sum == split.sum, "{what}: the per-pixel sums differ with a budget");
            assert!(whole.sum_sq == split.sum_sq, "{what}: the per-pixel sums of squares differ with a budget");
            assert!(
                split_submissions > 2 * whole_submissions,
                "{what}: {split_submissions} submissions with a 0.05 ms budget, {whole_submissions} without"
            );
            let (n, w) = (calls(&split, split_kernel), calls(&whole, split_kernel));
            assert!(
                n > w && n > split.iterations,
                "{what}: {split_kernel} dispatched {n} times with a budget, {w} without"
            );
        }
    });
}
