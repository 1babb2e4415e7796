//! The kernel cache on disk (docs/kernel-cache.md): a second `Gpu` or process with the
//! same folder compiles nothing and renders a bit-identical image; a changed define or
//! source misses; corrupt SPIR-V and pipeline-cache files are ignored and rewritten; an
//! unwritable folder costs one warning; `--no-kernel-cache` and `VKVCM_CACHE_DIR=` write
//! nothing; the default folder follows XDG_CACHE_HOME and HOME. Every test uses a
//! temporary folder of its own, with validation on.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use common::with_gpu_options;
use vkvcm::gpu::{groups_for, Bind, Gpu, GpuOptions, ShaderCounts};
use vkvcm::render::{self, Algorithm, Budget, RenderOutput, RenderSettings};

fn options(dir: &Path) -> GpuOptions {
    GpuOptions { kernel_cache: Some(dir.to_path_buf()), ..GpuOptions::for_tests() }
}

/// A tiny render of the reference scene glm_c with `algo`.
fn render(gpu: &std::sync::Arc<Gpu>, algo: Algorithm) -> RenderOutput {
    let scene = vkvcm::scene::load_named("glm_c").unwrap();
    let s = RenderSettings::new(algo, 16, 16, Budget::Iterations(2));
    render::render(gpu, &scene, &s, None, &mut |_| {}).unwrap()
}

/// Fails unless `a` and `b` are the same image, bit for bit.
fn assert_bit_identical(a: &RenderOutput, b: &RenderOutput) {
    let bits = |o: &RenderOutput| o.sum.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert!(bits(a) == bits(b), "the images differ");
    assert!(bits(a).iter().any(|&x| x != 0), "a black image proves nothing");
}

/// The files of `dir` whose names start with `prefix`, sorted.
fn files(dir: &Path, prefix: &str) -> Vec<PathBuf> {
    let mut out: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|entries| {
            entries
                .flatten()
                .filter(|e| e.file_name().to_string_lossy().starts_with(prefix))
                .map(|e| e.path())
                .collect()
        })
        .unwrap_or_default();
    out.sort();
    out
}

#[test]
fn a_second_gpu_with_the_same_folder_compiles_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let (first, cold, cold_pipelines) = with_gpu_options(&options(dir.path()), |gpu| {
        (render(gpu, Algorithm::Vcm), gpu.shader_counts(), gpu.pipeline_cache_loaded_bytes())
    });
    assert!(cold.compiled > 0 && cold.from_disk == 0, "{cold:?}");
    assert_eq!(cold_pipelines, 0, "an empty folder has no pipeline cache");
    assert_eq!(files(dir.path(), "spirv-").len(), cold.compiled, "one file per kernel variant");
    assert_eq!(files(dir.path(), "pipelines-").len(), 1, "one pipeline cache per device");

    let (second, warm, warm_pipelines) = with_gpu_options(&options(dir.path()), |gpu| {
        (render(gpu, Algorithm::Vcm), gpu.shader_counts(), gpu.pipeline_cache_loaded_bytes())
    });
    assert_eq!(warm, ShaderCounts { compiled: 0, from_disk: cold.compiled });
    assert!(warm_pipelines > 0, "the pipeline cache is read back");
    assert_bit_identical(&first, &second);
}

/// Runs tests/roundtrip.comp (`out = a * SCALE + b`) with `scale` and checks its output.
fn run_scale(gpu: &std::sync::Arc<Gpu>, scale: i32) {
    let n = 256usize;
    let a: Vec<f32> = (0..n).map(|i| i as f32).collect();
    let ba = gpu.buffer_from_slice("a", &a).unwrap();
    let bb = gpu.buffer_from_slice("b", &vec![0.5f32; n]).unwrap();
    let out = gpu.buffer_zeroed::<f32>("out", n).unwrap();
    let s = scale.to_string();
    let binds = [Bind::vec4("A", &ba), Bind::vec4("B", &bb), Bind::vec4("O", &out)];
    let k = gpu.kernel("tests/roundtrip.comp", &[("SCALE", &s)], &binds).unwrap();
    let mut batch = gpu.batch().unwrap();
    batch.dispatch(&k, [groups_for(n as u32, 64), 1, 1], bytemuck::bytes_of(&(n as u32))).unwrap();
    batch.submit_wait(None).unwrap();
    let o: Vec<f32> = out.read().unwrap();
    for (i, (o, a)) in o.iter().zip(&a).enumerate() {
        assert_eq!(*o, a * scale as f32 + 0.5, "element {i} with SCALE={scale}");
    }
}

