//! The interface circuit of a one-load transducer ([`crate::device::interface`]) as a hybrid
//! system: a diode bridge whose conduction starts and stops at located events (like contact),
//! and synchronous switches (SSHI, SECE) whose resets happen at the displacement extrema, the
//! `v = 0` events.
//!
//! The module reads better whole: the modes' equations, their guards and the resets at the
//! switches are one state machine, each part written against the others.
//!
//! # State and conventions
//! The state stays `(x, v, e1, e2)`: `e1` is the transducer's (the piezoelectric element's
//! voltage `Vp`, or the coil current `I`), `e2` the storage capacitor's voltage `Vs`. The
//! element's conventions are those of [`crate::physics::transducer`]: a piezoelectric element
//! puts `+theta Vp` on the mass and its open-circuit voltage obeys `Cp Vp' = -theta v`; a coil
//! puts `-Phi I` on the mass and is driven by the EMF `Phi v`. The bridge current `i >= 0`
//! leaves the element's terminal of polarity `s = +-1` and charges the storage, which feeds
//! the DC load current `I_L(Vs)` (`Vs / R`, `(Vs - V_b) / R_b` for a battery, 0 open).
//!
//! # Conduction modes ([`Bridge`])
//! With piecewise-linear diodes (forward drop `V_F`, on-resistance `R_on`, per diode; two in
//! series conduct) the circuit is linear in each mode:
//!
//! * `Off`: the bridge blocks. Piezo: `Cp Vp' = -theta v`, `Cs Vs' = -I_L`. Coil: `I = 0`.
//!   It conducts when the element's voltage (`|Vp|`, or the EMF `|Phi v|`) reaches
//!   `Vs + 2 V_F`.
//! * `On(s)`, piezo with `R_on = 0`: `Vp = s (Vs + 2 V_F)` is held (projected on entry) and the
//!   two capacitors move together, `(Cp + Cs) Vs' = -s theta v - I_L`; the bridge current is
//!   `i = Cs Vs' + I_L`, and the mode ends when it falls to zero.
//! * `On(s)`, piezo with `R_on > 0`: `i = (s Vp - Vs - 2 V_F) / (2 R_on)`,
//!   `Cp Vp' = -theta v - s i`, `Cs Vs' = i - I_L`; it ends when `i` falls to zero.
//! * `On(s)`, coil: `L I' = Phi v - (Rc + 2 R_on) I - s (Vs + 2 V_F)`, `Cs Vs' = s I - I_L`;
//!   it ends when `s I` falls to zero (with `L = 0` the current is algebraic and the mode ends
//!   when the EMF falls below `Vs + 2 V_F`).
//!
//! Shockley diodes have no modes: the two diodes of a conducting path share its voltage `u`
//! equally (the bridge is symmetric), so a path carries `I_s (exp(u / (2 n V_T)) - 1)`; the
//! element's current is the difference of the two paths', the storage's their sum.
//!
//! # Synchronous switches
//! The mode also remembers the sign of the velocity ([`Heading`]); an extremum is the guard
//! `-v` (or `v`) turning positive, where `v` is set to exactly zero (a projection within the
//! event tolerance, so that the next heading's guard starts at zero). There:
//!
//! * parallel SSHI: `Vp -> -gamma Vp` (the LC half-cycle is instantaneous; its loss
//!   `(1 - gamma^2) Cp Vp^2 / 2` is a switching loss);
//! * series SSHI: the loop of `Cp`, the inductor, the bridge and `Cs` rings for half a cycle:
//!   its voltage `u = |Vp| - Vs - 2 V_F` (when positive) becomes `-gamma u`, moving the charge
//!   `q = (1 + gamma) u Cp Cs / (Cp + Cs)` from the element to the storage (`2 V_F q` is lost
//!   in the diodes, the rest of the drop is a switching loss);
//! * SECE: `Vp -> 0` and `Cs Vs^2 / 2` gains `eta Cp Vp^2 / 2`.
//!
//! Between events every mode but Shockley's is linear in the state with the drive as input,
//! so an exact propagation of linear modes covers each.
//!
//! # Guards
//! The integrator takes three guards per mode: the contact's two (as in
//! [`crate::physics::harvester`]), and the circuit's, the largest of its (dimensionless)
//! guards, which turns positive when any of them does; the switch then picks the one that
//! fired.

