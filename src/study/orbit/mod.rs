//! Periodic orbits of the harvester under a sinusoidal drive, by shooting on the period map,
//! with their Floquet multipliers.
//!
//! # The period map and its section
//! For a drive a(t) = sqrt(2) a_rms sin(2 pi f t + phi), the period map P takes the state at
//! drive phase phi to the state one drive period T = 1/f later, integrated by the
//! event-locating [`Dopri5`] (through its public API: a new integrator per evaluation, so that
//! an evaluation never depends on the ones before). A periodic orbit is a fixed point
//! P(y) = y, found by Newton's method.
//!
//! The section (the drive phase phi at which the orbit is cut) must lie in free flight: the
//! end-stop force switches on at the stop, so a section that cuts the orbit in contact would
//! make P non-differentiable there and Newton would stall. Each [`Orbit`] therefore carries its
//! own section phase, and [`Shooter::reanchor`] moves it to the drive phase where x crosses
//! zero upwards (the orbit's fastest point, as far from both stops as it gets).
//!
//! Newton works in scaled coordinates z = y / s with s = [`Model::scales`] (x ~ xmax,
//! v ~ w0 xmax, charges ~ C0 Vb xmax / x0), so that every component is of order one.
//!
//! # The monodromy matrix
//! The monodromy matrix M = dP/dy is computed by the **variational equations** integrated
//! alongside the state: Phi' = J(y) Phi with Phi(0) = I, J the Jacobian of the mode's
//! right-hand side ([`Model::jacobian`]), and at every contact entry and exit the
//! saltation matrix
//!
//! S = I + (f+ - f-) n^T / (n . f-),
//!
//! with f- and f+ the vector fields before and after the switch and n the gradient of the guard
//! that fired (the end-stop damper switches on at the stop, so the acceleration jumps by
//! b_im v / m there and S is not the identity). The sensitivity to the continuation parameter,
//! dP/dp, rides along as a fifth column (with the end-time term f(y(T)) dT/dp for the
//! frequency). Why this choice rather than finite differences through the event-located
//! integration: one integration of the 24-dimensional system gives M and dP/dp to the
//! integrator's tolerance, whereas central differences need eight integrations and are accurate
//! only to about rtol/eps. Finite differences are kept as the check
//! ([`Shooter::monodromy_fd`]); the tests compare the two on impacting orbits.
//!
//! The Floquet multipliers are the eigenvalues of M; an orbit is stable when every multiplier
//! lies inside the unit circle.
//!
//! # Files
//! This file holds what an orbit is (its drive, settings, errors and summary); `shooter.rs`
//! the period map and Newton's method on it, `variational.rs` the variational equations with
//! their saltation matrices, `period_sums.rs` the sums over one period behind an
//! [`OrbitSummary`], `doubling.rs` the orbits of two drive periods born where an orbit
//! loses stability by a period doubling, `fold.rs` a fold found directly from a fold of a
//! nearby system, and `symmetry.rs` the mirror symmetry x -> -x with the half-period map
//! of symmetric orbits.
//!
//! [`Dopri5`]: crate::ode::Dopri5
//! [`Model::scales`]: crate::model::Model::scales
//! [`Model::jacobian`]: crate::model::Model::jacobian

use nalgebra::{Complex, DMatrix, DVector, SMatrix, SVector};
use thiserror::Error;

use crate::drive::Sine;
use crate::model::Layout;
use crate::ode::SolverError;
use crate::study::mass_peaks::MassPeaks;

mod doubling;
mod fold;
mod period_sums;
mod reach;
mod shooter;
mod symmetry;
mod variational;

pub use doubling::{flip_vector, DISTINCT_REL, DOUBLED_AMPLITUDES};
pub use fold::{FoldOrbit, FoldSearch};
pub use reach::ContactReach;
pub use shooter::{Linearised, Shooter};
pub use symmetry::{HalfMap, SYMMETRY_TOL};

pub use crate::drive::Parameter;

