//! The end-stops of a device: each side on its own, absent or a gap and a contact law.
//!
//! A stop at distance `gap_m` from rest on the upper (`x > 0`) or lower (`x < 0`) side touches
//! the proof mass when its penetration `delta = |x| - gap` is positive (eq 2). Its law is one of
//!
//! | `law` | force for `delta > 0` | keys |
//! |---|---|---|
//! | `hertz_line` | Hertz line contact of a half-cylinder on a flat (eq 6), or with `linear_fit = true` its linear fit `k = c pi E t / (1 - nu^2)` (eq 19) | `contact_length_m`, `bump_radius_m`, `youngs_modulus_pa`, `poisson_ratio`, `linear_fit`, `linear_coefficient` |
//! | `linear` | `k delta` | `stiffness_n_per_m` |
//! | `hertz_point` | `K delta^(3/2)` (sphere on a flat), `K` given or `(4/3) E* sqrt(R)` with `E* = E / (2 (1 - nu^2))` for two bodies of one material | `stiffness_n_per_m1p5`, or `sphere_radius_m`, `youngs_modulus_pa`, `poisson_ratio` |
//! | `hunt_crossley` | `K delta^n (1 + alpha d(delta)/dt)`, never tensile | `stiffness_n_per_m_pow_n`, `exponent`, `damping_s_per_m` |
//! | `restitution` | an instantaneous impact, `v+ = -e v-` (Newton's law) | `coefficient` |
//!
//! The first three take the paper's viscous end-stop damper `b_im d(delta)/dt` of eq 1
//! (`damping_n_s_per_m`, default 0) and its tension-free reading (`tension_free`, default
//! false: the bracket of eq 1 is clipped at zero so that the damper never pulls).
//!
//! In a file the two sides are tables `[stops.upper]` and `[stops.lower]`; `[stops.both]`
//! writes one stop for both sides (a symmetric device). A side without a table has no stop.

use serde::{Deserialize, Serialize};

use super::{Checker, ParamError};
use crate::laws::contact::Side;

/// The paper's coefficient of eq 19 (k_im = 0.058 pi E t / (1 - nu^2)).
pub const EQ19_COEFFICIENT: f64 = 0.058;

/// The Hertz line contact of eq 6 (a half-cylinder of length `t` and radius `R` on a flat),
/// or its linear fit of eq 19.
#[derive(Debug, Clone, PartialEq)]
pub struct HertzLineStop {
    /// Contact length t (m): the device layer thickness for an etched bump.
    pub contact_length_m: f64,
    /// Bump radius R (m).
    pub bump_radius_m: f64,
    /// Young's modulus E (Pa).
    pub youngs_modulus_pa: f64,
    /// Poisson's ratio nu.
    pub poisson_ratio: f64,
    /// Use the linear fit of eq 19 instead of eq 6.
    pub linear_fit: bool,
    /// The coefficient c of eq 19.
    pub linear_coefficient: f64,
}

impl HertzLineStop {
    /// The stiffness of eq 19, k = c pi E t / (1 - nu^2) (N/m).
    pub fn linear_stiffness_n_per_m(&self) -> f64 {
        self.linear_coefficient
            * std::f64::consts::PI
            * self.youngs_modulus_pa
            * self.contact_length_m
            / (1.0 - self.poisson_ratio * self.poisson_ratio)
    }
}

/// How `K` of a Hertz point contact is given.
#[derive(Debug, Clone, PartialEq)]
pub enum HertzPointStiffness {
    /// `K` directly (N/m^1.5).
    Given(f64),
    /// A sphere of radius R on a flat of the same material (E, nu).
    Sphere {
        /// Sphere radius R (m).
        radius_m: f64,
        /// Young's modulus E (Pa).
        youngs_modulus_pa: f64,
        /// Poisson's ratio nu.
        poisson_ratio: f64,
    },
}

impl HertzPointStiffness {
    /// `K` (N/m^1.5): given, or `(4/3) E* sqrt(R)` with `E* = E / (2 (1 - nu^2))`.
    pub fn value(&self) -> f64 {
        match *self {
            HertzPointStiffness::Given(k) => k,
            HertzPointStiffness::Sphere {
                radius_m,
                youngs_modulus_pa,
                poisson_ratio,
            } => {
                let e_star = youngs_modulus_pa / (2.0 * (1.0 - poisson_ratio * poisson_ratio));
                4.0 / 3.0 * e_star * radius_m.sqrt()
            }
        }
    }
}

