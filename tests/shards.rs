//! Shards and their exact merge (docs/distributed.md).
//!
//! * For every estimator, the films of the N shards of a 16x16 render of 7 iterations
//!   (N = 1, 2, 3, 7) add up to the film of the render on one device bit for bit, and so
//!   does the mean image computed from them. A shard's iterations keep their global
//!   indices (random numbers, merge radius): a shard renumbered from 0 would repeat the
//!   first iterations and differ by Monte Carlo noise.
//! * The CLI: `render --shard K/N` files merged by `vkvcm merge` give the one-device
//!   file's channels bit for bit (vcm, 3 shards, fresh processes); and each refusal
//!   (different seed, shard count, scene; a shard twice; a missing shard unless
//!   --partial; a truncated or foreign EXR) exits with its code and names the file.
//! * A reference split with `reference --shard K/N` and merged is the one-machine
//!   reference bit for bit, its two-halves errors included (N = 1, 2, 3); merge's
//!   refusals and --partial for reference shards; `converge` on reference shards, on
//!   their merge, and split over its estimators (--shard, --rows).
//! * The film's precision: a constant value summed 600 times gives that value back
//!   exactly (a float32 sum drifts: docs/distributed.md).

mod common;

use std::path::Path;
use std::sync::Arc;

use common::{vkvcm_in, with_gpu};
use vkvcm::gpu::Gpu;
use vkvcm::render::film::FilmSums;
use vkvcm::render::settings::ALGORITHMS;
use vkvcm::render::shard::{IterationSet, Shard};
use vkvcm::render::{Algorithm, Budget, RenderOutput, RenderSettings, Renderer};
use vkvcm::scene::Scene;

const SIZE: u32 = 16;
const ITERATIONS: u64 = 7;

fn settings(algo: Algorithm) -> RenderSettings {
    RenderSettings::new(algo, SIZE, SIZE, Budget::Iterations(ITERATIONS))
}

/// Renders the `shard` of `r`'s settings from an empty film.
fn render_shard(r: &mut Renderer, shard: Shard) -> RenderOutput {
    let range = shard.range(ITERATIONS);
    r.resume(&FilmSums::zero((SIZE * SIZE) as usize), &IterationSet::new(), 0.0).unwrap();
    r.start_at(range.start);
    r.run(Budget::Iterations(range.end - range.start), None, &mut |_| {}).unwrap();
    let out = r.output().unwrap();
    assert_eq!(out.held, IterationSet::of(range), "shard {shard}");
    out
}

fn merge_matches_one_render(gpu: &Arc<Gpu>, scene: &Scene, algo: Algorithm) {
    let s = settings(algo);
    let full = vkvcm::render::render(gpu, scene, &s, None, &mut |_| {}).unwrap();
    assert!(full.sums.sum.iter().flatten().any(|&q| q > 0), "{}: black image", algo.name());
    // One renderer renders the shards one after another, as a device does with
    // --devices; separate processes are checked by the CLI test below.
    let mut r = Renderer::new(gpu, scene, &s).unwrap();
    for n in [1u32, 2, 3, 7] {
        let mut sums = FilmSums::zero((SIZE * SIZE) as usize);
        let mut held = IterationSet::new();
        // In reverse order: the merge does not depend on it.
        for k in (0..n).rev() {
            let out = render_shard(&mut r, Shard { index: k, count: n });
            sums.add(&out.sums).unwrap();
            held.union(&out.held).unwrap();
        }
        assert_eq!(held, IterationSet::of(0..ITERATIONS));
        let what = format!("{}, {n} shards", algo.name());
        let differing = sums.sum.iter().zip(&full.sums.sum).filter(|(a, b)| a != b).count();
        assert_eq!(differing, 0, "{what}: {differing} pixels' sums differ from one render");
        assert!(sums.sum_sq == full.sums.sum_sq, "{what}: sums of squares differ");
        let bits = |p: &[[f32; 3]]| p.iter().flatten().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&sums.mean(ITERATIONS)), bits(&full.pixels), "{what}: mean image differs");
    }
}

#[test]
fn merged_shards_are_the_one_device_render_bit_for_bit() {
    // Lit by its background, which every estimator (ppm too) sees in 7 iterations.
    let scene = vkvcm::scene::load_named("gbs_b").unwrap();
    with_gpu(|gpu| {
        for algo in ALGORITHMS {
            merge_matches_one_render(gpu, &scene, algo);
        }
    });
}

