//! The transducers of [`crate::device::transducer`], evaluated: the force each puts on the
//! proof mass, the rates of its electrical state, their Jacobian, and what its loads see.
//!
//! The model's state is always `(x, v, e1, e2)`. Each transducer uses the leading electrical
//! components it needs and leaves the others at zero (their rates are zero and nothing reads
//! them), so that one integrator, one set of variational equations and one energy ledger serve
//! every device; [`TransducerModel::active_states`] says how many components are live.
//!
//! * **Capacitor pair** (eqs 7-10, and the gap-closing variant): `e_i = s_i`, the node charge
//!   of electrode i measured from its rest value, `s_i = Q_i + (C0 + Cp) Vb`. With
//!   `D_i = C_i + Cp + CL`: `V_i = (s_i + (C_i - C0) Vb) / D_i`, `s_i' = -V_i / RL`, and the
//!   force on the mass is `+1/2 sum_i (V_i - Vb)^2 dC_i/dx` (eq 9 with the sign it has in
//!   eq 7). Area overlap: `C_1,2 = C0 (1 +- x/x0)`; gap closing: `C_1,2 = C0 d0 / (d0 -+ x)`.
//! * **Piezoelectric**: `e1 = V`, force `+theta V`, `Cp V' = -V/R - theta v`.
//! * **Electromagnetic**: `e1 = I`, force `-Phi I`, `L I' = Phi v - (Rc + R) I`; with `L = 0`
//!   the current `Phi v / (Rc + R)` follows the velocity and there is no electrical state.

use nalgebra::SVector;

use crate::device::Transducer;

/// The model state (x in m, v in m/s, and two electrical components).
pub type State = SVector<f64, 4>;

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
    pub fn electrical(&self, y: &State) -> Electrical {
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

/// A transducer, evaluated (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TransducerModel {
    /// No transducer.
    None,
    /// A capacitor pair.
    Pair(CapacitorPair),
    /// Piezoelectric.
    Piezo {
        /// Coupling theta (N/V).
        theta: f64,
        /// Clamped capacitance (F).
        cp: f64,
        /// Load resistance (ohm).
        r: f64,
    },
    /// Electromagnetic.
    Electromagnetic {
        /// Transduction factor Phi (N/A).
        phi: f64,
        /// Coil resistance (ohm).
        rc: f64,
        /// Coil inductance (H); zero: no electrical state.
        l: f64,
        /// Load resistance (ohm).
        r: f64,
    },
}

impl TransducerModel {
    /// The model of a transducer description.
    pub fn of(t: &Transducer) -> Self {
        match t {
            Transducer::None => TransducerModel::None,
            Transducer::AreaOverlapPair(p) => TransducerModel::Pair(CapacitorPair {
                geometry: PairGeometry::AreaOverlap {
                    x0: p.finger_overlap_m,
                },
                c0: p.c0_f,
                cp: p.cp_f,
                cl: p.load_capacitance_f,
                rl: p.load_resistance_ohm,
                vb: p.bias_v,
            }),
            Transducer::GapClosingPair(p) => TransducerModel::Pair(CapacitorPair {
                geometry: PairGeometry::GapClosing {
                    d0: p.electrode_gap_m,
                },
                c0: p.c0_f,
                cp: p.cp_f,
                cl: p.load_capacitance_f,
                rl: p.load_resistance_ohm,
                vb: p.bias_v,
            }),
            Transducer::Piezoelectric(p) => TransducerModel::Piezo {
                theta: p.coupling_n_per_v,
                cp: p.capacitance_f,
                r: p.load_resistance_ohm,
            },
            Transducer::Electromagnetic(p) => TransducerModel::Electromagnetic {
                phi: p.transduction_n_per_a,
                rc: p.coil_resistance_ohm,
                l: p.coil_inductance_h,
                r: p.load_resistance_ohm,
            },
        }
    }

    /// Number of live components of the state: 2 (x, v) plus the electrical ones.
    pub fn active_states(&self) -> usize {
        match self {
            TransducerModel::None => 2,
            TransducerModel::Pair(_) => 4,
            TransducerModel::Piezo { .. } => 3,
            TransducerModel::Electromagnetic { l, .. } => {
                if *l > 0.0 {
                    3
                } else {
                    2
                }
            }
        }
    }

    /// The load resistance (ohm; of each load for a pair, infinite without a transducer).
    pub fn load_resistance(&self) -> f64 {
        match *self {
            TransducerModel::None => f64::INFINITY,
            TransducerModel::Pair(p) => p.rl,
            TransducerModel::Piezo { r, .. } | TransducerModel::Electromagnetic { r, .. } => r,
        }
    }

    /// Load voltages (and a pair's capacitances) at a state.
    #[inline]
    pub fn electrical(&self, y: &State) -> Electrical {
        match *self {
            TransducerModel::Pair(p) => p.electrical(y),
            TransducerModel::None => Electrical {
                v: [0.0, 0.0],
                c: [0.0, 0.0],
            },
            TransducerModel::Piezo { .. } => Electrical {
                v: [y[2], 0.0],
                c: [0.0, 0.0],
            },
            TransducerModel::Electromagnetic { phi, rc, l, r } => Electrical {
                v: [r * Self::em_current(phi, rc, l, r, y), 0.0],
                c: [0.0, 0.0],
            },
        }
    }

    #[inline]
    fn em_current(phi: f64, rc: f64, l: f64, r: f64, y: &State) -> f64 {
        if l > 0.0 {
            y[2]
        } else {
            phi * y[1] / (rc + r)
        }
    }

