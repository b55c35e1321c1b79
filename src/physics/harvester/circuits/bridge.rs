//! An interface circuit between a transducer and a DC load ([`crate::device::interface`]): a
//! diode bridge whose conduction starts and stops at located events, into a storage capacitor
//! that feeds the load, with a synchronous switch (SSHI, SECE) acting at the displacement
//! extrema, the `v = 0` events.
//!
//! The module reads better whole: the modes' equations, their guards and the resets at the
//! switches are one state machine, each part written against the others.
//!
//! # The transducer as a port
//! The circuit sees the transducer as a port ([`Element`]):
//! * a **piezoelectric element**, a current source `-theta v` into its clamped capacitance
//!   `Cp`: its voltage `Vp` is a state, `Cp Vp' = -theta v - i`, and it puts `+theta Vp` on
//!   the mass;
//! * a **coil**, the EMF `Phi v` behind `Rc` and `L`: its current `I` is a state
//!   (`L I' = Phi v - Rc I - V_terminal`; algebraic when `L = 0`), and it puts `-Phi I` on the
//!   mass;
//! * an **electrostatic pair** (eqs 8-10) across its two electrodes: the node charges `s1`,
//!   `s2` are states, the port's voltage is `V1 - V2` with `V_i = (s_i + (C_i - C0) Vb) / D_i`,
//!   `D_i = C_i + Cp + CL`; a current `i` out of electrode 1 and into electrode 2 moves
//!   `s1' = -i`, `s2' = +i`, and the force is eq 9's.
//!
//! The bridge current `i >= 0` leaves the element's terminal of polarity `s = +-1` and charges
//! the storage `Cs`, which feeds the DC load current `I_L(Vs)` (`Vs / R`, `(Vs - V_b) / R_b`
//! for a battery, 0 open).
//!
//! # Conduction modes
//! With piecewise-linear diodes (forward drop `V_F`, on-resistance `R_on`, per diode; two in
//! series conduct) the circuit is linear in each mode for the piezoelectric element and the
//! coil:
//!
//! * off: the bridge blocks. It conducts when the port's voltage (`|Vp|`, `|V1 - V2|`, or the
//!   EMF `|Phi v|`) reaches `Vs + 2 V_F`.
//! * on, a capacitive port (piezo, pair) with `R_on = 0`: the port's voltage is held at
//!   `s (Vs + 2 V_F)` (projected on entry) and the bridge current is what keeps it there,
//!   `i (S + 1/Cs) = s dV/dt|_0 + I_L / Cs`, with `S` the port's elastance (`1/Cp`;
//!   `1/D_1 + 1/D_2` for the pair) and `dV/dt|_0` the port voltage's rate with no current
//!   (`-theta v / Cp`; for the pair, the electrodes' motion at fixed charge). For the piezo it
//!   is `(-s theta v Cs + Cp I_L) / (Cp + Cs)`. The mode ends when `i` falls to zero.
//! * on, a capacitive port with `R_on > 0`: `i = (s V - Vs - 2 V_F) / (2 R_on)`; it ends when
//!   `i` falls to zero.
//! * on, coil: `L I' = Phi v - (Rc + 2 R_on) I - s (Vs + 2 V_F)`, `Cs Vs' = s I - I_L`; it ends
//!   when `s I` falls to zero (with `L = 0` the current is algebraic and the mode ends when the
//!   EMF falls below `Vs + 2 V_F`).
//!
//! Shockley diodes have no modes: the two diodes of a conducting path share its voltage `u`
//! equally (the bridge is symmetric), so a path carries `I_s (exp(u / (2 n V_T)) - 1)`; the
//! port's current is the difference of the two paths', the storage's their sum.
//!
//! # Synchronous switches (piezoelectric element)
//! The mode also remembers the sign of the velocity (the heading); an extremum is the guard
//! `-v` (or `v`) turning positive, where `v` is set to exactly zero (a projection within the
//! event tolerance, so that the next heading's guard starts at zero). There:
//!
//! * parallel SSHI: `Vp -> -gamma Vp` (the LC half-cycle is instantaneous; its loss
//!   `(1 - gamma^2) Cp Vp^2 / 2` is a switching loss);
//! * series SSHI: the loop of `Cp`, the inductor, the bridge and `Cs` rings for half a cycle:
//!   its voltage `u = |Vp| - Vs - 2 V_F` (when positive) becomes `-gamma u`, moving the charge
//!   `q = (1 + gamma) u Cp Cs / (Cp + Cs)` from the element to the storage (`2 V_F q` is lost
//!   in the diodes, the rest of the drop is a switching loss);
//! * SECE: `Vp -> 0` and `Cs Vs^2 / 2` gains `eta Cp Vp^2 / 2` (its transfer resolved
//!   through the inductor in time is [`super::sece_inductor`], which owns the behaviour of a
//!   circuit with [`Switch::BuckBoost`]).
//!
//! A parallel SSHI whose inversion rings through its inductor in time is
//! [`super::sshi_inductor`] ([`Switch::Inverter`]): the bridge's modes here, with the ring's
//! stages added to them there.
//!
//! # Guards
//! The circuit has one guard: the largest of its dimensionless guards (conduction and
//! extremum), which turns positive when any of them does; the switch then picks the one that
//! fired.

use nalgebra::{SMatrix, SVector};

use super::parts::{BuckBoost, DiodeLaw, Inverter, Sink, Switch};
use crate::physics::transducer::CapacitorPair;

/// An unused guard.
const OFF: f64 = f64::NEG_INFINITY;

/// The transducer as the circuit sees it (see the module docs).
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
    /// An electrostatic pair across its two electrodes (its loads' `rl` is that of an
    /// optional bleed resistor on each electrode, infinite without one).
    Pair(CapacitorPair),
}

