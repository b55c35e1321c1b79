//! The adaptive driver: an embedded Runge-Kutta pair with dense output ([`Dormand-Prince
//! 5(4)`](DormandPrince54) is the one the crate uses, [`Dopri5`]) stepping a [`HybridSystem`]
//! under error control and locating guard crossings on the dense output (see
//! [`crate::ode`]).

use std::marker::PhantomData;

use crate::ode::events;
use crate::ode::runge_kutta::{dense_output, error_estimate, stages};
use crate::ode::tableau::{DormandPrince54, Method};
use crate::ode::{
    HybridSystem, Observer, Options, SolverError, Stats, Step, Steps, Vector,
    MAX_SWITCHES_AT_ONE_TIME,
};

/// Safety factor of the step-size rule.
const SAFETY: f64 = 0.9;

/// The step-size rule's exponent for a pair whose lower order is `q`: `-1/(q + 1)`.
const fn step_exponent(q: u32) -> f64 {
    -1.0 / (q + 1) as f64
}

/// The error norm at or below which the step-size factor `SAFETY err^(-1/(q + 1))` is at least
/// 1: `SAFETY^(q + 1)`, rounded down to two decimals so that rounding in the power cannot
/// bring the factor below 1 (0.59 for Dormand-Prince, q = 4).
const fn max_err_keeping_step(q: u32) -> f64 {
    let mut p = 1.0;
    let mut i = 0;
    while i <= q {
        p *= SAFETY;
        i += 1;
    }
    ((p * 100.0) as u64) as f64 / 100.0
}

/// The adaptive integrator with the Dormand-Prince 5(4) pair, the crate's integrator for
/// hybrid systems.
pub type Dopri5<Sys> = Adaptive<Sys, DormandPrince54, 7>;

/// Integrator state of the embedded pair `M` (`K` stages) on a system `S`: time, state, mode,
/// the derivative at the current point, proposed step and counters.
///
/// The fields are private because the derivative at the current point (`k1`, the last stage of
/// the previous step for a first-same-as-last pair) is cached: read them with
/// [`Adaptive::t`], [`Adaptive::y`], [`Adaptive::mode`], [`Adaptive::stats`] and
/// [`Adaptive::options`], and move the integrator to another state with [`Adaptive::restart`],
/// which drops the cache.
#[derive(Debug)]
pub struct Adaptive<S: HybridSystem, M: Method<K>, const K: usize> {
    t: f64,
    y: S::State,
    mode: S::Mode,
    opts: Options<S::State>,
    stats: Stats,
    k1: S::State,
    h: f64,
    k1_valid: bool,
    /// The modes visited since time last advanced (empty when no switch happened since).
    switch_trail: Vec<S::Mode>,
    /// No step has been accepted since the last mode switch.
    after_event: bool,
    /// Per mode, the first full step accepted after the last switch into it: the step
    /// proposed after the next switch into that mode (see [`Adaptive::switch`]).
    entry_steps: Vec<(S::Mode, f64)>,
    /// The guards' values at the probes of a step (see `events.rs`), kept between steps.
    scratch: events::Scratch,
    method: PhantomData<M>,
}

// By hand: a derived `Clone` would ask `M: Clone` of the method's marker type.
impl<S: HybridSystem, M: Method<K>, const K: usize> Clone for Adaptive<S, M, K> {
    fn clone(&self) -> Self {
        Self {
            t: self.t,
            y: self.y,
            mode: self.mode,
            opts: self.opts.clone(),
            stats: self.stats,
            k1: self.k1,
            h: self.h,
            k1_valid: self.k1_valid,
            switch_trail: self.switch_trail.clone(),
            after_event: self.after_event,
            entry_steps: self.entry_steps.clone(),
            scratch: self.scratch.clone(),
            method: PhantomData,
        }
    }
}

struct Trial<V, const K: usize> {
    y1: V,
    k: [V; K],
    err: f64,
}

