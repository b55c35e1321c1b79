//! A harvester's port: its transducer with what the transducer drives, either the
//! transducer's own resistive loads (eqs 7-10 and their analogues, [`TransducerModel`]) or an
//! interface circuit into a storage capacitor ([`Circuit`]).

use nalgebra::{SMatrix, SVector};

use crate::physics::transducer::{State, TransducerModel};

use crate::circuits::{Bridge, Circuit, CircuitMode, Element};

/// The transducer and what it drives (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Port {
    /// The transducer with its own resistive loads (or no transducer): the state's
    /// components 2 and 3 are its (unused ones held at zero).
    Loaded(TransducerModel),
    /// The transducer behind an interface circuit.
    Circuit(Circuit),
}

/// The first four components of a state, where a loaded transducer reads its own.
#[inline(always)]
pub(crate) fn head<const N: usize>(y: &SVector<f64, N>) -> State {
    State::new(y[0], y[1], y[2], y[3])
}

impl Port {
    /// The force on the mass (N), with the rates of the port's components written into `d` (at
    /// the state's indices), in the circuit's mode `bits`.
    #[inline(always)]
    pub fn force_and_rates<const N: usize>(
        &self,
        bits: u8,
        y: &SVector<f64, N>,
        d: &mut SVector<f64, N>,
    ) -> f64 {
        match self {
            Port::Loaded(t) => {
                let (fe, rates) = t.force_and_rates(&head(y));
                d[2] = rates[0];
                d[3] = rates[1];
                fe
            }
            Port::Circuit(c) => c.force_and_rates(CircuitMode::of(bits).bridge, y, d),
        }
    }

    /// The force on the mass alone (N).
    #[inline(always)]
    pub fn force<const N: usize>(&self, bits: u8, y: &SVector<f64, N>) -> f64 {
        let mut d = SVector::<f64, N>::zeros();
        self.force_and_rates(bits, y, &mut d)
    }

    /// Number of the port's guards: none for loads, one for a circuit.
    pub fn guard_count(&self) -> usize {
        match self {
            Port::Loaded(_) => 0,
            Port::Circuit(_) => 1,
        }
    }

    /// The state's dimension the port needs: four for a loaded transducer and for a
    /// piezoelectric element or a coil behind a circuit (the element's component and the
    /// storage voltage), five for a pair behind a circuit or a piezoelectric element behind a
    /// SECE through its inductor (its current).
    pub fn dimension(&self) -> usize {
        match self {
            Port::Loaded(_) => 4,
            Port::Circuit(c) => c.dimension(),
        }
    }

    /// The circuit, if any.
    pub fn circuit(&self) -> Option<&Circuit> {
        match self {
            Port::Circuit(c) => Some(c),
            Port::Loaded(_) => None,
        }
    }

    /// The components held at zero: a loaded transducer's unused ones, a coil's without
    /// inductance.
    pub fn unused(&self) -> &'static [usize] {
        match self {
            Port::Loaded(t) => match t.active_states() {
                2 => &[2, 3],
                3 => &[3],
                _ => &[],
            },
            Port::Circuit(Circuit {
                element: Element::Coil { l, .. },
                ..
            }) if *l <= 0.0 => &[2],
            Port::Circuit(_) => &[],
        }
    }

    /// The circuit's mode at a state (zero bits for loads).
    pub fn mode_bits<const N: usize>(&self, y: &SVector<f64, N>) -> u8 {
        match self {
            Port::Loaded(_) => 0,
            Port::Circuit(c) => c.mode_of(y).bits(),
        }
    }

    /// The port's part of the Jacobian (rows of its components, and its force's gradient in
    /// row 1 divided by the mass `m`), in circuit mode `bits`; a loaded transducer's part is
    /// written by the harvester with its mechanics (see `linearisation.rs`).
    pub fn circuit_jacobian<const N: usize>(
        &self,
        bits: u8,
        y: &SVector<f64, N>,
        m: f64,
        sc: &SVector<f64, N>,
        j: &mut SMatrix<f64, N, N>,
    ) {
        if let Port::Circuit(c) = self {
            c.jacobian(CircuitMode::of(bits).bridge, y, m, sc, j);
        }
    }

    /// The bridge of a circuit's mode bits.
    pub fn bridge(bits: u8) -> Bridge {
        CircuitMode::of(bits).bridge
    }
}
