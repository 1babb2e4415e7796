//! Shared test helpers: a validated GPU (any validation message fails), small scenes.
#![allow(dead_code)]

pub mod corpus;
pub mod ggx;
pub mod instanced_gltf;
pub mod iridescence;
pub mod scenes;
pub mod sheen;

use std::sync::Arc;

use vkvcm::gpu::{Gpu, GpuOptions};

/// Runs `f` with a validation-enabled GPU with the test suite's kernel cache or none
/// ([`GpuOptions::for_tests`]); fails if the layer said anything, including at device
/// destruction (leaked objects).
pub fn with_gpu<R>(f: impl FnOnce(&Arc<Gpu>) -> R) -> R {
    with_gpu_options(&GpuOptions::for_tests(), f)
}

/// [`with_gpu`] with `opts` (which must turn validation on).
pub fn with_gpu_options<R>(opts: &GpuOptions, f: impl FnOnce(&Arc<Gpu>) -> R) -> R {
    let gpu = Gpu::new(opts).expect("cannot open a Vulkan device for tests");
    assert!(gpu.validation_enabled());
    let messages = gpu.validation_messages();
    let r = f(&gpu);
    assert_eq!(Arc::strong_count(&gpu), 1, "a GPU object outlived the test body");
    drop(gpu);
    let list = messages.list();
    assert!(list.is_empty(), "Vulkan validation messages:\n{}", list.join("\n"));
    r
}

/// Whether `gpu` has the feature `feature` (a name of src/gpu/context.rs's list, e.g.
/// `vkvcm::gpu::SHADER_INT64_ATOMICS`). Where it lacks it, the test `test` (or the part of
/// it that needs the feature) is skipped, never failed: [`skip`] says so.
pub fn device_has(gpu: &Gpu, feature: &str, test: &str) -> bool {
    let has = gpu.has(feature);
    if !has {
        skip(test, &format!("device {:?} lacks {feature}", gpu.info.name));
    }
    has
}

/// Records that `test` was skipped for `reason`: `skipped: <test>: <reason>` on stderr
/// (shown with --nocapture) and, where `VKVCM_TEST_SKIP_LOG` names a file, appended to it,
/// so that `make test` can count and list the skips (Makefile, test-swiftshader).
pub fn skip(test: &str, reason: &str) {
    let line = format!("skipped: {test}: {reason}");
    eprintln!("{line}");
    if let Some(path) = std::env::var_os("VKVCM_TEST_SKIP_LOG") {
        use std::io::Write;
        let file = std::fs::OpenOptions::new().create(true).append(true).open(&path);
        if let Err(e) = file.and_then(|mut f| writeln!(f, "{line}")) {
            panic!("cannot append to VKVCM_TEST_SKIP_LOG {path:?}: {e}");
        }
    }
}

/// `VKVCM_CACHE_DIR` for a test's `vkvcm` process: the suite's kernel cache
/// (`VKVCM_TEST_KERNEL_CACHE`, an absolute path, which `make test` sets: see
/// [`GpuOptions::for_tests`]) when there is one, else `own` (a folder of the test's, or ""
/// for none). Never the user's cache.
pub fn cli_cache_dir(own: impl AsRef<std::ffi::OsStr>) -> std::ffi::OsString {
    match GpuOptions::for_tests().kernel_cache {
        Some(suite) => suite.into_os_string(),
        None => own.as_ref().to_os_string(),
    }
}

/// `vkvcm` run in `dir` as the CLI tests run it: validation on, no injected faults, the
/// suite's kernel cache (or one of the test's own), lavapipe unless the environment names
/// a driver.
pub fn vkvcm_in(dir: &std::path::Path) -> std::process::Command {
    let mut c = std::process::Command::new(env!("CARGO_BIN_EXE_vkvcm"));
    c.current_dir(dir).env("VKVCM_VALIDATION", "1").env_remove("VKVCM_TEST_FAIL_AFTER_BATCHES");
    c.env("VKVCM_CACHE_DIR", cli_cache_dir(dir.join("kernel-cache")));
    if std::env::var_os("VK_DRIVER_FILES").is_none() {
        c.env("VK_DRIVER_FILES", "/usr/share/vulkan/icd.d/lvp_icd.json");
    }
    c
}