/// The contact law of one stop (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub enum StopLaw {
    /// Hertz line contact (eq 6) or its linear fit (eq 19).
    HertzLine(HertzLineStop),
    /// A linear spring.
    Linear {
        /// Stiffness k (N/m).
        stiffness_n_per_m: f64,
    },
    /// Hertz point contact, `K delta^(3/2)`.
    HertzPoint(HertzPointStiffness),
    /// Hunt-Crossley, `K delta^n (1 + alpha d(delta)/dt)`, clipped at zero.
    HuntCrossley {
        /// K (N/m^n).
        stiffness_n_per_m_pow_n: f64,
        /// The exponent n.
        exponent: f64,
        /// alpha (s/m).
        damping_s_per_m: f64,
    },
    /// An instantaneous impact with coefficient of restitution e.
    Restitution {
        /// e in [0, 1].
        coefficient: f64,
    },
}

impl StopLaw {
    /// The `law` key of this law.
    pub fn key(&self) -> &'static str {
        match self {
            StopLaw::HertzLine(_) => "hertz_line",
            StopLaw::Linear { .. } => "linear",
            StopLaw::HertzPoint(_) => "hertz_point",
            StopLaw::HuntCrossley { .. } => "hunt_crossley",
            StopLaw::Restitution { .. } => "restitution",
        }
    }

    /// True for the laws that take the viscous damper and the tension-free switch of eq 1.
    pub fn takes_viscous_damper(&self) -> bool {
        matches!(
            self,
            StopLaw::HertzLine(_) | StopLaw::Linear { .. } | StopLaw::HertzPoint(_)
        )
    }
}

/// One end-stop.
#[derive(Debug, Clone, PartialEq)]
pub struct Stop {
    /// Distance from rest to the stop (m).
    pub gap_m: f64,
    /// Contact law.
    pub law: StopLaw,
    /// The viscous damper b_im of eq 1 (N s/m); zero for the laws that do not take it.
    pub damping_n_s_per_m: f64,
    /// Clip the bracket of eq 1 at zero (the damper never pulls).
    pub tension_free: bool,
}

/// The two sides' stops.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Stops {
    /// The stop at `x = +gap`, if any.
    pub upper: Option<Stop>,
    /// The stop at `x = -gap`, if any.
    pub lower: Option<Stop>,
}

impl Stops {
    /// The stop on a side.
    pub fn side(&self, side: Side) -> Option<&Stop> {
        match side {
            Side::Upper => self.upper.as_ref(),
            Side::Lower => self.lower.as_ref(),
        }
    }

    /// The present stops with their sides, upper first.
    pub fn present(&self) -> impl Iterator<Item = (Side, &Stop)> {
        [
            (Side::Upper, self.upper.as_ref()),
            (Side::Lower, self.lower.as_ref()),
        ]
        .into_iter()
        .filter_map(|(s, st)| st.map(|st| (s, st)))
    }

    /// Applies `f` to every present stop.
    pub fn for_each_mut(&mut self, mut f: impl FnMut(&mut Stop)) {
        for s in [self.upper.as_mut(), self.lower.as_mut()]
            .into_iter()
            .flatten()
        {
            f(s);
        }
    }

    /// The one stop of a symmetric pair (both sides present and equal).
    pub fn symmetric(&self) -> Option<&Stop> {
        match (&self.upper, &self.lower) {
            (Some(a), Some(b)) if a == b => Some(a),
            _ => None,
        }
    }

    /// The smallest gap of the present stops (m), if any.
    pub fn smallest_gap_m(&self) -> Option<f64> {
        self.present().map(|(_, s)| s.gap_m).reduce(f64::min)
    }
}

/// The law keys of a file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
enum LawKey {
    HertzLine,
    Linear,
    HertzPoint,
    HuntCrossley,
    Restitution,
}

