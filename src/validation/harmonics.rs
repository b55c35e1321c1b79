//! Fourier coefficients of a periodic orbit, integrated on the integrator's own dense output:
//! what a frequency-domain reference (a closed form's phasor, a harmonic-balance amplitude) is
//! compared with.

use nalgebra::Complex;

use crate::ode::{SolverError, GAUSS_LEGENDRE_3};
use nalgebra::SVector;

use crate::model::Model;
use crate::study::orbit::{Orbit, Shooter};

/// The first Fourier coefficient of `f(y(t))` over one period of `orbit`, referred to the
/// drive's phase: `c = (2/T) int_0^T f(y(t)) e^{-j (w t + phi)} dt`, with the drive
/// `a(t) = A sin(w t + phi)` of the orbit's section, so that `f ~ Re(c e^{j (w t + phi)})` and
/// `|c|` is the amplitude of the fundamental.
///
/// A response whose phasor is `H` per unit acceleration (`f = Re(H A e^{j(wt + phi)})` for the
/// drive `Re(A e^{j(wt + phi)})`) therefore has `c = -j H A` under the sine drive, i.e.
/// `H = j c / A`.
///
/// The integral is the 3-point Gauss-Legendre rule on every accepted step's dense output (the
/// integrator's steps are at most a fiftieth of the natural period, so the rule's error on
/// the fundamental is below 1e-10 relative).
pub fn first_harmonic<M: Model<N>, const N: usize>(
    shooter: &Shooter<'_, M, N>,
    orbit: &Orbit,
    f: impl Fn(&SVector<f64, N>) -> f64,
) -> Result<Complex<f64>, SolverError> {
    let forcing = &orbit.forcing;
    let w = 2.0 * std::f64::consts::PI * forcing.freq_hz;
    let period = forcing.period_s();
    let mut sum = Complex::new(0.0, 0.0);
    shooter.flow(
        forcing,
        orbit.phase_rad,
        orbit.state_n(),
        period,
        |st, _| {
            for (x, wt) in GAUSS_LEGENDRE_3 {
                let t = st.t0 + x * st.h;
                let arg = w * t + orbit.phase_rad;
                sum += Complex::new(arg.cos(), -arg.sin()) * (wt * st.h * f(&st.at_theta(x)));
            }
        },
    )?;
    Ok(sum * (2.0 / period))
}
