//! No kernel needing a feature the device lacks is ever created (src/gpu/reflect.rs,
//! `KernelInterface::check_features`): a device without 64-bit integers (SwiftShader has
//! none and aborts with SIGILL on such a kernel; simulated here on lavapipe by
//! `VKVCM_TEST_WITHOUT_INT64`, src/gpu/fault_injection.rs, which every test of this file
//! sets alike before the first device is opened) refuses the test kernels that use them
//! with an error naming the feature, and the renderer refuses `--atomics 64`; no shader
//! module is created, which the validation layer (any message fails the test) would
//! otherwise report, since the features are then not enabled.
//!
//! Sabotage check (done by hand, not kept): without the `check_features` call in
//! `ShaderCache::module` the first test fails.

mod common;

use std::sync::Arc;

use vkvcm::gpu::{Bind, Gpu, SHADER_INT64, SHADER_INT64_ATOMICS};
use vkvcm::render::atomics::SplatAtomics;
use vkvcm::render::{Algorithm, Budget, RenderSettings, Renderer};

fn with_gpu_without_int64<R>(f: impl FnOnce(&Arc<Gpu>) -> R) -> Option<R> {
    if !cfg!(feature = "fault-injection") {
        common::skip("device_features", "needs --features fault-injection");
        return None;
    }
    std::env::set_var("VKVCM_TEST_WITHOUT_INT64", "1");
    Some(common::with_gpu(|gpu| {
        assert!(!gpu.has(SHADER_INT64) && !gpu.has(SHADER_INT64_ATOMICS), "the simulated lack did not apply");
        f(gpu)
    }))
}

#[test]
fn kernels_needing_64_bit_integers_are_refused_before_they_are_created() {
    with_gpu_without_int64(|gpu| {
        let input = gpu.buffer_zeroed::<[u32; 2]>("test_input", 4).unwrap();
        let output = gpu.buffer_zeroed::<[u32; 2]>("test_output", 4).unwrap();
        let Err(e) = gpu.kernel("tests/u64_to_float.comp", &[], &[Bind::own(&input), Bind::own(&output)]) else {
            panic!("a kernel with 64-bit integers was built on a device without them")
        };
        let e = format!("{e:#}");
        assert!(e.contains("u64_to_float.comp") && e.contains(SHADER_INT64), "{e}");
        let keys = gpu.buffer_zeroed::<u32>("keys", 4).unwrap();
        let binds = [Bind::u32("Keys", &keys), Bind::u32("Hist", &keys), Bind::u32("Sum", &output)];
        let Err(e) = gpu.kernel("tests/atomics.comp", &[], &binds) else {
            panic!("a kernel with 64-bit atomics was built")
        };
        let e = format!("{e:#}");
        assert!(e.contains("atomics.comp") && e.contains("shaderInt64"), "{e}");
    });
}

#[test]
fn the_renderer_refuses_64_bit_atomics_and_renders_with_32() {
    with_gpu_without_int64(|gpu| {
        let scene = vkvcm::scene::load_named("gbs_s").unwrap();
        let mut s = RenderSettings::new(Algorithm::Lt, 8, 8, Budget::Iterations(1));
        s.atomics = Some(SplatAtomics::Bits64);
        let Err(e) = Renderer::new(gpu, &scene, &s) else { panic!("--atomics 64 accepted without 64-bit atomics") };
        assert!(format!("{e:#}").contains("--atomics 32"), "{e:#}");
        s.atomics = None;
        let out = vkvcm::render::render(gpu, &scene, &s, None, &mut |_| {}).unwrap();
        assert_eq!(out.atomics, SplatAtomics::Bits32);
    });
}
