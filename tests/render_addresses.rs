//! Buffer device addresses (src/render/addresses.rs): on a device with them the kernels
//! reach the film, the splat sums, the light-vertex store with its offsets and scratch
//! slots, and the hash grid's keys and entries by address, so those buffers are limited
//! by maxMemoryAllocationSize instead of one binding (maxStorageBufferRange, 128 MiB on lavapipe). The kernels read and write
//! the same bytes in the same order either way, so:
//!
//! * every estimator gives bit-identical per-pixel sums, sums of squares and ray counts
//!   with and without device addresses (a device opened with `device_addresses: false`
//!   binds the buffers as storage buffers), with texel and with storage reads (storage
//!   reads make the camera kernel read the store and the grid by address too);
//! * with the device's binding limit capped below the film's size
//!   (`VKVCM_TEST_MAX_BINDING_BYTES`, src/gpu/fault_injection.rs), every estimator still
//!   renders, the same image as uncapped, while without device addresses the same render
//!   is refused before anything is allocated, naming the buffer and the limit.
//!
//! lavapipe, validation on (a kernel that reached an address without the feature enabled,
//! or a buffer without the usage flag, is a validation error).
//!
//! Sabotage checks (done by hand, not kept): registering the splat sums' address in the
//! film's field (`addresses.set(|a| &mut a.film, &splat)`), or reaching the film one vec4
//! past its address, fails the first test: on lavapipe the render then crashes (SIGSEGV),
//! as an address outside any buffer does there.

mod common;

use std::path::Path;
use std::process::Command;

use common::{invariance_cases, with_gpu_options};
use vkvcm::gpu::GpuOptions;
use vkvcm::render::reads::Reads;
use vkvcm::render::{self, Algorithm, Budget, RenderOutput, RenderSettings};

#[test]
fn images_do_not_depend_on_device_addresses() {
    let mut cases: Vec<_> = invariance_cases().into_iter().map(|(n, a, c)| (n, a, c, None)).collect();
    cases.push(("glm_c", Algorithm::El, vkvcm::render::Connect::Path, None));
    for (n, a, c) in [
        ("glm_c", Algorithm::Vcm, Algorithm::Vcm.default_connect()),
        ("gbs_s", Algorithm::Bpt, vkvcm::render::Connect::Path),
        ("glm_c", Algorithm::Bpt, vkvcm::render::Connect::Cache(1)),
    ] {
        cases.push((n, a, c, Some(Reads::Storage)));
    }
    let render_all = |device_addresses: bool| -> Vec<RenderOutput> {
        let opts = GpuOptions { device_addresses, ..GpuOptions::for_tests() };
        with_gpu_options(&opts, |gpu| {
            assert_eq!(gpu.has(vkvcm::gpu::BUFFER_DEVICE_ADDRESS), device_addresses, "lavapipe has device addresses");
            cases
                .iter()
                .map(|&(name, algo, connect, reads)| {
                    let scene = vkvcm::scene::load_named(name).unwrap();
                    let mut s = RenderSettings::new(algo, 23, 17, Budget::Iterations(2));
                    s.connect = connect;
                    s.count_rays = algo != Algorithm::El;
                    s.reads = reads;
                    render::render(gpu, &scene, &s, None, &mut |_| {}).unwrap()
                })
                .collect()
        })
    };
    let by_address = render_all(true);
    let bound = render_all(false);
    for ((name, algo, connect, reads), (a, b)) in cases.iter().zip(by_address.iter().zip(&bound)) {
        let what = format!("{name} {algo:?} {connect:?} reads {reads:?}, device addresses against bindings");
        assert!(a.sum.iter().any(|p| p.iter().any(|&c| c > 0.0)), "{what}: black image");
        assert!(a.sum == b.sum, "{what}: the per-pixel sums differ");
        assert!(a.sum_sq == b.sum_sq, "{what}: the per-pixel sums of squares differ");
        assert_eq!(a.profile.rays, b.profile.rays, "{what}: traced rays");
    }
}