mod jacobian;
mod ledger;

pub use ledger::{
    audit_start, AuditState as IfAuditState, InterfaceAudit, InterfaceLedger, IF_AUDIT_DIM,
};

use crate::device::{Device, Diode, Interface, Transducer};
use crate::drive::Excitation;
use crate::ode::{HybridSystem, Options};
use crate::physics::contact::{Mode, Side, StopModel};
use crate::physics::harvester::{Harvester, State};
use crate::physics::transducer::TransducerModel;

pub use crate::physics::assembly::circuits::{DiodeLaw, Sink, Switch};

/// The element behind the interface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Element {
    /// A piezoelectric element: coupling theta (N/V) and clamped capacitance Cp (F).
    Piezo {
        /// theta (N/V).
        theta: f64,
        /// Cp (F).
        cp: f64,
    },
    /// A coil: transduction Phi (N/A), resistance Rc (ohm), inductance L (H).
    Coil {
        /// Phi (N/A).
        phi: f64,
        /// Rc (ohm).
        rc: f64,
        /// L (H).
        l: f64,
    },
}

/// The interface circuit, evaluated (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InterfaceModel {
    /// The element.
    pub element: Element,
    /// The bridge's diodes.
    pub diode: DiodeLaw,
    /// Storage capacitance Cs (F).
    pub cs: f64,
    /// The DC load.
    pub sink: Sink,
    /// The switch.
    pub switch: Switch,
}

/// Whether the bridge conducts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Bridge {
    /// Blocking (or, with Shockley diodes, always: the law is smooth).
    Off,
    /// Conducting from the element's positive terminal.
    Positive,
    /// Conducting from its negative terminal.
    Negative,
}

impl Bridge {
    /// +1, -1, or 0 when off.
    pub fn sign(self) -> f64 {
        match self {
            Bridge::Off => 0.0,
            Bridge::Positive => 1.0,
            Bridge::Negative => -1.0,
        }
    }
}

/// The sign of the velocity since the last extremum.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Heading {
    /// v >= 0.
    Up,
    /// v < 0.
    Down,
}

/// The mode of a harvester with an interface: its contact and its circuit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct IfMode {
    /// Contact with the stops.
    pub contact: Mode,
    /// Bridge conduction.
    pub bridge: Bridge,
    /// Sign of the velocity (for the synchronous switches).
    pub heading: Heading,
}

/// What a switch of the circuit lost (J): in the diodes and in the switch.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ResetLoss {
    /// Diode conduction during a transfer.
    pub diode: f64,
    /// The switch: inversion losses, a converter's inefficiency.
    pub switching: f64,
}

impl InterfaceModel {
    /// The model of a device's interface; `None` for the resistive one (or a transducer that
    /// takes no interface, which validation refuses).
    pub fn of(device: &Device) -> Option<Self> {
        let element = match &device.transducer {
            Transducer::Piezoelectric(p) => Element::Piezo {
                theta: p.coupling_n_per_v,
                cp: p.capacitance_f,
            },
            Transducer::Electromagnetic(e) => Element::Coil {
                phi: e.transduction_n_per_a,
                rc: e.coil_resistance_ohm,
                l: e.coil_inductance_h,
            },
            _ => return None,
        };
        let diode_of = |d: &Diode| match *d {
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
        };
        let (diode, cs, load, switch) = match &device.interface {
            Interface::Resistive => return None,
            Interface::FullBridge(r) => (
                diode_of(&r.diode),
                r.storage_capacitance_f,
                &r.load,
                Switch::None,
            ),
            Interface::ParallelSshi(r, g) => (
                diode_of(&r.diode),
                r.storage_capacitance_f,
                &r.load,
                Switch::Parallel(g.gamma()),
            ),
            Interface::SeriesSshi(r, g) => (
                diode_of(&r.diode),
                r.storage_capacitance_f,
                &r.load,
                Switch::Series(g.gamma()),
            ),
            Interface::Sece {
                storage_capacitance_f,
                load,
                efficiency,
            } => (
                DiodeLaw::PiecewiseLinear { vf: 0.0, ron: 0.0 },
                *storage_capacitance_f,
                load,
                Switch::Sece(*efficiency),
            ),
        };
        Some(Self {
            element,
            diode,
            cs,
            sink: Sink::of(load),
            switch,
        })
    }

