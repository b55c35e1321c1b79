//! With the published parameters the 5.5 g up-sweep reaches the stops later than the measured
//! kink at 1135 Hz (Figure 8). [`calibrate_prototype1`] fits ONE parameter, the effective
//! end-stop gap xmax, to ONE measured feature, that kink: a root find (Illinois-modified
//! regula falsi, bisection while a bracket end is outside the swept range) on xmax, each
//! evaluation being the refined impact onset of a 5.5 g, 30 V up-sweep (Hertz contact,
//! b_im = 1.5 N s/m; the onset does not depend on the contact law, since before the first
//! contact the stop exerts no force). Everything else about prototype 1 is then a prediction.
//!
//! # The paper's fit of b_im
//! [`fit_bim_for_jump`] is the procedure of section 3.2: the end-stop damping for which the
//! impacting branch of the 5.5 g up-sweep ends at the measured 1425 Hz, for a given stiffness
//! law and parameter set.
//!
//! # Figure studies

use thiserror::Error;

use crate::device::{Device, StiffnessModel};
use crate::drive::Sine;
use crate::ode::{SolverError, Stats};
use crate::paper::fig08::{self, P1_HIGH_ACCEL_RMS_G};
use crate::paper::measured::P1_MEASURED_ONSET_HZ;
use crate::paper::setups::P1_BIAS_V;
use crate::physics::harvester::Harvester;
use crate::study::steady::SteadyConfig;
use crate::study::stepped::{continue_sweep, in_contact, Sweep, Transition};
use crate::study::sweep::frequency_continuation;
use crate::study::sweep::{BranchEnd, SweepSettings};

/// The calibration stops when the achieved onset is this close to the target (Hz).
pub const CALIBRATION_TOL_HZ: f64 = 0.25;

/// Bracket width to which the calibration refines each onset (Hz).
pub const CALIBRATION_REFINE_TOL_HZ: f64 = 0.05;

/// Failure of a narrowband study.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum NarrowbandError {
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
    cfg: &SteadyConfig,
    refine_tol_hz: f64,
) -> Result<OnsetSearch, SolverError> {
    let base = Harvester::new(device, Sine::from_rms_g(accel_rms_g, freqs_hz[0]));
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

/// The claim the calibrated set is fitted to, (claim id, quantity): under the calibrated set
/// its agreement holds by construction and is no evidence.
pub const CALIBRATION_TARGET: (&str, &str) = ("F8-b", "impact_onset_5p5g_hz");

/// Result of the one-parameter calibration of prototype 1 ([`calibrate_prototype1`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Calibration {
    /// The calibrated device: the published one with the fitted end-stop gap and
    /// `params = "calibrated"`; everything else unchanged.
    pub device: Device,
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
    /// Onset evaluations made by the root find (each a sweep plus a refinement).
    pub iterations: usize,
}

