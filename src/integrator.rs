//! Adaptive Dormand-Prince 5(4) integrator with dense output and event location for hybrid
//! (piecewise-smooth) systems.
//!
//! # Why it is hand-written
//! The end-stop model switches its right-hand side when the proof mass touches or leaves a
//! stop. An integrator that steps across such a switch sees a non-smooth right-hand side, its
//! error estimate breaks down, and the contact time is only known to within one step. At the
//! time of writing no Rust crate locates events on the dense output and steps onto them
//! (`differential-equations` 0.7 misplaces events, `ode_solvers` has none), so this module does.
//!
//! # Conventions
//! * A [`HybridSystem`] has a discrete `Mode`. Within one step the mode is fixed, so the
//!   right-hand side is smooth over the step.
//! * In each mode the system exposes up to [`MAX_GUARDS`] guard functions g_i(t, y). A guard
//!   that becomes **positive** asks to leave the mode. After each accepted step the guards are
//!   evaluated at the end point and at two interior points of the dense output; the earliest
//!   sign change from <= 0 to > 0 is located by the Illinois method on the dense output to a
//!   time tolerance of [`Options::event_time_tol`] seconds, and the step is **re-taken** from
//!   its start with exactly the length that lands on the event. The system then picks the new
//!   mode (and may project the state, e.g. put x exactly on the stop).
//! * A guard that is already positive at the start of a step (a mode entered at a grazing
//!   point) fires at once.
//! * The system may also impose breakpoints (the sample instants of a sampled input, the ends
//!   of whole periods): no step crosses a breakpoint.
//! * Error norm: RMS over components of err_i / (atol_i + rtol max(|y0_i|, |y1_i|)); a step is
//!   accepted when the norm is <= 1. Step-size factor 0.9 err^(-1/5), limited to [0.2, 10].
//! * Dense output: the 4th-order continuous extension of Hairer, Norsett and Wanner (the
//!   `contd5` of their DOPRI5 code).

use nalgebra::SVector;
use thiserror::Error;

/// Maximum number of guard functions of one mode.
pub const MAX_GUARDS: usize = 3;

/// Guard values of one mode; unused entries are `f64::NEG_INFINITY`.
pub type Guards = [f64; MAX_GUARDS];

/// A piecewise-smooth ODE system y' = f_mode(t, y).
pub trait HybridSystem<const N: usize> {
    /// Discrete mode (e.g. free flight or contact with one stop).
    type Mode: Copy + PartialEq + std::fmt::Debug;

    /// Right-hand side in a given mode.
    fn rhs(&self, mode: Self::Mode, t: f64, y: &SVector<f64, N>) -> SVector<f64, N>;

    /// Guard functions of a mode: a guard > 0 asks to leave the mode.
    fn guards(&self, mode: Self::Mode, t: f64, y: &SVector<f64, N>) -> Guards;

    /// Called when guard `index` of `mode` fires at time `t`: returns the new mode and may
    /// adjust the state (a projection within the integration tolerance).
    fn switch(&self, mode: Self::Mode, index: usize, t: f64, y: &mut SVector<f64, N>)
        -> Self::Mode;

    /// The first breakpoint strictly after `t` that no step may cross (default: none).
    fn next_breakpoint(&self, _t: f64) -> f64 {
        f64::INFINITY
    }

    /// Checks that a state is physically admissible; an `Err` stops the integration.
    fn check_state(&self, _mode: Self::Mode, _t: f64, _y: &SVector<f64, N>) -> Result<(), String> {
        Ok(())
    }
}

/// Integrator failure, with the simulated time and state where it happened.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum SolverError {
    /// The step size fell below [`Options::h_min`].
    #[error("step size {h:e} s below the minimum at t = {t:e} s (state {state:?})")]
    StepSizeTooSmall {
        /// Simulated time (s).
        t: f64,
        /// Rejected step size (s).
        h: f64,
        /// State at `t`.
        state: Vec<f64>,
    },
    /// A stage or the state became NaN or infinite.
    #[error("non-finite state at t = {t:e} s (state {state:?})")]
    NonFinite {
        /// Simulated time (s).
        t: f64,
        /// State at `t`.
        state: Vec<f64>,
    },
    /// More than [`Options::max_steps`] steps in one call.
    #[error(
        "more than {max_steps} steps before reaching t = {t_end:e} s (stopped at t = {t:e} s)"
    )]
    TooManySteps {
        /// Step limit.
        max_steps: u64,
        /// Time reached (s).
        t: f64,
        /// Requested end time (s).
        t_end: f64,
    },
    /// The system reported an inadmissible state.
    #[error("inadmissible state at t = {t:e} s: {message} (state {state:?})")]
    InvalidState {
        /// Simulated time (s).
        t: f64,
        /// The system's message.
        message: String,
        /// State at `t`.
        state: Vec<f64>,
    },
}

