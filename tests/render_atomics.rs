//! Splats summed with 32-bit atomics (`--atomics 32`, src/render/atomics.rs) give the
//! image of 64-bit atomics bit for bit, and a device without 64-bit integers (simulated on
//! lavapipe by `VKVCM_TEST_WITHOUT_INT64`, src/gpu/fault_injection.rs) renders that image
//! with no validation message (docs/devices.md). Exact comparisons: the design makes both
//! paths compute the same 64-bit sums and the same roundings, so there is no tolerance.

mod common;

use std::process::Command;

use common::{device_has, invariance_cases, run_test_kernel, with_gpu};
use vkvcm::gpu::{SHADER_INT64, SHADER_INT64_ATOMICS};
use vkvcm::render::atomics::SplatAtomics;
use vkvcm::render::{self, Algorithm, Budget, Connect, RenderOutput, RenderSettings};
use vkvcm::scene::{Light, Scene};

fn render_with(
    gpu: &std::sync::Arc<vkvcm::gpu::Gpu>,
    scene: &Scene,
    s: &RenderSettings,
    a: SplatAtomics,
) -> RenderOutput {
    let s = RenderSettings { atomics: Some(a), ..s.clone() };
    let out = render::render(gpu, scene, &s, None, &mut |_| {}).unwrap();
    assert_eq!(out.atomics, a);
    out
}

fn assert_same(what: &str, a: &RenderOutput, b: &RenderOutput) {
    assert!(a.sum == b.sum, "{what}: the per-pixel sums differ");
    assert!(a.sum_sq == b.sum_sq, "{what}: the per-pixel sums of squares differ");
    assert_eq!(a.rejected_samples, b.rejected_samples, "{what}: rejected samples");
    assert_eq!(a.overflow_splats, b.overflow_splats, "{what}: overflowing splats");
}

/// Every estimator (the light-subpath ones splat; pt and el do not, and must not care).
#[test]
fn images_do_not_depend_on_the_atomics() {
    let mut cases = invariance_cases();
    cases.push(("glm_c", Algorithm::El, Connect::Path));
    cases.push(("gbs_p", Algorithm::Vcm, Connect::Cache(2)));
    with_gpu(|gpu| {
        if !device_has(gpu, SHADER_INT64_ATOMICS, "images_do_not_depend_on_the_atomics") {
            return;
        }
        for (name, algo, connect) in cases {
            let scene = vkvcm::scene::load_named(name).unwrap();
            let mut s = RenderSettings::new(algo, 23, 17, Budget::Iterations(2));
            s.connect = connect;
            let a = render_with(gpu, &scene, &s, SplatAtomics::Bits64);
            let b = render_with(gpu, &scene, &s, SplatAtomics::Bits32);
            let what = format!("{name} {algo:?} {connect:?}, 32-bit against 64-bit atomics");
            assert!(a.sum.iter().any(|p| p.iter().any(|&c| c > 0.0)), "{what}: black image");
            assert_same(&what, &a, &b);
            // Deterministic from run to run.
            let c = render_with(gpu, &scene, &s, SplatAtomics::Bits32);
            assert_same(&format!("{name} {algo:?}, 32-bit atomics run twice"), &b, &c);
        }
    });
}

/// A light so bright that splats pass SPLAT_MAX: they are rejected and counted, the same
/// ones on both paths, and nothing wraps. The same scene at 1/10^6 of the power splats
/// without rejections.
#[test]
fn overflowing_splats_are_rejected_alike() {
    let mut scene = vkvcm::scene::load_named("glm_c").unwrap();
    let scale = |scene: &mut Scene, k: f32| {
        for l in &mut scene.lights {
            if let Light::Area { radiance, .. } = l {
                *radiance *= k;
            }
        }
    };
    with_gpu(|gpu| {
        // Without 64-bit atomics the 32-bit path's rejections are still checked.
        let has64 = device_has(gpu, SHADER_INT64_ATOMICS, "overflowing_splats_are_rejected_alike (against 64-bit)");
        for algo in [Algorithm::Lt, Algorithm::Vcm] {
            let s = RenderSettings::new(algo, 16, 16, Budget::Iterations(2));
            scale(&mut scene, 1e12);
            let b = render_with(gpu, &scene, &s, SplatAtomics::Bits32);
            assert!(b.overflow_splats > 0, "{algo:?}: no splat overflowed at 1e12 x the power");
            if has64 {
                let a = render_with(gpu, &scene, &s, SplatAtomics::Bits64);
                assert_same(&format!("{algo:?} at 1e12 x the power"), &a, &b);
            }
            scale(&mut scene, 1e-12);
            let c = render_with(gpu, &scene, &s, SplatAtomics::Bits32);
            assert_eq!(c.overflow_splats, 0, "{algo:?} at the scene's power");
        }
    });
}

