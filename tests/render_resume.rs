//! Resume: a render of N iterations saved to EXR, read back and continued for N more
//! equals an uninterrupted render of 2N iterations bit for bit (the per-pixel random
//! numbers and the merge radius depend only on the iteration index, and the film's
//! fixed-point sums are saved exactly and add in any order: src/render/film.rs). Plus: mismatching settings are refused, and absurd frames fail
//! cleanly before allocation.

mod common;

use std::sync::Arc;

use common::with_gpu;
use vkvcm::gpu::Gpu;
use vkvcm::render::saved::{self, Provenance};
use vkvcm::render::{Algorithm, Budget, RenderOutput, RenderSettings, Renderer};
use vkvcm::scene::{load_named, Scene};

const N: u64 = 6;
const SIZE: u32 = 32;

fn settings(algo: Algorithm, budget: Budget) -> RenderSettings {
    RenderSettings::new(algo, SIZE, SIZE, budget)
}

fn render(gpu: &Arc<Gpu>, scene: &Scene, algo: Algorithm, n: u64) -> RenderOutput {
    let s = settings(algo, Budget::Iterations(n));
    let mut r = Renderer::new(gpu, scene, &s).expect("renderer");
    r.run(Budget::Iterations(n), None, &mut |_| {}).expect("run");
    r.output().expect("output")
}

/// Largest relative difference between two sets of per-pixel values.
fn max_rel(a: impl Iterator<Item = f64>, b: impl Iterator<Item = f64>) -> f32 {
    a.zip(b)
        .map(|(x, y)| {
            let m = x.abs().max(y.abs());
            if m == 0.0 {
                0.0
            } else {
                ((x - y).abs() / m) as f32
            }
        })
        .fold(0.0, f32::max)
}

fn resume_matches_uninterrupted(algo: Algorithm) {
    let scene = load_named("gbs_s").unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("half.exr");
    with_gpu(|gpu| {
        let full = render(gpu, &scene, algo, 2 * N);
        let half = render(gpu, &scene, algo, N);
        let prov = Provenance::new(&scene, "default", &gpu.info.name);
        let s = settings(algo, Budget::Iterations(2 * N));
        saved::write_render_exr(&path, &half, &s, &prov).unwrap();

        let loaded = saved::read_render_exr(&path).unwrap();
        assert_eq!(loaded.iterations, N);
        loaded.check_matches(&s, &prov).unwrap();
        let mut r = Renderer::new(gpu, &scene, &s).unwrap();
        r.resume_saved(&loaded).unwrap();
        r.run(Budget::Iterations(N), None, &mut |_| {}).unwrap();
        let resumed = r.output().unwrap();
        drop(r);

        assert_eq!(resumed.iterations, 2 * N);
        let bits = |o: &RenderOutput| o.pixels.iter().flatten().map(|v| v.to_bits()).collect::<Vec<_>>();
        let mean = |o: &RenderOutput| o.pixels.iter().flatten().map(|&v| v as f64).collect::<Vec<_>>();
        // The halves differ by noise: bit-identity below is not a tautology.
        let d_half = max_rel(mean(&full).into_iter(), mean(&half).into_iter());
        eprintln!("{}: N vs 2N iterations: max rel diff {d_half:e}", algo.name());
        assert!(d_half > 1e-3, "{}: N and 2N iterations are nearly equal ({d_half})", algo.name());
        assert!(resumed.sums == full.sums, "{}: resumed film's sums differ from the uninterrupted", algo.name());
        assert_eq!(bits(&resumed), bits(&full), "{}: resumed mean differs from the uninterrupted", algo.name());
    });
}

#[test]
fn resume_pt() {
    resume_matches_uninterrupted(Algorithm::Pt);
}

#[test]
fn resume_vcm() {
    resume_matches_uninterrupted(Algorithm::Vcm);
}

