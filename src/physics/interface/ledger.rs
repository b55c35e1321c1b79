//! The energy ledger of a harvester with an interface circuit: the work of the drive equals
//! mechanical damping + contact losses + the coil's resistance + diode conduction + switching
//! losses + the DC load (or battery) + the change of the stored energy (kinetic, suspension,
//! contact spring, the element's capacitance or inductance, the storage capacitor).
//!
//! The continuous terms are integrated beside the state; the switches book what their resets
//! lose ([`super::ResetLoss`]), and any other change of the stored energy at a switch (a
//! projection onto a stop or onto a conduction constraint, within the event tolerance) is booked
//! apart, as [`crate::physics::energy`] does for the contact.

use nalgebra::SVector;

use crate::drive::Excitation;
use crate::ode::{HybridSystem, Options};
use crate::physics::contact::Mode;
use crate::physics::energy::EnergyLedger;
use crate::physics::harvester::State;

use super::{IfMode, Interfaced};

/// Number of states of the audit: the model's four and eleven accumulators.
pub const IF_AUDIT_DIM: usize = 15;

/// The interface audit's carried vector: the state, then its accumulators.
pub type AuditState = SVector<f64, IF_AUDIT_DIM>;

const EXCITATION: usize = 4;
const MECH: usize = 5;
const STOP: usize = 6;
const COIL: usize = 7;
const DIODE: usize = 8;
const DC: usize = 9;
const SWITCHING: usize = 10;
const CLIP: usize = 11;
const REENGAGE: usize = 12;
const PROJECTIONS: usize = 13;
const IMPACT: usize = 14;

/// The harvester with its interface and the work of every term accumulated (see the module
/// docs).
#[derive(Debug, Clone)]
pub struct InterfaceAudit<E: Excitation>(pub Interfaced<E>);

/// The energy balance of an audited run (J).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct InterfaceLedger {
    /// Work of the inertial force.
    pub excitation: f64,
    /// Mechanical damper.
    pub mech_damping: f64,
    /// Contact: the end-stop damper, clip losses minus re-engagement gains, impact losses.
    pub contact: f64,
    /// The coil's resistance.
    pub coil: f64,
    /// Diode conduction.
    pub diode: f64,
    /// The synchronous switch.
    pub switching: f64,
    /// Delivered to the DC load or battery.
    pub dc_load: f64,
    /// Stored energy changed by projections at switches (of the order of the event tolerance).
    pub projections: f64,
    /// Change of the stored energy.
    pub stored_change: f64,
}

impl InterfaceLedger {
    /// Energy in minus energy out and stored (J).
    pub fn residual(&self) -> f64 {
        self.excitation
            - self.mech_damping
            - self.contact
            - self.coil
            - self.diode
            - self.switching
            - self.dc_load
            - self.projections
            - self.stored_change
    }

    /// The residual over the sum of the terms' magnitudes.
    pub fn relative_residual(&self) -> f64 {
        let scale = self.excitation.abs()
            + self.mech_damping.abs()
            + self.contact.abs()
            + self.coil.abs()
            + self.diode.abs()
            + self.switching.abs()
            + self.dc_load.abs()
            + self.projections.abs()
            + self.stored_change.abs();
        self.residual() / scale
    }
}

/// The audit state at the model state `y` with every accumulator zero.
pub fn audit_start(y: &State) -> AuditState {
    let mut z = AuditState::zeros();
    z.fixed_rows_mut::<4>(0).copy_from(y);
    z
}

fn head(z: &AuditState) -> State {
    State::new(z[0], z[1], z[2], z[3])
}

impl<E: Excitation> InterfaceAudit<E> {
    /// Stored energy in a mode (J).
    pub fn stored_energy(&self, mode: IfMode, y: &State) -> f64 {
        let s = &self.0;
        // The harvester's stored energy with its open element (whose capacitance energy the
        // circuit counts).
        let mech = s.h.stored_energy(mode.contact, y) - s.h.transducer.add_stored_energy(0.0, y);
        mech + s.circuit.stored_energy(y)
    }

