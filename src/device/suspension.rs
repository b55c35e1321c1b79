//! The suspension's restoring force in a device file: linear (the default), a polynomial, or a
//! double well given by its wells and barrier.
//!
//! | `[mechanics.suspension]` `form` | restoring force `F_s(x)` | keys |
//! |---|---|---|
//! | (no table) or `linear` | `k x` with `k = mechanics.stiffness_n_per_m` | none |
//! | `polynomial` | `k1 x + k2 x^2 + ... + k7 x^7` (a negative `k1` allowed) | `k1_n_per_m`, `k2_n_per_m2`, ..., `k7_n_per_m7` (absent: 0) |
//! | `bistable` | `-k x + k3 x^3`, the double well `U = -k x^2/2 + k3 x^4/4` with its wells at `+-well_m` and `barrier_j` above them: `k = 4 barrier / well^2`, `k3 = k / well^2` | `well_m`, `barrier_j` |
//!
//! With a nonlinear form, `mechanics.stiffness_n_per_m` is not written: the device derives it
//! on load as the small-oscillation stiffness at its reference well (the stable equilibrium
//! nearest rest, [`crate::laws::suspension::reference_well`]), the stiffness the linear
//! theory, the time scales and the records' linearisation use.
//!
//! Refused, with an error naming the file, the field, the value and the valid range: a
//! non-finite coefficient, a well or barrier not above zero, a suspension that does not
//! confine the mass on a side without a stop there that does (a rigid stop, or a compliant one
//! whose force grows faster than the suspension's, or as fast and stiffer), and, for the
//! `bistable` form, a stop at or inside a well (the form names wells the mass could not reach;
//! a device held on its stops is a `polynomial`).

use serde::{Deserialize, Serialize};

use super::{Checker, Device, ParamError, StopLaw};
use crate::laws::contact::Side;
use crate::laws::suspension::{equilibria, reference_well, Polynomial, MAX_ORDER};

/// The restoring force of the suspension (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Suspension {
    /// `k x`, with `k` = `mechanics.stiffness_n_per_m`.
    #[default]
    Linear,
    /// `k1 x + ... + k7 x^7`.
    Polynomial {
        /// `k1 .. k7` (N/m^i).
        k: [f64; MAX_ORDER],
    },
    /// The double well with wells at `+-well_m` and barrier `barrier_j`.
    Bistable {
        /// Well position (m).
        well_m: f64,
        /// Barrier height above the wells (J).
        barrier_j: f64,
    },
}

impl Suspension {
    /// True for the linear default.
    pub fn is_linear(&self) -> bool {
        matches!(self, Suspension::Linear)
    }

    /// The `form` key.
    pub fn key(&self) -> &'static str {
        match self {
            Suspension::Linear => "linear",
            Suspension::Polynomial { .. } => "polynomial",
            Suspension::Bistable { .. } => "bistable",
        }
    }

    /// `k1 .. k7` of the restoring force (N/m^i); `linear_k` is the linear form's stiffness.
    pub fn coefficients(&self, linear_k: f64) -> [f64; MAX_ORDER] {
        let mut c = [0.0; MAX_ORDER];
        match *self {
            Suspension::Linear => c[0] = linear_k,
            Suspension::Polynomial { k } => c = k,
            Suspension::Bistable { well_m, barrier_j } => {
                let k = 4.0 * barrier_j / (well_m * well_m);
                c[0] = -k;
                c[2] = k / (well_m * well_m);
            }
        }
        c
    }
}

/// The key names of the polynomial's coefficients, `k1_n_per_m` to `k7_n_per_m7`.
pub const COEFFICIENT_KEYS: [&str; MAX_ORDER] = [
    "k1_n_per_m",
    "k2_n_per_m2",
    "k3_n_per_m3",
    "k4_n_per_m4",
    "k5_n_per_m5",
    "k6_n_per_m6",
    "k7_n_per_m7",
];

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
enum FormKey {
    Linear,
    Polynomial,
    Bistable,
}

/// The `[mechanics.suspension]` table as written.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSuspension {
    form: Option<FormKey>,
    #[serde(skip_serializing_if = "Option::is_none")]
    k1_n_per_m: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    k2_n_per_m2: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    k3_n_per_m3: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    k4_n_per_m4: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    k5_n_per_m5: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    k6_n_per_m6: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    k7_n_per_m7: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    well_m: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    barrier_j: Option<f64>,
}

/// The `[mechanics]` table as written.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawMechanics {
    mass_kg: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    stiffness_n_per_m: Option<f64>,
    damping_n_s_per_m: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    measured_resonance_hz: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    suspension: Option<RawSuspension>,
}

impl RawSuspension {
    fn coefficients(&self) -> [Option<f64>; MAX_ORDER] {
        [
            self.k1_n_per_m,
            self.k2_n_per_m2,
            self.k3_n_per_m3,
            self.k4_n_per_m4,
            self.k5_n_per_m5,
            self.k6_n_per_m6,
            self.k7_n_per_m7,
        ]
    }

