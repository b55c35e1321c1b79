//! Explicit Runge-Kutta integration of hybrid (piecewise-smooth) systems: one stepping engine
//! driven by Butcher tableaus ([`tableau`]; the stages in `runge_kutta.rs`), an adaptive driver with dense
//! output and event location ([`Adaptive`]; with Dormand-Prince 5(4), [`Dopri5`], the crate's
//! integrator) and a fixed-step one ([`FixedStep`]; with the classical RK4, the benchmark's
//! yardstick), beside the exponential free-flight step of sampled inputs ([`exponential`]).
//!
//! # Why it is hand-written
//! The end-stop model switches its right-hand side when the proof mass touches or leaves a
//! stop. An integrator that steps across such a switch sees a non-smooth right-hand side, its
//! error estimate breaks down, and the contact time is only known to within one step. No Rust
//! crate we found locates events on the dense output and steps onto them
//! (`differential-equations` 0.7 misplaces events, `ode_solvers` has none), so this module does.
//!
//! # Conventions
//! * A [`HybridSystem`] has a discrete `Mode`. Within one step the mode is fixed, so the
//!   right-hand side is smooth over the step.
//! * In each mode the system exposes up to [`MAX_GUARDS`] guard functions g_i(t, y). A guard
//!   that becomes **positive** asks to leave the mode. After each accepted step the guards are
//!   evaluated at the end point and at two interior points of the dense output; the earliest
//!   sign change from <= 0 to > 0 is located on the dense output by the crate's root finder
//!   ([`crate::num::roots::illinois`]) to a time tolerance of [`Options::event_time_tol`]
//!   seconds, and the step is **re-taken** from its start with exactly the length that lands
//!   on the event (and checked for finiteness like any step). A guard that rises above zero
//!   and falls back between two probes (a grazing contact) is found by maximising it on the
//!   dense output where the probes suggest a maximum near zero (see `events.rs`). The system
//!   then picks the new mode (and may project the state, e.g. put x exactly on the stop).
//! * After a switch, the next trial step is capped by the first full step accepted after the
//!   previous switch into the new mode, so that a mode with faster dynamics (a stiff contact)
//!   does not start with the step of the mode it left.
//! * A guard that is already positive at the start of a step (a mode entered at a grazing
//!   point) fires at once; more than [`MAX_SWITCHES_AT_ONE_TIME`] switches in a row without
//!   time advancing are an error ([`SolverError::Chattering`]).
//! * The system may also impose breakpoints (the sample instants of a sampled input, the ends
//!   of whole periods): no step crosses a breakpoint.
//! * The smallest step at time t is max(h_min, 16 eps |t|) ([`Options::min_step`]): a shorter
//!   step could not advance t.
//! * Error norm: RMS over components of err_i / (atol_i + rtol max(|y0_i|, |y1_i|)), with err
//!   the embedded estimate ([`tableau::Tableau::error`]); a step is accepted when the norm is
//!   <= 1. Step-size factor 0.9 err^(-1/(q+1)), q the pair's lower order (-1/5 for
//!   Dormand-Prince), limited to [0.2, 10].
//! * Dense output: the continuous extension in the form of Hairer, Norsett and Wanner's DOPRI5
//!   (`contd5`, 4th order for Dormand-Prince), from the tableau's dense coefficients
//!   ([`tableau::Tableau::dense`]).
//!
//! # Example
//! A ball dropped from 1 m onto a floor that returns it with half its speed: one guard (the
//! height below the floor), located on the dense output, and a switch that reverses the
//! velocity.
//!
//! ```
//! use endstop::ode::{Dopri5, Guards, HybridSystem, Options};
//! use nalgebra::SVector;
//!
//! struct Ball;
//!
//! impl HybridSystem<2> for Ball {
//!     type Mode = ();
//!     fn rhs(&self, _: (), _t: f64, y: &SVector<f64, 2>) -> SVector<f64, 2> {
//!         SVector::<f64, 2>::new(y[1], -9.81)
//!     }
//!     fn guards(&self, _: (), _t: f64, y: &SVector<f64, 2>) -> Guards {
//!         [-y[0], f64::NEG_INFINITY, f64::NEG_INFINITY]
//!     }
//!     fn switch(&self, _: (), _guard: usize, _t: f64, y: &mut SVector<f64, 2>) {
//!         y[0] = 0.0;
//!         y[1] *= -0.5;
//!     }
//! }
//!
//! let opts = Options {
//!     rtol: 1e-10,
//!     atol: SVector::<f64, 2>::repeat(1e-12),
//!     h_max: 0.01,
//!     h_min: 1e-16,
//!     h_init: 1e-4,
//!     max_steps: 100_000,
//!     event_time_tol: 1e-14,
//! };
//! let mut ode = Dopri5::new(0.0, SVector::<f64, 2>::new(1.0, 0.0), (), opts);
//! ode.integrate(&Ball, 0.7, |_, _| {})?;
//! // The floor at t1 = sqrt(2 h / g) with speed g t1; then up at half that speed.
//! let t1 = (2.0 / 9.81f64).sqrt();
//! let (t, u) = (0.7 - t1, 0.5 * 9.81 * t1);
//! assert_eq!(ode.stats().events, 1);
//! assert!((ode.y()[0] - (u * t - 0.5 * 9.81 * t * t)).abs() < 1e-9);
//! assert!((ode.y()[1] - (u - 9.81 * t)).abs() < 1e-9);
//! # Ok::<(), endstop::ode::SolverError>(())
//! ```

