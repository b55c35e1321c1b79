//! Energy bookkeeping of the harvester: the power of every force, the stored energy, and an
//! augmented system ([`EnergyAudit`]) that integrates the work of each force beside the state,
//! so that a run can be checked against the energy balance.
//!
//! The tension-free end stop (eq 1 with the bracket clipped at zero) also moves energy at its
//! mode switches: when the contact force would turn tensile while the mass is still pressed
//! in, the contact unloads and its spring energy U(delta) leaves the stored energy (a clip
//! loss); if a clipped contact re-engages while pressed, U(delta) reappears (a re-engagement
//! gain). The audit books the two apart, so that the end stop's net absorption, damper plus
//! clip losses minus re-engagement gains, shows whether the variant is passive.

use nalgebra::SVector;

use crate::drive::Excitation;
use crate::ode::{HybridSystem, Options};
use crate::physics::contact::Mode;
use crate::physics::harvester::{Harvester, State};

impl<E: Excitation> Harvester<E> {
    /// Instantaneous power terms at a state (W); see [`PowerTerms`].
    pub fn power_terms(&self, mode: Mode, t: f64, y: &State) -> PowerTerms {
        let v = y[1];
        let stop_damping = match mode {
            Mode::Contact(side) => match self.stop(side) {
                Some(s) => {
                    let delta = self.penetration(side, y[0]);
                    if s.tension_free() && self.contact_bracket(side, y) < 0.0 {
                        0.0
                    } else {
                        s.damping_power(delta, side.sign() * v)
                    }
                }
                None => 0.0,
            },
            _ => 0.0,
        };
        PowerTerms {
            excitation: self.mass_kg * self.excitation.accel(t) * v,
            mech_damping: self.damping * v * v,
            stop_damping,
            load: self.transducer.load_power(y),
            internal: self.transducer.internal_loss(y),
        }
    }

    /// Stored energy (J): kinetic, suspension, contact spring, and the transducer's.
    pub fn stored_energy(&self, mode: Mode, y: &State) -> f64 {
        let contact = match mode {
            Mode::Contact(side) => self
                .stop(side)
                .map_or(0.0, |s| s.energy(self.penetration(side, y[0]))),
            _ => 0.0,
        };
        let e = 0.5 * self.mass_kg * y[1] * y[1] + self.suspension_energy(y[0]) + contact;
        self.transducer.add_stored_energy(e, y)
    }

    /// Charge delivered by the bias source of a capacitor pair to the proof-mass electrode
    /// (C): sum_i (C_i + Cp)(Vb - V_i); zero without a source. The source's work is Vb times
    /// its change.
    pub fn source_charge(&self, y: &State) -> f64 {
        self.transducer.source_charge(y)
    }
}

/// Instantaneous power flows (W).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PowerTerms {
    /// Power delivered by the inertial force m a(t) v.
    pub excitation: f64,
    /// Dissipated in the mechanical damper, b v^2.
    pub mech_damping: f64,
    /// Dissipated by the contact damping (eq 1's b_im v^2, or Hunt-Crossley's) while the
    /// contact force acts.
    pub stop_damping: f64,
    /// Dissipated in the loads: (V1^2 + V2^2)/RL for a pair, V^2/R or I^2 R for one load.
    pub load: f64,
    /// Dissipated inside the transducer: the coil resistance's I^2 Rc.
    pub internal: f64,
}

/// Number of states of the audit: the model's four and nine accumulators ([`ledger_index`]).
pub const AUDIT_DIM: usize = 13;

/// The audit state: (x, v, s1, s2) and the accumulators of [`EnergyAudit`].
pub type AuditState = SVector<f64, AUDIT_DIM>;

/// Indices of the accumulators in [`AuditState`] (J).
pub mod ledger_index {
    /// Work of the inertial force m a(t) v.
    pub const EXCITATION: usize = 4;
    /// Mechanical damper, b v^2.
    pub const MECH_DAMPING: usize = 5;
    /// End-stop damper, b_im v^2 while the contact force acts.
    pub const STOP_DAMPING: usize = 6;
    /// Both load resistors.
    pub const LOADS: usize = 7;
    /// Contact spring energy U(delta) dropped when a tension-free contact unloads while still
    /// pressed (Contact -> Clipped).
    pub const CLIP_LOSSES: usize = 8;
    /// Contact spring energy U(delta) that reappears when a clipped contact re-engages while
    /// still pressed (Clipped -> Contact).
    pub const REENGAGEMENT_GAINS: usize = 9;
    /// Stored energy removed by the projections onto the stop at entry and exit (signed, of the
    /// order of the event time tolerance).
    pub const PROJECTIONS: usize = 10;
    /// Kinetic energy lost at impacts on rigid stops, (1 - e^2) m v^2 / 2 each (and all of
    /// it when the mass sticks).
    pub const IMPACT_LOSSES: usize = 11;
    /// Dissipated inside the transducer (a coil's resistance).
    pub const INTERNAL: usize = 12;
}