fn vkvcm(dir: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_vkvcm"));
    c.current_dir(dir)
        .env("VKVCM_VALIDATION", "1")
        .env("VKVCM_CACHE_DIR", common::cli_cache_dir(dir.join("kernel-cache")));
    c.env_remove("VKVCM_TEST_MAX_BINDING_BYTES").env_remove("VKVCM_DEVICE_ADDRESSES");
    c.env_remove("VKVCM_TEST_SCENE_CHUNK_BYTES");
    if std::env::var_os("VK_DRIVER_FILES").is_none() {
        c.env("VK_DRIVER_FILES", "/usr/share/vulkan/icd.d/lvp_icd.json");
    }
    c
}

/// `vkvcm render` of glm_c with `algo` at `size` x `size`, 2 iterations, storage reads,
/// the binding limit capped at `cap` bytes; the image, or the error text.
fn render_capped(
    dir: &Path,
    algo: &str,
    size: u32,
    cap: Option<u64>,
    addresses: bool,
) -> Result<Vec<[f32; 3]>, String> {
    render_scene_capped(dir, "glm_c", algo, size, cap, addresses)
}

fn render_scene_capped(
    dir: &Path,
    scene: &str,
    algo: &str,
    size: u32,
    cap: Option<u64>,
    addresses: bool,
) -> Result<Vec<[f32; 3]>, String> {
    render_cli(dir, scene, &["-a", algo], "storage", size, (cap, None), addresses)
}

/// `vkvcm render` of `scene` with `args` at `size` x `size`, 2 iterations, reading it as
/// `reads`, with the binding limit capped at `caps.0` bytes and scene arrays read in
/// chunks cut to `caps.1` bytes; the image, or the error text.
fn render_cli(
    dir: &Path,
    scene: &str,
    args: &[&str],
    reads: &str,
    size: u32,
    (cap, chunk): (Option<u64>, Option<u64>),
    addresses: bool,
) -> Result<Vec<[f32; 3]>, String> {
    let stem = Path::new(scene).file_stem().unwrap().to_string_lossy();
    let out = dir.join(format!("{stem}-{}-{reads}-{size}-{cap:?}-{chunk:?}-{addresses}.exr", args.join("")));
    let mut c = vkvcm(dir);
    // The library's white sky, not the CLI's default studio map: these tests cap the
    // bindings below the scene's own buffers, and the map would be over them first.
    c.args(["render", scene, "--env", "white"]).args(args);
    c.args(["--width", &size.to_string(), "--height", &size.to_string(), "-i", "2", "--reads", reads, "-o"]);
    c.arg(&out);
    if let Some(cap) = cap {
        c.env("VKVCM_TEST_MAX_BINDING_BYTES", cap.to_string());
    }
    if let Some(chunk) = chunk {
        c.env("VKVCM_TEST_SCENE_CHUNK_BYTES", chunk.to_string());
    }
    if !addresses {
        c.env("VKVCM_DEVICE_ADDRESSES", "0");
    }
    let o = c.output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(!err.contains("panicked") && !err.contains("validation"), "{args:?}: {err}");
    if !o.status.success() {
        return Err(err);
    }
    Ok(vkvcm::image::read_exr(&out).unwrap().0.data)
}

