//! The light tree (`--light-selection tree`: src/render/light_tree.rs,
//! glsl/light_tree.glsl): next-event estimation picks an emissive triangle with a
//! probability that depends on the receiving point and normal, and every estimator's MIS
//! takes that probability for the direct pdf of an emitter hit and of a light subpath's
//! start (glsl/mis_weights.glsl, glsl/subpath.glsl), while light subpaths still start by
//! power. So the image must not change: on glossy_floor_scene with a point light and 300
//! small emitters facing every way, pt with the tree, and bpt and vcm with the tree
//! against pt picking by power, per pixel (Welch test at 1e-3, Šidák over the pixels) and
//! on the image mean (a t-test of 16 blocks per render, 1e-3 Šidák over the three
//! comparisons: a bias of a percent over the image hides in per-pixel noise). (Not pt
//! without NEE: BSDF sampling cannot reach the point light, which keeps the tree's
//! other-lights branch in use.)
//! A wrong pdf (the tree's probability at an emitter hit 0.9 times the descent's, or
//! the pdf without the normal bound that the descent uses) fails the pt comparison.
//! tests/mis_weights.rs checks the weights of every technique of a path sum to 1 with
//! the tree. Lavapipe, validation on.

mod common;

use common::scenes::*;
use common::{image_mean, render_stats, with_gpu, TestRender, IMAGE_MEAN_BLOCKS};
use glam::Vec3;
use vkvcm::render::light_tree::LightTree;
use vkvcm::render::{Algorithm, LightSelection};
use vkvcm::scene::{Light, Material, Scene};
use vkvcm_tools::stats::{image_mean_test, sidak, welch_test, MeanEstimate};

const W: u32 = 32;
const H: u32 = 32;
const MAX_PATH_LENGTH: u32 = 4;

/// glossy_floor_scene (its lamp too) with a point light and 300 small emitters.
fn cloud_scene() -> Scene {
    let floor = Material { name: "floor".into(), diffuse: Vec3::new(0.6, 0.5, 0.4), ..Default::default() };
    let glossy = Material {
        name: "glossy".into(),
        diffuse: Vec3::new(0.2, 0.3, 0.4),
        glossy: Vec3::splat(0.5),
        roughness: 0.3,
        ..Default::default()
    };
    let mut s = glossy_floor_scene(floor, glossy);
    s.lights.push(Light::Point { position: Vec3::new(-0.5, 0.5, 1.2), intensity: Vec3::splat(0.5) });
    add_emitter_cloud(&mut s, 300, 11);
    s.name = "emitter cloud".into();
    s
}

#[test]
fn the_tree_holds_every_area_light_once() {
    let s = cloud_scene();
    let t = LightTree::new(&s).unwrap();
    let area = s.lights.iter().filter(|l| matches!(l, Light::Area { .. })).count();
    assert_eq!(t.nodes.len(), 2 * area - 1);
    let mut leaves: Vec<u32> = t.nodes.iter().map(|n| n.links[3]).filter(|&l| l != u32::MAX).collect();
    leaves.sort();
    let want: Vec<u32> =
        s.lights.iter().enumerate().filter(|(_, l)| matches!(l, Light::Area { .. })).map(|(i, _)| i as u32).collect();
    assert_eq!(leaves, want);
    // Links: each child names its parent; a node's power is its children's.
    for (i, n) in t.nodes.iter().enumerate() {
        if n.links[0] != u32::MAX {
            for c in [n.links[0], n.links[1]] {
                let child = &t.nodes[c as usize];
                assert_eq!(child.links[2], i as u32);
                for k in 0..3 {
                    assert!(child.min_power[k] >= n.min_power[k] && child.max_cos_o[k] <= n.max_cos_o[k]);
                }
            }
            let sum = t.nodes[n.links[0] as usize].min_power[3] + t.nodes[n.links[1] as usize].min_power[3];
            assert!((sum - n.min_power[3]).abs() <= 1e-4 * n.min_power[3]);
        }
    }
    // The point light is picked outside the tree with (nearly all) the rest of the power.
    let p = t.p_tree + t.other_prob.iter().sum::<f32>();
    assert!((p - 1.0).abs() < 1e-5, "p_tree + others = {p}");
}

#[test]
fn tree_selection_matches_power_selection() {
    let scene = cloud_scene();
    let run = |algo, iterations, seed, selection| {
        TestRender::new(algo, W, H, iterations)
            .seed(seed)
            .max_path_length(MAX_PATH_LENGTH)
            .independent()
            .light_selection(selection)
    };
    with_gpu(|gpu| {
        let stats_and_mean = |r: TestRender| {
            let (out, blocks) = r.blocks(gpu, &scene, IMAGE_MEAN_BLOCKS);
            (render_stats(&out, None), MeanEstimate::of_blocks(&blocks).unwrap())
        };
        let (pt, pt_mean) = stats_and_mean(run(Algorithm::Pt, 512, 81, LightSelection::Power));
        assert!(image_mean(&pt) > 0.02, "the scene rendered (almost) black");
        for (what, (other, other_mean)) in [
            ("PT, tree", stats_and_mean(run(Algorithm::Pt, 512, 82, LightSelection::Tree))),
            ("BPT, tree", stats_and_mean(run(Algorithm::Bpt, 256, 83, LightSelection::Tree))),
            ("VCM, tree", stats_and_mean(run(Algorithm::Vcm, 256, 84, LightSelection::Tree))),
        ] {
            let m = image_mean_test(pt_mean, other_mean);
            eprintln!("PT by power vs {what}: {m}");
            let t = welch_test(&pt, &other, 1e-3).unwrap();
            assert!(t.passed(), "PT by power vs {what}: {t}");
            assert!(m.p >= sidak(1e-3, 3), "PT by power vs {what}: {m}");
        }
    });
}