/// A sinusoidal drive: frequency and RMS acceleration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Forcing {
    /// Frequency (Hz).
    pub freq_hz: f64,
    /// RMS acceleration (g).
    pub accel_rms_g: f64,
}

impl Forcing {
    /// The value of a parameter.
    pub fn get(&self, p: Parameter) -> f64 {
        match p {
            Parameter::Frequency => self.freq_hz,
            Parameter::Amplitude => self.accel_rms_g,
        }
    }

    /// The same drive with one parameter changed.
    pub fn with(&self, p: Parameter, value: f64) -> Self {
        let mut f = *self;
        match p {
            Parameter::Frequency => f.freq_hz = value,
            Parameter::Amplitude => f.accel_rms_g = value,
        }
        f
    }

    /// Drive period (s).
    pub fn period_s(&self) -> f64 {
        1.0 / self.freq_hz
    }

    /// The sine with drive phase `phase_rad` at t = 0.
    pub fn sine(&self, phase_rad: f64) -> Sine {
        Sine {
            phase_rad,
            ..Sine::from_rms_g(self.accel_rms_g, self.freq_hz)
        }
    }
}

/// Options of the shooting method (a solver: Newton on the period map).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShootingOptions {
    /// Integrator relative tolerance (absolute tolerances are `rtol` times the state scales).
    pub rtol: f64,
    /// An orbit is accepted when |P(y) - y| / |y| (scaled, plain period map) is below this.
    pub residual_tol: f64,
    /// Largest number of Newton iterations.
    pub max_newton: usize,
}

impl Default for ShootingOptions {
    /// rtol 1e-10: the orbit is then accurate to about 1e-9 (the global error of the
    /// integration is some 15 rtol relative), and Newton drives the residual of the period map
    /// itself below 5e-10 (on smooth stretches of a branch it reaches 1e-14; near grazing,
    /// where the event times make the map less smooth, the noise of the map is near 1e-10).
    fn default() -> Self {
        Self {
            rtol: 1e-10,
            residual_tol: 5e-10,
            max_newton: 12,
        }
    }
}

impl ShootingOptions {
    /// Half the integrator tolerance (for convergence checks).
    pub fn halved(&self) -> Self {
        Self {
            rtol: 0.5 * self.rtol,
            ..*self
        }
    }
}

/// Failures of shooting and continuation, each with the parameter value last reached.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum OrbitError {
    /// The integrator failed.
    #[error("integration failed at {what} = {param}: {source}")]
    Solver {
        /// What the parameter is.
        what: &'static str,
        /// Parameter value.
        param: f64,
        /// The integrator's error.
        source: SolverError,
    },
    /// Newton's method did not reach the residual tolerance.
    #[error("Newton did not converge at {what} = {param} after {iterations} iterations (residual {residual:e})")]
    NoConvergence {
        /// What the parameter is.
        what: &'static str,
        /// Parameter value.
        param: f64,
        /// Iterations made.
        iterations: usize,
        /// Last scaled residual |P(y) - y| / |y|.
        residual: f64,
    },
    /// The Floquet multipliers could not be computed (the Schur iteration failed).
    #[error("no eigenvalues of the monodromy matrix at {what} = {param}")]
    Eigenvalues {
        /// What the parameter is.
        what: &'static str,
        /// Parameter value.
        param: f64,
    },
    /// The continuation's step fell below its minimum: the branch cannot be followed further.
    #[error("the branch cannot be continued past {what} = {last_param} (step below {ds_min:e})")]
    Stalled {
        /// What the parameter is.
        what: &'static str,
        /// The last parameter value reached on the branch.
        last_param: f64,
        /// The smallest step allowed.
        ds_min: f64,
    },
    /// Past a grazing that adds a strike, where a branch of orbits of one period ends, the
    /// only orbit found is one of several drive periods: the continuation follows orbits of
    /// one period and stops there.
    #[error(
        "the branch of one-period orbits ends at {what} = {last_param}: past it the only orbit \
         found has {periods} drive periods (at {what} = {param})"
    )]
    OtherPeriod {
        /// What the parameter is.
        what: &'static str,
        /// The last parameter value reached on the branch.
        last_param: f64,
        /// The least number of drive periods of the orbit found.
        periods: usize,
        /// Its parameter value.
        param: f64,
    },
    /// The continuation used its whole budget of points inside the range.
    #[error("the continuation used all {points} points and stopped at {what} = {last_param}")]
    TooManyPoints {
        /// What the parameter is.
        what: &'static str,
        /// The last parameter value reached.
        last_param: f64,
        /// The budget.
        points: usize,
    },
    /// Bad input.
    #[error("invalid input: {0}")]
    Invalid(String),
    /// The device's parts do not assemble into a model.
    #[error(transparent)]
    Device(#[from] crate::physics::harvester::AssemblyError),
}

