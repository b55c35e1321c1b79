//! The transducer as an interface circuit sees it: a port ([`Element`]) with a voltage that
//! drives the bridge, a capacitance a conduction holds at its threshold, the energy it stores
//! and the scales of its state components.
//!
//! * a **piezoelectric element**, a current source `-theta v` into its clamped capacitance
//!   `Cp`: its voltage `Vp` is a state, `Cp Vp' = -theta v - i`, and it puts `+theta Vp` on
//!   the mass;
//! * a **coil**, the EMF `Phi v` behind `Rc` and `L`: its current `I` is a state
//!   (`L I' = Phi v - Rc I - V_terminal`; algebraic when `L = 0`), and it puts `-Phi I` on the
//!   mass;
//! * an **electrostatic pair** (eqs 8-10 of Le & Halvorsen 2012) across its two electrodes:
//!   the node charges `s1`, `s2` are states, the port's voltage is `V1 - V2` with
//!   `V_i = (s_i + (C_i - C0) Vb) / D_i`, `D_i = C_i + Cp + CL`; a current `i` out of
//!   electrode 1 and into electrode 2 moves `s1' = -i`, `s2' = +i`, and the force is eq 9's.

use crate::laws::pair::CapacitorPair;

/// The transducer as the circuit sees it (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Element {
    /// A piezoelectric element: coupling theta (N/V) and clamped capacitance Cp (F).
    Piezo {
        /// theta (N/V).
        theta: f64,
        /// Cp (F).
        cp: f64,
    },
    /// A coil: transduction Phi (N/A), resistance Rc (ohm), inductance L (H).
    Coil {
        /// Phi (N/A).
        phi: f64,
        /// Rc (ohm).
        rc: f64,
        /// L (H).
        l: f64,
    },
    /// An electrostatic pair across its two electrodes (its loads' `rl` is that of an
    /// optional bleed resistor on each electrode, infinite without one).
    Pair(CapacitorPair),
}

/// A pair's node voltages, capacitances and their slopes at one state.
#[derive(Debug, Clone, Copy)]
pub(super) struct PairState {
    /// Node voltages (V).
    pub(super) v: [f64; 2],
    /// `D_i = C_i + Cp + CL` (F).
    pub(super) d: [f64; 2],
    /// `dC_i / dx` (F/m).
    pub(super) a: [f64; 2],
}
