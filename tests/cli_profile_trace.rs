//! `vkvcm render --profile-trace`: the file is a Chrome trace-event document (what
//! Perfetto and chrome://tracing open): complete events on a CPU and a GPU track that
//! nest, one GPU slice per timed dispatch (as many as --profile-json counts), each with
//! its pass, kernel, iteration and workgroups, and timestamps increasing per track.

use std::collections::BTreeSet;
use std::path::Path;
use std::process::Command;

use serde_json::Value;

mod common;

fn vkvcm(dir: &Path) -> Command {
    common::vkvcm_in(dir)
}

/// Fails unless any two of `slices` (start, end) are disjoint or one holds the other.
fn assert_nested(track: &str, slices: &[(f64, f64, String)]) {
    const EPS: f64 = 1e-3;
    for (i, a) in slices.iter().enumerate() {
        for b in &slices[i + 1..] {
            let disjoint = a.1 <= b.0 + EPS || b.1 <= a.0 + EPS;
            let a_holds_b = a.0 <= b.0 + EPS && b.1 <= a.1 + EPS;
            let b_holds_a = b.0 <= a.0 + EPS && a.1 <= b.1 + EPS;
            assert!(disjoint || a_holds_b || b_holds_a, "{track}: {a:?} and {b:?} overlap without nesting");
        }
    }
}

#[test]
fn trace_has_every_dispatch_on_a_gpu_track() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let o = vkvcm(d)
        .args(["render", "-a", "vcm", "--width", "16", "--height", "16", "-i", "3", "-o", "x.exr"])
        .args(["--profile-trace", "t.json", "--profile-json", "p.json"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success() && !err.contains("validation"), "{err}");
    let trace: Value = serde_json::from_slice(&std::fs::read(d.join("t.json")).unwrap()).unwrap();
    let events = trace["traceEvents"].as_array().expect("traceEvents");
    // Thread names say which track is which.
    let tid_of = |name: &str| {
        events
            .iter()
            .find(|e| e["ph"] == "M" && e["name"] == "thread_name" && e["args"]["name"] == name)
            .and_then(|e| e["tid"].as_u64())
            .unwrap_or_else(|| panic!("no {name} track"))
    };
    let (cpu, gpu) = (tid_of("CPU"), tid_of("GPU"));
    for e in events.iter().filter(|e| e["ph"] != "M") {
        assert_eq!(e["ph"], "X", "{e}");
        assert!(e["name"].is_string() && e["pid"].is_u64() && e["tid"].is_u64(), "{e}");
        assert!(e["ts"].as_f64().unwrap() >= 0.0 && e["dur"].as_f64().unwrap() >= 0.0, "{e}");
    }
    let track = |tid: u64| -> Vec<&Value> { events.iter().filter(|e| e["ph"] == "X" && e["tid"] == tid).collect() };
    let slices = |v: &[&Value]| -> Vec<(f64, f64, String)> {
        v.iter()
            .map(|e| {
                let ts = e["ts"].as_f64().unwrap();
                (ts, ts + e["dur"].as_f64().unwrap(), e["name"].as_str().unwrap().to_string())
            })
            .collect()
    };
    // GPU: in recording order, each dispatch starts after the one before has started.
    let g = track(gpu);
    let gs = slices(&g);
    assert!(gs.windows(2).all(|w| w[0].0 <= w[1].0), "GPU timestamps go back");
    assert_nested("GPU", &gs);
    let profile: Value = serde_json::from_slice(&std::fs::read(d.join("p.json")).unwrap()).unwrap();
    let calls: u64 = profile["kernels"].as_array().unwrap().iter().map(|k| k["calls"].as_u64().unwrap()).sum();
    assert_eq!(g.len() as u64, calls, "one GPU slice per timed dispatch");
    let mut iterations = BTreeSet::new();
    let mut passes = BTreeSet::new();
    for e in &g {
        let a = &e["args"];
        assert_eq!(a["kernel"], e["name"]);
        let groups: Vec<u64> = a["workgroups"].as_array().unwrap().iter().map(|n| n.as_u64().unwrap()).collect();
        assert!(groups.len() == 3 && groups.iter().all(|&n| n > 0), "{e}");
        iterations.insert(a["iteration"].as_u64().expect("iteration"));
        passes.insert(a["pass"].as_str().unwrap().to_string());
    }
    assert_eq!(iterations, (0..3).collect(), "dispatches of iterations 0, 1, 2");
    for p in ["light subpaths", "grid build", "camera subpaths"] {
        assert!(passes.contains(p), "no {p} pass in {passes:?}");
    }
    // CPU: the host phases, nested, increasing once sorted by start.
    let mut cs = slices(&track(cpu));
    cs.sort_by(|a, b| a.0.total_cmp(&b.0));
    assert_nested("CPU", &cs);
    for phase in ["scene load", "device open", "prepare", "render", "readback", "write EXR"] {
        assert!(cs.iter().any(|s| s.2.starts_with(phase)), "no {phase} phase in {cs:?}");
    }
    // The dispatches happen inside the render phase.
    let render = cs.iter().find(|s| s.2 == "render").unwrap();
    assert!(gs.iter().all(|s| s.0 >= render.0 && s.1 <= render.1 + 1e-3), "dispatches outside the render phase");
}