/// Integrator options.
#[derive(Debug, Clone, PartialEq)]
pub struct Options<const N: usize> {
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance per component (in the component's units).
    pub atol: SVector<f64, N>,
    /// Largest step (s).
    pub h_max: f64,
    /// Smallest step before giving up (s).
    pub h_min: f64,
    /// First trial step (s).
    pub h_init: f64,
    /// Maximum number of accepted + rejected steps per [`Dopri5::integrate`] call.
    pub max_steps: u64,
    /// Time tolerance for event location (s).
    pub event_time_tol: f64,
}

/// Counters, for benchmarks and convergence reports.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Stats {
    /// Accepted steps (including the re-taken steps that land on events).
    pub accepted: u64,
    /// Rejected steps.
    pub rejected: u64,
    /// Right-hand-side evaluations.
    pub rhs_evals: u64,
    /// Events (mode switches).
    pub events: u64,
}

/// One accepted step, with its dense output, as seen by an observer.
#[derive(Debug, Clone)]
pub struct Step<const N: usize> {
    /// Start time (s).
    pub t0: f64,
    /// Step length (s).
    pub h: f64,
    /// State at the start.
    pub y0: SVector<f64, N>,
    /// State at the end.
    pub y1: SVector<f64, N>,
    rcont: [SVector<f64, N>; 5],
}

impl<const N: usize> Step<N> {
    /// End time (s).
    pub fn t1(&self) -> f64 {
        self.t0 + self.h
    }

    /// Dense output at theta = (t - t0)/h in [0, 1].
    pub fn at_theta(&self, theta: f64) -> SVector<f64, N> {
        let th1 = 1.0 - theta;
        let r = &self.rcont;
        r[0] + (r[1] + (r[2] + (r[3] + r[4] * th1) * theta) * th1) * theta
    }

    /// Dense output at time t (s), t in [t0, t0 + h].
    pub fn at(&self, t: f64) -> SVector<f64, N> {
        self.at_theta((t - self.t0) / self.h)
    }

    /// Integral over the step of `f(y(t))` by 3-point Gauss-Legendre on the dense output.
    pub fn integrate<F: Fn(&SVector<f64, N>) -> f64>(&self, f: F) -> f64 {
        const X: [f64; 3] = [0.112_701_665_379_258_3, 0.5, 0.887_298_334_620_741_7];
        const W: [f64; 3] = [5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0];
        let mut s = 0.0;
        for i in 0..3 {
            s += W[i] * f(&self.at_theta(X[i]));
        }
        s * self.h
    }
}

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