/// A constant per-pixel value (an emitter seen directly through a black box: every
/// iteration's value is exactly 135/255) comes back exactly after 600 iterations, and
/// its square's sum is 600 times the rounded square.
#[test]
fn the_film_sums_a_constant_exactly() {
    use common::scenes::{area_lights, camera, inward_box, scene};
    use glam::Vec3;
    use vkvcm::scene::Material;
    let le = 135.0f32 / 255.0;
    let mat = Material { name: "lamp".into(), diffuse: Vec3::ZERO, emission: Vec3::splat(le), ..Default::default() };
    let tris = inward_box(1.0, 0);
    let lights = area_lights(&tris, std::slice::from_ref(&mat));
    let cam = camera(Vec3::new(0.1, -0.2, 0.05), Vec3::new(0.3, 1.0, 0.2), Vec3::Z, 70.0);
    let sc = scene("lamp box", tris, vec![mat], lights, cam);
    let n = 600u64;
    let out = with_gpu(|gpu| {
        let mut s = RenderSettings::new(Algorithm::Pt, 4, 4, Budget::Iterations(n));
        s.frame.max_path_length = 1;
        vkvcm::render::render(gpu, &sc, &s, None, &mut |_| {}).unwrap()
    });
    let q = (le as f64 * 2f64.powi(32)) as u128;
    let q2 = ((le * le) as f64 * 2f64.powi(32)).round() as u128;
    for (i, p) in out.pixels.iter().enumerate() {
        assert_eq!(*p, [le; 3], "pixel {i}: the mean of {n} equal values is not that value");
        assert_eq!(out.sums.sum[i], [q * n as u128; 3], "pixel {i}");
        assert_eq!(out.sums.sum_sq[i], [q2 * n as u128; 3], "pixel {i}");
    }
    // What the float32 film without compensation would give: visibly off.
    let naive = (0..n).fold(0f32, |s, _| s + le) / n as f32;
    assert_ne!(naive, le, "the test would not tell an exact sum from a naive one");
}

fn run(dir: &Path, args: &[&str]) -> (i32, String) {
    let out = vkvcm_in(dir).args(args).output().unwrap();
    (out.status.code().unwrap_or(-1), String::from_utf8_lossy(&out.stderr).into_owned())
}

fn render_cli(dir: &Path, out: &str, extra: &[&str]) {
    let scene = if extra.contains(&"gbs_p") { "gbs_p" } else { "gbs_s" };
    let extra: Vec<&str> = extra.iter().copied().filter(|a| *a != "gbs_p").collect();
    let mut args = vec!["render", scene, "-q", "--width", "8", "--height", "8", "-o", out];
    args.extend_from_slice(&extra);
    let (code, err) = run(dir, &args);
    assert_eq!(code, 0, "render {scene} {extra:?}: {err}");
}

#[test]
fn cli_merge_is_exact_and_refuses_what_it_cannot_merge() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let base = ["--algo", "vcm", "-i", "5"];
    render_cli(d, "full.exr", &base);
    for k in 0..3 {
        let shard = format!("{k}/3");
        render_cli(d, &format!("s{k}.exr"), &[&base[..], &["--shard", &shard]].concat());
    }
    let (code, err) = run(d, &["merge", "s2.exr", "s0.exr", "s1.exr", "-o", "m.exr", "--png", "m.png"]);
    assert_eq!(code, 0, "{err}");
    let (code, err) = run(d, &["diff", "--exact", "m.exr", "full.exr"]);
    assert_eq!(code, 0, "merged and one-device render differ: {err}");
    assert!(d.join("m.png").exists());

    // The refusals: usage errors (2), another scene (3); each names a file.
    render_cli(d, "seed.exr", &[&base[..], &["--shard", "1/3", "--seed", "9"]].concat());
    render_cli(d, "four.exr", &[&base[..], &["--shard", "1/4"]].concat());
    render_cli(d, "gbs_p.exr", &["gbs_p", "--algo", "vcm", "-i", "5", "--shard", "1/3"]);
    let bytes = std::fs::read(d.join("s1.exr")).unwrap();
    std::fs::write(d.join("cut.exr"), &bytes[..bytes.len() / 2]).unwrap();
    vkvcm::image::write_exr(&d.join("plain.exr"), &vkvcm::image::Image::new(8, 8), &[]).unwrap();
    let cases: [(&[&str], i32, &[&str]); 8] = [
        (&["s0.exr", "seed.exr", "s2.exr"], 2, &["seed.exr", "--seed 9"]),
        (&["s0.exr", "four.exr", "s2.exr"], 2, &["four.exr", "shard counts"]),
        (&["s0.exr", "s1.exr", "s1.exr", "s2.exr"], 2, &["s1.exr", "both shard 1/3"]),
        (&["s0.exr", "s2.exr"], 2, &["1/3", "missing", "--partial"]),
        (&["s0.exr", "cut.exr", "s2.exr"], 2, &["cut.exr"]),
        (&["s0.exr", "plain.exr"], 2, &["plain.exr"]),
        (&["s0.exr", "full.exr"], 2, &["full.exr", "not a shard"]),
        (&["s0.exr", "gbs_p.exr", "s2.exr"], 3, &["gbs_p.exr", "scene"]),
    ];
    for (files, want, needles) in cases {
        let mut args = vec!["merge"];
        args.extend_from_slice(files);
        args.extend_from_slice(&["-o", "bad.exr"]);
        let (code, err) = run(d, &args);
        assert_eq!(code, want, "merge {files:?}: {err}");
        for n in needles {
            assert!(err.contains(n), "merge {files:?}: {n:?} not in {err:?}");
        }
        assert!(!d.join("bad.exr").exists(), "merge {files:?} wrote an output");
    }
    // --partial merges what there is and says what is missing.
    let (code, err) = run(d, &["merge", "s0.exr", "s2.exr", "-o", "part.exr", "--partial"]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("holds 3 of the render's 5 iterations") && err.contains("missing: 1-2"), "{err}");
    let part = vkvcm::render::saved::read_render_exr(&d.join("part.exr")).unwrap();
    assert_eq!(part.held.to_string(), "0,3-4");
}