/// Calibrates prototype 1: the effective end-stop gap xmax for which the 5.5 g rms, 30 V
/// up-sweep (900 Hz upwards in 10 Hz steps, Hertz contact, b_im = 1.5 N s/m) first touches a
/// stop at the measured kink of Figure 8, 1135 Hz (section 3.2). A root find on xmax (see the
/// module docs), stopped when the refined onset is within [`CALIBRATION_TOL_HZ`] of the
/// target. The returned device is `published` with only `geometry.endstop_gap_m` changed and
/// `params = "calibrated"`.
pub fn calibrate_prototype1(published: &Device) -> Result<Calibration, NarrowbandError> {
    let setup = published
        .with_bias(P1_BIAS_V)
        .with_endstop(StiffnessModel::Hertz, 1.5);
    let settings = fig08::sweep_settings(published);
    let (freqs, cfg) = (settings.freqs_hz, settings.cfg);
    let target = P1_MEASURED_ONSET_HZ;
    let mut evaluations = 0usize;
    let mut eval = |gap: f64| -> Result<(f64, Option<Transition>), SolverError> {
        evaluations += 1;
        let mut d = setup.clone();
        d.geometry.endstop_gap_m = gap;
        Ok(
            match onset_search(
                &d,
                &freqs,
                P1_HIGH_ACCEL_RMS_G,
                &cfg,
                CALIBRATION_REFINE_TOL_HZ,
            )? {
                OnsetSearch::BelowRange => (f64::NEG_INFINITY, None),
                OnsetSearch::AboveRange => (f64::INFINITY, None),
                OnsetSearch::At(t) => (t.value() - target, Some(t)),
            },
        )
    };
    let published_gap = published.geometry.endstop_gap_m;
    let mut a = 0.5 * published_gap;
    let mut b = published_gap;
    let (mut fa, _) = eval(a)?;
    let (mut fb, mut tb) = eval(b)?;
    // If the published gap is already hit too early, widen up to the finger overlap x0
    // (the fingers must not disengage: params.rs validates xmax <= x0).
    if fb < 0.0 {
        a = b;
        fa = fb;
        b = published.geometry.finger_overlap_m;
        (fb, tb) = eval(b)?;
    }
    if !(fa < 0.0 && fb > 0.0) {
        return Err(NarrowbandError::NotBracketed {
            what: "calibration of the end-stop gap to the impact onset".into(),
            target,
            lo: a,
            f_lo: fa,
            hi: b,
            f_hi: fb,
        });
    }
    let done = |g: f64, f: f64, t: Transition, n: usize| Calibration {
        device: {
            let mut d = published.clone();
            d.geometry.endstop_gap_m = g;
            d.params = "calibrated".into();
            d.description = format!(
                "{}; calibrated: end-stop gap fitted so the 5.5 g, 30 V up-sweep's impact onset \
                 is at the measured {target} Hz (src/narrowband.rs, calibrate_prototype1)",
                published.description
            );
            d
        },
        fitted_gap_m: g,
        published_gap_m: published_gap,
        target_onset_hz: target,
        achieved_onset_hz: f + target,
        onset_bracket: t,
        iterations: n,
    };
    if fb.abs() <= CALIBRATION_TOL_HZ {
        let t = tb.expect("a finite onset has a bracket");
        return Ok(done(b, fb, t, evaluations));
    }
    // Illinois-modified regula falsi; plain bisection while an end is outside the range.
    let mut side = 0i8;
    for _ in 0..60 {
        let c = if fa.is_finite() && fb.is_finite() {
            (a * fb - b * fa) / (fb - fa)
        } else {
            0.5 * (a + b)
        };
        let (fc, tc) = eval(c)?;
        if fc.abs() <= CALIBRATION_TOL_HZ {
            let t = tc.expect("a finite onset has a bracket");
            return Ok(done(c, fc, t, evaluations));
        }
        if fc > 0.0 {
            b = c;
            fb = fc;
            if side == 1 {
                fa *= 0.5;
            }
            side = 1;
        } else {
            a = c;
            fa = fc;
            if side == -1 {
                fb *= 0.5;
            }
            side = -1;
        }
        if b - a < 1e-6 * published_gap {
            break;
        }
    }
    Err(NarrowbandError::NotConverged {
        what: "calibration of the end-stop gap to the impact onset".into(),
        iterations: evaluations,
        lo: a,
        hi: b,
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

/// Tolerance of [`fit_bim_for_jump`] on the branch end (Hz).
pub const BIM_FIT_TOL_HZ: f64 = 0.5;

/// The paper's procedure for the end-stop damping (section 3.2): the b_im for which the
/// impacting branch of the up-sweep of `device` (its stiffness model, bias and gap) at
/// `accel_rms_g` ends at `target_hz` (Figure 8: 1425 Hz). The branch end is the jump if there
/// is one and the loss of contact otherwise ([`SweepReport::branch_end`]); the result records
/// which. The end is assumed to fall as b_im grows (more end-stop damping, lower jump: claim
/// F8-e): b_im = 0 is tried first, and if its branch already ends below the target no b_im >= 0
/// can reach it and `bim_n_s_per_m` is `None`. Otherwise b_im is bracketed by doubling from
/// 1 N s/m and found by Illinois-modified regula falsi until the end is within `tol_hz` of
/// the target or the b_im bracket is narrower than 0.1 %; the best evaluation is returned.
pub fn fit_bim_for_jump(
    device: &Device,
    target_hz: f64,
    accel_rms_g: f64,
    settings: &SweepSettings,
    tol_hz: f64,
) -> Result<BimFit, NarrowbandError> {
    let stiffness = device.endstop.stiffness;
    let mut samples = Vec::new();
    let mut eval = |bim: f64| -> Result<(f64, Option<BranchEnd>), SolverError> {
        let d = device.with_endstop(stiffness, bim);
        let r = settings.run(&d, accel_rms_g, |_| {})?;
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
    let mut found: Option<(f64, Option<BranchEnd>)> = None;
    if f0 >= 0.0 {
        if f0.abs() <= tol_hz {
            found = Some((0.0, end0));
        } else {
            let (mut a, mut fa) = (0.0, f0);
            let mut b = 1.0;
            let (mut fb, mut eb) = eval(b)?;
            while fb > 0.0 {
                if b > 1e4 {
                    return Err(NarrowbandError::NotBracketed {
                        what: format!("b_im fit ({stiffness:?}) to the jump"),
                        target: target_hz,
                        lo: 0.0,
                        f_lo: f0,
                        hi: b,
                        f_hi: fb,
                    });
                }
                a = b;
                fa = fb;
                b *= 2.0;
                (fb, eb) = eval(b)?;
            }
            let mut best = (b, fb, eb);
            let mut side = 0i8;
            while best.1.abs() > tol_hz && (b - a) > 1e-3 * b {
                let c = if fa.is_finite() && fb.is_finite() {
                    (a * fb - b * fa) / (fb - fa)
                } else {
                    0.5 * (a + b)
                };
                let (fc, ec) = eval(c)?;
                if fc.abs() < best.1.abs() {
                    best = (c, fc, ec);
                }
                if fc > 0.0 {
                    a = c;
                    fa = fc;
                    if side == -1 {
                        fb *= 0.5;
                    }
                    side = -1;
                } else {
                    b = c;
                    fb = fc;
                    if side == 1 {
                        fa *= 0.5;
                    }
                    side = 1;
                }
            }
            found = Some((best.0, best.2));
        }
    }
    Ok(BimFit {
        target_hz,
        stiffness,
        bim_n_s_per_m: found.map(|f| f.0),
        achieved: found.and_then(|f| f.1),
        at_zero: end0,
        samples,
    })
}