/// A stop as written in a file: every key of every law, checked against the law on load.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawStop {
    gap_m: Option<f64>,
    law: Option<LawKey>,
    #[serde(skip_serializing_if = "Option::is_none")]
    damping_n_s_per_m: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    tension_free: Option<bool>,
    #[serde(skip_serializing_if = "Option::is_none")]
    contact_length_m: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    bump_radius_m: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    youngs_modulus_pa: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    poisson_ratio: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    linear_fit: Option<bool>,
    #[serde(skip_serializing_if = "Option::is_none")]
    linear_coefficient: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    stiffness_n_per_m: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    stiffness_n_per_m1p5: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    sphere_radius_m: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    stiffness_n_per_m_pow_n: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    exponent: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    damping_s_per_m: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    coefficient: Option<f64>,
}

/// The `[stops]` table of a file.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawStops {
    #[serde(skip_serializing_if = "Option::is_none")]
    both: Option<RawStop>,
    #[serde(skip_serializing_if = "Option::is_none")]
    upper: Option<RawStop>,
    #[serde(skip_serializing_if = "Option::is_none")]
    lower: Option<RawStop>,
}

impl RawStops {
    /// The stops of a file, every key checked against its law (field paths `stops.<side>.<key>`).
    pub(super) fn parse(&self, c: &Checker) -> Result<Stops, ParamError> {
        if let Some(both) = &self.both {
            if self.upper.is_some() || self.lower.is_some() {
                return Err(c.message(
                    "stops",
                    "`stops.both` stands for both sides: write either it or `stops.upper` / \
                     `stops.lower`",
                ));
            }
            let s = both.parse(c, "stops.both")?;
            return Ok(Stops {
                upper: Some(s.clone()),
                lower: Some(s),
            });
        }
        Ok(Stops {
            upper: self
                .upper
                .as_ref()
                .map(|s| s.parse(c, "stops.upper"))
                .transpose()?,
            lower: self
                .lower
                .as_ref()
                .map(|s| s.parse(c, "stops.lower"))
                .transpose()?,
        })
    }

    /// The file form with each side written on its own (no `both`).
    pub(super) fn expanded(stops: &Stops) -> Self {
        Self {
            both: None,
            upper: stops.upper.as_ref().map(RawStop::of),
            lower: stops.lower.as_ref().map(RawStop::of),
        }
    }

    /// The file form of stops (`both` for a symmetric pair).
    pub(super) fn of(stops: &Stops) -> Self {
        if let Some(s) = stops.symmetric() {
            return Self {
                both: Some(RawStop::of(s)),
                ..Self::default()
            };
        }
        Self {
            both: None,
            upper: stops.upper.as_ref().map(RawStop::of),
            lower: stops.lower.as_ref().map(RawStop::of),
        }
    }
}

/// The largest gap a stop may have (m).
pub const MAX_GAP_M: f64 = 1e3;

