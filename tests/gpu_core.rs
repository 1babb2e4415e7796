//! Foundation tests on lavapipe (or VKVCM_TEST_DEVICE): kernel round trip, atomics,
//! timestamps, includes/defines, compile errors, device listing. Validation is on.

mod common;

use common::with_gpu;
use rand::{Rng, SeedableRng};
use vkvcm::gpu::{self, groups_for, shader, Profile};

#[test]
fn roundtrip_matches_cpu_on_random_data() {
    with_gpu(|gpu| {
        let mut rng = rand_pcg::Pcg32::seed_from_u64(7);
        let n = 100_003usize; // not a multiple of the workgroup size
        let a: Vec<f32> = (0..n).map(|_| rng.random_range(-1e3..1e3)).collect();
        let b: Vec<f32> = (0..n).map(|_| rng.random_range(-1e3..1e3)).collect();
        let ba = gpu.buffer_from_slice("a", &a).unwrap();
        let bb = gpu.buffer_from_slice("b", &b).unwrap();
        let out = gpu.buffer_zeroed::<f32>("out", n + 5).unwrap();
        for scale in [3, -2] {
            let s = scale.to_string();
            let k = gpu.kernel("tests/roundtrip.comp", &[("SCALE", &s)], &[&ba, &bb, &out]).unwrap();
            let mut batch = gpu.batch().unwrap();
            batch.dispatch(&k, [groups_for(n as u32, 64), 1, 1], bytemuck::bytes_of(&(n as u32))).unwrap();
            batch.submit_wait(None).unwrap();
            let o: Vec<f32> = out.read().unwrap();
            for i in 0..n {
                let want = a[i] * scale as f32 + b[i];
                assert_eq!(o[i], want, "element {i} with SCALE={scale}");
            }
            // Elements past n are never written.
            assert!(o[n..].iter().all(|&x| x == 0.0));
        }
    });
}

/// More invocations than 65,535 workgroups of 64 hold: the dispatch is folded into 2-D
/// (gpu::groups_2d) and every element is still computed exactly once.
#[test]
fn dispatch_beyond_the_workgroup_count_limit() {
    with_gpu(|gpu| {
        let n = 64 * 65_535 + 1_000usize;
        let a: Vec<f32> = (0..n).map(|i| (i % 1000) as f32).collect();
        let ba = gpu.buffer_from_slice("a", &a).unwrap();
        let out = gpu.buffer_zeroed::<f32>("out", n).unwrap();
        let k = gpu.kernel("tests/roundtrip.comp", &[("SCALE", "2")], &[&ba, &ba, &out]).unwrap();
        let mut batch = gpu.batch().unwrap();
        let groups = vkvcm::gpu::groups_2d(n as u32, 64);
        assert!(groups[1] > 1, "the test must need a 2-D dispatch");
        batch.dispatch(&k, groups, bytemuck::bytes_of(&(n as u32))).unwrap();
        batch.submit_wait(None).unwrap();
        let o: Vec<f32> = out.read().unwrap();
        assert!(o.iter().zip(&a).all(|(o, a)| *o == 3.0 * a));
    });
}

#[test]
fn atomics_count_exactly() {
    with_gpu(|gpu| {
        let mut rng = rand_pcg::Pcg32::seed_from_u64(11);
        let n = 50_000u32;
        let bins = 37u32;
        let keys: Vec<u32> = (0..n).map(|_| rng.random_range(0..1_000_000)).collect();
        let bk = gpu.buffer_from_slice("keys", &keys).unwrap();
        let hist = gpu.buffer_zeroed::<u32>("hist", bins as usize).unwrap();
        let sum = gpu.buffer_zeroed::<u64>("sum", 1).unwrap();
        let k = gpu.kernel("tests/atomics.comp", &[], &[&bk, &hist, &sum]).unwrap();
        let mut batch = gpu.batch().unwrap();
        batch.dispatch(&k, [groups_for(n, 64), 1, 1], bytemuck::cast_slice(&[n, bins])).unwrap();
        batch.submit_wait(None).unwrap();
        let mut want = vec![0u32; bins as usize];
        let mut want_sum = 0u64;
        for &x in &keys {
            want[(x % bins) as usize] += 1;
            want_sum += (x as u64) << 20;
        }
        assert_eq!(hist.read::<u32>().unwrap(), want);
        assert_eq!(sum.read::<u64>().unwrap()[0], want_sum);
    });
}

