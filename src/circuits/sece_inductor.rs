//! Synchronous electric charge extraction through its buck-boost inductor: the SECE whose
//! transfer is resolved in time, with the inductor current a state of its own
//! ([`SeceInductor`], its description: `sece` with `inductance_h` in a device's
//! `[interface]`). The instantaneous SECE of [`super::instant`] is its limit
//! of a fast inductor.
//!
//! # The circuit
//! A piezoelectric element (`Cp`, coupling `theta`) behind an ideal rectifier; at each
//! displacement extremum a switch connects the rectified element to an inductor `L` with
//! series resistance `R_L`, whose flyback diode (forward drop `V_F`) feeds the storage `Cs`
//! and its DC load `I_L(Vs)`. The inductor current `I >= 0` is the state component after the
//! storage voltage. Three phases, in the bits of the circuit's [`Bridge`]:
//!
//! * open ([`Bridge::Off`]): `Cp Vp' = -theta v`, `I = 0`, `Cs Vs' = -I_L`. An extremum (the
//!   velocity's sign turning, as for every synchronous switch) closes the switch with the
//!   rectifier's polarity `s = sign(Vp)`, unless `|Vp|` is below 1e-9 of its scale (nothing to
//!   extract: the guard of the next phase would start at zero).
//! * charge ([`Bridge::Positive`], [`Bridge::Negative`] by `s`): the element discharges into
//!   the inductor, `Cp Vp' = -theta v - s I`, `L I' = s Vp - R_L I`. The guard is `-s Vp`: the
//!   phase ends when the element's voltage reaches zero, where it is put at exactly zero (a
//!   projection within the event tolerance).
//! * flyback ([`Bridge::Flyback`]): the switch opens and the inductor discharges into the
//!   storage, `L I' = -(Vs + V_F) - R_L I`, `Cs Vs' = I - I_L`, the element open. The guard
//!   is `-I`: the phase ends when the current reaches zero (put at exactly zero), and the
//!   circuit is open again.
//!
//! The mass feels `theta Vp` throughout. An extremum during a transfer (an inductor so slow
//! that a transfer outlasts half a period) only turns the heading: the transfer runs on.
//!
//! The charge phase ends with the current at its peak only if the loop is underdamped,
//! `R_L < 2 sqrt(L / Cp)` (with more, `Vp` decays without reaching zero): the description
//! refuses more. With `R_L = 0` and `V_F = 0` the transfer loses nothing, so in the limit of
//! a fast inductor this circuit is the instantaneous SECE with efficiency 1
//! (`tests/interface_sece_inductor.rs` shows the convergence).
//!
//! # Ledger
//! The inductor's `L I^2 / 2` is stored energy; `R_L I^2` is the element's loss, `V_F I` in
//! flyback the diodes'; the switches move energy only by their projections.

use nalgebra::{SMatrix, SVector};

use super::bridge::{Circuit, CircuitKind};
use super::description::{number, put, put_storage, storage_and_load, takes, DcLoad, Keys};
use super::element::Element;
use super::instant::{IDEAL, SECE_DIODE};
use super::mode::{Bridge, CircuitMode, Heading, ResetLoss};
use super::parts::Inductor;
use super::{Described, Interface, InterfaceKind, Kind};
use crate::check::{Checker, ParamError};
use crate::model::AffineGuard;

/// A `|Vp|` below this fraction of its scale at an extremum is not extracted.
const EMPTY: f64 = 1e-9;

/// The buck-boost inductor of a SECE through its inductor and its flyback diode, evaluated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BuckBoost {
    /// The inductor, its resistance and its current.
    pub inductor: Inductor,
    /// The flyback diode's forward drop V_F (V).
    pub vf: f64,
}

impl BuckBoost {
    /// The circuit's phases, as bridge states: open, charge by polarity, flyback.
    pub const PHASES: [Bridge; 4] = [
        Bridge::Off,
        Bridge::Positive,
        Bridge::Negative,
        Bridge::Flyback,
    ];

    /// The inductor current in a phase (A): zero while open.
    #[inline(always)]
    fn current<const N: usize>(&self, phase: Bridge, y: &SVector<f64, N>) -> f64 {
        if phase == Bridge::Off {
            0.0
        } else {
            y[self.inductor.i]
        }
    }