mod adaptive;
pub mod events;
pub mod exponential;
mod fixed;
mod runge_kutta;
pub mod tableau;

use std::ops::AddAssign;

use nalgebra::SVector;
use thiserror::Error;

pub use adaptive::{Adaptive, Dopri5};
pub use fixed::{FixedStep, Rk4};

/// Maximum number of guard functions of one mode.
pub const MAX_GUARDS: usize = 3;

/// Most mode switches allowed in a row without time advancing (see [`SolverError::Chattering`]).
pub const MAX_SWITCHES_AT_ONE_TIME: u32 = 16;

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
    /// The step size fell below [`Options::min_step`].
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
    /// Mode switches kept firing without time advancing: a guard of each new mode was
    /// positive at once, more than [`MAX_SWITCHES_AT_ONE_TIME`] times in a row.
    #[error("{switches} mode switches at t = {t:e} s without time advancing (modes {modes:?}, state {state:?})")]
    Chattering {
        /// Simulated time (s).
        t: f64,
        /// Switches made at `t`.
        switches: u32,
        /// The modes visited at `t`, in order (their `Debug` text).
        modes: Vec<String>,
        /// State at `t`.
        state: Vec<f64>,
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
    /// Absolute floor of the smallest step (s); the smallest step at time t is
    /// [`Options::min_step`].
    pub h_min: f64,
    /// First trial step (s).
    pub h_init: f64,
    /// Maximum number of accepted + rejected steps per [`Adaptive::integrate`] call.
    pub max_steps: u64,
    /// Time tolerance for event location (s).
    pub event_time_tol: f64,
}

impl<const N: usize> Options<N> {
    /// The smallest step allowed at time `t` (s): `max(h_min, MIN_STEP_REL |t|)`. A step
    /// shorter than a few units in the last place of t cannot advance t (as in Hairer's codes,
    /// whose DOPRI5 stops when 0.1 |h| <= |t| eps).
    pub fn min_step(&self, t: f64) -> f64 {
        self.h_min.max(MIN_STEP_REL * t.abs())
    }

    /// The same options for the system augmented to `M` components (variational equations,
    /// energy accumulators): `atol` gives the added components' tolerances, and its first `N`
    /// entries are replaced by this system's.
    pub fn augmented<const M: usize>(&self, mut atol: SVector<f64, M>) -> Options<M> {
        for i in 0..N.min(M) {
            atol[i] = self.atol[i];
        }
        Options {
            rtol: self.rtol,
            atol,
            h_max: self.h_max,
            h_min: self.h_min,
            h_init: self.h_init,
            max_steps: self.max_steps,
            event_time_tol: self.event_time_tol,
        }
    }
}

/// The smallest step relative to |t| (16 machine epsilons, see [`Options::min_step`]).
pub const MIN_STEP_REL: f64 = 16.0 * f64::EPSILON;

/// Counters, for benchmarks and convergence reports.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Stats {
    /// Accepted steps (including the re-taken steps that land on events).
    pub accepted: u64,
    /// Rejected steps.
    pub rejected: u64,
    /// Rejected trials of the first step after an event (included in `rejected`).
    pub rejected_after_event: u64,
    /// Right-hand-side evaluations.
    pub rhs_evals: u64,
    /// Events (mode switches).
    pub events: u64,
}

impl Stats {
    /// Steps tried: accepted and rejected.
    pub fn steps(&self) -> u64 {
        self.accepted + self.rejected
    }
}

impl AddAssign for Stats {
    fn add_assign(&mut self, other: Stats) {
        self.accepted += other.accepted;
        self.rejected += other.rejected;
        self.rejected_after_event += other.rejected_after_event;
        self.rhs_evals += other.rhs_evals;
        self.events += other.events;
    }
}

/// What an integration shows of itself as it runs: every accepted step, and every mode switch.
/// [`Dopri5::integrate`] takes a closure for the steps alone; [`Dopri5::integrate_observed`]
/// takes an observer of both.
pub trait Observer<const N: usize, M> {
    /// An accepted step, with the mode that was active over it.
    fn step(&mut self, step: &Step<N>, mode: M);
    /// A mode switch at time `t` from `from` to `to` (after the system's reset of the state).
    fn switched(&mut self, _t: f64, _from: M, _to: M) {}
}

/// An observer of the steps alone, from a closure.
pub(crate) struct Steps<F>(pub(crate) F);

impl<const N: usize, M, F: FnMut(&Step<N>, M)> Observer<N, M> for Steps<F> {
    #[inline(always)]
    fn step(&mut self, step: &Step<N>, mode: M) {
        (self.0)(step, mode)
    }
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
        let mut s = 0.0;
        for (x, w) in GAUSS_LEGENDRE_3 {
            s += w * f(&self.at_theta(x));
        }
        s * self.h
    }
}

/// The 3-point Gauss-Legendre rule on [0, 1]: (node, weight) pairs, exact for polynomials of
/// degree 5.
pub const GAUSS_LEGENDRE_3: [(f64, f64); 3] = [
    (0.112_701_665_379_258_3, 5.0 / 18.0),
    (0.5, 8.0 / 18.0),
    (0.887_298_334_620_741_7, 5.0 / 18.0),
];
