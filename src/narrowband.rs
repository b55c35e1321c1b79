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
//! a jump. If the mass is still in contact at the last requested frequency, the sweep is
//! continued in the same steps beyond the requested range ([`SweepSettings::extend_to_hz`])
//! until contact is lost, and the extra steps are marked ([`SweepReport::extended_from`]).
//!
//! # Steady state
//! [`steady_config`] chooses blocks of about the mechanical ring-up time 2m/b (at least
//! [`MIN_BLOCK_PERIODS`] periods): one block to settle, then blocks until the RMS voltages of
//! two successive blocks agree to 1e-3 (see [`crate::sweep`]). For prototype 1 (ring-up time
//! of about two periods) that is the minimum block; for prototype 2 (Qm near 200) blocks are
//! tens of periods long.
//!
//! # Calibration of prototype 1
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
//! [`figure8_curves`], [`run_curves`] and [`figure8_claims`] (likewise for Figures 9 and 13)
//! define the curves of each figure, run them in parallel, and turn them into the values of
//! the claims in `data/claims.toml`; the experiment binaries and the tests share them.
//! [`compare_sweeps`] and [`compare_amplitude`] measure how much a result moves when the
//! numerics are refined ([`SweepSettings::halved`], [`AmplitudeSettings::halved`]).

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
/// fraction across the refined bracket (of width [`REFINE_TOL_HZ`] or less). A continuous
/// branch changes far less across such a bracket in these sweeps (a few tenths of a percent
/// for prototype 1, a few percent at most on the steep flank of prototype 2's narrow peak),
/// whereas a saddle-node jump keeps its full drop however narrow the bracket.
pub const JUMP_MIN_DROP: f64 = 0.05;

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
            BranchEndKind::ContactLoss => "loss of contact, no jump",
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
    /// The coarse sweep (including any extension beyond the requested range).
    pub sweep: Sweep,
    /// Index of the first step beyond the requested range (`None`: not extended).
    pub extended_from: Option<usize>,
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

    /// The coarse measurements inside the requested range (without the extension).
    pub fn measurements_in_range(&self) -> impl Iterator<Item = &Measurement> {
        let n = self.extended_from.unwrap_or(self.sweep.steps.len());
        self.sweep.steps[..n].iter().map(|s| &s.measurement)
    }

    /// Integrator counters of the sweep and its refinements together.
    pub fn total_stats(&self) -> Stats {
        let mut s = self.sweep.stats;
        add_stats(&mut s, &self.refine_stats);
        s
    }

    /// Largest RMS voltage of load 1 over the requested range (V).
    pub fn max_v1_rms_v(&self) -> f64 {
        self.measurements_in_range()
            .map(|m| m.v1_rms_v)
            .fold(0.0, f64::max)
    }

    /// True if every coarse step met the steady-state criterion.
    pub fn all_converged(&self) -> bool {
        self.measurements().all(|m| m.converged)
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

/// Appends steps to `sweep` at `values`, each continuing from the last state, at drive
/// `drive(p)` = (Hz, g rms); stops after the first step for which `stop(m)` is true.
fn continue_sweep(
    base: &Harvester<Sine>,
    drive: impl Fn(f64) -> (f64, f64),
    cfg: &SteadyConfig,
    sweep: &mut Sweep,
    values: impl IntoIterator<Item = f64>,
    stop: impl Fn(&Measurement) -> bool,
) -> Result<(), SolverError> {
    for p in values {
        let (mut y, mut mode) = (base.rest_state(), crate::model::Mode::Free);
        if let Some(last) = sweep.steps.last() {
            y = last.state;
            mode = last.mode;
        }
        let (f, a) = drive(p);
        let model = base.with_excitation(Sine::from_rms_g(a, f));
        let (m, y1, mode1, st) = sweep::steady_state(&model, y, mode, a, cfg)?;
        add_stats(&mut sweep.stats, &st);
        sweep.values.push(p);
        sweep.steps.push(SweepStep {
            measurement: m,
            state: y1,
            mode: mode1,
            stats: st,
        });
        if stop(&m) {
            break;
        }
    }
    Ok(())
}

/// Values `last + step, last + 2 step, ...` up to `max` (inclusive, with rounding slack).
fn values_beyond(last: f64, step: f64, max: f64) -> impl Iterator<Item = f64> {
    (1..)
        .map(move |i| last + step * i as f64)
        .take_while(move |&v| v <= max + 1e-9 * max.abs())
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
    let settings = SweepSettings {
        freqs_hz: freqs_hz.to_vec(),
        extend_to_hz: f64::NEG_INFINITY,
        cfg: cfg.clone(),
        refine_tol_hz,
    };
    settings.run(device, accel_rms_g, progress)
}

/// Settings of an up-sweep: the frequency grid, an optional extension, the steady-state
/// criterion and the refinement tolerance.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepSettings {
    /// Frequencies (Hz, increasing), the requested range.
    pub freqs_hz: Vec<f64>,
    /// If the mass is still in contact at the last requested frequency, the sweep continues
    /// with the same spacing until contact is lost or this frequency is passed (Hz), so that
    /// an impacting branch that outlives the paper's range still gets an end. Steps beyond
    /// the requested range are marked by [`SweepReport::extended_from`].
    pub extend_to_hz: f64,
    /// Steady-state criterion.
    pub cfg: SteadyConfig,
    /// Bracket width of the refined onset, jump and loss of contact (Hz).
    pub refine_tol_hz: f64,
}

