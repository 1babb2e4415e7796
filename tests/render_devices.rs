//! One render on several devices (`render --devices`, src/render/devices.rs).
//!
//! * Two devices of one implementation (lavapipe opened twice) give the bits of one
//!   device's render: the films' fixed-point sums add exactly whichever device took which
//!   block (bpm, gbs_b, 16x16, 24 iterations in blocks of 2).
//! * lavapipe and SwiftShader together (both ICDs in `VK_DRIVER_FILES`: scripts/
//!   test-swiftshader.sh) render the same estimator as lavapipe alone: vcm on gbs_b,
//!   16x16, 256 independent iterations, a per-pixel Welch test against lavapipe alone at
//!   another seed, Šidák-corrected so that a run fails by chance with probability ALPHA =
//!   1e-3 (as tests/second_device.rs: the implementations round differently, so only the
//!   distributions agree). Both devices must have taken blocks. Skipped where either is
//!   missing.
//!
//! Sabotage check (by hand, not kept): a `Renderer::start_at` that ignores the block's
//! first index fails the first test (the devices render the same iterations).

mod common;

use common::{render_stats, skip, with_gpu};
use vkvcm::gpu::GpuOptions;
use vkvcm::render::devices::render_on_devices;
use vkvcm::render::{self, Algorithm, Budget, RenderSettings, Sampler};
use vkvcm_tools::stats::welch_test;

const ALPHA: f64 = 1e-3;

#[test]
fn identical_devices_give_one_devices_bits() {
    let scene = vkvcm::scene::load_named("gbs_b").unwrap();
    let s = RenderSettings::new(Algorithm::Bpm, 16, 16, Budget::Iterations(24));
    let one = with_gpu(|gpu| render::render(gpu, &scene, &s, None, &mut |_| {}).unwrap());
    let opts = GpuOptions::for_tests();
    let (two, shares) = render_on_devices(&[opts.clone(), opts], &scene, &s, None).unwrap();
    assert_eq!(shares.iter().map(|d| d.iterations).sum::<u64>(), 24, "{shares:?}");
    assert!(two.sums == one.sums, "two devices' film differs from one device's ({shares:?})");
    let bits = |p: &[[f32; 3]]| p.iter().flatten().map(|v| v.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&two.pixels), bits(&one.pixels));
}

#[test]
fn lavapipe_and_swiftshader_render_the_same_estimator() {
    let test = "lavapipe_and_swiftshader_render_the_same_estimator";
    let names: Vec<String> = vkvcm::gpu::list_devices().unwrap_or_default().into_iter().map(|d| d.name).collect();
    let present = |n: &str| names.iter().any(|d| d.to_lowercase().contains(n));
    if !present("llvmpipe") || !present("swiftshader") {
        skip(test, &format!("needs lavapipe and SwiftShader in VK_DRIVER_FILES (devices: {names:?})"));
        return;
    }
    let scene = vkvcm::scene::load_named("gbs_b").unwrap();
    let mut s = RenderSettings::new(Algorithm::Vcm, 16, 16, Budget::Iterations(256));
    // Independent iterations, which the Welch test assumes (Sobol's are stratified).
    s.sampler = Some(Sampler::Independent);
    let on = |name: &str| GpuOptions { device: Some(name.to_string()), ..GpuOptions::for_tests() };
    let (both, shares) = render_on_devices(&[on("llvmpipe"), on("SwiftShader")], &scene, &s, None).unwrap();
    eprintln!("{shares:?}");
    assert!(shares.iter().all(|d| d.blocks > 0), "a device took no block: {shares:?}");
    s.frame.seed += 1;
    let alone =
        common::with_gpu_options(&on("llvmpipe"), |gpu| render::render(gpu, &scene, &s, None, &mut |_| {})).unwrap();
    let (a, b) = (render_stats(&alone, None), render_stats(&both, None));
    assert!(common::image_mean(&a) > 0.0, "black image");
    welch_test(&a, &b, ALPHA).unwrap().assert_passed("vcm gbs_b, lavapipe alone against lavapipe + SwiftShader");
}
