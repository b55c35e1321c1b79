//! The calibration of prototype 1 and the paper's fit of the end-stop damping, both root finds
//! with the crate's one root finder ([`illinois`]), each evaluation being a whole sweep.
//!
//! # The calibration of prototype 1
//! With the published parameters the 5.5 g up-sweep reaches the stops later than the measured
//! kink at 1135 Hz (Figure 8). [`calibrate_prototype1`] fits ONE parameter, the effective
//! end-stop gap xmax, to ONE measured feature, that kink: a root find on xmax (bisection while
//! a bracket end is outside the swept range), each evaluation being the refined impact onset of
//! a 5.5 g, 30 V up-sweep (Hertz contact, b_im = 1.5 N s/m; the onset does not depend on the
//! contact law, since before the first contact the stop exerts no force). Everything else
//! about prototype 1 is then a prediction.
//!
//! # The paper's fit of b_im
//! [`fit_bim_for_jump`] is the procedure of section 3.2: the end-stop damping for which the
//! impacting branch of the 5.5 g up-sweep ends at the measured 1425 Hz, for a given stiffness
//! law and parameter set.

use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::device::{Device, StiffnessModel};
use crate::num::roots::{illinois, RootError, RootOptions, Sample, Termination};
use crate::ode::{SolverError, Stats};
use crate::paper::claims::{keys, ClaimKey};
use crate::paper::measured::P1_MEASURED_ONSET_HZ;
use crate::paper::setups::{comb, endstop, hertz_stop, prototype1_setup, with_endstop, ParamSet};
use crate::paper::sweeps::{self, P1_HIGH_ACCEL_RMS_G};
use crate::physics::harvester::Harvester;
use crate::progress::Silent;
use crate::study::steady::SettleSettings;
use crate::study::stepped::{continue_sweep, in_contact, Sweep, Transition};
use crate::study::sweep::frequency_continuation;
use crate::study::sweep::{BranchEnd, SweepSettings};

/// The calibration stops when the achieved onset is this close to the target (Hz): a
/// numerical requirement of the fit, well inside the frequency class of the claims.
pub const CALIBRATION_TOL_HZ: f64 = 0.25;

/// Bracket width to which the calibration refines each onset (Hz).
pub const CALIBRATION_REFINE_TOL_HZ: f64 = 0.05;

/// Failure of a sine-sweep study of prototype 1: Figure 8's sweeps, the calibration of its
/// gap or the fit of its end-stop damping.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum CalibrationError {
    /// The integrator failed.
    #[error(transparent)]
    Solver(#[from] SolverError),
    /// A root find could not bracket its target.
    #[error(
        "{what}: target {target} not bracketed: f({lo:e}) = {f_lo}, f({hi:e}) = {f_hi} \
         (parameter range searched: {lo:e} .. {hi:e})"
    )]
    NotBracketed {
        /// What was being fitted.
        what: String,
        /// Target value.
        target: f64,
        /// Lower parameter tried.
        lo: f64,
        /// Function value there.
        f_lo: f64,
        /// Upper parameter tried.
        hi: f64,
        /// Function value there.
        f_hi: f64,
    },
    /// A root find did not meet its tolerance.
    #[error(
        "{what}: no convergence after {iterations} evaluations (last bracket {lo:e} .. {hi:e})"
    )]
    NotConverged {
        /// What was being fitted.
        what: String,
        /// Evaluations made.
        iterations: usize,
        /// Final bracket.
        lo: f64,
        /// Final bracket.
        hi: f64,
    },
}

impl CalibrationError {
    fn from_root(e: RootError<SolverError>, what: &str, target: f64) -> Self {
        match e {
            RootError::Eval(e) => CalibrationError::Solver(e),
            RootError::NotBracketed { a, b } => {
                let ((lo, f_lo), (hi, f_hi)) = if a.0 <= b.0 { (a, b) } else { (b, a) };
                CalibrationError::NotBracketed {
                    what: what.to_string(),
                    target,
                    lo,
                    f_lo,
                    hi,
                    f_hi,
                }
            }
        }
    }
}

