//! Exponential Adams-Bashforth stepping on the sample grid of a linearly interpolated input.
//!
//! A system `y' = L y + c a(t) + N(y)` with a constant matrix `L`, an input `a(t)` read by
//! linear interpolation between samples `h` apart, and a remainder `N(y)` that does not
//! depend on time is advanced from sample to sample by the variation-of-constants formula
//!
//! `y(t+h) = e^{hL} y(t) + ∫_0^h e^{(h-s)L} [c a(t+s) + N(y(t+s))] ds`,
//!
//! in which the linear part and the input are integrated **exactly** (the input is linear in
//! `s` over the interval: `a(t+s) = a_k (1 - s/h) + a_{k+1} s/h`), and `N` is replaced by the
//! polynomial through its values at the last `P` samples (the exponential Adams-Bashforth
//! method of order `P`; Hochbruck and Ostermann, "Exponential integrators", Acta Numerica 19,
//! 2010, section 2.5). One step costs one evaluation of `N` and `P + 1` products of an
//! `N x N` matrix with a vector.
//!
//! # Why it is hand-written
//! No Rust crate offers exponential multistep methods, and what makes this one cheap is
//! specific to a sampled input: every step is one sample interval long, so the matrices are
//! computed once per device and sample rate.
//!
//! # What it is for
//! The harvester in free flight driven by a sampled record: `L` is the model linearised
//! about rest, `N` the rest (the capacitances' dependence on x, a few per cent of the linear
//! forces), so the step is set by the smoothness of `N` along the trajectory, not by the
//! 10 kHz content of the input, which the linear part takes exactly. A Runge-Kutta method
//! must resolve that content with all its stages. The method has no error estimate and no
//! event location: its user checks each step (the end-stop guard between samples) and hands
//! the interval to [`crate::ode::Dopri5`] where a check fails.
//!
//! # The matrices
//! With `Z = hL`, `φ_0(Z) = e^Z` and `φ_j(Z) = Σ_k Z^k / (k+j)!`:
//! `∫_0^h e^{(h-s)L} (s/h)^i ds = h i! φ_{i+1}(Z)`. The input weights are
//! `h (φ_1 - φ_2) c` (for `a_k`) and `h φ_2 c` (for `a_{k+1}`); the weight of `N_{k-j}` is
//! `h Σ_i m_ji i! φ_{i+1}(Z)`, where `Σ_i m_ji θ^i` is the Lagrange basis polynomial of node
//! `-j` on the nodes `0, -1, ..., -(P-1)`. The φ functions come from [`crate::ode::phi`], for
//! any norm of `hL`: by their Taylor series where the step resolves the linear dynamics (the
//! paper's devices at 10 us), by the exponential of a block matrix with scaling and squaring
//! where it does not (a coil whose time constant is shorter than the sample interval). The
//! linear part is then still integrated exactly, however stiff: the step is set by the
//! remainder alone.
//!
//! # Dense output
//! The same formula over `[0, θh]` (with `Z = θhL` and the input and the remainder's
//! polynomial read on that span: a factor `θ^i` on the weight of `(s/h)^i`) gives the state
//! inside a step ([`ExpAdams::dense`]), to the order of the step. An energy ledger uses it to
//! integrate the power of each force over a step ([`crate::study::record_ledger`]).

use nalgebra::{SMatrix, SVector};

use crate::ode::phi::{factorial, phi_functions, scaled};

/// Largest Frobenius norm of the scaled `h L` at which a step resolves the linear dynamics
/// (about the bound at which the φ functions' series converge fast, see
/// [`crate::ode::phi`]): the prototypes at 10 us are near 0.1. The step is exact for the
/// linear part at any norm; a nonlinear remainder, extrapolated from its values at past
/// samples, needs resolved motion ([`resolves`]).
pub const RESOLVED_NORM: f64 = 2.0;

/// True when the step `h` resolves the dynamics of `L` (the scaled `h L` has a norm of at most
/// [`RESOLVED_NORM`]; `scale` as in [`ExpAdams::new`]).
pub fn resolves<const N: usize>(l: &SMatrix<f64, N, N>, h: f64, scale: &SVector<f64, N>) -> bool {
    scaled(&(*l * h), scale).norm() <= RESOLVED_NORM
}