#[test]
#[cfg_attr(not(feature = "fault-injection"), ignore = "needs --features fault-injection")]
fn frame_buffers_larger_than_one_binding_render() {
    let dir = tempfile::tempdir().unwrap();
    // 48 x 48: the film (96 bytes per pixel, 216 KiB) exceeds a 128 KiB binding; every
    // buffer still bound (the hash grid's bucket starts, the cache's index) fits.
    // lt at 64 x 64 with 64 KiB: the splat sums (24 bytes per pixel, 96 KiB) exceed it too.
    let mut cases: Vec<(&str, u32, u64)> =
        ["el", "pt", "bpt", "ppm", "bpm", "vcm"].into_iter().map(|a| (a, 48, 128 << 10)).collect();
    cases.push(("lt", 64, 64 << 10));
    for (algo, size, cap) in cases {
        let free = render_capped(dir.path(), algo, size, None, true).unwrap();
        let capped = render_capped(dir.path(), algo, size, Some(cap), true)
            .unwrap_or_else(|e| panic!("{algo} with a {cap}-byte binding limit: {e}"));
        assert!(free.iter().any(|p| p[0] > 0.0), "{algo}: black image");
        assert!(capped == free, "{algo}: the image with a capped binding limit differs");
        let e = render_capped(dir.path(), algo, size, Some(cap), false).expect_err("bound film over the cap rendered");
        // The message names the largest buffer over the limit: the film (the light-vertex
        // store starts at what a binding holds, and grows only if an iteration needs it).
        let largest = "buffer film";
        let line = e.lines().find(|l| l.starts_with("error")).unwrap_or_default();
        assert!(line.contains(largest) && line.contains("maxStorageBufferRange"), "{algo}: {e}");
    }
}

/// The scene's buffers that can outgrow a binding (vertex attributes, texels, the
/// environment map: src/render/scene_gpu.rs, ADDRESSED) are reached by address too:
/// BoxTextured's texels (178 KB) over a 128 KiB binding limit and tests/env's textured
/// scene's environment map (128 KiB of env_texels) over a 96 KiB one render with device
/// addresses the image that bound buffers give without the cap, and are refused naming
/// the buffer without addresses. Sabotage (by hand, not kept): registering the vertex
/// attributes' address as the texels' fails BoxTextured (the images differ).
#[test]
#[cfg_attr(not(feature = "fault-injection"), ignore = "needs --features fault-injection")]
fn scene_buffers_larger_than_one_binding_render() {
    let dir = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let cases = [
        ("tests/khronos/BoxTextured.gltf", 128u64 << 10, "buffer texture_texels"),
        ("tests/env/textured_scene.gltf", 96 << 10, "buffer env_texels"),
    ];
    for (scene, cap, buffer) in cases {
        let scene = root.join(scene).to_string_lossy().to_string();
        for algo in ["pt", "vcm"] {
            let free = render_scene_capped(dir.path(), &scene, algo, 24, None, false).unwrap();
            let capped = render_scene_capped(dir.path(), &scene, algo, 24, Some(cap), true)
                .unwrap_or_else(|e| panic!("{scene} {algo} with a {cap}-byte binding limit: {e}"));
            assert!(free.iter().any(|p| p[0] > 0.0), "{scene} {algo}: black image");
            assert!(capped == free, "{scene} {algo}: the image with a capped binding limit differs");
            let e = render_scene_capped(dir.path(), &scene, algo, 24, Some(cap), false)
                .expect_err("a bound scene buffer over the cap rendered");
            let line = e.lines().find(|l| l.starts_with("error")).unwrap_or_default();
            assert!(line.contains(buffer) && line.contains("maxStorageBufferRange"), "{scene} {algo}: {e}");
        }
    }
}

/// [`render_cli`] at 16 x 16.
fn render_chunked(
    dir: &Path,
    scene: &Path,
    args: &[&str],
    reads: &str,
    cap: Option<u64>,
    chunk: Option<u64>,
    addresses: bool,
) -> Result<Vec<[f32; 3]>, String> {
    render_cli(dir, &scene.to_string_lossy(), args, reads, 16, (cap, chunk), addresses)
}