/// Whole-period measures of an orbit.
#[derive(Debug, Clone, PartialEq)]
pub struct OrbitSummary {
    /// RMS of the model's first output over the period (for a transducer with its loads, the
    /// voltage of load 1; behind a circuit, the storage voltage) (V).
    pub v1_rms_v: f64,
    /// RMS of the model's second output (load 2's voltage; behind a circuit, the element's).
    pub v2_rms_v: f64,
    /// Mean power of the loads the outputs are across (W).
    pub p_total_w: f64,
    /// Per output, its mean and RMS over the period, in the units of
    /// [`Layout::outputs`].
    pub outputs: Vec<OutputStats>,
    /// Largest |x| over the period (m), at a zero of v located on the dense output.
    pub x_max_m: f64,
    /// Largest x (m).
    pub x_upper_m: f64,
    /// Smallest x (m).
    pub x_lower_m: f64,
    /// Each mass's largest |x| and |v| over the period for a model of several masses (at the
    /// ends and the Gauss-Legendre nodes of the steps, and at each impact); none for one mass.
    pub mass_peaks: MassPeaks,
    /// Fraction of the period past a stop.
    pub contact_fraction: f64,
    /// Impacts per period: contact entries and rebounds off rigid stops.
    pub impacts: u32,
    /// The largest speed at which the mass strikes each side's rigid stop (upper, lower; m/s),
    /// zero where it does not: a rigid stop is never penetrated, so this, not the largest
    /// displacement, says how deep an orbit is past grazing.
    pub impact_speed_m_s: [f64; 2],
    /// How far the orbit reaches towards each of the model's contacts (those between two
    /// masses too), and the speed at which it strikes each rigid one.
    pub contact_reach: ContactReach,
    /// Time after the section at which x first crosses zero upwards (s), if it does.
    pub upcrossing_s: Option<f64>,
}

/// One output's mean and RMS over a period.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OutputStats {
    /// Mean.
    pub mean: f64,
    /// Root mean square.
    pub rms: f64,
}

impl OrbitSummary {
    /// The summary of a period's sums for a model's layout.
    fn of(layout: &Layout, acc: &period_sums::Sums, period: f64) -> Self {
        Self::from_integrals(
            layout,
            &acc.squares,
            &acc.integrals,
            period,
            Extent {
                x_upper_m: acc.x_upper,
                x_lower_m: acc.x_lower,
                mass_peaks: acc.mass_peaks,
                contact_fraction: acc.contact_time / period,
                impacts: acc.impacts,
                impact_speed_m_s: [acc.impact_speed[0], acc.impact_speed[1]],
                contact_reach: acc.reach,
                upcrossing_s: acc.upcrossing,
            },
        )
    }

