//! The variational equations of a model under a sine ([`crate::model::tangent`]) on the exact
//! engine: in an affine mode they are solved exactly too, the tangent map's columns by
//! `e^{sL}` and the parameter column by `e^{sL}` and the particular solution of its forcing
//! ([`AffineMode::sensitivity`]); the saltation at every switch is the model's.

use nalgebra::{SMatrix, SVector};

use crate::drive::Sine;
use crate::model::tangent::Tangents;
use crate::model::Model;
use crate::ode::Tangent;
use crate::study::flow::{AffineMode, Carrier};

impl<M: Model<N>, const N: usize> Carrier<N> for Tangents<'_, M, Sine, N> {
    type M = M;

    fn model(&self) -> &M {
        self.model
    }

    fn sine(&self) -> &Sine {
        &self.drive
    }

    const DENSE: bool = false;

    fn carry(
        &self,
        am: &AffineMode<N>,
        e: impl FnOnce() -> SMatrix<f64, N, N>,
        t: f64,
        s: f64,
        z: &Tangent<N>,
        y1: &SVector<f64, N>,
    ) -> Tangent<N> {
        let e = e();
        let mut phi = SMatrix::<f64, N, N>::zeros();
        for c in 0..N {
            phi.set_column(c, &(e * z.phi.column(c)));
        }
        let w1 = e * (z.dp - am.sensitivity(self.param, t)) + am.sensitivity(self.param, t + s);
        Tangent {
            y: *y1,
            phi,
            dp: w1,
        }
    }
}