/// Runs test kernel `path` (glsl/; its bindings named `test_input`, read, and `test_output`, one `O`
/// written per input element; push constant: the element count) over `input`.
pub fn run_test_kernel<I: bytemuck::Pod, O: bytemuck::Pod>(gpu: &Arc<Gpu>, path: &str, input: &[I]) -> Vec<O> {
    let inp = gpu.buffer_from_slice("test_input", input).unwrap();
    let out = gpu.buffer_zeroed::<O>("test_output", input.len()).unwrap();
    let k = gpu.kernel(path, &[], &[vkvcm::gpu::Bind::own(&inp), vkvcm::gpu::Bind::own(&out)]).unwrap();
    let n = input.len() as u32;
    let mut batch = gpu.batch().unwrap();
    batch.dispatch(&k, k.groups_for(n), bytemuck::bytes_of(&n)).unwrap();
    batch.submit_wait(None).unwrap();
    out.read().unwrap()
}

/// The mean over pixels and channels of a render's per-pixel means.
pub fn image_mean(s: &vkvcm_tools::stats::PixelStats) -> f64 {
    s.mean.iter().map(|c| c[0] + c[1] + c[2]).sum::<f64>() / (3 * s.mean.len()) as f64
}

/// Per-pixel statistics of one render, from its per-iteration sums (K = iterations).
/// Pixels where `mask` is false are zeroed (equal means, zero variance: they pass).
pub fn render_stats(out: &vkvcm::render::RenderOutput, mask: Option<&[bool]>) -> vkvcm_tools::stats::PixelStats {
    let (mut sum, mut sum_sq) = (out.sum.clone(), out.sum_sq.clone());
    if let Some(m) = mask {
        for i in 0..sum.len() {
            if !m[i] {
                sum[i] = [0.0; 3];
                sum_sq[i] = [0.0; 3];
            }
        }
    }
    let mut stats =
        vkvcm_tools::stats::PixelStats::from_sums(out.width, out.height, out.iterations as usize, &sum, &sum_sq)
            .expect("render statistics");
    // The film rounds each iteration's value and its square to 2^-FILM_FRACTION_BITS
    // (src/render/film.rs), so the second moment is known only to within half that per
    // iteration: a pixel whose samples are all below ~2^-16 shows zero variance (then any
    // two different means fail at z = inf). Add the bound, so such near-black pixels are
    // compared with their real uncertainty; next to a visible pixel's variance it is nothing.
    let bound = (-vkvcm::render::film::FILM_FRACTION_BITS as f64).exp2();
    for v in &mut stats.variance {
        *v = v.map(|x| x + bound);
    }
    stats
}

/// The reference-scene x estimator cases of the tests that check an image does not depend
/// on a setting which must not change it (tests/render_regen.rs, tests/render_reads.rs):
/// every light-subpath and camera estimator on glm_c (area light: light tracing's emitter
/// connections), bpt there with both connection strategies; lt, bpt and vcm on gbs_s
/// (directional light); pt and vcm on gbs_b (camera paths that escape to the
/// background), vcm there with SmallVCM's connections (`path`) and elsewhere with its
/// default (the light-vertex cache).
/// `(scene name, estimator, where bpt and vcm connect)`.
pub fn invariance_cases() -> Vec<(&'static str, vkvcm::render::Algorithm, vkvcm::render::Connect)> {
    use vkvcm::render::Algorithm::*;
    use vkvcm::render::Connect;
    let d = |a: vkvcm::render::Algorithm| a.default_connect();
    vec![
        ("glm_c", Pt, d(Pt)),
        ("glm_c", Lt, d(Lt)),
        ("glm_c", Bpt, Connect::Path),
        ("glm_c", Bpt, d(Bpt)),
        ("glm_c", Ppm, d(Ppm)),
        ("glm_c", Bpm, d(Bpm)),
        ("glm_c", Vcm, d(Vcm)),
        ("gbs_s", Lt, d(Lt)),
        ("gbs_s", Bpt, d(Bpt)),
        ("gbs_s", Vcm, d(Vcm)),
        ("gbs_b", Pt, d(Pt)),
        ("gbs_b", Vcm, Connect::Path),
    ]
}

