//! `vkvcm info` as a user runs it: `--json` on the reference scenes (also with render's
//! view options), an instanced scene and a malformed one; what it reports agrees with the loaded scene and the plan, and a
//! frame too large for the device is said to be so (exit code 5).

use std::path::Path;
use std::process::{Command, Output};

use serde_json::Value;

mod common;

fn vkvcm(dir: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_vkvcm"));
    c.current_dir(dir).env("VKVCM_VALIDATION", "1");
    c.env("VKVCM_CACHE_DIR", common::cli_cache_dir(dir.join("kernel-cache")));
    if std::env::var_os("VK_DRIVER_FILES").is_none() {
        c.env("VK_DRIVER_FILES", "/usr/share/vulkan/icd.d/lvp_icd.json");
    }
    c
}

/// `info --json` on `scene` with `args`: its exit code and the parsed JSON.
fn info_json(dir: &Path, scene: &str, args: &[&str]) -> (Option<i32>, Value, Output) {
    let o = vkvcm(dir).args(["info", scene, "--json"]).args(args).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("panicked") && !err.contains("validation"), "{err}");
    let v = serde_json::from_slice(&o.stdout).unwrap_or(Value::Null);
    (o.status.code(), v, o)
}

fn sum_bytes(v: &Value) -> u64 {
    v["plan"]["buffers"].as_array().unwrap().iter().map(|b| b["bytes"].as_u64().unwrap()).sum()
}

#[test]
fn reference_scenes() {
    let dir = tempfile::tempdir().unwrap();
    for name in vkvcm::scene::BUILTIN_SCENES {
        let (code, v, o) = info_json(dir.path(), name, &["--width", "32", "--height", "24", "-a", "vcm"]);
        assert_eq!(code, Some(0), "{name}: {}", String::from_utf8_lossy(&o.stderr));
        let scene = vkvcm::scene::load_named(name).unwrap();
        let s = &v["scene"];
        assert_eq!(s["name"], name);
        assert_eq!(s["triangles"].as_u64(), Some(scene.placed_triangles()), "{name}");
        assert_eq!(s["spheres"].as_u64(), Some(scene.spheres.len() as u64), "{name}");
        let count = |m: &Value| m.as_object().unwrap().values().map(|n| n.as_u64().unwrap()).sum::<u64>();
        assert_eq!(count(&s["materials_by_kind"]), scene.materials.len() as u64, "{name}");
        assert_eq!(count(&s["lights_by_kind"]), scene.lights.len() as u64, "{name}");
        assert_eq!(s["cameras"].as_array().unwrap().len(), 1, "{name}");
        assert!((s["camera_used"]["aspect"].as_f64().unwrap() - 32.0 / 24.0).abs() < 1e-9);
        // The features are those the kernels get.
        let features = vkvcm::render::features::FeatureSet::new(&scene, false);
        assert_eq!(v["features"], serde_json::to_value(&features).unwrap(), "{name}");
        let p = &v["plan"];
        assert_eq!(p["fits"], true, "{name}");
        assert!(p["error"].is_null());
        assert_eq!(p["total_bytes"].as_u64(), Some(sum_bytes(&v)));
        let film = p["buffers"].as_array().unwrap().iter().find(|b| b["name"] == "film").expect("film buffer");
        assert!(film["bytes"].as_u64().unwrap() >= 32 * 24 * 4 * 2, "{film}");
        assert!(p["buffers"].as_array().unwrap().iter().any(|b| b["name"] == "grid_keys"), "vcm merges");
    }
    // gbs_s's glass uses the transmission and IOR extensions.
    let (_, v, _) = info_json(dir.path(), "gbs_s", &["--width", "8", "--height", "8", "-a", "pt"]);
    let ext = &v["scene"]["materials_by_extension"];
    assert_eq!(ext["KHR_materials_transmission"], 1, "{ext}");
    // pt has no hash grid: the plan follows the estimator.
    assert!(!v["plan"]["buffers"].as_array().unwrap().iter().any(|b| b["name"] == "grid_keys"));
}

