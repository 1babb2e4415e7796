//! Progress reporting: a bar on a terminal, plain lines otherwise.

use std::io::IsTerminal;

use indicatif::{ProgressBar, ProgressStyle};

use vkvcm::render::{Budget, Progress};

/// A progress bar on a terminal, plain lines otherwise.
pub struct Reporter {
    bar: Option<ProgressBar>,
    last_line: f64,
}

impl Reporter {
    pub fn new(budget: Budget) -> Self {
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
        Reporter { bar, last_line: -1.0 }
    }

    pub fn update(&mut self, p: &Progress, pixels: f64) {
        let rate = p.iterations as f64 * pixels / p.seconds.max(1e-9);
        let msg = format!("{} it, {:.2} Msamples/s", p.iterations, rate * 1e-6);
        match &self.bar {
            Some(b) => {
                let len = b.length().unwrap_or(1);
                b.set_position((p.fraction * len as f64).round() as u64);
                b.set_message(msg);
            }
            None => {
                if p.seconds - self.last_line >= 5.0 || p.fraction >= 1.0 {
                    self.last_line = p.seconds;
                    eprintln!("progress: {:5.1}% {msg}, {:.1} s", 100.0 * p.fraction, p.seconds);
                }
            }
        }
    }

    pub fn finish(&self) {
        if let Some(b) = &self.bar {
            b.finish_and_clear();
        }
    }
}