    /// True when the bridge connects the element to the storage between extrema (a plain
    /// bridge or parallel SSHI); series SSHI and SECE leave the element open there.
    pub fn bridge_between_extrema(&self) -> bool {
        matches!(self.switch, Switch::None | Switch::Parallel(_))
    }

    /// True when conduction changes are events (piecewise-linear diodes on a bridge that
    /// connects between extrema).
    pub fn has_conduction_events(&self) -> bool {
        self.bridge_between_extrema() && matches!(self.diode, DiodeLaw::PiecewiseLinear { .. })
    }

    /// `2 V_F` (V): the conducting path's drop (zero for Shockley diodes).
    pub fn path_drop(&self) -> f64 {
        match self.diode {
            DiodeLaw::PiecewiseLinear { vf, .. } => 2.0 * vf,
            DiodeLaw::Shockley { .. } => 0.0,
        }
    }

    fn ron(&self) -> f64 {
        match self.diode {
            DiodeLaw::PiecewiseLinear { ron, .. } => ron,
            DiodeLaw::Shockley { .. } => 0.0,
        }
    }

    /// The current of one conducting path of two Shockley diodes at its voltage `u` (A).
    #[inline(always)]
    fn path_current(is: f64, nvt: f64, u: f64) -> f64 {
        is * (u / (2.0 * nvt)).exp_m1()
    }

    /// The element's voltage that drives the bridge: `Vp`, or the coil's EMF `Phi v`.
    #[inline(always)]
    pub fn drive_voltage(&self, y: &State) -> f64 {
        match self.element {
            Element::Piezo { .. } => y[2],
            Element::Coil { phi, .. } => phi * y[1],
        }
    }

    /// The coil current in a bridge mode (A); zero for a piezoelectric element.
    #[inline(always)]
    pub fn coil_current(&self, bridge: Bridge, y: &State) -> f64 {
        match self.element {
            Element::Piezo { .. } => 0.0,
            Element::Coil { phi, rc, l } => {
                if l > 0.0 {
                    y[2]
                } else if bridge == Bridge::Off {
                    0.0
                } else {
                    let s = bridge.sign();
                    (phi * y[1] - s * (y[3] + self.path_drop())) / (rc + 2.0 * self.ron())
                }
            }
        }
    }

    /// The bridge's output current into the storage side (A, >= 0 but for a Shockley
    /// bridge's leakage), in a bridge mode.
    #[inline]
    pub fn bridge_current(&self, bridge: Bridge, y: &State) -> f64 {
        if !self.bridge_between_extrema() {
            return 0.0;
        }
        let vs = y[3];
        match (self.element, self.diode) {
            (Element::Piezo { .. }, DiodeLaw::Shockley { is, nvt }) => {
                Self::path_current(is, nvt, y[2] - vs) + Self::path_current(is, nvt, -y[2] - vs)
            }
            (_, _) if bridge == Bridge::Off => 0.0,
            (Element::Piezo { theta, cp }, DiodeLaw::PiecewiseLinear { vf, ron }) => {
                let s = bridge.sign();
                if ron == 0.0 {
                    let il = self.sink.current(vs);
                    (-s * theta * y[1] * self.cs + cp * il) / (cp + self.cs)
                } else {
                    (s * y[2] - vs - 2.0 * vf) / (2.0 * ron)
                }
            }
            (Element::Coil { .. }, _) => bridge.sign() * self.coil_current(bridge, y),
        }
    }

    /// The force on the mass (N) and the rates of `e1`, `e2` in a bridge mode.
    #[inline]
    pub fn force_and_rates(&self, bridge: Bridge, y: &State) -> (f64, [f64; 2]) {
        let vs = y[3];
        let il = self.sink.current(vs);
        match self.element {
            Element::Piezo { theta, cp } => {
                let f = theta * y[2];
                let open = -theta * y[1] / cp;
                if !self.bridge_between_extrema() {
                    return (f, [open, -il / self.cs]);
                }
                match self.diode {
                    DiodeLaw::Shockley { is, nvt } => {
                        let i1 = Self::path_current(is, nvt, y[2] - vs);
                        let i2 = Self::path_current(is, nvt, -y[2] - vs);
                        (f, [open - (i1 - i2) / cp, (i1 + i2 - il) / self.cs])
                    }
                    DiodeLaw::PiecewiseLinear { vf, ron } => match bridge {
                        Bridge::Off => (f, [open, -il / self.cs]),
                        _ => {
                            let s = bridge.sign();
                            if ron == 0.0 {
                                let dvs = (-s * theta * y[1] - il) / (cp + self.cs);
                                (f, [s * dvs, dvs])
                            } else {
                                let i = (s * y[2] - vs - 2.0 * vf) / (2.0 * ron);
                                (f, [open - s * i / cp, (i - il) / self.cs])
                            }
                        }
                    },
                }
            }
            Element::Coil { phi, rc, l } => {
                let i = self.coil_current(bridge, y);
                let s = bridge.sign();
                let di = if l > 0.0 && bridge != Bridge::Off {
                    (phi * y[1] - (rc + 2.0 * self.ron()) * i - s * (vs + self.path_drop())) / l
                } else {
                    0.0
                };
                (-phi * i, [di, (s * i - il) / self.cs])
            }
        }
    }