impl RawStop {
    pub(super) fn parse(&self, c: &Checker, path: &str) -> Result<Stop, ParamError> {
        let f = |key: &str| format!("{path}.{key}");
        let gap_m = self
            .gap_m
            .ok_or_else(|| c.missing(&f("gap_m"), "the distance from rest to the stop (m)"))?;
        // A bound far above any harvester (and the unit gaps of nondimensional models) that
        // keeps the integrator's scales (the gap times the natural frequency) finite.
        c.within_closed(
            &f("gap_m"),
            gap_m,
            f64::MIN_POSITIVE,
            MAX_GAP_M,
            "finite, > 0 and at most 1000 m (a stop farther away is no stop: remove it)",
        )?;
        let law_key = self.law.ok_or_else(|| {
            c.missing(
                &f("law"),
                "one of hertz_line, linear, hertz_point, hunt_crossley, restitution",
            )
        })?;
        // The keys this law reads; any other key present is an error naming the law.
        let allowed: &[&str] = match law_key {
            LawKey::HertzLine => &[
                "contact_length_m",
                "bump_radius_m",
                "youngs_modulus_pa",
                "poisson_ratio",
                "linear_fit",
                "linear_coefficient",
                "damping_n_s_per_m",
                "tension_free",
            ],
            LawKey::Linear => &["stiffness_n_per_m", "damping_n_s_per_m", "tension_free"],
            LawKey::HertzPoint => &[
                "stiffness_n_per_m1p5",
                "sphere_radius_m",
                "youngs_modulus_pa",
                "poisson_ratio",
                "damping_n_s_per_m",
                "tension_free",
            ],
            LawKey::HuntCrossley => &["stiffness_n_per_m_pow_n", "exponent", "damping_s_per_m"],
            LawKey::Restitution => &["coefficient"],
        };
        let law_name = serde_name(law_key);
        for key in self.present_keys() {
            if !allowed.contains(&key) {
                return Err(c.message(
                    &f(key),
                    &format!(
                        "law `{law_name}` does not take `{key}` (its keys: {})",
                        allowed.join(", ")
                    ),
                ));
            }
        }
        let need = |key: &str, v: Option<f64>| {
            v.ok_or_else(|| c.missing(&f(key), &format!("law `{law_name}` needs it")))
        };
        let law = match law_key {
            LawKey::HertzLine => {
                let h = HertzLineStop {
                    contact_length_m: need("contact_length_m", self.contact_length_m)?,
                    bump_radius_m: need("bump_radius_m", self.bump_radius_m)?,
                    youngs_modulus_pa: need("youngs_modulus_pa", self.youngs_modulus_pa)?,
                    poisson_ratio: need("poisson_ratio", self.poisson_ratio)?,
                    linear_fit: self.linear_fit.unwrap_or(false),
                    linear_coefficient: self.linear_coefficient.unwrap_or(EQ19_COEFFICIENT),
                };
                c.positive(&f("contact_length_m"), h.contact_length_m)?;
                c.positive(&f("bump_radius_m"), h.bump_radius_m)?;
                check_material(c, path, h.youngs_modulus_pa, h.poisson_ratio)?;
                c.positive(&f("linear_coefficient"), h.linear_coefficient)?;
                StopLaw::HertzLine(h)
            }
            LawKey::Linear => {
                let k = need("stiffness_n_per_m", self.stiffness_n_per_m)?;
                c.positive(&f("stiffness_n_per_m"), k)?;
                StopLaw::Linear {
                    stiffness_n_per_m: k,
                }
            }
            LawKey::HertzPoint => {
                let sphere = [
                    self.sphere_radius_m,
                    self.youngs_modulus_pa,
                    self.poisson_ratio,
                ];
                match (self.stiffness_n_per_m1p5, sphere) {
                    (Some(k), [None, None, None]) => {
                        c.positive(&f("stiffness_n_per_m1p5"), k)?;
                        StopLaw::HertzPoint(HertzPointStiffness::Given(k))
                    }
                    (None, [Some(r), Some(e), Some(nu)]) => {
                        c.positive(&f("sphere_radius_m"), r)?;
                        check_material(c, path, e, nu)?;
                        StopLaw::HertzPoint(HertzPointStiffness::Sphere {
                            radius_m: r,
                            youngs_modulus_pa: e,
                            poisson_ratio: nu,
                        })
                    }
                    _ => {
                        return Err(c.message(
                            &f("stiffness_n_per_m1p5"),
                            "law `hertz_point` needs either `stiffness_n_per_m1p5` or all of \
                             `sphere_radius_m`, `youngs_modulus_pa` and `poisson_ratio`",
                        ))
                    }
                }
            }
            LawKey::HuntCrossley => {
                let k = need("stiffness_n_per_m_pow_n", self.stiffness_n_per_m_pow_n)?;
                let n = need("exponent", self.exponent)?;
                let alpha = need("damping_s_per_m", self.damping_s_per_m)?;
                c.positive(&f("stiffness_n_per_m_pow_n"), k)?;
                c.within_closed(&f("exponent"), n, 1.0, 3.0, "between 1 and 3")?;
                c.non_negative(&f("damping_s_per_m"), alpha)?;
                StopLaw::HuntCrossley {
                    stiffness_n_per_m_pow_n: k,
                    exponent: n,
                    damping_s_per_m: alpha,
                }
            }
            LawKey::Restitution => {
                let e = need("coefficient", self.coefficient)?;
                c.within_closed(&f("coefficient"), e, 0.0, 1.0, "between 0 and 1")?;
                StopLaw::Restitution { coefficient: e }
            }
        };
        let damping_n_s_per_m = self.damping_n_s_per_m.unwrap_or(0.0);
        c.non_negative(&f("damping_n_s_per_m"), damping_n_s_per_m)?;
        Ok(Stop {
            gap_m,
            law,
            damping_n_s_per_m,
            tension_free: self.tension_free.unwrap_or(false),
        })
    }

