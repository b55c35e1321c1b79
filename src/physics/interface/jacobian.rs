//! The derivatives of a harvester with an interface that its monodromy needs: the Jacobian of
//! each mode's vector field (constant in the circuit's variables for piecewise-linear diodes,
//! the modes being linear; Shockley's law is differentiated as it stands), and the Jacobian of
//! each switch's reset at an extremum. A conduction change leaves the state continuous (the
//! projection onto a conducting mode's constraint is within the event tolerance), so its reset
//! Jacobian is the identity.

use nalgebra::{Matrix4, RowVector4};

use crate::drive::Excitation;
use crate::physics::contact::Mode;
use crate::physics::harvester::State;

use super::{Bridge, DiodeLaw, Element, IfMode, InterfaceModel, Interfaced, Switch};

impl InterfaceModel {
    /// d I_L / d Vs of the DC load (S).
    fn sink_conductance(&self) -> f64 {
        match self.sink {
            super::Sink::Resistor(r) => 1.0 / r,
            super::Sink::Battery(_, r) => 1.0 / r,
            super::Sink::Open => 0.0,
        }
    }

    /// The gradients in the state of the element's force on the mass (N per unit of each state
    /// component) and of the rates of `e1`, `e2`, in a bridge mode: the derivative of
    /// [`InterfaceModel::force_and_rates`].
    pub fn force_and_rates_gradient(
        &self,
        bridge: Bridge,
        y: &State,
    ) -> (RowVector4<f64>, [RowVector4<f64>; 2]) {
        let gl = self.sink_conductance();
        let cs = self.cs;
        match self.element {
            Element::Piezo { theta, cp } => {
                let df = RowVector4::new(0.0, 0.0, theta, 0.0);
                let open = RowVector4::new(0.0, -theta / cp, 0.0, 0.0);
                let storage_only = RowVector4::new(0.0, 0.0, 0.0, -gl / cs);
                if !self.bridge_between_extrema() {
                    return (df, [open, storage_only]);
                }
                match self.diode {
                    DiodeLaw::Shockley { is, nvt } => {
                        // path current I_s (exp(u / 2nVT) - 1), u1 = Vp - Vs, u2 = -Vp - Vs.
                        let d = |u: f64| is / (2.0 * nvt) * (u / (2.0 * nvt)).exp();
                        let (d1, d2) = (d(y[2] - y[3]), d(-y[2] - y[3]));
                        // i1 - i2 and i1 + i2 in (Vp, Vs).
                        let diff = (d1 + d2, -d1 + d2);
                        let sum = (d1 - d2, -d1 - d2);
                        let r2 = open + RowVector4::new(0.0, 0.0, -diff.0 / cp, -diff.1 / cp);
                        let r3 = RowVector4::new(0.0, 0.0, sum.0 / cs, (sum.1 - gl) / cs);
                        (df, [r2, r3])
                    }
                    DiodeLaw::PiecewiseLinear { ron, .. } => match bridge {
                        Bridge::Off => (df, [open, storage_only]),
                        b => {
                            let s = b.sign();
                            if ron == 0.0 {
                                let dvs = RowVector4::new(0.0, -s * theta, 0.0, -gl) / (cp + cs);
                                (df, [dvs * s, dvs])
                            } else {
                                let di = RowVector4::new(0.0, 0.0, s, -1.0) / (2.0 * ron);
                                let r2 = open - di * (s / cp);
                                let r3 = (di - RowVector4::new(0.0, 0.0, 0.0, gl)) / cs;
                                (df, [r2, r3])
                            }
                        }
                    },
                }
            }
            Element::Coil { phi, rc, l } => {
                let s = bridge.sign();
                let rpath = rc + 2.0 * self.ron();
                // The coil current's gradient.
                let di = if l > 0.0 {
                    RowVector4::new(0.0, 0.0, 1.0, 0.0)
                } else if bridge == Bridge::Off {
                    RowVector4::zeros()
                } else {
                    RowVector4::new(0.0, phi, 0.0, -s) / rpath
                };
                let rate_i = if l > 0.0 && bridge != Bridge::Off {
                    (RowVector4::new(0.0, phi, 0.0, -s) - di * rpath) / l
                } else {
                    RowVector4::zeros()
                };
                let rate_vs = (di * s - RowVector4::new(0.0, 0.0, 0.0, gl)) / cs;
                (di * -phi, [rate_i, rate_vs])
            }
        }
    }

    /// The Jacobian of [`InterfaceModel::reset`] at the state `y` just before it (the
    /// velocity is zero there and stays so: the reset leaves it alone).
    pub fn reset_jacobian(&self, y: &State) -> Matrix4<f64> {
        let mut g = Matrix4::identity();
        let Element::Piezo { cp, .. } = self.element else {
            return g;
        };
        match self.switch {
            Switch::None => {}
            Switch::Parallel(gamma) => g[(2, 2)] = -gamma,
            Switch::Series(gamma) => {
                let s = y[2].signum();
                if s * y[2] - y[3] - self.path_drop() > 0.0 {
                    // q = (1 + gamma) ceff (s Vp - Vs - 2 V_F); Vp -= s q / Cp, Vs += q / Cs.
                    let k = (1.0 + gamma) * cp * self.cs / (cp + self.cs);
                    g[(2, 2)] = 1.0 - k / cp;
                    g[(2, 3)] = s * k / cp;
                    g[(3, 2)] = s * k / self.cs;
                    g[(3, 3)] = 1.0 - k / self.cs;
                }
            }
            Switch::Sece(eta) => {
                let vs = (y[3] * y[3] + eta * cp * y[2] * y[2] / self.cs).sqrt();
                g[(2, 2)] = 0.0;
                if vs > 0.0 {
                    g[(3, 2)] = eta * cp * y[2] / (self.cs * vs);
                    g[(3, 3)] = y[3] / vs;
                }
            }
        }
        g
    }
}

impl<E: Excitation> Interfaced<E> {
    /// The Jacobian of the vector field of `mode` at `y`: the mechanics' (with the stops')
    /// from [`crate::physics::harvester::Harvester::jacobian`], the circuit's from
    /// [`InterfaceModel::force_and_rates_gradient`].
    pub fn jacobian(&self, mode: IfMode, y: &State) -> Matrix4<f64> {
        let (df, rates) = self.circuit.force_and_rates_gradient(mode.bridge, y);
        let mut j = Matrix4::zeros();
        if !matches!(mode.contact, Mode::Stuck(_)) {
            let jh = self.h.jacobian(mode.contact, y);
            j[(0, 1)] = 1.0;
            j[(1, 0)] = jh[(1, 0)];
            j[(1, 1)] = jh[(1, 1)];
            let row = j.row(1) + df / self.h.mass_kg;
            j.set_row(1, &row);
        }
        j.set_row(2, &rates[0]);
        j.set_row(3, &rates[1]);
        j
    }

    /// True when guard 2 of `mode` firing at `y` is the switch's extremum (a reset), false
    /// when it is a conduction change (see [`crate::ode::HybridSystem::switch`]).
    pub fn fires_extremum(&self, mode: IfMode, y: &State) -> bool {
        let [conduction, extremum] = self.circuit_guards(mode, y);
        extremum >= conduction
    }
}
