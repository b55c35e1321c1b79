//! The grid of the exact steps: its step, a whole fraction of the drive period fine enough for
//! every affine mode's fastest oscillation, and each affine mode's propagators on it.

use nalgebra::SMatrix;

use crate::ode::phi::expm_n;

use super::affine::{fastest_oscillation, AffineMode};

/// Fewest grid steps per drive period.
pub const MIN_STEPS_PER_PERIOD: usize = 64;

/// Fewest grid steps per period of the fastest oscillation of an affine mode (the imaginary
/// part of an eigenvalue of its `L`).
pub const MIN_STEPS_PER_OSCILLATION: usize = 32;

/// The propagators of one affine mode on the grid: `e^{hL}` and `e^{h L / 2^j}`
/// (computed when first needed).
#[derive(Debug, Clone)]
pub(super) struct Propagators<const N: usize> {
    /// `e^{hL}`.
    pub(super) step: SMatrix<f64, N, N>,
    /// `dyadic[j - 1] = e^{h L / 2^j}`.
    dyadic: Vec<SMatrix<f64, N, N>>,
    l: SMatrix<f64, N, N>,
    h: f64,
}

impl<const N: usize> Propagators<N> {
    /// The propagators of the mode of matrix `l` on the grid of step `h`.
    pub(super) fn new(l: &SMatrix<f64, N, N>, h: f64) -> Self {
        Self {
            step: expm_n(&(l * h)),
            dyadic: Vec::new(),
            l: *l,
            h,
        }
    }

    /// `e^{h L / 2^j}`, `j >= 1`.
    pub(super) fn dyadic(&mut self, j: usize) -> &SMatrix<f64, N, N> {
        while self.dyadic.len() < j {
            let k = self.dyadic.len() + 1;
            let m = expm_n(&(self.l * (self.h * 0.5f64.powi(k as i32))));
            self.dyadic.push(m);
        }
        &self.dyadic[j - 1]
    }
}

/// The grid step of a model under its drive: [`MIN_STEPS_PER_PERIOD`] per period at least,
/// and [`MIN_STEPS_PER_OSCILLATION`] per period of the fastest oscillation of its affine
/// modes, a whole number per drive period; with that number.
pub(super) fn grid_step<const N: usize>(
    period: f64,
    modes: &[AffineMode<N>],
    unused: &[usize],
) -> (f64, usize) {
    let mut fastest = 0.0f64;
    for m in modes {
        fastest = fastest.max(fastest_oscillation(&m.l, unused));
    }
    let per_oscillation =
        (period * fastest / (2.0 * std::f64::consts::PI) * MIN_STEPS_PER_OSCILLATION as f64).ceil();
    let steps = (MIN_STEPS_PER_PERIOD as f64).max(per_oscillation);
    (period / steps, steps as usize)
}
