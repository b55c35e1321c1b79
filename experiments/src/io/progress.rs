//! Progress on stderr: a bar ([`progress`]), and the adapter that shows the library's
//! progress reports on it ([`Bar`], [`with_progress`]). Where stderr is not a terminal (a
//! job log, a pipe) the bar is hidden, and a run longer than [`QUIET_S`] prints a plain line
//! with its share done and an estimate of the time left every [`EVERY_S`] instead.

use std::io::IsTerminal;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};

/// Seconds a run stays quiet before its first plain progress line.
pub const QUIET_S: u64 = 5;
/// Seconds between plain progress lines.
pub const EVERY_S: u64 = 30;

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
pub struct Bar(pub ProgressBar, Lines);

/// The plain progress lines of a bar whose terminal is not one: its label, its start and its
/// last line's time (`None` where stderr is a terminal and the bar shows itself).
struct Lines(Option<(String, Instant, Mutex<Instant>)>);

impl Bar {
    /// A bar of `len` steps labelled `what`.
    pub fn new(len: u64, what: &str) -> Self {
        let plain = (!std::io::stderr().is_terminal()).then(|| {
            let now = Instant::now();
            (what.to_string(), now, Mutex::new(now))
        });
        Self(progress(len, what), Lines(plain))
    }

    /// Prints a plain line when one is due (see the module docs).
    fn report(&self) {
        let Some((what, start, last)) = &self.1 .0 else {
            return;
        };
        let Ok(mut last) = last.lock() else { return };
        let now = Instant::now();
        let elapsed = now.duration_since(*start);
        let first = *last == *start;
        let due = if first {
            elapsed >= Duration::from_secs(QUIET_S)
        } else {
            now.duration_since(*last) >= Duration::from_secs(EVERY_S)
        };
        if !due {
            return;
        }
        *last = now;
        let (pos, len) = (self.0.position(), self.0.length().unwrap_or(0));
        let share = if len > 0 {
            pos as f64 / len as f64
        } else {
            0.0
        };
        let left = if share > 0.0 {
            format!(
                ", about {:.0} s left",
                elapsed.as_secs_f64() * (1.0 - share) / share
            )
        } else {
            String::new()
        };
        eprintln!(
            "[{what}] {pos}/{len} ({:.0} %), {:.0} s elapsed{left}",
            100.0 * share,
            elapsed.as_secs_f64()
        );
    }
}

impl endstop::progress::Progress for Bar {
    fn tick(&self) {
        self.0.inc(1);
        self.report();
    }

    fn fraction(&self, done: f64) {
        let len = self.0.length().unwrap_or(0) as f64;
        self.0
            .set_position((done.clamp(0.0, 1.0) * len).round() as u64);
        self.report();
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
    let bar = Bar::new(len as u64, what);
    let out = work(&bar);
    bar.0.finish_and_clear();
    out
}
