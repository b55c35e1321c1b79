//! Down-sweeps ([`SweepSettings::run_down`], [`DownSweepReport`]) and the step's effect on
//! where a sweep leaves a branch: the end found again with the step divided
//! ([`SweepSettings::down_end_with_step_divided`], [`SweepSettings::up_end_with_step_divided`])
//! by a local rerun around it.

use super::{
    analyse_up_sweep, frequency_continuation, BranchEnd, Refine, SweepReport, SweepSettings,
    CANDIDATE_DROP, JUMP_MIN_DROP,
};
use nalgebra::{DVector, SVector};

use crate::device::Device;
use crate::model::{Mode, Model};
use crate::ode::{SolverError, Stats};
use crate::progress::{Progress, Silent};
use crate::study::steady::Measurement;
use crate::study::stepped::{
    first_contact, in_contact, Approach, Drive, SteppedDrive, Sweep, Transition,
};

/// A down-sweep: the stepped sine from high to low frequency, each step from the previous
/// final state, with its jump up and its first contact refined.
///
/// * **Jump up**: a candidate is a step whose total power exceeds the previous step's by more
///   than a factor 1 / (1 - [`CANDIDATE_DROP`]) beyond the lower branch's own climb (its
///   log-power's rate per Hz over the step before, where it rises, times the step; before the
///   second step, over one more step measured beyond the first); it is
///   refined by bisection (trials continue from the state at the bracket's high-frequency end,
///   "still before" meaning "total power below the geometric mean of the two coarse steps'"),
///   and confirmed when the power still rises by more than that factor beyond the climb
///   across the final bracket (a discontinuity keeps its full rise however narrow the
///   bracket; a steep flank of the lower branch resolved in small steps does not). On an end-stop harvester the lower (non-impacting)
///   branch ends where the orbit grazes a stop or at a fold, and the response jumps up onto
///   the impacting branch there.
/// * **Contact**: the first step in contact, refined with "still before" meaning "no contact".
#[derive(Debug, Clone)]
pub struct DownSweepReport {
    /// The coarse sweep, frequencies decreasing.
    pub sweep: Sweep,
    /// The confirmed jump up (`before` is the higher frequency).
    pub jump: Option<Transition>,
    /// Total power after / before across the refined jump bracket (above 1).
    pub jump_power_ratio: Option<f64>,
    /// First contact with a stop, refined (`None` if the sweep never touches one or is in
    /// contact from its first step).
    pub contact: Option<Transition>,
    /// Total power after / before across the refined contact bracket.
    pub contact_power_ratio: Option<f64>,
    /// Integrator counters of every refinement trial.
    pub refine_stats: Stats,
}

/// The rest state of `device`'s model and its mode: where a down-sweep starts.
fn rest_of(device: &Device) -> Result<(DVector<f64>, Mode), SolverError> {
    crate::with_harvester!(device, |h| {
        let r = h.rest_state();
        Ok::<_, SolverError>((DVector::from_column_slice(r.as_slice()), h.mode_of(&r)))
    })
}

/// How a down-sweep leaves the lower (non-impacting) branch.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DownEndKind {
    /// A confirmed jump up (a discontinuity of the power).
    Jump,
    /// The first contact without a confirmed jump: where the lower branch ends at a grazing
    /// point and the response moves onto the impacting branch with a power change below
    /// [`JUMP_MIN_DROP`] (at a grazing corner the two orbits nearly coincide).
    ContactOnset,
}

impl DownEndKind {
    /// Label for tables.
    pub fn label(self) -> &'static str {
        match self {
            DownEndKind::Jump => "jump",
            DownEndKind::ContactOnset => "contact onset, no jump in power",
        }
    }
}

impl DownSweepReport {
    /// Where the down-sweep leaves the lower branch: the jump if there is one, else the first
    /// contact (labelled, so that a caller never presents the latter as a jump).
    pub fn branch_end(&self) -> Option<(DownEndKind, Transition)> {
        self.jump
            .map(|t| (DownEndKind::Jump, t))
            .or(self.contact.map(|t| (DownEndKind::ContactOnset, t)))
    }

