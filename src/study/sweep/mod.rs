//! Frequency sweeps (stepped sine) with their impact onset, jump and loss of contact refined.
//!
//! Everything here is built on [`crate::study::stepped`]: a [`SteppedDrive`] runs the stepped sine
//! (each step starts from the previous final state and is measured in steady state), and
//! [`SteppedDrive::refine_steps`] bisects transitions between two steps.
//!
//! Down-sweeps ([`SweepSettings::run_down`], [`DownSweepReport`]) take the same grid from high
//! to low frequency and report the jump up onto the impacting branch.
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
//! Every step is measured once the model has settled by the criterion of [`SettleSettings`]
//! ([`crate::study::steady`]). [`SweepSettings::for_device`] takes the criterion of sweeps
//! that must leave a branch at its fold ([`settle_settings_across_folds`]): blocks long enough
//! that the ghost of the merged orbits cannot hold the state on a branch that has ended.

use crate::device::Device;
use crate::model::Model;
use crate::ode::{SolverError, Stats};
use crate::progress::{Progress, Silent};
use crate::study::steady::{settle_settings_across_folds, Measurement, SettleSettings};
use crate::study::stepped::{
    continue_sweep, first_contact, in_contact, values_beyond, with_midpoints, Approach, Drive,
    SteppedDrive, Sweep, Transition,
};

mod down;

pub use down::{DownEndKind, DownSweepReport};

/// A coarse step is a jump candidate when the total power falls by more than this fraction
/// relative to the previous step (which must be in contact).
pub const CANDIDATE_DROP: f64 = 0.05;

/// A candidate is confirmed as a jump when the total power still falls by more than this
/// fraction across the refined bracket (of width [`REFINE_TOL_HZ`] or less). A continuous
/// branch changes far less across such a bracket in these sweeps (a few tenths of a percent
/// for prototype 1, a few percent at most on the steep flank of prototype 2's narrow peak),
/// whereas a saddle-node jump keeps its full drop however narrow the bracket.
pub const JUMP_MIN_DROP: f64 = 0.05;

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

/// Which transitions a sweep's analysis refines, each by a bisection of steady states that
/// leaves the coarse steps as they are. The sweeps of the command refine every one
/// ([`Refine::ALL`]); a caller that reads only some (the fit's model reads the features its data
/// measure) leaves the others unrefined (`None` in the report).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Refine {
    /// The impact onset of an up-sweep.
    pub onset: bool,
    /// The end of the branch ([`SweepReport::branch_end`], [`DownSweepReport::branch_end`]):
    /// the jump, and where there is none the loss of contact (up) or the first contact (down).
    pub branch_end: bool,
    /// The loss of contact (up) or the first contact (down) also where a jump ends the branch.
    pub contact_beside_jump: bool,
}

impl Refine {
    /// Every transition.
    pub const ALL: Self = Self {
        onset: true,
        branch_end: true,
        contact_beside_jump: true,
    };

    /// Whether the contact transition is refined, given whether a jump was found.
    fn contact(self, jump_found: bool) -> bool {
        self.contact_beside_jump || (self.branch_end && !jump_found)
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
    /// Integrator counters of every trial of every refinement, each counted once (the coarse
    /// steps' own are in `sweep.stats`).
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
        s += self.refine_stats;
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

/// The continuation of an up-sweep in frequency at fixed RMS acceleration.
pub fn frequency_continuation<'a, M: Model<N>, const N: usize>(
    base: &'a M,
    accel_rms_g: f64,
    cfg: &SettleSettings,
) -> SteppedDrive<'a, M, impl Drive, N> {
    SteppedDrive {
        base,
        drive: move |f: f64| (f, accel_rms_g),
        cfg: cfg.clone(),
    }
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
    pub cfg: SettleSettings,
    /// Bracket width of the refined onset, jump and loss of contact (Hz).
    pub refine_tol_hz: f64,
}

/// Refinement tolerance of the onsets and jumps of Figures 8 and 13 (Hz): well below the 1 Hz
/// a jump claim needs.
pub const REFINE_TOL_HZ: f64 = 0.1;

