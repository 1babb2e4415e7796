//! `vkvcm render` as a user runs it: bad arguments give one error line naming the
//! argument; SIGINT/SIGTERM write the partial image; checkpoints grow; --resume continues;
//! a (simulated) device loss still writes the last completed snapshot. Tiny images, pt.

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Output, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use vkvcm::render::saved;

mod common;

fn vkvcm(dir: &Path) -> Command {
    common::vkvcm_in(dir)
}

const TINY: [&str; 6] = ["render", "-a", "pt", "--width", "16", "--height"];

fn tiny(dir: &Path) -> Command {
    let mut c = vkvcm(dir);
    c.args(TINY).arg("16");
    c
}

fn error_lines(o: &Output) -> Vec<String> {
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("panicked"), "panic:\n{err}");
    assert!(!err.contains("validation"), "validation message:\n{err}");
    err.lines().filter(|l| l.starts_with("error")).map(str::to_string).collect()
}

/// Fails unless `o` failed with exactly one error line, containing every needle.
fn one_error(o: &Output, needles: &[&str]) {
    assert!(!o.status.success(), "succeeded: {}", String::from_utf8_lossy(&o.stderr));
    let lines = error_lines(o);
    assert_eq!(lines.len(), 1, "error lines: {lines:?}\n{}", String::from_utf8_lossy(&o.stderr));
    for n in needles {
        assert!(lines[0].contains(n), "{:?} lacks {n:?}", lines[0]);
    }
}

#[test]
fn bad_arguments_one_error_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let run = |args: &[&str]| vkvcm(d).arg("render").args(args).output().unwrap();
    one_error(&run(&["--width", "0", "--height", "16"]), &["--width"]);
    one_error(&run(&["--width", "16", "--height", "0"]), &["--height"]);
    one_error(&run(&["-a", "pt", "--width", "16", "--height", "100000000"]), &["--height 100000000", "MiB"]);
    one_error(&run(&["--width", "16", "--height", "16", "-i", "0"]), &["--iterations"]);
    one_error(&run(&["--width", "16", "--height", "16", "--time=-1"]), &["--time"]);
    one_error(&run(&["--width", "16", "--height", "16", "--checkpoint-every", "0"]), &["--checkpoint-every"]);
    one_error(&run(&["--width", "16", "--height", "16", "-o", "missing/x.exr"]), &["--output", "missing"]);
    one_error(&run(&["-a", "pt", "--width", "16", "--height", "16", "--connect", "cache"]), &["--connect", "pt"]);
    one_error(
        &run(&["-a", "bpt", "--width", "16", "--height", "16", "--cache-connections", "0"]),
        &["--cache-connections"],
    );
    std::fs::create_dir(d.join("adir")).unwrap();
    one_error(&run(&["--width", "16", "--height", "16", "-o", "adir"]), &["--output", "directory"]);
    // Unwritable: a read-only directory, or /proc where root ignores permissions.
    // SAFETY: plain libc call.
    let unwritable = if unsafe { libc::geteuid() } == 0 {
        "/proc/x.exr".to_string()
    } else {
        let ro = d.join("ro");
        std::fs::create_dir(&ro).unwrap();
        std::fs::set_permissions(&ro, std::os::unix::fs::PermissionsExt::from_mode(0o555)).unwrap();
        ro.join("x.exr").display().to_string()
    };
    one_error(&run(&["--width", "16", "--height", "16", "-o", &unwritable]), &["--output", "cannot write"]);
}

/// `--gltf-scene` picks the glTF scene of a file with several (Khronos MultipleScenes): an
/// unknown one is one error line listing the scenes; scene 0 renders (and, since it is
/// chosen, no warning about the other scene).
#[test]
fn gltf_scene_option() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/khronos/MultipleScenes.gltf");
    let o = tiny(d).arg(&file).args(["-i", "1", "--gltf-scene", "nope", "-o", "x.exr"]).output().unwrap();
    one_error(&o, &["MultipleScenes.gltf", "'nope'", "available scenes: 0, 1"]);
    let o = tiny(d).arg(&file).args(["-i", "1", "--gltf-scene", "0", "-o", "x.exr"]).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(error_lines(&o).is_empty() && !err.contains("scenes"), "{err}");
    assert!(d.join("x.exr").is_file());
}

