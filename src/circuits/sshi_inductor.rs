//! Parallel SSHI whose inversion runs through its inductor: the synchronous switch of a
//! parallel SSHI (Guyomar et al. 2005, IEEE TUFFC 52 584; Lefeuvre et al. 2006) resolved in
//! time, the inductor current a state of its own (`parallel_sshi` with `inductance_h` in the
//! device's `[interface]`). The instantaneous inversion `Vp -> -gamma Vp` of
//! [`super::instant`] is its limit of a fast inductor.
//!
//! # The circuit
//! A piezoelectric element (`Cp`, coupling `theta`) behind the full bridge into the storage
//! `Cs` and its DC load, as the plain parallel SSHI. Across the element, a switch in series
//! with an inductor `L` of resistance `R_L`. The inductor current `I` (out of the element's
//! positive terminal) is the state component after the storage voltage. Between extrema the
//! switch is open, `I = 0`, and the bridge conducts as the plain bridge does. At each
//! displacement extremum (the velocity's sign turning, as for every synchronous switch) the
//! switch closes, the bridge stops conducting, and the element rings through the inductor:
//!
//! `Cp Vp' = -theta v - I`, `L I' = Vp - R_L I`, `Cs Vs' = -I_L`.
//!
//! The ring is two stages, in the bits of [`Bridge::Invert`] with `s` the sign of `Vp` when
//! the switch closed:
//!
//! * falling: `Vp` runs from its value at the extremum to zero while `s I` grows. The guard
//!   is `-s Vp`, which starts at `-|Vp|`, well below zero; at its zero `Vp` is put at exactly
//!   zero (a projection within the event tolerance).
//! * returning: `s I` falls back to zero while `Vp` swings to `-s gamma |Vp_0|`. The guard is
//!   `-s I`, armed only here, where it starts at the current's peak, well below zero: the
//!   switch opens where the current crosses zero towards the sign it did not have, and `I` is
//!   put at exactly zero.
//!
//! A single stage ending at `I = 0` would start with its guard at zero and fire at once, back
//! and forth at the extremum without time advancing: the stages arm the current's zero only
//! after the ring has started.
//!
//! # The inversion factor
//! With the mass still, the ring is the free L-C-R loop from `Vp_0` with no current: the
//! current's first zero is at half the damped period `pi / w_d`, where
//! `Vp = -Vp_0 exp(-alpha pi / w_d)`, `alpha = R_L / (2 L)`, `w_d = sqrt(1 / (L Cp) - alpha^2)`:
//! `gamma = exp(-pi / (2 Q) / sqrt(1 - 1 / (4 Q^2)))` with `Q = sqrt(L / Cp) / R_L`
//! ([`Inverter::gamma`]), `exp(-pi / (2 Q))` for a large `Q` (the form of Guyomar et al.). The
//! loop rings only if underdamped, `R_L < 2 sqrt(L / Cp)`, which the description checks.
//!
//! The ring is taken as short beside the vibration: an extremum during a ring only turns the
//! heading, and the bridge does not conduct during it (the element's voltage stays within
//! the `|Vp_0|` at which the bridge stopped, below its threshold once inverted with loss).
//!
//! # Ledger
//! The inductor's `L I^2 / 2` is stored energy and `R_L I^2` is the element's loss; the
//! switch moves energy only by its projections.

use nalgebra::{SMatrix, SVector};

use super::bridge::{Circuit, CircuitKind};
use super::description::{number, Inversion};
use super::element::Element;
use super::mode::{Bridge, CircuitMode, ResetLoss};
use super::parts::Inductor;
use crate::check::{Checker, ParamError};
use crate::model::AffineGuard;

/// A `|Vp|` below this fraction of its scale at an extremum is not inverted (nothing rings).
const EMPTY: f64 = 1e-9;

/// The inverting inductor of a parallel SSHI, evaluated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Inverter {
    /// The inductor, its resistance and its current.
    pub inductor: Inductor,
}

impl Inverter {
    /// The circuit's bridge states: the bridge's three, then the ring's stages by polarity.
    pub const PHASES: [Bridge; 7] = [
        Bridge::Off,
        Bridge::Positive,
        Bridge::Negative,
        Bridge::Invert {
            negative: false,
            returning: false,
        },
        Bridge::Invert {
            negative: true,
            returning: false,
        },
        Bridge::Invert {
            negative: false,
            returning: true,
        },
        Bridge::Invert {
            negative: true,
            returning: true,
        },
    ];

    /// The ring's stage in a bridge state: the sign `s` of the element's voltage when the
    /// switch closed, and whether the voltage has crossed zero; `None` with the switch open.
    #[inline(always)]
    pub fn stage(b: Bridge) -> Option<(f64, bool)> {
        match b {
            Bridge::Invert {
                negative,
                returning,
            } => Some((if negative { -1.0 } else { 1.0 }, returning)),
            _ => None,
        }
    }

    /// The inversion factor of the free ring (see the module docs) on the capacitance `cp`.
    pub fn gamma(&self, cp: f64) -> f64 {
        let alpha = self.inductor.rl / (2.0 * self.inductor.l);
        let wd = (1.0 / (self.inductor.l * cp) - alpha * alpha).sqrt();
        (-alpha * std::f64::consts::PI / wd).exp()
    }