/// What makes a frequency range and drive unusable for a sweep or a continuation (callers
/// word it with their own option names).
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum RangeError {
    /// The ends are not finite and positive with stop > start.
    #[error("the range must be positive and finite, with its stop above its start")]
    Ends,
    /// The step is not positive, exceeds the range, or gives more than [`MAX_STEPS`] steps.
    #[error("the step must be positive, not larger than the range, and give at most 100000 steps")]
    Step,
    /// The acceleration is not finite and positive.
    #[error("the acceleration must be a finite positive number")]
    Accel,
}

/// The most steps a range may hold: each is a steady state of its own, and a grid of more
/// (a step of 1e-300 Hz, say) would not fit in memory.
pub const MAX_STEPS: usize = 100_000;

/// Checks a frequency range `start_hz..stop_hz` with steps of `step_hz` at `accel_rms_g`.
pub fn check_range(
    accel_rms_g: f64,
    start_hz: f64,
    stop_hz: f64,
    step_hz: f64,
) -> Result<(), RangeError> {
    if !(start_hz.is_finite() && stop_hz.is_finite() && start_hz > 0.0 && stop_hz > start_hz) {
        return Err(RangeError::Ends);
    }
    if !(step_hz > 0.0
        && step_hz <= stop_hz - start_hz
        && (stop_hz - start_hz) / step_hz <= MAX_STEPS as f64)
    {
        return Err(RangeError::Step);
    }
    if !(accel_rms_g.is_finite() && accel_rms_g > 0.0) {
        return Err(RangeError::Accel);
    }
    Ok(())
}

impl SweepSettings {
    /// The sweep of the grid `freqs_hz` (up or down) for any device, without extension: the
    /// steady-state criterion of sweeps that must leave a branch at its fold
    /// ([`settle_settings_across_folds`]) at the grid's middle frequency, and transitions
    /// refined to `refine_tol_hz`. The `endstop` command's and the Python package's sweeps.
    pub fn for_device(device: &Device, freqs_hz: Vec<f64>, refine_tol_hz: f64) -> Self {
        let (lo, hi) = freqs_hz
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &f| {
                (lo.min(f), hi.max(f))
            });
        Self {
            cfg: settle_settings_across_folds(device, 0.5 * (lo + hi)),
            freqs_hz,
            extend_to_hz: f64::NEG_INFINITY,
            refine_tol_hz,
        }
    }

    /// The convergence check: half the frequency step, half the integrator
    /// tolerance, half the steady-state tolerance and half the refinement bracket.
    pub fn halved(&self) -> Self {
        Self {
            freqs_hz: with_midpoints(&self.freqs_hz),
            extend_to_hz: self.extend_to_hz,
            cfg: self.cfg.halved(),
            refine_tol_hz: 0.5 * self.refine_tol_hz,
        }
    }

    /// Runs the up-sweep of `device` at `accel_rms_g`, extends it if needed, and refines its
    /// transitions. `progress.tick()` is called after each coarse step of the requested range.
    pub fn run(
        &self,
        device: &Device,
        accel_rms_g: f64,
        progress: &dyn Progress,
    ) -> Result<SweepReport, SolverError> {
        self.run_with(device, accel_rms_g, Approach::Jump, progress)
    }

    /// As [`SweepSettings::run`], each step and each refinement trial reached by `approach`
    /// (the extension beyond the range, where there is one, steps at once).
    pub fn run_with(
        &self,
        device: &Device,
        accel_rms_g: f64,
        approach: Approach,
        progress: &dyn Progress,
    ) -> Result<SweepReport, SolverError> {
        crate::with_harvester!(device, |h| self.run_on(&h, accel_rms_g, approach, progress))
    }

    /// As [`SweepSettings::run_with`] on a model.
    pub fn run_on<M: Model<N>, const N: usize>(
        &self,
        base: &M,
        accel_rms_g: f64,
        approach: Approach,
        progress: &dyn Progress,
    ) -> Result<SweepReport, SolverError> {
        let report = self.run_on_until(
            base,
            accel_rms_g,
            approach,
            progress,
            Refine::ALL,
            &mut |_| false,
        )?;
        Ok(report.expect("a sweep that is never stopped completes"))
    }

    /// As [`SweepSettings::run`], given each coarse step of the requested range as it is
    /// measured: `None` as soon as `stop(m)` is true for one (the rest of the sweep is not
    /// run), else the report, the same as [`SweepSettings::run`]'s bit for bit.
    pub fn run_until(
        &self,
        device: &Device,
        accel_rms_g: f64,
        stop: &mut dyn FnMut(&Measurement) -> bool,
    ) -> Result<Option<SweepReport>, SolverError> {
        self.run_until_refining(device, accel_rms_g, Refine::ALL, stop)
    }

    /// As [`SweepSettings::run_until`], refining only the transitions `refine` names (the
    /// coarse steps and those refined are the same bit for bit).
    pub fn run_until_refining(
        &self,
        device: &Device,
        accel_rms_g: f64,
        refine: Refine,
        stop: &mut dyn FnMut(&Measurement) -> bool,
    ) -> Result<Option<SweepReport>, SolverError> {
        crate::with_harvester!(device, |h| self.run_on_until(
            &h,
            accel_rms_g,
            Approach::Jump,
            &Silent,
            refine,
            stop
        ))
    }

    fn run_on_until<M: Model<N>, const N: usize>(
        &self,
        base: &M,
        accel_rms_g: f64,
        approach: Approach,
        progress: &dyn Progress,
        refine: Refine,
        stop: &mut dyn FnMut(&Measurement) -> bool,
    ) -> Result<Option<SweepReport>, SolverError> {
        let freqs = &self.freqs_hz;
        let cont = frequency_continuation(base, accel_rms_g, &self.cfg);
        let rest = base.rest_state();
        let mut sweep = cont.run_from_until(
            rest,
            base.mode_of(&rest),
            None,
            freqs,
            approach,
            progress,
            stop,
        )?;
        if sweep.steps.len() < freqs.len() {
            return Ok(None);
        }
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
                base,
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
        let mut report = analyse_up_sweep(&cont, sweep, self.refine_tol_hz, approach, refine)?;
        report.extended_from = extended_from;
        Ok(Some(report))
    }
}