#[test]
fn a_changed_define_misses_the_cache() {
    let dir = tempfile::tempdir().unwrap();
    with_gpu_options(&options(dir.path()), |gpu| {
        run_scale(gpu, 5);
        assert_eq!(gpu.shader_counts(), ShaderCounts { compiled: 1, from_disk: 0 });
    });
    with_gpu_options(&options(dir.path()), |gpu| {
        run_scale(gpu, 5);
        assert_eq!(gpu.shader_counts(), ShaderCounts { compiled: 0, from_disk: 1 });
        run_scale(gpu, 6);
        assert_eq!(gpu.shader_counts(), ShaderCounts { compiled: 1, from_disk: 1 }, "SCALE=6 is compiled");
    });
    assert_eq!(files(dir.path(), "spirv-").len(), 2);
}

/// Corrupts `bytes` in the way `how` (0..5) numbers.
fn corrupt(bytes: &mut Vec<u8>, how: usize) -> &'static str {
    let n = bytes.len();
    match how % 5 {
        0 => {
            bytes.truncate(n / 2);
            "truncated to half"
        }
        1 => {
            // The payload's middle byte: inside an instruction of a SPIR-V file, inside the
            // driver's header in lavapipe's pipeline cache (32 bytes, header only).
            let middle = 72 + (n - 72) / 2;
            bytes[middle] ^= 0x40;
            "a byte of the payload flipped"
        }
        2 => {
            bytes[12] ^= 0x01;
            "a byte of the key flipped"
        }
        3 => {
            bytes.clear();
            "empty"
        }
        _ => {
            *bytes = (0..n).map(|i| (i * 7919 % 251) as u8).collect();
            "garbage"
        }
    }
}

#[test]
fn corrupt_spirv_files_are_compiled_again() {
    let dir = tempfile::tempdir().unwrap();
    let (first, cold) =
        with_gpu_options(&options(dir.path()), |gpu| (render(gpu, Algorithm::Vcm), gpu.shader_counts()));
    let spirv = files(dir.path(), "spirv-");
    assert_eq!(spirv.len(), cold.compiled);
    for (i, path) in spirv.iter().enumerate() {
        let mut bytes = std::fs::read(path).unwrap();
        corrupt(&mut bytes, i);
        std::fs::write(path, bytes).unwrap();
    }
    let (second, counts) =
        with_gpu_options(&options(dir.path()), |gpu| (render(gpu, Algorithm::Vcm), gpu.shader_counts()));
    assert_eq!(counts, ShaderCounts { compiled: cold.compiled, from_disk: 0 }, "every corrupt file is a miss");
    assert_bit_identical(&first, &second);
    // The corrupt files were replaced.
    let third = with_gpu_options(&options(dir.path()), |gpu| {
        render(gpu, Algorithm::Vcm);
        gpu.shader_counts()
    });
    assert_eq!(third, ShaderCounts { compiled: 0, from_disk: cold.compiled });
}

/// The SHA-256 of `payload` where a kernel-cache entry stores it (after the 8-byte magic
/// and the 32-byte key): rewrites `entry`'s digest so that it matches its payload.
fn reseal(entry: &mut [u8]) {
    use sha2::Digest;
    let digest = sha2::Sha256::digest(&entry[72..]);
    entry[40..72].copy_from_slice(&digest);
}

