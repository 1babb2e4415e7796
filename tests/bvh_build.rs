//! CPU tests of the BVH build and of the CPU traversal (the GPU traversal's reference).

mod bvh_common;

use bvh_common::*;
use glam::Vec3;
use rand::Rng;
use vkvcm::bvh::build::tree_stats;
use vkvcm::bvh::layout::{decode_ref, dequantize_boxes, quantize_boxes};
use vkvcm::bvh::{
    brute_force_any, brute_force_closest, build, build_with, Aabb, BuildOptions, Bvh, LeafRule, Ray, SplitMethod,
    MAX_DEPTH, MAX_LEAF_PRIMS, SIZE_LEAF_RULE_MIN_PRIMS,
};
use vkvcm::scene::{Sphere, Triangle};

fn prim_box(bvh: &Bvh, slot: usize) -> Aabb {
    let p = &bvh.prims[slot];
    if p.is_sphere() {
        let c = Vec3::new(p.a[0], p.a[1], p.a[2]);
        Aabb { min: c - p.b[0], max: c + p.b[0] }
    } else {
        let v = p.vertices();
        Aabb { min: v[0].min(v[1]).min(v[2]), max: v[0].max(v[1]).max(v[2]) }
    }
}

/// Structural invariants: every prim in exactly one leaf and inside every (decoded) box
/// on its root-to-leaf path, leaf sizes and depth bounded, node 0 is the root, every node
/// reached once.
fn check_structure(bvh: &Bvh) {
    let mut prim_seen = vec![0u32; bvh.prims.len()];
    let mut node_seen = vec![0u32; bvh.nodes.len()];
    let all = Aabb { min: Vec3::NEG_INFINITY, max: Vec3::INFINITY };
    // (node, level, intersection of the boxes on the path)
    let mut stack = vec![(0u32, 1u32, all)];
    let mut max_level = 0;
    while let Some((ni, level, path)) = stack.pop() {
        assert!(level <= MAX_DEPTH);
        max_level = max_level.max(level);
        node_seen[ni as usize] += 1;
        let n = &bvh.nodes[ni as usize];
        for i in 0..2 {
            let b = n.bounds(i);
            let path = Aabb { min: path.min.max(b.min), max: path.max.min(b.max) };
            match decode_ref(n.child(i)) {
                Ok(c) => stack.push((c, level + 1, path)),
                Err((first, count)) => {
                    assert!(count as usize <= MAX_LEAF_PRIMS);
                    for s in first..first + count {
                        prim_seen[s as usize] += 1;
                        assert!(path.contains(&prim_box(bvh, s as usize)), "prim escapes a box on its path");
                    }
                }
            }
        }
    }
    assert!(prim_seen.iter().all(|&c| c == 1), "a prim is not in exactly one leaf");
    assert!(node_seen.iter().all(|&c| c == 1), "a node is not reached exactly once");
    assert_eq!(max_level, bvh.stats.max_depth);
}

/// Each original triangle and sphere appears exactly once among the prims.
fn check_ids(bvh: &Bvh, tris: &[Triangle], spheres: &[Sphere], skipped: usize) {
    let mut t = vec![0u32; tris.len()];
    let mut s = vec![0u32; spheres.len()];
    for p in &bvh.prims {
        if p.is_sphere() {
            s[p.id() as usize] += 1;
            assert_eq!(p.material(), spheres[p.id() as usize].material);
        } else {
            t[p.id() as usize] += 1;
            assert_eq!(p.vertices(), tris[p.id() as usize].p);
            assert_eq!(p.material(), tris[p.id() as usize].material);
        }
    }
    let missing = t.iter().chain(&s).filter(|&&c| c == 0).count();
    assert!(t.iter().chain(&s).all(|&c| c <= 1));
    assert_eq!(missing, skipped);
    assert_eq!(bvh.stats.skipped_non_finite, skipped);
}

#[test]
fn structure_of_random_scene() {
    let s = test_scene(1, 20_000, 500);
    let bvh = build(&s.triangles, &s.spheres);
    check_structure(&bvh);
    check_ids(&bvh, &s.triangles, &s.spheres, 0);
}

