//! The harvester under a sine drive, integrated **exactly** wherever its dynamics are affine,
//! and by [`Dopri5`](crate::ode::Dopri5) elsewhere: the integrator of steady states, sweeps,
//! periodic orbits and their continuation.
//!
//! # Where it is exact
//! With a linear transducer (piezoelectric, electromagnetic, none), free flight is
//! `y' = L y + c a(t)`, and so is the contact of a linear spring with a viscous damper, up to
//! a constant term (see `affine.rs`). For `a(t) = A sin(w t + phi)` its solution is known in
//! closed form: `y(t0 + s) = e^{sL} (y(t0) - p(t0)) + p(t0 + s)`, with the periodic particular
//! solution `p` from `(i w - L)^-1`. A [`SineFlow`] advances such a mode by this formula on a
//! grid of the drive period (at least [`MIN_STEPS_PER_PERIOD`] steps per period and
//! [`MIN_STEPS_PER_OSCILLATION`] per period of the mode's fastest oscillation), whatever the
//! time constants: a coil whose `L/(Rc + R)` is a thousand times shorter than the step costs
//! what a slow mode costs. The matrix exponentials are computed once per drive
//! ([`crate::ode::phi::expm`], scaling and squaring).
//!
//! # Events on the exact solution
//! A mode's guards (the stops' penetrations, a linear contact's bracket) are affine in the
//! state. A guard that is positive at the end of a step has crossed; one whose cubic Hermite
//! estimate over the step (values and exact slopes at its ends) has an interior maximum within
//! [`GRAZE_MARGIN`] of its scale below zero is maximised on the exact solution, and has
//! crossed if it is positive there (a grazing trajectory). The first crossing is then located
//! by bisection on the exact solution, through the propagators `e^{h L / 2^j}`, to the event
//! time tolerance of [`Options`], and the step is cut there, as
//! Dormand-Prince cuts its steps; the event lies at the upper end of the final bracket (never
//! before the crossing). The grid makes each step a small fraction of the fastest
//! oscillation, so that a guard has at most one maximum in a step.
//!
//! # Elsewhere
//! A mode that is not affine (a Hertz or Hunt-Crossley contact, a mass stuck on a rigid stop,
//! any mode of a capacitor pair) goes to [`Dopri5`](crate::ode::Dopri5) with its event
//! location, from the switch into it to the switch out of it; a device whose free flight is not
//! affine (a capacitor pair) goes to Dormand-Prince throughout, exactly as it would without
//! this module (the same integrator, the same steps, the same bits).
//!
//! # What the observers see
//! Each exact step is shown to the observer as a [`Step`] whose dense output
//! is the quartic through the exact states at both ends and the midpoint with the exact
//! derivatives at the ends ([`Step::from_ends_and_midpoint`](crate::ode::Step::from_ends_and_midpoint));
//! with the grid above its error is about 1e-9 of the motion, below Dormand-Prince's at the
//! tolerances of the studies. The counters count an exact step as an accepted step with one
//! right-hand-side evaluation.

mod affine;
mod grid;
mod phase;
#[cfg(test)]
mod tests;
mod walk;

pub use grid::{MIN_STEPS_PER_OSCILLATION, MIN_STEPS_PER_PERIOD};
pub use walk::GRAZE_MARGIN;

pub(crate) use affine::AffineMode;
pub(crate) use walk::{cubic_max, Carrier, Engine};

use nalgebra::SVector;

use crate::drive::Sine;
use crate::model::{Driven, Mode, Model};
use crate::ode::{Observer, Options, SolverError, Stats, Step, Steps, Unseen};

/// How a [`SineFlow`] integrates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SineScheme {
    /// Exactly in the affine modes, Dormand-Prince elsewhere (see the module docs).
    Exact,
    /// Dormand-Prince everywhere: the reference the exact scheme is checked against.
    Dopri5,
}

/// The integration of a model under a sine (see the module docs).
pub struct SineFlow<'m, M: Model<N>, const N: usize> {
    engine: Engine<Driven<'m, M, Sine, N>, N>,
}

impl<'m, M: Model<N>, const N: usize> SineFlow<'m, M, N> {
    /// An integrator of `model` under `sine` from `y0` in `mode` at time `t0`, with
    /// Dormand-Prince at relative tolerance `rtol` ([`Model::solver_options`]) where it is not
    /// exact.
    pub fn new(
        model: &'m M,
        sine: Sine,
        t0: f64,
        y0: SVector<f64, N>,
        mode: Mode,
        rtol: f64,
    ) -> Self {
        Self::with(
            model,
            sine,
            t0,
            y0,
            mode,
            model.solver_options(rtol),
            SineScheme::Exact,
        )
    }

    /// As [`SineFlow::new`], with the integrator's options and the scheme given.
    pub fn with(
        model: &'m M,
        sine: Sine,
        t0: f64,
        y0: SVector<f64, N>,
        mode: Mode,
        opts: Options<SVector<f64, N>>,
        scheme: SineScheme,
    ) -> Self {
        Self {
            engine: Engine::new(
                Driven::new(model, sine),
                t0,
                y0,
                mode,
                opts,
                scheme == SineScheme::Exact,
            ),
        }
    }

    /// True when some of the device's modes are integrated exactly (its free flight is
    /// affine and the exact scheme was asked for).
    pub fn is_exact(&self) -> bool {
        self.engine.is_exact()
    }

    /// Current time (s).
    pub fn t(&self) -> f64 {
        self.engine.t()
    }

    /// Current state.
    pub fn y(&self) -> SVector<f64, N> {
        self.engine.z()
    }

    /// Current mode.
    pub fn mode(&self) -> Mode {
        self.engine.mode()
    }

    /// Counters since the start (see the module docs for what an exact step counts).
    pub fn stats(&self) -> Stats {
        self.engine.stats()
    }

    /// Integrates to `t_end` showing nothing (a transient): the steps are the same as
    /// [`SineFlow::integrate`]'s, without building the dense output an observer would see.
    pub fn advance(&mut self, t_end: f64) -> Result<(), SolverError> {
        self.engine.integrate_observed(t_end, &mut Unseen)
    }

    /// Integrates to `t_end`, calling `observer` with every step and the mode over it.
    pub fn integrate<O: FnMut(&Step<SVector<f64, N>>, Mode)>(
        &mut self,
        t_end: f64,
        observer: O,
    ) -> Result<(), SolverError> {
        self.engine.integrate_observed(t_end, &mut Steps(observer))
    }

    /// Integrates to `t_end`, showing `observer` every step and every mode switch.
    pub fn integrate_observed<O: Observer<SVector<f64, N>, Mode>>(
        &mut self,
        t_end: f64,
        observer: &mut O,
    ) -> Result<(), SolverError> {
        self.engine.integrate_observed(t_end, observer)
    }
}