#[test]
fn a_corrupt_pipeline_cache_is_ignored() {
    let dir = tempfile::tempdir().unwrap();
    let first = with_gpu_options(&options(dir.path()), |gpu| render(gpu, Algorithm::Pt));
    let [path] = files(dir.path(), "pipelines-").try_into().expect("one pipeline cache file");
    let intact = std::fs::read(&path).unwrap();
    let mut cases: Vec<(&str, Vec<u8>)> = (0..5)
        .map(|how| {
            let mut bytes = intact.clone();
            let what = corrupt(&mut bytes, how);
            (what, bytes)
        })
        .collect();
    // Intact as an entry, but the driver's header names another device (vendorID).
    let mut other_device = intact.clone();
    other_device[72 + 8] ^= 0x01;
    reseal(&mut other_device);
    cases.push(("another device's header", other_device));
    for (what, bytes) in cases {
        std::fs::write(&path, &bytes).unwrap();
        let (out, loaded) = with_gpu_options(&options(dir.path()), |gpu| {
            (render(gpu, Algorithm::Pt), gpu.pipeline_cache_loaded_bytes())
        });
        assert_eq!(loaded, 0, "{what}: not loaded");
        assert_bit_identical(&first, &out);
        assert_ne!(std::fs::read(&path).unwrap(), bytes, "{what}: the file is written again");
        let loaded = with_gpu_options(&options(dir.path()), |gpu| gpu.pipeline_cache_loaded_bytes());
        assert!(loaded > 0, "{what}: the rewritten file is loaded");
    }
}

/// `vkvcm render` of a tiny pt image to `dir/name.exr` with `--verbose` and the extra
/// arguments `args`; each of `env` sets a variable (`Some`, an empty path sets it empty) or
/// removes it (`None`). Fails unless it succeeds without a panic or validation message.
fn vkvcm_render(dir: &Path, name: &str, env: &[(&str, Option<&Path>)], args: &[&str]) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_vkvcm"));
    c.env("VKVCM_VALIDATION", "1").env_remove("VKVCM_TEST_FAIL_AFTER_BATCHES").env_remove("VKVCM_GLSL_DIR");
    if std::env::var_os("VK_DRIVER_FILES").is_none() {
        c.env("VK_DRIVER_FILES", "/usr/share/vulkan/icd.d/lvp_icd.json");
    }
    for (k, v) in env {
        match v {
            Some(v) => c.env(k, v),
            None => c.env_remove(k),
        };
    }
    c.args(["render", "-a", "pt", "--width", "16", "--height", "16", "-i", "1", "--verbose", "-o"])
        .arg(dir.join(format!("{name}.exr")))
        .args(args);
    let out = c.output().expect("run vkvcm");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "vkvcm failed:\n{err}");
    assert!(!err.contains("panicked") && !err.contains("validation"), "{err}");
    out
}

/// The number of kernels the --verbose line says were compiled.
fn compiled(out: &Output) -> usize {
    let err = String::from_utf8_lossy(&out.stderr);
    let line = err.lines().find(|l| l.starts_with("kernel cache")).unwrap_or_else(|| panic!("no cache line:\n{err}"));
    let (before, _) = line.split_once(" kernel(s) compiled").unwrap_or_else(|| panic!("{line}"));
    before.rsplit(' ').next().unwrap().parse().unwrap_or_else(|_| panic!("{line}"))
}

fn pixels(path: &Path) -> Vec<u32> {
    let (img, _) = vkvcm::image::read_exr(path).unwrap();
    img.data.iter().flatten().map(|x| x.to_bits()).collect()
}

#[test]
fn a_second_process_compiles_nothing_and_concurrent_ones_share_the_folder() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let env = [("VKVCM_CACHE_DIR", Some(cache.as_path()))];
    let cold = vkvcm_render(dir.path(), "cold", &env, &[]);
    assert!(compiled(&cold) > 0);
    let warm = vkvcm_render(dir.path(), "warm", &env, &[]);
    assert_eq!(compiled(&warm), 0, "{}", String::from_utf8_lossy(&warm.stderr));
    assert_eq!(pixels(&dir.path().join("cold.exr")), pixels(&dir.path().join("warm.exr")));
    // Processes writing the same (fresh) folder at once: each succeeds, and reads either
    // nothing or whole files.
    let shared = dir.path().join("shared");
    let runs: Vec<_> = (0..3)
        .map(|i| {
            let dir = dir.path().to_path_buf();
            let shared = shared.clone();
            std::thread::spawn(move || {
                vkvcm_render(&dir, &format!("concurrent{i}"), &[("VKVCM_CACHE_DIR", Some(shared.as_path()))], &[])
            })
        })
        .collect();
    for r in runs {
        r.join().unwrap();
    }
    let after = vkvcm_render(dir.path(), "after", &[("VKVCM_CACHE_DIR", Some(shared.as_path()))], &[]);
    assert_eq!(compiled(&after), 0);
    assert!(files(&shared, ".vkvcm-tmp").is_empty(), "no temporary file is left");
}

