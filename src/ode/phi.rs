//! The φ functions of exponential integrators for a matrix of any norm:
//! `φ_0(Z) = e^Z` and `φ_j(Z) = Σ_k Z^k / (k+j)!`, so that
//! `∫_0^1 e^{(1-s)Z} s^{j-1} / (j-1)! ds = φ_j(Z)`.
//!
//! # Two ways, one answer
//! * A step that resolves the linear dynamics (a scaled norm of `Z` at most
//!   [`SERIES_MAX_NORM`]) sums the Taylor series to [`SERIES_TERMS`] terms: the truncation is far
//!   below rounding there, and this is the arithmetic every recorded result of the paper's
//!   devices was computed with.
//! * Beyond it (a coil whose `L/(Rc + R)` is shorter than the step, an interface circuit's
//!   storage mode) the series would need many more terms and cancel; the φ functions are then
//!   read off the exponential of the block matrix
//!
//!   ```text
//!   W = | Z  I  0 .. 0 |        e^W = | φ_0(Z)  φ_1(Z)  φ_2(Z) .. φ_p(Z) |
//!       | 0  0  I .. 0 |              |   0       I       I    ..   .    |
//!       | .        .  I |              |   .                         .    |
//!       | 0  0  0 .. 0 |              |   0       0       0    ..   I    |
//!   ```
//!
//!   (Saad, SIAM J. Numer. Anal. 29, 1992, Proposition 2.1, in its block form; Al-Mohy and
//!   Higham, SIAM J. Sci. Comput. 33, 2011, Theorem 2.1), computed by `nalgebra`'s
//!   [`Matrix::exp`](nalgebra::Matrix::exp): Padé approximants with scaling and squaring
//!   (Al-Mohy and Higham, SIAM J. Matrix Anal. Appl. 31, 2009), accurate for any norm.
//!
//! Both are evaluated on `D^-1 Z D`, with `D` the diagonal of the state's characteristic
//! scales, so that the norm measures the dynamics, not the units; the tests check that the two
//! agree where both apply, and the block exponential against closed forms of stiff matrices.

use nalgebra::{DMatrix, Matrix4, Matrix6, SMatrix, SVector};

/// Terms of the Taylor series (see the module docs).
pub const SERIES_TERMS: usize = 40;

/// Largest Frobenius norm of the scaled `Z` summed by the series; beyond it the block
/// exponential is used (see the module docs).
pub const SERIES_MAX_NORM: f64 = 2.0;

/// `[φ_0(Z), φ_1(Z), ..., φ_p(Z)]` for `Z`, balanced by the characteristic scales `scale` of
/// the state's components (see the module docs).
///
/// # Panics
/// If a scale is not positive and finite (the caller's error).
pub fn phi_functions<const N: usize>(
    z: &SMatrix<f64, N, N>,
    p: usize,
    scale: &SVector<f64, N>,
) -> Vec<SMatrix<f64, N, N>> {
    let zs = scaled(z, scale);
    let mut phi = if zs.norm() <= SERIES_MAX_NORM {
        series(&zs, p)
    } else {
        block_exponential(&zs, p)
    };
    // Back to the unscaled variables: phi(Z) = D phi(D^-1 Z D) D^-1.
    for m in phi.iter_mut() {
        for i in 0..N {
            for j in 0..N {
                m[(i, j)] *= scale[i] / scale[j];
            }
        }
    }
    phi
}

/// `D^-1 Z D`, with `D` the diagonal of `scale` (see the module docs).
///
/// # Panics
/// If a scale is not positive and finite (the caller's error).
pub fn scaled<const N: usize>(
    z: &SMatrix<f64, N, N>,
    scale: &SVector<f64, N>,
) -> SMatrix<f64, N, N> {
    assert!(
        scale.iter().all(|s| s.is_finite() && *s > 0.0),
        "scales must be positive: {scale:?}"
    );
    let mut zs = *z;
    for i in 0..N {
        for j in 0..N {
            zs[(i, j)] *= scale[j] / scale[i];
        }
    }
    zs
}

/// `e^Z` alone for the model's 4 x 4 matrices, by scaling and squaring
/// ([`Matrix::exp`](nalgebra::Matrix::exp)).
pub fn expm(z: &Matrix4<f64>) -> Matrix4<f64> {
    z.exp()
}

/// `e^Z` alone for a model's `N x N` matrices, by scaling and squaring
/// ([`Matrix::exp`](nalgebra::Matrix::exp)).
///
/// The model's 4 x 4 matrices go through [`expm`] (the static matrix's own scaling and
/// squaring), and so do the 6 x 6 matrices of two masses (the static matrix's arithmetic
/// needs no heap and is about three times as fast as the dynamic matrix's); other sizes go
/// through the dynamic matrix's, the same algorithm: the one-mass models of 5 components
/// keep the arithmetic their recorded results were computed with.
pub fn expm_n<const N: usize>(z: &SMatrix<f64, N, N>) -> SMatrix<f64, N, N> {
    if N == 4 {
        let m = expm(&Matrix4::from_column_slice(z.as_slice()));
        return SMatrix::<f64, N, N>::from_column_slice(m.as_slice());
    }
    if N == 6 {
        let m = Matrix6::from_column_slice(z.as_slice()).exp();
        return SMatrix::<f64, N, N>::from_column_slice(m.as_slice());
    }
    let e = DMatrix::from_column_slice(N, N, z.as_slice()).exp();
    SMatrix::<f64, N, N>::from_column_slice(e.as_slice())
}

