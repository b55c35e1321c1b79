//! The stepped-drive engine behind every sweep: a sequence of drive values (frequencies or
//! amplitudes), each measured in steady state starting from the final state of the previous
//! one ([`SteppedDrive::run`]), and the bisection of a transition between two steps
//! ([`SteppedDrive::refine_steps`]), each trial continuing from the state at the bracket's
//! lower end. A step is taken at once, or by a phase-continuous ramp of the drive
//! ([`Approach`], [`crate::study::chirp`]) that keeps the transient of the step from carrying
//! the state off its branch.
//!
//! # Where a ramp is not needed
//! A ramp matters only where the path can decide the branch. A device whose free flight is
//! linear (a piezoelectric, electromagnetic or no transducer on a linear spring) has, off the
//! stops, a single periodic orbit at each drive, which attracts every state: a step from a
//! steady state that touched no stop, taken at once, whose whole transient touches none either
//! (no mode switch from its start to its measurement), ends on the orbit the ramp would reach,
//! to the steady-state tolerance. Such a step is kept and the ramp skipped; a step whose
//! transient touches a stop is taken again from the same state by the ramp. Far from the
//! stops (most of a wide sweep) the sweep then costs what steps taken at once cost.
//!
//! # Where a model has a slow time constant
//! A model with a time constant far longer than its mechanics' ring-up
//! ([`Model::slow_time_constant_s`]: a storage capacitor charging through its load) settles
//! slowly whatever path the drive takes, which is why its steady state is found by shooting
//! ([`crate::study::steady`]). The path a slow enough ramp follows is the periodic orbit
//! continued from the previous step's, and Newton's method on the period map started from the
//! previous step's state (a steady state, at a whole period) finds that orbit in a few periods,
//! where the ramp integrates hundreds of cycles, each at its own frequency. The step is kept
//! when Newton's method converges to a stable orbit that touches the stops as the previous
//! step did, and is measured from it (no settling block: it starts on its orbit). Otherwise (a
//! branch that ends, an impact that begins or stops: where the path decides) the step is taken
//! again by the ramp from the same state, as for any other model. The counters of a kept step
//! are its blocks'; those of a step taken again include the blocks of the first try.

use nalgebra::{DVector, SVector};
use serde::{Deserialize, Serialize};

use crate::drive::Sine;
use crate::model::{Mode, Model};
use crate::ode::{SolverError, Stats};
use crate::progress::Progress;
use crate::study::periodic::{self, SteadyMethod, SteadySettings};
use crate::study::ramp::ramp;
use crate::study::steady::{settle_and_measure, steady_state, Measurement, SettleSettings};

/// One step of a continuation: the measurement and the state it ended in.
#[derive(Debug, Clone)]
pub struct SweepStep {
    /// The measurement.
    pub measurement: Measurement,
    /// Final state (at a whole period; the model's components).
    pub state: DVector<f64>,
    /// Final mode.
    pub mode: Mode,
    /// Integrator counters of this step.
    pub stats: Stats,
}

/// A continuation in one drive parameter (frequency or amplitude).
#[derive(Debug, Clone)]
pub struct Sweep {
    /// Parameter values (Hz or g), one per step.
    pub values: Vec<f64>,
    /// Steps in order.
    pub steps: Vec<SweepStep>,
    /// Integrator counters summed over the sweep.
    pub stats: Stats,
}

/// How a stepped sweep moves its drive from one value to the next.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Approach {
    /// At once: the new drive starts from the last state at drive phase zero (the drive's
    /// phase is continuous, its frequency jumps).
    Jump,
    /// By a phase-continuous ramp at this rate (parameter units, Hz or g, per second), over
    /// a whole number of cycles ([`crate::study::ramp::ramp`]).
    Ramp {
        /// The rate (per second).
        rate_per_s: f64,
    },
}

/// The drive of a continuation at parameter value p: (frequency Hz, RMS acceleration g).
pub trait Drive: Fn(f64) -> (f64, f64) + Sync {}

impl<T: Fn(f64) -> (f64, f64) + Sync> Drive for T {}

/// A continuation in one drive parameter (frequency or amplitude) of a device.
///
/// ```
/// use endstop::device::Device;
/// use endstop::progress::Silent;
/// use endstop::study::steady::settle_settings;
/// use endstop::study::stepped::SteppedDrive;
///
/// let text = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/examples/piezo_cantilever.toml"));
/// let device = Device::from_toml_str(text, "piezo_cantilever.toml")?;
/// // An up-sweep in frequency at 0.01 g rms towards the 120 Hz short-circuit resonance.
/// let sweep = endstop::with_harvester!(&device, |h| {
///     let up = SteppedDrive { base: &h, drive: |f: f64| (f, 0.01), cfg: settle_settings(&device, 110.0) };
///     up.run(&[100.0, 110.0, 118.0], &Silent)
/// })?;
/// let v1: Vec<f64> = sweep.steps.iter().map(|s| s.measurement.v1_rms_v).collect();
/// assert!(v1[0] < v1[1] && v1[1] < v1[2], "the response grows towards the resonance");
/// assert!(sweep.steps.iter().all(|s| s.measurement.converged && s.measurement.contact_fraction == 0.0));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub struct SteppedDrive<'a, M, D: Drive, const N: usize> {
    /// The device's model.
    pub base: &'a M,
    /// Drive at parameter value p: (frequency Hz, RMS acceleration g).
    pub drive: D,
    /// Steady-state settings.
    pub cfg: SettleSettings,
}