#[test]
fn timestamps_are_monotonic_and_profiled() {
    with_gpu(|gpu| {
        let n = 1 << 16;
        let a = gpu.buffer_from_slice("a", &vec![1.0f32; n]).unwrap();
        let out = gpu.buffer_zeroed::<f32>("out", n).unwrap();
        let k = gpu.kernel("tests/roundtrip.comp", &[("SCALE", "2")], &[&a, &a, &out]).unwrap();
        let mut batch = gpu.batch().unwrap();
        let mut profile = Profile::default();
        for _ in 0..5 {
            batch.dispatch(&k, [groups_for(n as u32, 64), 1, 1], bytemuck::bytes_of(&(n as u32))).unwrap();
        }
        batch.submit_wait(Some(&mut profile)).unwrap();
        let ts = batch.last_timestamps().unwrap();
        assert_eq!(ts.len(), 10);
        assert!(ts.windows(2).all(|w| w[0] <= w[1]), "timestamps not monotonic: {ts:?}");
        assert_eq!(profile.kernels.len(), 1);
        assert_eq!(profile.kernels[0].calls, 5);
        assert!(profile.kernels[0].total_ms > 0.0);
        let table = profile.table();
        assert!(table.contains("tests/roundtrip.comp") && table.contains("share"), "{table}");
    });
}

#[test]
fn kernels_are_compiled_once_per_variant() {
    with_gpu(|gpu| {
        let a = gpu.buffer_zeroed::<f32>("a", 64).unwrap();
        let before = shader::compile_count();
        let _k1 = gpu.kernel("tests/roundtrip.comp", &[("SCALE", "5")], &[&a, &a, &a]).unwrap();
        let _k2 = gpu.kernel("tests/roundtrip.comp", &[("SCALE", "5")], &[&a, &a, &a]).unwrap();
        let after_same = shader::compile_count();
        let _k3 = gpu.kernel("tests/roundtrip.comp", &[("SCALE", "6")], &[&a, &a, &a]).unwrap();
        // Other tests may compile concurrently, so count at least, and compare deltas.
        assert!(after_same - before >= 1);
        assert!(shader::compile_count() > after_same);
    });
}

#[test]
fn compile_error_names_file_and_line() {
    let src = "#version 460\nlayout(local_size_x = 1) in;\nvoid main() {\n  float x = undefined_thing;\n}\n";
    let err = shader::compile_glsl("broken.comp", src, &[]).unwrap_err();
    let msg = format!("{err:#}");
    assert!(msg.contains("broken.comp:4"), "no file:line in {msg}");
    assert!(msg.contains("undefined_thing"), "no glslang message in {msg}");
    let err = shader::compile_glsl(
        "inc.comp",
        "#version 460\n#extension GL_GOOGLE_include_directive : require\n#include \"nope.glsl\"\nvoid main(){}\n",
        &[],
    )
    .unwrap_err();
    assert!(format!("{err:#}").contains("nope.glsl"), "{err:#}");
}

#[test]
fn define_changes_the_program() {
    let src = shader::source("tests/roundtrip.comp").unwrap();
    let a = shader::compile_glsl("tests/roundtrip.comp", &src, &[("SCALE", "2")]).unwrap();
    let b = shader::compile_glsl("tests/roundtrip.comp", &src, &[("SCALE", "3")]).unwrap();
    assert_ne!(a, b);
    // Without the define the kernel does not compile: the define really reaches it.
    assert!(shader::compile_glsl("tests/roundtrip.comp", &src, &[]).is_err());
}

#[test]
fn device_listing_names_features() {
    let devices = gpu::list_devices().unwrap();
    assert!(!devices.is_empty());
    for d in &devices {
        assert!(!d.name.is_empty());
        assert!(d.features.iter().any(|f| f.name == "shaderBufferInt64Atomics"));
    }
}

#[test]
fn unknown_device_is_a_clear_error() {
    let opts = vkvcm::gpu::GpuOptions { device: Some("no-such-gpu-xyz".into()), validation: false };
    let err = vkvcm::gpu::Gpu::new(&opts).err().expect("must fail");
    assert!(format!("{err}").contains("no-such-gpu-xyz"), "{err}");
    let opts = vkvcm::gpu::GpuOptions { device: Some("99".into()), validation: false };
    let err = vkvcm::gpu::Gpu::new(&opts).err().expect("must fail");
    assert!(format!("{err}").contains("99"), "{err}");
}

#[test]
fn validation_layer_reports_misuse() {
    // A kernel that declares three bindings, built with none: the pipeline layout does
    // not match the shader, which the validation layer must report. This proves that
    // `with_gpu` would fail on a real message.
    let gpu = vkvcm::gpu::Gpu::new(&vkvcm::gpu::GpuOptions::for_tests()).unwrap();
    let messages = gpu.validation_messages();
    let k = gpu.kernel("tests/roundtrip.comp", &[("SCALE", "1")], &[]);
    drop(k);
    drop(gpu);
    assert!(!messages.list().is_empty(), "the validation layer reported nothing");
}