/// Refinement tolerance of the onsets and jumps of Figures 8 and 13 (Hz): well below the 1 Hz
/// the issue asks for.
pub const REFINE_TOL_HZ: f64 = 0.1;

impl SweepSettings {
    /// Prototype 1, Figure 8: 900-1600 Hz in 10 Hz steps (extended to 2400 Hz if needed),
    /// [`steady_config`] at 1220 Hz, brackets of [`REFINE_TOL_HZ`].
    pub fn prototype1(device: &Device) -> Self {
        Self {
            freqs_hz: sweep::linspace_step(P1_SWEEP_START_HZ, P1_SWEEP_STOP_HZ, P1_SWEEP_STEP_HZ),
            extend_to_hz: 2400.0,
            cfg: steady_config(device, 1220.0),
            refine_tol_hz: REFINE_TOL_HZ,
        }
    }

    /// Prototype 2, Figure 13: 600-850 Hz in 2 Hz steps (extended to 1200 Hz if needed),
    /// [`steady_config`] at 700 Hz, brackets of [`REFINE_TOL_HZ`].
    pub fn prototype2(device: &Device) -> Self {
        Self {
            freqs_hz: sweep::linspace_step(600.0, 850.0, 2.0),
            extend_to_hz: 1200.0,
            cfg: steady_config(device, 700.0),
            refine_tol_hz: REFINE_TOL_HZ,
        }
    }

    /// The convergence check of the issue: half the frequency step, half the integrator
    /// tolerance, half the steady-state tolerance and half the refinement bracket.
    pub fn halved(&self) -> Self {
        let f = &self.freqs_hz;
        let mut freqs = Vec::with_capacity(2 * f.len());
        for w in f.windows(2) {
            freqs.push(w[0]);
            freqs.push(0.5 * (w[0] + w[1]));
        }
        if let Some(&last) = f.last() {
            freqs.push(last);
        }
        let mut cfg = self.cfg.clone();
        cfg.rtol *= 0.5;
        cfg.rel_change_tol *= 0.5;
        Self {
            freqs_hz: freqs,
            extend_to_hz: self.extend_to_hz,
            cfg,
            refine_tol_hz: 0.5 * self.refine_tol_hz,
        }
    }

    /// Runs the up-sweep of `device` at `accel_rms_g`, extends it if needed, and refines its
    /// transitions. `progress(i)` is called after each coarse step of the requested range.
    pub fn run(
        &self,
        device: &Device,
        accel_rms_g: f64,
        progress: impl FnMut(usize),
    ) -> Result<SweepReport, SolverError> {
        let freqs = &self.freqs_hz;
        let base = Harvester::new(device, Sine::from_rms_g(accel_rms_g, freqs[0]));
        let cont = frequency_continuation(&base, accel_rms_g, &self.cfg);
        let mut sweep = cont.run(freqs, progress)?;
        let n = sweep.steps.len();
        let mut extended_from = None;
        let last_in_contact = sweep
            .steps
            .last()
            .is_some_and(|s| in_contact(&s.measurement));
        if last_in_contact && n >= 2 {
            let step = freqs[n - 1] - freqs[n - 2];
            let more = values_beyond(freqs[n - 1], step, self.extend_to_hz);
            continue_sweep(
                &base,
                |f| (f, accel_rms_g),
                &self.cfg,
                &mut sweep,
                more,
                |m| !in_contact(m),
            )?;
            if sweep.steps.len() > n {
                extended_from = Some(n);
            }
        }
        let mut report = analyse_up_sweep(&cont, sweep, self.refine_tol_hz)?;
        report.extended_from = extended_from;
        Ok(report)
    }
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
        extended_from: None,
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
    /// The coarse continuation (values in g rms), including any extension.
    pub sweep: Sweep,
    /// Index of the first step beyond the requested range (`None`: not extended).
    pub extended_from: Option<usize>,
    /// Impact onset bracket (g rms); `None` if no contact, or contact from the first step.
    pub onset: Option<Transition>,
    /// True when the first step is already in contact.
    pub contact_at_start: bool,
}