/// Quantised node boxes contain the input boxes, are not much larger, and decode the
/// same way as the builder checked them, for boxes of all scales and signs.
#[test]
fn quantised_boxes_are_conservative_and_tight() {
    let mut r = rng(20);
    let mut worst = 0.0f32;
    for k in 0..200_000 {
        let scale = 10f32.powi(r.random_range(-30..30));
        let offset = 10f32.powi(r.random_range(-30..30)) * if k % 2 == 0 { 1.0 } else { -1.0 };
        let mut boxes = [Aabb::EMPTY; 2];
        for b in boxes.iter_mut() {
            let p = rand_vec(&mut r, -1.0, 1.0) * scale + Vec3::splat(offset);
            let q = rand_vec(&mut r, -1.0, 1.0) * scale + Vec3::splat(offset);
            *b = Aabb { min: p.min(q), max: p.max(q) };
            if k % 7 == 0 {
                b.max = b.min; // flat or point boxes
            }
        }
        let dec = dequantize_boxes(quantize_boxes(boxes));
        let node = boxes[0].union(&boxes[1]);
        for i in 0..2 {
            assert!(dec[i].contains(&boxes[i]), "{boxes:?} -> {dec:?}");
            // Looser than the input by at most a few grid steps (1/255 of the node, plus
            // the origin's 16-bit rounding).
            let slack = (dec[i].extent() - boxes[i].extent()) / (node.extent() + node.min.abs() * 1e-4 + 1e-37);
            worst = worst.max(slack.max_element());
        }
    }
    println!("worst loosening: {worst} of the node extent");
    assert!(worst < 0.03);
}

#[test]
fn tiny_scenes() {
    let mut r = rng(2);
    for nt in 0..7 {
        for ns in 0..3 {
            let tris = triangle_soup(&mut r, nt);
            let spheres = random_spheres(&mut r, ns);
            let bvh = build(&tris, &spheres);
            check_structure(&bvh);
            check_ids(&bvh, &tris, &spheres, 0);
            let gpu = bvh.to_gpu();
            for _ in 0..200 {
                let ray = Ray { o: rand_vec(&mut r, -2.0, 2.0), d: rand_dir(&mut r) };
                let want = brute_force_closest(&tris, &spheres, &ray, 0.0, f32::INFINITY);
                let got = gpu.closest_hit(&ray, 0.0, f32::INFINITY);
                assert_eq!(got.is_some(), want.is_some());
                if let (Some(g), Some(w)) = (got, want) {
                    assert_eq!((g.prim, g.is_sphere, g.t), (w.prim, w.is_sphere, w.t));
                }
            }
        }
    }
}

#[test]
fn non_finite_prims_are_skipped() {
    let mut r = rng(3);
    let mut tris = triangle_soup(&mut r, 3000);
    let mut spheres = random_spheres(&mut r, 100);
    let nan = f32::NAN;
    for k in (0..3000).step_by(97) {
        tris[k].p[k % 3].y = if k % 2 == 0 { nan } else { f32::INFINITY };
    }
    spheres[5].radius = nan;
    spheres[17].center.x = f32::NEG_INFINITY;
    // Finite, but the centroid sum overflows.
    tris[1].p = [Vec3::splat(f32::MAX), Vec3::splat(f32::MAX * 0.99), Vec3::new(f32::MAX, f32::MAX * 0.98, f32::MAX)];
    let skipped = 3000usize.div_ceil(97) + 2 + 1;
    let bvh = build(&tris, &spheres);
    check_structure(&bvh);
    check_ids(&bvh, &tris, &spheres, skipped);
    assert!(bvh.bounds().min.is_finite() && bvh.bounds().max.is_finite());
    assert!(bvh.stats.sah_cost.is_finite());
    let gpu = bvh.to_gpu();
    let mut finite_tris = tris.clone();
    finite_tris[1].p[0] = Vec3::NAN; // the brute force skips only non-finite prims
    for _ in 0..2000 {
        let ray = Ray { o: rand_vec(&mut r, -2.0, 2.0), d: rand_dir(&mut r) };
        let want = brute_force_closest(&finite_tris, &spheres, &ray, 0.0, f32::INFINITY);
        let got = gpu.closest_hit(&ray, 0.0, f32::INFINITY);
        assert_eq!(got.map(|h| (h.prim, h.is_sphere)), want.map(|h| (h.prim, h.is_sphere)));
    }
}

