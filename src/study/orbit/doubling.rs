//! Orbits of two drive periods, born where a periodic orbit loses its stability by a period
//! doubling (a real multiplier crossing -1).
//!
//! At the doubling the map over two periods, P^2, has the multiplier (-1)^2 = 1 along the flip
//! multiplier's eigenvector v, and a branch of its fixed points splits off the period-1 orbit
//! y1 along v: near the doubling the period-2 orbit's state at the section is y1 + a v + O(a^2),
//! with a growing as the square root of the distance in the parameter (the normal form of the
//! flip, Kuznetsov, "Elements of Applied Bifurcation Theory", 3rd ed., section 4.4). The
//! period-2 orbit is therefore sought by Newton's method on P^2 from y1 + a v for a few
//! amplitudes a ([`DOUBLED_AMPLITUDES`]) until Newton finds a fixed point of P^2 that is not a
//! fixed point of P: the period-1 orbit is one too, and from a seed too close to it Newton
//! returns it.

use nalgebra::{SMatrix, SVector};

use crate::model::Model;
use crate::ode::Stats;

use super::{Forcing, Orbit, OrbitError, Parameter, Shooter};

/// Amplitudes of the seed's step along the flip eigenvector, relative to the scaled norm of
/// the period-1 state, tried in turn: from a few per cent (near the doubling, where the
/// period-2 orbit lies close to the period-1 one) to a fifth (further on).
pub const DOUBLED_AMPLITUDES: [f64; 4] = [0.02, 0.05, 0.1, 0.2];

/// A fixed point of P^2 is taken for a period-1 orbit when one period moves it by less than
/// this relative to its scaled norm: a thousand times the shooting tolerance
/// ([`super::ShootingOptions`]), far below the split of a period-2 orbit even 1e-6 of the
/// parameter past its doubling (where it is of order 1e-3).
pub const DISTINCT_REL: f64 = 1e-6;

/// Inverse-iteration sweeps for the flip eigenvector: with the shift within 1e-8 of the
/// multiplier, each sweep shrinks the other directions by that ratio to the next multiplier.
const INVERSE_SWEEPS: usize = 3;

/// The real eigenvector of the orbit's scaled monodromy for its real multiplier nearest -1,
/// unit length in the scaled coordinates (None when the orbit has no negative real
/// multiplier, or the iteration fails).
pub fn flip_vector<const N: usize>(orbit: &Orbit) -> Option<SVector<f64, N>> {
    let mu = orbit
        .multipliers
        .iter()
        .filter(|m| m.im == 0.0 && m.re < 0.0)
        .min_by(|a, b| (a.re + 1.0).abs().total_cmp(&(b.re + 1.0).abs()))?
        .re;
    eigenvector_near(&orbit.monodromy_n(), mu)
}

/// The real eigenvector of the scaled monodromy `m` for its real multiplier `mu` (or the one
/// nearest it), of unit length, by inverse iteration (None when the iteration fails).
pub(super) fn eigenvector_near<const N: usize>(
    m: &SMatrix<f64, N, N>,
    mu: f64,
) -> Option<SVector<f64, N>> {
    // A shift just off the multiplier keeps the matrix regular.
    let shift = mu * (1.0 + 1e-8);
    let lu = crate::num::dense::Lu::of(&(m - SMatrix::<f64, N, N>::identity() * shift));
    let mut v = SVector::<f64, N>::repeat(1.0);
    for _ in 0..INVERSE_SWEEPS {
        let w = lu.solve(&v)?;
        let n = w.norm();
        if !(n.is_finite() && n > 0.0) {
            return None;
        }
        v = w / n;
    }
    Some(v)
}

impl<M: Model<N>, const N: usize> Shooter<'_, M, N> {
    /// The orbit of two drive periods under `forcing` born at the period doubling of the
    /// period-1 orbit `at_flip` (at or a little past the doubling, at the same or a nearby
    /// drive): Newton's method on P^2 from the section state of `at_flip` moved along its flip
    /// eigenvector (see the module docs), on both sides, for each of [`DOUBLED_AMPLITUDES`].
    /// Returns the first fixed point of P^2 that is not one of P (in its own section, moved
    /// into free flight as [`Shooter::reanchor`] does).
    pub fn period_doubled(
        &self,
        at_flip: &Orbit,
        forcing: &Forcing,
        param: Parameter,
        stats: &mut Stats,
    ) -> Result<Orbit, OrbitError> {
        let invalid = |what: &str| OrbitError::Invalid(format!("period doubling: {what}"));
        if at_flip.periods != 1 {
            return Err(invalid("the orbit at the doubling spans one drive period"));
        }
        let v = flip_vector::<N>(at_flip).ok_or_else(|| invalid("no flip multiplier"))?;
        let y1: SVector<f64, N> = at_flip.state_n();
        let size = self.norm(&y1);
        let mut last = invalid("no seed tried");
        for a in DOUBLED_AMPLITUDES {
            for sign in [1.0, -1.0] {
                let seed = y1 + (v * (sign * a * size)).component_mul(&self.scales());
                let o = match self.solve_periods(forcing, param, at_flip.phase_rad, seed, 2, stats)
                {
                    Ok(o) => o,
                    Err(e) => {
                        last = e;
                        continue;
                    }
                };
                if self.one_period_split(&o, param)? > DISTINCT_REL {
                    return self.section_into_free_flight(o, param, stats);
                }
                last = invalid("Newton returned the period-1 orbit from every seed");
            }
        }
        Err(last)
    }

    /// How far one drive period moves an orbit's section state, relative to its scaled norm
    /// (zero to the shooting tolerance for a period-1 orbit).
    pub fn one_period_split(&self, orbit: &Orbit, param: Parameter) -> Result<f64, OrbitError> {
        let y: SVector<f64, N> = orbit.state_n();
        let end = self
            .period_map(&orbit.forcing, orbit.phase_rad, y)
            .map_err(|e| self.solver_err(param, &orbit.forcing, e))?;
        Ok(self.norm(&(end - y)) / self.norm(&y).max(1e-300))
    }

    /// The orbit with its section moved into free flight when it is not there.
    fn section_into_free_flight(
        &self,
        o: Orbit,
        param: Parameter,
        stats: &mut Stats,
    ) -> Result<Orbit, OrbitError> {
        if self.section_is_free(&o) {
            Ok(o)
        } else {
            self.reanchor(&o, param, stats)
        }
    }
}