/// `vkvcm` in `dir`: exit code, stdout, stderr.
fn run_out(dir: &Path, args: &[&str]) -> (i32, String, String) {
    let out = vkvcm_in(dir).args(args).output().unwrap();
    let text = |b: &[u8]| String::from_utf8_lossy(b).into_owned();
    (out.status.code().unwrap_or(-1), text(&out.stdout), text(&out.stderr))
}

/// The line of `text` with the reference's two-halves error estimate.
fn error_line(text: &str) -> &str {
    text.lines().find(|l| l.starts_with("its own error estimate")).unwrap_or_else(|| panic!("none in {text:?}"))
}

/// The EXR's R, G, B bits and its attributes but the (per-run) seconds.
fn reference_bits(p: &Path) -> (Vec<u32>, Vec<(String, String)>) {
    let (img, meta) = vkvcm::image::read_exr(p).unwrap();
    let meta = meta.into_iter().filter(|(k, _)| k != "vkvcm:seconds").collect();
    (img.data.iter().flatten().map(|v| v.to_bits()).collect(), meta)
}

/// `vkvcm reference --shard K/N` and `vkvcm merge`: the merge of all N shards is the file
/// `vkvcm reference` writes on one machine, pixels and attributes (its two-halves
/// errors among them) bit for bit, and so is what both print, for N = 1, 2, 3 (vcm,
/// whose merge radius follows the global iteration index). Then the refusals, a partial
/// merge, and `vkvcm converge` on reference shards, on their merge, and split with
/// --shard and joined with --rows.
#[test]
fn cli_reference_shards_merge_into_the_one_machine_reference() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let base = ["reference", "gbs_s", "-a", "vcm", "--width", "8", "--height", "8", "-i", "6", "--seed", "5"];
    let (code, one_out, err) = run_out(d, &[&base[..], &["-o", "one.exr"]].concat());
    assert_eq!(code, 0, "{err}");
    let one = reference_bits(&d.join("one.exr"));
    assert!(one.1.iter().any(|(k, _)| k == "vkvcm:reference_rmse"), "{:?}", one.1);
    for n in 1..=3 {
        let names: Vec<String> = (0..n).map(|k| format!("r{k}of{n}.exr")).collect();
        for (k, name) in names.iter().enumerate() {
            let shard = format!("{k}/{n}");
            let (code, _, err) = run_out(d, &[&base[..], &["--shard", &shard, "-o", name]].concat());
            assert_eq!(code, 0, "reference --shard {shard}: {err}");
        }
        let out = format!("m{n}.exr");
        let mut args = vec!["merge"];
        args.extend(names.iter().rev().map(String::as_str));
        args.extend(["-o", &out]);
        let (code, merged_out, err) = run_out(d, &args);
        assert_eq!(code, 0, "{err}");
        let merged = reference_bits(&d.join(&out));
        assert!(merged.0 == one.0, "{n} shards: the merged reference's pixels differ from one machine's");
        assert_eq!(merged.1, one.1, "{n} shards: attributes differ");
        assert_eq!(error_line(&merged_out), error_line(&one_out), "{n} shards");
    }

    // Refusals, each naming the file; nothing written.
    render_cli(d, "render1.exr", &["--algo", "vcm", "-i", "3", "--seed", "5", "--shard", "1/3"]);
    let cases: [(&[&str], &[&str]); 2] = [
        (&["r0of3.exr", "render1.exr", "r2of3.exr"], &["render1.exr", "a render", "a reference"]),
        (&["r0of3.exr", "r2of3.exr"], &["1/3", "missing", "--partial"]),
    ];
    for (files, needles) in cases {
        let (code, _, err) = run_out(d, &[&["merge"], files, &["-o", "bad.exr"]].concat());
        assert_eq!(code, 2, "merge {files:?}: {err}");
        for n in needles {
            assert!(err.contains(n), "merge {files:?}: {n:?} not in {err:?}");
        }
        assert!(!d.join("bad.exr").exists(), "merge {files:?} wrote an output");
    }
    let (code, _, err) = run_out(d, &["render", "gbs_s", "-o", "res.exr", "--resume", "r0of3.exr", "-i", "4"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("r0of3.exr") && err.contains("shard of a reference"), "{err}");
    // --partial: the reference of the iterations there are, with its own errors, saying
    // which are missing.
    let (code, out, err) = run_out(d, &["merge", "r0of3.exr", "r2of3.exr", "-o", "part.exr", "--partial"]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("holds 2 of each half's 3 iterations; missing: 1"), "{err}");
    let (_, meta) = reference_bits(&d.join("part.exr"));
    let attr = |k: &str| meta.iter().find(|(m, _)| m == k).map(|(_, v)| v.as_str());
    assert_eq!((attr("vkvcm:iterations"), attr("vkvcm:missing")), (Some("4"), Some("1")));
    assert!(error_line(&out) != error_line(&one_out));

    // converge: on the shards (merged in memory) and on their merge, one estimator each
    // (--shard over --algos), then the two runs' rows joined.
    let conv = ["converge", "gbs_s", "--algos", "pt,bpt", "--time", "0.05", "-k", "1", "--seed", "77"];
    let runs: [(&str, &[&str]); 2] = [("0/2", &["r0of2.exr", "r1of2.exr"]), ("1/2", &["m2.exr"])];
    for (k, (shard, refs)) in runs.iter().enumerate() {
        let csv = format!("rows{k}.csv");
        let (code, _, err) = run_out(d, &[&conv[..], &["--shard", shard, "--csv", &csv, "-r"], refs].concat());
        assert_eq!(code, 0, "converge --shard {shard} -r {refs:?}: {err}");
    }
    let (code, _, err) =
        run_out(d, &[&conv[..], &["-r", "m2.exr", "--csv", "all.csv", "--rows", "rows1.csv", "rows0.csv"]].concat());
    assert_eq!(code, 0, "{err}");
    let rows = vkvcm::render::converge::read_csv(&std::fs::read_to_string(d.join("all.csv")).unwrap()).unwrap();
    let rmse: f64 = attr_of(&one.1, "vkvcm:reference_rmse").parse().unwrap();
    let names: Vec<&str> = rows.iter().map(|r| r.estimator.as_str()).collect();
    assert_eq!(names, ["pt", "bpt"], "the rows in --algos' order");
    for r in &rows {
        assert_eq!(r.reference_rmse, Some(rmse), "{} measured against another reference", r.estimator);
    }
    let (code, _, err) = run_out(d, &[&conv[..], &["-r", "m2.exr", "--rows", "rows0.csv"]].concat());
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("no file holds estimator bpt"), "{err}");
    // An incomplete reference set: converge names what is missing and `vkvcm merge
    // --partial`, not an option of its own.
    let (code, _, err) = run_out(d, &[&conv[..], &["-r", "r0of3.exr", "r2of3.exr"]].concat());
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("1/3") && err.contains("missing") && err.contains("`vkvcm merge --partial`"), "{err}");
    assert!(!err.contains("use --partial"), "{err}");
}

fn attr_of<'a>(meta: &'a [(String, String)], key: &str) -> &'a str {
    meta.iter().find(|(k, _)| k == key).map(|(_, v)| v.as_str()).unwrap_or_else(|| panic!("no {key}"))
}
