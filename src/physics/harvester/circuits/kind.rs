//! What a kind of interface circuit adds to the bridge it is built on: the trait every kind
//! implements in a file of its own. Its default answers are the plain bridge's, so that a kind
//! writes only what it changes: its own state slots (an inductor's current), its phases, their
//! rates and Jacobian, its guard and switch, the reset it applies at a displacement extremum
//! with that reset's Jacobian, its ledger's losses and the mirror of its own slots.
//!
//! The methods take the circuit ([`Circuit`]) the kind belongs to: its element, diodes,
//! storage and load, and the bridge's own equations to build on.

use nalgebra::{SMatrix, SVector};

use super::bridge::Circuit;
use super::element::Element;
use super::mode::{Bridge, CircuitMode, ResetLoss, BRIDGE_PHASES};
use super::parts::Inductor;
use crate::model::AffineGuard;

/// The behaviour of one kind of interface circuit (see the module docs); the registration
/// point ([`super::Kind`]) maps a device's `[interface]` to one.
pub trait CircuitKind: Copy {
    /// Why the kind cannot act on the element, if it cannot (the assembly refuses the device
    /// with this reason).
    fn refuses(&self, element: &Element) -> Option<&'static str> {
        let _ = element;
        None
    }

    /// The inductor the kind holds, its current a state component of its own.
    fn inductor(&self) -> Option<Inductor> {
        None
    }

    /// The bridge states of the kind's modes.
    fn phases(&self) -> &'static [Bridge] {
        &BRIDGE_PHASES
    }

    /// True when the bridge connects the element to the storage between extrema.
    #[inline(always)]
    fn bridge_between_extrema(&self) -> bool {
        true
    }

    /// True when the kind acts at the displacement extrema (a synchronous switch).
    #[inline(always)]
    fn acts_at_extrema(&self) -> bool {
        true
    }

    /// The force on the mass (N) and the rates of the circuit's components, in a bridge
    /// state (see [`Circuit::force_and_rates`]).
    #[inline(always)]
    fn force_and_rates<const N: usize>(
        &self,
        c: &Circuit,
        bridge: Bridge,
        y: &SVector<f64, N>,
        rates: &mut SVector<f64, N>,
    ) -> f64 {
        c.bridge_force_and_rates(bridge, y, rates)
    }

    /// The circuit's part of the Jacobian in a bridge state (see [`Circuit::jacobian`]).
    #[inline(always)]
    fn jacobian<const N: usize>(
        &self,
        c: &Circuit,
        bridge: Bridge,
        y: &SVector<f64, N>,
        m: f64,
        sc: &SVector<f64, N>,
        j: &mut SMatrix<f64, N, N>,
    ) {
        c.bridge_jacobian(bridge, y, m, sc, j)
    }

    /// Power lost in the diodes (W).
    #[inline(always)]
    fn diode_power<const N: usize>(&self, c: &Circuit, bridge: Bridge, y: &SVector<f64, N>) -> f64 {
        c.bridge_diode_power(bridge, y)
    }

    /// Power lost in the element and the kind's own parts (W).
    #[inline(always)]
    fn element_loss<const N: usize>(
        &self,
        c: &Circuit,
        bridge: Bridge,
        y: &SVector<f64, N>,
    ) -> f64 {
        c.port_loss(bridge, y)
    }

    /// The shortest time constant of the circuit's modes (s).
    fn time_constant_s(&self, c: &Circuit) -> f64 {
        c.bridge_time_constant_s()
    }

    /// The conduction (or phase) guard in a bridge state, dimensionless at the scales `sc`.
    #[inline(always)]
    fn conduction_guard<const N: usize>(
        &self,
        c: &Circuit,
        bridge: Bridge,
        y: &SVector<f64, N>,
        sc: &SVector<f64, N>,
    ) -> f64 {
        c.bridge_guard(bridge, y, sc)
    }

    /// The kind's own guard in a bridge state as an affine function of the state, where it
    /// replaces the bridge's conduction guard (for the exact propagators).
    fn guard_piece<const N: usize>(
        &self,
        c: &Circuit,
        bridge: Bridge,
        index: usize,
    ) -> Option<AffineGuard<N>> {
        let _ = (c, bridge, index);
        None
    }

    /// The switch when the circuit's guard fires (`extremum` when the extremum's guard is the
    /// larger): the next mode, with `y` reset or projected, and what a reset lost.
    fn switch<const N: usize>(
        &self,
        c: &Circuit,
        mode: CircuitMode,
        extremum: bool,
        y: &mut SVector<f64, N>,
        sc: &SVector<f64, N>,
    ) -> (CircuitMode, ResetLoss) {
        c.bridge_switch(mode, extremum, y, sc)
    }

    /// The reset at an extremum on a piezoelectric element of capacitance `cp`: changes `y`
    /// and says what it lost.
    fn reset<const N: usize>(&self, c: &Circuit, cp: f64, y: &mut SVector<f64, N>) -> ResetLoss {
        let _ = (c, cp, y);
        ResetLoss::default()
    }

    /// The Jacobian of [`CircuitKind::reset`] at the state `y` just before it, into `g` (the
    /// identity where the reset leaves the state alone).
    fn reset_jacobian<const N: usize>(
        &self,
        c: &Circuit,
        cp: f64,
        y: &SVector<f64, N>,
        g: &mut SMatrix<f64, N, N>,
    ) {
        let _ = (c, cp, y, g);
    }

    /// The bridge state a state starts in.
    fn phase_of<const N: usize>(&self, c: &Circuit, y: &SVector<f64, N>) -> Bridge {
        c.bridge_phase_of(y)
    }

    /// The kind's own slots' part of the mirror map x -> -x, into `s`.
    fn mirror<const N: usize>(&self, s: &mut SMatrix<f64, N, N>) {
        let _ = s;
    }
}