#[test]
fn resume_refuses_other_settings() {
    let scene = load_named("gbs_s").unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("r.exr");
    with_gpu(|gpu| {
        let out = render(gpu, &scene, Algorithm::Pt, 1);
        let s = settings(Algorithm::Pt, Budget::Iterations(1));
        let prov = Provenance::new(&scene, "default", "x");
        saved::write_render_exr(&path, &out, &s, &prov).unwrap();
    });
    let loaded = saved::read_render_exr(&path).unwrap();
    let base = settings(Algorithm::Pt, Budget::Iterations(2));
    let here = Provenance::new(&scene, "default", "y");
    loaded.check_matches(&base, &here).unwrap();
    let refuse = |s: &RenderSettings, scene_name: &str, camera: &str, needle: &str| {
        let p = Provenance { scene: scene_name.into(), camera: camera.into(), ..here.clone() };
        let e = loaded.check_matches(s, &p).unwrap_err().to_string();
        assert!(e.contains(needle) && !e.contains('\n'), "{e}");
    };
    let mut s = base.clone();
    s.frame.seed += 1;
    refuse(&s, &scene.name, "default", "--seed");
    let mut s = base.clone();
    s.algorithm = Algorithm::Vcm;
    refuse(&s, &scene.name, "default", "--algo");
    let mut s = base.clone();
    s.frame.width = 16;
    refuse(&s, &scene.name, "default", "--width");
    let mut s = base.clone();
    s.frame.max_path_length = 4;
    refuse(&s, &scene.name, "default", "--max-path-length");
    let mut s = base.clone();
    s.alpha = 0.5;
    refuse(&s, &scene.name, "default", "--alpha");
    refuse(&base, "glm_c", "default", "scene");
    refuse(&base, &scene.name, "cam2", "--camera");
    // The same scene name with edited content (one material's diffuse albedo 0.001 higher):
    // refused; an unedited copy is accepted (above).
    let mut edited = scene.clone();
    edited.materials[0].diffuse += glam::Vec3::splat(1e-3);
    let e = loaded.check_matches(&base, &Provenance::new(&edited, "default", "y")).unwrap_err().to_string();
    assert!(e.contains("has changed") && e.contains(&scene.name) && !e.contains('\n'), "{e}");

    // A plain EXR (no second moment, no settings) is refused with its name.
    let plain = dir.path().join("plain.exr");
    vkvcm::image::write_exr(&plain, &vkvcm::image::Image::new(2, 2), &[]).unwrap();
    let e = saved::read_render_exr(&plain).unwrap_err().to_string();
    assert!(e.contains("plain.exr"), "{e}");
}

#[test]
fn absurd_frames_fail_before_allocation() {
    let scene = load_named("gbs_s").unwrap();
    with_gpu(|gpu| {
        // The light-vertex store is sized to what the device holds (it grows when an
        // iteration needs more), so light vertices refuse a render only through the
        // per-light-subpath offsets: 2^32 - 1 light subpaths.
        for (algo, w, h, light_paths, needle) in [
            (Algorithm::Pt, 60_000, 60_000, None, "for buffer film"),
            (Algorithm::Vcm, 60_000, 60_000, None, "for buffer film"),
            (Algorithm::Vcm, 64, 64, Some(u32::MAX), "for buffer light_vertex_offsets"),
            (Algorithm::Pt, 0, 16, None, "width and height"),
            (Algorithm::Vcm, 16, 0, None, "width and height"),
            (Algorithm::Pt, 100_000, 100_000, None, "pixels"),
        ] {
            let s = settings(algo, Budget::Iterations(1));
            let frame = vkvcm::render::FrameSettings { width: w, height: h, ..s.frame };
            let s = RenderSettings { frame, light_paths, ..s };
            let e = match Renderer::new(gpu, &scene, &s) {
                Ok(_) => panic!("{w}x{h} {}: no error", algo.name()),
                Err(e) => format!("{e:#}"),
            };
            assert!(e.contains(needle) && !e.contains('\n'), "{w}x{h}: {e}");
        }
    });
}