/// A state of dimension `N` from a step's.
fn state_of<const N: usize>(y: &DVector<f64>) -> SVector<f64, N> {
    SVector::<f64, N>::from_column_slice(y.as_slice())
}

impl<M: Model<N>, D: Drive, const N: usize> SteppedDrive<'_, M, D, N> {
    fn measure(&self, p: f64, y: SVector<f64, N>, mode: Mode) -> Result<SweepStep, SolverError> {
        let (f, a) = (self.drive)(p);
        let (m, y1, mode1, stats) =
            steady_state(self.base, Sine::from_rms_g(a, f), y, mode, a, &self.cfg)?;
        Ok(SweepStep {
            measurement: m,
            state: DVector::from_column_slice(y1.as_slice()),
            mode: mode1,
            stats,
        })
    }

    /// The step at `p` continued along the orbit of the steady state `y` (at a whole period)
    /// of a model with a slow time constant (see the module docs), when Newton's method finds
    /// a stable orbit there and its measurement touches the stops as the previous step's did
    /// (`contact`): `Ok(Ok(step))`. Otherwise `Ok(Err(counters))`, the counters of a
    /// measurement that was tried and not kept.
    fn continue_orbit(
        &self,
        p: f64,
        y: SVector<f64, N>,
        contact: bool,
    ) -> Result<Result<SweepStep, Stats>, SolverError> {
        let (f, a) = (self.drive)(p);
        let sine = Sine::from_rms_g(a, f);
        // Newton's method from the given state alone: no transient, no iterated map.
        let settings = SteadySettings {
            rtol: self.cfg.rtol,
            transient_periods: 0,
            max_map_periods: 0,
            ..SteadySettings::default()
        };
        let orbit = match periodic::steady_state(self.base, sine, &y, &settings) {
            Ok(o) if o.method == SteadyMethod::Newton && o.is_stable() && o.contact == contact => {
                periodic::state_of(&o)
            }
            _ => return Ok(Err(Stats::default())),
        };
        let cfg = SettleSettings {
            settle_blocks: 0,
            ..self.cfg.clone()
        };
        let (m, y1, mode1, stats) =
            settle_and_measure(self.base, sine, orbit, self.base.mode_of(&orbit), a, &cfg)?;
        if in_contact(&m) != contact {
            return Ok(Err(stats));
        }
        Ok(Ok(SweepStep {
            measurement: m,
            state: DVector::from_column_slice(y1.as_slice()),
            mode: mode1,
            stats,
        }))
    }

    /// The step at `p` reached from the state `y` in `mode` at the value `from` (`None`: at
    /// once, as from rest) by `approach`; the ramp's counters are the step's. `contact`: whether
    /// the steady state at `from` touched a stop (`None`: unknown), so that with a linear free
    /// flight or a slow time constant the ramp may be skipped (see the module docs); the
    /// counters of a step tried first and then taken again by the ramp include both.
    fn measure_after(
        &self,
        from: Option<f64>,
        contact: Option<bool>,
        p: f64,
        y: SVector<f64, N>,
        mode: Mode,
        approach: Approach,
    ) -> Result<SweepStep, SolverError> {
        match (approach, from) {
            (Approach::Ramp { rate_per_s }, Some(q)) if q != p => {
                let mut tried = Stats::default();
                let off_stops = contact == Some(false);
                if off_stops && !mode.in_contact() && self.base.free_flight_is_linear() {
                    let step = self.measure(p, y, mode)?;
                    if step.stats.events == 0 {
                        return Ok(step);
                    }
                    tried = step.stats;
                }
                if let (Some(c), Some(_)) = (contact, self.base.slow_time_constant_s()) {
                    match self.continue_orbit(p, y, c)? {
                        Ok(step) => return Ok(step),
                        Err(st) => tried += st,
                    }
                }
                let (y1, mode1, st) = ramp(
                    self.base,
                    (self.drive)(q),
                    (self.drive)(p),
                    (p - q).abs() / rate_per_s,
                    y,
                    mode,
                    self.cfg.rtol,
                )?;
                let mut step = self.measure(p, y1, mode1)?;
                step.stats += st;
                step.stats += tried;
                Ok(step)
            }
            _ => self.measure(p, y, mode),
        }
    }

    /// The steady state at `p` reached by `approach` from `step`, measured at the value
    /// `from`.
    pub fn step_to(
        &self,
        from: f64,
        p: f64,
        step: &SweepStep,
        approach: Approach,
    ) -> Result<SweepStep, SolverError> {
        self.measure_after(
            Some(from),
            Some(in_contact(&step.measurement)),
            p,
            state_of(&step.state),
            step.mode,
            approach,
        )
    }

    /// Runs the continuation over `values` (increasing for an up-sweep, decreasing for a
    /// down-sweep), starting from rest;
    /// `on_step.tick()` is called after each step.
    pub fn run(&self, values: &[f64], on_step: &dyn Progress) -> Result<Sweep, SolverError> {
        self.run_with(values, Approach::Jump, on_step)
    }

    /// As [`SteppedDrive::run`], each step reached by `approach`.
    pub fn run_with(
        &self,
        values: &[f64],
        approach: Approach,
        on_step: &dyn Progress,
    ) -> Result<Sweep, SolverError> {
        self.run_from(
            self.base.rest_state(),
            self.base.mode_of(&self.base.rest_state()),
            None,
            values,
            approach,
            on_step,
        )
    }

    /// As [`SteppedDrive::run_with`] from the state `y` in `mode` at the value `from`
    /// (`None`: the first step starts from `y` at once).
    pub fn run_from(
        &self,
        y: SVector<f64, N>,
        mode: Mode,
        from: Option<f64>,
        values: &[f64],
        approach: Approach,
        on_step: &dyn Progress,
    ) -> Result<Sweep, SolverError> {
        self.run_from_until(y, mode, from, values, approach, on_step, &mut |_| false)
    }

    /// As [`SteppedDrive::run_from`], stopping after the first step for which `stop(m)` is
    /// true: the sweep returned then holds the steps up to that one only (its `values` cut
    /// to match). The steps it holds are those of the whole run, bit for bit.
    #[allow(clippy::too_many_arguments)]
    pub fn run_from_until(
        &self,
        y: SVector<f64, N>,
        mode: Mode,
        from: Option<f64>,
        values: &[f64],
        approach: Approach,
        on_step: &dyn Progress,
        stop: &mut dyn FnMut(&Measurement) -> bool,
    ) -> Result<Sweep, SolverError> {
        let (mut y, mut mode, mut prev) = (y, mode, from);
        // Nothing is known of the state given: the first step off it keeps its ramp.
        let mut contact = None;
        let mut steps = Vec::with_capacity(values.len());
        let mut stats = Stats::default();
        for &p in values {
            let step = self.measure_after(prev, contact, p, y, mode, approach)?;
            prev = Some(p);
            contact = Some(in_contact(&step.measurement));
            stats += step.stats;
            y = state_of(&step.state);
            mode = step.mode;
            let stopped = stop(&step.measurement);
            steps.push(step);
            on_step.tick();
            if stopped {
                break;
            }
        }
        Ok(Sweep {
            values: values[..steps.len()].to_vec(),
            steps,
            stats,
        })
    }

    /// Bisects a transition between steps `k - 1` and `k` of `sweep` to a bracket narrower
    /// than `tol`. `still_before(m)` tells whether a measurement is still before the
    /// transition. Each trial continues from the state at the current lower end.
    pub fn refine<P: Fn(&Measurement) -> bool>(
        &self,
        sweep: &Sweep,
        k: usize,
        still_before: P,
        tol: f64,
    ) -> Result<Transition, SolverError> {
        self.refine_steps(sweep, k, still_before, tol)
            .map(|r| r.transition)
    }

    /// As [`SteppedDrive::refine`], and also returns the steps measured at the two ends of
    /// the final bracket (so that a caller can tell a discontinuity from a steep but
    /// continuous change).
    pub fn refine_steps<P: Fn(&Measurement) -> bool>(
        &self,
        sweep: &Sweep,
        k: usize,
        still_before: P,
        tol: f64,
    ) -> Result<RefinedTransition, SolverError> {
        self.refine_steps_with(sweep, k, still_before, tol, Approach::Jump)
    }

    /// As [`SteppedDrive::refine_steps`], each trial reached from the bracket's lower end by
    /// `approach`.
    pub fn refine_steps_with<P: Fn(&Measurement) -> bool>(
        &self,
        sweep: &Sweep,
        k: usize,
        still_before: P,
        tol: f64,
        approach: Approach,
    ) -> Result<RefinedTransition, SolverError> {
        assert!(
            k >= 1 && k < sweep.steps.len(),
            "transition index out of range"
        );
        let mut lo = sweep.values[k - 1];
        let mut hi = sweep.values[k];
        let mut before = sweep.steps[k - 1].clone();
        let mut after = sweep.steps[k].clone();
        let mut stats = Stats::default();
        // Either direction: `lo` is the value before the transition in the sweep's order
        // (larger than `hi` in a down-sweep).
        while (hi - lo).abs() > tol {
            let mid = 0.5 * (lo + hi);
            let step = self.measure_after(
                Some(lo),
                Some(in_contact(&before.measurement)),
                mid,
                state_of(&before.state),
                before.mode,
                approach,
            )?;
            stats += step.stats;
            if still_before(&step.measurement) {
                lo = mid;
                before = step;
            } else {
                hi = mid;
                after = step;
            }
        }
        Ok(RefinedTransition {
            transition: Transition {
                before: lo,
                after: hi,
            },
            before,
            after,
            stats,
        })
    }
}