impl AmplitudeReport {
    /// The measurement at the largest requested amplitude (the saturated power of Figure 9).
    pub fn at_stop(&self) -> &Measurement {
        let n = self.extended_from.unwrap_or(self.sweep.steps.len());
        &self.sweep.steps[n - 1].measurement
    }

    /// The coarse measurements inside the requested range (without the extension).
    pub fn measurements_in_range(&self) -> impl Iterator<Item = &Measurement> {
        let n = self.extended_from.unwrap_or(self.sweep.steps.len());
        self.sweep.steps[..n].iter().map(|s| &s.measurement)
    }
}

/// Settings of an amplitude continuation (Figure 9).
#[derive(Debug, Clone, PartialEq)]
pub struct AmplitudeSettings {
    /// Drive frequency (Hz).
    pub freq_hz: f64,
    /// RMS accelerations (g, increasing), the requested range.
    pub accels_rms_g: Vec<f64>,
    /// If no step of the requested range touches a stop, the continuation goes on with the
    /// same spacing until it does or this amplitude is passed (g rms), so that the onset is
    /// found even beyond the paper's range.
    pub extend_to_g: f64,
    /// Steady-state criterion.
    pub cfg: SteadyConfig,
    /// Bracket width of the refined onset (g).
    pub refine_tol_g: f64,
}

impl AmplitudeSettings {
    /// Figure 9: prototype 1 at its measured resonance 1220 Hz, 0.5-5.5 g rms in 0.1 g steps
    /// (extended to 8 g if needed), [`steady_config`] at 1220 Hz, onset brackets of 0.005 g.
    pub fn figure9(device: &Device) -> Self {
        Self {
            freq_hz: FIG9_FREQ_HZ,
            accels_rms_g: sweep::linspace_step(0.5, 5.5, 0.1),
            extend_to_g: 8.0,
            cfg: steady_config(device, FIG9_FREQ_HZ),
            refine_tol_g: 0.005,
        }
    }

    /// Half the amplitude step, the integrator tolerance, the steady-state tolerance and the
    /// refinement bracket (convergence check).
    pub fn halved(&self) -> Self {
        let a = &self.accels_rms_g;
        let mut acc = Vec::with_capacity(2 * a.len());
        for w in a.windows(2) {
            acc.push(w[0]);
            acc.push(0.5 * (w[0] + w[1]));
        }
        if let Some(&last) = a.last() {
            acc.push(last);
        }
        let mut cfg = self.cfg.clone();
        cfg.rtol *= 0.5;
        cfg.rel_change_tol *= 0.5;
        Self {
            freq_hz: self.freq_hz,
            accels_rms_g: acc,
            extend_to_g: self.extend_to_g,
            cfg,
            refine_tol_g: 0.5 * self.refine_tol_g,
        }
    }

    /// Runs the continuation for `device` and refines the onset (see [`AmplitudeReport`]).
    pub fn run(
        &self,
        device: &Device,
        progress: impl FnMut(usize),
    ) -> Result<AmplitudeReport, SolverError> {
        let f = self.freq_hz;
        let acc = &self.accels_rms_g;
        let base = Harvester::new(device, Sine::from_rms_g(acc[0], f));
        let cont = Continuation {
            base: &base,
            drive: move |a: f64| (f, a),
            cfg: self.cfg.clone(),
        };
        let mut sweep = cont.run(acc, progress)?;
        let n = sweep.steps.len();
        let mut extended_from = None;
        if first_contact(&sweep).is_none() && n >= 2 {
            let step = acc[n - 1] - acc[n - 2];
            let more = values_beyond(acc[n - 1], step, self.extend_to_g);
            continue_sweep(&base, |a| (f, a), &self.cfg, &mut sweep, more, in_contact)?;
            if sweep.steps.len() > n {
                extended_from = Some(n);
            }
        }
        let k_on = first_contact(&sweep);
        let onset = match k_on {
            Some(k) if k > 0 => {
                Some(cont.refine(&sweep, k, |m| !in_contact(m), self.refine_tol_g)?)
            }
            _ => None,
        };
        Ok(AmplitudeReport {
            sweep,
            extended_from,
            onset,
            contact_at_start: k_on == Some(0),
        })
    }
}