    /// The coarse measurements, in sweep order (frequency decreasing).
    pub fn measurements(&self) -> impl Iterator<Item = &Measurement> {
        self.sweep.steps.iter().map(|s| &s.measurement)
    }

    /// Integrator counters of the sweep and its refinements together.
    pub fn total_stats(&self) -> Stats {
        let mut s = self.sweep.stats;
        s += self.refine_stats;
        s
    }
}

impl SweepSettings {
    /// Runs the down-sweep of `device` at `accel_rms_g` over the same grid taken from its
    /// highest to its lowest frequency (no extension), and refines its jump up and first
    /// contact to brackets narrower than the refinement tolerance. `progress.tick()` is called
    /// after each coarse step.
    pub fn run_down(
        &self,
        device: &Device,
        accel_rms_g: f64,
        progress: &dyn Progress,
    ) -> Result<DownSweepReport, SolverError> {
        self.run_down_with(device, accel_rms_g, Approach::Jump, progress)
    }

    /// As [`SweepSettings::run_down`], each step and each refinement trial reached by
    /// `approach`.
    pub fn run_down_with(
        &self,
        device: &Device,
        accel_rms_g: f64,
        approach: Approach,
        progress: &dyn Progress,
    ) -> Result<DownSweepReport, SolverError> {
        self.run_down_from(device, accel_rms_g, approach, rest_of(device)?, progress)
    }

    /// As [`SweepSettings::run_down_with`] from the state `start` (and its mode) at drive
    /// phase zero, e.g. an orbit of the continuation at the grid's highest frequency, instead
    /// of rest.
    pub fn run_down_from(
        &self,
        device: &Device,
        accel_rms_g: f64,
        approach: Approach,
        start: (DVector<f64>, Mode),
        progress: &dyn Progress,
    ) -> Result<DownSweepReport, SolverError> {
        let report = self.run_down_from_until(
            device,
            accel_rms_g,
            approach,
            start,
            progress,
            Refine::ALL,
            &mut |_| false,
        )?;
        Ok(report.expect("a sweep that is never stopped completes"))
    }

    /// As [`SweepSettings::run_down`], given each coarse step as it is measured: `None` as
    /// soon as `stop(m)` is true for one (the rest of the sweep is not run), else the report,
    /// the same as [`SweepSettings::run_down`]'s bit for bit.
    pub fn run_down_until(
        &self,
        device: &Device,
        accel_rms_g: f64,
        stop: &mut dyn FnMut(&Measurement) -> bool,
    ) -> Result<Option<DownSweepReport>, SolverError> {
        self.run_down_until_refining(device, accel_rms_g, Refine::ALL, stop)
    }

    /// As [`SweepSettings::run_down_until`], refining only the transitions `refine` names (the
    /// coarse steps and those refined are the same bit for bit).
    pub fn run_down_until_refining(
        &self,
        device: &Device,
        accel_rms_g: f64,
        refine: Refine,
        stop: &mut dyn FnMut(&Measurement) -> bool,
    ) -> Result<Option<DownSweepReport>, SolverError> {
        let rest = rest_of(device)?;
        self.run_down_from_until(
            device,
            accel_rms_g,
            Approach::Jump,
            rest,
            &Silent,
            refine,
            stop,
        )
    }

    #[allow(clippy::too_many_arguments)]
    fn run_down_from_until(
        &self,
        device: &Device,
        accel_rms_g: f64,
        approach: Approach,
        start: (DVector<f64>, Mode),
        progress: &dyn Progress,
        refine: Refine,
        stop: &mut dyn FnMut(&Measurement) -> bool,
    ) -> Result<Option<DownSweepReport>, SolverError> {
        let mut freqs = self.freqs_hz.clone();
        freqs.sort_by(|a, b| b.total_cmp(a));
        crate::with_harvester!(device, |h| {
            let cont = frequency_continuation(&h, accel_rms_g, &self.cfg);
            let sweep = cont.run_from_until(
                SVector::from_column_slice(start.0.as_slice()),
                start.1,
                None,
                &freqs,
                approach,
                progress,
                stop,
            )?;
            if sweep.steps.len() < freqs.len() {
                return Ok(None);
            }
            analyse_down_sweep(&cont, sweep, self.refine_tol_hz, approach, refine).map(Some)
        })
    }