#[test]
fn coincident_prims_and_depth_bound() {
    // Many identical triangles (no SAH split possible) and a geometric sequence of
    // positions (SAH would peel one prim per level): depth must stay within MAX_DEPTH.
    let t = Triangle { p: [Vec3::ZERO, Vec3::X, Vec3::Y], n: None, material: 0, attributes: None };
    let mut tris = vec![t; 5000];
    for i in 0..20_000 {
        let x = 1.5f32.powi(i % 200) * 1e-20;
        let s = x * 0.01;
        tris.push(Triangle {
            p: [Vec3::new(x, 0.0, 0.0), Vec3::new(x + s, 0.0, 0.0), Vec3::new(x, s, (i / 200) as f32)],
            n: None,
            material: 1,
            attributes: None,
        });
    }
    let bvh = build(&tris, &[]);
    check_structure(&bvh);
    check_ids(&bvh, &tris, &[], 0);
    assert!(bvh.stats.max_depth <= MAX_DEPTH);
}

#[test]
fn sah_beats_median_split() {
    let mut r = rng(4);
    // A clustered scene: SAH matters most when density varies.
    let mut tris = triangle_soup(&mut r, 20_000);
    for t in tris.iter_mut().take(15_000) {
        for p in t.p.iter_mut() {
            *p = *p * 0.1 + Vec3::new(0.7, 0.7, 0.0);
        }
    }
    let spheres = random_spheres(&mut r, 200);
    let sah = build(&tris, &spheres);
    let median = build_with(&tris, &spheres, &BuildOptions { method: SplitMethod::Median, ..Default::default() });
    check_structure(&median);
    let (_, _, median_cost) = tree_stats(&median, 1.0, 1.0);
    println!(
        "SAH cost {:.2} (depth {}), median {:.2} (depth {})",
        sah.stats.sah_cost, sah.stats.max_depth, median_cost, median.stats.max_depth
    );
    assert!(sah.stats.sah_cost < median_cost * 0.95);
}

/// `a` and `b` are the same BVH, bit for bit (nodes, primitives, and so the statistics).
fn assert_same_bvh(a: &Bvh, b: &Bvh, what: &str) {
    let first_diff = |x: usize, y: usize| x.min(y);
    if a.nodes != b.nodes {
        let i = (0..first_diff(a.nodes.len(), b.nodes.len())).find(|&i| a.nodes[i] != b.nodes[i]);
        panic!("{what}: node arrays differ ({} vs {} nodes, first difference at {i:?})", a.nodes.len(), b.nodes.len());
    }
    if a.prims != b.prims {
        let i = (0..first_diff(a.prims.len(), b.prims.len())).find(|&i| a.prims[i] != b.prims[i]);
        panic!("{what}: primitive arrays differ (first difference at {i:?})");
    }
    assert_eq!(a.stats.sah_cost.to_bits(), b.stats.sah_cost.to_bits(), "{what}: SAH cost");
    assert_eq!((a.stats.leaves, a.stats.max_depth), (b.stats.leaves, b.stats.max_depth), "{what}");
}

/// Meshes for the determinism tests: ordinary, degenerate and tiny, some large enough for
/// the builder's parallel paths (subtrees as tasks from 8k primitives, parallel binning
/// from 128k).
fn determinism_cases() -> Vec<(&'static str, Vec<Triangle>, Vec<Sphere>)> {
    let mut r = rng(30);
    let s = test_scene(5, 100_000, 1000);
    let same = Triangle { p: [Vec3::ZERO, Vec3::X, Vec3::Y], n: None, material: 0, attributes: None };
    let mut depth_guard = vec![same.clone(); 5000];
    for i in 0..20_000 {
        let x = 1.5f32.powi(i % 200) * 1e-20;
        depth_guard.push(Triangle {
            p: [Vec3::new(x, 0.0, 0.0), Vec3::new(x * 1.01, 0.0, 0.0), Vec3::new(x, x * 0.01, (i / 200) as f32)],
            n: None,
            material: 1,
            attributes: None,
        });
    }
    let one_sphere = vec![Sphere { center: Vec3::ONE, radius: 0.5, material: 3 }];
    vec![
        ("soup of 100k triangles and 1k spheres", s.triangles, s.spheres),
        ("163,840 triangles of 640 UV spheres", vkvcm_tools::bench::traverse::sphere_grid([8, 8, 10]), Vec::new()),
        ("60k triangles with one centroid", vec![same.clone(); 60_000], Vec::new()),
        ("5k coincident + 20k geometric sequence (depth guard)", depth_guard, Vec::new()),
        ("no primitive", Vec::new(), Vec::new()),
        ("1 triangle", vec![same], Vec::new()),
        ("1 sphere", Vec::new(), one_sphere.clone()),
        ("3 triangles and 1 sphere", triangle_soup(&mut r, 3), one_sphere),
        ("9 triangles", triangle_soup(&mut r, 9), Vec::new()),
    ]
}