/// Where an onset search ended.
#[derive(Debug, Clone, Copy, PartialEq)]
enum OnsetSearch {
    /// In contact from the first frequency.
    BelowRange,
    /// Refined onset.
    At(Transition),
    /// No contact anywhere in the range.
    AboveRange,
}

/// Impact onset of an up-sweep, stopping the sweep at the first step with contact.
fn onset_search(
    device: &Device,
    freqs_hz: &[f64],
    accel_rms_g: f64,
    cfg: &SettleSettings,
    refine_tol_hz: f64,
) -> Result<OnsetSearch, SolverError> {
    let base = Harvester::<4>::new(device)?;
    let cont = frequency_continuation(&base, accel_rms_g, cfg);
    let mut sweep = Sweep {
        values: Vec::new(),
        steps: Vec::new(),
        stats: Stats::default(),
    };
    continue_sweep(
        &base,
        |f| (f, accel_rms_g),
        cfg,
        &mut sweep,
        freqs_hz.iter().copied(),
        in_contact,
    )?;
    let k = sweep.steps.len() - 1;
    if !in_contact(&sweep.steps[k].measurement) {
        return Ok(OnsetSearch::AboveRange);
    }
    if k == 0 {
        return Ok(OnsetSearch::BelowRange);
    }
    Ok(OnsetSearch::At(cont.refine(
        &sweep,
        k,
        |m| !in_contact(m),
        refine_tol_hz,
    )?))
}

/// The claim number the calibrated set is fitted to: under the calibrated set its agreement
/// holds by construction and is no evidence.
pub const CALIBRATION_TARGET: ClaimKey = keys::F8B_ONSET;

/// What the calibration found, without the device (the artefact's record; the device is the
/// published one with [`CalibrationRecord::fitted_gap_m`], see [`calibrated_device`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CalibrationRecord {
    /// Fitted effective end-stop gap xmax (m).
    pub fitted_gap_m: f64,
    /// The published gap it replaces (m).
    pub published_gap_m: f64,
    /// Target: the measured kink of Figure 8 (Hz).
    pub target_onset_hz: f64,
    /// Refined onset of the calibrated device (Hz, midpoint of `onset_bracket`).
    pub achieved_onset_hz: f64,
    /// The refined onset bracket of the calibrated device (Hz).
    pub onset_bracket: Transition,
    /// Onset evaluations made by the root find, the bracket's ends included (each a sweep
    /// plus a refinement).
    pub evaluations: usize,
}

/// Result of the one-parameter calibration of prototype 1 ([`calibrate_prototype1`]): the
/// calibrated device and the record of the fit (what the artefact saves next to the device).
#[derive(Debug, Clone, PartialEq)]
pub struct Calibration {
    /// The calibrated device: the published one with the fitted end-stop gap and the
    /// calibrated set's label in `params`; everything else unchanged ([`calibrated_device`]).
    pub device: Device,
    /// What the fit found.
    pub record: CalibrationRecord,
}

/// The calibrated device for a fitted gap: `published` with only its stops' gap
/// (`stops.both.gap_m`) changed, the calibrated set's label in `params` and a description
/// that says so.
pub fn calibrated_device(published: &Device, gap_m: f64) -> Device {
    let mut d = published.with_stop_gap(gap_m);
    d.params = ParamSet::Calibrated.label().into();
    d.description = format!(
        "{}; calibrated: end-stop gap fitted so the 5.5 g, 30 V up-sweep's impact onset is at \
         the measured {P1_MEASURED_ONSET_HZ} Hz (src/paper/calibration.rs, calibrate_prototype1)",
        published.description
    );
    d
}