/// The exponential Adams-Bashforth method of order `P` for one step length `h` (see the
/// module docs).
// Laid out in order on a 16-byte boundary, the step length last, so that for an even `N`
// every matrix column starts on a 16-byte boundary and the step's products can read their
// weights straight from memory (3 % of a record's instructions, cachegrind, prototype 2 at
// 1e-4 g^2/Hz).
#[derive(Debug, Clone, PartialEq)]
#[repr(C, align(16))]
pub struct ExpAdams<const N: usize, const P: usize> {
    /// `e^{hL}`.
    pub propagator: SMatrix<f64, N, N>,
    /// Weight of the input sample at the start of the step.
    pub input_start: SVector<f64, N>,
    /// Weight of the input sample at the end of the step.
    pub input_end: SVector<f64, N>,
    /// Weights of the remainder at the current sample and the `P - 1` before it (newest
    /// first).
    pub remainder: [SMatrix<f64, N, N>; P],
    /// The span one [`ExpAdams::step`] advances (s): the step, or a part of it for the
    /// dense output ([`ExpAdams::dense`]).
    pub h: f64,
}

/// The last `P` values of the remainder `N`, newest first, and how many of them lie on one
/// smooth stretch of the trajectory.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C, align(16))]
pub struct History<const N: usize, const P: usize> {
    values: [SVector<f64, N>; P],
    valid: usize,
}

impl<const N: usize, const P: usize> Default for History<N, P> {
    fn default() -> Self {
        Self {
            values: [SVector::zeros(); P],
            valid: 0,
        }
    }
}

impl<const N: usize, const P: usize> History<N, P> {
    /// Forgets every value (after a non-smooth event: a mode switch).
    pub fn clear(&mut self) {
        self.valid = 0;
    }

    /// Adds the value at the next sample.
    #[inline]
    pub fn push(&mut self, value: SVector<f64, N>) {
        self.values.copy_within(0..P - 1, 1);
        self.values[0] = value;
        self.valid = (self.valid + 1).min(P);
    }

    /// True when `P` values on one smooth stretch are held.
    #[inline]
    pub fn is_full(&self) -> bool {
        self.valid == P
    }

    /// The values, newest first.
    pub fn values(&self) -> &[SVector<f64, N>; P] {
        &self.values
    }
}

impl<const N: usize, const P: usize> ExpAdams<N, P> {
    /// The method for `y' = L y + c a(t) + N(y)` with step `h`; `scale` holds the
    /// characteristic size of each component (it balances the φ functions, see
    /// [`crate::ode::phi`]). Any `h L` is accepted: a step that does not resolve the linear
    /// dynamics (a coil faster than the sample rate) still integrates them exactly.
    ///
    /// # Panics
    /// If `P` is 0 or above 8, or if a scale is not positive (the caller's errors).
    pub fn new(
        l: &SMatrix<f64, N, N>,
        c: &SVector<f64, N>,
        h: f64,
        scale: &SVector<f64, N>,
    ) -> Self {
        Self::dense(l, c, h, 1.0, scale)
    }

    /// The method's dense output at `theta` (in (0, 1]) of a step `h`: [`ExpAdams::step`] of
    /// the result gives the state `theta h` into the step, from the same state, input samples
    /// and history (the remainder's polynomial evaluated on `[0, theta h]`; see the module
    /// docs). Its `h` is `theta h`. `theta = 1` is [`ExpAdams::new`] (every factor `theta` is
    /// then an exact 1, so the weights are the step's, bit for bit).
    ///
    /// # Panics
    /// As [`ExpAdams::new`], and if `theta` is not in (0, 1].
    pub fn dense(
        l: &SMatrix<f64, N, N>,
        c: &SVector<f64, N>,
        h: f64,
        theta: f64,
        scale: &SVector<f64, N>,
    ) -> Self {
        assert!(theta > 0.0 && theta <= 1.0, "theta {theta} outside (0, 1]");
        assert!((1..=8).contains(&P), "order {P} outside 1..=8");
        // The span integrated, tau = theta h.
        let tau = theta * h;
        let phi = phi_functions(&(*l * tau), P, scale);
        // Over [0, tau] the input is a_k + (a_{k+1} - a_k) theta s/tau, and (s/h)^i is
        // theta^i (s/tau)^i.
        let input_start = (phi[1] - phi[2] * theta) * c * tau;
        let input_end = phi[2] * theta * c * tau;
        let basis = lagrange_monomials::<P>();
        let remainder = std::array::from_fn(|j| {
            let mut b = SMatrix::<f64, N, N>::zeros();
            for (i, m) in basis[j].iter().enumerate() {
                b += phi[i + 1] * (m * theta.powi(i as i32) * factorial(i) * tau);
            }
            b
        });
        Self {
            h: tau,
            propagator: phi[0],
            input_start,
            input_end,
            remainder,
        }
    }