/// A refined transition with the steps measured at its bracket ends.
#[derive(Debug, Clone)]
pub struct RefinedTransition {
    /// The bracket.
    pub transition: Transition,
    /// The step at `transition.before` (continued along the branch).
    pub before: SweepStep,
    /// The step at `transition.after`, continued from the state at the lower end of the
    /// bracket current when it was measured.
    pub after: SweepStep,
    /// Integrator counters of every trial of the bisection, each counted once (the two
    /// coarse steps that bound the initial bracket are not trials and are not included).
    pub stats: Stats,
}

/// A transition located between two parameter values.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Transition {
    /// Last value before the transition.
    pub before: f64,
    /// First value after it.
    pub after: f64,
}

impl Transition {
    /// Midpoint estimate.
    pub fn value(&self) -> f64 {
        0.5 * (self.before + self.after)
    }
    /// Half-width of the bracket (the estimate's uncertainty from bracketing alone; positive
    /// in either sweep direction).
    pub fn half_width(&self) -> f64 {
        0.5 * (self.after - self.before).abs()
    }
}

/// Is this measurement in contact with a stop (a non-zero contact fraction, or impacts: a
/// rigid stop's rebounds take no time)?
pub fn in_contact(m: &Measurement) -> bool {
    m.contact_fraction > 0.0 || m.impacts_per_period > 0.0
}

