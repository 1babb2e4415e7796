//! The light-vertex store (src/render/passes/light_subpaths.rs): an iteration's light
//! subpaths are traced in chunks, their vertices compacted into the store in path order,
//! and the store, sized from an estimate, grows when an iteration stores more than it
//! holds (the iterations that did not fit are left out of the film and rendered again).
//! None of this may change the image:
//!
//! * with chunks of 7 light subpaths (several per iteration, the last one partial) every
//!   light-subpath estimator gives bit-identical per-pixel sums, sums of squares and ray
//!   counts to one chunk per iteration;
//! * with a store of 5 vertices (every first iteration overflows and is rendered again)
//!   the sums are bit-identical too, and the store reports that it grew;
//! * with a store that holds exactly what the first iteration stored, a later iteration
//!   of a batch overflows: it and the rest of its batch are left out and rendered again,
//!   with the same image, and the progress reports name the iterations rendered again;
//! * where the device cannot hold the store an iteration needs (a binding limit capped to
//!   150,000 bytes, no device addresses: the store starts at what fits, 4687 vertices, and
//!   glm_c's bpt stores about 4900 per iteration with 2304 light subpaths), the render stops with a
//!   message that names the buffer, the numbers and what to lower; at 200,000 bytes it
//!   renders.
//!
//! lavapipe, validation on, tiny frames (23 x 17: light subpaths that do not divide into
//! whole chunks or workgroups).
//!
//! Sabotage checks (done by hand, not kept), each failing at its first case: writing each
//! chunk's vertices from the store's start (ignoring the previous chunk's offset) in
//! light_vertex_compact.comp fails the first test (glm_c bpt: the sums differ); letting
//! the camera kernel render an overflowed iteration (no skip) fails the second (glm_c bpt);
//! skipping only the batch's first overflowed iteration (`==` instead of `<=` in the camera
//! kernel's skip) fails the third (glm_c vcm).

mod common;

use std::process::Command;
use std::sync::Arc;

use common::{invariance_cases, with_gpu};
use vkvcm::gpu::Gpu;
use vkvcm::render::{Algorithm, Budget, Connect, RenderOutput, RenderSettings, Renderer, StoreUse};

fn settings(algo: Algorithm, connect: Connect, iterations: u64) -> RenderSettings {
    let mut s = RenderSettings::new(algo, 23, 17, Budget::Iterations(iterations));
    s.connect = connect;
    s.count_rays = true;
    s
}

fn render(gpu: &Arc<Gpu>, name: &str, s: &RenderSettings) -> (RenderOutput, Option<StoreUse>) {
    render_with_notes(gpu, name, s).0
}

/// [`render`], with the notes its progress reports carried.
fn render_with_notes(
    gpu: &Arc<Gpu>,
    name: &str,
    s: &RenderSettings,
) -> ((RenderOutput, Option<StoreUse>), Vec<String>) {
    let scene = vkvcm::scene::load_named(name).unwrap();
    let mut r = Renderer::new(gpu, &scene, s).unwrap();
    let mut notes = Vec::new();
    r.run(s.budget, None, &mut |p| notes.extend(p.note.clone())).unwrap();
    ((r.output().unwrap(), r.light_vertex_store_use()), notes)
}

fn light_subpath_cases() -> Vec<(&'static str, Algorithm, Connect)> {
    invariance_cases().into_iter().filter(|(_, a, _)| a.info().techniques.light_subpaths).collect()
}

fn assert_same(what: &str, a: &RenderOutput, b: &RenderOutput) {
    assert!(a.sum.iter().any(|p| p.iter().any(|&c| c > 0.0)), "{what}: black image");
    assert_eq!(a.iterations, b.iterations, "{what}: iterations");
    assert!(a.sum == b.sum, "{what}: the per-pixel sums differ");
    assert!(a.sum_sq == b.sum_sq, "{what}: the per-pixel sums of squares differ");
}

#[test]
fn chunks_do_not_change_the_image() {
    with_gpu(|gpu| {
        for (name, algo, connect) in light_subpath_cases() {
            let s = settings(algo, connect, 3);
            let (whole, _) = render(gpu, name, &s);
            let chunked = RenderSettings { light_chunk_paths: Some(7), ..s };
            let (chunks, _) = render(gpu, name, &chunked);
            let what = format!("{name} {algo:?} {connect:?}, chunks of 7 light subpaths");
            assert_same(&what, &whole, &chunks);
            assert_eq!(whole.profile.rays, chunks.profile.rays, "{what}: traced rays");
        }
    });
}