    /// Adds the ring's loop to the rates the open bridge wrote (in a ringing stage), or holds
    /// the current (switch open).
    #[inline]
    fn ring_rates<const N: usize>(
        &self,
        c: &Circuit,
        ringing: bool,
        y: &SVector<f64, N>,
        rates: &mut SVector<f64, N>,
    ) {
        rates[self.inductor.i] = 0.0;
        if ringing {
            let (_, cp) = c.piezo();
            let i = y[self.inductor.i];
            rates[c.e] -= i / cp;
            rates[self.inductor.i] = (y[c.e] - self.inductor.rl * i) / self.inductor.l;
        }
    }

    /// Adds the ring's loop to the open bridge's Jacobian (in a ringing stage).
    fn ring_jacobian<const N: usize>(
        &self,
        c: &Circuit,
        ringing: bool,
        j: &mut SMatrix<f64, N, N>,
    ) {
        if ringing {
            let (_, cp) = c.piezo();
            j[(c.e, self.inductor.i)] = -1.0 / cp;
            j[(self.inductor.i, c.e)] = 1.0 / self.inductor.l;
            j[(self.inductor.i, self.inductor.i)] = -self.inductor.rl / self.inductor.l;
        }
    }

    /// The ring's guard in a stage, dimensionless at the scales `sc`.
    #[inline]
    fn ring_guard<const N: usize>(
        &self,
        c: &Circuit,
        (s, returning): (f64, bool),
        y: &SVector<f64, N>,
        sc: &SVector<f64, N>,
    ) -> f64 {
        if returning {
            -s * y[self.inductor.i] / sc[self.inductor.i]
        } else {
            -s * y[c.e] / sc[c.e]
        }
    }

    /// The ring's guard in a stage as an affine function of the state.
    fn ring_piece<const N: usize>(
        &self,
        c: &Circuit,
        (s, returning): (f64, bool),
        index: usize,
    ) -> AffineGuard<N> {
        let mut n = SVector::<f64, N>::zeros();
        n[if returning { self.inductor.i } else { c.e }] = -s;
        AffineGuard { index, n, g0: 0.0 }
    }

    /// At an extremum with the switch open: the ring's first stage, with the current put at
    /// zero, unless the element holds nothing to invert (then the bridge stays off).
    fn close<const N: usize>(
        &self,
        c: &Circuit,
        y: &mut SVector<f64, N>,
        sc: &SVector<f64, N>,
    ) -> Bridge {
        if y[c.e].abs() <= EMPTY * sc[c.e] {
            return Bridge::Off;
        }
        y[self.inductor.i] = 0.0;
        Bridge::Invert {
            negative: y[c.e] < 0.0,
            returning: false,
        }
    }

    /// The ring's guard fired in a stage: the next stage, or the switch open, with the
    /// quantity that crossed zero put at exactly zero.
    fn advance<const N: usize>(
        &self,
        c: &Circuit,
        (s, returning): (f64, bool),
        y: &mut SVector<f64, N>,
    ) -> Bridge {
        if returning {
            y[self.inductor.i] = 0.0;
            return Bridge::Off;
        }
        y[c.e] = 0.0;
        Bridge::Invert {
            negative: s < 0.0,
            returning: true,
        }
    }

    /// The stage a state starts in: returning while the inductor carries a current (in its
    /// direction), else the switch open.
    fn ring_phase_of<const N: usize>(&self, y: &SVector<f64, N>) -> Option<Bridge> {
        let i = y[self.inductor.i];
        (i != 0.0).then_some(Bridge::Invert {
            negative: i < 0.0,
            returning: true,
        })
    }

    /// Power lost in the inductor's resistance (W).
    #[inline]
    fn resistive_power<const N: usize>(&self, y: &SVector<f64, N>) -> f64 {
        self.inductor.resistive_power(y[self.inductor.i])
    }
}

/// The bridge's state during a ring: off.
#[inline(always)]
fn open_in_ring(bridge: Bridge) -> Bridge {
    match bridge {
        Bridge::Invert { .. } => Bridge::Off,
        b => b,
    }
}