/// Runs an amplitude continuation of `device` at `freq_hz` over `accels_rms_g` (increasing;
/// each step starts from the previous final state) and refines the impact onset by bisection
/// to a bracket narrower than `refine_tol_g` (Figure 9). No extension beyond the range.
pub fn amplitude_sweep_report(
    device: &Device,
    freq_hz: f64,
    accels_rms_g: &[f64],
    cfg: &SteadyConfig,
    refine_tol_g: f64,
    progress: impl FnMut(usize),
) -> Result<AmplitudeReport, SolverError> {
    AmplitudeSettings {
        freq_hz,
        accels_rms_g: accels_rms_g.to_vec(),
        extend_to_g: f64::NEG_INFINITY,
        cfg: cfg.clone(),
        refine_tol_g,
    }
    .run(device, progress)
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
    let settings = SweepSettings::prototype1(published);
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

// ------------------------------------------------------------------ figure studies

/// One curve of an up-sweep figure: drive level and end-stop model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurveSpec {
    /// RMS acceleration (g).
    pub accel_rms_g: f64,
    /// Spring law of the stop.
    pub stiffness: StiffnessModel,
    /// End-stop damping b_im (N s/m).
    pub bim_n_s_per_m: f64,
    /// Tension-free contact (SPEC 5b) instead of eq 1 as written.
    pub tension_free: bool,
}

impl CurveSpec {
    /// A curve with eq 1 as written (the damper may pull).
    pub fn new(accel_rms_g: f64, stiffness: StiffnessModel, bim_n_s_per_m: f64) -> Self {
        Self {
            accel_rms_g,
            stiffness,
            bim_n_s_per_m,
            tension_free: false,
        }
    }

    /// The same curve with a tension-free contact.
    pub fn tension_free(mut self) -> Self {
        self.tension_free = true;
        self
    }

    /// Label, e.g. `5.5 g, Hertz, b_im=1.5`.
    pub fn label(&self) -> String {
        let law = match self.stiffness {
            StiffnessModel::Hertz => "Hertz",
            StiffnessModel::Linear => "linear",
        };
        format!(
            "{} g, {law}, b_im={}{}",
            self.accel_rms_g,
            self.bim_n_s_per_m,
            if self.tension_free {
                ", tension-free"
            } else {
                ""
            }
        )
    }

    /// The device with this curve's end-stop model.
    pub fn device(&self, base: &Device) -> Device {
        let mut d = base.with_endstop(self.stiffness, self.bim_n_s_per_m);
        d.endstop.tension_free = self.tension_free;
        d
    }
}

/// Figure 8's curves (prototype 1, 30 V): 4.1 g Hertz 1.5; 5.5 g Hertz b_im = 0, 1.5, 10;
/// 5.5 g linear (eq 19) b_im = 2; and, as a sensitivity, 5.5 g Hertz 1.5 tension-free.
pub fn figure8_curves() -> Vec<CurveSpec> {
    use StiffnessModel::{Hertz, Linear};
    vec![
        CurveSpec::new(P1_LOW_ACCEL_RMS_G, Hertz, 1.5),
        CurveSpec::new(P1_HIGH_ACCEL_RMS_G, Hertz, 0.0),
        CurveSpec::new(P1_HIGH_ACCEL_RMS_G, Hertz, 1.5),
        CurveSpec::new(P1_HIGH_ACCEL_RMS_G, Hertz, 10.0),
        CurveSpec::new(P1_HIGH_ACCEL_RMS_G, Linear, 2.0),
        CurveSpec::new(P1_HIGH_ACCEL_RMS_G, Hertz, 1.5).tension_free(),
    ]
}

/// Figure 13's bias voltage (V).
pub const FIG13_BIAS_V: f64 = 10.0;

