//! The mirror symmetry x -> -x of a device and the half-period map of its symmetric orbits.
//!
//! A device with the same stop on both sides and a transducer that is odd in x (a capacitor
//! pair, whose two capacitors trade places; a piezoelectric or electromagnetic transducer,
//! whose voltage or current changes sign) is unchanged by the involution
//! S (x, v, e1, e2) = (-x, -v, ...) together with the half-period shift of the drive,
//! a(t + T/2) = -a(t). An orbit is *symmetric* when y(t + T/2) = S y(t). Its period map is
//! then the square of the half-period map H(y) = S phi_{T/2}(y), and the multipliers of P are
//! the squares of those of H (Kuznetsov, section 7.4; di Bernardo et al. 2008, section 2.6).
//! A multiplier of H at -1 is a multiplier of P at +1 that is not a fold: the symmetric orbit
//! loses or gains stability to a pair of mirror-image asymmetric orbits, a symmetry-breaking
//! pitchfork.

use nalgebra::{Complex, SMatrix, SVector};

use crate::model::Model;
use crate::ode::Stats;

use super::{multipliers, Orbit, OrbitError, Parameter, Shooter};

/// Largest scaled distance |S y(T/2) - y(0)| / |y(0)| of an orbit called symmetric: a few
/// hundred times the residual to which orbits are solved, far below the asymmetry of any
/// orbit off the symmetric branch that matters.
pub const SYMMETRY_TOL: f64 = 1e-6;

/// The half-period map of a symmetric orbit: its multipliers, and how far the orbit is from
/// symmetric.
#[derive(Debug, Clone, PartialEq)]
pub struct HalfMap {
    /// Scaled |S y(T/2) - y(0)| / |y(0)| (zero for an exactly symmetric orbit).
    pub defect: f64,
    /// Multipliers of H = S phi_{T/2}, largest modulus first (unused components give 0).
    pub multipliers: Vec<Complex<f64>>,
}

impl<M: Model<N>, const N: usize> Shooter<'_, M, N> {
    /// The scaled distance of an orbit from the mirror image of itself half a period later,
    /// `|S y(T/2) - y(0)| / |y(0)|`; `None` for a device without the symmetry.
    pub fn symmetry_defect(&self, orbit: &Orbit) -> Result<Option<f64>, OrbitError> {
        let Some(s) = self.base.mirror() else {
            return Ok(None);
        };
        let f = &orbit.forcing;
        let (y, _, _) = self
            .advance(f, orbit.phase_rad, orbit.state_n(), 0.5 * f.period_s())
            .map_err(|e| OrbitError::Solver {
                what: "half-period map",
                param: f.freq_hz,
                source: e,
            })?;
        Ok(Some(self.defect(&s, &orbit.state_n(), &y)))
    }

    fn defect(
        &self,
        s: &SMatrix<f64, N, N>,
        y0: &SVector<f64, N>,
        y_half: &SVector<f64, N>,
    ) -> f64 {
        self.norm(&(s * y_half - y0)) / self.norm(y0).max(1e-300)
    }

    /// The half-period map of an orbit of a symmetric device: `None` when the device lacks
    /// the symmetry or the orbit is not symmetric (its defect above [`SYMMETRY_TOL`]).
    pub fn half_map(
        &self,
        orbit: &Orbit,
        stats: &mut Stats,
    ) -> Result<Option<HalfMap>, OrbitError> {
        let Some(s) = self.base.mirror() else {
            return Ok(None);
        };
        let f = &orbit.forcing;
        let lin = self
            .linearise_over(
                f,
                Parameter::Frequency,
                orbit.phase_rad,
                orbit.state_n(),
                0.5 * f.period_s(),
                stats,
            )
            .map_err(|e| OrbitError::Solver {
                what: "half-period map",
                param: f.freq_hz,
                source: e,
            })?;
        let defect = self.defect(&s, &orbit.state_n(), &lin.end);
        if defect > SYMMETRY_TOL {
            return Ok(None);
        }
        let h = self.scaled_monodromy(&(s * lin.monodromy));
        let multipliers = multipliers(&h).ok_or(OrbitError::Eigenvalues {
            what: "half-period map",
            param: f.freq_hz,
        })?;
        Ok(Some(HalfMap {
            defect,
            multipliers,
        }))
    }
}
