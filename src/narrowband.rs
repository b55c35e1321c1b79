//! Narrowband (sinusoidal) studies: the up-sweeps of Figures 8 and 13, the amplitude
//! continuation of Figure 9, the calibration of prototype 1's end-stop gap, and the paper's own
//! fit of the end-stop damping b_im to a jump frequency (section 3.2).
//!
//! Everything here is built on [`crate::sweep`]: a [`Continuation`] runs the stepped sine
//! (each step starts from the previous final state and is measured in steady state), and
//! [`Continuation::refine_steps`] bisects transitions between two steps.
//!
//! # What an up-sweep report contains
//! * **Impact onset**: the first step with a non-zero contact fraction, refined by bisection
//!   with "still before" meaning "no contact in the measured block". This is the kink of
//!   Figure 8 (1135 Hz in the paper at 5.5 g).
//! * **Jump**: the upper (impacting) branch is lost *discontinuously*. A candidate is a step
//!   that follows a step in contact and whose total power (both loads) is more than
//!   [`CANDIDATE_DROP`] below the previous one. It is refined by bisection with "still before"
//!   meaning "total power above the geometric mean of the powers of the two coarse steps". The
//!   candidate is a jump only if, across the final bracket (narrower than the refinement
//!   tolerance, typically 0.1 Hz), the power still falls by more than [`JUMP_MIN_DROP`]: a
//!   saddle-node jump keeps its full drop however narrow the bracket, whereas a steep but
//!   continuous decline does not. Candidates are tried in order and the first confirmed one is
//!   the jump.
//! * **Loss of contact**: the first step after the onset without contact, refined with "still
//!   before" meaning "in contact". When the upper branch ends with a jump the two coincide;
//!   when it is left gradually (as with the published prototype 1 parameters, see the Figure 8
//!   chapter) there is no jump and the loss of contact is where the impacting branch ends.
//!
//! [`SweepReport::branch_end`] returns the jump if there is one and the loss of contact
//! otherwise, labelled by [`BranchEndKind`], so that a caller never presents a gradual exit as
//! a jump.
//!
//! # Calibration of prototype 1
//! With the published parameters the 5.5 g up-sweep reaches the stops later than the measured
//! kink at 1135 Hz (Figure 8). [`calibrate_prototype1`] fits ONE parameter, the effective
//! end-stop gap xmax, to ONE measured feature, that kink: a root find (Illinois-modified
//! regula falsi, bisection while a bracket end is outside the swept range) on xmax, each
//! evaluation being the refined impact onset of a 5.5 g, 30 V up-sweep (Hertz contact,
//! b_im = 1.5 N s/m; the onset does not depend on the contact law, since before the first
//! contact the stop exerts no force). Everything else about prototype 1 is then a prediction.

use thiserror::Error;

use crate::excitation::Sine;
use crate::integrator::{SolverError, Stats};
use crate::model::Harvester;
use crate::params::{Device, StiffnessModel};
use crate::sweep::{
    self, first_contact, Continuation, Measurement, SteadyConfig, Sweep, SweepStep, Transition,
};

/// A coarse step is a jump candidate when the total power falls by more than this fraction
/// relative to the previous step (which must be in contact).
pub const CANDIDATE_DROP: f64 = 0.05;

/// A candidate is confirmed as a jump when the total power still falls by more than this
/// fraction across the refined bracket.
pub const JUMP_MIN_DROP: f64 = 0.25;

/// Minimum block length in periods for the default steady-state settings.
pub const MIN_BLOCK_PERIODS: usize = 5;

/// Prototype 1, Figure 8: bias voltage (V).
pub const P1_BIAS_V: f64 = 30.0;
/// Prototype 1, Figure 8: the low acceleration, no impacts (g rms).
pub const P1_LOW_ACCEL_RMS_G: f64 = 4.1;
/// Prototype 1, Figure 8: the high acceleration, with impacts (g rms).
pub const P1_HIGH_ACCEL_RMS_G: f64 = 5.5;
/// Prototype 1, Figure 8: first frequency of the up-sweep (Hz).
pub const P1_SWEEP_START_HZ: f64 = 900.0;
/// Prototype 1, Figure 8: last frequency of the up-sweep (Hz).
pub const P1_SWEEP_STOP_HZ: f64 = 1600.0;
/// Prototype 1: default frequency step of the up-sweeps (Hz).
pub const P1_SWEEP_STEP_HZ: f64 = 10.0;
/// Prototype 1, Figure 8: the measured kink (impact onset) at 5.5 g, section 3.2 (Hz).
pub const P1_MEASURED_ONSET_HZ: f64 = 1135.0;
/// Prototype 1, Figure 8: the measured jump at 5.5 g, section 3.2 (Hz).
pub const P1_MEASURED_JUMP_HZ: f64 = 1425.0;
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

