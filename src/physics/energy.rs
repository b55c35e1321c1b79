//! Energy bookkeeping of the harvester: the power of every force, the stored energy, and an
//! augmented system ([`EnergyAudit`]) that integrates the work of each force beside the state,
//! so that a run can be checked against the energy balance.

use nalgebra::SVector;

use crate::drive::Excitation;
use crate::ode::{Guards, HybridSystem, Options};
use crate::physics::contact::Mode;
use crate::physics::harvester::{Harvester, State};

impl<E: Excitation> Harvester<E> {
    /// Instantaneous power terms at a state (W); see [`PowerTerms`].
    pub fn power_terms(&self, mode: Mode, t: f64, y: &State) -> PowerTerms {
        let el = self.electrical(y);
        let v = y[1];
        let stop_damping = match mode {
            Mode::Contact(side) => {
                let bracket = self.contact_bracket(side, y);
                if self.tension_free && bracket < 0.0 {
                    0.0
                } else {
                    self.bim * v * v
                }
            }
            _ => 0.0,
        };
        PowerTerms {
            excitation: self.mass_kg * self.excitation.accel(t) * v,
            mech_damping: self.damping * v * v,
            stop_damping,
            load: (el.v[0] * el.v[0] + el.v[1] * el.v[1]) / self.rl,
        }
    }

    /// Stored energy (J): kinetic, suspension, contact spring, and the capacitors.
    pub fn stored_energy(&self, mode: Mode, y: &State) -> f64 {
        let el = self.electrical(y);
        let contact = match mode {
            Mode::Contact(side) => self.law.energy(self.penetration(side, y[0])),
            _ => 0.0,
        };
        let mut e = 0.5 * self.mass_kg * y[1] * y[1] + 0.5 * self.km * y[0] * y[0] + contact;
        for i in 0..2 {
            let u = el.v[i] - self.vb;
            e += 0.5 * (el.c[i] + self.cp) * u * u + 0.5 * self.cl * el.v[i] * el.v[i];
        }
        e
    }

    /// Charge delivered by the bias source to the proof-mass electrode (C):
    /// sum_i (C_i + Cp)(Vb - V_i). The source's work is Vb times its change.
    pub fn source_charge(&self, y: &State) -> f64 {
        let el = self.electrical(y);
        (0..2)
            .map(|i| (el.c[i] + self.cp) * (self.vb - el.v[i]))
            .sum()
    }
}

/// Instantaneous power flows (W).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PowerTerms {
    /// Power delivered by the inertial force m a(t) v.
    pub excitation: f64,
    /// Dissipated in the mechanical damper, b v^2.
    pub mech_damping: f64,
    /// Dissipated in the end-stop damper, b_im v^2 while in contact.
    pub stop_damping: f64,
    /// Dissipated in both load resistors, (V1^2 + V2^2)/RL.
    pub load: f64,
}

/// The harvester with the work of every force accumulated as four extra states, for energy
/// audits: y[4] excitation work, y[5] mechanical damping, y[6] end-stop losses (damping, and
/// the spring energy dropped when a tension-free contact unloads), y[7] loads.
///
/// Over any run, `y[4] + Vb * delta(source_charge) = y[5] + y[6] + y[7] + delta(stored_energy)`
/// (see [`Harvester::stored_energy`] and [`Harvester::source_charge`]); the tests use it to
/// check the model and the integrator together.
#[derive(Debug, Clone)]
pub struct EnergyAudit<E: Excitation>(pub Harvester<E>);

/// Splits the audit state into the model state.
pub fn audit_state(y: &SVector<f64, 8>) -> State {
    State::new(y[0], y[1], y[2], y[3])
}

impl<E: Excitation> EnergyAudit<E> {
    /// Integrator options: the model's, with absolute tolerances for the energy accumulators
    /// of `rtol` times the suspension energy at the stop, km xmax^2 / 2.
    pub fn solver_options(&self, rtol: f64) -> Options<8> {
        let base = self.0.solver_options(rtol);
        let e_scale = 0.5 * self.0.km * self.0.xmax * self.0.xmax;
        let mut atol = SVector::<f64, 8>::repeat(e_scale * rtol);
        for i in 0..4 {
            atol[i] = base.atol[i];
        }
        Options {
            rtol,
            atol,
            h_max: base.h_max,
            h_min: base.h_min,
            h_init: base.h_init,
            max_steps: base.max_steps,
            event_time_tol: base.event_time_tol,
        }
    }

    /// Relative residual of the energy balance between the rest state and `y` (in `mode`):
    /// (work in - dissipated - stored) divided by the sum of the magnitudes of its terms
    /// (excitation work, source work, dissipation, change of stored energy). Dividing by the
    /// work in alone would be ill-conditioned for a detuned drive, whose net work passes
    /// through zero while energy sloshes in and out of the resonator.
    pub fn relative_residual(&self, mode: Mode, y: &SVector<f64, 8>) -> f64 {
        let h = &self.0;
        let s = audit_state(y);
        let stored = h.stored_energy(mode, &s) - h.stored_energy(Mode::Free, &State::zeros());
        let source = h.vb * (h.source_charge(&s) - h.source_charge(&State::zeros()));
        let dissipated = y[5] + y[6] + y[7];
        let scale = y[4].abs() + source.abs() + dissipated.abs() + stored.abs();
        (y[4] + source - dissipated - stored) / scale
    }
}

impl<E: Excitation> HybridSystem<8> for EnergyAudit<E> {
    type Mode = Mode;

    fn rhs(&self, mode: Mode, t: f64, y: &SVector<f64, 8>) -> SVector<f64, 8> {
        let s = audit_state(y);
        let f = self.0.rhs(mode, t, &s);
        let p = self.0.power_terms(mode, t, &s);
        SVector::<f64, 8>::from_column_slice(&[
            f[0],
            f[1],
            f[2],
            f[3],
            p.excitation,
            p.mech_damping,
            p.stop_damping,
            p.load,
        ])
    }

    fn guards(&self, mode: Mode, t: f64, y: &SVector<f64, 8>) -> Guards {
        self.0.guards(mode, t, &audit_state(y))
    }

    /// Switches mode; any stored energy that the switch makes disappear (a tension-free
    /// contact that unloads while still pressed drops the spring energy U(delta)) is booked
    /// as end-stop dissipation, so the balance stays exact.
    fn switch(&self, mode: Mode, i: usize, t: f64, y: &mut SVector<f64, 8>) -> Mode {
        let mut s = audit_state(y);
        let before = self.0.stored_energy(mode, &s);
        let m = self.0.switch(mode, i, t, &mut s);
        y[0] = s[0];
        y[6] += before - self.0.stored_energy(m, &s);
        m
    }

    fn next_breakpoint(&self, t: f64) -> f64 {
        self.0.next_breakpoint(t)
    }

    fn check_state(&self, mode: Mode, t: f64, y: &SVector<f64, 8>) -> Result<(), String> {
        self.0.check_state(mode, t, &audit_state(y))
    }
}
