//! The affine form of each linear mode of several masses, which the exact propagators use
//! ([`crate::study::flow`] under a sine, the records' affine steps on the sample grid).
//!
//! The dampers between the masses and to the frame are linear, and so are the springs unless
//! one has a cubic term (then no mode is affine), so a mode is affine when the port is (a
//! loaded piezoelectric element, coil or none; behind a circuit, a
//! piezoelectric element or a coil with piecewise-linear diodes) and each contact adds no
//! nonlinear force: apart, clipped (a tension-free stop whose bracket is negative), or pressed
//! with a linear spring and a viscous damper. A resting contact (a mass held on a frame stop,
//! or two masses moving as one body until their holding force changes sign) is linear too, but
//! its release depends on the drive (the drive's inertial force presses a mass onto a frame
//! stop or pulls it off): [`Model::affine`] leaves it to the adaptive integrator, as the
//! one-mass harvester does, and [`Model::driven_affine`] gives it with the release as a guard
//! on the state and the drive. Its matrix is the Jacobian with the constraint (the held mass's
//! rows zero, or the pair's common acceleration); the holding force, `s F_i` on a frame stop
//! and `s (m_j F_i - m_i F_j) / (m_i + m_j)` between two masses, is affine in each mass's
//! free force `F_i`, whose rows are the free mode's acceleration rows times the mass, plus
//! the drive's weight on the mass.
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
use crate::model::{Affine, AffineGuard, Contact, DrivenAffine, Mode, Model};

use super::super::circuits::CircuitMode;
use super::super::port::Port;
use super::super::STOP_GUARDS;
use super::{ChainContact, MassChain};

impl<const N: usize> MassChain<N> {
    /// True when no spring has a cubic term.
    fn springs_linear(&self) -> bool {
        self.springs.iter().all(|s| s.cubic_n_per_m3 == 0.0)
    }

    /// The affine form of `mode` (see the module docs), or `None` where it is not affine.
    pub(super) fn affine_form(&self, mode: Mode) -> Option<Affine<N>> {
        if !(self.inner.port_is_affine() && self.springs_linear()) {
            return None;
        }
        let apart = mode.without_contacts();
        let rest = SVector::<f64, N>::zeros();
        let mut l = self.jacobian(apart, &rest);
        let mut d = self.rhs(apart, &rest, 0.0);
        let mut guards = Vec::new();
        for (k, c) in self.contacts.iter().enumerate() {
            let state = mode.contact(k);
            let (n, g0) = self.penetration_row(c);
            let (ix, jx) = (self.bodies[c.mass].ix, c.other.map(|o| self.bodies[o].ix));
            let gap = -g0;
            if state == Contact::Apart {
                guards.push(AffineGuard {
                    index: 2 * k,
                    n,
                    g0,
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
        self.port_guards(mode, &mut guards);
        let c = self.drive_column(mode);
        Some(Affine { l, c, d, guards })
    }

    /// The affine form of `mode`, in which the rigid contact `k` rests and every other contact
    /// is apart (see the module docs): the right-hand side with the contact's constraint (a
    /// mass held on a frame stop, or two masses moving as one), the other contacts'
    /// penetrations, and the release, where the holding force changes sign, as a guard on the
    /// state and the drive; `None` where the mode is not affine.
    pub(super) fn resting_form(&self, mode: Mode, k: usize) -> Option<DrivenAffine<N>> {
        let rests = matches!(self.contacts.get(k)?.stop, StopModel::Rigid { .. });
        let others_apart =
            (0..self.contacts.len()).all(|j| j == k || mode.contact(j) == Contact::Apart);
        if !(rests && others_apart && self.inner.port_is_affine() && self.springs_linear()) {
            return None;
        }
        let apart = mode.without_contacts();
        let rest = SVector::<f64, N>::zeros();
        let mut guards = Vec::new();
        let mut drive = Vec::new();
        for (j, c) in self.contacts.iter().enumerate().filter(|(j, _)| *j != k) {
            let (n, g0) = self.penetration_row(c);
            guards.push(AffineGuard {
                index: 2 * j,
                n,
                g0,
            });
            drive.push(0.0);
        }
        // Each mass's force without the constraint, `m_i (row_i . y + d_i) + w_i a`, from the
        // free mode's acceleration rows and the drive's weight on the mass.
        let (free, free_d, weights) = (
            self.jacobian(apart, &rest),
            self.rhs(apart, &rest, 0.0),
            self.drive_masses(),
        );
        let force = |i: usize| {
            let b = &self.bodies[i];
            let row: SVector<f64, N> = free.row(b.ix + 1).transpose() * b.mass_kg;
            (row, free_d[b.ix + 1] * b.mass_kg, weights[i])
        };
        // The holding force as `holding` has it; the guard is its negative.
        let c = &self.contacts[k];
        let (fi, gi, wi) = force(c.mass);
        let (n, g0, w) = match c.other {
            None => (fi * c.sign, gi * c.sign, wi * c.sign),
            Some(o) => {
                let (fj, gj, wj) = force(o);
                let (mi, mj) = (self.bodies[c.mass].mass_kg, self.bodies[o].mass_kg);
                let s = c.sign / (mi + mj);
                (
                    (fi * mj - fj * mi) * s,
                    (gi * mj - gj * mi) * s,
                    (wi * mj - wj * mi) * s,
                )
            }
        };
        guards.push(AffineGuard {
            index: 2 * k + 1,
            n: -n,
            g0: -g0,
        });
        drive.push(-w);
        self.port_guards(mode, &mut guards);
        drive.resize(guards.len(), 0.0);
        let affine = Affine {
            l: self.jacobian(mode, &rest),
            c: self.drive_column(mode),
            d: self.rhs(mode, &rest, 0.0),
            guards,
        };
        Some(DrivenAffine { affine, drive })
    }

    /// A contact's penetration `s (x_i - x_j) - gap` (the frame's `x_j` zero) as a row on
    /// the state and its offset.
    fn penetration_row(&self, c: &ChainContact) -> (SVector<f64, N>, f64) {
        let mut n = SVector::<f64, N>::zeros();
        n[self.bodies[c.mass].ix] = c.sign;
        if let Some(o) = c.other {
            n[self.bodies[o].ix] = -c.sign;
        }
        (n, -c.stop.gap())
    }

    /// Appends the port's conduction pieces (behind a circuit) to `guards`.
    fn port_guards(&self, mode: Mode, guards: &mut Vec<AffineGuard<N>>) {
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
