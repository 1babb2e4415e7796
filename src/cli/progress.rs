//! Progress reporting: a bar on a terminal, plain lines otherwise.

use std::io::IsTerminal;

use indicatif::{ProgressBar, ProgressStyle};

use vkvcm::render::{Budget, Progress};

/// A progress bar on a terminal, plain lines otherwise (the first after the first batch,
/// then every 5 s).
pub struct Reporter {
    bar: Option<ProgressBar>,
    budget: Budget,
    /// Iterations and seconds of a resumed render: `--time` counts from here, while an
    /// iteration budget is the total.
    base_seconds: f64,
    base_iterations: u64,
    last_line: f64,
}

impl Reporter {
    pub fn new(budget: Budget, base_iterations: u64, base_seconds: f64) -> Self {
        let bar = std::io::stderr().is_terminal().then(|| {
            let total = match budget {
                Budget::Iterations(n) => n,
                Budget::Seconds(_) => 1000,
            };
            let b = ProgressBar::new(total);
            b.set_style(
                ProgressStyle::with_template("{bar:40} {msg} [{elapsed_precise} < {eta_precise}]")
                    .unwrap_or_else(|_| ProgressStyle::default_bar()),
            );
            b
        });
        Reporter { bar, budget, base_seconds, base_iterations, last_line: -1.0 }
    }

    pub fn update(&mut self, p: &Progress, pixels: f64) {
        let seconds = p.seconds - self.base_seconds;
        let fraction = match self.budget {
            Budget::Iterations(n) => p.iterations as f64 / n as f64,
            Budget::Seconds(t) => seconds / t,
        }
        .clamp(0.0, 1.0);
        let rate = (p.iterations - self.base_iterations) as f64 * pixels / seconds.max(1e-9);
        let msg = format!("{} it, {:.2} Msamples/s", p.iterations, rate * 1e-6);
        match &self.bar {
            Some(b) => {
                let len = b.length().unwrap_or(1);
                b.set_position((fraction * len as f64).round() as u64);
                b.set_message(msg);
            }
            None => {
                if seconds - self.last_line >= 5.0 || fraction >= 1.0 || self.last_line < 0.0 {
                    self.last_line = seconds;
                    eprintln!("progress: {:5.1}% {msg}, {:.1} s", 100.0 * fraction, p.seconds);
                }
            }
        }
    }

    /// A line that does not disturb the bar.
    pub fn note(&self, line: &str) {
        match &self.bar {
            Some(b) => b.println(line),
            None => eprintln!("{line}"),
        }
    }

    pub fn finish(&self) {
        if let Some(b) = &self.bar {
            b.finish_and_clear();
        }
    }
}