/// Spawns `cmd` with stderr piped; lines arrive on the returned channel.
fn spawn(mut cmd: Command) -> (Child, mpsc::Receiver<String>) {
    let mut child = cmd.stderr(Stdio::piped()).spawn().unwrap();
    let err = child.stderr.take().unwrap();
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(err).lines().map_while(Result::ok) {
            eprintln!("  | {line}");
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    (child, rx)
}

fn wait_line(rx: &mpsc::Receiver<String>, prefix: &str, timeout: Duration) -> String {
    let end = Instant::now() + timeout;
    loop {
        let left = end.saturating_duration_since(Instant::now());
        match rx.recv_timeout(left) {
            Ok(l) if l.starts_with(prefix) => return l,
            Ok(_) => {}
            Err(e) => panic!("no line starting with {prefix:?} within {timeout:?}: {e}"),
        }
    }
}

fn wait_exit(child: &mut Child, timeout: Duration) -> std::process::ExitStatus {
    let end = Instant::now() + timeout;
    loop {
        if let Some(s) = child.try_wait().unwrap() {
            return s;
        }
        if Instant::now() > end {
            let _ = child.kill();
            panic!("vkvcm did not exit within {timeout:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn interrupted_render_is_written(signal: i32) {
    let dir = tempfile::tempdir().unwrap();
    let mut cmd = tiny(dir.path());
    cmd.args(["--time", "60", "-o", "out.exr"]);
    let (mut child, rx) = spawn(cmd);
    wait_line(&rx, "progress:", Duration::from_secs(60));
    let t0 = Instant::now();
    // SAFETY: plain libc call on our child's pid.
    assert_eq!(unsafe { libc::kill(child.id() as i32, signal) }, 0);
    let status = wait_exit(&mut child, Duration::from_secs(10));
    // Interrupted: the partial image is written, and the exit code says so (README.md).
    assert_eq!(status.code(), Some(130), "status {status:?}");
    assert!(t0.elapsed() < Duration::from_secs(5), "took {:?} to stop", t0.elapsed());
    let s = saved::read_render_exr(&dir.path().join("out.exr")).unwrap();
    assert!(s.iterations >= 1 && s.seconds < 60.0, "{} iterations, {} s", s.iterations, s.seconds);
    assert!(s.sums.sum.iter().flatten().any(|&v| v > 0), "black image");
}

#[test]
fn sigint_writes_partial_image() {
    interrupted_render_is_written(libc::SIGINT);
}

#[test]
fn sigterm_writes_partial_image() {
    interrupted_render_is_written(libc::SIGTERM);
}

#[test]
fn checkpoints_grow() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.exr");
    let mut cmd = tiny(dir.path());
    cmd.args(["--time", "30", "--checkpoint-every", "0.3", "-o", "out.exr"]);
    let (mut child, rx) = spawn(cmd);
    wait_line(&rx, "checkpoint:", Duration::from_secs(60));
    let first = saved::read_render_exr(&out).unwrap().iterations;
    wait_line(&rx, "checkpoint:", Duration::from_secs(10));
    let second = saved::read_render_exr(&out).unwrap().iterations;
    assert!(first >= 1 && second > first, "checkpoints at {first} then {second} iterations");
    // SAFETY: plain libc call on our child's pid.
    unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
    assert_eq!(wait_exit(&mut child, Duration::from_secs(10)).code(), Some(130));
    assert!(saved::read_render_exr(&out).unwrap().iterations >= second);
}

#[test]
fn resume_continues_to_the_total() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.exr");
    let o = tiny(dir.path()).args(["-i", "3", "-o", "out.exr"]).output().unwrap();
    assert!(o.status.success());
    let o = tiny(dir.path()).args(["-i", "7", "-o", "out.exr", "--resume"]).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stderr).contains("resuming"));
    assert_eq!(saved::read_render_exr(&out).unwrap().iterations, 7);
    // Other settings are refused, naming the option; the file is untouched.
    let o = tiny(dir.path()).args(["-i", "9", "-o", "out.exr", "--resume", "--seed", "5"]).output().unwrap();
    one_error(&o, &["--seed", "out.exr"]);
    assert_eq!(saved::read_render_exr(&out).unwrap().iterations, 7);
    // So is another connection strategy (bpt, recorded as vkvcm:connect).
    let bpt = ["render", "-a", "bpt", "--width", "16", "--height", "16", "-o", "bpt.exr"];
    let o = vkvcm(dir.path()).args(bpt).args(["-i", "2", "--connect", "path"]).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = vkvcm(dir.path()).args(bpt).args(["-i", "3", "--resume", "--connect", "cache"]).output().unwrap();
    one_error(&o, &["--connect", "bpt.exr"]);
    // --resume on a missing output starts a new render.
    let o = tiny(dir.path()).args(["-i", "2", "-o", "new.exr", "--resume"]).output().unwrap();
    assert!(o.status.success());
    assert_eq!(saved::read_render_exr(&dir.path().join("new.exr")).unwrap().iterations, 2);
}

