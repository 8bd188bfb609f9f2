//! Progress indicators on standard error (indicatif). They are drawn only when standard error is a
//! terminal, so pipes, files and CI logs stay clean, and never when `--quiet` is given. The
//! exception is `optimize --progress` ([`IterationProgress`]), which was asked for: plain lines
//! when standard error is not a terminal, also under `--quiet`.

use std::time::Duration;

use chainbeam::optimize::argmin::core::{Error as ArgminError, KvValue, State, KV};
use chainbeam::optimize::{Observe, ObservedState};
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

/// `optimize --progress`: the iteration, the objective and ‖∇c‖ of a single optimisation on
/// standard error, as an argmin observer ([`chainbeam::optimize::Minimizer::add_observer`]).
///
/// On a terminal it is an indicatif bar over the iteration limit whose message holds the
/// objective and ‖∇c‖ (left on screen at the end, so the last values stay readable). Elsewhere
/// (a pipe, a file, a CI log) it prints one plain line per iteration, `iter K  cost C  |g| G`
/// (with `  (polish)` for a step of the gradient polish), after a first line `METHOD: start,
/// cost C`: a log that tools and tests can read, without terminal control codes.
pub struct IterationProgress {
    bar: Option<ProgressBar>,
}

impl IterationProgress {
    /// A display for a run of at most `max_iters` iterations: the bar if `terminal`, plain
    /// lines otherwise.
    pub fn new(terminal: bool, max_iters: usize) -> Self {
        let bar = terminal.then(|| {
            let pb =
                ProgressBar::with_draw_target(Some(max_iters as u64), ProgressDrawTarget::stderr());
            let style = ProgressStyle::with_template(
                "{spinner} iter {pos}/{len} {msg} [{elapsed}] {wide_bar}",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar());
            pb.set_style(style);
            pb.enable_steady_tick(Duration::from_millis(120));
            pb
        });
        Self { bar }
    }

    /// A display for stderr: the bar when stderr is a terminal.
    pub fn on_stderr(max_iters: usize) -> Self {
        use std::io::IsTerminal;
        Self::new(std::io::stderr().is_terminal(), max_iters)
    }
}

/// `cost C  |g| G` of an observed state and its key-value log.
fn cost_and_gradient(state: &ObservedState, kv: &KV) -> String {
    let g = kv
        .get("grad_norm")
        .and_then(KvValue::get_float)
        .map_or_else(|| "-".to_string(), |g| format!("{g:.3e}"));
    format!("cost {:.12e}  |g| {g}", state.get_cost())
}

impl Observe<ObservedState> for IterationProgress {
    fn observe_init(
        &mut self,
        name: &str,
        state: &ObservedState,
        kv: &KV,
    ) -> Result<(), ArgminError> {
        match &self.bar {
            Some(pb) => pb.set_message(format!("{name}: {}", cost_and_gradient(state, kv))),
            None => eprintln!("{name}: start, cost {:.12e}", state.get_cost()),
        }
        Ok(())
    }

    fn observe_iter(&mut self, state: &ObservedState, kv: &KV) -> Result<(), ArgminError> {
        let polish = kv
            .get("polish")
            .and_then(KvValue::get_bool)
            .unwrap_or(false);
        let text = cost_and_gradient(state, kv);
        let suffix = if polish { "  (polish)" } else { "" };
        match &self.bar {
            Some(pb) => {
                pb.set_position(state.get_iter() + 1);
                pb.set_message(format!("{text}{suffix}"));
            }
            None => eprintln!("iter {:>5}  {text}{suffix}", state.get_iter() + 1),
        }
        Ok(())
    }

    fn observe_final(&mut self, _state: &ObservedState) -> Result<(), ArgminError> {
        if let Some(pb) = &self.bar {
            pb.finish();
        }
        Ok(())
    }
}

impl Drop for IterationProgress {
    /// A run that ended in an error never reaches `observe_final`: leave the bar as it was.
    fn drop(&mut self) {
        if let Some(pb) = &self.bar {
            if !pb.is_finished() {
                pb.abandon();
            }
        }
    }
}
