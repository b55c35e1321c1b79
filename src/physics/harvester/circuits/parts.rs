//! The parts of an interface circuit, evaluated from the device's description
//! ([`crate::device::interface`]): the diodes' law, the DC load the storage capacitor feeds,
//! and the synchronous switch acting at the displacement extrema. [`super::bridge`] writes the
//! circuit's modes, guards and switches with them.

use crate::device::DcLoad;

/// The diodes, evaluated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DiodeLaw {
    /// Forward drop and on-resistance per diode.
    PiecewiseLinear {
        /// V_F (V).
        vf: f64,
        /// R_on (ohm).
        ron: f64,
    },
    /// Shockley: saturation current and `n V_T` (V).
    Shockley {
        /// I_s (A).
        is: f64,
        /// n V_T (V).
        nvt: f64,
    },
}

/// The DC load, evaluated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Sink {
    /// A resistor (ohm).
    Resistor(f64),
    /// A battery: voltage (V) and series resistance (ohm).
    Battery(f64, f64),
    /// Nothing.
    Open,
}

impl Sink {
    pub(crate) fn of(l: &DcLoad) -> Self {
        match *l {
            DcLoad::Resistor { resistance_ohm } => Sink::Resistor(resistance_ohm),
            DcLoad::Battery {
                voltage_v,
                series_resistance_ohm,
            } => Sink::Battery(voltage_v, series_resistance_ohm),
            DcLoad::Open => Sink::Open,
        }
    }

    /// The current drawn from the storage at its voltage `vs` (A).
    #[inline(always)]
    pub fn current(&self, vs: f64) -> f64 {
        match *self {
            Sink::Resistor(r) => vs / r,
            Sink::Battery(vb, r) => (vs - vb) / r,
            Sink::Open => 0.0,
        }
    }
}

/// The synchronous switch, if any.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Switch {
    /// None: a plain bridge.
    None,
    /// Parallel SSHI with inversion factor gamma.
    Parallel(f64),
    /// Series SSHI with inversion factor gamma.
    Series(f64),
    /// SECE with efficiency eta.
    Sece(f64),
    /// SECE through its buck-boost inductor ([`super::sece_inductor`]).
    BuckBoost(BuckBoost),
    /// Parallel SSHI whose inversion rings through its inductor ([`super::sshi_inductor`]).
    Inverter(super::sshi_inductor::Inverter),
}

/// The buck-boost inductor of a SECE through its inductor, its resistance and its flyback
/// diode, evaluated; its behaviour is [`super::sece_inductor`]'s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BuckBoost {
    /// L (H).
    pub l: f64,
    /// R_L (ohm).
    pub rl: f64,
    /// The flyback diode's forward drop V_F (V).
    pub vf: f64,
    /// Index of the inductor current in the state.
    pub i: usize,
}

/// The shortest time constant (s) of an inductor `l` (H) with its resistance `rl` (ohm) in a
/// loop with the capacitance `cp` (F): the ring's `sqrt(L Cp)`, or `L / R_L` if shorter.
pub fn inductor_time_constant_s(l: f64, rl: f64, cp: f64) -> f64 {
    let ring = (l * cp).sqrt();
    if rl > 0.0 {
        ring.min(l / rl)
    } else {
        ring
    }
}