/// The simulated device loss (VKVCM_TEST_FAIL_AFTER_BATCHES): one error line saying what
/// failed, and the image of the last completed snapshot written. A 16x16 film is copied
/// to the host after every batch, so the loss at the 7th submit leaves 6 batches' worth.
#[test]
#[cfg_attr(not(feature = "fault-injection"), ignore = "needs --features fault-injection")]
fn device_loss_writes_last_snapshot() {
    let dir = tempfile::tempdir().unwrap();
    let o = tiny(dir.path())
        .args(["-i", "1000000", "-o", "out.exr"])
        .env("VKVCM_TEST_FAIL_AFTER_BATCHES", "6")
        .output()
        .unwrap();
    one_error(&o, &["device lost", "of pt", "iteration"]);
    let s = saved::read_render_exr(&dir.path().join("out.exr")).unwrap();
    assert!(s.iterations >= 6 && s.iterations < 1_000_000, "{} iterations", s.iterations);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains(&format!("wrote the last completed {} iterations", s.iterations)), "{err}");

    // With checkpoints, the last one is what the file keeps.
    let o = tiny(dir.path())
        .args(["-i", "1000000", "--checkpoint-every", "0.01", "-o", "cp.exr"])
        .env("VKVCM_TEST_FAIL_AFTER_BATCHES", "6")
        .output()
        .unwrap();
    one_error(&o, &["device lost"]);
    let s = saved::read_render_exr(&dir.path().join("cp.exr")).unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains(&format!("the last completed {} iterations", s.iterations)), "{err}");
}

/// A glTF file with neither a camera nor a light (the corpus triangle with a grey
/// material and without its camera node) renders a non-black image: a default camera
/// frames it and the built-in studio lights it, each announced once. `--look-from` / `--look-at`
/// then move that camera (a view from behind the triangle still sees it: two-sided).
#[test]
fn a_file_without_camera_or_lights_renders_with_the_defaults() {
    let dir = tempfile::tempdir().unwrap();
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/malformed/no_camera.gltf");
    let mut doc: serde_json::Value = serde_json::from_slice(&std::fs::read(src).unwrap()).unwrap();
    doc["materials"][0] = serde_json::json!({"name": "grey"});
    let file = dir.path().join("bare.gltf");
    std::fs::write(&file, serde_json::to_vec(&doc).unwrap()).unwrap();
    for (name, view) in [("default", vec![]), ("behind", vec!["--look-from", "0.2,0.1,-4", "--look-at", "0,0,0"])] {
        let exr = dir.path().join(format!("{name}.exr"));
        let mut c = tiny(dir.path());
        c.args([file.to_str().unwrap(), "-i", "2", "-o", exr.to_str().unwrap()]).args(&view);
        let o = c.output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success() && error_lines(&o).is_empty(), "{name}: {err}");
        assert_eq!(err.matches("default camera").count(), 1, "{name}: {err}");
        assert_eq!(err.matches("built-in studio lights the scene").count(), 1, "{name}: {err}");
        assert!(!err.contains("white sky"), "{name}: {err}");
        let (img, _) = vkvcm::image::read_exr(&exr).unwrap();
        let mean: f32 = img.data.iter().map(|p| p[0] + p[1] + p[2]).sum::<f32>() / img.data.len() as f32;
        assert!(mean > 0.01, "{name}: the image is black (mean {mean})");
    }
}

/// The frame follows the camera: a camera of aspectRatio 2 gives a 512 x 256 image by
/// default and --width 64 alone a 64 x 32 one (both given: as given); --look-from takes
/// negative coordinates.
#[test]
fn the_frame_follows_the_camera_and_negative_coordinates_parse() {
    let dir = tempfile::tempdir().unwrap();
    let file = common::wide_camera_box(dir.path());
    let cases: [(&[&str], (u32, u32)); 4] = [
        (&[], (512, 256)),
        (&["--width", "64"], (64, 32)),
        (&["--width", "20", "--height", "30"], (20, 30)),
        (&["--height", "16", "--look-from", "-14,-14,-14", "--look-at", "-0.5,0,0"], (32, 16)),
    ];
    for (k, (args, size)) in cases.iter().enumerate() {
        let exr = dir.path().join(format!("{k}.exr"));
        let mut c = vkvcm(dir.path());
        c.args(["render", file.to_str().unwrap(), "-a", "el", "-i", "1", "-o", exr.to_str().unwrap()]).args(*args);
        let o = c.output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success() && error_lines(&o).is_empty(), "{args:?}: {err}");
        let (img, _) = vkvcm::image::read_exr(&exr).unwrap();
        assert_eq!((img.width, img.height), *size, "{args:?}");
    }
}