/// The φ functions by their Taylor series (a scaled norm below [`SERIES_MAX_NORM`]).
fn series<const N: usize>(z: &SMatrix<f64, N, N>, p: usize) -> Vec<SMatrix<f64, N, N>> {
    let mut phi = vec![SMatrix::<f64, N, N>::zeros(); p + 1];
    let mut power = SMatrix::<f64, N, N>::identity();
    for k in 0..SERIES_TERMS {
        for (j, m) in phi.iter_mut().enumerate() {
            *m += power / factorial(k + j);
        }
        power *= z;
    }
    phi
}

/// The φ functions from the exponential of the block matrix of the module docs.
fn block_exponential<const N: usize>(z: &SMatrix<f64, N, N>, p: usize) -> Vec<SMatrix<f64, N, N>> {
    let size = N * (p + 1);
    let mut w = DMatrix::<f64>::zeros(size, size);
    w.view_mut((0, 0), (N, N)).copy_from(z);
    for b in 0..p {
        for i in 0..N {
            w[(b * N + i, (b + 1) * N + i)] = 1.0;
        }
    }
    let e = w.exp();
    (0..=p)
        .map(|b| SMatrix::<f64, N, N>::from_fn(|i, j| e[(i, b * N + j)]))
        .collect()
}

/// `n!` as a float.
pub(crate) fn factorial(n: usize) -> f64 {
    (1..=n).map(|k| k as f64).product()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The scalar φ functions in closed form: `φ_0 = e^z`, `φ_{j+1} = (φ_j - 1/j!) / z`
    /// (z far from zero, where the recurrence does not cancel).
    fn scalar_phi(z: f64, p: usize) -> Vec<f64> {
        let mut out = vec![z.exp()];
        for j in 0..p {
            out.push((out[j] - 1.0 / factorial(j)) / z);
        }
        out
    }

    fn close(a: &SMatrix<f64, 3, 3>, b: &SMatrix<f64, 3, 3>, rel: f64) -> bool {
        (a - b).norm() <= rel * b.norm()
    }

    #[test]
    fn series_and_block_exponential_agree_where_both_apply() {
        // A damped oscillator with a load (the paper's pair's linear part in its shape) at
        // scaled norms from 0.1 to the series' bound: both ways are accurate to rounding there,
        // so they agree to a few 1e-15 of the matrices' norms (bound 1e-13).
        let base = SMatrix::<f64, 3, 3>::new(0.0, 1.0, 0.0, -1.0, -0.05, 0.3, -0.2, 0.0, -0.7);
        let ones = SVector::<f64, 3>::repeat(1.0);
        for scale in [0.1, 0.5, 1.0, 1.2] {
            let z = base * scale;
            assert!(z.norm() <= SERIES_MAX_NORM);
            let a = series(&z, 6);
            let b = block_exponential(&z, 6);
            for j in 0..=6 {
                assert!(close(&a[j], &b[j], 1e-13), "phi_{j} at scale {scale}");
            }
            // And the public entry takes the series there, bit for bit.
            assert_eq!(phi_functions(&z, 6, &ones), a);
        }
    }

    #[test]
    fn stiff_diagonal_matrices_match_the_closed_forms() {
        // Decay rates from 8 (a coil at the sample interval) to 1e4 times the step, beside a
        // growing mode: every phi_j within 1e-12 of the closed form, relative to its size
        // (e^-1e4 underflows to zero and is compared absolutely).
        for rates in [
            [-8.0, -250.0, 0.5],
            [-8.0, -250.0, 3.0],
            [-8.0, -250.0, -1.0e4],
        ] {
            let z = SMatrix::<f64, 3, 3>::from_diagonal(&SVector::<f64, 3>::from(rates));
            let got = phi_functions(&z, 5, &SVector::<f64, 3>::repeat(1.0));
            for (k, &lam) in rates.iter().enumerate() {
                let want = scalar_phi(lam, 5);
                for j in 0..=5 {
                    let (a, b) = (got[j][(k, k)], want[j]);
                    assert!(
                        (a - b).abs() <= 1e-12 * b.abs().max(1e-300),
                        "phi_{j}({lam}): {a} vs {b}"
                    );
                }
            }
        }
    }

    #[test]
    fn a_stiff_coupled_matrix_matches_its_eigendecomposition() {
        // Z = V diag(l) V^-1 with a stiff electrical mode (-400), a lightly damped oscillation
        // (-0.01 +- 0.3 i, as a real 2x2 block) and a non-orthogonal V; the phi functions of
        // the block are closed forms of the complex rate, so phi_j(Z) = V phi_j(diag) V^-1.
        let v = SMatrix::<f64, 3, 3>::new(1.0, 0.2, 0.0, 0.3, 1.0, 0.5, -0.1, 0.4, 1.0);
        let vi = v.try_inverse().unwrap();
        let (a, b, s) = (-0.01, 0.3, -400.0);
        let block = SMatrix::<f64, 3, 3>::new(a, b, 0.0, -b, a, 0.0, 0.0, 0.0, s);
        let z = v * block * vi;
        let got = phi_functions(&z, 4, &SVector::<f64, 3>::new(1.0, 2.0, 0.5));
        // phi_j of the rotation block [[a, b], [-b, a]] is [[Re, Im], [-Im, Re]] of phi_j(a + ib).
        let mut want_phi = vec![nalgebra::Complex::new(a, b).exp()];
        let zc = nalgebra::Complex::new(a, b);
        for j in 0..4 {
            want_phi.push((want_phi[j] - 1.0 / factorial(j)) / zc);
        }
        let stiff = scalar_phi(s, 4);
        for j in 0..=4 {
            let c = want_phi[j];
            let m =
                SMatrix::<f64, 3, 3>::new(c.re, c.im, 0.0, -c.im, c.re, 0.0, 0.0, 0.0, stiff[j]);
            let want = v * m * vi;
            assert!(
                close(&got[j], &want, 1e-12),
                "phi_{j}: {:?} vs {want:?}",
                got[j]
            );
        }
    }
}