    /// Power lost in the diodes (W).
    #[inline]
    pub fn diode_power(&self, bridge: Bridge, y: &State) -> f64 {
        if !self.bridge_between_extrema() {
            return 0.0;
        }
        match self.diode {
            DiodeLaw::Shockley { is, nvt } => {
                let (u1, u2) = (y[2] - y[3], -y[2] - y[3]);
                Self::path_current(is, nvt, u1) * u1 + Self::path_current(is, nvt, u2) * u2
            }
            DiodeLaw::PiecewiseLinear { vf, ron } => {
                let i = self.bridge_current(bridge, y);
                2.0 * vf * i + 2.0 * ron * i * i
            }
        }
    }

    /// Power lost in the coil's resistance (W).
    #[inline]
    pub fn coil_loss(&self, bridge: Bridge, y: &State) -> f64 {
        match self.element {
            Element::Coil { rc, .. } => {
                let i = self.coil_current(bridge, y);
                rc * i * i
            }
            Element::Piezo { .. } => 0.0,
        }
    }

    /// Power into the DC load (W): `Vs^2 / R`, or for a battery all that leaves the storage
    /// into its branch, `Vs I_L` (its EMF's share `V_b I_L` plus its resistance's).
    #[inline]
    pub fn dc_power(&self, y: &State) -> f64 {
        y[3] * self.sink.current(y[3])
    }

    /// Energy on the element's capacitance or in the coil, and on the storage (J).
    pub fn stored_energy(&self, y: &State) -> f64 {
        let e1 = match self.element {
            Element::Piezo { cp, .. } => 0.5 * cp * y[2] * y[2],
            Element::Coil { l, .. } => 0.5 * l * y[2] * y[2],
        };
        e1 + 0.5 * self.cs * y[3] * y[3]
    }

    /// The scales of (e1, e2) for a displacement scale `x` and velocity scale `v`.
    pub fn scales(&self, x: f64, v: f64) -> [f64; 2] {
        match self.element {
            Element::Piezo { theta, cp } => [theta * x / cp, theta * x / cp],
            Element::Coil { phi, rc, l } => {
                let w = v / x;
                [phi * v / (rc + 2.0 * self.ron() + w * l), phi * v]
            }
        }
    }

    /// The fastest time constant of a conduction mode (s): `2 R_on Cp Cs / (Cp + Cs)` for a
    /// piezoelectric element with an on-resistance, `L / (Rc + 2 R_on)` for a coil; infinite
    /// where a mode has none.
    pub fn conduction_time_constant_s(&self) -> f64 {
        match self.element {
            Element::Piezo { cp, .. } if self.ron() > 0.0 && self.bridge_between_extrema() => {
                2.0 * self.ron() * cp * self.cs / (cp + self.cs)
            }
            Element::Coil { rc, l, .. } if l > 0.0 => l / (rc + 2.0 * self.ron()),
            _ => f64::INFINITY,
        }
    }