/// Index of the first step with contact, if any.
pub fn first_contact(sweep: &Sweep) -> Option<usize> {
    sweep.steps.iter().position(|s| in_contact(&s.measurement))
}

/// Evenly spaced values from `start` to `stop` inclusive with spacing close to `step`.
pub fn linspace_step(start: f64, stop: f64, step: f64) -> Vec<f64> {
    let n = ((stop - start) / step).round().max(1.0) as usize;
    (0..=n)
        .map(|i| start + (stop - start) * i as f64 / n as f64)
        .collect()
}

/// The grid `values` with the midpoint of every pair of neighbours inserted (half the step of
/// an evenly spaced grid, every original value kept).
pub fn with_midpoints(values: &[f64]) -> Vec<f64> {
    let mut out = Vec::with_capacity(2 * values.len());
    for w in values.windows(2) {
        out.push(w[0]);
        out.push(0.5 * (w[0] + w[1]));
    }
    out.extend(values.last());
    out
}

/// Appends steps to `sweep` at `values`, each continuing from the last state, at drive
/// `drive(p)` = (Hz, g rms); stops after the first step for which `stop(m)` is true.
pub fn continue_sweep<M: Model<N>, const N: usize>(
    base: &M,
    drive: impl Fn(f64) -> (f64, f64),
    cfg: &SettleSettings,
    sweep: &mut Sweep,
    values: impl IntoIterator<Item = f64>,
    stop: impl Fn(&Measurement) -> bool,
) -> Result<(), SolverError> {
    for p in values {
        let (mut y, mut mode) = (base.rest_state(), base.mode_of(&base.rest_state()));
        if let Some(last) = sweep.steps.last() {
            y = state_of(&last.state);
            mode = last.mode;
        }
        let (f, a) = drive(p);
        let (m, y1, mode1, st) = steady_state(base, Sine::from_rms_g(a, f), y, mode, a, cfg)?;
        sweep.stats += st;
        sweep.values.push(p);
        sweep.steps.push(SweepStep {
            measurement: m,
            state: DVector::from_column_slice(y1.as_slice()),
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
pub fn values_beyond(last: f64, step: f64, max: f64) -> impl Iterator<Item = f64> {
    (1..)
        .map(move |i| last + step * i as f64)
        .take_while(move |&v| v <= max + 1e-9 * max.abs())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn with_midpoints_inserts_one_value_between_neighbours_and_keeps_the_ends() {
        assert_eq!(with_midpoints(&[1.0, 2.0, 4.0]), [1.0, 1.5, 2.0, 3.0, 4.0]);
        assert_eq!(with_midpoints(&[5.0]), [5.0]);
        assert!(with_midpoints(&[]).is_empty());
    }
}