    /// The summary of an orbit of `period` (s) from the integrals over it of each output's
    /// square and of itself, and how far it reaches.
    pub(crate) fn from_integrals(
        layout: &Layout,
        squares: &[f64],
        integrals: &[f64],
        period: f64,
        extent: Extent,
    ) -> Self {
        let outputs: Vec<OutputStats> = squares
            .iter()
            .zip(integrals)
            .map(|(sq, int)| OutputStats {
                mean: int / period,
                rms: (sq / period).sqrt(),
            })
            .collect();
        let rms = |i: usize| outputs.get(i).map_or(0.0, |o| o.rms);
        let p_total_w = layout.load_power(squares, integrals, period);
        Self {
            v1_rms_v: rms(0),
            v2_rms_v: rms(1),
            p_total_w,
            outputs,
            x_max_m: extent.x_upper_m.max(-extent.x_lower_m),
            x_upper_m: extent.x_upper_m,
            x_lower_m: extent.x_lower_m,
            mass_peaks: extent.mass_peaks,
            contact_fraction: extent.contact_fraction,
            impacts: extent.impacts,
            impact_speed_m_s: extent.impact_speed_m_s,
            contact_reach: extent.contact_reach,
            upcrossing_s: extent.upcrossing_s,
        }
    }
}

/// How far an orbit reaches over its period (the measures of [`OrbitSummary`] besides its
/// outputs').
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Extent {
    pub(crate) x_upper_m: f64,
    pub(crate) x_lower_m: f64,
    pub(crate) mass_peaks: MassPeaks,
    pub(crate) contact_fraction: f64,
    pub(crate) impacts: u32,
    pub(crate) impact_speed_m_s: [f64; 2],
    pub(crate) contact_reach: ContactReach,
    pub(crate) upcrossing_s: Option<f64>,
}

/// A periodic orbit with its stability.
#[derive(Debug, Clone, PartialEq)]
pub struct Orbit {
    /// The drive.
    pub forcing: Forcing,
    /// Drive phase at the section (rad).
    pub phase_rad: f64,
    /// Drive periods in the orbit's period (1, or 2 for an orbit born at a period doubling):
    /// the monodromy, multipliers, residual and summary are those of this many periods.
    pub periods: usize,
    /// State at the section (the model's components, [`crate::model::Layout`]).
    pub state: DVector<f64>,
    /// Monodromy matrix in scaled coordinates (z = y / scales).
    pub monodromy: DMatrix<f64>,
    /// Floquet multipliers, largest modulus first (a state component the model leaves
    /// unused contributes a multiplier 0).
    pub multipliers: Vec<Complex<f64>>,
    /// |P(y) - y| / |y| of the plain period map (scaled coordinates).
    pub residual: f64,
    /// Newton iterations used.
    pub iterations: usize,
    /// Measures over the orbit's whole period (`periods` drive periods).
    pub summary: OrbitSummary,
}

impl Orbit {
    /// The state at the section as a model's state of dimension `N`.
    pub fn state_n<const N: usize>(&self) -> SVector<f64, N> {
        SVector::<f64, N>::from_column_slice(self.state.as_slice())
    }

    /// The scaled monodromy as a matrix of dimension `N`.
    pub fn monodromy_n<const N: usize>(&self) -> SMatrix<f64, N, N> {
        SMatrix::<f64, N, N>::from_column_slice(self.monodromy.as_slice())
    }

    /// Largest modulus of the multipliers off the neutral band ([`is_neutral`]; 0 when
    /// there are none).
    pub fn max_multiplier_abs(&self) -> f64 {
        leading_abs(&self.multipliers)
    }

    /// True when every multiplier off the neutral band lies inside the unit circle.
    pub fn is_stable(&self) -> bool {
        self.max_multiplier_abs() < 1.0
    }

    /// True when the multiplier of largest modulus is real and below -1: the orbit has lost
    /// its stability by a period doubling (a flip).
    pub fn is_flip_unstable(&self) -> bool {
        self.multipliers
            .iter()
            .find(|m| !is_neutral(**m, false))
            .is_some_and(|m| m.im.abs() < NEUTRAL_BAND && m.re < -1.0)
    }

    /// The orbit's period (s): `periods` drive periods.
    pub fn period_s(&self) -> f64 {
        self.periods as f64 * self.forcing.period_s()
    }

    /// True when the orbit touches a stop.
    pub fn is_impacting(&self) -> bool {
        self.summary.impacts > 0
    }

