//! How far a long computation has come, told as it goes: every long-running function of the
//! crate takes a `&dyn` [`Progress`] and reports to it, from whichever thread does the work.
//! The crate does no I/O: the experiment binaries show the reports as a progress bar.
//!
//! A closure `Fn() + Sync` is a [`Progress`] told of each unit of work, and [`Silent`] ignores
//! every report:
//!
//! ```
//! use std::sync::atomic::{AtomicUsize, Ordering};
//! use endstop::progress::{Progress, Silent};
//!
//! fn work(progress: &dyn Progress) {
//!     for _ in 0..3 {
//!         progress.tick();
//!     }
//!     progress.fraction(1.0);
//! }
//! let done = AtomicUsize::new(0);
//! work(&|| {
//!     done.fetch_add(1, Ordering::Relaxed);
//! });
//! assert_eq!(done.load(Ordering::Relaxed), 3);
//! work(&Silent);
//! ```

/// Told how far a computation has come. Each report has a default that ignores it, so an
/// observer implements only those it shows.
pub trait Progress: Sync {
    /// One more unit of work is done (a sweep's step, a record, a design point, a cell).
    fn tick(&self) {}

    /// The share of the work done, in [0, 1], for work that is not counted in units (a
    /// continuation across its range, a charging towards its target voltage).
    fn fraction(&self, _done: f64) {}

    /// What the computation begins now (a branch of a diagram).
    fn stage(&self, _what: &str) {}
}

/// A closure is told of each unit of work.
impl<F: Fn() + Sync> Progress for F {
    fn tick(&self) {
        self()
    }
}

/// Ignores every report.
#[derive(Debug, Clone, Copy, Default)]
pub struct Silent;

impl Progress for Silent {}

/// The share of the way from `from` to `to` that `at` has come, clamped to [0, 1] (0 when the
/// two ends coincide).
pub fn share(from: f64, to: f64, at: f64) -> f64 {
    let s = (at - from) / (to - from);
    if s.is_finite() {
        s.clamp(0.0, 1.0)
    } else {
        0.0
    }
}
