//! Progress indicators on standard error (indicatif). They are drawn only when standard error is a
//! terminal, so pipes, files and CI logs stay clean, and never when `--quiet` is given.

use std::time::Duration;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// Builds progress indicators, or hidden ones under `--quiet`.
#[derive(Clone, Copy)]
pub struct Progress {
    quiet: bool,
}

impl Progress {
    /// Progress shown on a terminal unless `quiet`.
    pub fn new(quiet: bool) -> Self {
        Self { quiet }
    }

    fn target(&self) -> ProgressDrawTarget {
        if self.quiet {
            ProgressDrawTarget::hidden()
        } else {
            // indicatif draws on stderr only when it is a terminal.
            ProgressDrawTarget::stderr()
        }
    }

    /// A spinner with a message and the elapsed time, for work of unknown length.
    pub fn spinner(&self, message: impl Into<String>) -> ProgressBar {
        let pb = ProgressBar::with_draw_target(None, self.target());
        let style = ProgressStyle::with_template("{spinner} {msg} [{elapsed}]")
            .unwrap_or_else(|_| ProgressStyle::default_spinner());
        pb.set_style(style);
        pb.set_message(message.into());
        pb.enable_steady_tick(Duration::from_millis(120));
        pb
    }

    /// A bar over `len` items.
    pub fn bar(&self, len: u64, message: impl Into<String>) -> ProgressBar {
        let pb = ProgressBar::with_draw_target(Some(len), self.target());
        let style =
            ProgressStyle::with_template("{msg} [{elapsed}] {wide_bar} {pos}/{len} (eta {eta})")
                .unwrap_or_else(|_| ProgressStyle::default_bar());
        pb.set_style(style);
        pb.set_message(message.into());
        pb
    }
}