    /// The parameter's value.
    pub fn param(&self, p: Parameter) -> f64 {
        self.forcing.get(p)
    }

    /// prod (mu_i - 1) over the multipliers off the neutral band, real: changes sign where a
    /// real multiplier crosses +1.
    pub fn det_minus_one(&self) -> f64 {
        shifted_product(&self.multipliers, -1.0, false)
    }

    /// prod (mu_i + 1) over the multipliers off the neutral band, real: changes sign where a
    /// real multiplier crosses -1.
    pub fn det_plus_one(&self) -> f64 {
        shifted_product(&self.multipliers, 1.0, false)
    }

    /// Number of multipliers outside the unit circle (off the neutral band).
    pub fn unstable_count(&self) -> usize {
        self.multipliers
            .iter()
            .filter(|m| !is_neutral(**m, false) && m.norm() > 1.0)
            .count()
    }
}

/// Half-width of the band about 1 in which a real multiplier is neutral ([`is_neutral`]):
/// ten times the default shooting tolerance ([`ShootingOptions`]); the neutral multipliers of
/// a bridge that never conducts, whose element charge the flow conserves, lie within 5e-11
/// of 1 there.
pub const NEUTRAL_BAND: f64 = 1e-9;

/// Whether a multiplier is neutral: real and within [`NEUTRAL_BAND`] of 1 (of +1 or -1 for a
/// half map's, `half`). A quantity the flow conserves (a circuit element's charge while its
/// bridge never conducts) gives a whole family of orbits and a multiplier of exactly 1 that
/// decides neither stability nor an event; a multiplier that crosses 1 as a parameter moves
/// lies in the band over a stretch of about `2 NEUTRAL_BAND / |dmu/dp|` of the branch, where
/// its event is located to that width.
///
/// ```
/// use endstop::study::orbit::{is_neutral, NEUTRAL_BAND};
/// use nalgebra::Complex;
///
/// let near_one = Complex::new(1.0 + 0.5 * NEUTRAL_BAND, 0.0);
/// assert!(is_neutral(near_one, false));
/// // -1 is neutral only for a half map (a symmetric orbit's), whose square is the period map.
/// assert!(!is_neutral(Complex::new(-1.0, 0.0), false));
/// assert!(is_neutral(Complex::new(-1.0, 0.0), true));
/// // A complex pair on the unit circle is not: it decides a Neimark-Sacker bifurcation.
/// assert!(!is_neutral(Complex::from_polar(1.0, 0.1), false));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn is_neutral(m: Complex<f64>, half: bool) -> bool {
    let near = |c: f64| (m.re - c).abs() < NEUTRAL_BAND;
    m.im.abs() < NEUTRAL_BAND && (near(1.0) || (half && near(-1.0)))
}

/// The largest modulus of the multipliers `ms` (largest first) off the neutral band; 0 when
/// there are none.
pub fn leading_abs(ms: &[Complex<f64>]) -> f64 {
    ms.iter()
        .find(|m| !is_neutral(**m, false))
        .map_or(0.0, |m| m.norm())
}

/// prod (mu_i + shift) over the multipliers off the neutral band (of a half map's, `half`),
/// real part.
pub fn shifted_product(ms: &[Complex<f64>], shift: f64, half: bool) -> f64 {
    ms.iter()
        .filter(|m| !is_neutral(**m, half))
        .fold(Complex::new(1.0, 0.0), |acc, &m| acc * (m + shift))
        .re
}

/// Chord steps on the plain period map after Newton has converged on the variational one.
pub const CHORD_STEPS: usize = 4;

/// The eigenvalues of a monodromy matrix, largest modulus first (None if the Schur iteration
/// fails).
pub fn multipliers<const N: usize>(m: &SMatrix<f64, N, N>) -> Option<Vec<Complex<f64>>> {
    let mut out = crate::num::dense::eigenvalues(m)?;
    out.sort_by(|a, b| b.norm().total_cmp(&a.norm()));
    Some(out)
}
