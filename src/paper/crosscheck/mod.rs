//! The cross-check with ngspice: the same model, exported as a SPICE netlist
//! ([`crate::spice::netlist`], the paper's Figure 6), simulated by ngspice and compared with our
//! integrator for the same drive, from the same initial state, over the same time span,
//! measured over the same window of whole periods.
//!
//! Cases ([`cases`]): prototype 1 without impacts, prototype 1 on its impacting upper branch
//! (Hertz and linear end-stop laws), prototype 1 grazing the stops at Figure 8's 5.5 g, and
//! prototype 2 on its upper branch near the jump at 0.31 g. Each case runs under several
//! ngspice settings ([`SETTINGS`]), from ngspice's defaults to the documented ones; the
//! documented ones must meet the acceptance tolerance ([`Case::tolerance`]: 0.1 % without
//! impacts, 1 % with impacts) on the RMS voltages.
//!
//! This module prepares our side of a case ([`prepare`], [`Prepared::ours`]), writes the
//! netlist of every setting ([`Prepared::netlist`]), and judges ngspice's `wrdata` output
//! ([`SpiceRun::of_wrdata`], [`Difference::of`]); running ngspice is the caller's job (the
//! `crosscheck` experiment). The cases and settings are here; our side of a case is the
//! submodule `ours`, ngspice's output and the judgement of it the submodule `judge`.

use thiserror::Error;

use crate::device::{Device, StiffnessModel};
pub use crate::num::compare::Verdict;
use crate::ode::SolverError;
use crate::paper::setups::{with_endstop, FIG13_BIAS_V};
use crate::spice::{Method, SolverSettings, SpiceError, DOCUMENTED_STEPS_PER_PERIOD};

mod judge;
mod ours;

pub use judge::{acceptance_failures, verdict_label, Difference, SpiceRun};
pub use ours::{prepare, Ours, Prepared};

/// Every comparison spans at least this many drive periods (long enough for ngspice's default
/// settings to fall off an upper branch, see the book chapter).
pub const MIN_SPAN_PERIODS: usize = 200;

/// Output step `tstep` of `.tran`: this many per period (ngspice's default max step is bounded
/// by it).
pub const OUTPUT_STEPS_PER_PERIOD: f64 = 100.0;

/// Steady-state criterion of our integrator: relative change of the RMS voltages between two
/// blocks (tighter than the sweeps' 1e-3, so that the comparison window is in steady state).
pub const REL_CHANGE_TOL: f64 = 1e-5;

/// Acceptance: relative difference of the RMS voltages with the documented settings, without
/// impacts.
pub const TOL_FREE: f64 = 1e-3;

/// Acceptance with impacts.
pub const TOL_IMPACTING: f64 = 1e-2;

/// The case whose netlist the book shows, and whose waveforms are plotted.
pub const BOOK_CASE: &str = "p1_impacting";

/// Failures of the cross-check.
#[derive(Debug, Error)]
pub enum CrosscheckError {
    /// Our integrator failed.
    #[error(transparent)]
    Solver(#[from] SolverError),
    /// Our steady state did not converge.
    #[error("{case}: our steady state did not converge")]
    NotSteady {
        /// Case key.
        case: &'static str,
    },
    /// ngspice's output could not be read or measured.
    #[error(transparent)]
    Output(#[from] SpiceError),
    /// ngspice's voltages are not finite.
    #[error("ngspice returned non-finite voltages")]
    NonFinite,
}

/// Where a case starts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Start {
    /// From rest.
    Rest,
    /// From the final state of an up-sweep (our continuation) from `from_hz` in steps of
    /// `step_hz` up to the case frequency: the upper branch.
    UpSweep {
        /// First frequency of the sweep (Hz).
        from_hz: f64,
        /// Frequency step (Hz).
        step_hz: f64,
    },
}

/// One case of the cross-check.
#[derive(Debug, Clone, PartialEq)]
pub struct Case {
    /// Key in file names and summary numbers.
    pub key: &'static str,
    /// Label for the book.
    pub label: &'static str,
    /// The device with its bias and end-stop model.
    pub device: Device,
    /// RMS acceleration (g).
    pub accel_rms_g: f64,
    /// Drive frequency (Hz).
    pub freq_hz: f64,
    /// Where it starts.
    pub start: Start,
    /// Impacts expected (selects the tolerance).
    pub impacting: bool,
}

impl Case {
    /// The acceptance tolerance on the relative difference of the RMS voltages.
    pub fn tolerance(&self) -> f64 {
        if self.impacting {
            TOL_IMPACTING
        } else {
            TOL_FREE
        }
    }

