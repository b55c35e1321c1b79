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
//! `crosscheck` experiment).

use thiserror::Error;

use crate::device::{Device, StiffnessModel};
use crate::drive::Sine;
pub use crate::num::compare::Verdict;
use crate::num::compare::{Comparison, Measure};
use crate::ode::{Dopri5, SolverError, Stats};
use crate::paper::setups::{with_endstop, FIG13_BIAS_V};
use crate::physics::contact::Mode;
use crate::physics::harvester::{Harvester, State};
use crate::progress::Silent;
use crate::spice::{
    netlist, parse_wrdata, InitialCondition, Method, SolverSettings, SpiceDrive, SpiceError,
    SpiceOptions, Transient, Waveforms, DOCUMENTED_STEPS_PER_PERIOD, HERTZ_NEWTON_STEPS,
};
use crate::study::steady::{steady_config, steady_state, Measurement, SteadyConfig};
use crate::study::stepped::{linspace_step, SteppedDrive};

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

/// A case ready to run: the model, the steady-state criterion and the state both simulators
/// start from.
#[derive(Debug, Clone)]
pub struct Prepared {
    /// The case.
    pub case: Case,
    /// The device driven at the case's drive.
    pub model: Harvester<Sine>,
    /// Our steady-state criterion: blocks of the ring-up time, [`REL_CHANGE_TOL`], and enough
    /// settling blocks to span [`MIN_SPAN_PERIODS`].
    pub cfg: SteadyConfig,
    /// The initial state.
    pub y0: State,
    /// The initial contact mode.
    pub mode0: Mode,
    /// Where the state comes from, for the book.
    pub start_label: String,
}

/// Prepares a case: the initial state is rest, or the end of our up-sweep at the case
/// frequency (the upper branch).
pub fn prepare(case: &Case) -> Result<Prepared, SolverError> {
    let (f, a) = (case.freq_hz, case.accel_rms_g);
    let model = Harvester::new(&case.device, Sine::from_rms_g(a, f));
    let mut cfg = steady_config(&case.device, f);
    cfg.rel_change_tol = REL_CHANGE_TOL;
    let (y0, mode0, start_label) = match case.start {
        Start::Rest => (model.rest_state(), Mode::Free, "rest".to_string()),
        Start::UpSweep { from_hz, step_hz } => {
            let c = SteppedDrive {
                base: &model,
                drive: move |ff: f64| (ff, a),
                cfg: cfg.clone(),
            };
            let sweep = c.run(&linspace_step(from_hz, f, step_hz), &Silent)?;
            let last = sweep
                .steps
                .last()
                .expect("a sweep up to the case frequency has a step");
            (
                last.state,
                last.mode,
                format!("up-sweep {from_hz}-{f} Hz in {step_hz} Hz steps (ours)"),
            )
        }
    };
    cfg.settle_blocks = MIN_SPAN_PERIODS.div_ceil(cfg.block_periods).max(1);
    Ok(Prepared {
        case: case.clone(),
        model,
        cfg,
        y0,
        mode0,
        start_label,
    })
}

/// Our side of a case: the steady state over the span, measured over its last block.
#[derive(Debug, Clone)]
pub struct Ours {
    /// The measurement over the comparison window.
    pub measurement: Measurement,
    /// The integrator's work.
    pub stats: Stats,
    /// The span, from 0 (s).
    pub t_end_s: f64,
    /// The comparison window (s): the last block.
    pub window_s: (f64, f64),
}

impl Ours {
    /// The length of the comparison window (s).
    pub fn window_length_s(&self) -> f64 {
        self.window_s.1 - self.window_s.0
    }
}

impl Prepared {
    /// Our steady state from the initial state over at least [`MIN_SPAN_PERIODS`] periods,
    /// measured over the last block; an error unless it converged.
    pub fn ours(&self) -> Result<Ours, CrosscheckError> {
        let a = self.case.accel_rms_g;
        let (m, _, _, stats) = steady_state(&self.model, self.y0, self.mode0, a, &self.cfg)?;
        if !m.converged {
            return Err(CrosscheckError::NotSteady {
                case: self.case.key,
            });
        }
        let block_s = self.cfg.block_periods as f64 * self.case.period_s();
        let t_end_s = (self.cfg.settle_blocks + m.blocks) as f64 * block_s;
        Ok(Ours {
            measurement: m,
            stats,
            t_end_s,
            window_s: (t_end_s - block_s, t_end_s),
        })
    }

    /// Our RMS voltage of load 1 from rest at the same drive (the lower branch where the drive
    /// is bistable), with the sweeps' steady-state criterion (V); for a case without impacts,
    /// `ours`'s own.
    pub fn v1_from_rest(&self, ours: &Ours) -> Result<f64, SolverError> {
        if !self.case.impacting {
            return Ok(ours.measurement.v1_rms_v);
        }
        let cfg = steady_config(&self.case.device, self.case.freq_hz);
        let rest = self.model.rest_state();
        let (m, ..) = steady_state(&self.model, rest, Mode::Free, self.case.accel_rms_g, &cfg)?;
        Ok(m.v1_rms_v)
    }

