//! Per-kernel GPU time from timestamp queries, reported by `--profile`: per kernel, per
//! pass (the name a renderer gave its dispatches with `Batch::begin_pass`) and
//! iteration, with the rays traced per second when they were counted.

use serde::Serialize;

/// Accumulated time of one kernel in one pass.
#[derive(Clone, Debug, Default, Serialize)]
pub struct KernelTime {
    /// The pass it was dispatched in.
    pub stage: String,
    pub kernel: String,
    pub calls: u64,
    pub total_ms: f64,
}

/// Kernel timings in first-dispatch order.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Profile {
    pub kernels: Vec<KernelTime>,
    /// Iterations the timings cover, and their wall-clock seconds (set by the renderer).
    pub iterations: u64,
    pub wall_seconds: f64,
    /// Rays traced in those iterations, when counted (kernels built with COUNT_RAYS).
    pub rays: Option<u64>,
    /// Every timed dispatch, when asked for (`render --profile-trace`); else `None`.
    #[serde(skip)]
    pub dispatches: Option<Vec<DispatchEvent>>,
}

/// One timed dispatch, for a trace (`render --profile-trace`).
#[derive(Clone, Debug)]
pub struct DispatchEvent {
    pub pass: String,
    pub kernel: String,
    pub groups: [u32; 3],
    /// The iteration it belongs to, as the renderer said ([`crate::gpu::Batch::set_iteration`]).
    pub iteration: Option<u64>,
    /// Start and duration in microseconds on the [`trace_clock_us`] clock: the GPU's
    /// timestamps, placed so that the batch's first dispatch starts when it was submitted.
    pub start_us: f64,
    pub duration_us: f64,
}

/// Microseconds since the process's first call: the clock of traces' host and GPU events.
pub fn trace_clock_us() -> f64 {
    static EPOCH: std::sync::OnceLock<std::time::Instant> = std::sync::OnceLock::new();
    EPOCH.get_or_init(std::time::Instant::now).elapsed().as_secs_f64() * 1e6
}

/// GPU time of one stage.
#[derive(Clone, Debug, Serialize)]
pub struct StageTime {
    pub stage: String,
    /// Its kernels, in first-dispatch order.
    pub kernels: Vec<String>,
    pub ms_per_iteration: f64,
    /// Fraction of the GPU time of all stages.
    pub share: f64,
}

impl Profile {
    /// Adds one dispatch of `kernel` in pass `stage` that took `ns` nanoseconds.
    pub fn add(&mut self, stage: &str, kernel: &str, ns: f64) {
        let i = self.entry(stage, kernel);
        self.kernels[i].calls += 1;
        self.kernels[i].total_ms += ns * 1e-6;
    }

    /// The index of (`stage`, `kernel`) in `kernels`, added if new.
    fn entry(&mut self, stage: &str, kernel: &str) -> usize {
        match self.kernels.iter().position(|k| k.stage == stage && k.kernel == kernel) {
            Some(i) => i,
            None => {
                self.kernels.push(KernelTime {
                    stage: stage.to_string(),
                    kernel: kernel.to_string(),
                    ..Default::default()
                });
                self.kernels.len() - 1
            }
        }
    }

    /// Counts `n` more iterations that took `seconds` of wall-clock time.
    pub fn add_iterations(&mut self, n: u64, seconds: f64) {
        self.iterations += n;
        self.wall_seconds += seconds;
    }

    /// What was added since `earlier` (an earlier copy of this profile).
    pub fn since(&self, earlier: &Profile) -> Profile {
        let kernels = self
            .kernels
            .iter()
            .map(|k| {
                let e = earlier.kernels.iter().find(|e| e.stage == k.stage && e.kernel == k.kernel);
                KernelTime {
                    stage: k.stage.clone(),
                    kernel: k.kernel.clone(),
                    calls: k.calls - e.map_or(0, |e| e.calls),
                    total_ms: k.total_ms - e.map_or(0.0, |e| e.total_ms),
                }
            })
            .filter(|k| k.calls > 0)
            .collect();
        Profile {
            kernels,
            iterations: self.iterations - earlier.iterations,
            wall_seconds: self.wall_seconds - earlier.wall_seconds,
            rays: self.rays.map(|r| r - earlier.rays.unwrap_or(0)),
            dispatches: None,
        }
    }