/// Pixels of a `width` x `height` render of `scene` whose camera rays, at 9 positions
/// spread over the pixel, all hit a surface whose material passes `keep` (traced on the
/// CPU with the BVH).
pub fn primary_hit_mask(
    scene: &vkvcm::scene::Scene,
    width: u32,
    height: u32,
    keep: impl Fn(&vkvcm::scene::Material) -> bool,
) -> Vec<bool> {
    let bvh = vkvcm::bvh::build(&scene.triangles, &scene.spheres).into_gpu();
    let cam = &scene.camera;
    let forward = cam.forward.normalize();
    let right = forward.cross(cam.up).normalize();
    let up = right.cross(forward);
    let plane = height as f32 / (2.0 * (0.5 * cam.yfov).tan());
    let mut mask = vec![true; (width * height) as usize];
    for y in 0..height {
        for x in 0..width {
            for (a, b) in [0.02f32, 0.5, 0.98].iter().flat_map(|a| [0.02f32, 0.5, 0.98].map(|b| (*a, b))) {
                let (rx, ry) = (x as f32 + a, y as f32 + b);
                let d =
                    (forward * plane + right * (rx - 0.5 * width as f32) + up * (0.5 * height as f32 - ry)).normalize();
                let hit = bvh.closest_hit(&vkvcm::bvh::Ray { o: cam.position, d }, 0.0, f32::INFINITY);
                mask[(y * width + x) as usize] &= hit.is_some_and(|h| keep(&scene.materials[h.material as usize]));
            }
        }
    }
    mask
}

/// The Mitsuba 3 reference `stem` of tests/env/ (scripts/env_reference.py,
/// scripts/texture_reference.py): per-pixel statistics of its independent renders, from
/// their mean and unbiased variance images (`STEM_mean.exr`, `STEM_var.exr`) and their
/// count (`seeds` in `STEM.json`).
pub fn mitsuba_reference(stem: &str) -> vkvcm_tools::stats::PixelStats {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/env");
    let meta: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join(format!("{stem}.json"))).unwrap()).unwrap();
    let k = meta["seeds"].as_u64().expect("seeds") as usize;
    let (mean, _) = vkvcm::image::read_exr(&dir.join(format!("{stem}_mean.exr"))).unwrap();
    let (var, _) = vkvcm::image::read_exr(&dir.join(format!("{stem}_var.exr"))).unwrap();
    let sum: Vec<[f64; 3]> = mean.data.iter().map(|m| m.map(|x| x as f64 * k as f64)).collect();
    let sum_sq: Vec<[f64; 3]> = mean
        .data
        .iter()
        .zip(&var.data)
        .map(|(m, v)| [0, 1, 2].map(|c| (k - 1) as f64 * v[c] as f64 + k as f64 * (m[c] as f64).powi(2)))
        .collect();
    vkvcm_tools::stats::PixelStats::from_sums(mean.width, mean.height, k, &sum, &sum_sq).unwrap()
}

/// Renders `scene` with each of `cases` (estimator, iterations) at the reference's size
/// with at most `max_path_length` segments and tests it against the Mitsuba 3 reference
/// `stem`: per pixel (Welch test, the reference's renders as its samples, ALPHA 1e-3
/// Šidák-corrected), and the image mean (every pixel and channel) at 1e-3 by
/// [`vkvcm_tools::stats::image_mean_test`].
pub fn assert_matches_mitsuba(
    gpu: &Arc<Gpu>,
    scene: &vkvcm::scene::Scene,
    stem: &str,
    max_path_length: u32,
    cases: &[(vkvcm::render::Algorithm, u64)],
) {
    use vkvcm::render::{Budget, RenderSettings};
    let reference = mitsuba_reference(stem);
    for &(algo, iterations) in cases {
        assert!(iterations % IMAGE_MEAN_BLOCKS == 0, "{stem}: {iterations} iterations in {IMAGE_MEAN_BLOCKS} blocks");
        let mut s = RenderSettings::new(algo, reference.width, reference.height, Budget::Iterations(iterations));
        s.frame.max_path_length = max_path_length;
        s.frame.seed = 5;
        // The Welch test takes the render's iterations as independent samples. With the
        // Sobol sampler they are stratified, and the film's per-pixel variance is then no
        // estimate of the error: a feature covering less than 1/N of a pixel's sample
        // space can be missed by all N points, with variance 0 (seen: vcm at a pixel
        // whose footprint on an environment map is 0.25 but for a sliver, 0.25 +- 0 in
        // 256 iterations against Mitsuba's 0.24952 +- 4e-5). tests/sampler.rs checks the
        // Sobol sampler against this one.
        s.sampler = Some(vkvcm::render::Sampler::Independent);
        // The iterations in blocks of one film, so that the blocks' image means (disjoint
        // iterations: independent) give the image mean's standard error.
        let (out, block_means) = TestRender(s).blocks(gpu, scene, IMAGE_MEAN_BLOCKS);
        let st = render_stats(&out, None);
        vkvcm_tools::stats::welch_test(&st, &reference, 1e-3)
            .unwrap()
            .assert_passed(&format!("{stem}_{}", algo.name()));
        use vkvcm_tools::stats::{image_mean_test, MeanEstimate};
        let m = image_mean_test(
            MeanEstimate::of_blocks(&block_means).unwrap(),
            MeanEstimate::of_independent_pixels(&reference).unwrap(),
        );
        eprintln!("{stem} {}: {m}", algo.name());
        assert!(m.p >= 1e-3, "{stem} {}: {m}, below 1e-3", algo.name());
    }
}