    /// Integrator options: the model's, with absolute tolerances for the accumulators of
    /// `rtol` times the suspension energy at the displacement scale.
    pub fn solver_options(&self, rtol: f64) -> Options<AuditState> {
        let xs = self.0.h.x_scale();
        let e_scale = 0.5 * self.0.h.km * xs * xs;
        let base = self.0.solver_options(rtol);
        let mut atol = AuditState::repeat(e_scale * rtol);
        atol.fixed_rows_mut::<4>(0).copy_from(&base.atol);
        base.with_atol(atol)
    }

    /// Every term of the balance between the audit's start `y0` (in `mode0`) and `y` (in
    /// `mode`).
    pub fn ledger(
        &self,
        mode0: IfMode,
        y0: &AuditState,
        mode: IfMode,
        y: &AuditState,
    ) -> InterfaceLedger {
        let d = |i: usize| y[i] - y0[i];
        InterfaceLedger {
            excitation: d(EXCITATION),
            mech_damping: d(MECH),
            contact: d(STOP) + d(CLIP) - d(REENGAGE) + d(IMPACT),
            coil: d(COIL),
            diode: d(DIODE),
            switching: d(SWITCHING),
            dc_load: d(DC),
            projections: d(PROJECTIONS),
            stored_change: self.stored_energy(mode, &head(y))
                - self.stored_energy(mode0, &head(y0)),
        }
    }
}

impl<E: Excitation> HybridSystem for InterfaceAudit<E> {
    type State = AuditState;
    type Mode = IfMode;

    fn guard_count(&self) -> usize {
        self.0.guard_count()
    }

    fn rhs(&self, mode: IfMode, t: f64, z: &AuditState) -> AuditState {
        let s = &self.0;
        let y = head(z);
        let f = s.rhs(mode, t, &y);
        let p = s.h.power_terms(mode.contact, t, &y);
        let mut d = AuditState::zeros();
        d.fixed_rows_mut::<4>(0).copy_from(&f);
        if !matches!(mode.contact, Mode::Stuck(_)) {
            d[EXCITATION] = p.excitation;
            d[MECH] = p.mech_damping;
        }
        d[STOP] = p.stop_damping;
        d[COIL] = s.circuit.coil_loss(mode.bridge, &y);
        d[DIODE] = s.circuit.diode_power(mode.bridge, &y);
        d[DC] = s.circuit.dc_power(&y);
        d
    }

    fn guards(&self, mode: IfMode, t: f64, z: &AuditState, g: &mut [f64]) {
        self.0.guards(mode, t, &head(z), g)
    }

    fn switch(&self, mode: IfMode, i: usize, t: f64, z: &mut AuditState) -> IfMode {
        let mut y = head(z);
        let before = self.stored_energy(mode, &y);
        let mut loss = super::ResetLoss::default();
        let next = if i < 2 {
            let mut n = mode;
            n.contact = self.0.h.switch(mode.contact, i, t, &mut y);
            n
        } else {
            // Replays the circuit's switch to learn what a reset lost.
            let [conduction, extremum] = self.0.circuit_guards(mode, &y);
            if extremum >= conduction {
                let mut probe = y;
                loss = self.0.circuit.reset(&mut probe);
            }
            self.0.switch(mode, i, t, &mut y)
        };
        z.fixed_rows_mut::<4>(0).copy_from(&y);
        let dropped = before - self.stored_energy(next, &y);
        z[DIODE] += loss.diode;
        z[SWITCHING] += loss.switching;
        let rest = dropped - loss.diode - loss.switching;
        if mode.contact != next.contact {
            let mut booked = EnergyLedger::default();
            booked.book_switch(mode.contact, next.contact, rest);
            z[CLIP] += booked.clip_losses;
            z[REENGAGE] += booked.reengagement_gains;
            z[PROJECTIONS] += booked.projections;
            z[IMPACT] += booked.impact_losses;
        } else {
            z[PROJECTIONS] += rest;
        }
        next
    }

    fn next_breakpoint(&self, t: f64) -> f64 {
        self.0.next_breakpoint(t)
    }
}