    fn parse(&self, c: &Checker) -> Result<Suspension, ParamError> {
        const P: &str = "mechanics.suspension";
        let form = self.form.ok_or_else(|| {
            c.missing(&format!("{P}.form"), "one of linear, polynomial, bistable")
        })?;
        let coeffs = self.coefficients();
        let present: Vec<&str> = COEFFICIENT_KEYS
            .iter()
            .zip(coeffs)
            .filter(|(_, v)| v.is_some())
            .map(|(k, _)| *k)
            .chain(self.well_m.map(|_| "well_m"))
            .chain(self.barrier_j.map(|_| "barrier_j"))
            .collect();
        let allowed: &[&str] = match form {
            FormKey::Linear => &[],
            FormKey::Polynomial => &COEFFICIENT_KEYS,
            FormKey::Bistable => &["well_m", "barrier_j"],
        };
        let name = match form {
            FormKey::Linear => "linear",
            FormKey::Polynomial => "polynomial",
            FormKey::Bistable => "bistable",
        };
        if let Some(key) = present.iter().find(|k| !allowed.contains(k)) {
            return Err(c.message(
                &format!("{P}.{key}"),
                &format!(
                    "form `{name}` does not take `{key}` (its keys: {})",
                    if allowed.is_empty() {
                        "none; the stiffness is mechanics.stiffness_n_per_m".to_string()
                    } else {
                        allowed.join(", ")
                    }
                ),
            ));
        }
        Ok(match form {
            FormKey::Linear => Suspension::Linear,
            FormKey::Polynomial => {
                let mut k = [0.0; MAX_ORDER];
                for (i, v) in coeffs.iter().enumerate() {
                    if let Some(v) = v {
                        if !v.is_finite() {
                            return Err(c.err(
                                &format!("{P}.{}", COEFFICIENT_KEYS[i]),
                                *v,
                                "finite",
                            ));
                        }
                        k[i] = *v;
                    }
                }
                if k.iter().skip(1).all(|&v| v == 0.0) {
                    return Err(c.message(
                        &format!("{P}.form"),
                        "a polynomial needs a non-zero term of order 2 or more (a linear \
                         suspension is mechanics.stiffness_n_per_m without this table)",
                    ));
                }
                Suspension::Polynomial { k }
            }
            FormKey::Bistable => {
                let need = |key: &str, v: Option<f64>| {
                    v.ok_or_else(|| c.missing(&format!("{P}.{key}"), "form `bistable` needs it"))
                };
                let well_m = need("well_m", self.well_m)?;
                let barrier_j = need("barrier_j", self.barrier_j)?;
                c.positive(&format!("{P}.well_m"), well_m)?;
                c.positive(&format!("{P}.barrier_j"), barrier_j)?;
                Suspension::Bistable { well_m, barrier_j }
            }
        })
    }

    fn of(s: &Suspension) -> Option<Self> {
        let mut r = Self::default();
        match *s {
            Suspension::Linear => return None,
            Suspension::Polynomial { k } => {
                r.form = Some(FormKey::Polynomial);
                let slots = [
                    &mut r.k1_n_per_m,
                    &mut r.k2_n_per_m2,
                    &mut r.k3_n_per_m3,
                    &mut r.k4_n_per_m4,
                    &mut r.k5_n_per_m5,
                    &mut r.k6_n_per_m6,
                    &mut r.k7_n_per_m7,
                ];
                for (slot, v) in slots.into_iter().zip(k) {
                    if v != 0.0 {
                        *slot = Some(v);
                    }
                }
            }
            Suspension::Bistable { well_m, barrier_j } => {
                r.form = Some(FormKey::Bistable);
                r.well_m = Some(well_m);
                r.barrier_j = Some(barrier_j);
            }
        }
        Some(r)
    }
}

impl RawMechanics {
    /// The mechanics of a file; a nonlinear suspension's `stiffness_n_per_m` is left at NaN
    /// for [`Device::derive_well_stiffness`] to fill once the stops are known.
    pub(super) fn parse(&self, c: &Checker) -> Result<super::Mechanics, ParamError> {
        let suspension = match &self.suspension {
            Some(s) => s.parse(c)?,
            None => Suspension::Linear,
        };
        let stiffness_n_per_m = match (suspension.is_linear(), self.stiffness_n_per_m) {
            (true, Some(k)) => k,
            (true, None) => {
                return Err(c.missing(
                    "mechanics.stiffness_n_per_m",
                    "the linear suspension's stiffness (N/m)",
                ))
            }
            (false, Some(_)) => {
                return Err(c.message(
                    "mechanics.stiffness_n_per_m",
                    &format!(
                        "is derived from mechanics.suspension (form `{}`): the small-oscillation \
                         stiffness at the reference well; write the suspension's own keys",
                        suspension.key()
                    ),
                ))
            }
            (false, None) => f64::NAN,
        };
        Ok(super::Mechanics {
            mass_kg: self.mass_kg,
            stiffness_n_per_m,
            damping_n_s_per_m: self.damping_n_s_per_m,
            measured_resonance_hz: self.measured_resonance_hz,
            suspension,
        })
    }

