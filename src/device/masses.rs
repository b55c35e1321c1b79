//! Devices of several masses: masses joined by springs and dampers to each other and to the
//! frame, stops from any mass to the frame and between two masses, and one transducer on one
//! mass.
//!
//! A file of this form has a `[[masses]]` array in place of `[mechanics]`, and `[[stops]]` is
//! an array of stops each naming its masses; a file without `[[masses]]` is a one-mass file
//! and reads as before. Masses are numbered from 0 in the order they are written.
//!
//! ```toml
//! name = "upconverter"
//! params = "example"
//! description = "..."
//! transducer_mass = 1          # the mass the transducer acts on (0 when absent)
//! drive_mass = 1               # optional: the drive is a force m_1 a(t) on mass 1 alone
//!
//! [[masses]]
//! name = "driver"
//! mass_kg = 1e-3
//!
//! [[springs]]                  # one mass: to the frame; two: between them
//! masses = [0]
//! stiffness_n_per_m = 15.8
//! cubic_n_per_m3 = 0.0         # optional: a hardening (> 0) or softening cubic term k3 d^3
//!
//! [[dampers]]
//! masses = [0, 1]
//! damping_n_s_per_m = 1e-3
//!
//! [[stops]]                    # mass 0 meets mass 1 where x0 - x1 = +gap (side upper) or
//! masses = [0, 1]              # -gap (side lower); one mass: where x0 = +gap or -gap
//! side = "upper"
//! gap_m = 1e-3
//! law = "restitution"          # any law of a one-mass file's stop, with its keys
//! coefficient = 0.8
//!
//! [transducer]
//! kind = "piezoelectric"
//! # ...
//! ```
//!
//! Without `drive_mass` the frame's acceleration `a(t)` drives every mass (`m_i a` on mass
//! `i`, displacements relative to the frame). With `drive_mass = j` the frame stands still and
//! the drive is a force `m_j a(t)` on mass `j` alone (a shaker on that mass, or a force-driven
//! reference problem): the same `a(t)` of the studies, applied to one mass.
//!
//! Every index is checked on load (a mass that does not exist, a spring, damper or stop
//! between a mass and itself, a mass connected to nothing), in a [`ParamError`] that names
//! the field (`stops[1].masses`).

use serde::{Deserialize, Serialize};

use super::stops::{RawStop, Stop};
use super::{Checker, ParamError};
use crate::laws::contact::Side;

/// One mass.
#[derive(Debug, Clone, PartialEq)]
pub struct Body {
    /// Its name, which the model's outputs and ledger terms carry.
    pub name: String,
    /// Its mass (kg).
    pub mass_kg: f64,
}

/// A spring or damper from a mass to the frame (`other` none) or between two masses.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Link {
    /// The mass.
    pub mass: usize,
    /// The other mass, if the link is between two.
    pub other: Option<usize>,
    /// The stiffness (N/m) of a spring, the coefficient (N s/m) of a damper.
    pub value: f64,
    /// A spring's cubic stiffness k3 (N/m^3): its force is `value d + k3 d^3` on the
    /// extension `d`; zero for a linear spring and for every damper.
    pub cubic_n_per_m3: f64,
}

/// A stop: mass `mass` meets the frame where `x = side * gap`, or meets mass `other` where
/// `x_mass - x_other = side * gap`.
#[derive(Debug, Clone, PartialEq)]
pub struct MassStop {
    /// The mass.
    pub mass: usize,
    /// The other mass, if the stop is between two.
    pub other: Option<usize>,
    /// Upper (`+gap`) or lower (`-gap`).
    pub side: Side,
    /// The stop and its contact law, as a one-mass file's.
    pub stop: Stop,
}

/// The mechanics of a device of several masses (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Masses {
    /// The masses, in file order.
    pub bodies: Vec<Body>,
    /// The springs.
    pub springs: Vec<Link>,
    /// The dampers.
    pub dampers: Vec<Link>,
    /// The stops.
    pub stops: Vec<MassStop>,
    /// The mass the transducer acts on.
    pub transducer_mass: usize,
    /// The mass a force drive acts on (`m_j a(t)` on it alone, the frame still); `None`: the
    /// frame's acceleration drives every mass.
    pub drive_mass: Option<usize>,
}