/// Whether the bridge conducts (bits 0-1 of the circuit's mode bits).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Bridge {
    /// Blocking (or, with Shockley diodes, always: the law is smooth).
    Off,
    /// Conducting from the element's positive terminal.
    Positive,
    /// Conducting from its negative terminal.
    Negative,
    /// Blocking, with a flyback diode carrying an inductor's current into the storage (a SECE
    /// through its inductor, [`super::sece_inductor`]).
    Flyback,
    /// Blocking, with the element ringing through an inverting inductor (bits 3-4; a
    /// parallel SSHI through its inductor, [`super::sshi_inductor`]).
    Invert {
        /// The element's voltage was negative when the switch closed.
        negative: bool,
        /// The element's voltage has crossed zero.
        returning: bool,
    },
}

impl Bridge {
    /// +1, -1, or 0 when off.
    #[inline(always)]
    pub fn sign(self) -> f64 {
        match self {
            Bridge::Off | Bridge::Flyback | Bridge::Invert { .. } => 0.0,
            Bridge::Positive => 1.0,
            Bridge::Negative => -1.0,
        }
    }
}

/// The sign of the velocity since the last extremum (bit 2 of the circuit's mode bits).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Heading {
    /// v >= 0.
    Up,
    /// v < 0.
    Down,
}

impl Heading {
    /// The heading after an extremum.
    #[inline(always)]
    pub fn turned(self) -> Self {
        match self {
            Heading::Up => Heading::Down,
            Heading::Down => Heading::Up,
        }
    }
}

/// The circuit's mode, from and to its bits of a [`crate::model::Mode`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CircuitMode {
    /// Bridge conduction.
    pub bridge: Bridge,
    /// Sign of the velocity since the last extremum.
    pub heading: Heading,
}

impl CircuitMode {
    /// The mode of the bits.
    #[inline(always)]
    pub fn of(bits: u8) -> Self {
        Self {
            bridge: match bits & 3 {
                _ if bits & 8 != 0 => Bridge::Invert {
                    negative: bits & 1 != 0,
                    returning: bits & 2 != 0,
                },
                0 => Bridge::Off,
                1 => Bridge::Positive,
                2 => Bridge::Negative,
                _ => Bridge::Flyback,
            },
            heading: if bits & 4 == 0 {
                Heading::Up
            } else {
                Heading::Down
            },
        }
    }

    /// The bits of the mode.
    #[inline(always)]
    pub fn bits(self) -> u8 {
        let b = match self.bridge {
            Bridge::Off => 0,
            Bridge::Positive => 1,
            Bridge::Negative => 2,
            Bridge::Flyback => 3,
            Bridge::Invert {
                negative,
                returning,
            } => 8 | u8::from(negative) | (u8::from(returning) << 1),
        };
        b | if self.heading == Heading::Down { 4 } else { 0 }
    }
}

/// What a switch of the circuit lost (J): in the diodes and in the switch.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ResetLoss {
    /// Diode conduction during a transfer.
    pub diode: f64,
    /// The switch: inversion losses, a converter's inefficiency.
    pub switching: f64,
}

/// A pair's node voltages, capacitances and their slopes at one state.
#[derive(Debug, Clone, Copy)]
struct PairState {
    /// Node voltages (V).
    v: [f64; 2],
    /// `D_i = C_i + Cp + CL` (F).
    d: [f64; 2],
    /// `dC_i / dx` (F/m).
    a: [f64; 2],
}

/// The interface circuit, evaluated (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Circuit {
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
    /// Index of the element's first state component (its second follows, for a pair).
    pub e: usize,
    /// Index of the storage voltage.
    pub vs: usize,
}

impl Circuit {
    /// The element's coupling and capacitance (theta, Cp) for a circuit with an inductor: the
    /// description admits a piezoelectric element only, and the assembly refuses the others.
    #[inline(always)]
    pub(crate) fn piezo(&self) -> (f64, f64) {
        match self.element {
            Element::Piezo { theta, cp } => (theta, cp),
            _ => (0.0, f64::INFINITY),
        }
    }

    /// The buck-boost inductor of a SECE through its inductor, which then owns the circuit's
    /// behaviour ([`super::sece_inductor`]).
    #[inline(always)]
    fn buck_boost(&self) -> Option<BuckBoost> {
        match self.switch {
            Switch::BuckBoost(b) => Some(b),
            _ => None,
        }
    }

    /// The inverting inductor of a parallel SSHI through its inductor, which adds the ring's
    /// stages to the bridge's modes ([`super::sshi_inductor`]).
    #[inline(always)]
    fn inverter(&self) -> Option<Inverter> {
        match self.switch {
            Switch::Inverter(v) => Some(v),
            _ => None,
        }
    }

    /// The state's dimension the circuit needs: its last component's index plus one.
    pub fn dimension(&self) -> usize {
        self.switch
            .inductor()
            .map_or(self.vs + 1, |inductor| inductor.i + 1)
    }