    pub(super) fn of(m: &super::Mechanics) -> Self {
        Self {
            mass_kg: m.mass_kg,
            stiffness_n_per_m: m.suspension.is_linear().then_some(m.stiffness_n_per_m),
            damping_n_s_per_m: m.damping_n_s_per_m,
            measured_resonance_hz: m.measured_resonance_hz,
            suspension: RawSuspension::of(&m.suspension),
        }
    }
}

/// How fast a stop's force grows with penetration (its power) and its stiffness coefficient,
/// for the confinement check; `None` for a rigid stop (it confines whatever pushes).
fn stop_growth(law: &StopLaw) -> Option<(f64, f64)> {
    match law {
        StopLaw::HertzLine(h) => Some((1.0, h.linear_stiffness_n_per_m())),
        StopLaw::Linear { stiffness_n_per_m } => Some((1.0, *stiffness_n_per_m)),
        StopLaw::HertzPoint(k) => Some((1.5, k.value())),
        StopLaw::HuntCrossley {
            stiffness_n_per_m_pow_n,
            exponent,
            ..
        } => Some((*exponent, *stiffness_n_per_m_pow_n)),
        StopLaw::Restitution { .. } => None,
    }
}

impl Device {
    /// The suspension's restoring polynomial `k1 .. k7`.
    pub fn restoring_polynomial(&self) -> Polynomial {
        Polynomial(
            self.mechanics
                .suspension
                .coefficients(self.mechanics.stiffness_n_per_m),
        )
    }

    /// Fills a nonlinear suspension's `mechanics.stiffness_n_per_m` with the stiffness at its
    /// reference well (the laws' [`reference_well`] of the suspension with the stops; the
    /// device's equilibria themselves are [`crate::physics::statics`]'s).
    pub(super) fn derive_well_stiffness(&mut self) {
        if !self.mechanics.suspension.is_linear() {
            let poly = self.restoring_polynomial();
            let (upper, lower) = self.stop_models();
            let well = reference_well(&equilibria(&poly, upper.as_ref(), lower.as_ref()));
            // On a rigid stop the static stiffness is infinite: the suspension's own sets
            // the scales there.
            self.mechanics.stiffness_n_per_m = well.map_or(f64::NAN, |w| {
                if w.stiffness_n_per_m.is_finite() {
                    w.stiffness_n_per_m
                } else {
                    poly.stiffness(w.x_m).abs().max(poly.0[0].abs())
                }
            });
        }
    }

    /// The checks of a nonlinear suspension against the stops (see the module docs).
    pub(super) fn validate_suspension(&self, c: &Checker) -> Result<(), ParamError> {
        let s = &self.mechanics.suspension;
        if s.is_linear() {
            return Ok(());
        }
        const P: &str = "mechanics.suspension";
        let poly = self.restoring_polynomial();
        if let Suspension::Polynomial { k } = s {
            for (i, v) in k.iter().enumerate() {
                if !v.is_finite() {
                    return Err(c.err(&format!("{P}.{}", COEFFICIENT_KEYS[i]), *v, "finite"));
                }
            }
        }
        if let Suspension::Bistable { well_m, barrier_j } = *s {
            c.positive(&format!("{P}.well_m"), well_m)?;
            c.positive(&format!("{P}.barrier_j"), barrier_j)?;
            for (side, stop) in self.stops.present() {
                if stop.gap_m <= well_m {
                    return Err(c.err(
                        &format!("{}.gap_m", self.stop_path(side)),
                        stop.gap_m,
                        &format!(
                            "> {P}.well_m = {well_m:e} (the well lies at or beyond the stop; a \
                             device held on its stops is written as form `polynomial`)"
                        ),
                    ));
                }
            }
        }
        let (n, lead) = poly.leading();
        for side in Side::BOTH {
            if poly.confines(side) {
                continue;
            }
            let stop = self.stops.side(side);
            let confined = match stop.map(|s| stop_growth(&s.law)) {
                None => false,
                Some(None) => true,
                Some(Some((power, k))) => power > n as f64 || (power == n as f64 && k > lead.abs()),
            };
            if !confined {
                let name = if side == Side::Upper {
                    "upper"
                } else {
                    "lower"
                };
                let field = format!("{P}.{}", COEFFICIENT_KEYS[n.max(1) - 1]);
                return Err(c.err(
                    &field,
                    lead,
                    &format!(
                        "a leading term that confines the mass on the {name} side (odd order \
                         with a positive coefficient), or a stop on that side that does: a \
                         rigid one, or a compliant one whose force grows faster than x^{n} (or \
                         as fast and stiffer)"
                    ),
                ));
            }
        }
        let k = self.mechanics.stiffness_n_per_m;
        if !(k.is_finite() && k > 0.0) {
            return Err(c.err(
                &format!("{P}.form"),
                k,
                "a suspension with a stable equilibrium (a well) between or on its stops",
            ));
        }
        Ok(())
    }
}
