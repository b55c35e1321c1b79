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
pub use crate::laws::pair::{CapacitorPair, Electrical, PairGeometry, PairGradients};

/// The model state (x in m, v in m/s, and two electrical components).
pub type State = SVector<f64, 4>;

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