    /// Adds `other`'s timings, iterations and rays to this profile.
    pub fn absorb(&mut self, other: &Profile) {
        for k in &other.kernels {
            let i = self.entry(&k.stage, &k.kernel);
            self.kernels[i].calls += k.calls;
            self.kernels[i].total_ms += k.total_ms;
        }
        self.iterations += other.iterations;
        self.wall_seconds += other.wall_seconds;
        self.rays = match (self.rays, other.rays) {
            (None, None) => None,
            (a, b) => Some(a.unwrap_or(0) + b.unwrap_or(0)),
        };
    }

    pub fn total_ms(&self) -> f64 {
        self.kernels.iter().map(|k| k.total_ms).sum()
    }

    /// GPU time per iteration of each pass, in the order the passes first ran.
    pub fn stages(&self) -> Vec<StageTime> {
        let n = self.iterations.max(1) as f64;
        let total = self.total_ms().max(1e-12);
        let mut names: Vec<&str> = Vec::new();
        for k in &self.kernels {
            if !names.contains(&k.stage.as_str()) {
                names.push(&k.stage);
            }
        }
        names
            .into_iter()
            .map(|stage| {
                let ks: Vec<&KernelTime> = self.kernels.iter().filter(|k| k.stage == stage).collect();
                let ms: f64 = ks.iter().map(|k| k.total_ms).sum();
                StageTime {
                    stage: stage.to_string(),
                    kernels: ks.iter().map(|k| k.kernel.clone()).collect(),
                    ms_per_iteration: ms / n,
                    share: ms / total,
                }
            })
            .collect()
    }

    /// Rays per second of wall-clock time, when rays were counted.
    pub fn rays_per_second(&self) -> Option<f64> {
        self.rays.filter(|_| self.wall_seconds > 0.0).map(|r| r as f64 / self.wall_seconds)
    }

    /// Rays per second of GPU (kernel) time, when rays were counted.
    pub fn rays_per_gpu_second(&self) -> Option<f64> {
        let s = self.total_ms() * 1e-3;
        self.rays.filter(|_| s > 0.0).map(|r| r as f64 / s)
    }

    /// A text table: pass and kernel, calls, total ms, mean ms, share.
    pub fn table(&self) -> String {
        let total = self.total_ms().max(1e-12);
        let label = |k: &KernelTime| format!("{}: {}", k.stage, k.kernel);
        let w = self.kernels.iter().map(|k| label(k).len()).max().unwrap_or(6).max(6);
        let mut s = format!("{:<w$} {:>7} {:>11} {:>10} {:>7}\n", "kernel", "calls", "total ms", "mean ms", "share");
        for k in &self.kernels {
            s += &format!(
                "{:<w$} {:>7} {:>11.3} {:>10.4} {:>6.1}%\n",
                label(k),
                k.calls,
                k.total_ms,
                k.total_ms / k.calls.max(1) as f64,
                100.0 * k.total_ms / total
            );
        }
        s += &format!("{:<w$} {:>7} {:>11.3}\n", "total", "", self.total_ms());
        s
    }

