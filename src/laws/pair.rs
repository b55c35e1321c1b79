//! The electrostatic pair's law (eqs 7-10, and the gap-closing variant): two variable
//! capacitors with the bias on the proof mass, their capacitances against the displacement,
//! the node voltages their charges make, and the force on the mass. With
//! `D_i = C_i + Cp + CL`: `V_i = (s_i + (C_i - C0) Vb) / D_i`, and the force is
//! `+1/2 sum_i (V_i - Vb)^2 dC_i/dx` (eq 9 with the sign it has in eq 7). Area overlap:
//! `C_1,2 = C0 (1 +- x/x0)`; gap closing: `C_1,2 = C0 d0 / (d0 -+ x)`.
//!
//! The law reads no device file; a transducer evaluated ([`crate::physics::transducer`]) and
//! an interface circuit's element ([`crate::circuits::Element`]) both hold one.

use nalgebra::SVector;

/// Which capacitance law a pair follows.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PairGeometry {
    /// `C = C0 (1 +- x/x0)` (eq 10).
    AreaOverlap {
        /// Finger overlap x0 (m).
        x0: f64,
    },
    /// `C = C0 d0 / (d0 -+ x)`.
    GapClosing {
        /// Electrode gap d0 (m).
        d0: f64,
    },
}

/// Two variable capacitors with the bias on the proof mass, each electrode loaded by RL
/// parallel CL.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CapacitorPair {
    /// Capacitance law.
    pub geometry: PairGeometry,
    /// C0 (F).
    pub c0: f64,
    /// Cp (F).
    pub cp: f64,
    /// CL (F).
    pub cl: f64,
    /// RL (ohm).
    pub rl: f64,
    /// Vb (V).
    pub vb: f64,
}

/// Node voltages and transducer capacitances of a pair at one state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Electrical {
    /// Voltages across the loads (V): both nodes for a pair, `[V, 0]` for a single load.
    pub v: [f64; 2],
    /// Transducer capacitances C1, C2 (F) of a pair; zero otherwise.
    pub c: [f64; 2],
}

impl CapacitorPair {
    /// `C_i - C0` for both transducers at x (F), and `dC_i/dx` (F/m).
    #[inline]
    fn capacitance_changes(&self, x: f64) -> ([f64; 2], [f64; 2]) {
        match self.geometry {
            PairGeometry::AreaOverlap { x0 } => {
                let dc = self.c0 * x / x0;
                let a = self.c0 / x0;
                ([dc, -dc], [a, -a])
            }
            PairGeometry::GapClosing { d0 } => {
                let (g1, g2) = (d0 - x, d0 + x);
                (
                    [self.c0 * x / g1, -self.c0 * x / g2],
                    [self.c0 * d0 / (g1 * g1), -self.c0 * d0 / (g2 * g2)],
                )
            }
        }
    }

    /// `dC_i/dx` of both transducers at x (F/m).
    #[inline]
    pub fn capacitance_slopes(&self, x: f64) -> [f64; 2] {
        self.capacitance_changes(x).1
    }

    /// Capacitances and node voltages at a state.
    #[inline(always)]
    pub fn electrical(&self, y: &SVector<f64, 4>) -> Electrical {
        match self.geometry {
            // Written out for the paper's pair: these are the operations of eqs 8-10 in the
            // order every recorded result was computed with.
            PairGeometry::AreaOverlap { x0 } => {
                let dc = self.c0 * y[0] / x0;
                let c1 = self.c0 + dc;
                let c2 = self.c0 - dc;
                let v1 = (y[2] + dc * self.vb) / (c1 + self.cp + self.cl);
                let v2 = (y[3] - dc * self.vb) / (c2 + self.cp + self.cl);
                Electrical {
                    v: [v1, v2],
                    c: [c1, c2],
                }
            }
            PairGeometry::GapClosing { .. } => {
                let ([d1, d2], _) = self.capacitance_changes(y[0]);
                let (c1, c2) = (self.c0 + d1, self.c0 + d2);
                Electrical {
                    v: [
                        (y[2] + d1 * self.vb) / (c1 + self.cp + self.cl),
                        (y[3] + d2 * self.vb) / (c2 + self.cp + self.cl),
                    ],
                    c: [c1, c2],
                }
            }
        }
    }