/// Every thread count builds the serial build's BVH, bit for bit: same splits, same node
/// order, same primitive order.
#[test]
fn parallel_build_is_the_serial_build() {
    for (what, tris, spheres) in determinism_cases() {
        let serial = build_with(&tris, &spheres, &BuildOptions { threads: 1, ..Default::default() });
        check_structure(&serial);
        check_ids(&serial, &tris, &spheres, 0);
        for threads in [2, 3, 8] {
            let parallel = build_with(&tris, &spheres, &BuildOptions { threads, ..Default::default() });
            assert_same_bvh(&serial, &parallel, &format!("{what}, {threads} threads"));
        }
        // The size rule (the default for large scenes) too.
        let by_size = |threads| BuildOptions { threads, leaf_rule: LeafRule::Size, ..Default::default() };
        let serial_by_size = build_with(&tris, &spheres, &by_size(1));
        check_structure(&serial_by_size);
        check_ids(&serial_by_size, &tris, &spheres, 0);
        for threads in [2, 8] {
            let parallel = build_with(&tris, &spheres, &by_size(threads));
            assert_same_bvh(&serial_by_size, &parallel, &format!("{what}, size rule, {threads} threads"));
        }
        // `threads: 0` builds on the caller's rayon pool, whatever its size.
        for pool_threads in [1, 2, 4] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(pool_threads).build().unwrap();
            let in_pool = pool.install(|| build(&tris, &spheres));
            assert_same_bvh(&serial, &in_pool, &format!("{what}, pool of {pool_threads}"));
        }
    }
}

/// The median-split baseline is deterministic across thread counts too.
#[test]
fn parallel_median_build_is_the_serial_build() {
    let s = test_scene(31, 50_000, 500);
    let opts = |threads| BuildOptions { threads, method: SplitMethod::Median, ..Default::default() };
    let serial = build_with(&s.triangles, &s.spheres, &opts(1));
    check_structure(&serial);
    assert_same_bvh(&serial, &build_with(&s.triangles, &s.spheres, &opts(4)), "median split, 4 threads");
}

/// With the SAH leaf rule the tree is the one the serial builder made before the build was
/// parallelised (commit ce99580, `threads: 1`): CRC-32 of the node and primitive arrays of
/// the 1M-triangle `displaced` scene, whose mesh needs no libm function (only sqrt and
/// floor, exact everywhere). The default build of that mesh (over
/// `SIZE_LEAF_RULE_MIN_PRIMS` primitives: the size rule) is pinned too, so that a change
/// of either tree, and so of rendered images, is noticed.
#[test]
fn tree_unchanged_since_the_serial_builder() {
    let scene = vkvcm_tools::bench::traverse::scene_displaced();
    assert!(scene.triangles.len() >= SIZE_LEAF_RULE_MIN_PRIMS);
    let sah =
        build_with(&scene.triangles, &scene.spheres, &BuildOptions { leaf_rule: LeafRule::Sah, ..Default::default() });
    assert_eq!((sah.nodes.len(), sah.prims.len()), (543_136, 1_002_252));
    assert_eq!(format!("{:08x}", vkvcm_tools::bench::build::checksum(&sah)), "dda26bfc");
    let default = build(&scene.triangles, &scene.spheres);
    assert_eq!((default.nodes.len(), default.prims.len()), (302_975, 1_002_252));
    assert_eq!(format!("{:08x}", vkvcm_tools::bench::build::checksum(&default)), "3a840532");
}

