//! A model's free flight split for the exponential integrator of sampled records
//! ([`crate::ode::exponential`], [`crate::study::record`]): `y' = L y + c a(t) + R(y)` off the
//! contacts, with `L` and `c` constant and a small remainder `R`.
//!
//! The exponential Adams-Bashforth step integrates `L` and the linearly interpolated input
//! exactly and extrapolates `R` from its values at past samples, one evaluation of `R` per
//! sample. A model offers its split through [`super::Model::flight`], which hands it to a
//! [`FlightVisitor`] together with the remainder's own type, so that a record's inner loop is
//! compiled for that remainder (the paper's capacitor pair has a closed-form one; a linear
//! transducer's is identically zero) rather than dispatching on it at every sample.

use nalgebra::{SMatrix, SVector};

use super::MAX_OUTPUTS;

/// The linear part of a model's free flight, `y' = L y + c a(t) + R(y)`, and what bounds an
/// exponential step (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct FlightSplit<const N: usize> {
    /// `L`: the free flight linearised about its reference state.
    pub l: SMatrix<f64, N, N>,
    /// `c`: the drive's column.
    pub c: SVector<f64, N>,
    /// True when the remainder is identically zero: the exponential step is then exact for
    /// the linearly interpolated input, whatever the step.
    pub linear: bool,
    /// The largest distance (m) the first mass may be taken from the origin by a step of the
    /// length the split was made for: a nonlinear suspension's stiffness strays from its value
    /// at the reference state farther out. Infinite where only the contacts bound the step.
    pub reach_m: f64,
    /// The first mass's position (m) at the reference state `L` is taken at (a nonlinear
    /// suspension's reference well; zero otherwise).
    pub centre_m: f64,
}

/// The remainder `R(y)` of a free flight split and the model's outputs at the same state: the
/// exponential step's one evaluation per sample.
pub trait Remainder<const N: usize>: Copy {
    /// `R(y)`, with the model's outputs at `y` (in free flight) written into `outputs`.
    fn remainder_and_outputs(
        &self,
        y: &SVector<f64, N>,
        outputs: &mut [f64; MAX_OUTPUTS],
    ) -> SVector<f64, N>;

    /// `R(y)`.
    #[inline(always)]
    fn remainder(&self, y: &SVector<f64, N>) -> SVector<f64, N> {
        let mut outputs = [0.0; MAX_OUTPUTS];
        self.remainder_and_outputs(y, &mut outputs)
    }
}

/// Why a model offers no free flight split.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NoFlight {
    /// The model has none (behind an interface circuit the modes are integrated through their
    /// affine forms, [`super::Model::affine`]).
    Unavailable,
    /// A capacitor pair has no stop on one side, so its free flight is not bounded and could
    /// reach a state only the adaptive integrator's checks catch (a vanishing capacitance, an
    /// electrode).
    UnboundedPair,
    /// A capacitance plus Cp of an area-overlap pair vanishes before a stop is reached.
    CapacitanceVanishes,
}

/// What a study does with a model's free flight split ([`super::Model::flight`]): `visit` is
/// compiled for each remainder type a model hands over.
pub trait FlightVisitor<const N: usize> {
    /// What the study returns.
    type Output;

    /// The model's split and its remainder.
    fn visit<R: Remainder<N>>(self, split: FlightSplit<N>, remainder: R) -> Self::Output;

    /// The model offers no split, for the stated reason.
    fn refused(self, why: NoFlight) -> Self::Output;
}