    /// The force on the mass (N) and the rates of `Vp`, `Vs` and `I` in a phase.
    #[inline]
    fn phase_rates<const N: usize>(
        &self,
        c: &Circuit,
        phase: Bridge,
        y: &SVector<f64, N>,
        rates: &mut SVector<f64, N>,
    ) -> f64 {
        let (theta, cp) = c.piezo();
        let (e, ivs, ii) = (c.e, c.vs, self.inductor.i);
        let (vp, vs) = (y[e], y[ivs]);
        let i = self.current(phase, y);
        let il = c.sink.current(vs);
        rates[e] = -theta * y[1] / cp;
        rates[ivs] = -il / c.cs;
        rates[ii] = 0.0;
        match phase {
            Bridge::Off | Bridge::Invert { .. } => {}
            Bridge::Positive | Bridge::Negative => {
                let s = phase.sign();
                rates[e] -= s * i / cp;
                rates[ii] = (s * vp - self.inductor.rl * i) / self.inductor.l;
            }
            Bridge::Flyback => {
                rates[ii] = (-(vs + self.vf) - self.inductor.rl * i) / self.inductor.l;
                rates[ivs] = (i - il) / c.cs;
            }
        }
        theta * vp
    }

    /// The circuit's part of the Jacobian in a phase (see [`Circuit::jacobian`]).
    fn phase_jacobian<const N: usize>(
        &self,
        c: &Circuit,
        phase: Bridge,
        m: f64,
        j: &mut SMatrix<f64, N, N>,
    ) {
        let (theta, cp) = c.piezo();
        let (e, ivs, ii) = (c.e, c.vs, self.inductor.i);
        let gl = c.sink_conductance();
        j[(1, e)] += theta / m;
        j[(e, 1)] = -theta / cp;
        j[(ivs, ivs)] = -gl / c.cs;
        match phase {
            Bridge::Off | Bridge::Invert { .. } => {}
            Bridge::Positive | Bridge::Negative => {
                let s = phase.sign();
                j[(e, ii)] = -s / cp;
                j[(ii, e)] = s / self.inductor.l;
                j[(ii, ii)] = -self.inductor.rl / self.inductor.l;
            }
            Bridge::Flyback => {
                j[(ii, ivs)] = -1.0 / self.inductor.l;
                j[(ii, ii)] = -self.inductor.rl / self.inductor.l;
                j[(ivs, ii)] = 1.0 / c.cs;
            }
        }
    }

    /// The phase's guard, dimensionless at the scales `sc` (the extremum's is the circuit's).
    #[inline]
    fn phase_guard<const N: usize>(
        &self,
        c: &Circuit,
        phase: Bridge,
        y: &SVector<f64, N>,
        sc: &SVector<f64, N>,
    ) -> f64 {
        match phase {
            Bridge::Off | Bridge::Invert { .. } => f64::NEG_INFINITY,
            Bridge::Positive | Bridge::Negative => -phase.sign() * y[c.e] / sc[c.e],
            Bridge::Flyback => -y[self.inductor.i] / sc[self.inductor.i],
        }
    }

    /// The phase's guard as an affine function of the state (for the exact propagators).
    fn phase_guard_piece<const N: usize>(
        &self,
        c: &Circuit,
        phase: Bridge,
        index: usize,
    ) -> Option<AffineGuard<N>> {
        let mut n = SVector::<f64, N>::zeros();
        match phase {
            Bridge::Off | Bridge::Invert { .. } => return None,
            Bridge::Positive | Bridge::Negative => n[c.e] = -phase.sign(),
            Bridge::Flyback => n[self.inductor.i] = -1.0,
        }
        Some(AffineGuard { index, n, g0: 0.0 })
    }

    /// The switch when the circuit's guard fires (`extremum` when the extremum's guard is the
    /// larger): the next mode, with `y` projected.
    fn phase_switch<const N: usize>(
        &self,
        c: &Circuit,
        mode: CircuitMode,
        extremum: bool,
        y: &mut SVector<f64, N>,
        sc: &SVector<f64, N>,
    ) -> CircuitMode {
        let mut next = mode;
        if extremum {
            // As for every synchronous switch: v is put at exactly zero so that the new
            // heading's guard starts at zero.
            y[1] = 0.0;
            next.heading = match mode.heading {
                Heading::Up => Heading::Down,
                Heading::Down => Heading::Up,
            };
            if mode.bridge == Bridge::Off && y[c.e].abs() > EMPTY * sc[c.e] {
                y[self.inductor.i] = 0.0;
                next.bridge = if y[c.e] > 0.0 {
                    Bridge::Positive
                } else {
                    Bridge::Negative
                };
            }
            return next;
        }
        match mode.bridge {
            Bridge::Positive | Bridge::Negative => {
                y[c.e] = 0.0;
                next.bridge = Bridge::Flyback;
            }
            Bridge::Flyback => {
                y[self.inductor.i] = 0.0;
                next.bridge = Bridge::Off;
            }
            Bridge::Off | Bridge::Invert { .. } => {}
        }
        next
    }

