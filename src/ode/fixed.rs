//! The fixed-step driver: an explicit Runge-Kutta method without error control (the classical
//! RK4, [`ClassicalRk4`], is the one the crate uses) stepping a [`HybridSystem`] with a fixed
//! number of equal steps between breakpoints, and switching modes at located guard crossings.
//!
//! The benchmark's yardstick for random records: a sampled input's breakpoints are its sample
//! instants, so the steps end on them and the input is smooth over each step. A step whose
//! end has a guard positive that was not positive at its start has crossed it: the crossing
//! is located by the crate's root finder ([`crate::num::roots::illinois`]) on steps of
//! shortened length from the same start (the method has no dense output), the mode switches
//! there, and the step is finished from the crossing. What this can miss: a guard that rises
//! above zero and falls back within one step (the adaptive driver's probes of the dense
//! output look for those).

use std::convert::Infallible;
use std::marker::PhantomData;

use crate::num::roots::{illinois, RootOptions, Sample};
use crate::ode::runge_kutta::stages;
use crate::ode::tableau::{ClassicalRk4, Method};
use crate::ode::{HybridSystem, SolverError, Stats, Vector, MAX_SWITCHES_AT_ONE_TIME};

/// The fixed-step integrator with the classical RK4.
pub type Rk4<Sys> = FixedStep<Sys, ClassicalRk4, 4>;

/// Largest number of guard evaluations spent locating one crossing.
const MAX_LOCATE_EVALS: usize = 60;

/// Relative part of the time tolerance of a located crossing (times the step's length).
const LOCATE_REL_TOL: f64 = 1e-12;

/// Integrator state of the method `M` (`K` stages) on a system `S`: time, state, mode, the
/// number of steps per interval between breakpoints, and counters.
#[derive(Debug)]
pub struct FixedStep<S: HybridSystem, M: Method<K>, const K: usize> {
    t: f64,
    y: S::State,
    mode: S::Mode,
    steps_per_interval: usize,
    root: RootOptions,
    stats: Stats,
    /// The guards' values at the start and the end of a step, and one evaluation while a
    /// crossing is located (kept between steps).
    buffers: [Vec<f64>; 3],
    method: PhantomData<M>,
}

impl<S: HybridSystem, M: Method<K>, const K: usize> FixedStep<S, M, K> {
    /// A new integrator at (t0, y0) in `mode` taking `steps_per_interval` equal steps between
    /// consecutive breakpoints (at least one) and locating crossings to `event_time_tol`
    /// seconds (plus 1e-12 of the step).
    pub fn new(
        t0: f64,
        y0: S::State,
        mode: S::Mode,
        steps_per_interval: usize,
        event_time_tol: f64,
    ) -> Self {
        Self {
            t: t0,
            y: y0,
            mode,
            steps_per_interval: steps_per_interval.max(1),
            root: RootOptions {
                f_tol: None,
                x_tol_abs: event_time_tol,
                x_tol_rel: LOCATE_REL_TOL,
                max_iter: MAX_LOCATE_EVALS,
            },
            stats: Stats::default(),
            buffers: Default::default(),
            method: PhantomData,
        }
    }

    /// Current time (s).
    pub fn t(&self) -> f64 {
        self.t
    }

    /// Current state.
    pub fn y(&self) -> S::State {
        self.y
    }

    /// Current mode.
    pub fn mode(&self) -> S::Mode {
        self.mode
    }

    /// Counters since [`FixedStep::new`] (every step counts as accepted; no step is rejected).
    pub fn stats(&self) -> Stats {
        self.stats
    }

    fn state_vec(&self) -> Vec<f64> {
        self.y.to_vec()
    }

    /// The state after a step of length `h` from the current point, whose derivative is `k1`.
    fn step(&mut self, sys: &S, k1: S::State, h: f64) -> S::State {
        self.stats.rhs_evals += (K - 1) as u64;
        stages::<S, M, K>(sys, self.mode, self.t, &self.y, k1, h).1
    }

    /// Integrates to `t_end`: each span between the current time, the breakpoints and `t_end`
    /// is cut into the integrator's number of equal steps.
    pub fn integrate(&mut self, sys: &S, t_end: f64) -> Result<(), SolverError> {
        while self.t < t_end {
            let start = self.t;
            let limit = t_end.min(sys.next_breakpoint(start));
            let n = self.steps_per_interval;
            let h = (limit - start) / n as f64;
            for j in 1..=n {
                let end = if j == n { limit } else { start + j as f64 * h };
                self.step_to(sys, end)?;
            }
        }
        Ok(())
    }