/// Primitives below each internal node (index = node), from the leaves up.
fn subtree_prims(bvh: &Bvh) -> Vec<u32> {
    let mut below = vec![0u32; bvh.nodes.len()];
    // Preorder: every child has a larger index than its parent.
    for ni in (0..bvh.nodes.len()).rev() {
        let n = &bvh.nodes[ni];
        below[ni] = (0..2)
            .map(|i| match decode_ref(n.child(i)) {
                Ok(c) => below[c as usize],
                Err((_, count)) => count,
            })
            .sum();
    }
    below
}

/// The size rule makes every node of at most `max_leaf` primitives a leaf (no internal
/// node but the root has that few below it), where the SAH rule splits some of them; the
/// automatic rule is the SAH rule below `SIZE_LEAF_RULE_MIN_PRIMS` primitives.
#[test]
fn leaf_rules() {
    let s = test_scene(41, 20_000, 200);
    let with = |leaf_rule| build_with(&s.triangles, &s.spheres, &BuildOptions { leaf_rule, ..Default::default() });
    let (sah, size, auto) = (with(LeafRule::Sah), with(LeafRule::Size), with(LeafRule::Auto));
    for bvh in [&sah, &size] {
        check_structure(bvh);
        check_ids(bvh, &s.triangles, &s.spheres, 0);
    }
    let small = |bvh: &Bvh| subtree_prims(bvh).iter().skip(1).filter(|&&n| n as usize <= MAX_LEAF_PRIMS).count();
    assert_eq!(small(&size), 0, "the size rule split a node of at most {MAX_LEAF_PRIMS} primitives");
    assert!(small(&sah) > 0, "the SAH rule split no small node: the test cannot tell the rules apart");
    assert!(size.nodes.len() < sah.nodes.len());
    assert_same_bvh(&sah, &auto, "automatic rule on 20,200 primitives");
}

#[test]
fn cpu_traversal_matches_brute_force() {
    let s = test_scene(6, 3000, 300);
    for leaf_rule in [LeafRule::Auto, LeafRule::Size] {
        let bvh = build_with(&s.triangles, &s.spheres, &BuildOptions { leaf_rule, ..Default::default() });
        cpu_traversal_matches_brute_force_on(&s, &bvh);
    }
}

fn cpu_traversal_matches_brute_force_on(s: &TestScene, bvh: &Bvh) {
    let gpu = bvh.to_gpu();
    let rays = test_rays(s, 7, 3000);
    let mut errors = Vec::new();
    let mut hits = 0;
    for (ray, tmin, tmax) in &rays {
        let want = brute_force_closest(&s.triangles, &s.spheres, ray, *tmin, *tmax);
        let got = gpu.closest_hit(ray, *tmin, *tmax);
        hits += want.is_some() as usize;
        if let Err(e) = check_hit(s, "cpu bvh", ray, got, want) {
            errors.push(e);
        }
        let any = gpu.any_hit(ray, *tmin, *tmax);
        let any_bf = brute_force_any(&s.triangles, &s.spheres, ray, *tmin, *tmax);
        if any != want.is_some() || any_bf != want.is_some() {
            errors.push(format!("any-hit disagrees {ray:?}: {any} {any_bf} {want:?}"));
        }
    }
    assert!(errors.is_empty(), "{} of {} rays: {:#?}", errors.len(), rays.len(), &errors[..errors.len().min(10)]);
    assert!(hits > rays.len() / 3, "too few hits: {hits}");
}