    /// The current through an electromagnetic transducer's coil (A); zero for the others.
    pub fn coil_current(&self, y: &State) -> f64 {
        match *self {
            TransducerModel::Electromagnetic { phi, rc, l, r } => {
                Self::em_current(phi, rc, l, r, y)
            }
            _ => 0.0,
        }
    }

    /// The force on the mass along +x (N) and the rates of the two electrical components.
    #[inline(always)]
    pub fn force_and_rates(&self, y: &State) -> (f64, [f64; 2]) {
        match *self {
            TransducerModel::Pair(p) => {
                let el = p.electrical(y);
                (p.force(y[0], &el), [-el.v[0] / p.rl, -el.v[1] / p.rl])
            }
            TransducerModel::None => (0.0, [0.0, 0.0]),
            TransducerModel::Piezo { theta, cp, r } => {
                let v = y[2];
                (theta * v, [(-v / r - theta * y[1]) / cp, 0.0])
            }
            TransducerModel::Electromagnetic { phi, rc, l, r } => {
                if l > 0.0 {
                    let i = y[2];
                    (-phi * i, [(phi * y[1] - (rc + r) * i) / l, 0.0])
                } else {
                    (-phi * phi * y[1] / (rc + r), [0.0, 0.0])
                }
            }
        }
    }

    /// Power dissipated in the loads (W).
    #[inline]
    pub fn load_power(&self, y: &State) -> f64 {
        match *self {
            TransducerModel::None => 0.0,
            TransducerModel::Pair(p) => {
                let el = p.electrical(y);
                (el.v[0] * el.v[0] + el.v[1] * el.v[1]) / p.rl
            }
            TransducerModel::Piezo { r, .. } => y[2] * y[2] / r,
            TransducerModel::Electromagnetic { phi, rc, l, r } => {
                let i = Self::em_current(phi, rc, l, r, y);
                i * i * r
            }
        }
    }

    /// Power dissipated inside the transducer: the coil's resistance (W).
    #[inline]
    pub fn internal_loss(&self, y: &State) -> f64 {
        match *self {
            TransducerModel::Electromagnetic { phi, rc, l, r } => {
                let i = Self::em_current(phi, rc, l, r, y);
                i * i * rc
            }
            _ => 0.0,
        }
    }

    /// `e` plus the energy stored in the transducer and its loads (J): the capacitors of a
    /// pair (against the bias), the piezoelectric capacitance, the coil's magnetic energy.
    pub fn add_stored_energy(&self, mut e: f64, y: &State) -> f64 {
        match *self {
            TransducerModel::None => e,
            TransducerModel::Pair(p) => {
                let el = p.electrical(y);
                for i in 0..2 {
                    let u = el.v[i] - p.vb;
                    e += 0.5 * (el.c[i] + p.cp) * u * u + 0.5 * p.cl * el.v[i] * el.v[i];
                }
                e
            }
            TransducerModel::Piezo { cp, .. } => e + 0.5 * cp * y[2] * y[2],
            TransducerModel::Electromagnetic { l, .. } => e + 0.5 * l * y[2] * y[2],
        }
    }

    /// Charge delivered by a pair's bias source to the proof-mass electrode (C),
    /// `sum_i (C_i + Cp)(Vb - V_i)`; zero without a source. The source's work is Vb times
    /// its change.
    pub fn source_charge(&self, y: &State) -> f64 {
        match *self {
            TransducerModel::Pair(p) => {
                let el = p.electrical(y);
                (0..2).map(|i| (el.c[i] + p.cp) * (p.vb - el.v[i])).sum()
            }
            _ => 0.0,
        }
    }

    /// The bias voltage of a pair (V); zero otherwise.
    pub fn bias_v(&self) -> f64 {
        match *self {
            TransducerModel::Pair(p) => p.vb,
            _ => 0.0,
        }
    }

    /// Characteristic scales of the two electrical components, for a displacement scale
    /// `x_scale` (m) and a velocity scale `v_scale` (m/s).
    pub fn scales(&self, x_scale: f64, v_scale: f64) -> [f64; 2] {
        match *self {
            TransducerModel::None => [1.0, 1.0],
            TransducerModel::Pair(p) => {
                let q = p.c0 * p.vb.max(1.0) * x_scale / p.length_scale();
                [q, q]
            }
            TransducerModel::Piezo { theta, cp, .. } => [theta * x_scale / cp, 1.0],
            TransducerModel::Electromagnetic { phi, rc, l, r } => {
                if l > 0.0 {
                    [phi * v_scale / (rc + r), 1.0]
                } else {
                    [1.0, 1.0]
                }
            }
        }
    }

    /// Checks that a pair's capacitances stay positive (and a gap-closing pair's electrodes
    /// apart) at x; the message says what failed.
    pub fn check(&self, x: f64, y: &State) -> Result<(), String> {
        if let TransducerModel::Pair(p) = self {
            if let PairGeometry::GapClosing { d0 } = p.geometry {
                if x.abs() >= d0 {
                    return Err(format!(
                        "the proof mass reached a gap-closing electrode (x = {x:e} m, d0 = {d0:e} m)"
                    ));
                }
            }
            let el = p.electrical(y);
            if el.c[0] + p.cp <= 0.0 || el.c[1] + p.cp <= 0.0 {
                return Err(format!(
                    "a transducer capacitance plus Cp is not positive (x = {x:e} m): C1+Cp = {:e} F, C2+Cp = {:e} F",
                    el.c[0] + p.cp,
                    el.c[1] + p.cp
                ));
            }
        }
        Ok(())
    }
}