    /// The phase a state starts in: flyback while the inductor carries a current, else open.
    fn phase_at<const N: usize>(&self, y: &SVector<f64, N>) -> Bridge {
        if y[self.inductor.i] > 0.0 {
            Bridge::Flyback
        } else {
            Bridge::Off
        }
    }

    /// Power lost in the inductor's resistance (W).
    #[inline]
    fn resistive_power<const N: usize>(&self, phase: Bridge, y: &SVector<f64, N>) -> f64 {
        self.inductor.resistive_power(self.current(phase, y))
    }

    /// Power lost in the flyback diode (W).
    #[inline]
    fn flyback_power<const N: usize>(&self, phase: Bridge, y: &SVector<f64, N>) -> f64 {
        if phase == Bridge::Flyback {
            self.vf * y[self.inductor.i]
        } else {
            0.0
        }
    }
}

impl CircuitKind for BuckBoost {
    fn refuses(&self, element: &Element) -> Option<&'static str> {
        (!matches!(element, Element::Piezo { .. })).then_some(
            "a SECE's inductor discharges a piezoelectric element's clamped capacitance only",
        )
    }

    fn inductor(&self) -> Option<Inductor> {
        Some(self.inductor)
    }

    fn phases(&self) -> &'static [Bridge] {
        &Self::PHASES
    }

    #[inline(always)]
    fn bridge_between_extrema(&self) -> bool {
        false
    }

    #[inline(always)]
    fn force_and_rates<const N: usize>(
        &self,
        c: &Circuit,
        bridge: Bridge,
        y: &SVector<f64, N>,
        rates: &mut SVector<f64, N>,
    ) -> f64 {
        self.phase_rates(c, bridge, y, rates)
    }

    fn jacobian<const N: usize>(
        &self,
        c: &Circuit,
        bridge: Bridge,
        _y: &SVector<f64, N>,
        m: f64,
        _sc: &SVector<f64, N>,
        j: &mut SMatrix<f64, N, N>,
    ) {
        self.phase_jacobian(c, bridge, m, j)
    }

    #[inline(always)]
    fn diode_power<const N: usize>(
        &self,
        _c: &Circuit,
        bridge: Bridge,
        y: &SVector<f64, N>,
    ) -> f64 {
        self.flyback_power(bridge, y)
    }

    #[inline(always)]
    fn element_loss<const N: usize>(
        &self,
        _c: &Circuit,
        bridge: Bridge,
        y: &SVector<f64, N>,
    ) -> f64 {
        self.resistive_power(bridge, y)
    }

    fn time_constant_s(&self, c: &Circuit) -> f64 {
        self.inductor.time_constant_s(c.piezo().1)
    }

    #[inline(always)]
    fn conduction_guard<const N: usize>(
        &self,
        c: &Circuit,
        bridge: Bridge,
        y: &SVector<f64, N>,
        sc: &SVector<f64, N>,
    ) -> f64 {
        self.phase_guard(c, bridge, y, sc)
    }

    fn guard_piece<const N: usize>(
        &self,
        c: &Circuit,
        bridge: Bridge,
        index: usize,
    ) -> Option<AffineGuard<N>> {
        self.phase_guard_piece(c, bridge, index)
    }

    fn switch<const N: usize>(
        &self,
        c: &Circuit,
        mode: CircuitMode,
        extremum: bool,
        y: &mut SVector<f64, N>,
        sc: &SVector<f64, N>,
    ) -> (CircuitMode, ResetLoss) {
        let next = self.phase_switch(c, mode, extremum, y, sc);
        (next, ResetLoss::default())
    }

    fn phase_of<const N: usize>(&self, _c: &Circuit, y: &SVector<f64, N>) -> Bridge {
        self.phase_at(y)
    }

    /// The current flows one way behind the rectifier: it keeps its sign.
    fn mirror<const N: usize>(&self, s: &mut SMatrix<f64, N, N>) {
        s[(self.inductor.i, self.inductor.i)] = 1.0;
    }
}

/// A SECE whose transfer runs through its buck-boost inductor, as a device describes it: at
/// each displacement extremum the rectified element discharges into the inductor, which then
/// discharges into the storage through a flyback diode ([`BuckBoost`]).
#[derive(Debug, Clone, PartialEq)]
pub struct SeceInductor {
    /// Storage capacitance C_s (F).
    pub storage_capacitance_f: f64,
    /// The DC load.
    pub load: DcLoad,
    /// The inductance L (H).
    pub inductance_h: f64,
    /// The inductor's series resistance R_L (ohm).
    pub inductor_resistance_ohm: f64,
    /// The flyback diode's forward drop V_F (V).
    pub flyback_drop_v: f64,
}

