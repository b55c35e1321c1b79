//! The harvester's energy ledger: the power of every force and loss, the stored energy, and
//! what the switches move.
//!
//! Over any run, the drive's work + a bias source's work + re-engagement gains = mechanical
//! damping + end-stop damping + clip losses + impact losses + projections + the port's terms
//! (the loads and a coil's resistance; behind a circuit, the element's resistances, the
//! diodes, the switch and the DC load) + the change of the stored energy.
//!
//! A tension-free stop (eq 1 with the bracket clipped at zero) also moves energy at its mode
//! switches: when the contact force would turn tensile while the mass is still pressed in, the
//! contact unloads and its spring energy U(delta) leaves the stored energy (a clip loss); if a
//! clipped contact re-engages while pressed, U(delta) reappears (a re-engagement gain). An
//! impact on a rigid stop loses kinetic energy; the projections onto a stop or onto a
//! conduction constraint at a switch move the stored energy by the order of the event
//! tolerance; a circuit's reset loses what its switch and diodes take.

use nalgebra::SVector;

use crate::circuits::CircuitMode;
use crate::model::{Contact, Flow, LedgerTerm, Mode, SwitchKind};

use super::port::{head, Port};
use super::stops::FrameStops;
use super::Harvester;

/// The drive's work, `m a v`.
pub const DRIVE: usize = 0;
/// The mechanical damper, `b v^2`.
pub const MECH_DAMPING: usize = 1;
/// The end-stop damper while the contact force acts.
pub const STOP_DAMPING: usize = 2;
/// Contact spring energy dropped when a tension-free contact unloads while pressed.
pub const CLIP_LOSSES: usize = 3;
/// Contact spring energy that reappears when a clipped contact re-engages while pressed.
pub const REENGAGEMENT_GAINS: usize = 4;
/// Kinetic energy lost at impacts on rigid stops.
pub const IMPACT_LOSSES: usize = 5;
/// Stored energy moved by the projections at switches (signed).
pub const PROJECTIONS: usize = 6;
/// The loads of a loaded transducer (both of a pair), or a circuit's element losses (a coil's
/// resistance, a pair's bleed resistors).
pub const LOADS: usize = 7;
/// A loaded coil's resistance; a circuit's diodes.
pub const INTERNAL: usize = 8;
/// A circuit's synchronous switch.
pub const SWITCHING: usize = 9;
/// A circuit's DC load (or battery).
pub const DC_LOAD: usize = 10;

fn term(name: &str, flow: Flow) -> LedgerTerm {
    LedgerTerm {
        name: name.to_string(),
        flow,
    }
}

impl<const N: usize> Harvester<N> {
    pub(super) fn make_terms(&self) -> Vec<LedgerTerm> {
        let mut t = vec![
            term("drive", Flow::In),
            term("mech_damping", Flow::Out),
            term("stop_damping", Flow::Out),
            term("clip_losses", Flow::Out),
            term("reengagement_gains", Flow::In),
            term("impact_losses", Flow::Out),
            term("projections", Flow::Out),
        ];
        match &self.port {
            Port::Loaded(_) => {
                t.push(term("loads", Flow::Out));
                t.push(term("coil", Flow::Out));
            }
            Port::Circuit(_) => {
                t.push(term("element", Flow::Out));
                t.push(term("diodes", Flow::Out));
                t.push(term("switching", Flow::Out));
                t.push(term("dc_load", Flow::Out));
            }
        }
        t
    }