/// The GPU's descent against its pdf (glsl/tests/light_tree.comp) at 16 random points
/// and normals (a quarter without a normal) of cloud_scene, M = 4096 stratified draws
/// each: every draw's probability is nee_light_prob of the light drawn (to float
/// rounding, 1e-4 relative: the descent multiplies the per-node factors root first, the
/// pdf leaf first), each light's share of the draws is its nee_light_prob (within 4 / M:
/// the u of one light form one interval in the tree, a few in the alias table of the
/// other lights, so stratified draws miss its probability by at most that many 1 / M),
/// and the probabilities sum to at most 1 (less only where no light can shine).
#[test]
fn gpu_descent_follows_the_pdf() {
    use vkvcm::gpu::{groups_2d, Bind};
    use vkvcm::render::gpu_types::GpuPush;
    use vkvcm::render::reads::Reads;
    use vkvcm::render::{FrameSettings, SceneGpu};
    let scene = cloud_scene();
    let (queries, m) = (16usize, 4096usize);
    let lights = scene.lights.len();
    assert!(lights <= m);
    let out: Vec<[f32; 4]> = with_gpu(|gpu| {
        let frame = FrameSettings {
            width: 4,
            height: 4,
            seed: 5,
            max_path_length: 4,
            min_path_length: 0,
            light_selection: LightSelection::Tree,
        };
        let sg = SceneGpu::new(gpu, &scene, &frame, Reads::resolve(gpu, None).unwrap()).unwrap();
        assert!(sg.variant.light_tree);
        let count = (queries * m) as u32;
        let results = gpu.buffer_zeroed::<[f32; 4]>("tree_results", count as usize).unwrap();
        let mut binds = sg.binds();
        binds.push(Bind::own(&results));
        let kernel = gpu.kernel("tests/light_tree.comp", &sg.variant.defines().pairs(), &binds).unwrap();
        let push = GpuPush { count, light_paths: m as u32, ..Default::default() };
        let mut batch = gpu.batch().unwrap();
        batch.dispatch(&kernel, groups_2d(count, 64), bytemuck::bytes_of(&push)).unwrap();
        batch.submit_wait(None).unwrap();
        results.read::<[f32; 4]>().unwrap()
    });
    for q in 0..queries {
        let draws = &out[q * m..(q + 1) * m];
        let mut count = vec![0usize; lights];
        for (j, [li, prob, pdf, _]) in draws.iter().enumerate() {
            let li = li.to_bits();
            if li == u32::MAX {
                assert_eq!(*prob, 0.0, "query {q} draw {j}: no light but probability {prob}");
                continue;
            }
            count[li as usize] += 1;
            assert!((prob - pdf).abs() <= 1e-4 * prob, "query {q} draw {j}: light {li} drawn with {prob}, pdf {pdf}");
        }
        let pdf: Vec<f64> = draws[..lights].iter().map(|d| d[3] as f64).collect();
        for (i, (&c, &p)) in count.iter().zip(&pdf).enumerate() {
            let f = c as f64 / m as f64;
            assert!((f - p).abs() <= 4.0 / m as f64, "query {q} light {i}: drawn {f}, pdf {p}");
        }
        let total: f64 = pdf.iter().sum();
        assert!(total <= 1.0 + 1e-5 && total > 0.5, "query {q}: probabilities sum to {total}");
    }
}

/// Next-event estimation through the tree against BSDF sampling alone (no light pick at
/// all) on cloud_scene without its point light (which BSDF sampling cannot reach): pt
/// with the tree against pt without NEE, per pixel (Welch test at 1e-3) and on the
/// image mean (blocks, 1e-3).
#[test]
fn tree_nee_matches_bsdf_sampling() {
    let mut scene = cloud_scene();
    scene.lights.retain(|l| matches!(l, Light::Area { .. }));
    let run =
        |seed| TestRender::new(Algorithm::Pt, W, H, 512).seed(seed).max_path_length(MAX_PATH_LENGTH).independent();
    with_gpu(|gpu| {
        let stats_and_mean = |r: TestRender| {
            let (out, blocks) = r.blocks(gpu, &scene, IMAGE_MEAN_BLOCKS);
            (render_stats(&out, None), MeanEstimate::of_blocks(&blocks).unwrap())
        };
        let (tree, tree_mean) = stats_and_mean(run(91).light_selection(LightSelection::Tree));
        let (bsdf, bsdf_mean) = stats_and_mean(run(92).nee(false));
        let m = image_mean_test(tree_mean, bsdf_mean);
        eprintln!("PT with the tree vs PT without NEE: {m}");
        let t = welch_test(&tree, &bsdf, 1e-3).unwrap();
        assert!(t.passed(), "PT with the tree vs PT without NEE: {t}");
        assert!(m.p >= 1e-3, "PT with the tree vs PT without NEE: {m}");
    });
}
