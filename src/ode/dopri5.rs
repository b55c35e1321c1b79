//! The Dormand-Prince 5(4) pair with its 4th-order dense output, stepping a
//! [`HybridSystem`] and locating guard crossings on the dense output (see [`crate::ode`]).

use nalgebra::SVector;

use crate::ode::events;
use crate::ode::{
    HybridSystem, Observer, Options, SolverError, Stats, Step, Steps, MAX_GUARDS,
    MAX_SWITCHES_AT_ONE_TIME,
};

// Dormand-Prince 5(4) coefficients.
const C2: f64 = 1.0 / 5.0;
const C3: f64 = 3.0 / 10.0;
const C4: f64 = 4.0 / 5.0;
const C5: f64 = 8.0 / 9.0;
const A21: f64 = 1.0 / 5.0;
const A31: f64 = 3.0 / 40.0;
const A32: f64 = 9.0 / 40.0;
const A41: f64 = 44.0 / 45.0;
const A42: f64 = -56.0 / 15.0;
const A43: f64 = 32.0 / 9.0;
const A51: f64 = 19372.0 / 6561.0;
const A52: f64 = -25360.0 / 2187.0;
const A53: f64 = 64448.0 / 6561.0;
const A54: f64 = -212.0 / 729.0;
const A61: f64 = 9017.0 / 3168.0;
const A62: f64 = -355.0 / 33.0;
const A63: f64 = 46732.0 / 5247.0;
const A64: f64 = 49.0 / 176.0;
const A65: f64 = -5103.0 / 18656.0;
const A71: f64 = 35.0 / 384.0;
const A73: f64 = 500.0 / 1113.0;
const A74: f64 = 125.0 / 192.0;
const A75: f64 = -2187.0 / 6784.0;
const A76: f64 = 11.0 / 84.0;
const E1: f64 = 71.0 / 57600.0;
const E3: f64 = -71.0 / 16695.0;
const E4: f64 = 71.0 / 1920.0;
const E5: f64 = -17253.0 / 339200.0;
const E6: f64 = 22.0 / 525.0;
const E7: f64 = -1.0 / 40.0;
const D1: f64 = -12715105075.0 / 11282082432.0;
const D3: f64 = 87487479700.0 / 32700410799.0;
const D4: f64 = -10690763975.0 / 1880347072.0;
const D5: f64 = 701980252875.0 / 199316789632.0;
const D6: f64 = -1453857185.0 / 822651844.0;
const D7: f64 = 69997945.0 / 29380423.0;

/// The error norm below which the step-size factor `0.9 err^(-1/5)` is at least 1:
/// `0.9^5` (rounded down, so that the skipped factor is always >= 1).
const MAX_ERR_KEEPING_STEP: f64 = 0.59;

/// Integrator state: time, state, mode, FSAL derivative, proposed step and counters.
///
/// The fields are private because the derivative at the current point (`k1`, reused by the
/// next step) is cached: read them with [`Dopri5::t`], [`Dopri5::y`], [`Dopri5::mode`],
/// [`Dopri5::stats`] and [`Dopri5::options`], and move the integrator to another state with
/// [`Dopri5::restart`], which drops the cache.
#[derive(Debug, Clone)]
pub struct Dopri5<S: HybridSystem<N>, const N: usize> {
    t: f64,
    y: SVector<f64, N>,
    mode: S::Mode,
    opts: Options<N>,
    stats: Stats,
    k1: SVector<f64, N>,
    h: f64,
    k1_valid: bool,
    /// The modes visited since time last advanced (empty when no switch happened since).
    switch_trail: Vec<S::Mode>,
    /// No step has been accepted since the last mode switch.
    after_event: bool,
    /// Per mode, the first full step accepted after the last switch into it: the step
    /// proposed after the next switch into that mode (see [`Dopri5::switch`]).
    entry_steps: Vec<(S::Mode, f64)>,
}

struct Trial<const N: usize> {
    y1: SVector<f64, N>,
    k: [SVector<f64, N>; 7],
    err: f64,
}

impl<S: HybridSystem<N>, const N: usize> Dopri5<S, N> {
    /// A new integrator at (t0, y0) in `mode`.
    pub fn new(t0: f64, y0: SVector<f64, N>, mode: S::Mode, opts: Options<N>) -> Self {
        let h = opts.h_init;
        Self {
            t: t0,
            y: y0,
            mode,
            opts,
            stats: Stats::default(),
            k1: SVector::zeros(),
            h,
            k1_valid: false,
            switch_trail: Vec::new(),
            after_event: false,
            entry_steps: Vec::new(),
        }
    }

    /// Current time (s).
    pub fn t(&self) -> f64 {
        self.t
    }

    /// Current state.
    pub fn y(&self) -> SVector<f64, N> {
        self.y
    }

    /// Current mode.
    pub fn mode(&self) -> S::Mode {
        self.mode
    }

    /// Counters since [`Dopri5::new`].
    pub fn stats(&self) -> Stats {
        self.stats
    }

    /// Options.
    pub fn options(&self) -> &Options<N> {
        &self.opts
    }

    /// Continues from a new point (t, y, mode), keeping the options and the counters: the
    /// cached derivative is dropped and the next trial step is [`Options::h_init`].
    pub fn restart(&mut self, t: f64, y: SVector<f64, N>, mode: S::Mode) {
        self.t = t;
        self.y = y;
        self.mode = mode;
        self.h = self.opts.h_init;
        self.k1_valid = false;
        self.after_event = false;
        self.switch_trail.clear();
    }