/// Blocks of iterations whose image means [`assert_matches_mitsuba`] compares.
pub const IMAGE_MEAN_BLOCKS: u64 = 16;

/// A small render test's settings, built up by name where a test would otherwise pass
/// a row of positional numbers: `TestRender::new(Algorithm::Pt, 20, 20, 1024).seed(51)
/// .max_path_length(2).nee(false).stats(gpu, &scene)`; what is not set is
/// `RenderSettings::new`'s.
pub struct TestRender(pub vkvcm::render::RenderSettings);

impl TestRender {
    pub fn new(algo: vkvcm::render::Algorithm, width: u32, height: u32, iterations: u64) -> Self {
        let budget = vkvcm::render::Budget::Iterations(iterations);
        TestRender(vkvcm::render::RenderSettings::new(algo, width, height, budget))
    }
    pub fn seed(mut self, seed: u32) -> Self {
        self.0.frame.seed = seed;
        self
    }
    pub fn max_path_length(mut self, segments: u32) -> Self {
        self.0.frame.max_path_length = segments;
        self
    }
    pub fn light_selection(mut self, selection: vkvcm::render::LightSelection) -> Self {
        self.0.frame.light_selection = selection;
        self
    }
    pub fn nee(mut self, on: bool) -> Self {
        self.0.nee = on;
        self
    }
    /// Independent random numbers (the per-pixel tests' samples), not the estimator's
    /// default sampler.
    pub fn independent(mut self) -> Self {
        self.0.sampler = Some(vkvcm::render::Sampler::Independent);
        self
    }
    /// [`render_checked`] with these settings.
    pub fn output(&self, gpu: &Arc<Gpu>, scene: &vkvcm::scene::Scene) -> vkvcm::render::RenderOutput {
        render_checked(gpu, scene, &self.0)
    }
    /// The render's iterations in `blocks` equal blocks of one film (the iterations a
    /// multiple of `blocks`): its output and the image mean (every pixel and channel) of
    /// each block, independent estimates whatever correlates the render's pixels.
    pub fn blocks(
        &self,
        gpu: &Arc<Gpu>,
        scene: &vkvcm::scene::Scene,
        blocks: u64,
    ) -> (vkvcm::render::RenderOutput, Vec<f64>) {
        let vkvcm::render::Budget::Iterations(iterations) = self.0.budget else { panic!("blocks of a timed render") };
        assert!(iterations % blocks == 0, "{iterations} iterations in {blocks} blocks");
        let per_block = iterations / blocks;
        let mut r = vkvcm::render::Renderer::new(gpu, scene, &self.0).unwrap();
        let (mut block_means, mut before) = (Vec::new(), 0.0);
        loop {
            r.run(vkvcm::render::Budget::Iterations(per_block), None, &mut |_| {}).unwrap();
            let out = r.output().unwrap();
            let total: f64 = out.sum.iter().flatten().sum();
            block_means.push((total - before) / (3 * out.sum.len()) as f64 / per_block as f64);
            before = total;
            if out.iterations == iterations {
                assert_eq!(out.rejected_samples, 0, "{} {:?}: rejected samples", scene.name, self.0.algorithm);
                assert_eq!(out.overflow_splats, 0, "{} {:?}: overflowing splats", scene.name, self.0.algorithm);
                return (out, block_means);
            }
        }
    }
    /// Per-pixel statistics of [`TestRender::output`] ([`render_stats`]).
    pub fn stats(&self, gpu: &Arc<Gpu>, scene: &vkvcm::scene::Scene) -> vkvcm_tools::stats::PixelStats {
        render_stats(&self.output(gpu, scene), None)
    }
}

