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