/// The harvester with the work of every force accumulated as extra states (see
/// [`ledger_index`]): the excitation's work, the mechanical damper, the end-stop damper, the
/// loads, the transducer's internal losses, and, booked at mode switches, the clip losses, the
/// re-engagement gains, the impact losses and the projections.
///
/// Over any run, excitation + source + re-engagement gains = mechanical damping + end-stop
/// damping + loads + internal losses + clip losses + impact losses + projections + change of
/// stored energy, where the source's
/// work is Vb times the change of [`Harvester::source_charge`] and the stored energy is
/// [`Harvester::stored_energy`]; [`EnergyAudit::ledger`] evaluates every term and the tests
/// use it to check the model and the integrator together. The end stop absorbs
/// end-stop damping + clip losses - re-engagement gains in all.
#[derive(Debug, Clone)]
pub struct EnergyAudit<E: Excitation>(pub Harvester<E>);

/// Splits the audit state into the model state.
pub fn audit_state(y: &AuditState) -> State {
    State::new(y[0], y[1], y[2], y[3])
}

/// The energy balance of an audited run from the rest state (J).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct EnergyLedger {
    /// Work of the inertial force.
    pub excitation: f64,
    /// Work of the bias source, Vb times the charge it delivered.
    pub source: f64,
    /// Mechanical damper.
    pub mech_damping: f64,
    /// End-stop damper.
    pub stop_damping: f64,
    /// Load resistors.
    pub loads: f64,
    /// Contact spring energy dropped at clips (tension-free contact only).
    pub clip_losses: f64,
    /// Contact spring energy restored at re-engagements (tension-free contact only).
    pub reengagement_gains: f64,
    /// Stored energy removed by the projections onto the stop.
    pub projections: f64,
    /// Kinetic energy lost at impacts on rigid stops.
    pub impact_losses: f64,
    /// Dissipated inside the transducer (a coil's resistance).
    pub internal: f64,
    /// Change of the stored energy.
    pub stored_change: f64,
}

impl EnergyLedger {
    /// Energy in minus energy out and stored (J); zero for an exact run.
    pub fn residual(&self) -> f64 {
        self.excitation + self.source + self.reengagement_gains
            - self.mech_damping
            - self.stop_damping
            - self.loads
            - self.clip_losses
            - self.projections
            - self.impact_losses
            - self.internal
            - self.stored_change
    }

    /// The residual divided by the sum of the magnitudes of the terms. Dividing by the work
    /// in alone would be ill-conditioned for a detuned drive, whose net work passes through
    /// zero while energy sloshes in and out of the resonator.
    pub fn relative_residual(&self) -> f64 {
        let scale = self.excitation.abs()
            + self.source.abs()
            + self.reengagement_gains.abs()
            + self.mech_damping.abs()
            + self.stop_damping.abs()
            + self.loads.abs()
            + self.clip_losses.abs()
            + self.projections.abs()
            + self.impact_losses.abs()
            + self.internal.abs()
            + self.stored_change.abs();
        self.residual() / scale
    }

    /// Net energy absorbed by the end stop: its damper plus the clip losses minus the
    /// re-engagement gains.
    pub fn stop_absorbed(&self) -> f64 {
        self.stop_damping + self.clip_losses - self.reengagement_gains
    }

    /// Books the stored energy `dropped_j` (before minus after) that a switch from `from` to
    /// `to` makes disappear or appear: a tension-free contact that unloads while still
    /// pressed drops the spring energy U(delta) (a clip loss), one that re-engages while
    /// pressed restores it (a re-engagement gain), and the projection onto the stop at entry
    /// and exit moves the stored energy by the order of the event time tolerance; an impact on
    /// a rigid stop loses kinetic energy (an impact loss).
    pub fn book_switch(&mut self, from: Mode, to: Mode, dropped_j: f64) {
        match (from, to) {
            (Mode::Contact(_), Mode::Clipped(_)) => self.clip_losses += dropped_j,
            (Mode::Clipped(_), Mode::Contact(_)) => self.reengagement_gains -= dropped_j,
            (Mode::Free, Mode::Free) | (Mode::Free, Mode::Stuck(_)) => {
                self.impact_losses += dropped_j
            }
            _ => self.projections += dropped_j,
        }
    }
}