    /// [`Dopri5::restart`] with the next trial step `h` instead of [`Options::h_init`] (for a
    /// caller that knows the scale of the motion, e.g. the sample interval of a sampled
    /// input in free flight).
    pub fn restart_with_step(&mut self, t: f64, y: SVector<f64, N>, mode: S::Mode, h: f64) {
        self.restart(t, y, mode);
        self.h = h;
    }

    fn state_vec(&self) -> Vec<f64> {
        self.y.iter().copied().collect()
    }

    fn trial(&mut self, sys: &S, h: f64) -> Trial<N> {
        let (t, y, k1, mode) = (self.t, self.y, self.k1, self.mode);
        let k2 = sys.rhs(mode, t + C2 * h, &(y + k1 * (A21 * h)));
        let k3 = sys.rhs(mode, t + C3 * h, &(y + (k1 * A31 + k2 * A32) * h));
        let k4 = sys.rhs(
            mode,
            t + C4 * h,
            &(y + (k1 * A41 + k2 * A42 + k3 * A43) * h),
        );
        let k5 = sys.rhs(
            mode,
            t + C5 * h,
            &(y + (k1 * A51 + k2 * A52 + k3 * A53 + k4 * A54) * h),
        );
        let k6 = sys.rhs(
            mode,
            t + h,
            &(y + (k1 * A61 + k2 * A62 + k3 * A63 + k4 * A64 + k5 * A65) * h),
        );
        let y1 = y + (k1 * A71 + k3 * A73 + k4 * A74 + k5 * A75 + k6 * A76) * h;
        let k7 = sys.rhs(mode, t + h, &y1);
        self.stats.rhs_evals += 6;
        let e = (k1 * E1 + k3 * E3 + k4 * E4 + k5 * E5 + k6 * E6 + k7 * E7) * h;
        let mut acc = 0.0;
        for i in 0..N {
            let sc = self.opts.atol[i] + self.opts.rtol * y[i].abs().max(y1[i].abs());
            let r = e[i] / sc;
            acc += r * r;
        }
        let err = (acc / N as f64).sqrt();
        Trial {
            y1,
            k: [k1, k2, k3, k4, k5, k6, k7],
            err,
        }
    }

    fn make_step(&self, h: f64, tr: &Trial<N>) -> Step<N> {
        let y0 = self.y;
        let k = &tr.k;
        let ydiff = tr.y1 - y0;
        let bspl = k[0] * h - ydiff;
        let r3 = ydiff - k[6] * h - bspl;
        let r4 = (k[0] * D1 + k[2] * D3 + k[3] * D4 + k[4] * D5 + k[5] * D6 + k[6] * D7) * h;
        Step {
            t0: self.t,
            h,
            y0,
            y1: tr.y1,
            rcont: [y0, ydiff, bspl, r3, r4],
        }
    }

    /// Switches the mode through guard `index` at the current time and state (the state may
    /// be projected by the system); errs when switches keep firing without time advancing.
    ///
    /// The next trial step is the current one capped by the first full step accepted after
    /// the previous switch into the new mode: a mode's own dynamics set its step (the end-stop
    /// contact rings ~100 times faster than the free motion, and the step from before the
    /// impact used to be rejected several times). Hairer's starting-step heuristic evaluated
    /// at the switch does not serve here: at a contact entry the penetration, hence the contact
    /// force, is zero, so a derivative estimate at that point cannot see the stiffness that
    /// builds up within the step.
    fn switch<O: Observer<N, S::Mode>>(
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
    fn advance(&mut self, t: f64, y: SVector<f64, N>) {
        self.t = t;
        self.y = y;
        self.switch_trail.clear();
    }

    /// Integrates to `t_end`, calling `observer` with every accepted step (and with the mode
    /// that was active over it).
    pub fn integrate<O: FnMut(&Step<N>, S::Mode)>(
        &mut self,
        sys: &S,
        t_end: f64,
        observer: O,
    ) -> Result<(), SolverError> {
        self.integrate_observed(sys, t_end, &mut Steps(observer))
    }

    /// Integrates to `t_end`, showing `observer` every accepted step and every mode switch.
    pub fn integrate_observed<O: Observer<N, S::Mode>>(
        &mut self,
        sys: &S,
        t_end: f64,
        observer: &mut O,
    ) -> Result<(), SolverError> {
        let mut steps: u64 = 0;
        while self.t < t_end {
            if !self.k1_valid {
                self.k1 = sys.rhs(self.mode, self.t, &self.y);
                self.stats.rhs_evals += 1;
                self.k1_valid = true;
                if !self.k1.iter().all(|v| v.is_finite()) {
                    return Err(SolverError::NonFinite {
                        t: self.t,
                        state: self.state_vec(),
                    });
                }
                // A guard already positive at the start of a step fires at once.
                let g = sys.guards(self.mode, self.t, &self.y);
                if let Some(i) = (0..MAX_GUARDS).find(|&i| g[i] > 0.0) {
                    self.switch(sys, i, observer)?;
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
            if !tr.err.is_finite() || !tr.y1.iter().all(|v| v.is_finite()) {
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
            // the factor is below 1, i.e. err > 0.9^5: skip the power where it cannot matter
            // (most steps of a sampled input end on a breakpoint).
            let fac = if clipped && tr.err <= MAX_ERR_KEEPING_STEP {
                1.0
            } else {
                (0.9 * tr.err.powf(-0.2)).clamp(0.2, 10.0)
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
            match events::locate(sys, self.mode, &step, self.opts.event_time_tol) {
                None => {
                    self.stats.accepted += 1;
                    observer.step(&step, self.mode);
                    self.advance(t_new, tr.y1);
                    self.k1 = tr.k[6];
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
                        if !tr_ev.err.is_finite() || !tr_ev.y1.iter().all(|v| v.is_finite()) {
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
        }
        Ok(())
    }
}
