//! `vkvcm render --reference`: the error on the progress lines, and the final RMSE and
//! relative MSE in the EXR's attributes equal to what `vkvcm diff` measures of that EXR.

use std::path::Path;
use std::process::{Command, Output};

mod common;

fn vkvcm(dir: &Path) -> Command {
    common::vkvcm_in(dir)
}

fn ok(o: Output) -> String {
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(o.status.success(), "{err}");
    assert!(!err.contains("validation"), "{err}");
    err
}

/// The value after `key` on the line of `text` that starts with `key`.
fn field<'a>(text: &'a str, key: &str) -> &'a str {
    let line = text.lines().find(|l| l.starts_with(key)).unwrap_or_else(|| panic!("no {key} in {text}"));
    line[key.len()..].trim()
}

#[test]
fn reference_errors_match_diff() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let frame = ["-a", "pt", "--width", "16", "--height", "16"];
    ok(vkvcm(d).arg("render").args(frame).args(["-i", "16", "--seed", "7", "-o", "ref.exr"]).output().unwrap());
    let err = ok(vkvcm(d)
        .arg("render")
        .args(frame)
        .args(["-i", "4000", "-o", "a.exr", "--reference", "ref.exr"])
        .output()
        .unwrap());
    // Progress lines after the first image read back carry its error; an iteration
    // budget ends on a line at 100%, after several read-backs.
    assert!(err.lines().any(|l| l.starts_with("progress:") && l.contains("rmse") && l.contains("rel_mse")), "{err}");
    let (_, meta) = vkvcm::image::read_exr(&d.join("a.exr")).unwrap();
    let attr = |k: &str| -> f64 {
        let v = meta.iter().find(|(n, _)| n == k).unwrap_or_else(|| panic!("no {k} in {meta:?}"));
        v.1.parse().unwrap()
    };
    let (rmse, rel_mse) = (attr("vkvcm:reference_rmse"), attr("vkvcm:reference_rel_mse"));
    assert!(rmse > 0.0 && rel_mse > 0.0, "a 1.5 s render is not the 16-iteration reference");
    let o = vkvcm(d).args(["diff", "a.exr", "ref.exr"]).output().unwrap();
    assert!(o.status.success());
    let diff = String::from_utf8_lossy(&o.stdout);
    assert_eq!(format!("{rmse:.6e}"), field(&diff, "rmse"));
    assert_eq!(format!("{rel_mse:.6e}"), field(&diff, "rel_mse"));
    // And what the render printed at the end.
    let end = format!("against the reference: rmse {rmse:.6e}, rel_mse {rel_mse:.6e}");
    assert!(err.contains(&end), "{end:?} not in\n{err}");
}

#[test]
fn a_reference_of_another_size_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    ok(vkvcm(d)
        .args(["render", "-a", "pt", "--width", "8", "--height", "8", "-i", "1", "-o", "ref.exr"])
        .output()
        .unwrap());
    let o = vkvcm(d)
        .args([
            "render",
            "-a",
            "pt",
            "--width",
            "16",
            "--height",
            "8",
            "-i",
            "1",
            "-o",
            "a.exr",
            "--reference",
            "ref.exr",
        ])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--reference"));
    assert!(!d.join("a.exr").exists());
}
