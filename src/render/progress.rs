//! A progress bar on stderr (samples per second, elapsed, ETA), drawn only
//! when stderr is a terminal so logs and pipes stay clean.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;

pub struct Progress {
    bar: ProgressBar,
}

impl Progress {
    /// `total_samples` is `None` when the render stops on noise, not on a
    /// count: the bar then shows samples taken and their rate, no ETA.
    pub fn new(enabled: bool, total_samples: Option<u64>) -> Progress {
        let target = if enabled && std::io::stderr().is_terminal() {
            ProgressDrawTarget::stderr()
        } else {
            ProgressDrawTarget::hidden()
        };
        let bar = ProgressBar::with_draw_target(total_samples, target);
        let template = if total_samples.is_some() {
            "{elapsed_precise} [{bar:40}] {percent:>3}%  {human_per_sec:>12} samples  ETA {eta}"
        } else {
            "{elapsed_precise} {spinner} {human_pos} samples  {human_per_sec:>12} samples"
        };
        bar.set_style(
            ProgressStyle::with_template(template)
                .expect("valid template")
                .progress_chars("=> "),
        );
        Progress { bar }
    }

    pub fn advance(&self, samples: u64) {
        self.bar.inc(samples);
    }

    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}
