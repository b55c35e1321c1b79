//! Parallel SSHI whose inversion runs through its inductor: the synchronous switch of a
//! parallel SSHI (Guyomar et al. 2005, IEEE TUFFC 52 584; Lefeuvre et al. 2006) resolved in
//! time, the inductor current a state of its own (`parallel_sshi` with `inductance_h` in the
//! device's `[interface]`). The instantaneous inversion `Vp -> -gamma Vp` of
//! [`super::bridge`] is its limit of a fast inductor.
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

use super::bridge::{Bridge, Circuit};
use super::parts::Inverter;
use crate::model::AffineGuard;

/// A `|Vp|` below this fraction of its scale at an extremum is not inverted (nothing rings).
const EMPTY: f64 = 1e-9;

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
    pub fn rates<const N: usize>(
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
    pub fn jacobian<const N: usize>(&self, c: &Circuit, ringing: bool, j: &mut SMatrix<f64, N, N>) {
        if ringing {
            let (_, cp) = c.piezo();
            j[(c.e, self.inductor.i)] = -1.0 / cp;
            j[(self.inductor.i, c.e)] = 1.0 / self.inductor.l;
            j[(self.inductor.i, self.inductor.i)] = -self.inductor.rl / self.inductor.l;
        }
    }

    /// The ring's guard in a stage, dimensionless at the scales `sc`.
    #[inline]
    pub fn guard<const N: usize>(
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
    pub fn guard_piece<const N: usize>(
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
    pub fn close<const N: usize>(
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
    pub fn advance<const N: usize>(
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
    pub fn phase_of<const N: usize>(&self, y: &SVector<f64, N>) -> Option<Bridge> {
        let i = y[self.inductor.i];
        (i != 0.0).then_some(Bridge::Invert {
            negative: i < 0.0,
            returning: true,
        })
    }

    /// Power lost in the inductor's resistance (W).
    #[inline]
    pub fn resistive_power<const N: usize>(&self, y: &SVector<f64, N>) -> f64 {
        self.inductor.resistive_power(y[self.inductor.i])
    }
}
