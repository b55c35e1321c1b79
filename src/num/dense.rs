//! LU solves and eigenvalues of a model's `N x N` matrices for any `N`.
//!
//! nalgebra decomposes a matrix of a size fixed in its type only where that size names a
//! `typenum` type (`Const<N>: ToTypenum`), a bound a function generic over `N` cannot state
//! without repeating it through every study that calls it. These wrappers decompose the
//! 4 x 4 matrices (every device of the paper and of the examples) as nalgebra's own static
//! type, which is how every recorded result was computed, and any other size as a dynamic
//! matrix, by the same algorithms.

use nalgebra::{Complex, DMatrix, DVector, Matrix4, SMatrix, SVector, Vector4, LU, U4};

/// An LU decomposition of an `N x N` real matrix (see the module docs).
#[derive(Debug, Clone)]
pub enum Lu<const N: usize> {
    /// A 4 x 4 matrix, decomposed as nalgebra's static type.
    Four(LU<f64, U4, U4>),
    /// Any other size, as a dynamic matrix.
    Dynamic(LU<f64, nalgebra::Dyn, nalgebra::Dyn>),
}

impl<const N: usize> Lu<N> {
    /// The decomposition of `m`.
    pub fn of(m: &SMatrix<f64, N, N>) -> Self {
        if N == 4 {
            Lu::Four(Matrix4::from_column_slice(m.as_slice()).lu())
        } else {
            Lu::Dynamic(DMatrix::from_column_slice(N, N, m.as_slice()).lu())
        }
    }

    /// The solution of `m x = b`, or `None` when `m` is singular.
    pub fn solve(&self, b: &SVector<f64, N>) -> Option<SVector<f64, N>> {
        match self {
            Lu::Four(lu) => {
                let x = lu.solve(&Vector4::from_column_slice(b.as_slice()))?;
                Some(SVector::from_column_slice(x.as_slice()))
            }
            Lu::Dynamic(lu) => {
                let x = lu.solve(&DVector::from_column_slice(b.as_slice()))?;
                Some(SVector::from_column_slice(x.as_slice()))
            }
        }
    }
}

/// An LU decomposition of an `N x N` complex matrix (see the module docs).
#[derive(Debug, Clone)]
pub enum ComplexLu<const N: usize> {
    /// A 4 x 4 matrix, decomposed as nalgebra's static type (boxed: it is four times the
    /// dynamic variant's size).
    Four(Box<LU<Complex<f64>, U4, U4>>),
    /// Any other size, as a dynamic matrix.
    Dynamic(LU<Complex<f64>, nalgebra::Dyn, nalgebra::Dyn>),
}

impl<const N: usize> ComplexLu<N> {
    /// The decomposition of `m`.
    pub fn of(m: &SMatrix<Complex<f64>, N, N>) -> Self {
        if N == 4 {
            ComplexLu::Four(Box::new(
                nalgebra::Matrix4::<Complex<f64>>::from_column_slice(m.as_slice()).lu(),
            ))
        } else {
            ComplexLu::Dynamic(DMatrix::from_column_slice(N, N, m.as_slice()).lu())
        }
    }

    /// The solution of `m x = b`, or `None` when `m` is singular.
    pub fn solve(&self, b: &SVector<Complex<f64>, N>) -> Option<SVector<Complex<f64>, N>> {
        match self {
            ComplexLu::Four(lu) => {
                let x = lu.solve(&nalgebra::Vector4::from_column_slice(b.as_slice()))?;
                Some(SVector::from_column_slice(x.as_slice()))
            }
            ComplexLu::Dynamic(lu) => {
                let x = lu.solve(&DVector::from_column_slice(b.as_slice()))?;
                Some(SVector::from_column_slice(x.as_slice()))
            }
        }
    }
}

/// The eigenvalues of an `N x N` real matrix by the real Schur form (see the module docs);
/// `None` when the Schur iteration does not converge in 10 000 steps.
pub fn eigenvalues<const N: usize>(m: &SMatrix<f64, N, N>) -> Option<Vec<Complex<f64>>> {
    if N == 4 {
        let schur = nalgebra::Schur::try_new(
            Matrix4::from_column_slice(m.as_slice()),
            f64::EPSILON,
            10_000,
        )?;
        Some(schur.complex_eigenvalues().iter().copied().collect())
    } else {
        let schur = nalgebra::Schur::try_new(
            DMatrix::from_column_slice(N, N, m.as_slice()),
            f64::EPSILON,
            10_000,
        )?;
        Some(schur.complex_eigenvalues().iter().copied().collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn four_and_five_solve_and_find_eigenvalues_alike() {
        let m4 =
            SMatrix::<f64, 4, 4>::from_fn(|i, j| if i == j { 2.0 } else { 0.1 * (i + j) as f64 });
        let b4 = SVector::<f64, 4>::new(1.0, 2.0, 3.0, 4.0);
        let x4 = Lu::of(&m4).solve(&b4).unwrap();
        assert!((m4 * x4 - b4).norm() < 1e-14);
        let m5 =
            SMatrix::<f64, 5, 5>::from_fn(|i, j| if i == j { 2.0 } else { 0.1 * (i + j) as f64 });
        let b5 = SVector::<f64, 5>::new(1.0, 2.0, 3.0, 4.0, 5.0);
        let x5 = Lu::of(&m5).solve(&b5).unwrap();
        assert!((m5 * x5 - b5).norm() < 1e-14);
        // A rotation by 90 degrees in a plane and 3 on the rest: eigenvalues +-i and 3.
        let mut r = SMatrix::<f64, 5, 5>::identity() * 3.0;
        r[(0, 0)] = 0.0;
        r[(1, 1)] = 0.0;
        r[(0, 1)] = -1.0;
        r[(1, 0)] = 1.0;
        let mut ev = eigenvalues(&r).unwrap();
        ev.sort_by(|a, b| a.re.total_cmp(&b.re).then(a.im.total_cmp(&b.im)));
        assert!((ev[0] - Complex::new(0.0, -1.0)).norm() < 1e-12);
        assert!((ev[1] - Complex::new(0.0, 1.0)).norm() < 1e-12);
        assert!(ev[2..]
            .iter()
            .all(|e| (e - Complex::new(3.0, 0.0)).norm() < 1e-12));
    }
}