    /// One step from the sample where the state is `y` and the input `a0` to the next, where
    /// the input is `a1`; `history` holds the remainder at this sample and the `P - 1` before.
    // Forced inline: it is a record's inner loop (see `FastFlight::step` in
    // `crate::study::record`).
    #[inline(always)]
    pub fn step(
        &self,
        y: &SVector<f64, N>,
        a0: f64,
        a1: f64,
        history: &History<N, P>,
    ) -> SVector<f64, N> {
        let mut out = self.propagator * y + self.input_start * a0 + self.input_end * a1;
        for (b, n) in self.remainder.iter().zip(&history.values) {
            out += b * n;
        }
        out
    }
}

/// Monomial coefficients of the Lagrange basis on the nodes `0, -1, ..., -(P-1)`:
/// `out[j][i]` is the coefficient of `θ^i` in the polynomial that is 1 at `-j` and 0 at the
/// other nodes.
fn lagrange_monomials<const P: usize>() -> [[f64; P]; P] {
    std::array::from_fn(|j| {
        let mut poly = [0.0; P];
        poly[0] = 1.0;
        let mut degree = 0;
        let mut denom = 1.0;
        for n in 0..P {
            if n == j {
                continue;
            }
            // Multiply by (θ + n).
            let node = n as f64;
            for i in (0..=degree).rev() {
                poly[i + 1] += poly[i];
                poly[i] *= node;
            }
            degree += 1;
            denom *= node - j as f64;
        }
        poly.map(|c| c / denom)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lagrange_basis_interpolates_the_nodes() {
        let b = lagrange_monomials::<4>();
        for (j, coeffs) in b.iter().enumerate() {
            for n in 0..4 {
                let theta = -(n as f64);
                let v: f64 = coeffs
                    .iter()
                    .enumerate()
                    .map(|(i, c)| c * theta.powi(i as i32))
                    .sum();
                let want = if n == j { 1.0 } else { 0.0 };
                assert!((v - want).abs() < 1e-12, "basis {j} at node {n}: {v}");
            }
        }
    }

    #[test]
    fn exact_for_a_linear_system_with_a_linear_input() {
        // y'' = -w^2 y + a(t), a linear between samples, N = 0: the step is exact, so it
        // matches the closed form of a harmonic oscillator driven by a ramp.
        let w = 2.0 * std::f64::consts::PI * 1000.0;
        let l = SMatrix::<f64, 2, 2>::new(0.0, 1.0, -w * w, 0.0);
        let c = SVector::<f64, 2>::new(0.0, 1.0);
        let h = 1e-5;
        let m = ExpAdams::<2, 3>::new(&l, &c, h, &SVector::<f64, 2>::new(1.0, w));
        let (a0, a1) = (2.0, 5.0);
        let y0 = SVector::<f64, 2>::new(1e-3, 0.3);
        let y1 = m.step(&y0, a0, a1, &History::default());
        // Closed form: particular solution of y'' + w^2 y = a0 + r s (r = (a1-a0)/h) is
        // (a0 + r s)/w^2; the homogeneous part matches the initial state.
        let r = (a1 - a0) / h;
        let (c1, c2) = (y0[0] - a0 / (w * w), (y0[1] - r / (w * w)) / w);
        let s = h;
        let x = c1 * (w * s).cos() + c2 * (w * s).sin() + (a0 + r * s) / (w * w);
        let v = -c1 * w * (w * s).sin() + c2 * w * (w * s).cos() + r / (w * w);
        assert!((y1[0] - x).abs() < 1e-12 * x.abs(), "{} vs {x}", y1[0]);
        assert!((y1[1] - v).abs() < 1e-12 * v.abs(), "{} vs {v}", y1[1]);
    }

    #[test]
    fn exact_for_a_stiff_linear_system_with_a_linear_input() {
        // A coil-like mode y' = (a(t) - y) / tau with tau = 1.25 us, eight times shorter than
        // the 10 us step (the electromagnetic example): the step is exact for the linear input,
        // so it matches the closed form y(s) = (y0 - a0 + r tau) e^{-s/tau} + a0 + r (s - tau).
        let tau = 1.25e-6;
        let l = SMatrix::<f64, 1, 1>::new(-1.0 / tau);
        let c = SVector::<f64, 1>::new(1.0 / tau);
        let h = 1e-5;
        let m = ExpAdams::<1, 3>::new(&l, &c, h, &SVector::<f64, 1>::new(1.0));
        let (a0, a1) = (2.0, -3.0);
        let r = (a1 - a0) / h;
        for y0 in [0.0, 5.0, -40.0] {
            let got = m.step(&SVector::<f64, 1>::new(y0), a0, a1, &History::default())[0];
            let want = (y0 - a0 + r * tau) * (-h / tau).exp() + a0 + r * (h - tau);
            assert!((got - want).abs() < 1e-12 * want.abs(), "{got} vs {want}");
        }
    }

    #[test]
    fn order_p_on_a_polynomial_remainder() {
        // y' = -y + N(t) with N a polynomial of degree P-1 in t, fed through the history: the
        // method integrates it exactly (N at the nodes determines the polynomial).
        let l = SMatrix::<f64, 1, 1>::new(-50.0);
        let c = SVector::<f64, 1>::zeros();
        let h = 1e-3;
        let m = ExpAdams::<1, 3>::new(&l, &c, h, &SVector::<f64, 1>::new(1.0));
        let n = |t: f64| 1.0 + 30.0 * t - 400.0 * t * t;
        let mut hist = History::<1, 3>::default();
        for k in [2.0, 1.0, 0.0] {
            hist.push(SVector::<f64, 1>::new(n(-k * h)));
        }
        assert!(hist.is_full());
        let y0 = SVector::<f64, 1>::new(0.2);
        let y1 = m.step(&y0, 0.0, 0.0, &hist);
        // Reference: Gauss-Legendre quadrature (exact for this smooth integrand to rounding)
        // of e^{-50 (h-s)} N(s) plus e^{-50h} y0.
        let (x, w) = (
            [
                -0.906_179_845_938_664,
                -0.538_469_310_105_683,
                0.0,
                0.538_469_310_105_683,
                0.906_179_845_938_664,
            ],
            [
                0.236_926_885_056_189,
                0.478_628_670_499_366,
                0.568_888_888_888_889,
                0.478_628_670_499_366,
                0.236_926_885_056_189,
            ],
        );
        let integral: f64 = x
            .iter()
            .zip(w)
            .map(|(xi, wi)| {
                let s = 0.5 * h * (xi + 1.0);
                wi * 0.5 * h * (-50.0 * (h - s)).exp() * n(s)
            })
            .sum();
        let want = (-50.0 * h).exp() * 0.2 + integral;
        assert!((y1[0] - want).abs() < 1e-13, "{} vs {want}", y1[0]);
    }

    #[test]
    fn dense_output_is_the_step_over_part_of_the_interval() {
        // theta = 1 is the step itself, bit for bit.
        let l = SMatrix::<f64, 2, 2>::new(0.0, 1.0, -4.0e6, -300.0);
        let c = SVector::<f64, 2>::new(0.0, 1.0);
        let scale = SVector::<f64, 2>::new(1e-6, 2e-3);
        let h = 1e-5;
        let step = ExpAdams::<2, 3>::new(&l, &c, h, &scale);
        assert_eq!(ExpAdams::dense(&l, &c, h, 1.0, &scale), step);
        // With N = 0 and a linear input both are exact, so the dense output at theta is the
        // step of length theta h to the input's value there.
        let theta = 0.3;
        let part = ExpAdams::<2, 3>::dense(&l, &c, h, theta, &scale);
        let short = ExpAdams::<2, 3>::new(&l, &c, theta * h, &scale);
        let empty = History::<2, 3>::default();
        let y0 = SVector::<f64, 2>::new(3e-7, -1e-3);
        let (a0, a1) = (20.0, -50.0);
        let got = part.step(&y0, a0, a1, &empty);
        let want = short.step(&y0, a0, a0 + theta * (a1 - a0), &empty);
        for i in 0..2 {
            assert!(
                (got[i] - want[i]).abs() < 1e-12 * scale[i],
                "{got:?} vs {want:?}"
            );
        }
        // A remainder that is a polynomial of degree P - 1 in t is extrapolated exactly, so
        // the dense output is exact inside the interval too.
        let l1 = SMatrix::<f64, 1, 1>::new(-50.0);
        let c1 = SVector::<f64, 1>::new(0.0);
        let h = 1e-3;
        let part = ExpAdams::<1, 3>::dense(&l1, &c1, h, theta, &SVector::<f64, 1>::new(1.0));
        let n = |t: f64| 1.0 + 30.0 * t - 400.0 * t * t;
        let mut hist = History::<1, 3>::default();
        for k in [2.0, 1.0, 0.0] {
            hist.push(SVector::<f64, 1>::new(n(-k * h)));
        }
        let got = part.step(&SVector::<f64, 1>::new(0.2), 0.0, 0.0, &hist)[0];
        // The integrand is a polynomial times an exponential that varies by 1.5 % over the
        // span: 3-point Gauss-Legendre is exact to about 1e-12 of it.
        let tau = theta * h;
        let integral: f64 = crate::ode::GAUSS_LEGENDRE_3
            .iter()
            .map(|&(x, w)| w * tau * (-50.0 * (tau - x * tau)).exp() * n(x * tau))
            .sum();
        let want = (-50.0 * tau).exp() * 0.2 + integral;
        assert!((got - want).abs() < 1e-12, "{got} vs {want}");
    }
}