#[test]
fn icosphere_is_watertight_on_cpu() {
    let s = test_scene(8, 0, 0);
    let bvh = build(&s.triangles, &s.spheres);
    let mut r = rng(9);
    let ico = &s.triangles[s.ico.clone()];
    let mut dirs: Vec<Vec3> = Vec::new();
    for t in ico {
        for e in 0..3 {
            dirs.push(t.p[e] - s.ico_center);
            dirs.push(0.5 * (t.p[e] + t.p[(e + 1) % 3]) - s.ico_center);
            let f = r.random_range(0.0f32..1.0);
            dirs.push(t.p[e].lerp(t.p[(e + 1) % 3], f) - s.ico_center);
        }
    }
    for _ in 0..20_000 {
        dirs.push(rand_dir(&mut r));
    }
    for d in dirs {
        let ray = Ray { o: s.ico_center, d };
        let h = bvh.closest_hit(&ray, 0.0, f32::INFINITY);
        let h = h.unwrap_or_else(|| panic!("ray escaped the icosphere: {ray:?}"));
        assert!(s.ico.contains(&(h.prim as usize)));
    }
}

#[test]
fn build_one_million_triangles() {
    let scene = vkvcm_tools::bench::traverse::scene_spheres();
    assert_eq!(scene.triangles.len(), 1 << 20);
    let serial = build_with(&scene.triangles, &scene.spheres, &BuildOptions { threads: 1, ..Default::default() });
    let bvh = build(&scene.triangles, &scene.spheres);
    println!(
        "1M triangles: {:.2} s on 1 thread, {:.2} s on all; {} nodes, depth {}, SAH {:.1}",
        serial.stats.build_seconds, bvh.stats.build_seconds, bvh.stats.nodes, bvh.stats.max_depth, bvh.stats.sah_cost
    );
    check_structure(&bvh);
    assert_eq!(bvh.prims.len(), 1 << 20);
    assert_same_bvh(&serial, &bvh, "1M triangles, all threads");
}

/// The two-level BVH (instances over per-mesh trees) against the brute force over the
/// same scene flattened into world space: the same closest primitive (instance and
/// triangle) for every ray, at the same distance up to float rounding (the instanced
/// traversal intersects in object space: 1e-4 in distance is a few ulps of the transform
/// of coordinates up to 10), and any-hit agreeing. Rays leaving closed instances from inside all hit.
#[test]
fn instanced_bvh_matches_the_flattened_brute_force() {
    let s = instanced_scene(41, 24);
    let bvh = vkvcm::bvh::build_scene(&s, &BuildOptions::default());
    assert_eq!(bvh.stats.instances, 24);
    // The mesh trees build in parallel: the arrays must not depend on the thread count.
    let serial = vkvcm::bvh::build_scene(&s, &BuildOptions { threads: 1, ..Default::default() });
    assert!(serial.nodes == bvh.nodes && serial.prims == bvh.prims, "the thread count changed the BVH");
    let flat = s.flattened_triangles();
    let origin = flattened_origin(&s);
    let rays = instanced_rays(&s, 42, 20_000);
    let inside = rays.len() - 20_000;
    let mut errors = Vec::new();
    let mut hits = 0;
    for (k, (ray, tmin, tmax)) in rays.iter().enumerate() {
        let got = bvh.closest_hit(ray, *tmin, *tmax);
        let want = brute_force_closest(&flat, &s.spheres, ray, *tmin, *tmax);
        if k >= 20_000 && got.is_none() {
            errors.push(format!("ray {k} from inside a closed instance escaped: {ray:?}"));
        }
        if bvh.any_hit(ray, *tmin, *tmax) != got.is_some() {
            errors.push(format!("ray {k}: any-hit disagrees with closest {got:?}"));
        }
        match (got, want) {
            (None, None) => {}
            (Some(g), Some(w)) => {
                hits += 1;
                let want_id = if w.is_sphere { (None, w.prim) } else { origin[w.prim as usize] };
                let same_prim = g.is_sphere == w.is_sphere && (g.instance, g.prim) == want_id;
                let distance = (g.t - w.t).abs() * ray.d.length();
                // Another primitive at the same distance (a shared edge) is fine.
                if distance > 1e-4 || (!same_prim && distance > 1e-6) {
                    errors.push(format!("ray {k}: got {g:?}, want {w:?} = {want_id:?}"));
                }
            }
            (g, w) => errors.push(format!("ray {k}: got {g:?}, want {w:?}")),
        }
    }
    println!("{} rays ({inside} from inside instances), {hits} hits", rays.len());
    assert!(errors.is_empty(), "{} of {} rays: {:#?}", errors.len(), rays.len(), &errors[..errors.len().min(10)]);
    assert!(hits > rays.len() / 8);
}