/// Figure 13's curves (prototype 2, 10 V): 0.12 and 0.31 g with the linear law and
/// b_im = 0.4 N s/m, and 0.31 g with the Hertz law and b_im = 0.34 N s/m.
pub fn figure13_curves() -> Vec<CurveSpec> {
    use StiffnessModel::{Hertz, Linear};
    vec![
        CurveSpec::new(0.12, Linear, 0.4),
        CurveSpec::new(0.31, Linear, 0.4),
        CurveSpec::new(0.31, Hertz, 0.34),
    ]
}

/// A curve and its sweep.
#[derive(Debug, Clone)]
pub struct Curve {
    /// What was swept.
    pub spec: CurveSpec,
    /// The report.
    pub report: SweepReport,
}

/// Runs the up-sweeps of `specs` on `device` in parallel (rayon); `on_step()` is called after
/// every coarse step of every sweep (from any thread).
pub fn run_curves(
    device: &Device,
    specs: &[CurveSpec],
    settings: &SweepSettings,
    on_step: &(dyn Fn() + Sync),
) -> Result<Vec<Curve>, SolverError> {
    use rayon::prelude::*;
    specs
        .par_iter()
        .map(|spec| {
            let report = settings.run(&spec.device(device), spec.accel_rms_g, |_| on_step())?;
            Ok(Curve {
                spec: *spec,
                report,
            })
        })
        .collect()
}

/// Finds a curve by its spec.
pub fn find_curve<'a>(curves: &'a [Curve], spec: &CurveSpec) -> Option<&'a Curve> {
    curves.iter().find(|c| c.spec == *spec)
}

/// Our value for one number of a claim (`data/claims.toml`), with a note for the book.
#[derive(Debug, Clone, PartialEq)]
pub struct ClaimValue {
    /// Claim id, e.g. `F8-c`.
    pub id: &'static str,
    /// Quantity key.
    pub quantity: &'static str,
    /// Our value (qualitative: 1 yes, 0 no).
    pub value: f64,
    /// Uncertainty (bracket half-width), same unit.
    pub uncertainty: Option<f64>,
    /// What the value is (e.g. "loss of contact, no jump").
    pub note: String,
}

fn bool_value(id: &'static str, quantity: &'static str, yes: bool, note: String) -> ClaimValue {
    ClaimValue {
        id,
        quantity,
        value: if yes { 1.0 } else { 0.0 },
        uncertainty: None,
        note,
    }
}

/// The value of a jump claim: the end of the impacting branch, labelled jump or loss of
/// contact (a gradual exit is never presented as a jump), `None` if the branch never ends.
fn branch_end_value(
    id: &'static str,
    quantity: &'static str,
    curve: &Curve,
    stop_hz: f64,
) -> Option<ClaimValue> {
    let end = curve.report.branch_end()?;
    let v = end.transition.value();
    let mut note = end.kind.label().to_string();
    if v > stop_hz {
        note.push_str(&format!(
            ", beyond the paper's {stop_hz} Hz (extended sweep)"
        ));
    }
    Some(ClaimValue {
        id,
        quantity,
        value: v,
        uncertainty: Some(end.transition.half_width()),
        note,
    })
}