/// Default steady-state settings for a device driven near `freq_hz`: blocks of about the
/// mechanical ring-up time 2m/b (SPEC 8), at least [`MIN_BLOCK_PERIODS`] periods, see
/// [`SteadyConfig::for_ring_time`].
pub fn steady_config(device: &Device, freq_hz: f64) -> SteadyConfig {
    let ring_s = 2.0 * device.mechanics.mass_kg / device.mechanics.damping_n_s_per_m;
    SteadyConfig::for_ring_time(ring_s, freq_hz, MIN_BLOCK_PERIODS)
}

/// Is this measurement in contact with a stop (non-zero contact fraction)?
fn in_contact(m: &Measurement) -> bool {
    m.contact_fraction > 0.0
}

/// How the impacting (upper) branch of an up-sweep ends.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BranchEndKind {
    /// A confirmed jump down (a discontinuity of the response).
    Jump,
    /// A gradual exit: contact is lost without a discontinuity.
    ContactLoss,
}

impl BranchEndKind {
    /// Label for tables.
    pub fn label(self) -> &'static str {
        match self {
            BranchEndKind::Jump => "jump",
            BranchEndKind::ContactLoss => "loss of contact (no jump)",
        }
    }
}

/// Where and how the impacting branch ends.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BranchEnd {
    /// Jump or gradual loss of contact.
    pub kind: BranchEndKind,
    /// The refined bracket (Hz).
    pub transition: Transition,
}

/// An up-sweep (Figures 8 and 13) with its refined transitions.
#[derive(Debug, Clone)]
pub struct SweepReport {
    /// The coarse sweep.
    pub sweep: Sweep,
    /// Impact onset: bracket between the last frequency without contact and the first with.
    /// `None` if the sweep never touches a stop or is in contact from its first step.
    pub onset: Option<Transition>,
    /// True when the first step is already in contact (no onset inside the range).
    pub contact_at_start: bool,
    /// A confirmed jump down (see the module docs for the criterion).
    pub jump: Option<Transition>,
    /// Total power after / before across the refined jump bracket.
    pub jump_power_ratio: Option<f64>,
    /// First loss of contact after the onset, refined.
    pub contact_lost: Option<Transition>,
    /// Integrator counters of the refinements (the sweep's own are in `sweep.stats`).
    pub refine_stats: Stats,
}

impl SweepReport {
    /// True if any step of the coarse sweep is in contact.
    pub fn any_contact(&self) -> bool {
        first_contact(&self.sweep).is_some()
    }

    /// Where the impacting branch ends: the jump if there is one, else the loss of contact.
    pub fn branch_end(&self) -> Option<BranchEnd> {
        if let Some(t) = self.jump {
            Some(BranchEnd {
                kind: BranchEndKind::Jump,
                transition: t,
            })
        } else {
            self.contact_lost.map(|t| BranchEnd {
                kind: BranchEndKind::ContactLoss,
                transition: t,
            })
        }
    }

    /// The coarse measurements, in order.
    pub fn measurements(&self) -> impl Iterator<Item = &Measurement> {
        self.sweep.steps.iter().map(|s| &s.measurement)
    }

    /// Integrator counters of the sweep and its refinements together.
    pub fn total_stats(&self) -> Stats {
        let mut s = self.sweep.stats;
        add_stats(&mut s, &self.refine_stats);
        s
    }
}

fn add_stats(acc: &mut Stats, s: &Stats) {
    acc.accepted += s.accepted;
    acc.rejected += s.rejected;
    acc.rhs_evals += s.rhs_evals;
    acc.events += s.events;
}

/// The continuation of an up-sweep in frequency at fixed RMS acceleration.
fn frequency_continuation<'a>(
    base: &'a Harvester<Sine>,
    accel_rms_g: f64,
    cfg: &SteadyConfig,
) -> Continuation<'a, impl sweep::Drive> {
    Continuation {
        base,
        drive: move |f: f64| (f, accel_rms_g),
        cfg: cfg.clone(),
    }
}