#[test]
fn a_store_that_grows_does_not_change_the_image() {
    with_gpu(|gpu| {
        for (name, algo, connect) in light_subpath_cases() {
            if !algo.info().techniques.store_vertices {
                continue;
            }
            let s = settings(algo, connect, 3);
            let (sized, _) = render(gpu, name, &s);
            let small = RenderSettings { light_vertex_capacity: Some(5), light_chunk_paths: Some(100), ..s };
            let (grown, store) = render(gpu, name, &small);
            let what = format!("{name} {algo:?} {connect:?}, a store of 5 vertices at first");
            assert_same(&what, &sized, &grown);
            let store = store.expect("a light-vertex store");
            assert!(store.grown >= 1 && store.iterations_redone >= 1, "{what}: the store did not grow: {store:?}");
            assert!(store.capacity >= store.most_vertices, "{what}: {store:?}");
        }
    });
}

#[test]
fn an_overflow_in_the_middle_of_a_batch_renders_the_rest_of_it_again() {
    with_gpu(|gpu| {
        for (name, algo, connect) in
            [("glm_c", Algorithm::Vcm, Connect::Path), ("gbs_s", Algorithm::Bpt, Connect::Cache(1))]
        {
            // What the first iteration stores.
            let (_, first) = render(gpu, name, &settings(algo, connect, 1));
            let first = first.unwrap().most_vertices;
            let s = settings(algo, connect, 16);
            let (sized, _) = render(gpu, name, &s);
            // Iteration 0 fits exactly (the first batch is one iteration); the next batch
            // holds the other 15, and one of them stores more.
            let tight = RenderSettings { light_vertex_capacity: Some(first), ..s };
            let ((grown, store), notes) = render_with_notes(gpu, name, &tight);
            let what = format!("{name} {algo:?} {connect:?}, a store of {first} vertices at first");
            assert_same(&what, &sized, &grown);
            let store = store.unwrap();
            assert!(store.grown >= 1, "{what}: no later iteration overflowed: {store:?}");
            assert!(store.most_vertices > first, "{what}: {store:?}");
            // The progress says so, naming the iterations rendered again.
            assert_eq!(notes.len() as u32, store.grown, "{what}: {notes:?}");
            let named = notes[0].starts_with("light-vertex store grown to") && notes[0].ends_with("rendered again");
            assert!(named, "{what}: {notes:?}");
        }
    });
}

#[test]
#[cfg_attr(not(feature = "fault-injection"), ignore = "needs --features fault-injection")]
fn a_store_the_device_cannot_hold_is_refused_with_what_to_lower() {
    let dir = tempfile::tempdir().unwrap();
    let run = |cap: &str| {
        let mut c = Command::new(env!("CARGO_BIN_EXE_vkvcm"));
        c.current_dir(dir.path()).env("VKVCM_VALIDATION", "1").env("VKVCM_CACHE_DIR", common::cli_cache_dir(""));
        c.env("VKVCM_TEST_MAX_BINDING_BYTES", cap).env("VKVCM_DEVICE_ADDRESSES", "0");
        if std::env::var_os("VK_DRIVER_FILES").is_none() {
            c.env("VK_DRIVER_FILES", "/usr/share/vulkan/icd.d/lvp_icd.json");
        }
        // 36 x 36 with 2304 light subpaths: the film (96 bytes per pixel, 124 KB) fits both
        // caps, the store's first half (about 4900 vertices of 32 bytes) only the larger.
        let frame = ["--width", "36", "--height", "36", "--light-paths", "2304"];
        c.args(["render", "glm_c", "--algo", "bpt", "-i", "3", "-o", "out.exr"]).args(frame);
        c.output().unwrap()
    };
    let refused = run("150000");
    let err = String::from_utf8_lossy(&refused.stderr);
    assert!(!refused.status.success(), "{err}");
    for part in ["store up to", "light vertices (2304 light subpaths)", "light_vertices_a", "maxStorageBufferRange"] {
        assert!(err.contains(part), "{part:?} not in: {err}");
    }
    assert!(err.contains("lower --light-paths, the resolution or --max-path-length"), "{err}");
    let rendered = run("200000");
    assert!(rendered.status.success(), "{}", String::from_utf8_lossy(&rendered.stderr));
}