    /// The switch's reset at an extremum: changes `y` and says what it lost.
    pub fn reset(&self, y: &mut State) -> ResetLoss {
        let Element::Piezo { cp, .. } = self.element else {
            return ResetLoss::default();
        };
        match self.switch {
            Switch::None => ResetLoss::default(),
            Switch::Parallel(gamma) => {
                let e = 0.5 * cp * y[2] * y[2];
                y[2] *= -gamma;
                ResetLoss {
                    diode: 0.0,
                    switching: e * (1.0 - gamma * gamma),
                }
            }
            Switch::Series(gamma) => {
                let s = y[2].signum();
                let u = s * y[2] - y[3] - self.path_drop();
                if u <= 0.0 {
                    return ResetLoss::default();
                }
                let ceff = cp * self.cs / (cp + self.cs);
                let q = (1.0 + gamma) * u * ceff;
                y[2] -= s * q / cp;
                y[3] += q / self.cs;
                ResetLoss {
                    diode: self.path_drop() * q,
                    switching: 0.5 * ceff * u * u * (1.0 - gamma * gamma),
                }
            }
            Switch::Sece(eta) => {
                let e = 0.5 * cp * y[2] * y[2];
                y[3] = (y[3] * y[3] + 2.0 * eta * e / self.cs).sqrt();
                y[2] = 0.0;
                ResetLoss {
                    diode: 0.0,
                    switching: (1.0 - eta) * e,
                }
            }
        }
    }
}

/// A harvester with an interface circuit, driven by an excitation: a [`HybridSystem`] of
/// dimension 4 with the modes [`IfMode`].
#[derive(Debug, Clone)]
pub struct Interfaced<E: Excitation> {
    /// The mechanics and stops (its transducer is the open piezoelectric element, or none for
    /// a coil; the circuit below supplies the element's force). A rebound on a rigid stop
    /// decides whether the mass sticks from this transducer's force, so for a coil the coil's
    /// force is left out of that decision (the stuck mode's own guard includes it).
    pub h: Harvester<E>,
    /// The circuit.
    pub circuit: InterfaceModel,
}

/// An unused guard. (A bridge that keeps switching without time advancing ends in the
/// integrator's named error, [`crate::ode::SolverError::Chattering`].)
const OFF: f64 = f64::NEG_INFINITY;

impl<E: Excitation> Interfaced<E> {
    /// The model of a device with an interface; `None` when its interface is resistive.
    pub fn new(device: &Device, excitation: E) -> Option<Self> {
        let circuit = InterfaceModel::of(device)?;
        let mut h = Harvester::new(device, excitation);
        h.transducer = match circuit.element {
            Element::Piezo { theta, cp } => TransducerModel::Piezo {
                theta,
                cp,
                r: f64::INFINITY,
            },
            Element::Coil { .. } => TransducerModel::None,
        };
        Some(Self { h, circuit })
    }

    /// Replaces the excitation.
    pub fn with_excitation<F: Excitation>(&self, excitation: F) -> Interfaced<F> {
        Interfaced {
            h: self.h.with_excitation(excitation),
            circuit: self.circuit,
        }
    }

    /// Characteristic scales of (x, v, e1, e2).
    pub fn scales(&self) -> State {
        let w0 = (self.h.km / self.h.mass_kg).sqrt();
        let x = self.h.x_scale();
        let [e1, e2] = self.circuit.scales(x, w0 * x);
        State::new(x, w0 * x, e1, e2)
    }

    /// Integrator options with relative tolerance `rtol`.
    pub fn solver_options(&self, rtol: f64) -> Options<State> {
        let mut o = self.h.solver_options(rtol);
        o.atol = self.scales() * rtol;
        o
    }

    /// The mode a state starts in: contact past a compliant stop; the bridge conducting in
    /// the direction of a coil's current where it has one, else off (a guard already positive
    /// switches it on at once); the heading from the velocity's sign.
    pub fn mode_of(&self, y: &State) -> IfMode {
        let mut contact = Mode::Free;
        for side in Side::BOTH {
            if self.h.penetration(side, y[0]) > 0.0
                && matches!(self.h.stop(side), Some(StopModel::Compliant { .. }))
            {
                contact = Mode::Contact(side);
            }
        }
        let bridge = match self.circuit.element {
            Element::Coil { l, .. } if l > 0.0 && y[2] > 0.0 => Bridge::Positive,
            Element::Coil { l, .. } if l > 0.0 && y[2] < 0.0 => Bridge::Negative,
            _ => Bridge::Off,
        };
        IfMode {
            contact,
            bridge,
            heading: if y[1] >= 0.0 {
                Heading::Up
            } else {
                Heading::Down
            },
        }
    }

    /// The net force on the mass but the stops' (N).
    #[inline(always)]
    fn free_force(&self, t: f64, y: &State, fe: f64) -> f64 {
        let h = &self.h;
        h.mass_kg * h.excitation.accel(t) - h.damping * y[1] - h.km * y[0] + fe
    }

