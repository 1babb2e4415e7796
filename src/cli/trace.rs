//! `render --profile-trace FILE`: a trace in the Chrome trace-event format (JSON), which
//! Perfetto (ui.perfetto.dev) and chrome://tracing open. One process, two tracks: the
//! host's phases on "CPU" (complete events, "ph":"X", nested in time) and every timed
//! dispatch on "GPU" with its pass, kernel, iteration and workgroups. Times are in
//! microseconds on one clock (`vkvcm::gpu::trace_clock_us`).

use std::sync::Mutex;

use anyhow::Result;
use serde_json::{json, Value};

use vkvcm::gpu::{trace_clock_us, DispatchEvent};

const PID: u32 = 1;
const CPU_TID: u32 = 1;
const GPU_TID: u32 = 2;

/// The events so far; `None` unless a trace was asked for (then recording is a no-op).
static EVENTS: Mutex<Option<Vec<Value>>> = Mutex::new(None);

/// Starts recording.
pub fn start() {
    trace_clock_us();
    if let Ok(mut e) = EVENTS.lock() {
        *e = Some(Vec::new());
    }
}

fn push(v: Value) {
    if let Ok(mut e) = EVENTS.lock() {
        if let Some(list) = e.as_mut() {
            list.push(v);
        }
    }
}

/// A host phase that ends when the returned guard drops; `args` are shown with it.
pub fn phase(name: &str) -> Phase {
    Phase { name: name.to_string(), start: trace_clock_us(), args: json!({}) }
}

pub struct Phase {
    name: String,
    start: f64,
    args: Value,
}

impl Phase {
    /// Adds an argument shown with the phase.
    pub fn arg(&mut self, key: &str, value: Value) {
        self.args[key] = value;
    }
}

impl Drop for Phase {
    fn drop(&mut self) {
        let dur = trace_clock_us() - self.start;
        push(json!({"name": self.name, "cat": "host", "ph": "X", "ts": self.start, "dur": dur,
            "pid": PID, "tid": CPU_TID, "args": self.args}));
    }
}

/// The GPU track's events for `dispatches`.
pub fn dispatches(dispatches: &[DispatchEvent]) {
    for d in dispatches {
        push(json!({"name": d.kernel, "cat": d.pass, "ph": "X", "ts": d.start_us, "dur": d.duration_us,
            "pid": PID, "tid": GPU_TID,
            "args": {"pass": d.pass, "kernel": d.kernel, "iteration": d.iteration, "workgroups": d.groups}}));
    }
}

/// Writes the trace (atomically) when one was asked for.
pub fn write(path: &std::path::Path) -> Result<()> {
    let events = EVENTS.lock().map(|e| e.clone().unwrap_or_default()).unwrap_or_default();
    let name =
        |tid: u32, n: &str| json!({"name": "thread_name", "ph": "M", "pid": PID, "tid": tid, "args": {"name": n}});
    let mut all = vec![
        json!({"name": "process_name", "ph": "M", "pid": PID, "args": {"name": "vkvcm render"}}),
        name(CPU_TID, "CPU"),
        name(GPU_TID, "GPU"),
    ];
    all.extend(events);
    super::write_json(path, &json!({"traceEvents": all, "displayTimeUnit": "ms"}))
}
