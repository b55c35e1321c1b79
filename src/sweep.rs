//! Stepped-sine sweeps with continuation, steady-state measurement, and the detection and
//! refinement of impact onsets and jumps (SPEC 5; Figures 8, 9 and 13).
//!
//! # Steady state
//! At each step of a sweep the drive is restarted at phase zero from the final state of the
//! previous step (every measurement ends on a whole number of periods, so the drive phase is
//! continuous). The model is integrated for `settle_blocks` blocks of `block_periods` periods,
//! then measured block by block; the step has converged when the RMS voltages of two successive
//! blocks differ by less than `rel_change_tol` (relative). The block length is chosen of the
//! order of the mechanical ring-up time 2m/b, so the remaining transient is then of the order
//! of the tolerance. The last block is the measurement.
//!
//! # Transitions
//! [`Continuation::refine`] bisects between the last step before a transition (onset of
//! impacts, loss of the upper branch) and the first step after it, each trial continuing from
//! the state of the bracket's lower end, until the bracket is narrower than a tolerance.

use crate::excitation::Sine;
use crate::integrator::{Dopri5, SolverError, Stats};
use crate::model::{Harvester, Mode, State};

/// Steady-state measurement settings.
#[derive(Debug, Clone, PartialEq)]
pub struct SteadyConfig {
    /// Integrator relative tolerance.
    pub rtol: f64,
    /// Periods per block.
    pub block_periods: usize,
    /// Blocks simulated before the first measured block.
    pub settle_blocks: usize,
    /// Convergence: relative change of RMS voltages between successive blocks.
    pub rel_change_tol: f64,
    /// Maximum measured blocks per step (the step is flagged unconverged beyond).
    pub max_blocks: usize,
}

impl SteadyConfig {
    /// Settings for a device: blocks of about the ring-up time 2m/b at `freq_hz`, at least
    /// `min_periods`.
    pub fn for_ring_time(ring_time_s: f64, freq_hz: f64, min_periods: usize) -> Self {
        let periods = (ring_time_s * freq_hz).ceil() as usize;
        Self {
            rtol: 1e-8,
            block_periods: periods.max(min_periods),
            settle_blocks: 1,
            rel_change_tol: 1e-3,
            max_blocks: 60,
        }
    }
}

/// Steady-state response at one drive.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Measurement {
    /// Drive frequency (Hz).
    pub freq_hz: f64,
    /// Drive RMS acceleration (g).
    pub accel_rms_g: f64,
    /// RMS voltage of load 1 (V).
    pub v1_rms_v: f64,
    /// RMS voltage of load 2 (V).
    pub v2_rms_v: f64,
    /// RMS of the differential voltage V2 - V1 (V).
    pub vdiff_rms_v: f64,
    /// Mean power in load 1 (W).
    pub p1_w: f64,
    /// Mean power in load 2 (W).
    pub p2_w: f64,
    /// Largest |x| (m).
    pub x_peak_m: f64,
    /// Fraction of time past a stop.
    pub contact_fraction: f64,
    /// Impacts (contact entries) per period.
    pub impacts_per_period: f64,
    /// Measured blocks needed.
    pub blocks: usize,
    /// Relative change between the last two blocks.
    pub last_rel_change: f64,
    /// True when the convergence criterion was met.
    pub converged: bool,
}

impl Measurement {
    /// Power of both loads (W).
    pub fn p_total_w(&self) -> f64 {
        self.p1_w + self.p2_w
    }
}

/// Accumulates whole-period averages over accepted steps.
#[derive(Debug, Clone, Copy, Default)]
struct Block {
    v1sq: f64,
    v2sq: f64,
    vdsq: f64,
    x_peak: f64,
    contact_time: f64,
    impacts: u64,
    prev_mode_free: bool,
}

/// Integrates `model` from (y, mode) at phase zero to steady state and measures it.
/// Returns the measurement, the final state and mode (at a whole period), and the counters.
pub fn steady_state(
    model: &Harvester<Sine>,
    y: State,
    mode: Mode,
    accel_rms_g: f64,
    cfg: &SteadyConfig,
) -> Result<(Measurement, State, Mode, Stats), SolverError> {
    let period = model.excitation.period_s();
    let block_t = cfg.block_periods as f64 * period;
    let mut ode = Dopri5::new(0.0, y, mode, model.solver_options(cfg.rtol));
    let mut t_end = 0.0;
    for _ in 0..cfg.settle_blocks {
        t_end += block_t;
        ode.integrate(model, t_end, |_, _| {})?;
    }
    let mut prev: Option<(f64, f64)> = None;
    let mut blocks = 0;
    let mut last_change = f64::INFINITY;
    loop {
        let t_start = t_end;
        t_end += block_t;
        let mut b = Block {
            prev_mode_free: ode.mode == Mode::Free,
            ..Block::default()
        };
        ode.integrate(model, t_end, |st, m| {
            let el = |y: &State| model.electrical(y).v;
            b.v1sq += st.integrate(|y| el(y)[0].powi(2));
            b.v2sq += st.integrate(|y| el(y)[1].powi(2));
            b.vdsq += st.integrate(|y| {
                let v = el(y);
                (v[1] - v[0]).powi(2)
            });
            let xm = st.at_theta(0.5)[0].abs();
            b.x_peak = b.x_peak.max(st.y1[0].abs()).max(xm);
            if m.in_contact() {
                b.contact_time += st.h;
                if b.prev_mode_free {
                    b.impacts += 1;
                }
            }
            b.prev_mode_free = !m.in_contact();
        })?;
        blocks += 1;
        let dur = t_end - t_start;
        let v1 = (b.v1sq / dur).sqrt();
        let v2 = (b.v2sq / dur).sqrt();
        let converged = if let Some((p1, p2)) = prev {
            let rel = |a: f64, b: f64| (a - b).abs() / a.abs().max(b.abs()).max(1e-300);
            last_change = rel(v1, p1).max(rel(v2, p2));
            last_change < cfg.rel_change_tol
        } else {
            false
        };
        prev = Some((v1, v2));
        if converged || blocks >= cfg.max_blocks {
            let m = Measurement {
                freq_hz: model.excitation.freq_hz,
                accel_rms_g,
                v1_rms_v: v1,
                v2_rms_v: v2,
                vdiff_rms_v: (b.vdsq / dur).sqrt(),
                p1_w: b.v1sq / dur / model.rl,
                p2_w: b.v2sq / dur / model.rl,
                x_peak_m: b.x_peak,
                contact_fraction: b.contact_time / dur,
                impacts_per_period: b.impacts as f64 / cfg.block_periods as f64,
                blocks,
                last_rel_change: last_change,
                converged,
            };
            return Ok((m, ode.y, ode.mode, ode.stats));
        }
    }
}