fn analyse_up_sweep<M: Model<N>, D: Drive, const N: usize>(
    cont: &SteppedDrive<'_, M, D, N>,
    sweep: Sweep,
    tol: f64,
    approach: Approach,
    refine: Refine,
) -> Result<SweepReport, SolverError> {
    let mut refine_stats = Stats::default();
    let steps = &sweep.steps;
    let k_on = first_contact(&sweep);
    let contact_at_start = k_on == Some(0);
    let onset = match k_on {
        Some(k) if k > 0 && refine.onset => {
            let r = cont.refine_steps_with(&sweep, k, |m| !in_contact(m), tol, approach)?;
            refine_stats += r.stats;
            Some(r.transition)
        }
        _ => None,
    };
    let mut jump = None;
    let mut jump_power_ratio = None;
    let mut contact_lost = None;
    if let Some(k0) = k_on {
        let candidates = if refine.branch_end {
            (k0 + 1)..steps.len()
        } else {
            0..0
        };
        for k in candidates {
            let a = &steps[k - 1].measurement;
            let b = &steps[k].measurement;
            if !(in_contact(a) && b.p_total_w() < (1.0 - CANDIDATE_DROP) * a.p_total_w()) {
                continue;
            }
            let threshold = (a.p_total_w() * b.p_total_w()).sqrt();
            let r =
                cont.refine_steps_with(&sweep, k, |m| m.p_total_w() > threshold, tol, approach)?;
            refine_stats += r.stats;
            let ratio = r.after.measurement.p_total_w() / r.before.measurement.p_total_w();
            if ratio < 1.0 - JUMP_MIN_DROP {
                jump = Some(r.transition);
                jump_power_ratio = Some(ratio);
                break;
            }
        }
        let lost = ((k0 + 1)..steps.len()).find(|&k| !in_contact(&steps[k].measurement));
        if let Some(k) = lost.filter(|_| refine.contact(jump.is_some())) {
            let r = cont.refine_steps_with(&sweep, k, in_contact, tol, approach)?;
            refine_stats += r.stats;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::drive::Sine;
    use crate::progress::Silent;
    use crate::study::steady::{settle_settings, steady_state};
    use crate::study::stepped::linspace_step;

    #[test]
    fn a_range_is_refused_with_the_reason_named() {
        assert_eq!(check_range(0.3, 500.0, 700.0, 2.0), Ok(()));
        assert_eq!(check_range(0.3, 700.0, 500.0, 2.0), Err(RangeError::Ends));
        assert_eq!(check_range(0.3, 0.0, 500.0, 2.0), Err(RangeError::Ends));
        assert_eq!(
            check_range(0.3, 500.0, f64::NAN, 2.0),
            Err(RangeError::Ends)
        );
        assert_eq!(check_range(0.3, 500.0, 700.0, 0.0), Err(RangeError::Step));
        assert_eq!(check_range(0.3, 500.0, 700.0, 300.0), Err(RangeError::Step));
        assert_eq!(
            check_range(0.3, 500.0, 700.0, 1e-300),
            Err(RangeError::Step)
        );
        assert_eq!(check_range(0.3, 500.0, 1e300, 2.0), Err(RangeError::Step));
        assert_eq!(check_range(0.0, 500.0, 700.0, 2.0), Err(RangeError::Accel));
        assert_eq!(
            check_range(f64::INFINITY, 500.0, 700.0, 2.0),
            Err(RangeError::Accel)
        );
    }

    /// The integrator counters of a report count every trial of a refinement exactly once:
    /// here the onset bisection is redone by hand, trial by trial, from the same states, and
    /// its summed counters must equal the report's `refine_stats` (the coarse steps are in
    /// `sweep.stats` only).
    #[test]
    fn refinement_stats_count_every_trial_exactly_once() {
        let device = Device::from_toml_str(
            include_str!("../../../data/prototype1.toml"),
            "data/prototype1.toml",
        )
        .unwrap()
        .with_bias(30.0);
        // The file's Hertz stops with b_im = 1.5 N s/m. Published prototype 1 at 5.5 g: first contact near 1197 Hz, contact kept up to
        // 1210 Hz and the power still rising, so the onset is the only refinement.
        let (accel, tol) = (5.5, 0.1);
        let freqs = linspace_step(1170.0, 1210.0, 10.0);
        let settings = SweepSettings {
            freqs_hz: freqs.clone(),
            extend_to_hz: f64::NEG_INFINITY,
            cfg: settle_settings(&device, 1220.0),
            refine_tol_hz: tol,
        };
        let r = settings.run(&device, accel, &Silent).unwrap();
        assert!(r.onset.is_some() && r.jump.is_none() && r.contact_lost.is_none());
        let k = first_contact(&r.sweep).unwrap();
        let base = crate::physics::harvester::Harvester::<4>::new(&device).unwrap();
        let (mut lo, mut hi) = (r.sweep.values[k - 1], r.sweep.values[k]);
        let before = &r.sweep.steps[k - 1];
        let (mut y, mut mode) = (
            nalgebra::SVector::<f64, 4>::from_column_slice(before.state.as_slice()),
            before.mode,
        );
        let (mut expected, mut trials) = (Stats::default(), 0);
        while hi - lo > tol {
            let mid = 0.5 * (lo + hi);
            let (m, y1, mode1, st) = steady_state(
                &base,
                Sine::from_rms_g(accel, mid),
                y,
                mode,
                accel,
                &settings.cfg,
            )
            .unwrap();
            expected += st;
            trials += 1;
            if in_contact(&m) {
                hi = mid;
            } else {
                (lo, y, mode) = (mid, y1, mode1);
            }
        }
        assert!(trials >= 2, "{trials} trials");
        assert_eq!(r.refine_stats, expected);
        let mut total = r.sweep.stats;
        total += expected;
        assert_eq!(r.total_stats(), total);
    }
}
