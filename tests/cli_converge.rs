//! `vkvcm reference`, `vkvcm converge` and `vkvcm diff`, run as the binary on tiny images
//! (lavapipe unless VKVCM_TEST_DEVICE says otherwise, validation on: a validation message
//! makes the command fail).

use std::path::Path;
use std::process::{Command, Output};

use vkvcm::image::{read_exr, write_exr, Image};

mod common;

fn vkvcm(args: &[&str], gpu: bool) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_vkvcm"));
    // The suite's kernel cache or none.
    c.args(args).env("VKVCM_VALIDATION", "1").env("VKVCM_CACHE_DIR", common::cli_cache_dir(""));
    if std::env::var_os("VK_DRIVER_FILES").is_none() {
        let lvp = ["/usr/share/vulkan/icd.d/lvp_icd.x86_64.json", "/usr/share/vulkan/icd.d/lvp_icd.json"]
            .into_iter()
            .find(|p| Path::new(p).exists());
        if let Some(p) = lvp {
            c.env("VK_DRIVER_FILES", p);
        }
    }
    if gpu {
        if let Ok(d) = std::env::var("VKVCM_TEST_DEVICE") {
            c.args(["--device", &d]);
        }
    }
    c.output().expect("cannot run the vkvcm binary")
}

fn ok(args: &[&str], gpu: bool) -> String {
    let out = vkvcm(args, gpu);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "vkvcm {args:?} failed:\n{stderr}");
    String::from_utf8(out.stdout).unwrap()
}

fn fails(args: &[&str]) -> String {
    let out = vkvcm(args, false);
    assert!(!out.status.success(), "vkvcm {args:?} should have failed");
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[derive(Debug)]
struct Row {
    estimator: String,
    checkpoint: usize,
    iterations: u64,
    seconds: f64,
    rmse: f64,
    rel_mse: f64,
    bias: f64,
    max_abs: f64,
    reference_rmse: f64,
}

fn read_csv(p: &Path) -> Vec<Row> {
    let text = std::fs::read_to_string(p).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "estimator,checkpoint,iterations,seconds,rmse,rel_mse,mean_abs_bias,max_abs,reference_rmse,reference_rel_mse"
    );
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            assert_eq!(f.len(), 10, "{l}");
            let num = |i: usize| f[i].parse::<f64>().unwrap_or_else(|_| panic!("column {i} of {l}"));
            Row {
                estimator: f[0].to_string(),
                checkpoint: f[1].parse().unwrap(),
                iterations: f[2].parse().unwrap(),
                seconds: num(3),
                rmse: num(4),
                rel_mse: num(5),
                bias: num(6),
                max_abs: num(7),
                reference_rmse: num(8),
            }
        })
        .collect()
}

