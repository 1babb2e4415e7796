//! Texel-buffer reads (src/render/reads.rs): the kernels read the scene (BVH, triangles,
//! spheres, materials, lights, shading normals) and, in the camera kernel, the light-vertex
//! store, the hash grid and the light-vertex cache's index either as storage buffers or as
//! uniform texel buffers. Both read the same bytes, so the image must not depend on the
//! choice: every estimator renders glm_c (area light, a sphere) with both, and so do lt,
//! bpt and vcm on gbs_s (directional light, two spheres), pt and vcm on gbs_b (background
//! light), pt and el on a mesh with shading normals; the per-pixel sums, sums of squares
//! and traced-ray counts must be bit-identical. 23x17 pixels, 2 iterations; lavapipe,
//! validation on (a descriptor of the wrong kind for the shader's declaration is a
//! validation error, so the test also checks that every kernel's bindings match its
//! declarations in both modes).
//!
//! Sabotage checks (done by hand, not kept): swapping two fields in scene.glsl's
//! `light_at` texel accessor, or reading the hash grid's entry j + 1 in `grid_point_at`,
//! fails this test.

mod common;

use common::{invariance_cases, with_gpu};
use glam::Vec3;
use vkvcm::gpu::{Bind, Gpu};
use vkvcm::render::reads::Reads;
use vkvcm::render::Connect;
use vkvcm::render::{self, Algorithm, Budget, RenderSettings};
use vkvcm::scene::Scene;

fn check_same_image(gpu: &std::sync::Arc<Gpu>, name: &str, scene: &Scene, algo: Algorithm, connect: Connect) {
    check_same_image_with(gpu, name, scene, algo, connect, false);
}

fn check_same_image_with(
    gpu: &std::sync::Arc<Gpu>,
    name: &str,
    scene: &Scene,
    algo: Algorithm,
    connect: Connect,
    generic: bool,
) {
    let render_with = |reads: Reads| {
        let mut s = RenderSettings::new(algo, 23, 17, Budget::Iterations(2));
        s.connect = connect;
        s.generic = generic;
        s.count_rays = algo != Algorithm::El;
        s.reads = Some(reads);
        render::render(gpu, scene, &s, None, &mut |_| {}).unwrap()
    };
    let storage = render_with(Reads::Storage);
    let texel = render_with(Reads::Texel);
    let what = format!("{name} {algo:?} {connect:?}, texel reads against storage");
    assert!(storage.sum.iter().any(|p| p.iter().any(|&c| c > 0.0)), "{what}: black image");
    assert!(storage.sum == texel.sum, "{what}: the per-pixel sums differ");
    assert!(storage.sum_sq == texel.sum_sq, "{what}: the per-pixel sums of squares differ");
    assert_eq!(storage.profile.rays, texel.profile.rays, "{what}: traced rays");
}

#[test]
fn images_do_not_depend_on_reads() {
    let mut cases = invariance_cases();
    cases.push(("glm_c", Algorithm::El, Connect::Path));
    with_gpu(|gpu| {
        for (name, algo, connect) in cases {
            let scene = vkvcm::scene::load_named(name).unwrap();
            check_same_image(gpu, name, &scene, algo, connect);
        }
    });
}

/// Shading normals (the binding `shading_normals`) are read by el, and by every estimator's generic kernels:
/// glm_c with per-vertex normals tilted off the faces' normals.
#[test]
fn shading_normals_read_the_same_as_texels() {
    let mut scene = vkvcm::scene::load_named("glm_c").unwrap();
    for t in &mut scene.triangles {
        let g = (t.p[1] - t.p[0]).cross(t.p[2] - t.p[0]).normalize();
        t.n = Some([(g + Vec3::X * 0.3).normalize(), (g + Vec3::Y * 0.3).normalize(), (g + Vec3::Z * 0.3).normalize()]);
    }
    with_gpu(|gpu| {
        check_same_image_with(gpu, "glm_c with shading normals", &scene, Algorithm::El, Connect::Path, false);
        check_same_image_with(gpu, "glm_c with shading normals, generic", &scene, Algorithm::Pt, Connect::Path, true);
    });
}

/// A texel binding must be a whole number of texels; refused before anything is created.
#[test]
fn a_partial_texel_is_refused() {
    with_gpu(|gpu| {
        let b = gpu.buffer_zeroed::<u32>("odd", 5).unwrap();
        let out = gpu.buffer_zeroed::<u32>("out", 5).unwrap();
        let binds = [Bind::vec4("texels", &b), Bind::u32("results", &out)];
        let e = gpu.kernel("tests/texel_read.comp", &[], &binds).err().expect("20-byte texel buffer bound");
        let e = format!("{e:#}");
        assert!(e.contains("\"odd\"") && e.contains("whole number"), "{e}");
        // The same buffer read as uint texels is whole, and reads what it holds.
        b.write(&[7u32, 8, 9, 10, 11]).unwrap();
        let k =
            gpu.kernel("tests/texel_read.comp", &[], &[Bind::u32("texels", &b), Bind::u32("results", &out)]).unwrap();
        let mut batch = gpu.batch().unwrap();
        batch.dispatch(&k, k.groups_for(5), bytemuck::bytes_of(&5u32)).unwrap();
        batch.submit_wait(None).unwrap();
        assert_eq!(out.read::<u32>().unwrap(), [7, 8, 9, 10, 11]);
    });
}