/// Figure 8's claim values from its curves ([`figure8_curves`]).
///
/// * F8-a: 1 if the 4.1 g sweep never touches a stop.
/// * F8-b: refined onset of the 5.5 g Hertz b_im = 1.5 sweep.
/// * F8-c, d, e, f: where the impacting branch of each 5.5 g sweep ends (jump, or loss of
///   contact when there is no jump; the note says which).
/// * F8-e order: 1 only if all three Hertz sweeps end with a confirmed jump and the jump
///   frequencies fall strictly as b_im grows.
pub fn figure8_claims(curves: &[Curve], stop_hz: f64) -> Vec<ClaimValue> {
    use StiffnessModel::{Hertz, Linear};
    let hi = P1_HIGH_ACCEL_RMS_G;
    let mut out = Vec::new();
    if let Some(c) = find_curve(curves, &CurveSpec::new(P1_LOW_ACCEL_RMS_G, Hertz, 1.5)) {
        let touched = c.report.any_contact();
        out.push(bool_value(
            "F8-a",
            "no_impact_4p1g",
            !touched,
            if touched {
                "the mass reaches the stops".into()
            } else {
                "no step of the sweep has contact".into()
            },
        ));
    }
    let h15 = find_curve(curves, &CurveSpec::new(hi, Hertz, 1.5));
    if let Some(t) = h15.and_then(|c| c.report.onset) {
        out.push(ClaimValue {
            id: "F8-b",
            quantity: "impact_onset_5p5g_hz",
            value: t.value(),
            uncertainty: Some(t.half_width()),
            note: "first contact, refined".into(),
        });
    }
    let jump_claims = [
        (
            "F8-c",
            "jump_hertz_bim1p5_hz",
            CurveSpec::new(hi, Hertz, 1.5),
        ),
        ("F8-d", "jump_hertz_bim0_hz", CurveSpec::new(hi, Hertz, 0.0)),
        (
            "F8-e",
            "jump_hertz_bim10_hz",
            CurveSpec::new(hi, Hertz, 10.0),
        ),
        (
            "F8-f",
            "jump_linear_bim2_hz",
            CurveSpec::new(hi, Linear, 2.0),
        ),
    ];
    for (id, q, spec) in jump_claims {
        if let Some(v) = find_curve(curves, &spec).and_then(|c| branch_end_value(id, q, c, stop_hz))
        {
            out.push(v);
        }
    }
    let jumps: Vec<Option<f64>> = [0.0, 1.5, 10.0]
        .iter()
        .map(|&b| {
            find_curve(curves, &CurveSpec::new(hi, Hertz, b))
                .and_then(|c| c.report.jump.map(|t| t.value()))
        })
        .collect();
    let (ordered, note) = match (jumps[0], jumps[1], jumps[2]) {
        (Some(j0), Some(j1), Some(j10)) => (
            j0 > j1 && j1 > j10,
            "all three sweeps jump; order of the jump frequencies".to_string(),
        ),
        _ => (
            false,
            "not every one of the three sweeps ends with a jump".to_string(),
        ),
    };
    out.push(bool_value("F8-e", "jump_order_by_bim", ordered, note));
    out
}

/// Figure 9's measured resonance frequency (Hz).
pub const FIG9_FREQ_HZ: f64 = 1220.0;
/// Figure 9's bias voltages (V).
pub const FIG9_BIASES_V: [f64; 3] = [20.0, 30.0, 40.0];
/// Figure 9's end-stop model: the Hertz fit of Figure 8 (the paper does not say).
pub const FIG9_BIM_N_S_PER_M: f64 = 1.5;
/// Two onsets are "the same" when they differ by at most this (g): the amplitude-threshold
/// tolerance class of the claims file.
pub const ONSET_SAME_TOL_G: f64 = 0.25;

/// Which power Figure 9 plots (SPEC 5b).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PowerReading {
    /// The power of one load, <V1^2>/RL.
    OneLoad,
    /// The power of both loads, <V1^2 + V2^2>/RL.
    BothLoads,
}

impl PowerReading {
    /// The power of a measurement under this reading (W).
    pub fn of(self, m: &Measurement) -> f64 {
        match self {
            PowerReading::OneLoad => m.p1_w,
            PowerReading::BothLoads => m.p_total_w(),
        }
    }

    /// Label for tables.
    pub fn label(self) -> &'static str {
        match self {
            PowerReading::OneLoad => "one load",
            PowerReading::BothLoads => "both loads",
        }
    }
}

/// One bias voltage of Figure 9.
#[derive(Debug, Clone)]
pub struct AmplitudeCurve {
    /// Bias voltage (V).
    pub bias_v: f64,
    /// The continuation.
    pub report: AmplitudeReport,
}

/// Runs Figure 9's amplitude continuations (one per bias voltage in `biases_v`) in parallel;
/// the device's end-stop is set to Hertz with [`FIG9_BIM_N_S_PER_M`].
pub fn run_figure9(
    device: &Device,
    biases_v: &[f64],
    settings: &AmplitudeSettings,
    on_step: &(dyn Fn() + Sync),
) -> Result<Vec<AmplitudeCurve>, SolverError> {
    use rayon::prelude::*;
    let dev = device.with_endstop(StiffnessModel::Hertz, FIG9_BIM_N_S_PER_M);
    biases_v
        .par_iter()
        .map(|&vb| {
            let report = settings.run(&dev.with_bias(vb), |_| on_step())?;
            Ok(AmplitudeCurve { bias_v: vb, report })
        })
        .collect()
}

