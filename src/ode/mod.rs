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
//! * The system carries a [`Vector`] (a model's state, or the state augmented with its
//!   variational equations or running integrals, see [`vector`]).
//! * The system has [`HybridSystem::guard_count`] guard functions g_i(t, y), as many as it
//!   needs (a mode that uses fewer fills the rest with `f64::NEG_INFINITY`). A guard that
//!   becomes **positive** asks to leave the mode. After each accepted step the guards are
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
//! use endstop::ode::{Dopri5, HybridSystem, Options};
//! use nalgebra::SVector;
//!
//! struct Ball;
//!
//! impl HybridSystem for Ball {
//!     type State = SVector<f64, 2>;
//!     type Mode = ();
//!     fn guard_count(&self) -> usize {
//!         1
//!     }
//!     fn rhs(&self, _: (), _t: f64, y: &SVector<f64, 2>) -> SVector<f64, 2> {
//!         SVector::<f64, 2>::new(y[1], -9.81)
//!     }
//!     fn guards(&self, _: (), _t: f64, y: &SVector<f64, 2>, g: &mut [f64]) {
//!         g[0] = -y[0];
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
pub mod phi;
mod runge_kutta;
pub mod tableau;
pub mod vector;

use std::ops::AddAssign;

use thiserror::Error;

pub use adaptive::{Adaptive, Dopri5};
pub use fixed::{FixedStep, Rk4};
pub use vector::{Augmented, Tangent, Vector};

/// Most mode switches allowed in a row without time advancing (see [`SolverError::Chattering`]).
pub const MAX_SWITCHES_AT_ONE_TIME: u32 = 16;

/// A piecewise-smooth ODE system y' = f_mode(t, y).
pub trait HybridSystem {
    /// What the system carries.
    type State: Vector;

    /// Discrete mode (e.g. free flight or contact with one stop).
    type Mode: Copy + PartialEq + std::fmt::Debug;

    /// Number of guard functions (the same in every mode; a mode that has fewer fills the
    /// rest of [`HybridSystem::guards`] with `f64::NEG_INFINITY`).
    fn guard_count(&self) -> usize;

    /// Right-hand side in a given mode.
    fn rhs(&self, mode: Self::Mode, t: f64, y: &Self::State) -> Self::State;

    /// Guard functions of a mode, written into `g` (of length [`HybridSystem::guard_count`]):
    /// a guard > 0 asks to leave the mode.
    fn guards(&self, mode: Self::Mode, t: f64, y: &Self::State, g: &mut [f64]);

    /// The guards of `mode` at `theta` on the dense output of `step` (at time `t`, which the
    /// caller computes as `step.t0 + theta * step.h`), written into `g` as
    /// [`HybridSystem::guards`] writes them: the event location probes a step's guards here.
    ///
    /// The default interpolates the whole state ([`Step::at_theta`]). A system whose guards
    /// read part of what it carries (the state of a [`Tangent`], not its tangent map)
    /// overrides it to interpolate that part alone ([`Step::part_at_theta`], the same bits
    /// component by component).
    ///
    /// Always inlined: the default is the interpolation and the guards that the event
    /// location inlined before it had this hook (left out of line, the call shows apart in a
    /// fit's profile, at some 3 % of its samples).
    #[inline(always)]
    fn guards_on_step(
        &self,
        mode: Self::Mode,
        t: f64,
        step: &Step<Self::State>,
        theta: f64,
        g: &mut [f64],
    ) {
        self.guards(mode, t, &step.at_theta(theta), g)
    }

    /// Called when guard `index` of `mode` fires at time `t`: returns the new mode and may
    /// adjust the state (a projection within the integration tolerance).
    fn switch(&self, mode: Self::Mode, index: usize, t: f64, y: &mut Self::State) -> Self::Mode;

    /// The first breakpoint strictly after `t` that no step may cross (default: none).
    fn next_breakpoint(&self, _t: f64) -> f64 {
        f64::INFINITY
    }

