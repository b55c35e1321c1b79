//! An interface circuit between a transducer and a DC load ([`crate::device::interface`]): a
//! diode bridge whose conduction starts and stops at located events, into a storage capacitor
//! that feeds the load, with the behaviour its kind adds ([`super::CircuitKind`]): a
//! synchronous switch acting at the displacement extrema, the `v = 0` events, or an
//! inductor's transfer in time.
//!
//! The module reads better whole: the circuit calls its kind at every rate, guard and switch,
//! and the trait's defaults are the circuit's own bridge equations, so the two are one
//! definition read together (the element's port is in [`super::port`], the linearisation in
//! [`super::jacobian`]).
//!
//! The circuit sees the transducer as a port ([`super::element`]). The bridge current `i >= 0` leaves the element's terminal of polarity `s = +-1` and charges
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
//! # Extrema
//! The mode also remembers the sign of the velocity (the heading); an extremum is the guard
//! `-v` (or `v`) turning positive, where `v` is set to exactly zero (a projection within the
//! event tolerance, so that the next heading's guard starts at zero), and the circuit's kind
//! acts there ([`super::instant`], [`super::sece_inductor`], [`super::sshi_inductor`]).
//!
//!
//! # Guards
//! The circuit has one guard: the largest of its dimensionless guards (conduction and
//! extremum), which turns positive when any of them does; the switch then picks the one that
//! fired.
//!
//! # What a kind adds
//! [`CircuitKind`] is the trait every kind of circuit implements in a file of its own. Its
//! default answers are the plain bridge's, so that a kind writes only what it changes: its own
//! state slots (an inductor's current), its phases, their rates and Jacobian, its guard and
//! switch, the reset it applies at a displacement extremum with that reset's Jacobian, its
//! ledger's losses and the mirror of its own slots. Its methods take the circuit ([`Circuit`])
//! the kind belongs to: its element, diodes, storage and load, and the bridge's own equations
//! to build on.

use nalgebra::{SMatrix, SVector};

use super::element::Element;
use super::mode::{Bridge, CircuitMode, Heading, ResetLoss, BRIDGE_PHASES};
use super::parts::{DiodeLaw, Inductor, Sink};
use super::Kind;
use crate::model::AffineGuard;