/// A scene whose BVH and geometry are larger than one binding (src/render/scene_gpu.rs,
/// CHUNKED) is read by address in chunks, each its own allocation, so its size is limited
/// by device memory: with the binding limit capped below the BVH primitives' size and
/// chunks of 512 bytes (a BVH primitive's three elements then often straddle two chunks,
/// and each array has several), every estimator renders the instanced scene (mesh trees,
/// instance records, smooth normals) with storage reads, pt with texel reads, vcm its
/// flattened form, and pt and lt BoxTextured's texture coordinates (the vertex
/// attributes, otherwise one allocation), each bit-identical to the uncapped
/// render, which binds the arrays whole; without device addresses the capped render is
/// refused naming the buffer.
///
/// Sabotage (by hand, not kept): the triangles' chunks looked up from the BVH nodes'
/// first chunk (CHUNK_NODES for CHUNK_TRIANGLES in glsl/scene.glsl) fails the first case
/// (the render crashes on an address outside any buffer); the texture coordinates read
/// from a vertex's second element (glsl/textures.glsl, vertex_attribute_at) fails
/// BoxTextured.
#[test]
#[cfg_attr(not(feature = "fault-injection"), ignore = "needs --features fault-injection")]
fn scene_bvh_and_geometry_larger_than_one_binding_render_in_chunks() {
    let dir = tempfile::tempdir().unwrap();
    let scene = common::instanced_gltf::write_instanced_gltf(dir.path());
    let (cap, chunk) = (CHUNK_TEST_CAP, 512);
    let mut cases: Vec<(Vec<&str>, &str)> = Vec::new();
    // A merge radius large enough that photon mapping's 2 iterations are not black.
    let radius = ["--radius-factor", "0.05"];
    for algo in ["el", "pt", "lt", "bpt", "ppm", "bpm", "vcm"] {
        cases.push(([["-a", algo].as_slice(), &radius].concat(), "storage"));
    }
    // With texel reads the camera kernel also reads the light-vertex store and the grid
    // as texels, which the cap would refuse: pt, which has neither.
    cases.push((vec!["-a", "pt"], "texel"));
    cases.push(([["-a", "vcm", "--flatten-instances"].as_slice(), &radius].concat(), "storage"));
    for (args, reads) in cases {
        let what = format!("{args:?} reads {reads}");
        let free = render_chunked(dir.path(), &scene, &args, reads, None, None, true).unwrap();
        let chunked = render_chunked(dir.path(), &scene, &args, reads, Some(cap), Some(chunk), true)
            .unwrap_or_else(|e| panic!("{what} with a {cap}-byte binding limit: {e}"));
        assert!(free.iter().any(|p| p[0] > 0.0), "{what}: black image");
        assert!(chunked == free, "{what}: the image read in chunks differs");
    }
    // Texture coordinates (vertex attributes) in chunks of 256 bytes, a vertex's three
    // elements often in two: BoxTextured (its arrays are small, hence the smaller cap).
    let textured = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/khronos/BoxTextured.gltf");
    for algo in ["pt", "lt"] {
        let free = render_chunked(dir.path(), &textured, &["-a", algo], "storage", None, None, true).unwrap();
        let chunked = render_chunked(dir.path(), &textured, &["-a", algo], "storage", Some(512), Some(256), true)
            .unwrap_or_else(|e| panic!("BoxTextured {algo} with a 512-byte binding limit: {e}"));
        assert!(chunked == free, "BoxTextured {algo}: the image read in chunks differs");
    }
    let e = render_chunked(dir.path(), &scene, &["-a", "pt"], "storage", Some(cap), Some(chunk), false)
        .expect_err("a bound BVH over the cap rendered");
    let line = e.lines().find(|l| l.starts_with("error")).unwrap_or_default();
    // (It names the largest scene buffer over the cap: the vertex attributes here.)
    assert!(line.contains("maxStorageBufferRange") && line.contains("the scene is too large"), "{e}");
}

/// The binding limit of the chunked-scene test: below the instanced scene's BVH
/// primitives, above every other buffer bound at 16 x 16.
const CHUNK_TEST_CAP: u64 = 8 << 10;