/// A material lobe's estimators agree on a closed scene, per pixel (Welch test at
/// 1e-3) and on the image mean (a t-test of [`IMAGE_MEAN_BLOCKS`] blocks of each render,
/// 1e-3 Šidák-corrected over the three comparisons: a bias of a percent or two over the
/// whole image hides in per-pixel noise), paths of at most `max_path_length` segments at
/// `width` x `height`, independent random numbers: pt with NEE (`iterations`) against pt
/// without it (`iterations`: bsdf_eval's pdf is the density bsdf_sample draws), bpt (half
/// as many: the reverse pdfs of its MIS) and light tracing (`iterations`: the adjoint BSDF
/// on light subpaths).
pub fn assert_estimators_agree(
    gpu: &Arc<Gpu>,
    scene: &vkvcm::scene::Scene,
    width: u32,
    height: u32,
    max_path_length: u32,
    iterations: u64,
) {
    use vkvcm::render::Algorithm::{Bpt, Lt, Pt};
    use vkvcm_tools::stats::{image_mean_test, sidak, welch_test, MeanEstimate};
    let run = |algo, iterations, seed| {
        TestRender::new(algo, width, height, iterations).seed(seed).max_path_length(max_path_length).independent()
    };
    let stats_and_mean = |r: TestRender| {
        let (out, blocks) = r.blocks(gpu, scene, IMAGE_MEAN_BLOCKS);
        (render_stats(&out, None), MeanEstimate::of_blocks(&blocks).unwrap())
    };
    let (pt, pt_mean) = stats_and_mean(run(Pt, iterations, 71));
    assert!(image_mean(&pt) > 0.02, "{}: the scene rendered (almost) black", scene.name);
    for (what, (other, other_mean)) in [
        ("PT without NEE", stats_and_mean(run(Pt, iterations, 72).nee(false))),
        ("BPT", stats_and_mean(run(Bpt, iterations / 2, 73))),
        ("LT", stats_and_mean(run(Lt, iterations, 74))),
    ] {
        let m = image_mean_test(pt_mean, other_mean);
        eprintln!("{}: PT vs {what}: {m}", scene.name);
        let t = welch_test(&pt, &other, 1e-3).unwrap();
        assert!(t.passed(), "{}: PT vs {what}: {t}", scene.name);
        assert!(m.p >= sidak(1e-3, 3), "{}: PT vs {what}: {m}", scene.name);
    }
}

/// A material's textures scale its factors per point: PT on `textured` against PT on
/// `factors` (the same scene with the textured products as constant factors), and BPT on
/// `textured` against PT on `factors` (light vertices carry the point's values), per pixel
/// (Welch test at 1e-3) and on the image mean (blocks, as [`assert_estimators_agree`]),
/// 1024 iterations each of independent random numbers, paths of at most 4 segments.
pub fn assert_textures_match_factors(
    gpu: &Arc<Gpu>,
    textured: &vkvcm::scene::Scene,
    factors: &vkvcm::scene::Scene,
    width: u32,
    height: u32,
) {
    use vkvcm::render::Algorithm::{Bpt, Pt};
    use vkvcm_tools::stats::{image_mean_test, sidak, welch_test, MeanEstimate};
    let run = |algo, seed, scene| {
        let r = TestRender::new(algo, width, height, 1024).seed(seed).max_path_length(4).independent();
        let (out, blocks) = r.blocks(gpu, scene, IMAGE_MEAN_BLOCKS);
        (render_stats(&out, None), MeanEstimate::of_blocks(&blocks).unwrap())
    };
    let (pt_tex, pt_tex_mean) = run(Pt, 81, textured);
    let (pt_factors, pt_factors_mean) = run(Pt, 82, factors);
    let (bpt_tex, bpt_tex_mean) = run(Bpt, 83, textured);
    for (what, a, a_mean, b, b_mean) in [
        ("PT textured vs its factors", &pt_tex, pt_tex_mean, &pt_factors, pt_factors_mean),
        ("PT factors vs BPT textured", &pt_factors, pt_factors_mean, &bpt_tex, bpt_tex_mean),
    ] {
        let m = image_mean_test(a_mean, b_mean);
        eprintln!("{}: {what}: {m}", textured.name);
        let t = welch_test(a, b, 1e-3).unwrap();
        assert!(t.passed(), "{}: {what}: {t}", textured.name);
        assert!(m.p >= sidak(1e-3, 2), "{}: {what}: {m}", textured.name);
    }
}

