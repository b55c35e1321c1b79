//! The circuit kinds whose switch acts in an instant: the plain full bridge, and the
//! synchronous switches at the displacement extrema on a piezoelectric element (Guyomar et
//! al. 2005, IEEE TUFFC 52 584; Lefeuvre et al. 2006, Sens. Actuators A 126 405):
//!
//! * parallel SSHI: `Vp -> -gamma Vp` (the LC half-cycle is instantaneous; its loss
//!   `(1 - gamma^2) Cp Vp^2 / 2` is a switching loss); the bridge conducts between extrema;
//! * series SSHI: the loop of `Cp`, the inductor, the bridge and `Cs` rings for half a cycle:
//!   its voltage `u = |Vp| - Vs - 2 V_F` (when positive) becomes `-gamma u`, moving the charge
//!   `q = (1 + gamma) u Cp Cs / (Cp + Cs)` from the element to the storage (`2 V_F q` is lost
//!   in the diodes, the rest of the drop is a switching loss); the element is open between
//!   extrema;
//! * SECE: `Vp -> 0` and `Cs Vs^2 / 2` gains `eta Cp Vp^2 / 2`; the element is open between
//!   extrema (its transfer resolved through the inductor in time is
//!   [`super::sece_inductor`]).
//!
//! A synchronous switch refuses the electrostatic pair: it acts on a piezoelectric element's
//! voltage only.

use nalgebra::{SMatrix, SVector};

use super::bridge::{Circuit, CircuitKind};
use super::element::Element;
use super::mode::ResetLoss;

/// Why a synchronous switch refuses an element.
const PIEZO_ONLY: &str = "a synchronous switch acts on a piezoelectric element's voltage only";

/// The refusal of a synchronous switch.
fn piezo_only(element: &Element) -> Option<&'static str> {
    matches!(element, Element::Pair(_)).then_some(PIEZO_ONLY)
}

/// A plain full bridge: no switch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FullBridge;

impl CircuitKind for FullBridge {
    #[inline(always)]
    fn acts_at_extrema(&self) -> bool {
        false
    }
}

/// A parallel SSHI with its inversion factor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParallelSshi {
    /// gamma.
    pub gamma: f64,
}

impl CircuitKind for ParallelSshi {
    fn refuses(&self, element: &Element) -> Option<&'static str> {
        piezo_only(element)
    }

    fn reset<const N: usize>(&self, c: &Circuit, cp: f64, y: &mut SVector<f64, N>) -> ResetLoss {
        let e = c.e;
        let en = 0.5 * cp * y[e] * y[e];
        y[e] *= -self.gamma;
        ResetLoss {
            diode: 0.0,
            switching: en * (1.0 - self.gamma * self.gamma),
        }
    }

    fn reset_jacobian<const N: usize>(
        &self,
        c: &Circuit,
        _cp: f64,
        _y: &SVector<f64, N>,
        g: &mut SMatrix<f64, N, N>,
    ) {
        g[(c.e, c.e)] = -self.gamma;
    }
}

/// A series SSHI with its inversion factor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeriesSshi {
    /// gamma.
    pub gamma: f64,
}

impl CircuitKind for SeriesSshi {
    fn refuses(&self, element: &Element) -> Option<&'static str> {
        piezo_only(element)
    }

    #[inline(always)]
    fn bridge_between_extrema(&self) -> bool {
        false
    }

    fn reset<const N: usize>(&self, c: &Circuit, cp: f64, y: &mut SVector<f64, N>) -> ResetLoss {
        let (e, ivs, gamma) = (c.e, c.vs, self.gamma);
        let s = y[e].signum();
        let u = s * y[e] - y[ivs] - c.path_drop();
        if u <= 0.0 {
            return ResetLoss::default();
        }
        let ceff = cp * c.cs / (cp + c.cs);
        let q = (1.0 + gamma) * u * ceff;
        y[e] -= s * q / cp;
        y[ivs] += q / c.cs;
        ResetLoss {
            diode: c.path_drop() * q,
            switching: 0.5 * ceff * u * u * (1.0 - gamma * gamma),
        }
    }

    fn reset_jacobian<const N: usize>(
        &self,
        c: &Circuit,
        cp: f64,
        y: &SVector<f64, N>,
        g: &mut SMatrix<f64, N, N>,
    ) {
        let (e, ivs) = (c.e, c.vs);
        let s = y[e].signum();
        if s * y[e] - y[ivs] - c.path_drop() > 0.0 {
            // q = (1 + gamma) ceff (s Vp - Vs - 2 V_F); Vp -= s q / Cp, Vs += q / Cs.
            let k = (1.0 + self.gamma) * cp * c.cs / (cp + c.cs);
            g[(e, e)] = 1.0 - k / cp;
            g[(e, ivs)] = s * k / cp;
            g[(ivs, e)] = s * k / c.cs;
            g[(ivs, ivs)] = 1.0 - k / c.cs;
        }
    }
}

/// A SECE with its efficiency.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sece {
    /// eta.
    pub eta: f64,
}

impl CircuitKind for Sece {
    fn refuses(&self, element: &Element) -> Option<&'static str> {
        piezo_only(element)
    }

    #[inline(always)]
    fn bridge_between_extrema(&self) -> bool {
        false
    }

    fn reset<const N: usize>(&self, c: &Circuit, cp: f64, y: &mut SVector<f64, N>) -> ResetLoss {
        let (e, ivs) = (c.e, c.vs);
        let en = 0.5 * cp * y[e] * y[e];
        y[ivs] = (y[ivs] * y[ivs] + 2.0 * self.eta * en / c.cs).sqrt();
        y[e] = 0.0;
        ResetLoss {
            diode: 0.0,
            switching: (1.0 - self.eta) * en,
        }
    }

    fn reset_jacobian<const N: usize>(
        &self,
        c: &Circuit,
        cp: f64,
        y: &SVector<f64, N>,
        g: &mut SMatrix<f64, N, N>,
    ) {
        let (e, ivs, eta) = (c.e, c.vs, self.eta);
        let vs = (y[ivs] * y[ivs] + eta * cp * y[e] * y[e] / c.cs).sqrt();
        g[(e, e)] = 0.0;
        if vs > 0.0 {
            g[(ivs, e)] = eta * cp * y[e] / (c.cs * vs);
            g[(ivs, ivs)] = y[ivs] / vs;
        }
    }
}