#[test]
fn a_changed_source_misses_the_cache() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let glsl = dir.path().join("glsl");
    std::fs::create_dir(&glsl).unwrap();
    // VKVCM_GLSL_DIR reads the files it holds from there and the rest from the binary:
    // a changed include (common.glsl, included by every kernel) changes every kernel.
    let common = vkvcm::gpu::shader::source("common.glsl").unwrap();
    std::fs::write(glsl.join("common.glsl"), format!("{common}\n// changed by tests/kernel_cache.rs\n")).unwrap();
    let embedded = [("VKVCM_CACHE_DIR", Some(cache.as_path()))];
    let changed = [("VKVCM_CACHE_DIR", Some(cache.as_path())), ("VKVCM_GLSL_DIR", Some(glsl.as_path()))];
    let n = compiled(&vkvcm_render(dir.path(), "a", &embedded, &[]));
    assert!(n > 0);
    assert_eq!(compiled(&vkvcm_render(dir.path(), "b", &changed, &[])), n, "the changed include misses");
    assert_eq!(compiled(&vkvcm_render(dir.path(), "c", &changed, &[])), 0);
    assert_eq!(compiled(&vkvcm_render(dir.path(), "d", &embedded, &[])), 0, "both versions are kept");
    assert_eq!(pixels(&dir.path().join("a.exr")), pixels(&dir.path().join("b.exr")));
}

#[test]
fn an_unwritable_folder_costs_one_warning() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("a-file");
    std::fs::write(&file, b"not a folder").unwrap();
    let cache = file.join("cache");
    let out = vkvcm_render(dir.path(), "out", &[("VKVCM_CACHE_DIR", Some(cache.as_path()))], &[]);
    let err = String::from_utf8_lossy(&out.stderr);
    let warnings: Vec<_> = err.lines().filter(|l| l.starts_with("warning: kernel cache")).collect();
    assert_eq!(warnings.len(), 1, "{err}");
    assert!(compiled(&out) > 0);
    assert!(dir.path().join("out.exr").exists());
}

#[test]
fn the_folder_follows_the_environment_and_can_be_turned_off() {
    let dir = tempfile::tempdir().unwrap();
    let home = dir.path().join("home");
    let xdg = dir.path().join("xdg");
    let chosen = dir.path().join("chosen");
    let empty = Path::new("");
    let spirv_in = |d: &Path| files(d, "spirv-").len();

    // VKVCM_CACHE_DIR set and empty: no cache anywhere.
    let env =
        [("VKVCM_CACHE_DIR", Some(empty)), ("XDG_CACHE_HOME", Some(xdg.as_path())), ("HOME", Some(home.as_path()))];
    let out = vkvcm_render(dir.path(), "off", &env, &[]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("kernel cache: off"));
    // (Mesa's own shader cache may appear in XDG_CACHE_HOME: not vkvcm's.)
    assert!(!xdg.join("vkvcm").exists() && !home.exists());
    // --no-kernel-cache: neither the folder VKVCM_CACHE_DIR names.
    let env = [("VKVCM_CACHE_DIR", Some(chosen.as_path()))];
    vkvcm_render(dir.path(), "flag", &env, &["--no-kernel-cache"]);
    assert!(!chosen.exists());
    // Without VKVCM_CACHE_DIR: $XDG_CACHE_HOME/vkvcm, else $HOME/.cache/vkvcm.
    let env = [("VKVCM_CACHE_DIR", None), ("XDG_CACHE_HOME", Some(xdg.as_path())), ("HOME", Some(home.as_path()))];
    vkvcm_render(dir.path(), "xdg", &env, &[]);
    assert!(spirv_in(&xdg.join("vkvcm")) > 0 && !home.join(".cache/vkvcm").exists());
    let env = [("VKVCM_CACHE_DIR", None), ("XDG_CACHE_HOME", None), ("HOME", Some(home.as_path()))];
    vkvcm_render(dir.path(), "home", &env, &[]);
    assert!(spirv_in(&home.join(".cache/vkvcm")) > 0);
}
