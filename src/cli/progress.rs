//! Status output for long work: a spinner with the current stage on a terminal, nothing with
//! `--quiet` or when stderr is not a terminal.

use std::io::IsTerminal;
use std::time::Duration;

use indicatif::{ProgressBar, ProgressStyle};

/// A stage spinner.
pub struct Stages {
    bar: Option<ProgressBar>,
}

impl Stages {
    /// A spinner, or nothing when `quiet` or stderr is not a terminal.
    pub fn new(quiet: bool) -> Self {
        if quiet || !std::io::stderr().is_terminal() {
            return Stages { bar: None };
        }
        let bar = ProgressBar::new_spinner();
        bar.set_style(
            ProgressStyle::with_template("{spinner} {elapsed_precise} {msg}")
                .expect("valid template"),
        );
        bar.enable_steady_tick(Duration::from_millis(100));
        Stages { bar: Some(bar) }
    }

    /// Shows the stage now running.
    pub fn stage(&self, message: &str) {
        if let Some(b) = &self.bar {
            b.set_message(message.to_string());
        }
    }
}

impl Drop for Stages {
    fn drop(&mut self) {
        if let Some(b) = &self.bar {
            b.finish_and_clear();
        }
    }
}

/// A [`Stages`] spinner that also observes the library's pipeline stages.
pub type Spinner = Stages;

impl grainline::pipeline::Observer for Stages {
    fn stage(&self, name: &str) {
        Stages::stage(self, name);
    }
}

/// Warnings a designer should see even when the run succeeds: a light tool that could not reach
/// the wanted ℓ, a solve that made no progress.
pub fn warn_about(report: &grainline::pipeline::optimize::OptimizeStageReport) {
    for e in &report.edits {
        if let Some(err) = e.angle_error_deg.filter(|&a| a > 5.0) {
            eprintln!(
                "grainline: warning: edit [{}] ({}): the best light reaches the wanted highlight \
                 direction only within {err:.1}°",
                e.index, e.tool
            );
        }
    }
    let s = &report.solver;
    if s.iterations.is_empty()
        && matches!(
            s.stop,
            grainline::solve::StopReason::NoProgress | grainline::solve::StopReason::Gradient
        )
        && s.initial_energy.highlight > 1e-12
    {
        eprintln!(
            "grainline: warning: the solver made no step ({}): where the grain is constant \
             on a flat region ℓ = 0 and the highlight energy has no gradient; start from a \
             varying field (e.g. a stencil) there",
            s.stop
        );
    }
}