    /// The stage table (GPU ms per iteration) and the ray throughput, then [`Profile::table`].
    pub fn report(&self) -> String {
        let mut s = format!("{:<19} {:>12} {:>7}  kernels\n", "stage", "ms/iteration", "share");
        for st in self.stages() {
            s += &format!(
                "{:<19} {:>12.3} {:>6.1}%  {}\n",
                st.stage,
                st.ms_per_iteration,
                100.0 * st.share,
                st.kernels.join(", ")
            );
        }
        s += &format!(
            "{:<19} {:>12.3}          ({} iterations, {:.3} s wall)\n",
            "total",
            self.total_ms() / self.iterations.max(1) as f64,
            self.iterations,
            self.wall_seconds
        );
        if let (Some(r), Some(rw), Some(rg)) = (self.rays, self.rays_per_second(), self.rays_per_gpu_second()) {
            s += &format!(
                "rays: {r} traced ({:.0} per iteration), {:.3} M/s of wall time, {:.3} M/s of GPU time\n",
                r as f64 / self.iterations.max(1) as f64,
                rw * 1e-6,
                rg * 1e-6
            );
        }
        s + &self.table()
    }
}

/// What `--profile-json` writes: the profile of one render with its stages per iteration.
#[derive(Clone, Debug, Serialize)]
pub struct ProfileReport {
    pub scene: String,
    pub estimator: String,
    pub width: u32,
    pub height: u32,
    /// Iterations timed (this run; a resumed render's earlier ones are not included).
    pub iterations: u64,
    pub wall_seconds: f64,
    pub gpu_ms_per_iteration: f64,
    pub samples_per_second: f64,
    pub stages: Vec<StageTime>,
    pub kernels: Vec<KernelTime>,
    pub rays: Option<u64>,
    pub rays_per_second: Option<f64>,
    pub rays_per_gpu_second: Option<f64>,
    /// How the render ran, when the caller says (`vkvcm render` does): paths per kernel
    /// invocation (src/render/regen.rs) and how the kernels read their read-only buffers
    /// (src/render/reads.rs). Neither changes the image; both change the time.
    pub paths_per_invocation: Option<u32>,
    pub reads: Option<String>,
}

impl ProfileReport {
    pub fn new(p: &Profile, scene: &str, estimator: &str, width: u32, height: u32) -> ProfileReport {
        let samples = width as f64 * height as f64 * p.iterations as f64;
        ProfileReport {
            scene: scene.to_string(),
            estimator: estimator.to_string(),
            width,
            height,
            iterations: p.iterations,
            wall_seconds: p.wall_seconds,
            gpu_ms_per_iteration: p.total_ms() / p.iterations.max(1) as f64,
            samples_per_second: if p.wall_seconds > 0.0 { samples / p.wall_seconds } else { 0.0 },
            stages: p.stages(),
            kernels: p.kernels.clone(),
            rays: p.rays,
            rays_per_second: p.rays_per_second(),
            rays_per_gpu_second: p.rays_per_gpu_second(),
            paths_per_invocation: None,
            reads: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stages_group_kernels_in_pipeline_order() {
        let mut p = Profile::default();
        for (stage, k, ms) in [
            ("light subpaths", "light_subpath.comp", 2.0),
            ("grid build", "hash_grid_count.comp", 0.5),
            ("grid build", "exclusive_scan.comp", 0.25),
            ("grid build", "exclusive_scan.comp", 0.25),
            ("camera subpaths", "camera_subpath.comp", 3.0),
        ] {
            p.add(stage, k, ms * 1e6);
        }
        p.add_iterations(2, 0.01);
        p.rays = Some(1000);
        let st = p.stages();
        let names: Vec<&str> = st.iter().map(|s| s.stage.as_str()).collect();
        assert_eq!(names, ["light subpaths", "grid build", "camera subpaths"]);
        assert_eq!(st[1].kernels, ["hash_grid_count.comp", "exclusive_scan.comp"]);
        assert!((st[1].ms_per_iteration - 0.5).abs() < 1e-12);
        assert!((st[2].share - 0.5).abs() < 1e-12);
        assert!((p.rays_per_second().unwrap() - 1e5).abs() < 1e-6);
        assert!(p.report().contains("grid build"));
    }
}