    /// The bridge states of the circuit's modes.
    pub fn bridges(&self) -> &'static [Bridge] {
        match self.switch {
            Switch::BuckBoost(_) => &BuckBoost::PHASES,
            Switch::Inverter(_) => &Inverter::PHASES,
            _ => &[Bridge::Off, Bridge::Positive, Bridge::Negative],
        }
    }

    /// True when the bridge connects the element to the storage between extrema (a plain
    /// bridge or parallel SSHI); series SSHI and SECE leave the element open there.
    #[inline(always)]
    pub fn bridge_between_extrema(&self) -> bool {
        matches!(
            self.switch,
            Switch::None | Switch::Parallel(_) | Switch::Inverter(_)
        )
    }

    /// True when conduction changes are events (piecewise-linear diodes on a bridge that
    /// connects between extrema).
    #[inline(always)]
    pub fn has_conduction_events(&self) -> bool {
        self.bridge_between_extrema() && matches!(self.diode, DiodeLaw::PiecewiseLinear { .. })
    }

    /// `2 V_F` (V): the conducting path's drop (zero for Shockley diodes).
    #[inline(always)]
    pub fn path_drop(&self) -> f64 {
        match self.diode {
            DiodeLaw::PiecewiseLinear { vf, .. } => 2.0 * vf,
            DiodeLaw::Shockley { .. } => 0.0,
        }
    }

    /// The on-resistance of one diode (ohm; zero for Shockley diodes).
    #[inline(always)]
    pub fn ron(&self) -> f64 {
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

    /// A pair's node voltages and capacitances.
    #[inline(always)]
    fn pair<const N: usize>(&self, p: &CapacitorPair, y: &SVector<f64, N>) -> PairState {
        let z = SVector::<f64, 4>::new(y[0], y[1], y[self.e], y[self.e + 1]);
        let el = p.electrical(&z);
        let a = p.capacitance_slopes(y[0]);
        PairState {
            v: el.v,
            d: [el.c[0] + p.cp + p.cl, el.c[1] + p.cp + p.cl],
            a,
        }
    }

    /// The port's voltage that drives the bridge: `Vp`, `V1 - V2`, or the coil's EMF `Phi v`.
    #[inline(always)]
    pub fn drive_voltage<const N: usize>(&self, y: &SVector<f64, N>) -> f64 {
        match self.element {
            Element::Piezo { .. } => y[self.e],
            Element::Coil { phi, .. } => phi * y[1],
            Element::Pair(p) => {
                let ps = self.pair(&p, y);
                ps.v[0] - ps.v[1]
            }
        }
    }

    /// A capacitive port's elastance `S` (V/C) and its voltage's rate with no port current
    /// (V/s; a pair's node loads still drain it), for the ideal bridge's constraint (see the
    /// module docs).
    #[inline]
    fn elastance_and_open_rate<const N: usize>(&self, y: &SVector<f64, N>) -> (f64, f64) {
        match self.element {
            Element::Piezo { theta, cp } => (1.0 / cp, -theta * y[1] / cp),
            Element::Pair(p) => {
                let ps = self.pair(&p, y);
                // dV_i/dt with no port current: the motion's -a_i v (V_i - Vb) / D_i and the
                // node's own load draining it, -(V_i / R_L) / D_i.
                let r1 = -(ps.a[0] * y[1] * (ps.v[0] - p.vb) + ps.v[0] / p.rl) / ps.d[0];
                let r2 = -(ps.a[1] * y[1] * (ps.v[1] - p.vb) + ps.v[1] / p.rl) / ps.d[1];
                (1.0 / ps.d[0] + 1.0 / ps.d[1], r1 - r2)
            }
            Element::Coil { .. } => (0.0, 0.0),
        }
    }

    /// The coil current in a bridge mode (A); zero for a capacitive element.
    #[inline(always)]
    pub fn coil_current<const N: usize>(&self, bridge: Bridge, y: &SVector<f64, N>) -> f64 {
        match self.element {
            Element::Coil { phi, rc, l } => {
                if l > 0.0 {
                    y[self.e]
                } else if bridge == Bridge::Off {
                    0.0
                } else {
                    let s = bridge.sign();
                    (phi * y[1] - s * (y[self.vs] + self.path_drop())) / (rc + 2.0 * self.ron())
                }
            }
            _ => 0.0,
        }
    }

    /// The bridge's output current into the storage side (A, >= 0 but for a Shockley
    /// bridge's leakage), in a bridge mode.
    #[inline]
    pub fn bridge_current<const N: usize>(&self, bridge: Bridge, y: &SVector<f64, N>) -> f64 {
        if !self.bridge_between_extrema() {
            return 0.0;
        }
        let vs = y[self.vs];
        match (self.element, self.diode) {
            (Element::Coil { .. }, _) => bridge.sign() * self.coil_current(bridge, y),
            (_, DiodeLaw::Shockley { is, nvt }) => {
                let u = self.drive_voltage(y);
                Self::path_current(is, nvt, u - vs) + Self::path_current(is, nvt, -u - vs)
            }
            (_, _) if bridge.sign() == 0.0 => 0.0,
            (Element::Piezo { theta, cp }, DiodeLaw::PiecewiseLinear { vf, ron }) => {
                let s = bridge.sign();
                if ron == 0.0 {
                    let il = self.sink.current(vs);
                    (-s * theta * y[1] * self.cs + cp * il) / (cp + self.cs)
                } else {
                    (s * y[self.e] - vs - 2.0 * vf) / (2.0 * ron)
                }
            }
            (Element::Pair(_), DiodeLaw::PiecewiseLinear { vf, ron }) => {
                let s = bridge.sign();
                if ron == 0.0 {
                    let il = self.sink.current(vs);
                    let (el, open) = self.elastance_and_open_rate(y);
                    (s * open + il / self.cs) / (el + 1.0 / self.cs)
                } else {
                    (s * self.drive_voltage(y) - vs - 2.0 * vf) / (2.0 * ron)
                }
            }
        }
    }

    /// The current out of the element's positive terminal (A): `s i` for the bridge, the
    /// difference of the two paths' currents for Shockley diodes.
    #[inline]
    fn port_current<const N: usize>(&self, bridge: Bridge, y: &SVector<f64, N>) -> f64 {
        if !self.bridge_between_extrema() {
            return 0.0;
        }
        match self.diode {
            DiodeLaw::Shockley { is, nvt } => {
                let (u, vs) = (self.drive_voltage(y), y[self.vs]);
                Self::path_current(is, nvt, u - vs) - Self::path_current(is, nvt, -u - vs)
            }
            DiodeLaw::PiecewiseLinear { .. } => bridge.sign() * self.bridge_current(bridge, y),
        }
    }

    /// The force on the mass (N), and the rates of the element's components and of the
    /// storage voltage written into `rates` (at the state's indices), in a bridge mode.
    #[inline]
    pub fn force_and_rates<const N: usize>(
        &self,
        bridge: Bridge,
        y: &SVector<f64, N>,
        rates: &mut SVector<f64, N>,
    ) -> f64 {
        if let Some(b) = self.buck_boost() {
            return b.force_and_rates(self, bridge, y, rates);
        }
        if let Some(v) = self.inverter() {
            let ringing = Inverter::stage(bridge).is_some();
            let f = self.bridge_force_and_rates(Self::open_in_ring(bridge), y, rates);
            v.rates(self, ringing, y, rates);
            return f;
        }
        self.bridge_force_and_rates(bridge, y, rates)
    }

    /// The bridge's state during a ring: off.
    #[inline(always)]
    fn open_in_ring(bridge: Bridge) -> Bridge {
        match bridge {
            Bridge::Invert { .. } => Bridge::Off,
            b => b,
        }
    }

    /// [`Circuit::force_and_rates`] of the bridge and its element.
    #[inline]
    fn bridge_force_and_rates<const N: usize>(
        &self,
        bridge: Bridge,
        y: &SVector<f64, N>,
        rates: &mut SVector<f64, N>,
    ) -> f64 {
        let (e, ivs) = (self.e, self.vs);
        let vs = y[ivs];
        let il = self.sink.current(vs);
        match self.element {
            Element::Piezo { theta, cp } => {
                let f = theta * y[e];
                let open = -theta * y[1] / cp;
                if !self.bridge_between_extrema() {
                    rates[e] = open;
                    rates[ivs] = -il / self.cs;
                    return f;
                }
                match self.diode {
                    DiodeLaw::Shockley { is, nvt } => {
                        let i1 = Self::path_current(is, nvt, y[e] - vs);
                        let i2 = Self::path_current(is, nvt, -y[e] - vs);
                        rates[e] = open - (i1 - i2) / cp;
                        rates[ivs] = (i1 + i2 - il) / self.cs;
                    }
                    DiodeLaw::PiecewiseLinear { vf, ron } => match bridge {
                        Bridge::Off => {
                            rates[e] = open;
                            rates[ivs] = -il / self.cs;
                        }
                        _ => {
                            let s = bridge.sign();
                            if ron == 0.0 {
                                let dvs = (-s * theta * y[1] - il) / (cp + self.cs);
                                rates[e] = s * dvs;
                                rates[ivs] = dvs;
                            } else {
                                let i = (s * y[e] - vs - 2.0 * vf) / (2.0 * ron);
                                rates[e] = open - s * i / cp;
                                rates[ivs] = (i - il) / self.cs;
                            }
                        }
                    },
                }
                f
            }
            Element::Coil { phi, rc, l } => {
                let i = self.coil_current(bridge, y);
                let s = bridge.sign();
                let di = if l > 0.0 && bridge != Bridge::Off {
                    (phi * y[1] - (rc + 2.0 * self.ron()) * i - s * (vs + self.path_drop())) / l
                } else if l > 0.0 {
                    // Off, the current is held at zero (projected there on entry). A current
                    // off zero is outside the mode's states; it decays at the coil's own rate,
                    // so the period map contracts across that direction and an orbit that
                    // never conducts has no neutral multiplier 1 to stall Newton's method.
                    -(rc + 2.0 * self.ron()) * i / l
                } else {
                    0.0
                };
                rates[e] = di;
                rates[ivs] = (s * i - il) / self.cs;
                -phi * i
            }
            Element::Pair(p) => {
                let ps = self.pair(&p, y);
                let (u1, u2) = (ps.v[0] - p.vb, ps.v[1] - p.vb);
                let f = 0.5 * (u1 * u1 * ps.a[0] + u2 * u2 * ps.a[1]);
                let ip = self.port_current(bridge, y);
                let bleed = [ps.v[0] / p.rl, ps.v[1] / p.rl];
                rates[e] = -ip - bleed[0];
                rates[e + 1] = ip - bleed[1];
                let i_out = match self.diode {
                    DiodeLaw::Shockley { .. } => self.bridge_current(bridge, y),
                    DiodeLaw::PiecewiseLinear { .. } => self.bridge_current(bridge, y),
                };
                rates[ivs] = (i_out - il) / self.cs;
                f
            }
        }
    }

    /// Power lost in the diodes (W).
    #[inline]
    pub fn diode_power<const N: usize>(&self, bridge: Bridge, y: &SVector<f64, N>) -> f64 {
        if let Some(b) = self.buck_boost() {
            return b.diode_power(bridge, y);
        }
        let bridge = Self::open_in_ring(bridge);
        if !self.bridge_between_extrema() {
            return 0.0;
        }
        match self.diode {
            DiodeLaw::Shockley { is, nvt } => {
                let u = self.drive_voltage(y);
                let (u1, u2) = (u - y[self.vs], -u - y[self.vs]);
                Self::path_current(is, nvt, u1) * u1 + Self::path_current(is, nvt, u2) * u2
            }
            DiodeLaw::PiecewiseLinear { vf, ron } => {
                let i = self.bridge_current(bridge, y);
                2.0 * vf * i + 2.0 * ron * i * i
            }
        }
    }

    /// Power lost in the coil's resistance, or a pair's bleed resistors (W).
    #[inline]
    pub fn element_loss<const N: usize>(&self, bridge: Bridge, y: &SVector<f64, N>) -> f64 {
        if let Some(b) = self.buck_boost() {
            return b.resistive_power(bridge, y);
        }
        if let Some(v) = self.inverter() {
            return v.resistive_power(y);
        }
        match self.element {
            Element::Coil { rc, .. } => {
                let i = self.coil_current(bridge, y);
                rc * i * i
            }
            Element::Piezo { .. } => 0.0,
            Element::Pair(p) => {
                let ps = self.pair(&p, y);
                (ps.v[0] * ps.v[0] + ps.v[1] * ps.v[1]) / p.rl
            }
        }
    }

    /// Power into the DC load (W): `Vs^2 / R`, or for a battery all that leaves the storage
    /// into its branch, `Vs I_L` (its EMF's share `V_b I_L` plus its resistance's).
    #[inline]
    pub fn dc_power<const N: usize>(&self, y: &SVector<f64, N>) -> f64 {
        y[self.vs] * self.sink.current(y[self.vs])
    }

    /// Energy on the element's capacitance (against a pair's bias) or in the coil, and on the
    /// storage (J).
    pub fn stored_energy<const N: usize>(&self, y: &SVector<f64, N>) -> f64 {
        let e1 = match self.element {
            Element::Piezo { cp, .. } => 0.5 * cp * y[self.e] * y[self.e],
            Element::Coil { l, .. } => 0.5 * l * y[self.e] * y[self.e],
            Element::Pair(p) => {
                let z = SVector::<f64, 4>::new(y[0], y[1], y[self.e], y[self.e + 1]);
                let el = p.electrical(&z);
                let mut e = 0.0;
                for i in 0..2 {
                    let u = el.v[i] - p.vb;
                    e += 0.5 * (el.c[i] + p.cp) * u * u + 0.5 * p.cl * el.v[i] * el.v[i];
                }
                e
            }
        };
        let inductor = self
            .switch
            .inductor()
            .map_or(0.0, |inductor| inductor.stored_energy(y));
        e1 + inductor + 0.5 * self.cs * y[self.vs] * y[self.vs]
    }

    /// The charge a pair's bias source has delivered (C); zero for the others.
    pub fn source_charge<const N: usize>(&self, y: &SVector<f64, N>) -> f64 {
        match self.element {
            Element::Pair(p) => {
                let z = SVector::<f64, 4>::new(y[0], y[1], y[self.e], y[self.e + 1]);
                let el = p.electrical(&z);
                (0..2).map(|i| (el.c[i] + p.cp) * (p.vb - el.v[i])).sum()
            }
            _ => 0.0,
        }
    }

    /// The bias voltage of a pair (V); zero otherwise.
    pub fn bias_v(&self) -> f64 {
        match self.element {
            Element::Pair(p) => p.vb,
            _ => 0.0,
        }
    }

    /// The scales of the element's components and of the storage voltage, for a displacement
    /// scale `x` and velocity scale `v`, written into `sc`.
    pub fn scales<const N: usize>(&self, x: f64, v: f64, sc: &mut SVector<f64, N>) {
        match self.element {
            Element::Piezo { theta, cp } => {
                sc[self.e] = theta * x / cp;
                sc[self.vs] = theta * x / cp;
                if let Some(inductor) = self.switch.inductor() {
                    inductor.scale(cp, sc[self.e], sc);
                }
            }
            Element::Coil { phi, rc, l } => {
                let w = v / x;
                sc[self.e] = phi * v / (rc + 2.0 * self.ron() + w * l);
                sc[self.vs] = phi * v;
            }
            Element::Pair(p) => {
                let q = p.c0 * p.vb.max(1.0) * x / p.length_scale();
                sc[self.e] = q;
                sc[self.e + 1] = q;
                sc[self.vs] = q / (p.c0 + p.cp + p.cl);
            }
        }
    }

    /// The storage's time constant through its load (s): `R Cs` for a resistor, `R_b Cs` for
    /// a battery; `None` for an open load (it only charges).
    pub fn storage_time_constant_s(&self) -> Option<f64> {
        match self.sink {
            Sink::Resistor(r) | Sink::Battery(_, r) => Some(r * self.cs),
            Sink::Open => None,
        }
    }

    /// The shortest time constant of a conduction mode (s): `2 R_on C_port Cs / (C_port + Cs)`
    /// for a capacitive element with an on-resistance (`C_port` the element's capacitance at
    /// rest), `L / (Rc + 2 R_on)` for a coil; infinite where a mode has none.
    pub fn conduction_time_constant_s(&self) -> f64 {
        if let Some(b) = self.buck_boost() {
            return b.inductor.time_constant_s(self.piezo().1);
        }
        let ring = self.inverter().map_or(f64::INFINITY, |v| {
            v.inductor.time_constant_s(self.piezo().1)
        });
        let capacitive = |c: f64| 2.0 * self.ron() * c * self.cs / (c + self.cs);
        match self.element {
            Element::Piezo { cp, .. } if self.ron() > 0.0 && self.bridge_between_extrema() => {
                capacitive(cp)
            }
            Element::Pair(p) if self.ron() > 0.0 && self.bridge_between_extrema() => {
                // Two electrodes in series across the port.
                capacitive(0.5 * (p.c0 + p.cp + p.cl))
            }
            Element::Coil { rc, l, .. } if l > 0.0 => l / (rc + 2.0 * self.ron()),
            _ => f64::INFINITY,
        }
        .min(ring)
    }

    /// The switch's reset at an extremum: changes `y` and says what it lost.
    pub fn reset<const N: usize>(&self, y: &mut SVector<f64, N>) -> ResetLoss {
        let Element::Piezo { cp, .. } = self.element else {
            return ResetLoss::default();
        };
        let (e, ivs) = (self.e, self.vs);
        match self.switch {
            Switch::None | Switch::BuckBoost(_) | Switch::Inverter(_) => ResetLoss::default(),
            Switch::Parallel(gamma) => {
                let en = 0.5 * cp * y[e] * y[e];
                y[e] *= -gamma;
                ResetLoss {
                    diode: 0.0,
                    switching: en * (1.0 - gamma * gamma),
                }
            }
            Switch::Series(gamma) => {
                let s = y[e].signum();
                let u = s * y[e] - y[ivs] - self.path_drop();
                if u <= 0.0 {
                    return ResetLoss::default();
                }
                let ceff = cp * self.cs / (cp + self.cs);
                let q = (1.0 + gamma) * u * ceff;
                y[e] -= s * q / cp;
                y[ivs] += q / self.cs;
                ResetLoss {
                    diode: self.path_drop() * q,
                    switching: 0.5 * ceff * u * u * (1.0 - gamma * gamma),
                }
            }
            Switch::Sece(eta) => {
                let en = 0.5 * cp * y[e] * y[e];
                y[ivs] = (y[ivs] * y[ivs] + 2.0 * eta * en / self.cs).sqrt();
                y[e] = 0.0;
                ResetLoss {
                    diode: 0.0,
                    switching: (1.0 - eta) * en,
                }
            }
        }
    }

    /// The circuit's guards, dimensionless, at the state scales `sc`: (conduction, extremum).
    #[inline]
    pub fn guards<const N: usize>(
        &self,
        mode: CircuitMode,
        y: &SVector<f64, N>,
        sc: &SVector<f64, N>,
    ) -> [f64; 2] {
        let ring = self.inverter().zip(Inverter::stage(mode.bridge));
        let conduction = if let Some(b) = self.buck_boost() {
            b.phase_guard(self, mode.bridge, y, sc)
        } else if let Some((v, stage)) = ring {
            v.guard(self, stage, y, sc)
        } else if self.has_conduction_events() {
            let threshold = y[self.vs] + self.path_drop();
            match mode.bridge {
                Bridge::Off => (self.drive_voltage(y).abs() - threshold) / sc[self.vs],
                b => {
                    let s = b.sign();
                    match self.element {
                        Element::Piezo { theta, .. } if self.ron() == 0.0 => {
                            -self.bridge_current(b, y) / (theta * sc[1])
                        }
                        Element::Pair(p) if self.ron() == 0.0 => {
                            // The current over the scale of the open-circuit current.
                            let q = sc[self.e];
                            -self.bridge_current(b, y) / (q * sc[1] / p.length_scale())
                        }
                        Element::Coil { l, .. } if l > 0.0 => -s * y[self.e] / sc[self.e],
                        _ => -(s * self.drive_voltage(y) - threshold) / sc[self.vs],
                    }
                }
            }
        } else {
            OFF
        };
        let extremum = match (self.switch, mode.heading) {
            (Switch::None, _) => OFF,
            (_, Heading::Up) => -y[1] / sc[1],
            (_, Heading::Down) => y[1] / sc[1],
        };
        [conduction, extremum]
    }

    /// The circuit's switch when its guard fires (at the scales `sc`): the new circuit mode,
    /// with `y` reset or projected, and what a reset lost.
    pub fn switch<const N: usize>(
        &self,
        mode: CircuitMode,
        y: &mut SVector<f64, N>,
        sc: &SVector<f64, N>,
    ) -> (CircuitMode, ResetLoss) {
        let mut next = mode;
        let [conduction, extremum] = self.guards(mode, y, sc);
        if let Some(b) = self.buck_boost() {
            let next = b.switch(self, mode, extremum >= conduction, y, sc);
            return (next, ResetLoss::default());
        }
        if let Some(v) = self.inverter() {
            let stage = Inverter::stage(mode.bridge);
            if extremum >= conduction {
                // v is put at exactly zero, as for every synchronous switch; an extremum
                // during a ring only turns the heading.
                y[1] = 0.0;
                next.heading = mode.heading.turned();
                if stage.is_none() {
                    next.bridge = v.close(self, y, sc);
                }
                return (next, ResetLoss::default());
            }
            if let Some(stage) = stage {
                next.bridge = v.advance(self, stage, y);
                return (next, ResetLoss::default());
            }
        }
        if extremum >= conduction {
            // The extremum is located to the event tolerance; v is put at exactly zero so that
            // the guard of the new heading starts at zero and does not fire again at once.
            y[1] = 0.0;
            let loss = self.reset(y);
            next.heading = mode.heading.turned();
            if self.switch != Switch::None {
                next.bridge = Bridge::Off;
            }
            return (next, loss);
        }
        next.bridge = match mode.bridge {
            Bridge::Off => {
                let s = self.drive_voltage(y).signum();
                if self.ron() == 0.0 {
                    self.project(s, y);
                }
                if s > 0.0 {
                    Bridge::Positive
                } else {
                    Bridge::Negative
                }
            }
            b => {
                match self.element {
                    Element::Coil { l, .. } if l > 0.0 => y[self.e] = 0.0,
                    // The conduction ends where the current falls to zero, which is where the
                    // port's voltage, held at the threshold, would start to fall below it: the
                    // off mode's guard starts at zero with zero rate. Held within rounding, it
                    // may start a rounding error above zero and fire at once, back into a
                    // conduction whose current is already negative, again and again; put on
                    // the threshold (a projection within rounding), it starts at zero.
                    Element::Piezo { .. } | Element::Pair(_) if self.ron() == 0.0 => {
                        self.project(b.sign(), y);
                        self.settle_off(b.sign(), mode, y, sc);
                    }
                    _ => {}
                }
                Bridge::Off
            }
        };
        (next, ResetLoss::default())
    }

    /// Puts a capacitive port's voltage at the conduction threshold `s (Vs + 2 V_F)` (a
    /// projection within the event tolerance): the piezo's voltage is set, the pair's charge
    /// moved from one electrode to the other.
    fn project<const N: usize>(&self, s: f64, y: &mut SVector<f64, N>) {
        let target = s * (y[self.vs] + self.path_drop());
        match self.element {
            Element::Piezo { .. } => y[self.e] = target,
            Element::Pair(_) => {
                let (el, _) = self.elastance_and_open_rate(y);
                let dq = (self.drive_voltage(y) - target) / el;
                y[self.e] -= dq;
                y[self.e + 1] += dq;
            }
            Element::Coil { .. } => {}
        }
    }

    /// After a conduction's exit has put the port's voltage on the threshold, moves it inside
    /// by the off guard's excess where that guard still reads above zero: the projection holds
    /// only within rounding (the pair's voltage is computed from its charges), and a guard a
    /// rounding error above zero would switch the bridge back on at once, again and again.
    /// The move is of the order of the last places of the voltage.
    fn settle_off<const N: usize>(
        &self,
        s: f64,
        mode: CircuitMode,
        y: &mut SVector<f64, N>,
        sc: &SVector<f64, N>,
    ) {
        let off = CircuitMode {
            bridge: Bridge::Off,
            ..mode
        };
        for _ in 0..4 {
            let g = self.guards(off, y, sc)[0];
            // Only a rounding error is settled: a state that cannot sit on the threshold
            // (a negative one, `Vs < -2 V_F`) is left as projected.
            let size = y[self.vs].abs() + self.path_drop();
            if g <= 0.0 || g * sc[self.vs] > 64.0 * f64::EPSILON * size {
                return;
            }
            let dv = 2.0 * g * sc[self.vs] + f64::EPSILON * size;
            match self.element {
                Element::Piezo { .. } => y[self.e] -= s * dv,
                Element::Pair(_) => {
                    let (el, _) = self.elastance_and_open_rate(y);
                    let dq = s * dv / el;
                    y[self.e] -= dq;
                    y[self.e + 1] += dq;
                }
                Element::Coil { .. } => return,
            }
        }
    }

    /// The mode a state starts in: the bridge conducting in the direction of a coil's current
    /// where it has one, else off (a guard already positive switches it on at once); the
    /// heading from the velocity's sign.
    pub fn mode_of<const N: usize>(&self, y: &SVector<f64, N>) -> CircuitMode {
        let ring = self.inverter().and_then(|v| v.phase_of(y));
        let bridge = match (self.element, self.buck_boost()) {
            _ if ring.is_some() => ring.unwrap_or(Bridge::Off),
            (_, Some(b)) => b.phase_of(y),
            (Element::Coil { l, .. }, _) if l > 0.0 && y[self.e] > 0.0 => Bridge::Positive,
            (Element::Coil { l, .. }, _) if l > 0.0 && y[self.e] < 0.0 => Bridge::Negative,
            _ => Bridge::Off,
        };
        CircuitMode {
            bridge,
            heading: if y[1] >= 0.0 {
                Heading::Up
            } else {
                Heading::Down
            },
        }
    }

    /// d I_L / d Vs of the DC load (S).
    pub(super) fn sink_conductance(&self) -> f64 {
        match self.sink {
            Sink::Resistor(r) => 1.0 / r,
            Sink::Battery(_, r) => 1.0 / r,
            Sink::Open => 0.0,
        }
    }

    /// The circuit's part of the Jacobian in a bridge mode: the gradient of the force on the
    /// mass (added to row 1 divided by the mass `m`) and the rows of the element's components
    /// and of the storage voltage.
    pub fn jacobian<const N: usize>(
        &self,
        bridge: Bridge,
        y: &SVector<f64, N>,
        m: f64,
        sc: &SVector<f64, N>,
        j: &mut SMatrix<f64, N, N>,
    ) {
        if let Some(b) = self.buck_boost() {
            return b.jacobian(self, bridge, m, j);
        }
        self.bridge_jacobian(Self::open_in_ring(bridge), y, m, sc, j);
        if let Some(v) = self.inverter() {
            v.jacobian(self, Inverter::stage(bridge).is_some(), j);
        }
    }

    /// [`Circuit::jacobian`] of the bridge and its element.
    fn bridge_jacobian<const N: usize>(
        &self,
        bridge: Bridge,
        y: &SVector<f64, N>,
        m: f64,
        sc: &SVector<f64, N>,
        j: &mut SMatrix<f64, N, N>,
    ) {
        let gl = self.sink_conductance();
        let cs = self.cs;
        let (e, ivs) = (self.e, self.vs);
        match self.element {
            Element::Piezo { theta, cp } => {
                j[(1, e)] += theta / m;
                let open_v = -theta / cp;
                let set_open = |j: &mut SMatrix<f64, N, N>| {
                    j[(e, 1)] = open_v;
                    j[(ivs, ivs)] = -gl / cs;
                };
                if !self.bridge_between_extrema() {
                    set_open(j);
                    return;
                }
                match self.diode {
                    DiodeLaw::Shockley { is, nvt } => {
                        // path current I_s (exp(u / 2nVT) - 1), u1 = Vp - Vs, u2 = -Vp - Vs.
                        let d = |u: f64| is / (2.0 * nvt) * (u / (2.0 * nvt)).exp();
                        let (d1, d2) = (d(y[e] - y[ivs]), d(-y[e] - y[ivs]));
                        // i1 - i2 and i1 + i2 in (Vp, Vs).
                        let diff = (d1 + d2, -d1 + d2);
                        let sum = (d1 - d2, -d1 - d2);
                        j[(e, 1)] = open_v;
                        j[(e, e)] = -diff.0 / cp;
                        j[(e, ivs)] = -diff.1 / cp;
                        j[(ivs, e)] = sum.0 / cs;
                        j[(ivs, ivs)] = (sum.1 - gl) / cs;
                    }
                    DiodeLaw::PiecewiseLinear { ron, .. } => match bridge {
                        Bridge::Off => set_open(j),
                        b => {
                            let s = b.sign();
                            if ron == 0.0 {
                                let (dv, dvs) = (-s * theta / (cp + cs), -gl / (cp + cs));
                                j[(e, 1)] = dv * s;
                                j[(e, ivs)] = dvs * s;
                                j[(ivs, 1)] = dv;
                                j[(ivs, ivs)] = dvs;
                            } else {
                                let (die, divs) = (s / (2.0 * ron), -1.0 / (2.0 * ron));
                                j[(e, 1)] = open_v;
                                j[(e, e)] = -die * (s / cp);
                                j[(e, ivs)] = -divs * (s / cp);
                                j[(ivs, e)] = die / cs;
                                j[(ivs, ivs)] = (divs - gl) / cs;
                            }
                        }
                    },
                }
            }
            Element::Coil { phi, rc, l } => {
                let s = bridge.sign();
                let rpath = rc + 2.0 * self.ron();
                // The coil current's gradient in (v, I, Vs).
                let di = if l > 0.0 {
                    [0.0, 1.0, 0.0]
                } else if bridge == Bridge::Off {
                    [0.0; 3]
                } else {
                    [phi / rpath, 0.0, -s / rpath]
                };
                let cols = [1, e, ivs];
                for (k, &c) in cols.iter().enumerate() {
                    j[(1, c)] += di[k] * -phi / m;
                }
                if l > 0.0 && bridge != Bridge::Off {
                    let src = [phi, 0.0, -s];
                    for (k, &c) in cols.iter().enumerate() {
                        j[(e, c)] = (src[k] - di[k] * rpath) / l;
                    }
                } else if l > 0.0 {
                    j[(e, e)] = -rpath / l;
                }
                for (k, &c) in cols.iter().enumerate() {
                    let gl_k = if c == ivs { gl } else { 0.0 };
                    j[(ivs, c)] = (di[k] * s - gl_k) / cs;
                }
            }
            Element::Pair(_) => self.pair_jacobian(bridge, y, m, sc, j),
        }
    }

    /// The pair's part of the Jacobian, by central differences of the circuit's force and
    /// rates in the state's scaled coordinates: the port's equations are smooth in each mode,
    /// and their derivatives by hand would repeat the node voltages' quotient rule for every
    /// diode law; the monodromy they feed is checked against differences of the period map.
    fn pair_jacobian<const N: usize>(
        &self,
        bridge: Bridge,
        y: &SVector<f64, N>,
        m: f64,
        sc: &SVector<f64, N>,
        j: &mut SMatrix<f64, N, N>,
    ) {
        let rows = [self.e, self.e + 1, self.vs];
        let eval = |z: &SVector<f64, N>| {
            let mut r = SVector::<f64, N>::zeros();
            let f = self.force_and_rates(bridge, z, &mut r);
            (f, r)
        };
        for c in [0, 1, self.e, self.e + 1, self.vs] {
            // Steps of 1e-6 of each scale: truncation ~1e-12 and rounding ~1e-10 of a row.
            let h = 1e-6 * sc[c];
            let (mut yp, mut ym) = (*y, *y);
            yp[c] += h;
            ym[c] -= h;
            let ((fp, rp), (fm, rm)) = (eval(&yp), eval(&ym));
            j[(1, c)] += (fp - fm) / (2.0 * h) / m;
            for &r in &rows {
                j[(r, c)] = (rp[r] - rm[r]) / (2.0 * h);
            }
        }
    }

    /// The Jacobian of [`Circuit::reset`] at the state `y` just before it (the velocity is
    /// zero there and stays so: the reset leaves it alone), into `g` (the identity elsewhere).
    pub fn reset_jacobian<const N: usize>(&self, y: &SVector<f64, N>, g: &mut SMatrix<f64, N, N>) {
        let Element::Piezo { cp, .. } = self.element else {
            return;
        };
        let (e, ivs) = (self.e, self.vs);
        match self.switch {
            Switch::None | Switch::BuckBoost(_) | Switch::Inverter(_) => {}
            Switch::Parallel(gamma) => g[(e, e)] = -gamma,
            Switch::Series(gamma) => {
                let s = y[e].signum();
                if s * y[e] - y[ivs] - self.path_drop() > 0.0 {
                    // q = (1 + gamma) ceff (s Vp - Vs - 2 V_F); Vp -= s q / Cp, Vs += q / Cs.
                    let k = (1.0 + gamma) * cp * self.cs / (cp + self.cs);
                    g[(e, e)] = 1.0 - k / cp;
                    g[(e, ivs)] = s * k / cp;
                    g[(ivs, e)] = s * k / self.cs;
                    g[(ivs, ivs)] = 1.0 - k / self.cs;
                }
            }
            Switch::Sece(eta) => {
                let vs = (y[ivs] * y[ivs] + eta * cp * y[e] * y[e] / self.cs).sqrt();
                g[(e, e)] = 0.0;
                if vs > 0.0 {
                    g[(ivs, e)] = eta * cp * y[e] / (self.cs * vs);
                    g[(ivs, ivs)] = y[ivs] / vs;
                }
            }
        }
    }
}