/// u64_words_to_float (glsl/common.glsl), which takes the 32-bit splat sums, rounds every
/// 64-bit value as the 64-bit conversion does: all bit lengths, the ties between two
/// floats (both parities), one above and one below them, and random values.
#[test]
fn word_pairs_round_like_the_64_bit_conversion() {
    let mut values: Vec<u64> = vec![0, 1, u32::MAX as u64, 1 << 32, u64::MAX];
    for bits in 24..64u32 {
        let top = 1u64 << bits;
        let ulp = 1u64 << (bits - 23);
        for m in [top, top + ulp, top + 2 * ulp, (top << 1).wrapping_sub(ulp)] {
            let m = m & !(ulp - 1);
            for d in [0, ulp / 2, ulp / 2 - 1, ulp / 2 + 1, ulp - 1] {
                values.push(m.wrapping_add(d));
            }
        }
    }
    let mut x: u64 = 0x9e37_79b9_7f4a_7c15;
    for _ in 0..20_000 {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        values.push(x >> (x % 40));
    }
    with_gpu(|gpu| {
        // The reference is the GPU's own 64-bit conversion.
        if !device_has(gpu, SHADER_INT64, "word_pairs_round_like_the_64_bit_conversion") {
            return;
        }
        let words: Vec<[u32; 2]> = values.iter().map(|&v| [v as u32, (v >> 32) as u32]).collect();
        let got: Vec<[u32; 2]> = run_test_kernel(gpu, "tests/u64_to_float.comp", &words);
        for (v, [want, words]) in values.iter().zip(got) {
            assert_eq!(want, words, "{v:#x}: 64-bit conversion {want:#x}, from the words {words:#x}");
            // Independent of the GPU: Rust's u64 -> f32 conversion rounds to nearest even too.
            assert_eq!(want, (*v as f32).to_bits(), "{v:#x}: the GPU's 64-bit conversion");
        }
    });
}

fn vkvcm(args: &[&str], without_int64: bool) -> std::process::Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_vkvcm"));
    c.args(args).env("VKVCM_VALIDATION", "1").env_remove("VKVCM_TEST_FAIL_AFTER_BATCHES");
    c.env("VKVCM_CACHE_DIR", common::cli_cache_dir("")); // the suite's kernel cache or none
    if without_int64 {
        c.env("VKVCM_TEST_WITHOUT_INT64", "1");
    } else {
        c.env_remove("VKVCM_TEST_WITHOUT_INT64");
    }
    c.output().unwrap()
}

/// On a device without shaderInt64 and 64-bit atomics (simulated: the features are then
/// not enabled, so the validation layer would report any kernel using 64-bit integers),
/// `vkvcm devices` says which fallbacks apply and every estimator renders the image of a
/// device with them.
#[test]
#[cfg_attr(not(feature = "fault-injection"), ignore = "needs --features fault-injection")]
fn a_device_without_64_bit_integers_renders_the_same_images() {
    let dir = tempfile::tempdir().unwrap();
    let out = vkvcm(&["devices"], true);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    assert!(text.contains("NO  shaderInt64") && text.contains("NO  shaderBufferInt64Atomics"), "{text}");
    assert!(text.contains("usable by vkvcm"), "{text}");
    for algo in ["pt", "lt", "bpt", "vcm"] {
        let path = |tag: &str| dir.path().join(format!("{algo}_{tag}.exr")).to_string_lossy().into_owned();
        for (tag, without) in [("int64", false), ("int32", true)] {
            let o = path(tag);
            let args = ["render", "gbs_s", "--algo", algo, "--width", "20", "--height", "12", "-i", "2", "-o", &o];
            let out = vkvcm(&args, without);
            assert!(out.status.success(), "{algo} {tag}: {}", String::from_utf8_lossy(&out.stderr));
            assert!(!String::from_utf8_lossy(&out.stderr).contains("validation"), "{algo} {tag}");
        }
        let diff = vkvcm(&["diff", "--exact", &path("int64"), &path("int32")], false);
        assert!(diff.status.success(), "{algo}: {}", String::from_utf8_lossy(&diff.stderr));
    }
    // 64-bit atomics asked for where there are none: refused, naming the way out.
    let o = dir.path().join("x.exr").to_string_lossy().into_owned();
    let out =
        vkvcm(&["render", "gbs_s", "--algo", "lt", "--width", "8", "--height", "8", "--atomics", "64", "-o", &o], true);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("--atomics 32"), "{err}");
}
