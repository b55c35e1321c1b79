//! What an integrator carries: a [`Vector`], a fixed number of `f64` components with the
//! vector-space operations that Runge-Kutta sums need.
//!
//! A model's state is an [`SVector`]; its variational equations carry the state with its
//! tangent map and one parameter column ([`Tangent`]), and an energy audit the state with its
//! running integrals ([`Augmented`]). Each is sized by the model's dimension alone, so a study
//! written for any dimension `N` carries them without arithmetic on `N` in a type (which stable
//! Rust does not allow). Every operation acts component by component in the order of
//! [`Vector::components`], so a [`Tangent`] rounds exactly as the flat vector of its components
//! would.

use std::fmt::Debug;
use std::ops::{Add, Mul, Sub};

use nalgebra::{SMatrix, SVector};

/// A vector an integrator carries (see the module docs).
pub trait Vector:
    Copy
    + Debug
    + PartialEq
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<f64, Output = Self>
    + Send
    + Sync
    + 'static
{
    /// The zero vector.
    fn zeros() -> Self;

    /// The components, in the order the error norm and the checks visit them.
    fn components(&self) -> &[f64];

    /// The components, mutable.
    fn components_mut(&mut self) -> &mut [f64];

    /// True when every component is finite.
    #[inline]
    fn is_finite(&self) -> bool {
        self.components().iter().all(|v| v.is_finite())
    }

    /// The components as an owned list (for error messages).
    fn to_vec(&self) -> Vec<f64> {
        self.components().to_vec()
    }
}

impl<const N: usize> Vector for SVector<f64, N> {
    #[inline(always)]
    fn zeros() -> Self {
        SVector::zeros()
    }

    #[inline(always)]
    fn components(&self) -> &[f64] {
        self.as_slice()
    }

    #[inline(always)]
    fn components_mut(&mut self) -> &mut [f64] {
        self.as_mut_slice()
    }
}

/// Implements the vector-space operations of a `#[repr(C)]` struct of nalgebra arrays field by
/// field, and [`Vector`] on its memory as one run of `f64`.
macro_rules! fieldwise_vector {
    ($name:ident < $($c:ident),* > { $($f:ident),* }) => {
        impl<$(const $c: usize),*> Add for $name<$($c),*> {
            type Output = Self;
            #[inline(always)]
            fn add(self, o: Self) -> Self {
                Self { $($f: self.$f + o.$f),* }
            }
        }

        impl<$(const $c: usize),*> Sub for $name<$($c),*> {
            type Output = Self;
            #[inline(always)]
            fn sub(self, o: Self) -> Self {
                Self { $($f: self.$f - o.$f),* }
            }
        }

        impl<$(const $c: usize),*> Mul<f64> for $name<$($c),*> {
            type Output = Self;
            #[inline(always)]
            fn mul(self, s: f64) -> Self {
                Self { $($f: self.$f * s),* }
            }
        }

        impl<$(const $c: usize),*> Vector for $name<$($c),*> {
            #[inline(always)]
            fn zeros() -> Self {
                Self { $($f: nalgebra::zero()),* }
            }

            #[inline(always)]
            fn components(&self) -> &[f64] {
                let n = std::mem::size_of::<Self>() / std::mem::size_of::<f64>();
                // SAFETY: the struct is `repr(C)` and made only of nalgebra arrays of `f64`
                // (each `repr(C)` over `[[f64; R]; C]`), so it is `n` contiguous `f64`s with no
                // padding, aligned as `f64`.
                unsafe { std::slice::from_raw_parts((self as *const Self).cast::<f64>(), n) }
            }

            #[inline(always)]
            fn components_mut(&mut self) -> &mut [f64] {
                let n = std::mem::size_of::<Self>() / std::mem::size_of::<f64>();
                // SAFETY: as in `components`.
                unsafe { std::slice::from_raw_parts_mut((self as *mut Self).cast::<f64>(), n) }
            }
        }
    };
}

/// A state with its first-order sensitivities: the tangent map `phi = dy/dy0` and `P`
/// parameter columns `dp = dy/dp` (one by default), in that order after the state (the layout
/// of the flat vector `(y, phi by columns, dp by columns)`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tangent<const N: usize, const P: usize = 1> {
    /// The state.
    pub y: SVector<f64, N>,
    /// The tangent map, `d y / d y0`.
    pub phi: SMatrix<f64, N, N>,
    /// The parameter columns, `d y / d p`.
    pub dp: SMatrix<f64, N, P>,
}

fieldwise_vector!(Tangent<N, P> { y, phi, dp });

impl<const N: usize, const P: usize> Tangent<N, P> {
    /// The state `y0` with the identity tangent map and zero parameter columns.
    pub fn start(y0: SVector<f64, N>) -> Self {
        Self {
            y: y0,
            phi: SMatrix::identity(),
            dp: SMatrix::zeros(),
        }
    }
}

/// A state with `K` running integrals beside it (an energy audit's accumulators).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Augmented<const N: usize, const K: usize> {
    /// The state.
    pub y: SVector<f64, N>,
    /// The integrals.
    pub acc: SVector<f64, K>,
}

fieldwise_vector!(Augmented<N, K> { y, acc });

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_tangent_is_its_flat_vector() {
        let mut t = Tangent::<3>::start(SVector::<f64, 3>::new(1.0, 2.0, 3.0));
        t.dp = SVector::<f64, 3>::new(7.0, 8.0, 9.0);
        let c = t.components();
        assert_eq!(c.len(), 15);
        assert_eq!(&c[..3], &[1.0, 2.0, 3.0]);
        // The identity by columns, then the parameter column.
        assert_eq!(&c[3..6], &[1.0, 0.0, 0.0]);
        assert_eq!(&c[6..9], &[0.0, 1.0, 0.0]);
        assert_eq!(&c[12..], &[7.0, 8.0, 9.0]);
        let u = (t + t * 2.0 - t) * 0.5;
        assert!(u.components().iter().zip(c).all(|(a, b)| *a == *b));
    }

    #[test]
    fn an_augmented_state_is_its_flat_vector() {
        let mut a = Augmented::<2, 3>::zeros();
        a.components_mut()
            .copy_from_slice(&[1.0, 2.0, 3.0, 4.0, 5.0]);
        assert_eq!(a.y, SVector::<f64, 2>::new(1.0, 2.0));
        assert_eq!(a.acc, SVector::<f64, 3>::new(3.0, 4.0, 5.0));
        assert!(a.is_finite());
    }
}