    /// The power of each continuous term (W), into `p` (see the module docs).
    pub(super) fn power_terms(&self, mode: Mode, y: &SVector<f64, N>, a: f64, p: &mut [f64]) {
        let v = y[1];
        let stop_damping = match FrameStops::touching(mode) {
            Some((side, Contact::Pressed)) => match self.stop(side) {
                Some(s) => {
                    let delta = self.penetration(side, y[0]);
                    if s.tension_free() && self.stops.bracket(side, y[0], v) < 0.0 {
                        0.0
                    } else {
                        s.damping_power(delta, side.sign() * v)
                    }
                }
                None => 0.0,
            },
            _ => 0.0,
        };
        p[DRIVE] = self.mass_kg * a * v;
        p[MECH_DAMPING] = self.damping * v * v;
        p[STOP_DAMPING] = stop_damping;
        p[CLIP_LOSSES] = 0.0;
        p[REENGAGEMENT_GAINS] = 0.0;
        p[IMPACT_LOSSES] = 0.0;
        p[PROJECTIONS] = 0.0;
        match &self.port {
            Port::Loaded(t) => {
                let h = head(y);
                p[LOADS] = t.load_power(&h);
                p[INTERNAL] = t.internal_loss(&h);
            }
            Port::Circuit(c) => {
                let bridge = CircuitMode::of(mode.circuit(0)).bridge;
                p[LOADS] = c.element_loss(bridge, y);
                p[INTERNAL] = c.diode_power(bridge, y);
                p[SWITCHING] = 0.0;
                p[DC_LOAD] = c.dc_power(y);
            }
        }
    }

    /// Stored energy (J): kinetic, suspension, contact spring, and the port's.
    pub(super) fn energy(&self, mode: Mode, y: &SVector<f64, N>) -> f64 {
        let contact = match FrameStops::touching(mode) {
            Some((side, Contact::Pressed)) => self
                .stop(side)
                .map_or(0.0, |s| s.energy(self.penetration(side, y[0]))),
            _ => 0.0,
        };
        let e = 0.5 * self.mass_kg * y[1] * y[1] + self.suspension_energy(y[0]) + contact;
        match &self.port {
            Port::Loaded(t) => t.add_stored_energy(e, &head(y)),
            Port::Circuit(c) => e + c.stored_energy(y),
        }
    }

    /// The work of a pair's bias source from the rest state to `y`: Vb times the charge it
    /// delivered (J); zero without a source.
    pub(super) fn bias_work(&self, y: &SVector<f64, N>) -> f64 {
        let rest = self.static_state_at(0.0, 0.0);
        match &self.port {
            Port::Loaded(t) => {
                t.bias_v() * (t.source_charge(&head(y)) - t.source_charge(&head(&rest)))
            }
            Port::Circuit(c) => c.bias_v() * (c.source_charge(y) - c.source_charge(&rest)),
        }
    }

    /// Books what the switch from `from` to `to` moved, from the states `before` and `after`
    /// it (see the module docs).
    pub(super) fn book(
        &self,
        from: Mode,
        to: Mode,
        before: &SVector<f64, N>,
        after: &SVector<f64, N>,
        book: &mut [f64],
    ) {
        let dropped = self.energy(from, before) - self.energy(to, after);
        match SwitchKind::between(from, to) {
            SwitchKind::Circuit => {
                let mut rest = dropped;
                if let Port::Circuit(c) = &self.port {
                    let (a, b) = (
                        CircuitMode::of(from.circuit(0)),
                        CircuitMode::of(to.circuit(0)),
                    );
                    // An extremum flips the heading; its reset loses what the switch takes.
                    if a.heading != b.heading {
                        let mut probe = *before;
                        probe[1] = 0.0;
                        let loss = c.reset(&mut probe);
                        book[INTERNAL] += loss.diode;
                        book[SWITCHING] += loss.switching;
                        rest -= loss.diode + loss.switching;
                    }
                }
                book[PROJECTIONS] += rest;
            }
            SwitchKind::Clip => {
                let k = changed_contact(from, to);
                if from.contact(k) == Contact::Pressed {
                    book[CLIP_LOSSES] += dropped
                } else {
                    book[REENGAGEMENT_GAINS] -= dropped
                }
            }
            SwitchKind::Rebound | SwitchKind::Stick => book[IMPACT_LOSSES] += dropped,
            _ => book[PROJECTIONS] += dropped,
        }
    }
}

/// The first contact whose state differs between two modes.
fn changed_contact(a: Mode, b: Mode) -> usize {
    (0..crate::model::MAX_CONTACTS)
        .find(|&k| a.contact(k) != b.contact(k))
        .unwrap_or(0)
}
