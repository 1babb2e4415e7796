//! The Kubernetes jobs of docs/distributed.md ("Kubernetes"), run without Kubernetes: the
//! container command of kubernetes/render-job.yaml (an Indexed Job) is read from the manifest
//! and run as the container runs it (`sh -c`, the manifest's environment) once for each
//! JOB_COMPLETION_INDEX, then kubernetes/merge-job.yaml's command; the merged image must be
//! bit for bit the same render done in one process. Two changes, both checked against the
//! manifests rather than assumed: the volume's mount point becomes a temporary folder, and the
//! render's size and iterations become tiny (its scene, seed and other options stay).

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use yaml_rust2::{Yaml, YamlLoader};

mod common;

fn manifest(name: &str) -> Yaml {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("kubernetes").join(name);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut docs = YamlLoader::load_from_str(&text).unwrap_or_else(|e| panic!("{name}: {e}"));
    assert_eq!(docs.len(), 1, "{name}: one document expected");
    docs.remove(0)
}

fn strings(y: &Yaml, what: &str) -> Vec<String> {
    match y {
        Yaml::BadValue => Vec::new(),
        _ => y
            .as_vec()
            .unwrap_or_else(|| panic!("{what} is not a list"))
            .iter()
            .map(|s| s.as_str().unwrap_or_else(|| panic!("{what}: {s:?} is not a string")).to_string())
            .collect(),
    }
}

/// A Job's one container: its command line (command then args), environment, and the
/// claim and mount point of its one volume.
struct Container {
    command: Vec<String>,
    args: Vec<String>,
    env: HashMap<String, String>,
    mount_path: String,
    claim: String,
}

fn container(job: &Yaml, name: &str) -> Container {
    assert_eq!(job["kind"].as_str(), Some("Job"), "{name}");
    let pod = &job["spec"]["template"]["spec"];
    let containers = pod["containers"].as_vec().unwrap_or_else(|| panic!("{name}: no containers"));
    assert_eq!(containers.len(), 1, "{name}: one container expected");
    let c = &containers[0];
    let env = c["env"]
        .as_vec()
        .unwrap_or_else(|| panic!("{name}: no env"))
        .iter()
        .map(|e| (e["name"].as_str().unwrap().to_string(), e["value"].as_str().unwrap().to_string()))
        .collect();
    let mounts = c["volumeMounts"].as_vec().unwrap_or_else(|| panic!("{name}: no volumeMounts"));
    let volumes = pod["volumes"].as_vec().unwrap_or_else(|| panic!("{name}: no volumes"));
    assert_eq!((mounts.len(), volumes.len()), (1, 1), "{name}: one volume expected");
    assert_eq!(mounts[0]["name"], volumes[0]["name"], "{name}: the mount is not the volume");
    Container {
        command: strings(&c["command"], &format!("{name}: command")),
        args: strings(&c["args"], &format!("{name}: args")),
        env,
        mount_path: mounts[0]["mountPath"].as_str().unwrap().to_string(),
        claim: volumes[0]["persistentVolumeClaim"]["claimName"].as_str().unwrap().to_string(),
    }
}

/// Runs `c`'s command line as its container would, in `dir`, with `vkvcm` on the PATH (the
/// binary under test, with the CLI tests' environment), the manifest's environment but the
/// volume's mount point at `shards`, and `extra` variables.
fn run(c: &Container, args: &[String], dir: &Path, shards: &Path, extra: &[(&str, String)]) -> Output {
    assert_eq!(c.env.get("SHARDS_DIR"), Some(&c.mount_path), "SHARDS_DIR is not the volume's mount point");
    let mut cmd = Command::new(&c.command[0]);
    cmd.args(&c.command[1..]).args(args).current_dir(dir);
    // The CLI tests' environment (validation on, the suite's kernel cache, lavapipe).
    for (k, v) in common::vkvcm_in(dir).get_envs() {
        match v {
            Some(v) => cmd.env(k, v),
            None => cmd.env_remove(k),
        };
    }
    let bin = PathBuf::from(env!("CARGO_BIN_EXE_vkvcm"));
    let path = std::env::join_paths(
        std::iter::once(bin.parent().unwrap().to_path_buf())
            .chain(std::env::split_paths(&std::env::var_os("PATH").unwrap_or_default())),
    )
    .unwrap();
    cmd.env("PATH", path).envs(&c.env).env("SHARDS_DIR", shards);
    for (k, v) in extra {
        cmd.env(k, v);
    }
    let out = cmd.output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{:?} {args:?} with {extra:?} failed:\n{err}", c.command);
    assert!(!err.contains("validation"), "validation message:\n{err}");
    out
}

/// The manifest's render arguments with `option`'s value replaced by `value`.
fn replace(args: &mut [String], option: &str, value: &str) {
    let i = args.iter().position(|a| a == option).unwrap_or_else(|| panic!("render-job.yaml's args lack {option}"));
    args[i + 1] = value.to_string();
}

#[test]
fn indexed_job_then_merge_equals_one_render() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let shards = d.join("shards");
    std::fs::create_dir(&shards).unwrap();

    let volume = manifest("shards-volume.yaml");
    assert_eq!(volume["kind"].as_str(), Some("PersistentVolumeClaim"));
    let claim = volume["metadata"]["name"].as_str().unwrap();

    let job = manifest("render-job.yaml");
    assert_eq!(job["spec"]["completionMode"].as_str(), Some("Indexed"));
    let n = job["spec"]["completions"].as_i64().expect("render-job.yaml: completions");
    let render = container(&job, "render-job.yaml");
    assert_eq!(render.env.get("SHARDS"), Some(&n.to_string()), "render-job.yaml: SHARDS is not completions");
    assert_eq!(render.claim, claim, "render-job.yaml: not the shards' volume");
    let mut args = render.args.clone();
    replace(&mut args, "--width", "32");
    replace(&mut args, "--height", "32");
    replace(&mut args, "--iterations", "12");
    for k in 0..n {
        run(&render, &args, d, &shards, &[("JOB_COMPLETION_INDEX", k.to_string())]);
        assert!(shards.join(format!("shard-{k}.exr")).is_file(), "index {k} wrote no shards/shard-{k}.exr");
    }

    let merge = container(&manifest("merge-job.yaml"), "merge-job.yaml");
    assert_eq!(merge.env.get("SHARDS"), render.env.get("SHARDS"), "merge-job.yaml: SHARDS is not the render job's");
    assert_eq!(merge.claim, claim, "merge-job.yaml: not the shards' volume");
    run(&merge, &merge.args, d, &shards, &[]);
    assert!(shards.join("merged.png").is_file(), "the merge job wrote no merged.png");

    let one = common::vkvcm_in(d).arg("render").args(&args).args(["-o", "one.exr", "--quiet"]).output().unwrap();
    assert!(one.status.success(), "{}", String::from_utf8_lossy(&one.stderr));
    let diff =
        common::vkvcm_in(d).arg("diff").arg("--exact").arg(shards.join("merged.exr")).arg("one.exr").output().unwrap();
    assert!(
        diff.status.success(),
        "the merged image is not the one-process render:\n{}{}",
        String::from_utf8_lossy(&diff.stdout),
        String::from_utf8_lossy(&diff.stderr)
    );
}