    fn present_keys(&self) -> Vec<&'static str> {
        let mut keys = Vec::new();
        let mut add = |present: bool, key| {
            if present {
                keys.push(key)
            }
        };
        add(self.damping_n_s_per_m.is_some(), "damping_n_s_per_m");
        add(self.tension_free.is_some(), "tension_free");
        add(self.contact_length_m.is_some(), "contact_length_m");
        add(self.bump_radius_m.is_some(), "bump_radius_m");
        add(self.youngs_modulus_pa.is_some(), "youngs_modulus_pa");
        add(self.poisson_ratio.is_some(), "poisson_ratio");
        add(self.linear_fit.is_some(), "linear_fit");
        add(self.linear_coefficient.is_some(), "linear_coefficient");
        add(self.stiffness_n_per_m.is_some(), "stiffness_n_per_m");
        add(self.stiffness_n_per_m1p5.is_some(), "stiffness_n_per_m1p5");
        add(self.sphere_radius_m.is_some(), "sphere_radius_m");
        add(
            self.stiffness_n_per_m_pow_n.is_some(),
            "stiffness_n_per_m_pow_n",
        );
        add(self.exponent.is_some(), "exponent");
        add(self.damping_s_per_m.is_some(), "damping_s_per_m");
        add(self.coefficient.is_some(), "coefficient");
        keys
    }

    pub(super) fn of(s: &Stop) -> Self {
        let mut r = RawStop {
            gap_m: Some(s.gap_m),
            ..Self::default()
        };
        if s.law.takes_viscous_damper() {
            r.damping_n_s_per_m = Some(s.damping_n_s_per_m);
            r.tension_free = Some(s.tension_free);
        }
        match &s.law {
            StopLaw::HertzLine(h) => {
                r.law = Some(LawKey::HertzLine);
                r.contact_length_m = Some(h.contact_length_m);
                r.bump_radius_m = Some(h.bump_radius_m);
                r.youngs_modulus_pa = Some(h.youngs_modulus_pa);
                r.poisson_ratio = Some(h.poisson_ratio);
                r.linear_fit = Some(h.linear_fit);
                r.linear_coefficient = Some(h.linear_coefficient);
            }
            StopLaw::Linear { stiffness_n_per_m } => {
                r.law = Some(LawKey::Linear);
                r.stiffness_n_per_m = Some(*stiffness_n_per_m);
            }
            StopLaw::HertzPoint(k) => {
                r.law = Some(LawKey::HertzPoint);
                match *k {
                    HertzPointStiffness::Given(k) => r.stiffness_n_per_m1p5 = Some(k),
                    HertzPointStiffness::Sphere {
                        radius_m,
                        youngs_modulus_pa,
                        poisson_ratio,
                    } => {
                        r.sphere_radius_m = Some(radius_m);
                        r.youngs_modulus_pa = Some(youngs_modulus_pa);
                        r.poisson_ratio = Some(poisson_ratio);
                    }
                }
            }
            StopLaw::HuntCrossley {
                stiffness_n_per_m_pow_n,
                exponent,
                damping_s_per_m,
            } => {
                r.law = Some(LawKey::HuntCrossley);
                r.stiffness_n_per_m_pow_n = Some(*stiffness_n_per_m_pow_n);
                r.exponent = Some(*exponent);
                r.damping_s_per_m = Some(*damping_s_per_m);
            }
            StopLaw::Restitution { coefficient } => {
                r.law = Some(LawKey::Restitution);
                r.coefficient = Some(*coefficient);
            }
        }
        r
    }
}

fn serde_name(k: LawKey) -> &'static str {
    match k {
        LawKey::HertzLine => "hertz_line",
        LawKey::Linear => "linear",
        LawKey::HertzPoint => "hertz_point",
        LawKey::HuntCrossley => "hunt_crossley",
        LawKey::Restitution => "restitution",
    }
}

fn check_material(c: &Checker, path: &str, e: f64, nu: f64) -> Result<(), ParamError> {
    c.within(
        &format!("{path}.youngs_modulus_pa"),
        e,
        1e6,
        1e13,
        "between 1e6 and 1e13 Pa",
    )?;
    c.within(
        &format!("{path}.poisson_ratio"),
        nu,
        -1.0,
        0.5,
        "between -1 and 0.5 (exclusive)",
    )
}