/// Calibrates prototype 1: the effective end-stop gap xmax for which the 5.5 g rms, 30 V
/// up-sweep (Figure 8's settings, Hertz contact, b_im = 1.5 N s/m) first touches a stop at
/// the measured kink of Figure 8, 1135 Hz (section 3.2). A root find on xmax between half the
/// published gap and the published gap (or, if the published gap is already hit too early,
/// between it and the finger overlap x0, which xmax must not exceed), stopped when the refined
/// onset is within [`CALIBRATION_TOL_HZ`] of the target. The returned device is
/// [`calibrated_device`].
pub fn calibrate_prototype1(published: &Device) -> Result<Calibration, CalibrationError> {
    const WHAT: &str = "calibration of the end-stop gap to the impact onset";
    let setup = prototype1_setup(published);
    let settings = sweeps::sweep_settings(published);
    let target = P1_MEASURED_ONSET_HZ;
    let mut evaluations = 0usize;
    let mut eval = |gap: f64| -> Result<(f64, Option<Transition>), SolverError> {
        evaluations += 1;
        let d = setup.with_stop_gap(gap);
        let found = onset_search(
            &d,
            &settings.freqs_hz,
            P1_HIGH_ACCEL_RMS_G,
            &settings.cfg,
            CALIBRATION_REFINE_TOL_HZ,
        )?;
        Ok(match found {
            OnsetSearch::BelowRange => (f64::NEG_INFINITY, None),
            OnsetSearch::AboveRange => (f64::INFINITY, None),
            OnsetSearch::At(t) => (t.value() - target, Some(t)),
        })
    };
    let sample = |eval: &mut dyn FnMut(f64) -> Result<(f64, Option<Transition>), SolverError>,
                  x: f64| { eval(x).map(|(f, t)| Sample::new(x, f, t)) };
    let published_gap = endstop(published).gap_m;
    let mut a = sample(&mut eval, 0.5 * published_gap)?;
    let mut b = sample(&mut eval, published_gap)?;
    if b.f < 0.0 {
        a = b;
        b = sample(&mut eval, comb(published).finger_overlap_m)?;
    }
    if !(a.f < 0.0 && b.f > 0.0) {
        return Err(CalibrationError::NotBracketed {
            what: WHAT.into(),
            target,
            lo: a.x,
            f_lo: a.f,
            hi: b.x,
            f_hi: b.f,
        });
    }
    let opts = RootOptions {
        f_tol: Some(CALIBRATION_TOL_HZ),
        x_tol_abs: 1e-6 * published_gap,
        x_tol_rel: 0.0,
        max_iter: 60,
    };
    let root = illinois(&mut eval, a, b, &opts)
        .map_err(|e| CalibrationError::from_root(e, WHAT, target))?;
    if root.stop != Termination::Value {
        return Err(CalibrationError::NotConverged {
            what: WHAT.into(),
            iterations: evaluations,
            lo: root.non_positive.x.min(root.positive.x),
            hi: root.non_positive.x.max(root.positive.x),
        });
    }
    let best = root.best;
    let t = best
        .payload
        .expect("an onset within the tolerance has a bracket");
    Ok(Calibration {
        device: calibrated_device(published, best.x),
        record: CalibrationRecord {
            fitted_gap_m: best.x,
            published_gap_m: published_gap,
            target_onset_hz: target,
            achieved_onset_hz: t.value(),
            onset_bracket: t,
            evaluations,
        },
    })
}

/// One evaluation of a b_im fit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BimSample {
    /// End-stop damping tried (N s/m).
    pub bim_n_s_per_m: f64,
    /// How and where the impacting branch ended (`None`: no impacts, or contact up to the end
    /// of the range).
    pub end: Option<BranchEnd>,
}

