//! Instanced scenes (a mesh stored once, placed by instances: src/bvh/layout.rs,
//! "Instancing") render the image of the same scene flattened into world-space triangles,
//! in every estimator, with a fraction of the memory.
//!
//! Same seed, same random numbers: the two renders differ only where float rounding
//! differs. The instanced traversal intersects in object space and maps hit points and
//! normals back, so hit points differ by a few ulps; almost every path is then the same
//! sequence of vertices and its contribution agrees to ~1e-5, but a path that grazes an
//! edge, or draws a number within rounding of a lobe's probability, can continue
//! differently in one render and change its pixel by any amount. So the check is: at most
//! 0.5% of pixels (5 of 1024) differ by more than 1e-3 relative, and the means of the
//! other pixels agree to 1e-5 relative (a diverged path is not a systematic difference).
//! Measured on lavapipe (printed with --nocapture): one pixel of pt, bpt and vcm (the same
//! camera path's numbers) diverges, by up to 13%, which alone moves the whole image's
//! mean by 5e-4; the other pixels' means differ by at most 8e-7. A render with
//! another seed is the control: 67% of its pixels differ by more than 1e-3. A sabotage
//! that fails it in every estimator: vertex normals interpolated before they are
//! normalised in world space (the non-uniformly scaled instances).

mod common;

use std::sync::Arc;

use common::with_gpu;
use vkvcm::gpu::Gpu;
use vkvcm::render::{Algorithm, Budget, RenderOutput, RenderSettings, Renderer};
use vkvcm::scene::{load_with, LoadOptions, Scene};

const SIZE: u32 = 32;
const PIXEL_TOL: f64 = 1e-3;
const MAX_DIFFERING: f64 = 0.005;
const MEAN_TOL: f64 = 1e-5;

fn render(gpu: &Arc<Gpu>, scene: &Scene, algo: Algorithm, iterations: u64, seed: u32) -> (RenderOutput, u64) {
    let mut s = RenderSettings::new(algo, SIZE, SIZE, Budget::Iterations(iterations));
    s.frame.seed = seed;
    let mut r = Renderer::new(gpu, scene, &s).expect("renderer");
    r.run(s.budget, None, &mut |_| {}).expect("run");
    let scene_bytes: u64 = r
        .buffers()
        .iter()
        .filter(|(n, _)| {
            ["bvh_nodes", "bvh_prims", "triangles", "shading_normals", "vertex_attributes"].contains(&n.as_str())
        })
        .map(|(_, b)| b)
        .sum();
    (r.output().expect("output"), scene_bytes)
}

/// (fraction of pixel channels differing by more than PIXEL_TOL relative, relative
/// difference of the means of the other channels, largest per-pixel relative difference).
fn compare(a: &RenderOutput, b: &RenderOutput) -> (f64, f64, f64) {
    let floor = 1e-3 * a.pixels.iter().flatten().map(|&v| v as f64).sum::<f64>() / (3 * a.pixels.len()) as f64;
    let rel: Vec<f64> = a
        .pixels
        .iter()
        .flatten()
        .zip(b.pixels.iter().flatten())
        .map(|(&x, &y)| (x as f64 - y as f64).abs() / ((x as f64).abs().max(y as f64) + floor))
        .collect();
    let differing = rel.iter().filter(|&&r| r > PIXEL_TOL).count() as f64 / rel.len() as f64;
    let agreeing = |o: &RenderOutput| -> f64 {
        o.pixels.iter().flatten().zip(&rel).filter(|&(_, &r)| r <= PIXEL_TOL).map(|(&v, _)| v as f64).sum()
    };
    let (ma, mb) = (agreeing(a), agreeing(b));
    (differing, (ma - mb).abs() / ma.max(mb), rel.iter().copied().fold(0.0, f64::max))
}

#[test]
fn instanced_scene_renders_the_flattened_image_in_every_estimator() {
    let dir = tempfile::tempdir().unwrap();
    let path = common::instanced_gltf::write_instanced_gltf(dir.path());
    let instanced = load_with(&path, &LoadOptions::default()).unwrap();
    let flattened = load_with(&path, &LoadOptions { flatten_instances: true, ..Default::default() }).unwrap();
    assert_eq!(instanced.instances.len(), 7);
    with_gpu(|gpu| {
        let mut report = String::new();
        let mut failures = Vec::new();
        for (algo, iterations) in [
            (Algorithm::El, 4),
            (Algorithm::Pt, 16),
            (Algorithm::Lt, 16),
            (Algorithm::Bpt, 16),
            (Algorithm::Ppm, 16),
            (Algorithm::Bpm, 16),
            (Algorithm::Vcm, 16),
        ] {
            let (a, bytes_a) = render(gpu, &instanced, algo, iterations, 7);
            let (b, bytes_b) = render(gpu, &flattened, algo, iterations, 7);
            let (differing, mean, worst) = compare(&a, &b);
            report += &format!(
                "{algo:?}: {:.2}% of pixels differ by > {PIXEL_TOL}, means by {mean:.2e}, largest {worst:.2e}; scene buffers {bytes_a} vs {bytes_b} bytes\n",
                100.0 * differing
            );
            if differing > MAX_DIFFERING || mean > MEAN_TOL {
                failures.push(format!("{algo:?}"));
            }
            // The instanced scene stores the sphere once: 288 triangles and 7 instances
            // against 7 x 288 triangles.
            assert!((bytes_a as f64) < 0.3 * bytes_b as f64, "{algo:?}: {bytes_a} vs {bytes_b} bytes");
        }
        // Control: another seed.
        let (a, _) = render(gpu, &instanced, Algorithm::Pt, 16, 7);
        let (c, _) = render(gpu, &flattened, Algorithm::Pt, 16, 8);
        let (differing, _, _) = compare(&a, &c);
        report += &format!("control (pt, another seed): {:.1}% of pixels differ\n", 100.0 * differing);
        println!("{report}");
        assert!(differing > 0.5, "the control should differ in most pixels:\n{report}");
        assert!(failures.is_empty(), "{failures:?} differ:\n{report}");
    });
}
