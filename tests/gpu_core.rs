//! Foundation tests on lavapipe (or VKVCM_TEST_DEVICE): kernel round trip, atomics,
//! timestamps, includes/defines, compile errors, device listing. Validation is on.

mod common;

use common::{with_gpu, with_gpu_options};
use rand::{Rng, SeedableRng};
use vkvcm::gpu::{self, groups_for, shader, Bind, GpuOptions, Profile};

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
            let k = gpu.kernel("tests/roundtrip.comp", &[("SCALE", &s)], &roundtrip(&ba, &bb, &out)).unwrap();
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
        let k = gpu.kernel("tests/roundtrip.comp", &[("SCALE", "2")], &roundtrip(&ba, &ba, &out)).unwrap();
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
        // The kernel sums with 64-bit atomics.
        if !common::device_has(gpu, vkvcm::gpu::SHADER_INT64_ATOMICS, "atomics_count_exactly") {
            return;
        }
        let mut rng = rand_pcg::Pcg32::seed_from_u64(11);
        let n = 50_000u32;
        let bins = 37u32;
        let keys: Vec<u32> = (0..n).map(|_| rng.random_range(0..1_000_000)).collect();
        let bk = gpu.buffer_from_slice("keys", &keys).unwrap();
        let hist = gpu.buffer_zeroed::<u32>("hist", bins as usize).unwrap();
        let sum = gpu.buffer_zeroed::<u64>("sum", 1).unwrap();
        let k = gpu
            .kernel(
                "tests/atomics.comp",
                &[],
                &[Bind::u32("Keys", &bk), Bind::u32("Hist", &hist), Bind::u32("Sum", &sum)],
            )
            .unwrap();
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
        let k = gpu.kernel("tests/roundtrip.comp", &[("SCALE", "2")], &roundtrip(&a, &a, &out)).unwrap();
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
    // No disk cache (`make test` gives the suite one), which could hold the variants.
    let opts = GpuOptions { kernel_cache: None, ..GpuOptions::for_tests() };
    with_gpu_options(&opts, |gpu| {
        let a = gpu.buffer_zeroed::<f32>("a", 64).unwrap();
        let before = shader::compile_count();
        let _k1 = gpu.kernel("tests/roundtrip.comp", &[("SCALE", "5")], &roundtrip(&a, &a, &a)).unwrap();
        let _k2 = gpu.kernel("tests/roundtrip.comp", &[("SCALE", "5")], &roundtrip(&a, &a, &a)).unwrap();
        let after_same = shader::compile_count();
        let _k3 = gpu.kernel("tests/roundtrip.comp", &[("SCALE", "6")], &roundtrip(&a, &a, &a)).unwrap();
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
    let opts = vkvcm::gpu::GpuOptions {
        device: Some("no-such-gpu-xyz".into()),
        validation: false,
        kernel_cache: None,
        device_addresses: true,
    };
    let err = vkvcm::gpu::Gpu::new(&opts).err().expect("must fail");
    assert!(format!("{err}").contains("no-such-gpu-xyz"), "{err}");
    let opts = vkvcm::gpu::GpuOptions {
        device: Some("99".into()),
        validation: false,
        kernel_cache: None,
        device_addresses: true,
    };
    let err = vkvcm::gpu::Gpu::new(&opts).err().expect("must fail");
    assert!(format!("{err}").contains("99"), "{err}");
}

#[test]
fn validation_layer_reports_misuse() {
    // A dispatch of more workgroups than maxComputeWorkGroupCount allows, recorded but
    // never submitted: the validation layer must report it. This proves that `with_gpu`
    // would fail on a real message.
    let gpu = vkvcm::gpu::Gpu::new(&vkvcm::gpu::GpuOptions::for_tests()).unwrap();
    let messages = gpu.validation_messages();
    let a = gpu.buffer_zeroed::<f32>("a", 64).unwrap();
    let k = gpu.kernel("tests/roundtrip.comp", &[("SCALE", "1")], &roundtrip(&a, &a, &a)).unwrap();
    let mut batch = gpu.batch().unwrap();
    batch.dispatch(&k, [u32::MAX, 1, 1], bytemuck::bytes_of(&0u32)).unwrap();
    drop(batch);
    drop(k);
    drop(a);
    drop(gpu);
    assert!(!messages.list().is_empty(), "the validation layer reported nothing");
}

/// tests/roundtrip.comp's bindings A, B (inputs) and O (output).
fn roundtrip<'a>(a: &'a gpu::Buffer, b: &'a gpu::Buffer, o: &'a gpu::Buffer) -> [Bind<'a>; 3] {
    [Bind::vec4("A", a), Bind::vec4("B", b), Bind::vec4("O", o)]
}