/// Runs an up-sweep of `device` over `freqs_hz` (increasing) at `accel_rms_g` and refines its
/// impact onset, jump and loss of contact to brackets narrower than `refine_tol_hz` (see the
/// module docs; Figures 8 and 13). `progress(i)` is called after each coarse step.
pub fn up_sweep_report(
    device: &Device,
    freqs_hz: &[f64],
    accel_rms_g: f64,
    cfg: &SteadyConfig,
    refine_tol_hz: f64,
    progress: impl FnMut(usize),
) -> Result<SweepReport, SolverError> {
    let base = Harvester::new(device, Sine::from_rms_g(accel_rms_g, freqs_hz[0]));
    let cont = frequency_continuation(&base, accel_rms_g, cfg);
    let sweep = cont.run(freqs_hz, progress)?;
    analyse_up_sweep(&cont, sweep, refine_tol_hz)
}

fn analyse_up_sweep<D: sweep::Drive>(
    cont: &Continuation<'_, D>,
    sweep: Sweep,
    tol: f64,
) -> Result<SweepReport, SolverError> {
    let mut refine_stats = Stats::default();
    let steps = &sweep.steps;
    let k_on = first_contact(&sweep);
    let contact_at_start = k_on == Some(0);
    let onset = match k_on {
        Some(k) if k > 0 => {
            let r = cont.refine_steps(&sweep, k, |m| !in_contact(m), tol)?;
            add_stats(&mut refine_stats, &r.before.stats);
            Some(r.transition)
        }
        _ => None,
    };
    let mut jump = None;
    let mut jump_power_ratio = None;
    let mut contact_lost = None;
    if let Some(k0) = k_on {
        for k in (k0 + 1)..steps.len() {
            let a = &steps[k - 1].measurement;
            let b = &steps[k].measurement;
            if !(in_contact(a) && b.p_total_w() < (1.0 - CANDIDATE_DROP) * a.p_total_w()) {
                continue;
            }
            let threshold = (a.p_total_w() * b.p_total_w()).sqrt();
            let r = cont.refine_steps(&sweep, k, |m| m.p_total_w() > threshold, tol)?;
            add_stats(&mut refine_stats, &r.before.stats);
            let ratio = r.after.measurement.p_total_w() / r.before.measurement.p_total_w();
            if ratio < 1.0 - JUMP_MIN_DROP {
                jump = Some(r.transition);
                jump_power_ratio = Some(ratio);
                break;
            }
        }
        if let Some(k) = ((k0 + 1)..steps.len()).find(|&k| !in_contact(&steps[k].measurement)) {
            let r = cont.refine_steps(&sweep, k, in_contact, tol)?;
            add_stats(&mut refine_stats, &r.before.stats);
            contact_lost = Some(r.transition);
        }
    }
    Ok(SweepReport {
        sweep,
        onset,
        contact_at_start,
        jump,
        jump_power_ratio,
        contact_lost,
        refine_stats,
    })
}

/// An amplitude continuation at fixed frequency (Figure 9) with its refined impact onset.
#[derive(Debug, Clone)]
pub struct AmplitudeReport {
    /// The coarse continuation (values in g rms).
    pub sweep: Sweep,
    /// Impact onset bracket (g rms); `None` if no contact, or contact from the first step.
    pub onset: Option<Transition>,
    /// True when the first step is already in contact.
    pub contact_at_start: bool,
}

impl AmplitudeReport {
    /// The measurement at the largest amplitude (the saturated power of Figure 9).
    pub fn last(&self) -> &Measurement {
        &self
            .sweep
            .steps
            .last()
            .expect("a continuation has at least one step")
            .measurement
    }
}