    /// The guards of a mode: the contact's two and the circuit's (see the module docs).
    #[inline]
    pub fn guard_values(&self, mode: IfMode, t: f64, y: &State) -> [f64; 3] {
        let mut v = match mode.contact {
            Mode::Stuck(side) => {
                let (fe, _) = self.circuit.force_and_rates(mode.bridge, y);
                [-side.sign() * self.free_force(t, y, fe), OFF, OFF]
            }
            m => self.h.guard_values(m, t, y),
        };
        let [a, b] = self.circuit_guards(mode, y);
        v[2] = a.max(b);
        v
    }

    /// The circuit's guards, dimensionless: (conduction, extremum).
    #[inline]
    pub(crate) fn circuit_guards(&self, mode: IfMode, y: &State) -> [f64; 2] {
        let c = &self.circuit;
        let sc = self.scales();
        let conduction = if c.has_conduction_events() {
            let threshold = y[3] + c.path_drop();
            match mode.bridge {
                Bridge::Off => (c.drive_voltage(y).abs() - threshold) / sc[3],
                b => {
                    let s = b.sign();
                    match c.element {
                        Element::Piezo { theta, .. } if c.ron() == 0.0 => {
                            -c.bridge_current(b, y) / (theta * sc[1])
                        }
                        Element::Coil { l, .. } if l > 0.0 => -s * y[2] / sc[2],
                        _ => -(s * c.drive_voltage(y) - threshold) / sc[3],
                    }
                }
            }
        } else {
            OFF
        };
        let extremum = match (c.switch, mode.heading) {
            (Switch::None, _) => OFF,
            (_, Heading::Up) => -y[1] / sc[1],
            (_, Heading::Down) => y[1] / sc[1],
        };
        [conduction, extremum]
    }
}

impl<E: Excitation> HybridSystem for Interfaced<E> {
    type State = State;
    type Mode = IfMode;

    #[inline(always)]
    fn guard_count(&self) -> usize {
        crate::physics::harvester::GUARDS
    }

    #[inline]
    fn rhs(&self, mode: IfMode, t: f64, y: &State) -> State {
        let (fe, rates) = self.circuit.force_and_rates(mode.bridge, y);
        if let Mode::Stuck(_) = mode.contact {
            return State::new(0.0, 0.0, rates[0], rates[1]);
        }
        let f = self.free_force(t, y, fe) - self.h.endstop_force(mode.contact, y);
        State::new(y[1], f / self.h.mass_kg, rates[0], rates[1])
    }

    #[inline]
    fn guards(&self, mode: IfMode, t: f64, y: &State, g: &mut [f64]) {
        g[..3].copy_from_slice(&self.guard_values(mode, t, y));
    }

    fn switch(&self, mode: IfMode, index: usize, t: f64, y: &mut State) -> IfMode {
        let mut next = mode;
        if index < 2 {
            next.contact = self.h.switch(mode.contact, index, t, y);
            return next;
        }
        let [conduction, extremum] = self.circuit_guards(mode, y);
        if extremum >= conduction {
            // The extremum is located to the event tolerance; v is put at exactly zero so that
            // the guard of the new heading starts at zero and does not fire again at once.
            y[1] = 0.0;
            self.circuit.reset(y);
            next.heading = match mode.heading {
                Heading::Up => Heading::Down,
                Heading::Down => Heading::Up,
            };
            if self.circuit.switch != Switch::None {
                next.bridge = Bridge::Off;
            }
            return next;
        }
        let c = &self.circuit;
        next.bridge = match mode.bridge {
            Bridge::Off => {
                let s = c.drive_voltage(y).signum();
                if let Element::Piezo { .. } = c.element {
                    if c.ron() == 0.0 {
                        y[2] = s * (y[3] + c.path_drop());
                    }
                }
                if s > 0.0 {
                    Bridge::Positive
                } else {
                    Bridge::Negative
                }
            }
            _ => {
                if let Element::Coil { l, .. } = c.element {
                    if l > 0.0 {
                        y[2] = 0.0;
                    }
                }
                Bridge::Off
            }
        };
        next
    }

    fn next_breakpoint(&self, t: f64) -> f64 {
        self.h.next_breakpoint(t)
    }
}