    /// Checks that a state is physically admissible; an `Err` stops the integration.
    fn check_state(&self, _mode: Self::Mode, _t: f64, _y: &Self::State) -> Result<(), String> {
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
    /// The system could not be built (a model whose parts do not assemble).
    #[error("{0}")]
    Model(String),
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
pub struct Options<V> {
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance per component (in the component's units).
    pub atol: V,
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

impl<V> Options<V> {
    /// The smallest step allowed at time `t` (s): `max(h_min, MIN_STEP_REL |t|)`. A step
    /// shorter than a few units in the last place of t cannot advance t (as in Hairer's codes,
    /// whose DOPRI5 stops when 0.1 |h| <= |t| eps).
    pub fn min_step(&self, t: f64) -> f64 {
        self.h_min.max(MIN_STEP_REL * t.abs())
    }

    /// The same options for another carried vector with absolute tolerances `atol` (a system
    /// augmented with variational equations or accumulators; the caller puts the system's own
    /// tolerances in the state's place).
    pub fn with_atol<W>(&self, atol: W) -> Options<W> {
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

impl<const N: usize> Options<nalgebra::SVector<f64, N>> {
    /// The same options for the system augmented to `M` components (variational equations,
    /// energy accumulators): `atol` gives the added components' tolerances, and its first `N`
    /// entries are replaced by this system's.
    pub fn augmented<const M: usize>(
        &self,
        mut atol: nalgebra::SVector<f64, M>,
    ) -> Options<nalgebra::SVector<f64, M>> {
        for i in 0..N.min(M) {
            atol[i] = self.atol[i];
        }
        self.with_atol(atol)
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
pub trait Observer<V, M> {
    /// An accepted step, with the mode that was active over it.
    fn step(&mut self, step: &Step<V>, mode: M);
    /// A mode switch at time `t` from `from` to `to` (after the system's reset of the state).
    fn switched(&mut self, _t: f64, _from: M, _to: M) {}
    /// False for an observer that looks at nothing: an integrator may then skip building
    /// what it would only show (the exact path's dense output through its midpoint).
    const SEES: bool = true;
}

/// An observer of nothing: integration alone, without the work of showing its steps.
pub(crate) struct Unseen;

impl<V, M> Observer<V, M> for Unseen {
    #[inline(always)]
    fn step(&mut self, _: &Step<V>, _: M) {}
    const SEES: bool = false;
}

/// An observer of the steps alone, from a closure.
pub(crate) struct Steps<F>(pub(crate) F);

impl<V, M, F: FnMut(&Step<V>, M)> Observer<V, M> for Steps<F> {
    #[inline(always)]
    fn step(&mut self, step: &Step<V>, mode: M) {
        (self.0)(step, mode)
    }
}

/// One accepted step, with its dense output, as seen by an observer.
#[derive(Debug, Clone)]
pub struct Step<V> {
    /// Start time (s).
    pub t0: f64,
    /// Step length (s).
    pub h: f64,
    /// State at the start.
    pub y0: V,
    /// State at the end.
    pub y1: V,
    rcont: [V; 5],
}

impl<V: Vector> Step<V> {
    /// A step of an integrator that knows its solution at the ends and the midpoint (an exact
    /// propagator): its dense output is the quartic through `y0`, `y_mid` and `y1` with
    /// derivatives `f0` and `f1` at the ends (the cubic Hermite interpolant plus a multiple of
    /// `theta^2 (1 - theta)^2`, in the form of the Dormand-Prince dense output).
    pub fn from_ends_and_midpoint(
        t0: f64,
        h: f64,
        [y0, y_mid, y1]: [V; 3],
        [f0, f1]: [V; 2],
    ) -> Self {
        let r1 = y1 - y0;
        let r2 = f0 * h - r1;
        let r3 = r1 - f1 * h - r2;
        let r4 = (y_mid - (y0 + r1 * 0.5 + r2 * 0.25 + r3 * 0.125)) * 16.0;
        Self {
            t0,
            h,
            y0,
            y1,
            rcont: [y0, r1, r2, r3, r4],
        }
    }

    /// End time (s).
    pub fn t1(&self) -> f64 {
        self.t0 + self.h
    }

    /// Dense output at theta = (t - t0)/h in [0, 1].
    pub fn at_theta(&self, theta: f64) -> V {
        self.part_at_theta(theta, |v| v)
    }

    /// The dense output at theta of the part of the state that `part` picks (a field of a
    /// [`Tangent`], or the whole state for [`Step::at_theta`]): the same operations on each of
    /// its components, hence the same bits, without the work on the rest.
    #[inline]
    pub fn part_at_theta<P: Vector>(&self, theta: f64, part: impl Fn(&V) -> &P) -> P {
        let th1 = 1.0 - theta;
        let [r0, r1, r2, r3, r4] = self.rcont.each_ref().map(|r| *part(r));
        r0 + (r1 + (r2 + (r3 + r4 * th1) * theta) * th1) * theta
    }

    /// Dense output at time t (s), t in [t0, t0 + h].
    pub fn at(&self, t: f64) -> V {
        self.at_theta((t - self.t0) / self.h)
    }

    /// Integral over the step of `f(y(t))` by 3-point Gauss-Legendre on the dense output.
    pub fn integrate<F: Fn(&V) -> f64>(&self, f: F) -> f64 {
        let mut s = 0.0;
        for (x, w) in GAUSS_LEGENDRE_3 {
            s += w * f(&self.at_theta(x));
        }
        s * self.h
    }

    /// The integrals over the step of each component of `f(y(t))`, as [`Step::integrate`]
    /// computes each of them (the same operations in the same order, so the same bits), with
    /// the dense output and `f` evaluated once per node for all of them.
    pub fn integrate_each<const K: usize, F: Fn(&V) -> [f64; K]>(&self, f: F) -> [f64; K] {
        let mut s = [0.0; K];
        for (x, w) in GAUSS_LEGENDRE_3 {
            let v = f(&self.at_theta(x));
            for (sk, vk) in s.iter_mut().zip(v) {
                *sk += w * vk;
            }
        }
        s.map(|sk| sk * self.h)
    }
}

/// The 3-point Gauss-Legendre rule on [0, 1]: (node, weight) pairs, exact for polynomials of
/// degree 5.
pub const GAUSS_LEGENDRE_3: [(f64, f64); 3] = [
    (0.112_701_665_379_258_3, 5.0 / 18.0),
    (0.5, 8.0 / 18.0),
    (0.887_298_334_620_741_7, 5.0 / 18.0),
];

/// The 5-point Gauss-Legendre rule on [-1, 1]: (node, weight) pairs, exact for polynomials of
/// degree 9 (Abramowitz and Stegun, Table 25.4).
pub const GAUSS_LEGENDRE_5: [(f64, f64); 5] = [
    (0.0, 0.568_888_888_888_889),
    (-0.538_469_310_105_683, 0.478_628_670_499_366),
    (0.538_469_310_105_683, 0.478_628_670_499_366),
    (-0.906_179_845_938_664, 0.236_926_885_056_189),
    (0.906_179_845_938_664, 0.236_926_885_056_189),
];