/// An unused guard.
pub(super) const OFF: f64 = f64::NEG_INFINITY;

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
    /// The circuit's kind: what it adds to the bridge.
    pub kind: Kind,
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

    /// The state's dimension the circuit needs: its last component's index plus one.
    pub fn dimension(&self) -> usize {
        self.kind
            .inductor()
            .map_or(self.vs + 1, |inductor| inductor.i + 1)
    }

    /// The bridge states of the circuit's modes.
    pub fn bridges(&self) -> &'static [Bridge] {
        self.kind.phases()
    }

    /// True when the bridge connects the element to the storage between extrema (a plain
    /// bridge or parallel SSHI); series SSHI and SECE leave the element open there.
    #[inline(always)]
    pub fn bridge_between_extrema(&self) -> bool {
        self.kind.bridge_between_extrema()
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
    pub(super) fn path_current(is: f64, nvt: f64, u: f64) -> f64 {
        is * (u / (2.0 * nvt)).exp_m1()
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
        self.kind.force_and_rates(self, bridge, y, rates)
    }

    /// The bridge and its element's force and rates (see [`Circuit::force_and_rates`]).
    #[inline]
    pub(super) fn bridge_force_and_rates<const N: usize>(
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
        self.kind.diode_power(self, bridge, y)
    }

    /// Power lost in the bridge's diodes (W).
    #[inline]
    pub(super) fn bridge_diode_power<const N: usize>(
        &self,
        bridge: Bridge,
        y: &SVector<f64, N>,
    ) -> f64 {
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

    /// Power lost in the element (W): a coil's resistance, a pair's bleed resistors, a
    /// circuit's inductor.
    #[inline]
    pub fn element_loss<const N: usize>(&self, bridge: Bridge, y: &SVector<f64, N>) -> f64 {
        self.kind.element_loss(self, bridge, y)
    }

    /// Power lost in the coil's resistance, or a pair's bleed resistors (W).
    #[inline]
    pub(super) fn port_loss<const N: usize>(&self, bridge: Bridge, y: &SVector<f64, N>) -> f64 {
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

    /// Energy on the element's capacitance (against a pair's bias) or in the coil, in a
    /// circuit's inductor, and on the storage (J).
    pub fn stored_energy<const N: usize>(&self, y: &SVector<f64, N>) -> f64 {
        let e1 = self.element_energy(y);
        let inductor = self
            .kind
            .inductor()
            .map_or(0.0, |inductor| inductor.stored_energy(y));
        e1 + inductor + 0.5 * self.cs * y[self.vs] * y[self.vs]
    }

    /// The storage's time constant through its load (s): `R Cs` for a resistor, `R_b Cs` for
    /// a battery; `None` for an open load (it only charges).
    pub fn storage_time_constant_s(&self) -> Option<f64> {
        match self.sink {
            Sink::Resistor(r) | Sink::Battery(_, r) => Some(r * self.cs),
            Sink::Open => None,
        }
    }

    /// The shortest time constant of the circuit's modes (s).
    pub fn conduction_time_constant_s(&self) -> f64 {
        self.kind.time_constant_s(self)
    }

    /// The shortest time constant of a bridge's conduction mode (s):
    /// `2 R_on C_port Cs / (C_port + Cs)` for a capacitive element with an on-resistance
    /// (`C_port` the element's capacitance at rest), `L / (Rc + 2 R_on)` for a coil; infinite
    /// where a mode has none.
    pub(super) fn bridge_time_constant_s(&self) -> f64 {
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
    }

    /// The kind's reset at an extremum: changes `y` and says what it lost (a synchronous
    /// switch acts on a piezoelectric element only).
    pub fn reset<const N: usize>(&self, y: &mut SVector<f64, N>) -> ResetLoss {
        let Element::Piezo { cp, .. } = self.element else {
            return ResetLoss::default();
        };
        self.kind.reset(self, cp, y)
    }

    /// The Jacobian of [`Circuit::reset`] at the state `y` just before it (the velocity is
    /// zero there and stays so: the reset leaves it alone), into `g` (the identity elsewhere).
    pub fn reset_jacobian<const N: usize>(&self, y: &SVector<f64, N>, g: &mut SMatrix<f64, N, N>) {
        let Element::Piezo { cp, .. } = self.element else {
            return;
        };
        self.kind.reset_jacobian(self, cp, y, g);
    }

    /// The circuit's guards, dimensionless, at the state scales `sc`: (conduction, extremum).
    #[inline]
    pub fn guards<const N: usize>(
        &self,
        mode: CircuitMode,
        y: &SVector<f64, N>,
        sc: &SVector<f64, N>,
    ) -> [f64; 2] {
        let conduction = self.kind.conduction_guard(self, mode.bridge, y, sc);
        let extremum = match (self.kind.acts_at_extrema(), mode.heading) {
            (false, _) => OFF,
            (true, Heading::Up) => -y[1] / sc[1],
            (true, Heading::Down) => y[1] / sc[1],
        };
        [conduction, extremum]
    }

    /// The bridge's conduction guard, dimensionless at the scales `sc` ([`OFF`] where
    /// conduction changes are not events).
    #[inline]
    pub(super) fn bridge_guard<const N: usize>(
        &self,
        bridge: Bridge,
        y: &SVector<f64, N>,
        sc: &SVector<f64, N>,
    ) -> f64 {
        if self.has_conduction_events() {
            let threshold = y[self.vs] + self.path_drop();
            match bridge {
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
        }
    }

    /// The circuit's switch when its guard fires (at the scales `sc`): the new circuit mode,
    /// with `y` reset or projected, and what a reset lost.
    pub fn switch<const N: usize>(
        &self,
        mode: CircuitMode,
        y: &mut SVector<f64, N>,
        sc: &SVector<f64, N>,
    ) -> (CircuitMode, ResetLoss) {
        let [conduction, extremum] = self.guards(mode, y, sc);
        self.kind.switch(self, mode, extremum >= conduction, y, sc)
    }

    /// The bridge's switch (see [`Circuit::switch`]): at an extremum (`extremum`) the kind's
    /// reset, else a conduction starting or ending.
    pub(super) fn bridge_switch<const N: usize>(
        &self,
        mode: CircuitMode,
        extremum: bool,
        y: &mut SVector<f64, N>,
        sc: &SVector<f64, N>,
    ) -> (CircuitMode, ResetLoss) {
        let mut next = mode;
        if extremum {
            // The extremum is located to the event tolerance; v is put at exactly zero so that
            // the guard of the new heading starts at zero and does not fire again at once.
            y[1] = 0.0;
            let loss = self.reset(y);
            next.heading = mode.heading.turned();
            if self.kind.acts_at_extrema() {
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
    /// The mode a state starts in: the kind's phase at the state, and the heading from the
    /// velocity's sign.
    pub fn mode_of<const N: usize>(&self, y: &SVector<f64, N>) -> CircuitMode {
        CircuitMode {
            bridge: self.kind.phase_of(self, y),
            heading: if y[1] >= 0.0 {
                Heading::Up
            } else {
                Heading::Down
            },
        }
    }

    /// The bridge's state at a state: conducting in the direction of a coil's current where
    /// it has one, else off (a guard already positive switches it on at once).
    pub(super) fn bridge_phase_of<const N: usize>(&self, y: &SVector<f64, N>) -> Bridge {
        match self.element {
            Element::Coil { l, .. } if l > 0.0 && y[self.e] > 0.0 => Bridge::Positive,
            Element::Coil { l, .. } if l > 0.0 && y[self.e] < 0.0 => Bridge::Negative,
            _ => Bridge::Off,
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
        self.kind.jacobian(self, bridge, y, m, sc, j);
    }
}

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