/// A file whose only lights are emissive triangles gets the studio too, with one line
/// that says so and how to change it; `--env none` leaves only the emission (a darker
/// image, no line), `--env sky` lights it with the sky (no line: asked for).
#[test]
fn emissive_only_files_get_the_studio() {
    let dir = tempfile::tempdir().unwrap();
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/malformed/no_camera.gltf");
    let mut doc: serde_json::Value = serde_json::from_slice(&std::fs::read(src).unwrap()).unwrap();
    doc["materials"][0] = serde_json::json!({"name": "glow", "emissiveFactor": [0.2, 0.2, 0.2]});
    let file = dir.path().join("glow.gltf");
    std::fs::write(&file, serde_json::to_vec(&doc).unwrap()).unwrap();
    let mut means = Vec::new();
    for env in [None, Some("none"), Some("sky")] {
        let exr = dir.path().join(format!("{env:?}.exr"));
        let mut c = tiny(dir.path());
        c.args([file.to_str().unwrap(), "-i", "4", "-o", exr.to_str().unwrap()]);
        if let Some(e) = env {
            c.args(["--env", e]);
        }
        let o = c.output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success() && error_lines(&o).is_empty(), "{env:?}: {err}");
        let notes = err.lines().filter(|l| l.starts_with("note: ") && l.contains("studio")).count();
        assert_eq!(notes, usize::from(env.is_none()), "{env:?}: {err}");
        if env.is_none() {
            assert!(err.contains("together with its emissive surfaces") && err.contains("--env"), "{err}");
        }
        let (img, _) = vkvcm::image::read_exr(&exr).unwrap();
        means.push(img.data.iter().map(|p| (p[0] + p[1] + p[2]) as f64).sum::<f64>() / img.data.len() as f64);
    }
    assert!(means[0] > 2.0 * means[1], "studio {} vs emission alone {}", means[0], means[1]);
    assert!(means[2] > 2.0 * means[1], "sky {} vs emission alone {}", means[2], means[1]);
}

/// `--env` lights a file without lights with the map instead of the white sky (no sky
/// warning), `--env-strength` scales the image, and a missing or unreadable map is one
/// error line naming --env.
#[test]
fn env_option_lights_the_scene() {
    let dir = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let src = root.join("tests/malformed/no_camera.gltf");
    let mut doc: serde_json::Value = serde_json::from_slice(&std::fs::read(src).unwrap()).unwrap();
    doc["materials"][0] = serde_json::json!({"name": "grey"});
    let file = dir.path().join("bare.gltf");
    std::fs::write(&file, serde_json::to_vec(&doc).unwrap()).unwrap();
    let sky = root.join("tests/env/sky.hdr");
    let mut means = Vec::new();
    for strength in ["1", "2"] {
        let exr = dir.path().join(format!("s{strength}.exr"));
        let mut c = tiny(dir.path());
        c.args([file.to_str().unwrap(), "-i", "4", "--seed", "3", "-o", exr.to_str().unwrap()]);
        c.args(["--env", sky.to_str().unwrap(), "--env-strength", strength, "--env-rotate", "-45"]);
        let o = c.output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success() && error_lines(&o).is_empty(), "{err}");
        assert!(!err.contains("white sky"), "{err}");
        let (img, _) = vkvcm::image::read_exr(&exr).unwrap();
        means.push(img.data.iter().map(|p| (p[0] + p[1] + p[2]) as f64).sum::<f64>() / img.data.len() as f64);
    }
    assert!(means[0] > 0.01, "black image under the map");
    assert!((means[1] / means[0] - 2.0).abs() < 1e-3, "strength 2 gives {} x the image", means[1] / means[0]);
    let run = |env: &str| {
        let mut c = tiny(dir.path());
        c.args([file.to_str().unwrap(), "-i", "1", "--env", env]);
        c.output().unwrap()
    };
    one_error(&run("missing.hdr"), &["--env", "missing.hdr"]);
    std::fs::write(dir.path().join("text.hdr"), "hello").unwrap();
    one_error(&run("text.hdr"), &["--env", "neither a Radiance HDR"]);
}