    /// The drive period (s).
    pub fn period_s(&self) -> f64 {
        1.0 / self.freq_hz
    }
}

/// The cases, from the published prototypes (as loaded; bias and end-stop model are set here).
pub fn cases(p1: &Device, p2: &Device) -> Vec<Case> {
    let p1_30 = p1.with_bias(30.0);
    let p2_10 = p2.with_bias(FIG13_BIAS_V);
    let upper_p1 = Start::UpSweep {
        from_hz: 1100.0,
        step_hz: 10.0,
    };
    vec![
        Case {
            key: "p1_free",
            label: "P1, 30 V, 4.1 g, 1000 Hz, no impacts (Hertz, b_im = 1.5 N s/m)",
            device: with_endstop(&p1_30, StiffnessModel::Hertz, 1.5),
            accel_rms_g: 4.1,
            freq_hz: 1000.0,
            start: Start::Rest,
            impacting: false,
        },
        Case {
            key: "p1_impacting",
            label: "P1, 30 V, 7 g, 1350 Hz, upper branch (Hertz, b_im = 1.5 N s/m)",
            device: with_endstop(&p1_30, StiffnessModel::Hertz, 1.5),
            accel_rms_g: 7.0,
            freq_hz: 1350.0,
            start: upper_p1,
            impacting: true,
        },
        Case {
            key: "p1_impacting_linear",
            label: "P1, 30 V, 7 g, 1350 Hz, upper branch (linear k_im, b_im = 2 N s/m)",
            device: with_endstop(&p1_30, StiffnessModel::Linear, 2.0),
            accel_rms_g: 7.0,
            freq_hz: 1350.0,
            start: upper_p1,
            impacting: true,
        },
        Case {
            key: "p1_grazing",
            label: "P1, 30 V, 5.5 g, 1240 Hz, grazing (Hertz, b_im = 1.5 N s/m)",
            device: with_endstop(&p1_30, StiffnessModel::Hertz, 1.5),
            accel_rms_g: 5.5,
            freq_hz: 1240.0,
            start: upper_p1,
            impacting: true,
        },
        Case {
            key: "p2_upper",
            label: "P2, 10 V, 0.31 g, 720 Hz, upper branch (linear k_im, b_im = 0.4 N s/m)",
            device: with_endstop(&p2_10, StiffnessModel::Linear, 0.4),
            accel_rms_g: 0.31,
            freq_hz: 720.0,
            start: Start::UpSweep {
                from_hz: 640.0,
                step_hz: 5.0,
            },
            impacting: true,
        },
    ]
}

/// The ngspice settings a case runs under.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Setting {
    /// ngspice's defaults (reltol 1e-3, abstol 1e-12, vntol 1e-6, chgtol 1e-14, trapezoidal;
    /// max step bounded by the output step T/100).
    Defaults,
    /// Defaults with only the max step reduced to T/1000.
    DefaultsMaxStep,
    /// The documented tolerances, with ngspice's default max step.
    DocumentedNoMaxStep,
    /// The documented settings ([`SolverSettings::documented`]), held to the acceptance
    /// tolerance.
    Documented,
    /// The documented settings with Gear's method of order 2.
    DocumentedGear2,
}

/// Every setting, in the order of the tables.
pub const SETTINGS: [Setting; 5] = [
    Setting::Defaults,
    Setting::DefaultsMaxStep,
    Setting::DocumentedNoMaxStep,
    Setting::Documented,
    Setting::DocumentedGear2,
];

impl Setting {
    /// Key in file names and summary numbers.
    pub fn key(self) -> &'static str {
        match self {
            Setting::Defaults => "defaults",
            Setting::DefaultsMaxStep => "defaults_maxstep",
            Setting::DocumentedNoMaxStep => "documented_no_maxstep",
            Setting::Documented => "documented",
            Setting::DocumentedGear2 => "documented_gear2",
        }
    }

    /// Label for tables.
    pub fn label(self) -> &'static str {
        match self {
            Setting::Defaults => "ngspice defaults",
            Setting::DefaultsMaxStep => "defaults, max step T/1000",
            Setting::DocumentedNoMaxStep => "documented tolerances, default max step",
            Setting::Documented => "documented (trapezoidal)",
            Setting::DocumentedGear2 => "documented, Gear order 2",
        }
    }

    /// True for the documented settings, the ones held to the acceptance tolerance.
    pub fn documented(self) -> bool {
        self == Setting::Documented
    }

    /// The solver settings for a drive period `period_s`.
    pub fn solver(self, period_s: f64) -> SolverSettings {
        match self {
            Setting::Defaults => SolverSettings::ngspice_defaults(),
            Setting::DefaultsMaxStep => SolverSettings {
                max_step_s: Some(period_s / DOCUMENTED_STEPS_PER_PERIOD),
                ..SolverSettings::ngspice_defaults()
            },
            Setting::DocumentedNoMaxStep => SolverSettings {
                max_step_s: None,
                ..SolverSettings::documented(period_s)
            },
            Setting::Documented => SolverSettings::documented(period_s),
            Setting::DocumentedGear2 => SolverSettings {
                method: Method::Gear { maxord: 2 },
                ..SolverSettings::documented(period_s)
            },
        }
    }

    /// The settings as ngspice's options read, `*` marking ngspice's defaults and `T` the
    /// drive period `period_s`.
    pub fn text(self, period_s: f64) -> String {
        let s = self.solver(period_s);
        let f = |v: Option<f64>, d: &str| v.map(|x| format!("{x:e}")).unwrap_or(format!("{d}*"));
        let method = match s.method {
            Method::Trapezoidal => "trap".to_string(),
            Method::Gear { maxord } => format!("gear{maxord}"),
        };
        let maxstep = match s.max_step_s {
            Some(h) => format!("T/{}", (period_s / h).round()),
            None => format!("T/{OUTPUT_STEPS_PER_PERIOD}*"),
        };
        format!(
            "reltol={} abstol={} vntol={} chgtol={} {method} maxstep={maxstep}",
            f(s.reltol, "1e-3"),
            f(s.abstol, "1e-12"),
            f(s.vntol, "1e-6"),
            f(s.chgtol, "1e-14"),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_documented_setting_is_held_to_the_tolerance() {
        let documented: Vec<Setting> = SETTINGS.into_iter().filter(|s| s.documented()).collect();
        assert_eq!(documented, [Setting::Documented]);
        let period = 1e-3;
        assert_eq!(
            Setting::Documented.solver(period),
            SolverSettings::documented(period)
        );
    }
}