    /// The options of the netlist of `setting` over `ours`'s span, writing its waveforms to
    /// `wrdata_file`.
    pub fn spice_options(
        &self,
        ours: &Ours,
        setting: Setting,
        wrdata_file: String,
    ) -> SpiceOptions {
        let period = self.case.period_s();
        SpiceOptions {
            title: format!(
                "endstop crosscheck: {} [{}]",
                self.case.label,
                setting.label()
            ),
            initial: InitialCondition::from_state(&self.case.device, &self.y0),
            solver: setting.solver(period),
            transient: Transient {
                stop_s: ours.t_end_s,
                step_s: period / OUTPUT_STEPS_PER_PERIOD,
                save_from_s: (ours.window_s.0 - period).max(0.0),
                wrdata_file: Some(wrdata_file),
            },
            hertz_newton_steps: HERTZ_NEWTON_STEPS,
        }
    }

    /// The netlist of `setting` over `ours`'s span, writing its waveforms to `wrdata_file`.
    pub fn netlist(&self, ours: &Ours, setting: Setting, wrdata_file: String) -> String {
        let drive = SpiceDrive {
            accel_rms_g: self.case.accel_rms_g,
            freq_hz: self.case.freq_hz,
        };
        netlist(
            &self.case.device,
            &drive,
            &self.spice_options(ours, setting, wrdata_file),
        )
    }

    /// Our V1 over the last period of `ours`'s span, sampled at `n` + 1 points, as (phase in
    /// periods, V1) (the book's plot).
    pub fn last_period(&self, ours: &Ours, n: usize) -> Result<Vec<(f64, f64)>, SolverError> {
        let model = &self.model;
        let period = self.case.period_s();
        let t_end = ours.t_end_s;
        let t_start = t_end - period;
        let times: Vec<f64> = (0..=n)
            .map(|i| t_start + period * i as f64 / n as f64)
            .collect();
        let mut pts = Vec::with_capacity(n + 1);
        let mut k = 0;
        let opts = model.solver_options(self.cfg.rtol);
        let mut ode = Dopri5::new(0.0, self.y0, self.mode0, opts);
        ode.integrate(model, t_end, |st, _| {
            while k < times.len() && times[k] <= st.t1() {
                if times[k] >= st.t0 {
                    let y = st.at(times[k]);
                    pts.push(((times[k] - t_start) / period, model.electrical(&y).v[0]));
                }
                k += 1;
            }
        })?;
        Ok(pts)
    }
}

/// ngspice's run of a case, measured over the comparison window.
#[derive(Debug, Clone, PartialEq)]
pub struct SpiceRun {
    /// RMS voltage of load 1 (V).
    pub v1_rms_v: f64,
    /// RMS voltage of load 2 (V).
    pub v2_rms_v: f64,
    /// Largest |x| (m).
    pub x_peak_m: f64,
    /// Fraction of the window in contact.
    pub contact_fraction: f64,
    /// Time points in the window.
    pub points: usize,
    /// The waveforms as read.
    pub waveforms: Waveforms,
}

impl SpiceRun {
    /// Reads ngspice's `wrdata` text (vectors `v(n1)`, `v(n2)`, `v(xpos)` in um) and measures
    /// it over `window_s`; `gap_m` is the end-stop gap (contact is |x| beyond it).
    pub fn of_wrdata(
        text: &str,
        gap_m: f64,
        window_s: (f64, f64),
    ) -> Result<Self, CrosscheckError> {
        let (t0, t1) = window_s;
        let w = parse_wrdata(text)?;
        let run = Self {
            v1_rms_v: w.rms("v(n1)", t0, t1)?,
            v2_rms_v: w.rms("v(n2)", t0, t1)?,
            x_peak_m: w.max_abs("v(xpos)", t0, t1)? * 1e-6,
            contact_fraction: w.fraction_above("v(xpos)", gap_m * 1e6, t0, t1)?,
            points: w.time.iter().filter(|&&t| t >= t0 && t <= t1).count(),
            waveforms: w,
        };
        if !(run.v1_rms_v.is_finite() && run.v2_rms_v.is_finite()) {
            return Err(CrosscheckError::NonFinite);
        }
        Ok(run)
    }
}

/// The verdict on one ngspice run as the tables write it: within or outside the case's
/// tolerance, or, with [`Verdict::NotYet`], why ngspice gave no result (`failure`).
pub fn verdict_label(verdict: Verdict, failure: Option<&str>) -> String {
    match verdict {
        Verdict::Reproduced => "within tolerance".into(),
        Verdict::Deviates => "outside tolerance".into(),
        Verdict::NotYet => format!("ngspice failed: {}", failure.unwrap_or("no result")),
        Verdict::Open => "open question".into(),
    }
}

