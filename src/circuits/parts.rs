//! The parts of an interface circuit, evaluated from the device's description
//! ([`crate::device::interface`]): the diodes' law, the DC load the storage capacitor feeds,
//! and the inductor a circuit kind may hold. [`super::bridge`] writes the circuit's modes,
//! guards and switches with them.

use nalgebra::SVector;

use super::description::{DcLoad, Diode};

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

impl DiodeLaw {
    /// The law of the described diodes.
    pub(crate) fn of(d: &Diode) -> Self {
        match *d {
            Diode::PiecewiseLinear {
                forward_drop_v,
                on_resistance_ohm,
            } => DiodeLaw::PiecewiseLinear {
                vf: forward_drop_v,
                ron: on_resistance_ohm,
            },
            Diode::Shockley {
                saturation_current_a,
                ideality,
                thermal_voltage_v,
            } => DiodeLaw::Shockley {
                is: saturation_current_a,
                nvt: ideality * thermal_voltage_v,
            },
        }
    }
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

/// An inductor with its series resistance, its current a state component of its own,
/// evaluated: the part every circuit with an inductor holds ([`super::BuckBoost`],
/// [`super::Inverter`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Inductor {
    /// L (H).
    pub l: f64,
    /// R_L (ohm).
    pub rl: f64,
    /// Index of the inductor current in the state.
    pub i: usize,
}

impl Inductor {
    /// Power lost in the resistance (W) while the inductor carries the current `i` (A).
    #[inline(always)]
    pub fn resistive_power(&self, i: f64) -> f64 {
        self.rl * i * i
    }

    /// The inductor's energy `L I^2 / 2` (J).
    #[inline]
    pub fn stored_energy<const N: usize>(&self, y: &SVector<f64, N>) -> f64 {
        0.5 * self.l * y[self.i] * y[self.i]
    }

    /// The current's scale: the peak current of the element's capacitance `cp` discharging
    /// through the inductor from the element's voltage scale `vp_scale`, `Vp sqrt(Cp / L)`.
    pub fn scale<const N: usize>(&self, cp: f64, vp_scale: f64, sc: &mut SVector<f64, N>) {
        sc[self.i] = vp_scale * (cp / self.l).sqrt();
    }

    /// The shortest time constant (s) of the inductor in a loop with the element's
    /// capacitance `cp`: the ring's `sqrt(L Cp)`, or `L / R_L` if shorter.
    pub fn time_constant_s(&self, cp: f64) -> f64 {
        let ring = (self.l * cp).sqrt();
        if self.rl > 0.0 {
            ring.min(self.l / self.rl)
        } else {
            ring
        }
    }
}
