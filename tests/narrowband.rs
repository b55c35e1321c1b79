//! The narrowband tests (Figures 8, 9 and 13, the calibration of prototype 1 and the fit of
//! b_im) in ONE test binary, so that the calibration and each figure's run are computed once
//! (one `OnceLock` each) and shared:
//!
//! * [`paper`] (`tests/narrowband/paper.rs`): correctness, i.e. the claims against the paper
//!   through the paper layer's `claims` functions and the claims file's own verdicts, the jump
//!   criterion, the b_im fit and the calibration against their definitions;
//! * [`regression`] (`tests/narrowband/regression.rs`): snapshots of our own characterisation
//!   numbers (onsets, jumps, fitted gap and dampings, powers), so that a change shows.

#[path = "narrowband/paper.rs"]
mod paper;
#[path = "narrowband/regression.rs"]
mod regression;

use std::sync::OnceLock;

use endstop::device::Device;
use endstop::paper::calibration::{calibrate_prototype1, Calibration};
use endstop::paper::claims::Claims;
use endstop::paper::{fig08, fig09, fig13};

/// The claims file compiled into the crate.
pub fn claims_file() -> &'static Claims {
    static C: OnceLock<Claims> = OnceLock::new();
    C.get_or_init(|| Claims::bundled().expect("data/claims.toml parses"))
}

/// Prototype 1 as published.
pub fn p1() -> Device {
    Device::from_toml_str(
        include_str!("../data/prototype1.toml"),
        "data/prototype1.toml",
    )
    .expect("prototype 1 parses")
}

/// Prototype 2 as published.
pub fn p2() -> Device {
    Device::from_toml_str(
        include_str!("../data/prototype2.toml"),
        "data/prototype2.toml",
    )
    .expect("prototype 2 parses")
}

/// The calibration of prototype 1, computed once for the whole binary.
pub fn calibration() -> &'static Calibration {
    static C: OnceLock<Calibration> = OnceLock::new();
    C.get_or_init(|| calibrate_prototype1(&p1()).expect("the calibration converges"))
}

/// Figure 8, both sets, as the `fig08` binary runs it.
pub fn fig08_run() -> &'static fig08::Run {
    static R: OnceLock<fig08::Run> = OnceLock::new();
    R.get_or_init(|| fig08::run(&p1(), &calibration().device, &|| {}).expect("Figure 8 runs"))
}

/// Figure 9, both sets, as the `fig09` binary runs it.
pub fn fig09_run() -> &'static fig09::Run {
    static R: OnceLock<fig09::Run> = OnceLock::new();
    R.get_or_init(|| fig09::run(&p1(), &calibration().device, &|| {}).expect("Figure 9 runs"))
}

/// Figure 13 as the `fig13` binary runs it.
pub fn fig13_run() -> &'static fig13::Run {
    static R: OnceLock<fig13::Run> = OnceLock::new();
    R.get_or_init(|| fig13::run(&p2(), &|| {}).expect("Figure 13 runs"))
}