/// Instancing stores a mesh once: 64 instances of a 5120-triangle mesh take about the
/// memory of one mesh plus 64 instance primitives and records, against 64 meshes
/// flattened.
#[test]
fn instanced_bvh_stores_each_mesh_once() {
    use glam::Affine3A;
    use vkvcm::scene::{Camera, Instance, LoadReport, Scene, SharedMesh};
    let ico = vkvcm_tools::bench::traverse::icosphere(Vec3::ZERO, 1.0, 4, 0);
    let n = ico.len() as u32;
    let instances: Vec<Instance> = (0..64)
        .map(|k| Instance {
            mesh: 0,
            object_to_world: Affine3A::from_translation(Vec3::new((k % 8) as f32 * 3.0, (k / 8) as f32 * 3.0, 0.0)),
        })
        .collect();
    let s = Scene {
        name: "ico x 64".into(),
        triangles: ico,
        meshes: vec![SharedMesh { name: "ico".into(), first: 0, count: n }],
        instances,
        spheres: vec![],
        materials: vec![],
        lights: vec![],
        camera: Camera { position: Vec3::ZERO, forward: Vec3::NEG_Z, up: Vec3::Y, yfov: 1.0 },
        report: LoadReport::default(),
        images: vec![],
    };
    let instanced = vkvcm::bvh::build_scene(&s, &BuildOptions::default()).into_gpu().size_bytes();
    let flat = build(&s.flattened_triangles(), &[]).into_gpu().size_bytes();
    let ratio = instanced as f64 / flat as f64;
    println!("instanced {instanced} bytes, flattened {flat} bytes: {ratio:.4} (1/64 = {:.4})", 1.0 / 64.0);
    assert!(ratio < 1.2 / 64.0, "instanced BVH is {ratio} of the flattened one");
}