impl<E: Excitation> EnergyAudit<E> {
    /// Integrator options: the model's, with absolute tolerances for the energy accumulators
    /// of `rtol` times the suspension energy at the displacement scale, km x_s^2 / 2.
    pub fn solver_options(&self, rtol: f64) -> Options<AuditState> {
        let base = self.0.solver_options(rtol);
        let xs = self.0.x_scale();
        let e_scale = 0.5 * self.0.well_stiffness() * xs * xs;
        let mut atol = AuditState::repeat(e_scale * rtol);
        atol.fixed_rows_mut::<4>(0).copy_from(&base.atol);
        base.with_atol(atol)
    }

    /// Every term of the energy balance between the rest state and `y` (in `mode`).
    pub fn ledger(&self, mode: Mode, y: &AuditState) -> EnergyLedger {
        use ledger_index as l;
        let h = &self.0;
        let s = audit_state(y);
        EnergyLedger {
            excitation: y[l::EXCITATION],
            source: h.transducer.bias_v()
                * (h.source_charge(&s) - h.source_charge(&State::zeros())),
            mech_damping: y[l::MECH_DAMPING],
            stop_damping: y[l::STOP_DAMPING],
            loads: y[l::LOADS],
            clip_losses: y[l::CLIP_LOSSES],
            reengagement_gains: y[l::REENGAGEMENT_GAINS],
            projections: y[l::PROJECTIONS],
            impact_losses: y[l::IMPACT_LOSSES],
            internal: y[l::INTERNAL],
            stored_change: h.stored_energy(mode, &s) - h.stored_energy(Mode::Free, &State::zeros()),
        }
    }

    /// Relative residual of the energy balance between the rest state and `y` (in `mode`);
    /// see [`EnergyLedger::relative_residual`].
    pub fn relative_residual(&self, mode: Mode, y: &AuditState) -> f64 {
        self.ledger(mode, y).relative_residual()
    }
}

impl<E: Excitation> HybridSystem for EnergyAudit<E> {
    type State = AuditState;
    type Mode = Mode;

    fn guard_count(&self) -> usize {
        self.0.guard_count()
    }

    fn rhs(&self, mode: Mode, t: f64, y: &AuditState) -> AuditState {
        use ledger_index as l;
        let s = audit_state(y);
        let f = self.0.rhs(mode, t, &s);
        let p = self.0.power_terms(mode, t, &s);
        let mut d = AuditState::zeros();
        d.fixed_rows_mut::<4>(0).copy_from(&f);
        d[l::EXCITATION] = p.excitation;
        d[l::MECH_DAMPING] = p.mech_damping;
        d[l::STOP_DAMPING] = p.stop_damping;
        d[l::LOADS] = p.load;
        d[l::INTERNAL] = p.internal;
        d
    }

    fn guards(&self, mode: Mode, t: f64, y: &AuditState, g: &mut [f64]) {
        self.0.guards(mode, t, &audit_state(y), g)
    }

    /// Switches mode and books the stored energy that the switch makes disappear or appear
    /// ([`EnergyLedger::book_switch`]).
    fn switch(&self, mode: Mode, i: usize, t: f64, y: &mut AuditState) -> Mode {
        use ledger_index as l;
        let mut s = audit_state(y);
        let before = self.0.stored_energy(mode, &s);
        let m = self.0.switch(mode, i, t, &mut s);
        y.fixed_rows_mut::<4>(0).copy_from(&s);
        let mut booked = EnergyLedger::default();
        booked.book_switch(mode, m, before - self.0.stored_energy(m, &s));
        y[l::CLIP_LOSSES] += booked.clip_losses;
        y[l::REENGAGEMENT_GAINS] += booked.reengagement_gains;
        y[l::PROJECTIONS] += booked.projections;
        y[l::IMPACT_LOSSES] += booked.impact_losses;
        m
    }

    fn next_breakpoint(&self, t: f64) -> f64 {
        self.0.next_breakpoint(t)
    }

    fn check_state(&self, mode: Mode, t: f64, y: &AuditState) -> Result<(), String> {
        self.0.check_state(mode, t, &audit_state(y))
    }
}