impl<S: HybridSystem, M: Method<K>, const K: usize> Adaptive<S, M, K> {
    /// A new integrator at (t0, y0) in `mode`.
    pub fn new(t0: f64, y0: S::State, mode: S::Mode, opts: Options<S::State>) -> Self {
        let h = opts.h_init;
        Self {
            t: t0,
            y: y0,
            mode,
            opts,
            stats: Stats::default(),
            k1: S::State::zeros(),
            h,
            k1_valid: false,
            switch_trail: Vec::new(),
            after_event: false,
            entry_steps: Vec::new(),
            scratch: events::Scratch::default(),
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

    /// Counters since [`Adaptive::new`].
    pub fn stats(&self) -> Stats {
        self.stats
    }

    /// Options.
    pub fn options(&self) -> &Options<S::State> {
        &self.opts
    }

    /// Continues from a new point (t, y, mode), keeping the options and the counters: the
    /// cached derivative is dropped and the next trial step is [`Options::h_init`].
    pub fn restart(&mut self, t: f64, y: S::State, mode: S::Mode) {
        self.t = t;
        self.y = y;
        self.mode = mode;
        self.h = self.opts.h_init;
        self.k1_valid = false;
        self.after_event = false;
        self.switch_trail.clear();
    }

    /// [`Adaptive::restart`] with the next trial step `h` instead of [`Options::h_init`] (for a
    /// caller that knows the scale of the motion, e.g. the sample interval of a sampled
    /// input in free flight).
    pub fn restart_with_step(&mut self, t: f64, y: S::State, mode: S::Mode, h: f64) {
        self.restart(t, y, mode);
        self.h = h;
    }

    fn state_vec(&self) -> Vec<f64> {
        self.y.to_vec()
    }

    fn trial(&mut self, sys: &S, h: f64) -> Trial<S::State, K> {
        let (k, y1) = stages::<S, M, K>(sys, self.mode, self.t, &self.y, self.k1, h);
        self.stats.rhs_evals += (K - 1) as u64;
        let e = error_estimate::<M, S::State, K>(&k, h);
        let (y, y1c, e, atol) = (
            self.y.components(),
            y1.components(),
            e.components(),
            self.opts.atol.components(),
        );
        let n = y.len();
        let mut acc = 0.0;
        for i in 0..n {
            let sc = atol[i] + self.opts.rtol * y[i].abs().max(y1c[i].abs());
            let r = e[i] / sc;
            acc += r * r;
        }
        let err = (acc / n as f64).sqrt();
        Trial { y1, k, err }
    }

    fn make_step(&self, h: f64, tr: &Trial<S::State, K>) -> Step<S::State> {
        Step {
            t0: self.t,
            h,
            y0: self.y,
            y1: tr.y1,
            rcont: dense_output::<M, S::State, K>(&self.y, &tr.y1, &tr.k, h),
        }
    }

    /// Switches the mode through guard `index` at the current time and state (the state may
    /// be projected by the system); errs when switches keep firing without time advancing.
    ///
    /// The next trial step is the current one capped by the first full step accepted after
    /// the previous switch into the new mode: a mode's own dynamics set its step (the end-stop
    /// contact rings ~100 times faster than the free motion, so the step from before the
    /// impact would be rejected several times). Hairer's starting-step heuristic evaluated
    /// at the switch does not serve here: at a contact entry the penetration, hence the contact
    /// force, is zero, so a derivative estimate at that point cannot see the stiffness that
    /// builds up within the step.
    fn switch<O: Observer<S::State, S::Mode>>(
        &mut self,
        sys: &S,
        index: usize,
        observer: &mut O,
    ) -> Result<(), SolverError> {
        if self.switch_trail.is_empty() {
            self.switch_trail.push(self.mode);
        }
        let mut y = self.y;
        let from = self.mode;
        self.mode = sys.switch(self.mode, index, self.t, &mut y);
        observer.switched(self.t, from, self.mode);
        self.y = y;
        self.stats.events += 1;
        self.k1_valid = false;
        self.after_event = true;
        if let Some(&(_, h)) = self.entry_steps.iter().find(|(m, _)| *m == self.mode) {
            self.h = self.h.min(h);
        }
        self.switch_trail.push(self.mode);
        let switches = (self.switch_trail.len() - 1) as u32;
        if switches > MAX_SWITCHES_AT_ONE_TIME {
            return Err(SolverError::Chattering {
                t: self.t,
                switches,
                modes: self.switch_trail.iter().map(|m| format!("{m:?}")).collect(),
                state: self.state_vec(),
            });
        }
        Ok(())
    }

    /// Records `h` as the first full step of the current mode after a switch into it.
    fn remember_entry_step(&mut self, h: f64) {
        /// Modes remembered (a hybrid system has few).
        const MAX_MODES: usize = 16;
        if let Some(e) = self.entry_steps.iter_mut().find(|(m, _)| *m == self.mode) {
            e.1 = h;
        } else if self.entry_steps.len() < MAX_MODES {
            self.entry_steps.push((self.mode, h));
        }
    }

    /// Moves to the end of an accepted step of positive length.
    fn advance(&mut self, t: f64, y: S::State) {
        self.t = t;
        self.y = y;
        self.switch_trail.clear();
    }

    /// Integrates to `t_end`, calling `observer` with every accepted step (and with the mode
    /// that was active over it).
    pub fn integrate<O: FnMut(&Step<S::State>, S::Mode)>(
        &mut self,
        sys: &S,
        t_end: f64,
        observer: O,
    ) -> Result<(), SolverError> {
        self.integrate_observed(sys, t_end, &mut Steps(observer))
    }

    /// Integrates to `t_end`, showing `observer` every accepted step and every mode switch.
    pub fn integrate_observed<O: Observer<S::State, S::Mode>>(
        &mut self,
        sys: &S,
        t_end: f64,
        observer: &mut O,
    ) -> Result<(), SolverError> {
        self.integrate_until(sys, t_end, observer, |_| false)
            .map(|_| ())
    }

    /// As [`Adaptive::integrate_observed`], but returns at the first switch into a mode for
    /// which `stop` holds (at the switch's time, in the new mode), with `true`; `false` when
    /// `t_end` is reached first. A caller that integrates some modes otherwise (exactly, see
    /// [`crate::study::flow`]) hands this integrator the others.
    pub fn integrate_until<O: Observer<S::State, S::Mode>>(
        &mut self,
        sys: &S,
        t_end: f64,
        observer: &mut O,
        stop: impl Fn(S::Mode) -> bool,
    ) -> Result<bool, SolverError> {
        let mut steps: u64 = 0;
        while self.t < t_end {
            if !self.k1_valid {
                self.k1 = sys.rhs(self.mode, self.t, &self.y);
                self.stats.rhs_evals += 1;
                self.k1_valid = true;
                if !self.k1.is_finite() {
                    return Err(SolverError::NonFinite {
                        t: self.t,
                        state: self.state_vec(),
                    });
                }
                // A guard already positive at the start of a step fires at once.
                let g = self.scratch.guards(sys.guard_count());
                sys.guards(self.mode, self.t, &self.y, g);
                if let Some(i) = g.iter().position(|&gi| gi > 0.0) {
                    self.switch(sys, i, observer)?;
                    if stop(self.mode) {
                        return Ok(true);
                    }
                    continue;
                }
            }
            steps += 1;
            if steps > self.opts.max_steps {
                return Err(SolverError::TooManySteps {
                    max_steps: self.opts.max_steps,
                    t: self.t,
                    t_end,
                });
            }
            let limit = t_end.min(sys.next_breakpoint(self.t));
            let mut h = self.h.min(self.opts.h_max);
            let mut clipped = false;
            if self.t + h >= limit {
                h = limit - self.t;
                clipped = true;
            }
            // A step below the resolution of time cannot advance it (a step clipped to a
            // breakpoint ends exactly on it, however short).
            let h_floor = self.opts.min_step(self.t);
            if !clipped && h < h_floor {
                return Err(SolverError::StepSizeTooSmall {
                    t: self.t,
                    h,
                    state: self.state_vec(),
                });
            }
            let tr = self.trial(sys, h);
            if !tr.err.is_finite() || !tr.y1.is_finite() {
                self.stats.rejected += 1;
                if self.after_event {
                    self.stats.rejected_after_event += 1;
                }
                self.h = h * 0.2;
                if self.h < h_floor {
                    return Err(SolverError::NonFinite {
                        t: self.t,
                        state: self.state_vec(),
                    });
                }
                continue;
            }
            // The step-size factor. A step clipped to a breakpoint keeps its proposal unless
            // the factor is below 1: skip the power where it cannot matter (most steps of a
            // sampled input end on a breakpoint).
            let (exponent, keep) = const {
                let q = M::TABLEAU.error_order;
                (step_exponent(q), max_err_keeping_step(q))
            };
            let fac = if clipped && tr.err <= keep {
                1.0
            } else {
                (SAFETY * tr.err.powf(exponent)).clamp(0.2, 10.0)
            };
            if tr.err > 1.0 {
                self.stats.rejected += 1;
                if self.after_event {
                    self.stats.rejected_after_event += 1;
                }
                self.h = h * fac.min(1.0);
                if self.h < h_floor {
                    return Err(SolverError::StepSizeTooSmall {
                        t: self.t,
                        h: self.h,
                        state: self.state_vec(),
                    });
                }
                continue;
            }
            // Accepted: look for guard crossings on the dense output.
            let first_after_event = std::mem::replace(&mut self.after_event, false);
            let step = self.make_step(h, &tr);
            let t_new = if clipped { limit } else { self.t + h };
            match events::locate(
                sys,
                self.mode,
                &step,
                self.opts.event_time_tol,
                &mut self.scratch,
            ) {
                None => {
                    self.stats.accepted += 1;
                    observer.step(&step, self.mode);
                    self.advance(t_new, tr.y1);
                    if const { M::TABLEAU.is_fsal() } {
                        self.k1 = tr.k[K - 1];
                    } else {
                        self.k1_valid = false;
                    }
                    if first_after_event && !clipped {
                        self.remember_entry_step(h);
                    }
                    if !clipped || fac < 1.0 {
                        self.h = h * fac;
                    }
                }
                Some((theta, index)) => {
                    // Re-take the step so that it ends exactly on the event.
                    let h_ev = theta * h;
                    if h_ev > 0.0 {
                        let tr_ev = self.trial(sys, h_ev);
                        if !tr_ev.err.is_finite() || !tr_ev.y1.is_finite() {
                            return Err(SolverError::NonFinite {
                                t: self.t,
                                state: self.state_vec(),
                            });
                        }
                        let st = self.make_step(h_ev, &tr_ev);
                        self.stats.accepted += 1;
                        observer.step(&st, self.mode);
                        self.advance(self.t + h_ev, tr_ev.y1);
                    }
                    self.h = h;
                    self.switch(sys, index, observer)?;
                }
            }
            if let Err(message) = sys.check_state(self.mode, self.t, &self.y) {
                return Err(SolverError::InvalidState {
                    t: self.t,
                    message,
                    state: self.state_vec(),
                });
            }
            if !self.switch_trail.is_empty() && stop(self.mode) {
                return Ok(true);
            }
        }
        Ok(false)
    }
}
