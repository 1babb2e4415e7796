//! VK_EXT_debug_utils names and labels (src/gpu/debug_names.rs): with the extension (the
//! Vulkan loader has it for lavapipe), a render names every buffer it allocated and every
//! kernel's pipeline, and labels every dispatch, with validation on and silent (a label
//! left open or closed twice would be a validation message).

mod common;

use common::scenes::{camera, scene};
use glam::Vec3;
use vkvcm::render::{Algorithm, Budget, RenderSettings, Renderer};
use vkvcm::scene::{Light, Material, Triangle};

#[test]
fn buffers_pipelines_and_dispatches_are_named() {
    let floor = Material { name: "floor".into(), diffuse: Vec3::splat(0.5), ..Default::default() };
    let (a, b, c, d) =
        (Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 0.0, -1.0), Vec3::new(1.0, 0.0, 1.0), Vec3::new(-1.0, 0.0, 1.0));
    let tris = vec![
        Triangle { p: [a, c, b], n: None, material: 0, attributes: None },
        Triangle { p: [a, d, c], n: None, material: 0, attributes: None },
    ];
    let lamp = Light::Point { position: Vec3::new(0.0, 1.0, 0.0), intensity: Vec3::ONE };
    let s = scene(
        "names",
        tris,
        vec![floor],
        vec![lamp],
        camera(Vec3::new(0.0, 1.0, 2.0), Vec3::new(0.0, -0.5, -1.0), Vec3::Y, 40.0),
    );
    common::with_gpu(|gpu| {
        let Some((names0, labels0)) = gpu.debug_name_counts() else {
            common::skip("buffers_pipelines_and_dispatches_are_named", "no VK_EXT_debug_utils");
            return;
        };
        let settings = RenderSettings::new(Algorithm::Bpt, 8, 8, Budget::Iterations(2));
        let mut r = Renderer::new(gpu, &s, &settings).unwrap();
        r.trace_dispatches();
        r.run(settings.budget, None, &mut |_| {}).unwrap();
        let dispatches = r.take_dispatches().len() as u64;
        let (names, labels) = gpu.debug_name_counts().unwrap();
        let buffers = r.buffers().len() as u64;
        let kernels = r.passes().len() as u64;
        assert!(
            names - names0 >= buffers + kernels,
            "{} names for {buffers} buffers and at least {kernels} kernels",
            names - names0
        );
        assert!(
            dispatches > 0 && labels - labels0 >= dispatches,
            "{} labels for {dispatches} timed dispatches",
            labels - labels0
        );
    });
}