/// Most masses a device may have.
pub const MAX_MASSES: usize = 8;

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawBody {
    name: String,
    mass_kg: f64,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSpring {
    masses: Vec<usize>,
    stiffness_n_per_m: f64,
    #[serde(default, skip_serializing_if = "is_zero")]
    cubic_n_per_m3: f64,
}

fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawDamper {
    masses: Vec<usize>,
    damping_n_s_per_m: f64,
}

/// The multi-mass part of a file: the tables a one-mass file does not have.
#[derive(Debug, Clone, Default)]
pub(super) struct RawMasses {
    pub(super) masses: Vec<RawBody>,
    pub(super) springs: Vec<RawSpring>,
    pub(super) dampers: Vec<RawDamper>,
    pub(super) stops: Vec<toml::Table>,
    pub(super) transducer_mass: Option<usize>,
    pub(super) drive_mass: Option<usize>,
}

impl RawMasses {
    /// Takes the multi-mass keys out of a file's table (what is left is the common part).
    pub(super) fn take(table: &mut toml::Table, c: &Checker) -> Result<Self, ParamError> {
        fn array<T: serde::de::DeserializeOwned>(
            table: &mut toml::Table,
            key: &str,
            c: &Checker,
        ) -> Result<Vec<T>, ParamError> {
            match table.remove(key) {
                None => Ok(Vec::new()),
                Some(v) => v
                    .try_into()
                    .map_err(|e: toml::de::Error| ParamError::Parse {
                        source_name: c.source.to_string(),
                        message: format!("`{key}`: {e}"),
                    }),
            }
        }
        let index = |table: &mut toml::Table, key: &str| match table.remove(key) {
            None => Ok(None),
            Some(toml::Value::Integer(i)) if i >= 0 => Ok(Some(i as usize)),
            Some(v) => Err(c.message(key, &format!("must be a mass's index (0, 1, ...), not {v}"))),
        };
        let transducer_mass = index(table, "transducer_mass")?;
        let drive_mass = index(table, "drive_mass")?;
        Ok(Self {
            masses: array(table, "masses", c)?,
            springs: array(table, "springs", c)?,
            dampers: array(table, "dampers", c)?,
            stops: array(table, "stops", c)?,
            transducer_mass,
            drive_mass,
        })
    }

    /// The checked mechanics.
    pub(super) fn parse(&self, c: &Checker) -> Result<Masses, ParamError> {
        let n = self.masses.len();
        if n < 2 {
            return Err(c.message(
                "masses",
                &format!("a file of several masses lists at least two, not {n}"),
            ));
        }
        if n > MAX_MASSES {
            return Err(c.err("masses", n as f64, &format!("<= {MAX_MASSES} masses")));
        }
        let mut bodies = Vec::with_capacity(n);
        for (i, b) in self.masses.iter().enumerate() {
            let f = format!("masses[{i}]");
            c.positive(&format!("{f}.mass_kg"), b.mass_kg)?;
            let ok = |ch: char| ch.is_ascii_alphanumeric() || ch == '_';
            if b.name.is_empty() || !b.name.chars().all(ok) {
                return Err(c.message(
                    &format!("{f}.name"),
                    "must be letters, digits and `_` (it names columns)",
                ));
            }
            if bodies.iter().any(|o: &Body| o.name == b.name) {
                return Err(c.message(&format!("{f}.name"), "two masses have this name"));
            }
            bodies.push(Body {
                name: b.name.clone(),
                mass_kg: b.mass_kg,
            });
        }
        let ends = |field: &str, m: &[usize]| -> Result<(usize, Option<usize>), ParamError> {
            let f = format!("{field}.masses");
            for &i in m {
                if i >= n {
                    return Err(c.err(&f, i as f64, &format!("a mass's index < {n}")));
                }
            }
            match *m {
                [a] => Ok((a, None)),
                [a, b] if a == b => Err(c.message(&f, &format!("joins mass {a} to itself"))),
                [a, b] => Ok((a, Some(b))),
                _ => Err(c.message(&f, "one mass (to the frame) or two (between them)")),
            }
        };
        let mut springs = Vec::new();
        for (i, s) in self.springs.iter().enumerate() {
            let f = format!("springs[{i}]");
            let (mass, other) = ends(&f, &s.masses)?;
            c.positive(&format!("{f}.stiffness_n_per_m"), s.stiffness_n_per_m)?;
            if !s.cubic_n_per_m3.is_finite() {
                return Err(c.message(&format!("{f}.cubic_n_per_m3"), "must be a finite number"));
            }
            springs.push(Link {
                mass,
                other,
                value: s.stiffness_n_per_m,
                cubic_n_per_m3: s.cubic_n_per_m3,
            });
        }
        let mut dampers = Vec::new();
        for (i, d) in self.dampers.iter().enumerate() {
            let f = format!("dampers[{i}]");
            let (mass, other) = ends(&f, &d.masses)?;
            c.non_negative(&format!("{f}.damping_n_s_per_m"), d.damping_n_s_per_m)?;
            dampers.push(Link {
                mass,
                other,
                value: d.damping_n_s_per_m,
                cubic_n_per_m3: 0.0,
            });
        }
        let mut stops = Vec::new();
        for (i, t) in self.stops.iter().enumerate() {
            let f = format!("stops[{i}]");
            let mut t = t.clone();
            let masses: Vec<usize> = match t.remove("masses") {
                Some(v) => v.try_into().map_err(|e: toml::de::Error| {
                    c.message(&format!("{f}.masses"), &format!("a list of indices: {e}"))
                })?,
                None => return Err(c.missing(&format!("{f}.masses"), "the stop's mass or masses")),
            };
            let (mass, other) = ends(&f, &masses)?;
            let side = match t.remove("side") {
                Some(toml::Value::String(s)) if s == "upper" => Side::Upper,
                Some(toml::Value::String(s)) if s == "lower" => Side::Lower,
                Some(v) => {
                    return Err(c.message(
                        &format!("{f}.side"),
                        &format!("`upper` or `lower`, not {v}"),
                    ))
                }
                None => return Err(c.missing(&format!("{f}.side"), "`upper` or `lower`")),
            };
            let raw: RawStop = toml::Value::Table(t)
                .try_into()
                .map_err(|e: toml::de::Error| ParamError::Parse {
                    source_name: c.source.to_string(),
                    message: format!("`{f}`: {e}"),
                })?;
            let stop = raw.parse(c, &f)?;
            c.non_negative(&format!("{f}.damping_n_s_per_m"), stop.damping_n_s_per_m)?;
            stops.push(MassStop {
                mass,
                other,
                side,
                stop,
            });
        }
        let transducer_mass = self.transducer_mass.unwrap_or(0);
        if transducer_mass >= n {
            return Err(c.err(
                "transducer_mass",
                transducer_mass as f64,
                &format!("a mass's index < {n}"),
            ));
        }
        if let Some(j) = self.drive_mass.filter(|&j| j >= n) {
            return Err(c.err("drive_mass", j as f64, &format!("a mass's index < {n}")));
        }
        let m = Masses {
            bodies,
            springs,
            dampers,
            stops,
            transducer_mass,
            drive_mass: self.drive_mass,
        };
        for i in 0..n {
            let touches = |l: &Link| l.mass == i || l.other == Some(i);
            let connected = m.springs.iter().any(touches)
                || m.dampers.iter().any(touches)
                || m.stops.iter().any(|s| s.mass == i || s.other == Some(i));
            if !connected {
                return Err(c.message(
                    &format!("masses[{i}]"),
                    "is connected to nothing (no spring, damper or stop)",
                ));
            }
        }
        Ok(m)
    }

    /// The file form of checked mechanics, as entries of a file's table.
    pub(super) fn write(m: &Masses, table: &mut toml::Table) {
        let ends =
            |l: usize, o: Option<usize>| -> Vec<usize> { std::iter::once(l).chain(o).collect() };
        table.insert(
            "transducer_mass".into(),
            toml::Value::Integer(m.transducer_mass as i64),
        );
        if let Some(j) = m.drive_mass {
            table.insert("drive_mass".into(), toml::Value::Integer(j as i64));
        }
        let bodies: Vec<RawBody> = m
            .bodies
            .iter()
            .map(|b| RawBody {
                name: b.name.clone(),
                mass_kg: b.mass_kg,
            })
            .collect();
        table.insert("masses".into(), value(&bodies));
        let springs: Vec<RawSpring> = m
            .springs
            .iter()
            .map(|l| RawSpring {
                masses: ends(l.mass, l.other),
                stiffness_n_per_m: l.value,
                cubic_n_per_m3: l.cubic_n_per_m3,
            })
            .collect();
        if !springs.is_empty() {
            table.insert("springs".into(), value(&springs));
        }
        let dampers: Vec<RawDamper> = m
            .dampers
            .iter()
            .map(|l| RawDamper {
                masses: ends(l.mass, l.other),
                damping_n_s_per_m: l.value,
            })
            .collect();
        if !dampers.is_empty() {
            table.insert("dampers".into(), value(&dampers));
        }
        let stops: Vec<toml::Value> = m
            .stops
            .iter()
            .map(|s| {
                let mut t = match value(&RawStop::of(&s.stop)) {
                    toml::Value::Table(t) => t,
                    _ => toml::Table::new(),
                };
                let masses: Vec<toml::Value> = ends(s.mass, s.other)
                    .into_iter()
                    .map(|i| toml::Value::Integer(i as i64))
                    .collect();
                t.insert("masses".into(), toml::Value::Array(masses));
                let side = match s.side {
                    Side::Upper => "upper",
                    Side::Lower => "lower",
                };
                t.insert("side".into(), toml::Value::String(side.into()));
                toml::Value::Table(t)
            })
            .collect();
        if !stops.is_empty() {
            table.insert("stops".into(), toml::Value::Array(stops));
        }
    }
}

/// A part of the file form as a TOML value.
fn value<T: Serialize>(v: &T) -> toml::Value {
    toml::Value::try_from(v).expect("the file form's parts serialise")
}

impl Masses {
    /// The total mass (kg).
    pub fn total_mass_kg(&self) -> f64 {
        self.bodies.iter().map(|b| b.mass_kg).sum()
    }

    /// The mass the drive acts on (kg): the total mass under the frame's acceleration, the
    /// driven mass's under a force drive. A white noise of two-sided PSD `Sa` puts the mean
    /// power `M Sa / 2` into the device with this `M`, whatever its springs, dampers and
    /// contacts: each mass driven by `m_i a(t)` has its velocity jump by the acceleration's
    /// impulse, so that `E[m_i a v_i] = m_i Sa / 2`, summed over the driven masses.
    pub fn driven_mass_kg(&self) -> f64 {
        match self.drive_mass {
            Some(j) => self.bodies[j].mass_kg,
            None => self.total_mass_kg(),
        }
    }

    /// The sum of the springs' stiffnesses to the frame (N/m).
    pub fn frame_stiffness_n_per_m(&self) -> f64 {
        self.springs
            .iter()
            .filter(|l| l.other.is_none())
            .map(|l| l.value)
            .sum()
    }

    /// The damping that gives the total mass the slowest ring-up of the masses (N s/m):
    /// `M / max_i (m_i / b_i)`, `b_i` the dampers on mass `i`, so that `2 M / b` is the
    /// longest of the masses' own `2 m_i / b_i`; zero when a mass has no damper.
    pub fn ring_damping_n_s_per_m(&self) -> f64 {
        let slowest = (0..self.bodies.len())
            .map(|i| {
                let b: f64 = self
                    .dampers
                    .iter()
                    .filter(|l| l.mass == i || l.other == Some(i))
                    .map(|l| l.value)
                    .sum();
                self.bodies[i].mass_kg / b
            })
            .fold(0.0, f64::max);
        if slowest.is_finite() {
            self.total_mass_kg() / slowest
        } else {
            0.0
        }
    }

    /// The smallest gap of the stops (m), if any.
    pub fn smallest_gap_m(&self) -> Option<f64> {
        self.stops
            .iter()
            .map(|s| s.stop.gap_m)
            .min_by(|a, b| a.total_cmp(b))
    }
}
