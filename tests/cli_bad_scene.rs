//! `vkvcm render` on every malformed scene of tests/malformed/ (issue #9 part 1), as a
//! user runs it: the process exits non-zero, prints no panic, and prints exactly one error
//! line that names the file and contains the case's expected message (`<case>.expect`).
//! The loader itself is tested case by case in tests/scene_malformed.rs; this proves the
//! binary turns those errors into one line and a failing exit status. Cases expected to
//! load (`ok`) must render a tiny image and exit 0.

use std::path::Path;
use std::process::{Command, Output};

mod common;
use common::corpus::malformed_cases;

fn render(scene: &Path, out: &Path) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_vkvcm"));
    c.env("VKVCM_VALIDATION", "1").env_remove("VKVCM_TEST_FAIL_AFTER_BATCHES");
    c.env("VKVCM_CACHE_DIR", common::cli_cache_dir("")); // the suite's kernel cache or none
    if std::env::var_os("VK_DRIVER_FILES").is_none() {
        c.env("VK_DRIVER_FILES", "/usr/share/vulkan/icd.d/lvp_icd.json");
    }
    c.arg("render")
        .arg(scene)
        .args(["-a", "pt", "--width", "8", "--height", "8", "-i", "1", "-o"])
        .arg(out)
        .output()
        .expect("run vkvcm")
}

/// Checks one run; returns a description of what is wrong, if anything.
fn check(scene: &Path, expect: &str, o: &Output, out: &Path) -> Result<(), String> {
    let name = scene.file_name().unwrap().to_string_lossy().to_string();
    let err = String::from_utf8_lossy(&o.stderr);
    if err.contains("panicked") || err.contains("RUST_BACKTRACE") {
        return Err(format!("{name}: panicked:\n{err}"));
    }
    if err.to_lowercase().contains("validation") {
        return Err(format!("{name}: validation message:\n{err}"));
    }
    let errors: Vec<&str> = err.lines().filter(|l| l.starts_with("error")).collect();
    if expect == "ok" {
        if !o.status.success() || !errors.is_empty() {
            return Err(format!("{name}: expected to render, got {:?}:\n{err}", o.status));
        }
        if !out.is_file() {
            return Err(format!("{name}: rendered but wrote no {}", out.display()));
        }
        return Ok(());
    }
    if o.status.success() {
        return Err(format!("{name}: exited 0, expected an error containing '{expect}'"));
    }
    if out.exists() {
        return Err(format!("{name}: failed but left an output file"));
    }
    match errors.as_slice() {
        [line] if !line.contains(&name) => Err(format!("{name}: error line does not name the file: {line}")),
        [line] if !line.contains(expect) => Err(format!("{name}: error line lacks '{expect}': {line}")),
        [_] => Ok(()),
        _ => Err(format!("{name}: expected one error line, got {}:\n{err}", errors.len())),
    }
}

#[test]
fn every_malformed_scene_gives_one_error_line_and_fails() {
    let tmp = tempfile::tempdir().unwrap();
    let cases = malformed_cases();
    assert!(cases.len() >= 50, "corpus has only {} cases", cases.len());
    let mut failures = Vec::new();
    let (mut errors, mut oks) = (0, 0);
    for (i, (case, expect)) in cases.iter().enumerate() {
        let expect = expect.as_str();
        let out = tmp.path().join(format!("out{i}.exr"));
        let o = render(case, &out);
        if expect == "ok" {
            oks += 1;
        } else {
            errors += 1;
        }
        if let Err(f) = check(case, expect, &o, &out) {
            failures.push(f);
        }
    }
    assert!(failures.is_empty(), "{} of {} cases failed:\n{}", failures.len(), cases.len(), failures.join("\n"));
    assert!(errors > 0 && oks > 0, "{errors} error cases, {oks} ok cases");
}

#[test]
fn missing_and_unreadable_scenes_give_one_error_line() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out.exr");
    // A path that does not exist, and a folder where a file is expected.
    let missing = tmp.path().join("no_such_scene.gltf");
    let o = render(&missing, &out);
    check(&missing, "no_such_scene.gltf", &o, &out).unwrap();
    let dir = tmp.path().join("folder.gltf");
    std::fs::create_dir(&dir).unwrap();
    let o = render(&dir, &out);
    check(&dir, "folder.gltf", &o, &out).unwrap();
    // An unknown extension is not guessed at.
    let txt = tmp.path().join("scene.txt");
    std::fs::write(&txt, "{}").unwrap();
    let o = render(&txt, &out);
    check(&txt, "scene.txt", &o, &out).unwrap();
}
