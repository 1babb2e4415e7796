//! `--submission-budget-ms`: the most GPU time of one queue submission (src/gpu/batch.rs),
//! so that a display GPU's watchdog does not reset the device (docs/robustness.md).

/// The submission budget's option, flattened into `render`'s arguments.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct SubmissionArgs {
    /// The most GPU time of one queue submission, in milliseconds: passes are split into
    /// pieces of paths to fit (the image does not change). Default: 500 on GPUs, which may
    /// drive a display and its ~2 s watchdog; none on CPU devices. 0: no budget.
    #[arg(long, value_name = "MS", value_parser = parse_budget)]
    pub submission_budget_ms: Option<f64>,
}

impl SubmissionArgs {
    /// Sets `settings`' budget where the option was given.
    pub fn apply(&self, settings: &mut vkvcm::render::RenderSettings) {
        if self.submission_budget_ms.is_some() {
            settings.submission_budget_ms = self.submission_budget_ms;
        }
    }
}

fn parse_budget(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
        _ => Err(format!("{s:?} is not a number of milliseconds >= 0 (0: no budget)")),
    }
}