/// Runs an amplitude continuation of `device` at `freq_hz` over `accels_rms_g` (increasing;
/// each step starts from the previous final state) and refines the impact onset by bisection
/// to a bracket narrower than `refine_tol_g` (Figure 9).
pub fn amplitude_sweep_report(
    device: &Device,
    freq_hz: f64,
    accels_rms_g: &[f64],
    cfg: &SteadyConfig,
    refine_tol_g: f64,
    progress: impl FnMut(usize),
) -> Result<AmplitudeReport, SolverError> {
    let base = Harvester::new(device, Sine::from_rms_g(accels_rms_g[0], freq_hz));
    let cont = Continuation {
        base: &base,
        drive: move |a: f64| (freq_hz, a),
        cfg: cfg.clone(),
    };
    let sweep = cont.run(accels_rms_g, progress)?;
    let k_on = first_contact(&sweep);
    let onset = match k_on {
        Some(k) if k > 0 => Some(cont.refine(&sweep, k, |m| !in_contact(m), refine_tol_g)?),
        _ => None,
    };
    Ok(AmplitudeReport {
        sweep,
        onset,
        contact_at_start: k_on == Some(0),
    })
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
    let mut y = base.rest_state();
    let mut mode = crate::model::Mode::Free;
    let mut steps: Vec<SweepStep> = Vec::new();
    let mut stats = Stats::default();
    for &f in freqs_hz {
        let model = base.with_excitation(Sine::from_rms_g(accel_rms_g, f));
        let (m, y1, mode1, st) = sweep::steady_state(&model, y, mode, accel_rms_g, cfg)?;
        add_stats(&mut stats, &st);
        y = y1;
        mode = mode1;
        let touched = in_contact(&m);
        steps.push(SweepStep {
            measurement: m,
            state: y1,
            mode: mode1,
            stats: st,
        });
        if touched {
            break;
        }
    }
    let k = steps.len() - 1;
    if !in_contact(&steps[k].measurement) {
        return Ok(OnsetSearch::AboveRange);
    }
    if k == 0 {
        return Ok(OnsetSearch::BelowRange);
    }
    let sweep = Sweep {
        values: freqs_hz[..=k].to_vec(),
        steps,
        stats,
    };
    Ok(OnsetSearch::At(cont.refine(
        &sweep,
        k,
        |m| !in_contact(m),
        refine_tol_hz,
    )?))
}

/// Result of the one-parameter calibration of prototype 1.
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
    let freqs = sweep::linspace_step(P1_SWEEP_START_HZ, P1_SWEEP_STOP_HZ, P1_SWEEP_STEP_HZ);
    let cfg = steady_config(published, P1_MEASURED_ONSET_HZ);
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

/// The paper's procedure for the end-stop damping (section 3.2): the b_im for which the
/// impacting branch of the up-sweep of `device` (its stiffness model, bias and gap) at
/// `accel_rms_g` ends at `target_hz` (Figure 8: 1425 Hz). The branch end is the jump if there
/// is one and the loss of contact otherwise ([`SweepReport::branch_end`]); the result records
/// which. The end is assumed to fall as b_im grows (more end-stop damping, lower jump: claim
/// F8-e): b_im = 0 is tried first, and if its branch already ends below the target no b_im >= 0
/// can reach it and `bim_n_s_per_m` is `None`. Otherwise b_im is bracketed by doubling from
/// 1 N s/m and found by Illinois-modified regula falsi until the end is within `tol_hz` of
/// the target or the b_im bracket is narrower than 0.1 %.
pub fn fit_bim_for_jump(
    device: &Device,
    target_hz: f64,
    accel_rms_g: f64,
    freqs_hz: &[f64],
    cfg: &SteadyConfig,
    refine_tol_hz: f64,
    tol_hz: f64,
) -> Result<BimFit, NarrowbandError> {
    let stiffness = device.endstop.stiffness;
    let mut samples = Vec::new();
    let mut eval = |bim: f64| -> Result<(f64, Option<BranchEnd>), SolverError> {
        let d = device.with_endstop(stiffness, bim);
        let r = up_sweep_report(&d, freqs_hz, accel_rms_g, cfg, refine_tol_hz, |_| {})?;
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
    let result = |bim: Option<f64>, achieved: Option<BranchEnd>, samples: Vec<BimSample>| BimFit {
        target_hz,
        stiffness,
        bim_n_s_per_m: bim,
        achieved,
        at_zero: end0,
        samples,
    };
    if f0 < 0.0 {
        drop(eval);
        return Ok(result(None, None, samples));
    }
    if f0.abs() <= tol_hz {
        drop(eval);
        return Ok(result(Some(0.0), end0, samples));
    }
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
    if fb.abs() <= tol_hz {
        drop(eval);
        return Ok(result(Some(b), eb, samples));
    }
    let mut side = 0i8;
    let mut best: (f64, f64, Option<BranchEnd>) = (b, fb, eb);
    for _ in 0..60 {
        let c = if fa.is_finite() && fb.is_finite() {
            (a * fb - b * fa) / (fb - fa)
        } else {
            0.5 * (a + b)
        };
        let (fc, ec) = eval(c)?;
        if fc.abs() < best.1.abs() {
            best = (c, fc, ec);
        }
        if fc.abs() <= tol_hz || (b - a) < 1e-3 * b {
            break;
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
    drop(eval);
    Ok(result(Some(best.0), best.2, samples))
}
