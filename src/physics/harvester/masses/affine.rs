//! The affine form of each linear mode of several masses, which the exact propagators use
//! ([`crate::study::flow`] under a sine, the records' affine steps on the sample grid).
//!
//! The springs and dampers between the masses and to the frame are linear, so a mode is affine
//! when the port is (a loaded piezoelectric element, coil or none; behind a circuit, a
//! piezoelectric element or a coil with piecewise-linear diodes) and each contact adds no
//! nonlinear force: apart, clipped (a tension-free stop whose bracket is negative), or pressed
//! with a linear spring and a viscous damper. A resting contact (a mass held on a frame stop,
//! or two masses moving as one body until their holding force changes sign) has a guard that
//! depends on the drive and is left to the adaptive integrator, as the one-mass harvester
//! leaves it.
//!
//! The matrix is the Jacobian with every contact apart, at rest (the springs, the dampers and
//! the port do not depend on the state there), plus each pressed contact's spring and damper
//! on the relative coordinates of its masses; the constant term is the right-hand side at rest
//! with no drive (a bridge's drop, a battery) plus each pressed contact's spring pushed in
//! from the gap. Every guard is affine in the state: a contact's penetration
//! `s (x_i - x_j) - gap` (the frame's `x_j` zero), its bracket `k delta + b delta'`, and the
//! port's conduction pieces, which act on the transducer's mass at the state's head as the
//! one-mass harvester's do.

use nalgebra::{SMatrix, SVector};

use crate::laws::contact::{ContactDamping, ContactLaw, StopModel};
use crate::model::{Affine, AffineGuard, Contact, Mode, Model};

use super::super::circuits::CircuitMode;
use super::super::port::Port;
use super::super::STOP_GUARDS;
use super::{ChainContact, MassChain};

impl<const N: usize> MassChain<N> {
    /// The affine form of `mode` (see the module docs), or `None` where it is not affine.
    pub(super) fn affine_form(&self, mode: Mode) -> Option<Affine<N>> {
        if !self.inner.port_is_affine() {
            return None;
        }
        let apart = mode.without_contacts();
        let rest = SVector::<f64, N>::zeros();
        let mut l = self.jacobian(apart, &rest);
        let mut d = self.rhs(apart, &rest, 0.0);
        let mut guards = Vec::new();
        for (k, c) in self.contacts.iter().enumerate() {
            let state = mode.contact(k);
            // The penetration `s (x_i - x_j) - gap` as a row on the state.
            let mut n = SVector::<f64, N>::zeros();
            let (ix, jx) = (self.bodies[c.mass].ix, c.other.map(|o| self.bodies[o].ix));
            n[ix] = c.sign;
            if let Some(jx) = jx {
                n[jx] = -c.sign;
            }
            let gap = c.stop.gap();
            if state == Contact::Apart {
                guards.push(AffineGuard {
                    index: 2 * k,
                    n,
                    g0: -gap,
                });
                continue;
            }
            let StopModel::Compliant {
                law: ContactLaw::Linear(stiffness),
                damping: ContactDamping::Viscous(b),
                tension_free,
                ..
            } = c.stop
            else {
                return None;
            };
            // Leaving the contact: the penetration turns negative.
            guards.push(AffineGuard {
                index: 2 * k,
                n: -n,
                g0: gap,
            });
            // The bracket `k delta + b delta'`, delta' the same row on the velocities.
            let mut bracket = n * stiffness;
            bracket[ix + 1] = c.sign * b;
            if let Some(jx) = jx {
                bracket[jx + 1] = -c.sign * b;
            }
            let bracket_g0 = -stiffness * gap;
            match state {
                Contact::Pressed => {
                    if tension_free {
                        guards.push(AffineGuard {
                            index: 2 * k + 1,
                            n: -bracket,
                            g0: -bracket_g0,
                        });
                    }
                    self.press(c, &bracket, bracket_g0, &mut l, &mut d);
                }
                Contact::Clipped => guards.push(AffineGuard {
                    index: 2 * k + 1,
                    n: bracket,
                    g0: bracket_g0,
                }),
                Contact::Apart | Contact::Resting => return None,
            }
        }
        if let Port::Circuit(circuit) = &self.inner.port {
            let cm = CircuitMode::of(mode.circuit(0));
            let first = 2 * self.contacts.len();
            for piece in self.inner.circuit_guard_pieces(circuit, cm) {
                guards.push(AffineGuard {
                    index: piece.index - STOP_GUARDS + first,
                    ..piece
                });
            }
        }
        let c = self.drive_column(mode);
        Some(Affine { l, c, d, guards })
    }

    /// Adds a pressed contact's force, `-s B` on its mass and `+s B` on the other (Newton's
    /// third law) with the bracket `B = bracket . y + g0`, to the rows of the masses'
    /// accelerations.
    fn press(
        &self,
        c: &ChainContact,
        bracket: &SVector<f64, N>,
        g0: f64,
        l: &mut SMatrix<f64, N, N>,
        d: &mut SVector<f64, N>,
    ) {
        let on_other = c.other.map(|j| (j, c.sign));
        for (body, s) in std::iter::once((c.mass, -c.sign)).chain(on_other) {
            let row = self.bodies[body].ix + 1;
            let m = self.bodies[body].mass_kg;
            for col in 0..N {
                l[(row, col)] += s * bracket[col] / m;
            }
            d[row] += s * g0 / m;
        }
    }
}