/// The description of `sece` with `inductance_h` (optional `inductor_resistance_ohm` and
/// `flyback_drop_v`, 0 when not given): it takes no `efficiency`, the transfer losing what
/// the resistance and the diode take.
pub struct SeceInductorFile;

impl SeceInductorFile {
    /// The variant's description.
    fn of(i: &Interface) -> Option<&SeceInductor> {
        match i {
            Interface::SeceInductor(s) => Some(s),
            _ => None,
        }
    }
}

impl InterfaceKind for SeceInductorFile {
    fn key(&self) -> &'static str {
        "sece"
    }

    fn claims(&self, keys: &toml::Table) -> bool {
        keys.contains_key("inductance_h")
    }

    fn check_key(&self, _keys: &toml::Table, key: &str, c: &Checker) -> Result<(), ParamError> {
        match key {
            "efficiency" => Err(c.message(
                "interface.efficiency",
                "interface kind `sece` with `inductance_h` takes no `efficiency`: the transfer \
                 through the inductor loses what its resistance and flyback diode take",
            )),
            "diode" => Err(c.message("interface.diode", SECE_DIODE)),
            _ => takes(
                self.key(),
                &[
                    "storage_capacitance_f",
                    "load",
                    "inductance_h",
                    "inductor_resistance_ohm",
                    "flyback_drop_v",
                ],
                key,
                c,
            ),
        }
    }

    fn parse(&self, keys: &toml::Table, c: &Checker) -> Result<Interface, ParamError> {
        let (storage_capacitance_f, load) = storage_and_load(keys, c)?;
        Ok(Interface::SeceInductor(SeceInductor {
            storage_capacitance_f,
            load,
            inductance_h: number(keys, "inductance_h", c)?.unwrap_or(f64::NAN),
            inductor_resistance_ohm: number(keys, "inductor_resistance_ohm", c)?.unwrap_or(0.0),
            flyback_drop_v: number(keys, "flyback_drop_v", c)?.unwrap_or(0.0),
        }))
    }

    fn write(&self, i: &Interface, keys: &mut Keys) {
        if let Some(s) = Self::of(i) {
            put_storage(keys, s.storage_capacitance_f);
            put(keys, "load", &s.load);
            put(keys, "inductance_h", s.inductance_h);
            put(keys, "inductor_resistance_ohm", s.inductor_resistance_ohm);
            put(keys, "flyback_drop_v", s.flyback_drop_v);
        }
    }

    fn storage<'a>(&self, i: &'a Interface) -> Option<(f64, &'a DcLoad)> {
        Self::of(i).map(|s| (s.storage_capacitance_f, &s.load))
    }

    fn load_mut<'a>(&self, i: &'a mut Interface) -> Option<&'a mut DcLoad> {
        match i {
            Interface::SeceInductor(s) => Some(&mut s.load),
            _ => None,
        }
    }

    /// The inductor's values, and that the charge phase's loop with the element's clamped
    /// capacitance is underdamped, `R_L < 2 sqrt(L / Cp)`: with more, the element's voltage
    /// decays without reaching zero and the transfer never ends.
    fn validate(
        &self,
        i: &Interface,
        clamped_capacitance_f: Option<f64>,
        c: &Checker,
    ) -> Result<(), ParamError> {
        let Some(s) = Self::of(i) else {
            return Ok(());
        };
        c.positive("interface.inductance_h", s.inductance_h)?;
        c.non_negative(
            "interface.inductor_resistance_ohm",
            s.inductor_resistance_ohm,
        )?;
        c.non_negative("interface.flyback_drop_v", s.flyback_drop_v)?;
        if let Some(cp) = clamped_capacitance_f {
            let critical = 2.0 * (s.inductance_h / cp).sqrt();
            if s.inductor_resistance_ohm >= critical {
                return Err(c.err(
                    "interface.inductor_resistance_ohm",
                    s.inductor_resistance_ohm,
                    &format!(
                        "below 2 sqrt(L / Cp) = {critical:e} ohm (an overdamped transfer never \
                         empties the element)"
                    ),
                ));
            }
        }
        Ok(())
    }

    fn model<'a>(&self, i: &'a Interface, slot: usize) -> Result<Described<'a>, &'static str> {
        let s = Self::of(i).ok_or("the interface is not a SECE through its inductor")?;
        Ok(Described {
            diode: IDEAL,
            cs: s.storage_capacitance_f,
            load: &s.load,
            kind: Kind::SeceInductor(BuckBoost {
                inductor: Inductor {
                    l: s.inductance_h,
                    rl: s.inductor_resistance_ohm,
                    i: slot,
                },
                vf: s.flyback_drop_v,
            }),
        })
    }
}
