//! The sine-sweep tests (Figures 8, 9 and 13, the calibration of prototype 1 and the fit of
//! b_im) in ONE test binary, so that the calibration and each figure's run are computed once
//! (one `OnceLock` each) and shared:
//!
//! * [`paper`] (`tests/sweep_figures/paper.rs`): correctness, i.e. the claims against the paper
//!   through the paper layer's `claims` functions and the claims file's own verdicts, the jump
//!   criterion, the b_im fit and the calibration against their definitions;
//! * [`regression`] (`tests/sweep_figures/regression.rs`): snapshots of our own characterisation
//!   numbers (onsets, jumps, fitted gap and dampings, powers), so that a change shows.

use crate::common;
#[path = "sweep_figures/paper.rs"]
mod paper;
#[path = "sweep_figures/regression.rs"]
mod regression;

use std::sync::OnceLock;

use endstop::paper::figures::fig08::{self, Fig08};
use endstop::paper::figures::fig09::{self, Fig09};
use endstop::paper::figures::fig13::{self, Fig13};
use endstop::paper::Figure;

/// Figure 8, both sets, as the `fig08` binary runs it.
pub fn fig08_run() -> &'static fig08::Run {
    static R: OnceLock<fig08::Run> = OnceLock::new();
    R.get_or_init(|| Fig08::run(&common::prototype1_sets(), &|| {}).expect("Figure 8 runs"))
}

/// Figure 9, both sets, as the `fig09` binary runs it.
pub fn fig09_run() -> &'static fig09::Run {
    static R: OnceLock<fig09::Run> = OnceLock::new();
    R.get_or_init(|| Fig09::run(&common::prototype1_sets(), &|| {}).expect("Figure 9 runs"))
}

/// Figure 13 as the `fig13` binary runs it.
pub fn fig13_run() -> &'static fig13::Run {
    static R: OnceLock<fig13::Run> = OnceLock::new();
    R.get_or_init(|| Fig13::run(&common::prototype2(), &|| {}).expect("Figure 13 runs"))
}