/// Result of [`fit_bim_for_jump`].
#[derive(Debug, Clone, PartialEq)]
pub struct BimFit {
    /// Target jump frequency (Hz).
    pub target_hz: f64,
    /// Spring law of the stop used.
    pub stiffness: StiffnessModel,
    /// Fitted b_im (N s/m); `None` if even b_im = 0 ends the impacting branch below the target.
    pub bim_n_s_per_m: Option<f64>,
    /// The branch end at the fitted b_im.
    pub achieved: Option<BranchEnd>,
    /// The branch end at b_im = 0 (the highest reachable).
    pub at_zero: Option<BranchEnd>,
    /// Every evaluation, in order.
    pub samples: Vec<BimSample>,
}

/// Tolerance of [`fit_bim_for_jump`] on the branch end (Hz): a numerical requirement of the
/// fit, well inside the frequency class of the claims.
pub const BIM_FIT_TOL_HZ: f64 = 0.5;

/// The paper's procedure for the end-stop damping (section 3.2): the b_im for which the
/// impacting branch of the up-sweep of `device` (its stiffness model, bias and gap) at
/// `accel_rms_g` ends at `target_hz` (Figure 8: 1425 Hz). The branch end is the jump if there
/// is one and the loss of contact otherwise ([`crate::study::sweep::SweepReport::branch_end`]);
/// the result records which. The end is assumed to fall as b_im grows (more end-stop damping,
/// lower jump: claim F8-e): b_im = 0 is tried first, and if its branch already ends below the
/// target no b_im >= 0 can reach it and `bim_n_s_per_m` is `None`. Otherwise b_im is bracketed
/// by doubling from 1 N s/m and found by [`illinois`] until the end is within `tol_hz` of the
/// target or the b_im bracket is narrower than 0.1 %; the best evaluation is returned.
pub fn fit_bim_for_jump(
    device: &Device,
    target_hz: f64,
    accel_rms_g: f64,
    settings: &SweepSettings,
    tol_hz: f64,
) -> Result<BimFit, CalibrationError> {
    let stiffness = if hertz_stop(device).linear_fit {
        StiffnessModel::Linear
    } else {
        StiffnessModel::Hertz
    };
    let what = format!("b_im fit ({stiffness:?}) to the jump");
    let mut samples = Vec::new();
    let mut eval = |bim: f64| -> Result<(f64, Option<BranchEnd>), SolverError> {
        let d = with_endstop(device, stiffness, bim);
        let r = settings.run(&d, accel_rms_g, &Silent)?;
        let end = r.branch_end();
        samples.push(BimSample {
            bim_n_s_per_m: bim,
            end,
        });
        let f = match end {
            Some(e) => e.transition.value() - target_hz,
            None if r.any_contact() => f64::INFINITY,
            None => f64::NEG_INFINITY,
        };
        Ok((f, end))
    };
    let (f0, end0) = eval(0.0)?;
    let found = if f0 < 0.0 {
        None
    } else if f0 <= tol_hz {
        Some((0.0, end0))
    } else {
        let mut a = Sample::new(0.0, f0, end0);
        let mut b = 1.0;
        let (mut fb, mut eb) = eval(b)?;
        while fb > 0.0 {
            if b > 1e4 {
                return Err(CalibrationError::NotBracketed {
                    what,
                    target: target_hz,
                    lo: 0.0,
                    f_lo: f0,
                    hi: b,
                    f_hi: fb,
                });
            }
            a = Sample::new(b, fb, eb);
            b *= 2.0;
            (fb, eb) = eval(b)?;
        }
        let opts = RootOptions {
            f_tol: Some(tol_hz),
            x_tol_abs: 0.0,
            x_tol_rel: 1e-3,
            max_iter: 100,
        };
        let root = illinois(&mut eval, a, Sample::new(b, fb, eb), &opts)
            .map_err(|e| CalibrationError::from_root(e, &what, target_hz))?;
        Some((root.best.x, root.best.payload))
    };
    Ok(BimFit {
        target_hz,
        stiffness,
        bim_n_s_per_m: found.map(|f| f.0),
        achieved: found.and_then(|f| f.1),
        at_zero: end0,
        samples,
    })
}