/// Integrator state: time, state, mode, FSAL derivative, proposed step and counters.
#[derive(Debug, Clone)]
pub struct Dopri5<S: HybridSystem<N>, const N: usize> {
    /// Current time (s).
    pub t: f64,
    /// Current state.
    pub y: SVector<f64, N>,
    /// Current mode.
    pub mode: S::Mode,
    /// Options.
    pub opts: Options<N>,
    /// Counters.
    pub stats: Stats,
    k1: SVector<f64, N>,
    h: f64,
    k1_valid: bool,
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
        }
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

    /// Integrates to `t_end`, calling `observer` with every accepted step (and with the mode
    /// that was active over it).
    pub fn integrate<O: FnMut(&Step<N>, S::Mode)>(
        &mut self,
        sys: &S,
        t_end: f64,
        mut observer: O,
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
                    let mut y = self.y;
                    self.mode = sys.switch(self.mode, i, self.t, &mut y);
                    self.y = y;
                    self.stats.events += 1;
                    self.k1_valid = false;
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
            let tr = self.trial(sys, h);
            if !tr.err.is_finite() || !tr.y1.iter().all(|v| v.is_finite()) {
                self.stats.rejected += 1;
                self.h = h * 0.2;
                if self.h < self.opts.h_min {
                    return Err(SolverError::NonFinite {
                        t: self.t,
                        state: self.state_vec(),
                    });
                }
                continue;
            }
            let fac = (0.9 * tr.err.powf(-0.2)).clamp(0.2, 10.0);
            if tr.err > 1.0 {
                self.stats.rejected += 1;
                self.h = h * fac.min(1.0);
                if self.h < self.opts.h_min {
                    return Err(SolverError::StepSizeTooSmall {
                        t: self.t,
                        h: self.h,
                        state: self.state_vec(),
                    });
                }
                continue;
            }
            // Accepted: look for guard crossings on the dense output.
            let step = self.make_step(h, &tr);
            let t_new = if clipped { limit } else { self.t + h };
            match self.locate_event(sys, &step) {
                None => {
                    self.stats.accepted += 1;
                    observer(&step, self.mode);
                    self.t = t_new;
                    self.y = tr.y1;
                    self.k1 = tr.k[6];
                    if !clipped || fac < 1.0 {
                        self.h = h * fac;
                    }
                }
                Some((theta, index)) => {
                    // Re-take the step so that it ends exactly on the event.
                    let h_ev = theta * h;
                    let (t_ev, mut y_ev) = if h_ev > 0.0 {
                        let tr_ev = self.trial(sys, h_ev);
                        let st = self.make_step(h_ev, &tr_ev);
                        self.stats.accepted += 1;
                        observer(&st, self.mode);
                        (self.t + h_ev, tr_ev.y1)
                    } else {
                        (self.t, self.y)
                    };
                    self.mode = sys.switch(self.mode, index, t_ev, &mut y_ev);
                    self.stats.events += 1;
                    self.t = t_ev;
                    self.y = y_ev;
                    self.k1_valid = false;
                    self.h = h;
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

    /// Earliest guard crossing within the step as (theta, guard index).
    fn locate_event(&self, sys: &S, step: &Step<N>) -> Option<(f64, usize)> {
        const PROBES: [f64; 3] = [1.0 / 3.0, 2.0 / 3.0, 1.0];
        let g0 = sys.guards(self.mode, step.t0, &step.y0);
        let mut best: Option<(f64, usize)> = None;
        let mut lo_theta = [0.0; MAX_GUARDS];
        let mut lo_val = g0;
        let mut found = [false; MAX_GUARDS];
        let mut hi_theta = [1.0; MAX_GUARDS];
        let mut hi_val = [0.0; MAX_GUARDS];
        for &th in &PROBES {
            let y = if th == 1.0 {
                step.y1
            } else {
                step.at_theta(th)
            };
            let g = sys.guards(self.mode, step.t0 + th * step.h, &y);
            for i in 0..MAX_GUARDS {
                if found[i] {
                    continue;
                }
                if g[i] > 0.0 {
                    found[i] = true;
                    hi_theta[i] = th;
                    hi_val[i] = g[i];
                } else {
                    lo_theta[i] = th;
                    lo_val[i] = g[i];
                }
            }
        }
        for i in 0..MAX_GUARDS {
            if !found[i] {
                continue;
            }
            if best.is_some_and(|(b, _)| b <= lo_theta[i]) {
                continue;
            }
            let th = self.illinois(sys, step, i, lo_theta[i], lo_val[i], hi_theta[i], hi_val[i]);
            if best.is_none_or(|(b, _)| th < b) {
                best = Some((th, i));
            }
        }
        best
    }

    /// Illinois (modified regula falsi) on the dense output; returns the upper end of the final
    /// bracket, so the event is never placed before the crossing.
    #[allow(clippy::too_many_arguments)]
    fn illinois(
        &self,
        sys: &S,
        step: &Step<N>,
        i: usize,
        mut a: f64,
        mut ga: f64,
        mut b: f64,
        mut gb: f64,
    ) -> f64 {
        let tol = self.opts.event_time_tol / step.h;
        let mut side = 0i8;
        for _ in 0..200 {
            if b - a <= tol {
                break;
            }
            let mut c = (a * gb - b * ga) / (gb - ga);
            if !(c > a && c < b) {
                c = 0.5 * (a + b);
            }
            let gc = sys.guards(self.mode, step.t0 + c * step.h, &step.at_theta(c))[i];
            if gc > 0.0 {
                b = c;
                gb = gc;
                if side == 1 {
                    ga *= 0.5;
                }
                side = 1;
            } else {
                a = c;
                ga = gc;
                if side == -1 {
                    gb *= 0.5;
                }
                side = -1;
            }
        }
        b
    }
}