    /// The electrostatic force on the mass, `+1/2 sum (V_i - Vb)^2 dC_i/dx` (N).
    #[inline(always)]
    pub fn force(&self, x: f64, el: &Electrical) -> f64 {
        let u1 = el.v[0] - self.vb;
        let u2 = el.v[1] - self.vb;
        match self.geometry {
            PairGeometry::AreaOverlap { x0 } => {
                let dcdx = self.c0 / x0;
                0.5 * dcdx * (u1 * u1 - u2 * u2)
            }
            PairGeometry::GapClosing { .. } => {
                let (_, [a1, a2]) = self.capacitance_changes(x);
                0.5 * (u1 * u1 * a1 + u2 * u2 * a2)
            }
        }
    }

    /// The derivatives of the force and of both node rates with respect to (x, s1, s2), at a
    /// state with its electrical quantities `el`: `(dF/dx, dF/ds1, dF/ds2)` and
    /// `d s_i' / d(x, s_i)`.
    ///
    /// With `D_i = C_i + Cp + CL`, `u_i = V_i - Vb` and `a_i = dC_i/dx`:
    /// `dV_i/dx = -a_i u_i / D_i`, `dV_i/ds_i = 1/D_i`, and
    /// `dF/dx = sum_i (a_i u_i dV_i/dx + u_i^2 a_i' / 2)` with `a_i'` the second derivative
    /// of `C_i` (zero for area overlap).
    pub fn gradients(&self, x: f64, el: &Electrical) -> PairGradients {
        let d1 = el.c[0] + self.cp + self.cl;
        let d2 = el.c[1] + self.cp + self.cl;
        let (u1, u2) = (el.v[0] - self.vb, el.v[1] - self.vb);
        let g = 1.0 / self.rl;
        match self.geometry {
            // The paper's pair, in the order its Jacobian has always been computed.
            PairGeometry::AreaOverlap { x0 } => {
                let a = self.c0 / x0;
                let dv1_dx = -a * u1 / d1;
                let dv2_dx = a * u2 / d2;
                PairGradients {
                    df_dx: a * (u1 * dv1_dx - u2 * dv2_dx),
                    df_ds: [a * u1 / d1, -a * u2 / d2],
                    rate_dx: [-g * dv1_dx, -g * dv2_dx],
                    rate_ds: [-g / d1, -g / d2],
                }
            }
            PairGeometry::GapClosing { d0 } => {
                let (_, [a1, a2]) = self.capacitance_changes(x);
                let (g1, g2) = (d0 - x, d0 + x);
                // d^2 C_i / dx^2: 2 C0 d0 / (d0 -+ x)^3, with the sign of the second pair.
                let (b1, b2) = (
                    2.0 * self.c0 * d0 / (g1 * g1 * g1),
                    2.0 * self.c0 * d0 / (g2 * g2 * g2),
                );
                let dv1_dx = -a1 * u1 / d1;
                let dv2_dx = -a2 * u2 / d2;
                PairGradients {
                    df_dx: a1 * u1 * dv1_dx
                        + a2 * u2 * dv2_dx
                        + 0.5 * (u1 * u1 * b1 + u2 * u2 * b2),
                    df_ds: [a1 * u1 / d1, a2 * u2 / d2],
                    rate_dx: [-g * dv1_dx, -g * dv2_dx],
                    rate_ds: [-g / d1, -g / d2],
                }
            }
        }
    }

    /// `x0` or `d0` (m): the length over which the capacitances change by C0.
    pub fn length_scale(&self) -> f64 {
        match self.geometry {
            PairGeometry::AreaOverlap { x0 } => x0,
            PairGeometry::GapClosing { d0 } => d0,
        }
    }
}

/// Derivatives of a pair's force and node rates (see [`CapacitorPair::gradients`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairGradients {
    /// dF/dx (N/m).
    pub df_dx: f64,
    /// dF/ds_i (N/C).
    pub df_ds: [f64; 2],
    /// d s_i' / dx.
    pub rate_dx: [f64; 2],
    /// d s_i' / d s_i.
    pub rate_ds: [f64; 2],
}
