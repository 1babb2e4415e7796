//! Per-kernel GPU time from timestamp queries, reported by `--profile`.

use serde::Serialize;

/// Accumulated time of one kernel.
#[derive(Clone, Debug, Default, Serialize)]
pub struct KernelTime {
    pub kernel: String,
    pub calls: u64,
    pub total_ms: f64,
}

/// Kernel timings in first-dispatch order.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Profile {
    pub kernels: Vec<KernelTime>,
}

impl Profile {
    pub fn add(&mut self, kernel: &str, ns: f64) {
        let i = match self.kernels.iter().position(|k| k.kernel == kernel) {
            Some(i) => i,
            None => {
                self.kernels.push(KernelTime { kernel: kernel.to_string(), ..Default::default() });
                self.kernels.len() - 1
            }
        };
        self.kernels[i].calls += 1;
        self.kernels[i].total_ms += ns * 1e-6;
    }

    pub fn total_ms(&self) -> f64 {
        self.kernels.iter().map(|k| k.total_ms).sum()
    }

    /// A text table: kernel, calls, total ms, mean ms, share.
    pub fn table(&self) -> String {
        let total = self.total_ms().max(1e-12);
        let w = self.kernels.iter().map(|k| k.kernel.len()).max().unwrap_or(6).max(6);
        let mut s = format!("{:<w$} {:>7} {:>11} {:>10} {:>7}\n", "kernel", "calls", "total ms", "mean ms", "share");
        for k in &self.kernels {
            s += &format!(
                "{:<w$} {:>7} {:>11.3} {:>10.4} {:>6.1}%\n",
                k.kernel,
                k.calls,
                k.total_ms,
                k.total_ms / k.calls.max(1) as f64,
                100.0 * k.total_ms / total
            );
        }
        s += &format!("{:<w$} {:>7} {:>11.3}\n", "total", "", self.total_ms());
        s
    }
}