    /// The end of the lower branch of a down-sweep found again with the step divided by
    /// `divisor`: the sweep is rerun from its coarse state three steps above the end's bracket
    /// to two steps below it (the rest of the sweep is not rerun), and refined as before. How
    /// far the end moves is the step's effect on it. `None` when the report has no end.
    pub fn down_end_with_step_divided(
        &self,
        device: &Device,
        accel_rms_g: f64,
        approach: Approach,
        report: &DownSweepReport,
        divisor: f64,
    ) -> Result<Option<(DownEndKind, Transition)>, SolverError> {
        let Some((_, t)) = report.branch_end() else {
            return Ok(None);
        };
        let Some(local) =
            self.rerun_around(device, accel_rms_g, approach, &report.sweep, t, divisor)?
        else {
            return Ok(None);
        };
        crate::with_harvester!(device, |h| {
            let cont = frequency_continuation(&h, accel_rms_g, &self.cfg);
            let r = analyse_down_sweep(&cont, local, self.refine_tol_hz, approach, Refine::ALL)?;
            Ok(r.branch_end())
        })
    }

    /// The end of the upper branch of an up-sweep found again with the step divided by
    /// `divisor` (as [`SweepSettings::down_end_with_step_divided`]).
    pub fn up_end_with_step_divided(
        &self,
        device: &Device,
        accel_rms_g: f64,
        approach: Approach,
        report: &SweepReport,
        divisor: f64,
    ) -> Result<Option<BranchEnd>, SolverError> {
        let Some(end) = report.branch_end() else {
            return Ok(None);
        };
        let t = end.transition;
        let Some(local) =
            self.rerun_around(device, accel_rms_g, approach, &report.sweep, t, divisor)?
        else {
            return Ok(None);
        };
        crate::with_harvester!(device, |h| {
            let cont = frequency_continuation(&h, accel_rms_g, &self.cfg);
            let r = analyse_up_sweep(&cont, local, self.refine_tol_hz, approach, Refine::ALL)?;
            Ok(r.branch_end())
        })
    }

    /// The steps of `sweep` rerun around its transition `t` with the step divided by
    /// `divisor` ([`local_grid`]), from the coarse state where the rerun starts, after the
    /// coarse steps before it ([`with_history`]). `None` for a sweep of fewer than two steps.
    fn rerun_around(
        &self,
        device: &Device,
        accel_rms_g: f64,
        approach: Approach,
        sweep: &Sweep,
        t: Transition,
        divisor: f64,
    ) -> Result<Option<Sweep>, SolverError> {
        let Some((start, values)) = local_grid(&sweep.values, t, divisor) else {
            return Ok(None);
        };
        let s0 = &sweep.steps[start];
        let local = crate::with_harvester!(device, |h| {
            let cont = frequency_continuation(&h, accel_rms_g, &self.cfg);
            cont.run_from(
                SVector::from_column_slice(s0.state.as_slice()),
                s0.mode,
                Some(sweep.values[start]),
                &values,
                approach,
                &Silent,
            )
        })?;
        Ok(Some(with_history(sweep, start, local)))
    }
}

/// A local rerun after the coarse steps of `sweep` up to `start` (their last two and the one
/// it starts from, so that the analysis sees the branch's trend before the rerun), the
/// local steps' counters only.
fn with_history(sweep: &Sweep, start: usize, local: Sweep) -> Sweep {
    let first = start.saturating_sub(2);
    let mut values = sweep.values[first..=start].to_vec();
    let mut steps = sweep.steps[first..=start].to_vec();
    values.extend(local.values);
    steps.extend(local.steps);
    Sweep {
        values,
        steps,
        stats: local.stats,
    }
}

