//! The exit codes of `vkvcm` (README.md, "Exit codes"), one per class of failure, as a
//! script sees them; `render --quiet`; `vkvcm completions`. The code on SIGINT (130) is
//! checked with the interrupted renders of tests/cli_render.rs.

use std::path::Path;
use std::process::{Command, Output};

mod common;

fn vkvcm(dir: &Path) -> Command {
    common::vkvcm_in(dir)
}

/// Runs `vkvcm render` with `args` and a tiny pt frame; fails unless it exits with `code`
/// and, when it fails, prints exactly one error line.
fn render_exits(dir: &Path, args: &[&str], code: i32) -> Output {
    let o = vkvcm(dir).args(["render", "-a", "pt", "-i", "1"]).args(args).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("panicked") && !err.contains("validation"), "{err}");
    assert_eq!(o.status.code(), Some(code), "{args:?}:\n{err}");
    if code != 0 {
        assert_eq!(err.lines().filter(|l| l.starts_with("error")).count(), 1, "{args:?}:\n{err}");
    }
    o
}

#[test]
fn each_class_of_failure_has_its_code() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let small = ["--width", "8", "--height", "8", "-o", "x.exr"];
    // 2: bad arguments, clap's and ours.
    render_exits(d, &["--no-such-option"], 2);
    render_exits(d, &["--width", "0", "--height", "8"], 2);
    render_exits(d, &["--width", "8", "--height", "8", "--connect", "cache"], 2);
    // -o writes OpenEXR: another image extension is refused, pointing at --png.
    let o = render_exits(d, &["--width", "8", "--height", "8", "-o", "x.png"], 2);
    assert!(String::from_utf8_lossy(&o.stderr).contains("--png"), "{o:?}");
    assert!(!d.join("x.png").exists());
    // Settings the estimator refuses (lt traces no camera paths for AOVs).
    render_exits(d, &[&["--algo", "lt", "--aov", "albedo"][..], &small].concat(), 2);
    render_exits(d, &[&["--algo", "pt", "--light-paths", "4"][..], &small].concat(), 2);
    // 3: the scene cannot be read: missing, malformed, or an unknown camera.
    render_exits(d, &[&["no_such_scene.gltf"][..], &small].concat(), 3);
    let malformed = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/malformed/bad_json.gltf");
    render_exits(d, &[&[malformed.to_str().unwrap()][..], &small].concat(), 3);
    render_exits(d, &[&["--camera", "nope"][..], &small].concat(), 3);
    // 4: no such device.
    render_exits(d, &[&["--device", "99"][..], &small].concat(), 4);
    render_exits(d, &[&["--device", "no such device"][..], &small].concat(), 4);
    // 5: the frame does not fit the device.
    render_exits(d, &["--width", "16", "--height", "100000000", "-o", "x.exr"], 5);
    assert!(!d.join("x.exr").exists());
    // reference and converge share the scene and device codes.
    let reference = |args: &[&str]| {
        vkvcm(d).args(["reference", "-a", "pt", "--width", "8", "--height", "8"]).args(args).output().unwrap()
    };
    assert_eq!(reference(&["no_such_scene.gltf", "-o", "r.exr"]).status.code(), Some(3));
    assert_eq!(reference(&["gbs_s", "--device", "99", "-o", "r.exr"]).status.code(), Some(4));
    // 0, and the image.
    render_exits(d, &small, 0);
    assert!(d.join("x.exr").is_file());
}

#[test]
fn quiet_prints_only_warnings_and_errors() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let o = render_exits(d, &["--width", "8", "--height", "8", "-o", "q.exr", "--quiet"], 0);
    assert!(o.stderr.is_empty(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(d.join("q.exr").is_file());
    // Without it, the same render says what it did.
    let o = render_exits(d, &["--width", "8", "--height", "8", "-o", "q.exr"], 0);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("device:") && err.contains("progress:") && err.contains("wrote"), "{err}");
    // Errors are still printed.
    let o = render_exits(d, &["--width", "8", "--height", "8", "-o", "q.exr", "-q", "--device", "99"], 4);
    assert!(String::from_utf8_lossy(&o.stderr).starts_with("error: "));
}

#[test]
fn completions_for_each_shell() {
    let dir = tempfile::tempdir().unwrap();
    for shell in ["bash", "zsh", "fish"] {
        let o = vkvcm(dir.path()).args(["completions", shell]).output().unwrap();
        assert!(o.status.success(), "{shell}: {}", String::from_utf8_lossy(&o.stderr));
        let s = String::from_utf8_lossy(&o.stdout);
        for word in ["render", "info", "quiet", "algo", "profile-json"] {
            assert!(s.contains(word), "{shell} completions lack {word}");
        }
    }
    let o = vkvcm(dir.path()).args(["completions", "tcsh"]).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
}