/// The uploaded 4-wide form ([`vkvcm::bvh::layout::widen`]) against the BVH2 it is made
/// from, both traversed on the CPU: the same hits at the same distances (another primitive
/// only where two meet, within 1e-6 of the hit's distance: the two traversals test leaves
/// in different orders)
/// and the same any-hits, on trees of both leaf rules, a deep tree, tiny trees and a
/// two-level tree; and no more wide nodes than `max_wide_nodes` allows for.
#[test]
fn wide_form_matches_bvh2() {
    use vkvcm::bvh::layout::max_wide_nodes;
    let check = |what: &str, bvh: &Bvh, rays: &[(Ray, f32, f32)], trees: u64| {
        let gpu = bvh.to_gpu();
        assert!(
            gpu.nodes.len() as u64 <= max_wide_nodes(bvh.prims.len() as u64, trees),
            "{what}: {} wide nodes",
            gpu.nodes.len()
        );
        assert!(gpu.nodes.len() < bvh.nodes.len().max(2), "{what}: the wide form is not smaller");
        let (mut hits, mut ties, mut visits, mut visits2) = (0, 0, 0u64, 0u64);
        for (k, (ray, tmin, tmax)) in rays.iter().enumerate() {
            let (got, c) = vkvcm::bvh::traverse::closest_hit_counted(&gpu.nodes[..], &gpu.prims, ray, *tmin, *tmax);
            let (want, c2) = vkvcm::bvh::traverse::closest_hit_counted(&bvh.nodes[..], &bvh.prims, ray, *tmin, *tmax);
            (visits, visits2) = (visits + c.nodes as u64, visits2 + c2.nodes as u64);
            assert_eq!(gpu.any_hit(ray, *tmin, *tmax), bvh.any_hit(ray, *tmin, *tmax), "{what}: ray {k} any-hit");
            match (got, want) {
                (None, None) => {}
                (Some(g), Some(w)) => {
                    hits += 1;
                    // Another primitive: where two meet (the test rays aim at shared edges and
                    // vertices), each traversal may keep the one it tested first. "Meet" is
                    // within float precision, which is relative: 1e-6 of the hit's distance
                    // along the ray (the deep tree's triangles span sizes from 1e-22 to 1e13,
                    // its rays ten triangle sizes long).
                    let same = (g.prim, g.is_sphere, g.instance) == (w.prim, w.is_sphere, w.instance);
                    let distance = (g.t - w.t).abs() * ray.d.length();
                    let scale = 1.0 + g.t.max(w.t) * ray.d.length();
                    assert!(
                        if same { g.t == w.t } else { distance <= 1e-6 * scale },
                        "{what}: ray {k}: {g:?} against {w:?}"
                    );
                    ties += !same as usize;
                }
                (g, w) => panic!("{what}: ray {k}: {g:?} against {w:?}"),
            }
        }
        println!(
            "{what}: {} rays, {hits} hits ({ties} another primitive at the same distance), node visits 4-wide / BVH2 {:.3}",
            rays.len(),
            visits as f64 / visits2.max(1) as f64
        );
        hits
    };
    let s = test_scene(17, 20_000, 500);
    let rays = test_rays(&s, 18, 20_000);
    for leaf_rule in [LeafRule::Auto, LeafRule::Size] {
        let bvh = build_with(&s.triangles, &s.spheres, &BuildOptions { leaf_rule, ..Default::default() });
        assert!(check(&format!("{leaf_rule:?} leaves"), &bvh, &rays, 1) > rays.len() / 10);
    }
    let mut r = rng(19);
    for nt in 0..7 {
        let tris = triangle_soup(&mut r, nt);
        let spheres = random_spheres(&mut r, 1);
        // Random rays: few hit these few primitives, but the trees are only a node or two.
        let rays: Vec<_> = (0..300)
            .map(|_| (Ray { o: rand_vec(&mut r, -2.0, 2.0), d: rand_dir(&mut r) }, 0.0, f32::INFINITY))
            .collect();
        check(&format!("{nt} triangles and a sphere"), &build(&tris, &spheres), &rays, 1);
    }
    // A deep tree: small triangles at a geometric sequence of positions (as
    // coincident_prims_and_depth_bound, but each triangle flat in its own z plane: that
    // test's slivers, 1e-5 wide and 30 long, meet the triangle test's float rounding, which
    // reports hits outside them, kept or culled depending on the traversal's order).
    let tris: Vec<Triangle> = (0..20_000)
        .map(|i| {
            let x = 1.5f32.powi(i % 200) * 1e-20;
            let s = x * 0.01;
            let z = (i / 200) as f32;
            Triangle {
                p: [Vec3::new(x, 0.0, z), Vec3::new(x + s, 0.0, z), Vec3::new(x, s, z)],
                n: None,
                material: 0,
                attributes: None,
            }
        })
        .collect();
    let deep = build(&tris, &[]);
    println!("deep tree: {} levels", deep.stats.max_depth);
    // Rays aimed at random triangles from ten times their size away.
    let rays: Vec<_> = (0..5000)
        .map(|_| {
            let t = &tris[r.random_range(0..tris.len())];
            let c = (t.p[0] + t.p[1] + t.p[2]) / 3.0;
            let o = c + rand_dir(&mut r) * 10.0 * (t.p[1] - t.p[0]).length();
            (Ray { o, d: c - o }, 0.0, f32::INFINITY)
        })
        .collect();
    assert!(check("deep tree", &deep, &rays, 1) > rays.len() / 10);
    let s = instanced_scene(41, 24);
    let bvh = vkvcm::bvh::build_scene(&s, &BuildOptions::default());
    let rays = instanced_rays(&s, 42, 20_000);
    assert!(check("instances", &bvh, &rays, 1 + s.meshes.len() as u64) > rays.len() / 10);
}

/// glsl/bvh.glsl's traversal stack holds what src/bvh/layout.rs proves it needs.
#[test]
fn glsl_stack_size_is_the_layouts() {
    use vkvcm::bvh::layout::{MAX_STACK, MAX_STACK_INSTANCED};
    let src = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/glsl/bvh.glsl")).unwrap();
    let sizes: Vec<usize> = src
        .lines()
        .filter_map(|l| l.trim().strip_prefix("#define BVH_STACK_SIZE "))
        .map(|v| v.trim().parse().unwrap())
        .collect();
    assert_eq!(sizes, [MAX_STACK_INSTANCED, MAX_STACK], "BVH_STACK_SIZE with and without BVH_INSTANCES");
}