    /// One step to `end`, switching modes at every crossing on the way.
    fn step_to(&mut self, sys: &S, end: f64) -> Result<(), SolverError> {
        let mut switches = 0u32;
        while self.t < end {
            let [mut g0, g1, buf] = std::mem::take(&mut self.buffers);
            g0.resize(sys.guard_count(), f64::NEG_INFINITY);
            sys.guards(self.mode, self.t, &self.y, &mut g0);
            // A guard already positive at the start of a step fires at once.
            let found = match g0.iter().position(|&g| g > 0.0) {
                Some(i) => Ok(Some((0.0, self.y, i))),
                None => self.crossing(sys, end, &g0, g1, buf),
            };
            self.buffers[0] = g0;
            let crossing = found?;
            let Some((dt, y, i)) = crossing else {
                break;
            };
            if dt > 0.0 {
                self.stats.accepted += 1;
            }
            self.t += dt;
            self.y = y;
            switches += 1;
            if switches > MAX_SWITCHES_AT_ONE_TIME {
                return Err(SolverError::Chattering {
                    t: self.t,
                    switches,
                    modes: vec![format!("{:?}", self.mode)],
                    state: self.state_vec(),
                });
            }
            let mut y = self.y;
            self.mode = sys.switch(self.mode, i, self.t, &mut y);
            self.y = y;
            self.stats.events += 1;
        }
        if let Err(message) = sys.check_state(self.mode, self.t, &self.y) {
            return Err(SolverError::InvalidState {
                t: self.t,
                message,
                state: self.state_vec(),
            });
        }
        Ok(())
    }

    /// Steps from the current point to `end`. Returns the earliest guard crossing on the way
    /// as (time from the current point, state there, guard index), or None after moving to
    /// `end`.
    #[allow(clippy::type_complexity)]
    fn crossing(
        &mut self,
        sys: &S,
        end: f64,
        g0: &[f64],
        mut g1: Vec<f64>,
        mut buf: Vec<f64>,
    ) -> Result<Option<(f64, S::State, usize)>, SolverError> {
        let left = end - self.t;
        let k1 = sys.rhs(self.mode, self.t, &self.y);
        self.stats.rhs_evals += 1;
        let y1 = self.step(sys, k1, left);
        if !y1.is_finite() {
            self.buffers[1] = g1;
            self.buffers[2] = buf;
            return Err(SolverError::NonFinite {
                t: self.t,
                state: self.state_vec(),
            });
        }
        g1.resize(g0.len(), f64::NEG_INFINITY);
        buf.resize(g0.len(), f64::NEG_INFINITY);
        sys.guards(self.mode, end, &y1, &mut g1);
        let mut first: Option<(f64, S::State, usize)> = None;
        for i in (0..g0.len()).filter(|&i| g0[i] <= 0.0 && g1[i] > 0.0) {
            let (t0, y0, mode) = (self.t, self.y, self.mode);
            let evals = std::cell::Cell::new(0u64);
            let mut f = |s: f64| -> Result<(f64, S::State), Infallible> {
                evals.set(evals.get() + (K - 1) as u64);
                let ys = stages::<S, M, K>(sys, mode, t0, &y0, k1, s).1;
                sys.guards(mode, t0 + s, &ys, &mut buf);
                Ok((buf[i], ys))
            };
            let root = illinois(
                &mut f,
                Sample::new(0.0, g0[i], y0),
                Sample::new(left, g1[i], y1),
                &self.root,
            );
            self.stats.rhs_evals += evals.get();
            // The ends bracket by construction and the evaluation cannot fail.
            let hit = match root {
                Ok(r) => r.positive,
                Err(_) => Sample::new(left, g1[i], y1),
            };
            if first.as_ref().is_none_or(|(dt, _, _)| hit.x < *dt) {
                first = Some((hit.x, hit.payload, i));
            }
        }
        if first.is_none() {
            self.stats.accepted += 1;
            self.t = end;
            self.y = y1;
        }
        self.buffers[1] = g1;
        self.buffers[2] = buf;
        Ok(first)
    }
}
