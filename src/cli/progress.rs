//! Progress reporting: a bar on a terminal, plain lines otherwise. [`Reporter`]: renders;
//! [`ActivityLines`]: the library's long activities (scene loads, BVH builds).

use std::io::{IsTerminal, Write};
use std::sync::mpsc::{self, RecvTimeoutError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use vkvcm::activity::{Observer, Tracker};
use vkvcm::render::{Budget, Progress};

/// An activity shows progress only once it has run this long.
const ACTIVITY_SHOWN_AFTER: Duration = Duration::from_secs(1);
/// Plain lines (stderr not a terminal): one per this interval while an activity runs.
const PLAIN_LINE_EVERY: Duration = Duration::from_secs(5);

/// The binary's [`Observer`] of library activities (installed in main). An activity that
/// runs for more than [`ACTIVITY_SHOWN_AFTER`] gets, on a terminal, a bar (a spinner when
/// its amount of work is unknown) that is cleared when it ends; when stderr is not a
/// terminal, a plain line every [`PLAIN_LINE_EVERY`] and one when it ends. Shorter
/// activities show nothing, so tests and logs of small scenes stay as they were.
pub struct ActivityLines;

impl Observer for ActivityLines {
    fn begin(&self, what: String, total: Option<u64>) -> Box<dyn Tracker> {
        // The bar counts from the start, drawn nowhere until the activity is shown.
        let bar = ProgressBar::with_draw_target(total, ProgressDrawTarget::hidden());
        // Dropping `ended` (when the activity ends) wakes the thread that shows it.
        let (ended, wait) = mpsc::channel::<()>();
        let shown = bar.clone();
        let thread = std::thread::Builder::new()
            .name("activity progress".into())
            .spawn(move || show_activity(&shown, &what, &wait, std::io::stderr().is_terminal(), &mut std::io::stderr()))
            .ok();
        Box::new(ActivityLine { bar, ended: Some(ended), thread })
    }
}

struct ActivityLine {
    bar: ProgressBar,
    ended: Option<mpsc::Sender<()>>,
    thread: Option<JoinHandle<()>>,
}

impl Tracker for ActivityLine {
    fn advance(&self, units: u64) {
        self.bar.inc(units);
    }
}

impl Drop for ActivityLine {
    fn drop(&mut self) {
        drop(self.ended.take());
        // The line is complete (or cleared) before anything else is printed.
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// Shows the activity `what` counted by `bar` until `wait` disconnects (see
/// [`ActivityLines`]): as a bar on stderr if `terminal`, else as plain lines on `lines`.
fn show_activity(bar: &ProgressBar, what: &str, wait: &mpsc::Receiver<()>, terminal: bool, lines: &mut dyn Write) {
    let start = Instant::now();
    if wait.recv_timeout(ACTIVITY_SHOWN_AFTER) != Err(RecvTimeoutError::Timeout) {
        return;
    }
    let sized = bar.length().is_some_and(|n| n > 0);
    if terminal {
        let template = if sized {
            "{bar:40} {percent:>3}% {msg} [{elapsed_precise}]"
        } else {
            "{spinner} {msg} [{elapsed_precise}]"
        };
        bar.set_style(ProgressStyle::with_template(template).unwrap_or_else(|_| ProgressStyle::default_bar()));
        bar.set_message(what.to_string());
        bar.set_draw_target(ProgressDrawTarget::stderr());
        bar.enable_steady_tick(Duration::from_millis(100));
        let _ = wait.recv();
        bar.finish_and_clear();
    } else {
        let done = || match bar.length() {
            Some(n) if sized => format!(" {:.0}% done", 100.0 * bar.position() as f64 / n as f64),
            _ => String::new(),
        };
        // A progress line that cannot be written is not worth failing the work for.
        while wait.recv_timeout(PLAIN_LINE_EVERY) == Err(RecvTimeoutError::Timeout) {
            let _ = writeln!(lines, "{what}:{} after {:.0} s", done(), start.elapsed().as_secs_f64());
        }
        let _ = writeln!(lines, "{what}: took {:.1} s", start.elapsed().as_secs_f64());
    }
}

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
    /// --quiet: no bar, no progress lines; only warnings among the notes.
    quiet: bool,
    /// render --reference: the error of the last image read back, shown on each line.
    error: Option<String>,
}

impl Reporter {
    pub fn new(budget: Budget, base_iterations: u64, base_seconds: f64, quiet: bool) -> Self {
        let bar = (!quiet && std::io::stderr().is_terminal()).then(|| {
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
        Reporter { bar, budget, base_seconds, base_iterations, last_line: -1.0, quiet, error: None }
    }

    pub fn update(&mut self, p: &Progress, pixels: f64) {
        if self.quiet {
            return;
        }
        let seconds = p.seconds - self.base_seconds;
        let fraction = match self.budget {
            Budget::Iterations(n) => p.iterations as f64 / n as f64,
            Budget::Seconds(t) => seconds / t,
        }
        .clamp(0.0, 1.0);
        let rate = (p.iterations - self.base_iterations) as f64 * pixels / seconds.max(1e-9);
        let mut msg = format!("{} it, {:.2} Msamples/s", p.iterations, rate * 1e-6);
        if let Some(e) = &self.error {
            msg += &format!(", {e}");
        }
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

    /// The error against a reference that the following progress lines show.
    pub fn set_error(&mut self, error: &str) {
        self.error = Some(error.to_string());
    }

    /// A line that does not disturb the bar.
    pub fn note(&self, line: &str) {
        if self.quiet && !line.starts_with("warning") {
            return;
        }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The plain lines `show_activity` writes for an activity that ends after `seconds`.
    fn plain_lines(seconds: f64) -> String {
        let bar = ProgressBar::with_draw_target(Some(10), ProgressDrawTarget::hidden());
        bar.inc(5);
        let (ended, wait) = mpsc::channel::<()>();
        let end = std::thread::spawn(move || {
            std::thread::sleep(Duration::from_secs_f64(seconds));
            drop(ended);
        });
        let mut out = Vec::new();
        show_activity(&bar, "work", &wait, false, &mut out);
        end.join().unwrap();
        String::from_utf8(out).unwrap()
    }

    #[test]
    fn activities_show_only_after_a_second() {
        assert_eq!(plain_lines(0.05), "");
        let long = plain_lines(1.3);
        assert!(long.starts_with("work: took 1.") && long.lines().count() == 1, "{long:?}");
    }
}