/// One step of a continuation: the measurement and the state it ended in.
#[derive(Debug, Clone)]
pub struct SweepStep {
    /// The measurement.
    pub measurement: Measurement,
    /// Final state (at a whole period).
    pub state: State,
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

/// The drive of a continuation at parameter value p: (frequency Hz, RMS acceleration g).
pub trait Drive: Fn(f64) -> (f64, f64) + Sync {}
impl<T: Fn(f64) -> (f64, f64) + Sync> Drive for T {}

/// A continuation in one drive parameter (frequency or amplitude) of a device.
pub struct Continuation<'a, D: Drive> {
    /// The device model (its excitation is replaced at every step).
    pub base: &'a Harvester<Sine>,
    /// Drive at parameter value p: (frequency Hz, RMS acceleration g).
    pub drive: D,
    /// Steady-state settings.
    pub cfg: SteadyConfig,
}

impl<D: Drive> Continuation<'_, D> {
    fn measure(&self, p: f64, y: State, mode: Mode) -> Result<SweepStep, SolverError> {
        let (f, a) = (self.drive)(p);
        let model = self.base.with_excitation(Sine::from_rms_g(a, f));
        let (m, y1, mode1, stats) = steady_state(&model, y, mode, a, &self.cfg)?;
        Ok(SweepStep {
            measurement: m,
            state: y1,
            mode: mode1,
            stats,
        })
    }

    /// Runs the continuation over `values` (increasing for an up-sweep), starting from rest;
    /// `on_step(i)` is called after each step.
    pub fn run(
        &self,
        values: &[f64],
        mut on_step: impl FnMut(usize),
    ) -> Result<Sweep, SolverError> {
        let mut y = self.base.rest_state();
        let mut mode = Mode::Free;
        let mut steps = Vec::with_capacity(values.len());
        let mut stats = Stats::default();
        for (i, &p) in values.iter().enumerate() {
            let step = self.measure(p, y, mode)?;
            add_stats(&mut stats, &step.stats);
            y = step.state;
            mode = step.mode;
            steps.push(step);
            on_step(i);
        }
        Ok(Sweep {
            values: values.to_vec(),
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

    /// As [`Continuation::refine`], and also returns the steps measured at the two ends of
    /// the final bracket (so that a caller can tell a discontinuity from a steep but
    /// continuous change).
    pub fn refine_steps<P: Fn(&Measurement) -> bool>(
        &self,
        sweep: &Sweep,
        k: usize,
        still_before: P,
        tol: f64,
    ) -> Result<RefinedTransition, SolverError> {
        assert!(
            k >= 1 && k < sweep.steps.len(),
            "transition index out of range"
        );
        let mut lo = sweep.values[k - 1];
        let mut hi = sweep.values[k];
        let mut before = sweep.steps[k - 1].clone();
        let mut after = sweep.steps[k].clone();
        while hi - lo > tol {
            let mid = 0.5 * (lo + hi);
            let step = self.measure(mid, before.state, before.mode)?;
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
}

fn add_stats(acc: &mut Stats, s: &Stats) {
    acc.accepted += s.accepted;
    acc.rejected += s.rejected;
    acc.rhs_evals += s.rhs_evals;
    acc.events += s.events;
}

/// A transition located between two parameter values.
#[derive(Debug, Clone, Copy, PartialEq)]
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
    /// Half-width of the bracket (the estimate's uncertainty from bracketing alone).
    pub fn half_width(&self) -> f64 {
        0.5 * (self.after - self.before)
    }
}

/// Index of the first step with contact, if any.
pub fn first_contact(sweep: &Sweep) -> Option<usize> {
    sweep
        .steps
        .iter()
        .position(|s| s.measurement.contact_fraction > 0.0)
}

/// Evenly spaced values from `start` to `stop` inclusive with spacing close to `step`.
pub fn linspace_step(start: f64, stop: f64, step: f64) -> Vec<f64> {
    let n = ((stop - start) / step).round().max(1.0) as usize;
    (0..=n)
        .map(|i| start + (stop - start) * i as f64 / n as f64)
        .collect()
}