/// ngspice against ours on one case and setting.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Difference {
    /// (ngspice - ours) / ours of the RMS voltage of load 1.
    pub rel_v1: f64,
    /// The same for load 2.
    pub rel_v2: f64,
    /// The larger magnitude of the two, what the tolerance applies to.
    pub rel: f64,
    /// Our RMS voltages of loads 1 and 2 (V).
    pub ours_v: [f64; 2],
    /// ngspice's (V).
    pub spice_v: [f64; 2],
}

impl Difference {
    /// ngspice's run against our measurement.
    pub fn of(ours: &Measurement, spice: &SpiceRun) -> Self {
        let rel_v1 = (spice.v1_rms_v - ours.v1_rms_v) / ours.v1_rms_v;
        let rel_v2 = (spice.v2_rms_v - ours.v2_rms_v) / ours.v2_rms_v;
        Self {
            rel_v1,
            rel_v2,
            rel: rel_v1.abs().max(rel_v2.abs()),
            ours_v: [ours.v1_rms_v, ours.v2_rms_v],
            spice_v: [spice.v1_rms_v, spice.v2_rms_v],
        }
    }

    /// Each load's RMS voltage, ngspice's against ours relative to ours, under `tolerance`.
    pub fn comparisons(&self, tolerance: f64) -> [Comparison; 2] {
        [0, 1].map(|k| Comparison {
            ours: self.ours_v[k],
            reference: self.spice_v[k],
            measure: Measure::RelativeToOurs,
            tolerance,
        })
    }

    /// The verdict under `tolerance`: reproduced if both loads' relative differences are at
    /// most `tolerance` (a NaN deviates).
    pub fn verdict(&self, tolerance: f64) -> Verdict {
        Verdict::of(self.comparisons(tolerance).iter().all(Comparison::within))
    }
}

/// The acceptance over the whole cross-check: every case of `case_keys` must have exactly one
/// verdict under the documented settings ([`Setting::documented`]), and each must be
/// [`Verdict::Reproduced`]. `verdicts` holds (case key, setting, verdict) of every run. Returns
/// the failures, one line each: a case without a documented verdict (or with two), and a
/// documented verdict outside the tolerance or failed; a set with no case fails.
pub fn acceptance_failures(
    case_keys: &[&str],
    verdicts: &[(&str, Setting, Verdict)],
) -> Vec<String> {
    if case_keys.is_empty() {
        return vec!["no case was compared".into()];
    }
    let mut failures = Vec::new();
    for key in case_keys {
        let documented: Vec<Verdict> = verdicts
            .iter()
            .filter(|(k, s, _)| k == key && s.documented())
            .map(|(_, _, v)| *v)
            .collect();
        match documented.as_slice() {
            [Verdict::Reproduced] => {}
            [v] => failures.push(format!("{key} [documented]: {}", verdict_label(*v, None))),
            vs => failures.push(format!(
                "{key}: {} verdicts under the documented settings, expected one",
                vs.len()
            )),
        }
    }
    failures
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_acceptance_fails_on_a_missing_case_an_outside_verdict_or_no_case() {
        let within = Verdict::Reproduced;
        let outside = Verdict::Deviates;
        let all = [
            ("a", Setting::Defaults, outside),
            ("a", Setting::Documented, within),
            ("b", Setting::Documented, within),
        ];
        assert!(acceptance_failures(&["a", "b"], &all).is_empty());
        // Case b was not run under the documented settings: a failure, not a pass.
        let f = acceptance_failures(&["a", "b"], &all[..2]);
        assert_eq!(f.len(), 1, "{f:?}");
        assert!(f[0].starts_with("b: 0 verdicts"), "{f:?}");
        // Nothing compared at all.
        assert_eq!(acceptance_failures(&[], &[]).len(), 1);
        assert_eq!(acceptance_failures(&["a"], &[]).len(), 1);
        // A documented verdict outside the tolerance.
        let f = acceptance_failures(&["a"], &[("a", Setting::Documented, outside)]);
        assert_eq!(f, ["a [documented]: outside tolerance"]);
    }

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

    #[test]
    fn a_difference_that_is_not_a_number_is_outside() {
        let d = Difference {
            rel_v1: f64::NAN,
            rel_v2: f64::NAN,
            rel: f64::NAN,
            ours_v: [1.0, 1.0],
            spice_v: [f64::NAN, f64::NAN],
        };
        assert_eq!(d.verdict(1e-3), Verdict::Deviates);
        // One load's NaN is enough.
        let d = Difference {
            spice_v: [1.0, f64::NAN],
            ..d
        };
        assert_eq!(d.verdict(1e-3), Verdict::Deviates);
    }
}