/// Figure 9's claim values under a power reading.
///
/// * F9-a: refined onsets at 20, 30, 40 V (found beyond 5.5 g by the extension if needed;
///   the note says so); "the same for all" is 1 when all exist and their spread is at most
///   [`ONSET_SAME_TOL_G`].
/// * F9-b: the power at 5.5 g at 20 and 40 V (nW) and their ratio.
pub fn figure9_claims(curves: &[AmplitudeCurve], reading: PowerReading) -> Vec<ClaimValue> {
    let mut out = Vec::new();
    let by_vb = |vb: f64| curves.iter().find(|c| c.bias_v == vb);
    let mut onsets = Vec::new();
    for (vb, q) in [
        (20.0, "onset_g_20v"),
        (30.0, "onset_g_30v"),
        (40.0, "onset_g_40v"),
    ] {
        let Some(c) = by_vb(vb) else { continue };
        onsets.push(c.report.onset.map(|t| t.value()));
        if let Some(t) = c.report.onset {
            let beyond = c.report.extended_from.is_some();
            out.push(ClaimValue {
                id: "F9-a",
                quantity: q,
                value: t.value(),
                uncertainty: Some(t.half_width()),
                note: if beyond {
                    "first contact, beyond the paper's 5.5 g (extended continuation)".into()
                } else {
                    "first contact, refined".into()
                },
            });
        }
    }
    let all: Option<Vec<f64>> = onsets.iter().copied().collect();
    let (same, note) = match all {
        Some(v) if v.len() == 3 => {
            let spread = v.iter().cloned().fold(f64::MIN, f64::max)
                - v.iter().cloned().fold(f64::MAX, f64::min);
            (
                spread <= ONSET_SAME_TOL_G,
                format!("spread of the three onsets vs {ONSET_SAME_TOL_G} g"),
            )
        }
        _ => (false, "an onset is missing".to_string()),
    };
    out.push(bool_value("F9-a", "onset_same_all_vb", same, note));
    let p = |vb: f64| by_vb(vb).map(|c| reading.of(c.report.at_stop()));
    let note = format!("{} at 5.5 g", reading.label());
    if let Some(p20) = p(20.0) {
        out.push(ClaimValue {
            id: "F9-b",
            quantity: "p_sat_20v_nw",
            value: p20 * 1e9,
            uncertainty: None,
            note: note.clone(),
        });
    }
    if let Some(p40) = p(40.0) {
        out.push(ClaimValue {
            id: "F9-b",
            quantity: "p_sat_40v_nw",
            value: p40 * 1e9,
            uncertainty: None,
            note: note.clone(),
        });
    }
    if let (Some(p20), Some(p40)) = (p(20.0), p(40.0)) {
        out.push(ClaimValue {
            id: "F9-b",
            quantity: "p_sat_ratio_40v_20v",
            value: p40 / p20,
            uncertainty: None,
            note,
        });
    }
    out
}

/// Figure 13's claim values from its curves ([`figure13_curves`]).
///
/// * no impact at 0.12 g: 1 if no step has contact;
/// * jump at 0.31 g: 1 if the linear-law sweep has contact and a confirmed jump;
/// * Hertz and linear agree: 1 if both 0.31 g sweeps jump and their jump frequencies differ
///   by at most 3 % (the frequency tolerance class) of the linear one.
pub fn figure13_claims(curves: &[Curve]) -> Vec<ClaimValue> {
    use StiffnessModel::{Hertz, Linear};
    let mut out = Vec::new();
    if let Some(c) = find_curve(curves, &CurveSpec::new(0.12, Linear, 0.4)) {
        let touched = c.report.any_contact();
        out.push(bool_value(
            "F13",
            "no_impact_0p12g",
            !touched,
            if touched {
                "the mass reaches the stops".into()
            } else {
                "no step of the sweep has contact".into()
            },
        ));
    }
    let lin = find_curve(curves, &CurveSpec::new(0.31, Linear, 0.4));
    let her = find_curve(curves, &CurveSpec::new(0.31, Hertz, 0.34));
    if let Some(c) = lin {
        let yes = c.report.any_contact() && c.report.jump.is_some();
        out.push(bool_value(
            "F13",
            "jump_0p31g",
            yes,
            match c.report.jump {
                Some(_) => "impacts and a confirmed jump".into(),
                None => "no confirmed jump".into(),
            },
        ));
    }
    if let (Some(l), Some(h)) = (lin, her) {
        let (agree, note) = match (l.report.jump, h.report.jump) {
            (Some(jl), Some(jh)) => {
                let rel = (jh.value() - jl.value()).abs() / jl.value();
                (
                    rel <= 0.03,
                    "relative difference of the jumps vs 3 %".to_string(),
                )
            }
            _ => (false, "a sweep has no jump".to_string()),
        };
        out.push(bool_value("F13", "hertz_linear_agree", agree, note));
    }
    out
}