/// reference -> converge on glm_c (area light only: pt and bpt are unbiased there).
///
/// Why "last RMSE < 0.7 x first RMSE" is safe: the checkpoints span a 16x range of render
/// time, so an unbiased estimator's variance drops ~16x and its expected RMSE 4x, down to
/// the floor of the reference's own noise. The reference (pt, 2048 iterations) has an RMS
/// error of ~0.05 at 24x24, while pt after its first checkpoint (~1/20 s, a few tens of
/// iterations) is at ~0.5 (measured: 0.56 -> 0.09 for pt, 0.61 -> 0.20 for bpt over the
/// same range). sqrt(0.5^2 / 16 + 0.05^2) / 0.5 is ~0.27, far below 0.7; the RMSE averages
/// 1728 pixel-channels, so it does not swing by 2.5x between runs.
#[test]
fn reference_then_converge() {
    let dir = tempfile::tempdir().unwrap();
    let (r, csv, png) = (dir.path().join("ref.exr"), dir.path().join("c.csv"), dir.path().join("c.png"));
    let out = ok(
        &[
            "reference",
            "glm_c",
            "--algo",
            "pt",
            "--iterations",
            "2048",
            "--width",
            "24",
            "--height",
            "24",
            "--light-selection",
            "uniform",
            "-o",
            s(&r),
        ],
        true,
    );
    assert!(out.contains("its own error estimate"), "{out}");
    let (img, meta) = read_exr(&r).unwrap();
    assert_eq!((img.width, img.height), (24, 24));
    let get = |k: &str| meta.iter().find(|(key, _)| key == k).map(|(_, v)| v.clone()).unwrap_or_default();
    assert_eq!(get("vkvcm:iterations"), "2048");
    assert_eq!(get("vkvcm:estimator"), "pt");
    // The settings the reference rendered with, as its metadata records them.
    assert_eq!(get("vkvcm:light_selection"), "uniform");
    let ref_rmse: f64 = get("vkvcm:reference_rmse").parse().unwrap();
    assert!(ref_rmse > 0.0 && ref_rmse < 0.2, "reference's own RMSE {ref_rmse}");

    let k = 5;
    ok(
        &[
            "converge",
            "glm_c",
            "--reference",
            s(&r),
            "--algos",
            "pt,bpt@144",
            "--light-selection",
            "uniform",
            "--time",
            "0.8",
            "--checkpoints",
            "5",
            "--csv",
            s(&csv),
            "--plot",
            s(&png),
        ],
        true,
    );
    let rows = read_csv(&csv);
    assert_eq!(rows.len(), 2 * k);
    // bpt@144: a quarter of the default light subpaths per iteration (render --light-paths).
    for (e, est) in ["pt", "bpt@144"].iter().enumerate() {
        let rs = &rows[e * k..(e + 1) * k];
        for (i, r) in rs.iter().enumerate() {
            assert_eq!((r.estimator.as_str(), r.checkpoint), (*est, i + 1));
            assert!(
                [r.seconds, r.rmse, r.rel_mse, r.bias, r.max_abs].iter().all(|v| v.is_finite() && *v >= 0.0),
                "{r:?}"
            );
            assert_eq!(r.reference_rmse, ref_rmse);
        }
        assert!(rs.windows(2).all(|p| p[1].iterations > p[0].iterations && p[1].seconds > p[0].seconds), "{rs:?}");
        // Checkpoint times are 0.05, 0.1, ..., 0.8 s of render time; a batch may overshoot.
        assert!(rs[k - 1].seconds >= 0.8 && rs[k - 1].seconds < 2.0, "{rs:?}");
        // On a machine so loaded that the 16x time range gave fewer than 4x the iterations,
        // only ask for a fall (the 0.7 margin assumes the iterations follow the time).
        let factor = if rs[k - 1].iterations >= 4 * rs[0].iterations { 0.7 } else { 1.0 };
        assert!(rs[k - 1].rmse < factor * rs[0].rmse, "{est}: RMSE did not fall over a 16x time range: {rs:?}");
    }
    let plot = image::open(&png).expect("the plot decodes as an image");
    assert_eq!((plot.width(), plot.height()), (900, 600));

    // A reference of another size is refused before anything renders.
    let err = fails(&["converge", "glm_c", "--reference", s(&r), "--width", "16", "--time", "0.1"]);
    assert!(err.contains("is 24x24 but the render would be 16x24"), "{err}");
    // So is a light-path count the estimator cannot take.
    let err = fails(&["converge", "glm_c", "--reference", s(&r), "--algos", "pt@100", "--time", "0.1"]);
    assert!(err.contains("pt@100"), "{err}");
}

#[test]
fn diff_reports_exact_metrics() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b, c) = (dir.path().join("a.exr"), dir.path().join("b.exr"), dir.path().join("c.exr"));
    // Multiples of 1/64 plus 0.25: every difference is exactly 0.25 in f32 and f64.
    let base = Image::from_fn(8, 6, |x, y| [x as f32 / 64.0, y as f32 / 64.0, (x + y) as f32 / 32.0]);
    write_exr(&b, &base, &[]).unwrap();
    write_exr(&a, &base.map(|p| p.map(|v| v + 0.25)), &[]).unwrap();
    write_exr(&c, &Image::new(8, 5), &[]).unwrap();
    let metrics = |out: &str| -> Vec<(String, f64)> {
        out.lines()
            .skip(1)
            .take(4)
            .map(|l| {
                let mut f = l.split_whitespace();
                (f.next().unwrap().to_string(), f.next().unwrap().parse::<f64>().unwrap())
            })
            .collect()
    };

    let same = metrics(&ok(&["diff", s(&b), s(&b)], false));
    let names: Vec<&str> = same.iter().map(|m| m.0.as_str()).collect();
    assert_eq!(names, ["rmse", "rel_mse", "mean_abs_bias", "max_abs"]);
    assert!(same.iter().all(|m| m.1 == 0.0), "{same:?}");

    let fc = dir.path().join("fc.png");
    let off = metrics(&ok(&["diff", s(&a), s(&b), "--false-colour", s(&fc)], false));
    assert_eq!(off[0].1, 0.25, "rmse");
    assert_eq!(off[2].1, 0.25, "mean_abs_bias");
    assert_eq!(off[3].1, 0.25, "max_abs");
    assert!(off[1].1 > 0.0);
    let fcimg = image::open(&fc).expect("false-colour PNG decodes");
    assert_eq!((fcimg.width(), fcimg.height()), (8, 6));

    let err = fails(&["diff", s(&a), s(&c)]);
    assert!(err.contains("8x6") && err.contains("8x5") && err.contains("sizes differ"), "{err}");
    let err = fails(&["diff", s(&a), s(&b), "--scale=-1"]);
    assert!(err.contains("--scale"), "{err}");
}
