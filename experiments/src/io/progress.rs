//! Progress on stderr: a bar ([`progress`]), and the adapter that shows the library's
//! progress reports on it ([`Bar`], [`with_progress`]).

use indicatif::{ProgressBar, ProgressStyle};

/// A progress bar on stderr (hidden when stderr is not a terminal).
pub fn progress(len: u64, what: &str) -> ProgressBar {
    let pb = ProgressBar::new(len);
    pb.set_style(
        ProgressStyle::with_template("{prefix:>10} [{bar:30}] {pos}/{len} {msg} ({elapsed})")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    pb.set_prefix(what.to_string());
    pb
}

/// The library's progress reports ([`endstop::progress::Progress`]) shown on a progress bar: a
/// unit of work advances it by one, a share of the work sets its position, a stage is its
/// message.
pub struct Bar(pub ProgressBar);

impl endstop::progress::Progress for Bar {
    fn tick(&self) {
        self.0.inc(1);
    }

    fn fraction(&self, done: f64) {
        let len = self.0.length().unwrap_or(0) as f64;
        self.0
            .set_position((done.clamp(0.0, 1.0) * len).round() as u64);
    }

    fn stage(&self, what: &str) {
        self.0.set_message(what.to_string());
    }
}

/// Runs `work` under a progress bar of `len` steps labelled `what` (cleared when `work`
/// returns); `work` reports to the bar through the [`endstop::progress::Progress`] it gets.
pub fn with_progress<T>(
    len: usize,
    what: &str,
    work: impl FnOnce(&dyn endstop::progress::Progress) -> T,
) -> T {
    let bar = Bar(progress(len as u64, what));
    let out = work(&bar);
    bar.0.finish_and_clear();
    out
}