/// The grid of a local rerun around a transition `t` of a sweep over `values` (either
/// direction): the index of the coarse step three steps before the transition's bracket, and
/// the values after it to two steps past the bracket, in steps of the coarse step over
/// `divisor`. `None` for a sweep of fewer than two steps.
fn local_grid(values: &[f64], t: Transition, divisor: f64) -> Option<(usize, Vec<f64>)> {
    if values.len() < 2 {
        return None;
    }
    let step = values[1] - values[0];
    let dir = step.signum();
    // The last coarse value before the transition (in the sweep's direction).
    let k = values
        .iter()
        .rposition(|&v| (v - t.before) * dir <= 1e-9 * v.abs())
        .unwrap_or(0);
    let start = k.saturating_sub(3);
    let end = (values[k] + 3.0 * step).clamp(
        values[0].min(values[values.len() - 1]),
        values[0].max(values[values.len() - 1]),
    );
    let fine = step / divisor;
    let n = ((end - values[start]) / fine).round().max(1.0) as usize;
    let grid = (1..=n).map(|i| values[start] + fine * i as f64).collect();
    Some((start, grid))
}

fn analyse_down_sweep<M: Model<N>, D: Drive, const N: usize>(
    cont: &SteppedDrive<'_, M, D, N>,
    sweep: Sweep,
    tol: f64,
    approach: Approach,
    refine: Refine,
) -> Result<DownSweepReport, SolverError> {
    let mut refine_stats = Stats::default();
    let steps = &sweep.steps;
    let rise = 1.0 / (1.0 - CANDIDATE_DROP);
    let confirm = 1.0 / (1.0 - JUMP_MIN_DROP);
    let mut jump = None;
    let mut jump_power_ratio = None;
    let candidates = if refine.branch_end {
        1..steps.len()
    } else {
        0..0
    };
    for k in candidates {
        let a = &steps[k - 1].measurement;
        let b = &steps[k].measurement;
        // The lower branch's own climb towards resonance (the log-power's rate per Hz over the
        // step before, where it rises) is not a jump: a step or bracket is judged by its rise
        // beyond that climb, so that a steep flank resolved in small steps (a rise of more
        // than 5 % per bracket) is not taken for a jump, while a jump keeps its full rise.
        let ratio_ab = b.p_total_w() / a.p_total_w();
        if ratio_ab <= rise {
            continue;
        }
        let rate = |p: &Measurement| {
            let df = (a.freq_hz - p.freq_hz).abs().max(1e-300);
            ((a.p_total_w() / p.p_total_w()).ln() / df).max(0.0)
        };
        let climb = if k >= 2 {
            rate(&steps[k - 2].measurement)
        } else {
            // The first step has none before it: one more steady state, a step further out.
            let f_out = 2.0 * a.freq_hz - b.freq_hz;
            let out = cont.step_to(a.freq_hz, f_out, &steps[k - 1], approach)?;
            refine_stats += out.stats;
            rate(&out.measurement)
        };
        let beyond = |ratio: f64, df: f64| ratio.ln() - climb * df.abs();
        if beyond(ratio_ab, b.freq_hz - a.freq_hz) <= rise.ln() {
            continue;
        }
        let threshold = (a.p_total_w() * b.p_total_w()).sqrt();
        let r = cont.refine_steps_with(&sweep, k, |m| m.p_total_w() < threshold, tol, approach)?;
        refine_stats += r.stats;
        let ratio = r.after.measurement.p_total_w() / r.before.measurement.p_total_w();
        let width = r.transition.after - r.transition.before;
        if beyond(ratio, width) > confirm.ln() {
            jump = Some(r.transition);
            jump_power_ratio = Some(ratio);
            break;
        }
    }
    let (contact, contact_power_ratio) = match first_contact(&sweep) {
        Some(k) if k > 0 && refine.contact(jump.is_some()) => {
            let r = cont.refine_steps_with(&sweep, k, |m| !in_contact(m), tol, approach)?;
            refine_stats += r.stats;
            let ratio = r.after.measurement.p_total_w() / r.before.measurement.p_total_w();
            (Some(r.transition), Some(ratio))
        }
        _ => (None, None),
    };
    Ok(DownSweepReport {
        sweep,
        jump,
        jump_power_ratio,
        contact,
        contact_power_ratio,
        refine_stats,
    })
}