/// `info` takes `render`'s scene and view options (one `SceneArgs`): without --width and
/// --height the planned frame follows the camera's aspect ratio as a render's does
/// (512 on the longer side), and --look-from with negative numbers and --fov are taken.
#[test]
fn view_options_are_renders() {
    let dir = tempfile::tempdir().unwrap();
    let file = common::wide_camera_box(dir.path());
    let file = file.to_str().unwrap();
    let (code, v, o) = info_json(dir.path(), file, &["-a", "pt", "--look-from", "-1,2.5,-4", "--fov", "30"]);
    assert_eq!(code, Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    let p = &v["plan"];
    assert_eq!((p["width"].as_u64(), p["height"].as_u64()), (Some(512), Some(256)), "{p}");
    assert!((v["scene"]["camera_used"]["yfov_degrees"].as_f64().unwrap() - 30.0).abs() < 1e-4, "{}", v["scene"]);
    assert!((v["scene"]["camera_used"]["aspect"].as_f64().unwrap() - 2.0).abs() < 1e-9, "{}", v["scene"]);
    let (code, _, o) = info_json(dir.path(), "gbs_s", &["--width", "0"]);
    assert_eq!(code, Some(2), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn instanced_scene() {
    let dir = tempfile::tempdir().unwrap();
    let path = common::instanced_gltf::write_instanced_gltf(dir.path());
    let file = path.to_str().unwrap();
    let (code, v, o) = info_json(dir.path(), file, &["--width", "16", "--height", "16"]);
    assert_eq!(code, Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    let s = &v["scene"];
    let placed = s["triangles"].as_u64().unwrap();
    assert!(s["instances"].as_u64().unwrap() > 1, "{s}");
    assert!(s["shared_meshes"].as_u64().unwrap() >= 1);
    assert!(placed > s["stored_triangles"].as_u64().unwrap(), "{s}");
    assert_eq!(v["features"]["instances"], true);
    assert!(s["extensions_used"].as_array().unwrap().iter().any(|e| e == "EXT_mesh_gpu_instancing"), "{s}");
    // Flattened: the same triangles placed, every one stored, no instances.
    let (_, f, _) = info_json(dir.path(), file, &["--width", "16", "--height", "16", "--flatten-instances"]);
    assert_eq!(f["scene"]["instances"], 0);
    assert_eq!(f["scene"]["triangles"].as_u64(), Some(placed));
    assert_eq!(f["scene"]["stored_triangles"].as_u64(), Some(placed));
    assert_eq!(f["features"]["instances"], false);
}

#[test]
fn malformed_scene_is_one_error_and_exit_code_3() {
    let dir = tempfile::tempdir().unwrap();
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/malformed/bad_json.gltf");
    let (code, v, o) = info_json(dir.path(), file.to_str().unwrap(), &[]);
    assert_eq!(code, Some(3), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(v.is_null() && o.stdout.is_empty(), "printed a report for a scene it could not read");
    let err = String::from_utf8_lossy(&o.stderr);
    let errors: Vec<&str> = err.lines().filter(|l| l.starts_with("error")).collect();
    assert!(errors.len() == 1 && errors[0].contains("bad_json.gltf"), "{err}");
}

#[test]
fn too_large_a_frame_is_reported_with_exit_code_5() {
    let dir = tempfile::tempdir().unwrap();
    let (code, v, _) = info_json(dir.path(), "gbs_s", &["-a", "pt", "--width", "100000", "--height", "40000"]);
    assert_eq!(code, Some(5));
    assert_eq!(v["plan"]["fits"], false);
    assert!(v["plan"]["error"].as_str().unwrap().contains("film"), "{}", v["plan"]);
    assert!(sum_bytes(&v) > 100_000u64 * 40_000 * 16, "the film alone is 16 bytes a pixel or more");
}