impl CircuitKind for Inverter {
    fn refuses(&self, element: &Element) -> Option<&'static str> {
        (!matches!(element, Element::Piezo { .. })).then_some(
            "an SSHI's inductor rings with a piezoelectric element's clamped capacitance only",
        )
    }

    fn inductor(&self) -> Option<Inductor> {
        Some(self.inductor)
    }

    fn phases(&self) -> &'static [Bridge] {
        &Self::PHASES
    }

    /// The bridge's rates, open during a ring, with the ring's loop added.
    #[inline(always)]
    fn force_and_rates<const N: usize>(
        &self,
        c: &Circuit,
        bridge: Bridge,
        y: &SVector<f64, N>,
        rates: &mut SVector<f64, N>,
    ) -> f64 {
        let ringing = Self::stage(bridge).is_some();
        let f = c.bridge_force_and_rates(open_in_ring(bridge), y, rates);
        self.ring_rates(c, ringing, y, rates);
        f
    }

    fn jacobian<const N: usize>(
        &self,
        c: &Circuit,
        bridge: Bridge,
        y: &SVector<f64, N>,
        m: f64,
        sc: &SVector<f64, N>,
        j: &mut SMatrix<f64, N, N>,
    ) {
        c.bridge_jacobian(open_in_ring(bridge), y, m, sc, j);
        self.ring_jacobian(c, Self::stage(bridge).is_some(), j);
    }

    #[inline(always)]
    fn diode_power<const N: usize>(&self, c: &Circuit, bridge: Bridge, y: &SVector<f64, N>) -> f64 {
        c.bridge_diode_power(open_in_ring(bridge), y)
    }

    #[inline(always)]
    fn element_loss<const N: usize>(
        &self,
        _c: &Circuit,
        _bridge: Bridge,
        y: &SVector<f64, N>,
    ) -> f64 {
        self.resistive_power(y)
    }

    fn time_constant_s(&self, c: &Circuit) -> f64 {
        let ring = self.inductor.time_constant_s(c.piezo().1);
        c.bridge_time_constant_s().min(ring)
    }

    /// The ring's stage guards it; the bridge's conduction guards the open switch.
    #[inline(always)]
    fn conduction_guard<const N: usize>(
        &self,
        c: &Circuit,
        bridge: Bridge,
        y: &SVector<f64, N>,
        sc: &SVector<f64, N>,
    ) -> f64 {
        match Self::stage(bridge) {
            Some(stage) => self.ring_guard(c, stage, y, sc),
            None => c.bridge_guard(bridge, y, sc),
        }
    }

    fn guard_piece<const N: usize>(
        &self,
        c: &Circuit,
        bridge: Bridge,
        index: usize,
    ) -> Option<AffineGuard<N>> {
        Self::stage(bridge).map(|stage| self.ring_piece(c, stage, index))
    }

    fn switch<const N: usize>(
        &self,
        c: &Circuit,
        mode: CircuitMode,
        extremum: bool,
        y: &mut SVector<f64, N>,
        sc: &SVector<f64, N>,
    ) -> (CircuitMode, ResetLoss) {
        let mut next = mode;
        let stage = Self::stage(mode.bridge);
        if extremum {
            // v is put at exactly zero, as for every synchronous switch; an extremum during a
            // ring only turns the heading.
            y[1] = 0.0;
            next.heading = mode.heading.turned();
            if stage.is_none() {
                next.bridge = self.close(c, y, sc);
            }
            return (next, ResetLoss::default());
        }
        if let Some(stage) = stage {
            next.bridge = self.advance(c, stage, y);
            return (next, ResetLoss::default());
        }
        c.bridge_switch(mode, false, y, sc)
    }

    fn phase_of<const N: usize>(&self, c: &Circuit, y: &SVector<f64, N>) -> Bridge {
        self.ring_phase_of(y)
            .unwrap_or_else(|| c.bridge_phase_of(y))
    }

    /// The current flows as the element's voltage drives it: it changes sign.
    fn mirror<const N: usize>(&self, s: &mut SMatrix<f64, N, N>) {
        s[(self.inductor.i, self.inductor.i)] = -1.0;
    }
}

/// The file keys of the ringing inductor, beside a parallel SSHI's bridge.
pub(super) const KEYS: [&str; 2] = ["inductance_h", "inductor_resistance_ohm"];

/// The inversion through the inductor a parallel SSHI's keys give, if `inductance_h` is
/// among them (`inductor_resistance_ohm` is 0 when not given).
pub(super) fn inversion(keys: &toml::Table, c: &Checker) -> Result<Option<Inversion>, ParamError> {
    let Some(inductance_h) = number(keys, "inductance_h", c)? else {
        return Ok(None);
    };
    Ok(Some(Inversion::Inductor {
        inductance_h,
        resistance_ohm: number(keys, "inductor_resistance_ohm", c)?.unwrap_or(0.0),
    }))
}

/// Checks the inverting inductor: positive, with a resistance that leaves the ring with the
/// element's clamped capacitance `clamped_capacitance_f` (F; `None` for another transducer)
/// underdamped, `R_L < 2 sqrt(L / Cp)` (with more, the element's voltage never swings through
/// zero and nothing is inverted).
pub(super) fn check_ring(
    inductance_h: f64,
    resistance_ohm: f64,
    clamped_capacitance_f: Option<f64>,
    c: &Checker,
) -> Result<(), ParamError> {
    c.positive("interface.inductance_h", inductance_h)?;
    c.non_negative("interface.inductor_resistance_ohm", resistance_ohm)?;
    if let Some(cp) = clamped_capacitance_f {
        let critical = 2.0 * (inductance_h / cp).sqrt();
        if resistance_ohm >= critical {
            return Err(c.err(
                "interface.inductor_resistance_ohm",
                resistance_ohm,
                &format!(
                    "below 2 sqrt(L / Cp) = {critical:e} ohm (an overdamped ring inverts \
                     nothing)"
                ),
            ));
        }
    }
    Ok(())
}