/// A render's per-pixel statistics against known values (an analytic answer or a CPU
/// quadrature): the one-sample test at 1e-3 over the pixels that have a value (`None`:
/// left out, e.g. a pixel the object covers only in part).
pub fn assert_matches_values(st: &vkvcm_tools::stats::PixelStats, values: &[Option<[f32; 3]>], what: &str) {
    let mut expected = vkvcm::image::Image::filled(st.width, st.height, [0.0; 3]);
    let mut masked = st.clone();
    for (i, v) in values.iter().enumerate() {
        match v {
            Some(v) => expected.data[i] = *v,
            None => {
                masked.mean[i] = [0.0; 3];
                masked.variance[i] = [0.0; 3];
            }
        }
    }
    let t = vkvcm_tools::stats::one_sample_test(&masked, &expected, 1e-3).unwrap();
    assert!(t.passed(), "{what}: {t}");
}

/// A white furnace returns no more than it receives: no pixel (of those `keep` holds, all
/// without a mask) and channel above 1 by more than its one-sided z at 1e-3 Šidák-corrected
/// over the image's tests. Returns the brightest of them.
pub fn assert_no_pixel_above_one(st: &vkvcm_tools::stats::PixelStats, keep: Option<&[bool]>, what: &str) -> f64 {
    use vkvcm_tools::stats::{inverse_normal_cdf, sidak};
    let z = inverse_normal_cdf(1.0 - sidak(1e-3, 3 * st.mean.len()));
    let mut brightest = 0.0f64;
    for (i, (m, v)) in st.mean.iter().zip(&st.variance).enumerate() {
        if keep.is_some_and(|k| !k[i]) {
            continue;
        }
        for c in 0..3 {
            let se = (v[c] / st.count as f64).sqrt();
            brightest = brightest.max(m[c]);
            assert!(m[c] <= 1.0 + z * se + 1e-6, "{what}: a pixel returns {} +- {se} > 1", m[c]);
        }
    }
    brightest
}

/// `render::render` of `scene` with `s`, failing on rejected samples or overflowing splats.
pub fn render_checked(
    gpu: &Arc<Gpu>,
    scene: &vkvcm::scene::Scene,
    s: &vkvcm::render::RenderSettings,
) -> vkvcm::render::RenderOutput {
    let out = vkvcm::render::render(gpu, scene, s, None, &mut |_| {}).unwrap();
    assert_eq!(out.rejected_samples, 0, "{} {:?}: rejected samples", scene.name, s.algorithm);
    assert_eq!(out.overflow_splats, 0, "{} {:?}: overflowing splats", scene.name, s.algorithm);
    out
}

/// tests/khronos/Box.gltf with a camera of aspectRatio 2 (yfov 0.7) at (0, 0, 4), written
/// to `dir`/wide.gltf: a frame whose default size follows the camera (512 x 256).
pub fn wide_camera_box(dir: &std::path::Path) -> std::path::PathBuf {
    let src = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/khronos/Box.gltf");
    let mut doc: serde_json::Value = serde_json::from_slice(&std::fs::read(src).unwrap()).unwrap();
    doc["cameras"] =
        serde_json::json!([{"type": "perspective", "perspective": {"yfov": 0.7, "aspectRatio": 2.0, "znear": 0.1}}]);
    doc["nodes"].as_array_mut().unwrap().push(serde_json::json!({"camera": 0, "translation": [0.0, 0.0, 4.0]}));
    let n = doc["nodes"].as_array().unwrap().len() - 1;
    doc["scenes"][0]["nodes"].as_array_mut().unwrap().push(serde_json::json!(n));
    let file = dir.join("wide.gltf");
    std::fs::write(&file, serde_json::to_vec(&doc).unwrap()).unwrap();
    file
}