/// Buffers are bound by the names the compiled kernel declares, in any order; a buffer
/// the kernel does not declare is ignored, a declared binding without a buffer is refused
/// with its name, and the workgroup size is read from the SPIR-V.
#[test]
fn kernels_bind_buffers_by_reflected_name() {
    with_gpu(|gpu| {
        let n = 100usize;
        let a = gpu.buffer_from_slice("a", &vec![1.5f32; n]).unwrap();
        let b = gpu.buffer_from_slice("b", &vec![0.25f32; n]).unwrap();
        let out = gpu.buffer_zeroed::<f32>("out", n).unwrap();
        let spare = gpu.buffer_zeroed::<f32>("spare", 4).unwrap();
        let binds = [Bind::vec4("O", &out), Bind::vec4("unused", &spare), Bind::vec4("B", &b), Bind::vec4("A", &a)];
        let k = gpu.kernel("tests/roundtrip.comp", &[("SCALE", "2")], &binds).unwrap();
        assert_eq!(k.local_size(), [64, 1, 1]);
        let mut batch = gpu.batch().unwrap();
        batch.dispatch(&k, k.groups_for(n as u32), bytemuck::bytes_of(&(n as u32))).unwrap();
        batch.submit_wait(None).unwrap();
        assert!(out.read::<f32>().unwrap().iter().all(|&x| x == 3.25));
        let e = gpu.kernel("tests/roundtrip.comp", &[("SCALE", "2")], &[Bind::vec4("A", &a), Bind::vec4("B", &b)]);
        let e = format!("{:#}", e.err().expect("binding O has no buffer"));
        assert!(e.contains("\"O\"") && e.contains("tests/roundtrip.comp"), "{e}");
    });
}

/// Reflection names a storage buffer by its block and a texel buffer by its variable,
/// with the descriptor kind each declares, and bindings the compiler assigned.
#[test]
fn reflection_reads_names_kinds_and_workgroup_size() {
    let src = "#version 460\n#extension GL_EXT_samplerless_texture_functions : require\n\
               layout(local_size_x = 32, local_size_y = 2) in;\n\
               layout(std430) buffer results { uint r[]; };\n\
               uniform utextureBuffer texels;\n\
               void main() { r[gl_LocalInvocationIndex] = texelFetch(texels, 0).x; }\n";
    let spirv = shader::compile_glsl("reflect.comp", src, &[]).unwrap();
    let i = gpu::reflect::reflect("reflect.comp", &spirv).unwrap();
    assert_eq!(i.local_size, [32, 2, 1]);
    let mut names: Vec<(String, ash::vk::DescriptorType)> =
        i.bindings.iter().map(|b| (b.name.clone(), b.descriptor_type)).collect();
    names.sort_by(|x, y| x.0.cmp(&y.0));
    assert_eq!(
        names,
        [
            ("results".to_string(), ash::vk::DescriptorType::STORAGE_BUFFER),
            ("texels".to_string(), ash::vk::DescriptorType::UNIFORM_TEXEL_BUFFER)
        ]
    );
    let mut numbers: Vec<u32> = i.bindings.iter().map(|b| b.binding).collect();
    numbers.sort();
    assert_eq!(numbers, [0, 1]);
    // What the driver gets has no debug instructions left: not even the names.
    let stripped = shader::strip_debug_info(&spirv);
    assert!(stripped.len() < spirv.len());
    assert!(gpu::reflect::reflect("reflect.comp", &stripped).is_err());
}