// ------------------------------------------------------------------ convergence

/// Differences between a sweep and its refined repetition ([`SweepSettings::halved`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SweepComparison {
    /// Relative change of the onset (`None` if either has none).
    pub onset_rel: Option<f64>,
    /// Relative change of the branch end (`None` if either has none).
    pub end_rel: Option<f64>,
    /// Whether the two runs agree on the kind of branch end.
    pub same_end_kind: bool,
    /// Largest relative change of the RMS voltage of load 1 at the common frequencies.
    pub max_v1_rel: f64,
    /// Largest relative change of the RMS voltage of load 2 at the common frequencies.
    pub max_v2_rel: f64,
    /// Common frequencies compared.
    pub compared: usize,
    /// Common frequencies left out because they lie between the two runs' branch ends
    /// (there the runs are legitimately on different branches).
    pub excluded: usize,
}

/// Compares `reference` with `refined` at the frequencies they share (see
/// [`SweepComparison`]).
pub fn compare_sweeps(reference: &SweepReport, refined: &SweepReport) -> SweepComparison {
    let rel = |a: f64, b: f64| (a - b).abs() / a.abs().max(b.abs()).max(1e-300);
    let onset_rel = match (reference.onset, refined.onset) {
        (Some(a), Some(b)) => Some(rel(a.value(), b.value())),
        _ => None,
    };
    let (ea, eb) = (reference.branch_end(), refined.branch_end());
    let end_rel = match (ea, eb) {
        (Some(a), Some(b)) => Some(rel(a.transition.value(), b.transition.value())),
        _ => None,
    };
    let same_end_kind = ea.map(|e| e.kind) == eb.map(|e| e.kind);
    let between = match (ea, eb) {
        (Some(a), Some(b)) => {
            let (x, y) = (a.transition.value(), b.transition.value());
            Some((x.min(y), x.max(y)))
        }
        _ => None,
    };
    let mut out = SweepComparison {
        onset_rel,
        end_rel,
        same_end_kind,
        max_v1_rel: 0.0,
        max_v2_rel: 0.0,
        compared: 0,
        excluded: 0,
    };
    for ma in reference.measurements() {
        let f = ma.freq_hz;
        let Some(mb) = refined
            .measurements()
            .find(|m| (m.freq_hz - f).abs() <= 1e-9 * f)
        else {
            continue;
        };
        if let Some((lo, hi)) = between {
            if f >= lo && f <= hi {
                out.excluded += 1;
                continue;
            }
        }
        out.compared += 1;
        out.max_v1_rel = out.max_v1_rel.max(rel(ma.v1_rms_v, mb.v1_rms_v));
        out.max_v2_rel = out.max_v2_rel.max(rel(ma.v2_rms_v, mb.v2_rms_v));
    }
    out
}

/// Differences between an amplitude continuation and its refined repetition.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AmplitudeComparison {
    /// Absolute change of the onset (g; `None` if either has none).
    pub onset_abs_g: Option<f64>,
    /// Relative change of the power of both loads at the last requested amplitude.
    pub p_rel: f64,
    /// Largest relative change of the RMS voltage of load 1 at the common amplitudes.
    pub max_v1_rel: f64,
}

/// Compares two amplitude continuations (see [`AmplitudeComparison`]).
pub fn compare_amplitude(
    reference: &AmplitudeReport,
    refined: &AmplitudeReport,
) -> AmplitudeComparison {
    let rel = |a: f64, b: f64| (a - b).abs() / a.abs().max(b.abs()).max(1e-300);
    let mut max_v1_rel: f64 = 0.0;
    for ma in reference.measurements_in_range() {
        if let Some(mb) = refined
            .measurements_in_range()
            .find(|m| (m.accel_rms_g - ma.accel_rms_g).abs() <= 1e-9)
        {
            max_v1_rel = max_v1_rel.max(rel(ma.v1_rms_v, mb.v1_rms_v));
        }
    }
    AmplitudeComparison {
        onset_abs_g: match (reference.onset, refined.onset) {
            (Some(a), Some(b)) => Some((a.value() - b.value()).abs()),
            _ => None,
        },
        p_rel: rel(
            reference.at_stop().p_total_w(),
            refined.at_stop().p_total_w(),
        ),
        max_v1_rel,
    }
}
