//! The uncertain inputs of the sensitivity study and the multi-claim calibration: which device
//! parameters (and the drive's scale) may differ from the published values, and by how much
//! (`data/sensitivity.toml`, each range justified there). Each input is a [`ParamRange`] of a
//! device parameter by its dotted path ([`crate::device::ACCEL_SCALE_PATH`] for the drive's
//! scale) with the short name the study's tables use ([`Factor`]).
//!
//! A point of the unit cube (one coordinate per factor, in the file's order) maps to a
//! [`Variant`]: a validated device and the factor by which the stated acceleration is scaled.

use serde::Deserialize;

use crate::device::{at_unit, own_value, Device, ParamError, ParamRange, Spacing};

/// The ranges file compiled into the crate.
pub const SENSITIVITY_TOML: &str = include_str!("../../../data/sensitivity.toml");

/// An uncertain input: a parameter's range and its short name in the study's tables.
#[derive(Debug, Clone, PartialEq)]
pub struct Factor {
    /// Short name, e.g. `endstop_gap`.
    pub name: String,
    /// The parameter and its range.
    pub range: ParamRange,
}

/// Why the ranges file or a point could not be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RangesError {
    /// Not valid TOML for the schema (unknown key, missing key, wrong type).
    #[error("data/sensitivity.toml: {0}")]
    Parse(String),
    /// A range is malformed; `field` is the table and the parameter's path.
    #[error("data/sensitivity.toml: `{field}`: {why}")]
    Range {
        /// Table and dotted path, e.g. `prototype1.stops.both.gap_m`.
        field: String,
        /// What is wrong.
        why: String,
    },
    /// A point has the wrong length or a coordinate outside [0, 1].
    #[error("point {point:?} is not in the unit cube of {factors} factors")]
    Point {
        /// The point.
        point: Vec<f64>,
        /// How many factors there are.
        factors: usize,
    },
    /// The device at a point fails validation.
    #[error(transparent)]
    Device(#[from] ParamError),
    /// The published value of a factor lies outside its range (no point of the cube is the
    /// published set).
    #[error("data/sensitivity.toml: the published {factor} ({value}) lies outside its range")]
    PublishedOutside {
        /// The factor's name.
        factor: String,
        /// The published value.
        value: f64,
    },
}

/// One factor as written in the file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFactor {
    /// Short name for the tables.
    name: String,
    /// Dotted path of the parameter.
    path: String,
    /// A factor on the device's own value.
    relative: Option<[f64; 2]>,
    /// Absolute bounds in SI units.
    absolute: Option<[f64; 2]>,
    /// A yes/no switch: its two settings.
    switch: Option<[bool; 2]>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFile {
    prototype1: Vec<RawFactor>,
    prototype2: Vec<RawFactor>,
}

/// The factors of one prototype, in the order of the unit-cube coordinates.
#[derive(Debug, Clone, PartialEq)]
pub struct Ranges {
    /// The factors.
    pub factors: Vec<Factor>,
}

/// The ranges of both prototypes (the same factors, in the same order).
#[derive(Debug, Clone, PartialEq)]
pub struct RangesFile {
    /// Prototype 1.
    pub prototype1: Ranges,
    /// Prototype 2.
    pub prototype2: Ranges,
}

/// A device with every factor set, and the drive's scale.
#[derive(Debug, Clone, PartialEq)]
pub struct Variant {
    /// The device (validated).
    pub device: Device,
    /// True over stated acceleration.
    pub accel_scale: f64,
}

impl RangesFile {
    /// The bundled file, parsed and checked.
    pub fn bundled() -> Result<Self, RangesError> {
        Self::parse(SENSITIVITY_TOML)
    }

    /// Parses and checks a ranges file: each factor one of `relative = [lo, hi]`,
    /// `absolute = [lo, hi]` or `switch = [a, b]`, no path twice, and both prototypes with the
    /// same factor names in the same order (the study's tables share their columns).
    pub fn parse(text: &str) -> Result<Self, RangesError> {
        let file: RawFile = toml::from_str(text).map_err(|e| RangesError::Parse(e.to_string()))?;
        let file = RangesFile {
            prototype1: Ranges::of_raw("prototype1", &file.prototype1)?,
            prototype2: Ranges::of_raw("prototype2", &file.prototype2)?,
        };
        if file.prototype1.names() != file.prototype2.names() {
            return Err(RangesError::Range {
                field: "prototype2".into(),
                why: format!(
                    "must name the factors of prototype1 in the same order ({})",
                    file.prototype1.names().join(", ")
                ),
            });
        }
        Ok(file)
    }
}

impl Ranges {
    fn of_raw(table: &str, raw: &[RawFactor]) -> Result<Self, RangesError> {
        let mut factors: Vec<Factor> = Vec::new();
        for f in raw {
            let field = format!("{table}.{}", f.path);
            let err = |why: String| RangesError::Range {
                field: field.clone(),
                why,
            };
            if factors
                .iter()
                .any(|g| g.range.path == f.path || g.name == f.name)
            {
                return Err(err(format!("`{}` or its path is given twice", f.name)));
            }
            let range = match (f.relative, f.absolute, f.switch) {
                (Some([lo, hi]), None, None) => {
                    ParamRange::relative(&f.path, lo, hi, Spacing::Linear)
                }
                (None, Some([lo, hi]), None) => ParamRange::new(&f.path, lo, hi, Spacing::Linear),
                (None, None, Some([a, b])) => {
                    let setting = |x: bool| f64::from(u8::from(x));
                    ParamRange::new(&f.path, setting(a), setting(b), Spacing::Switch)
                }
                _ => {
                    return Err(err(
                        "give exactly one of `relative = [lo, hi]`, `absolute = [lo, hi]` or \
                         `switch = [a, b]`"
                            .into(),
                    ))
                }
            }
            .map_err(|e| err(e.to_string()))?;
            factors.push(Factor {
                name: f.name.clone(),
                range,
            });
        }
        if factors.is_empty() {
            return Err(RangesError::Range {
                field: table.into(),
                why: "lists no factor".into(),
            });
        }
        Ok(Ranges { factors })
    }

    /// The factors' names, in order.
    pub fn names(&self) -> Vec<&str> {
        self.factors.iter().map(|f| f.name.as_str()).collect()
    }

    /// How many factors (the dimension of the unit cube).
    pub fn len(&self) -> usize {
        self.factors.len()
    }

    /// True without factors (never, for a parsed file).
    pub fn is_empty(&self) -> bool {
        self.factors.is_empty()
    }

    /// The factors' ranges, in order.
    pub fn ranges(&self) -> Vec<ParamRange> {
        self.factors.iter().map(|f| f.range.clone()).collect()
    }

    /// The coordinates of the switches (a history match keeps them at the ends).
    pub fn switches(&self) -> Vec<usize> {
        (0..self.len())
            .filter(|&i| self.factors[i].range.spacing == Spacing::Switch)
            .collect()
    }

    /// The point of the unit cube whose variant is `base` itself (the published set): for a
    /// range, where the device's own value lies in it (the factor 1 of a relative range); for
    /// a switch, the middle of the half that selects the device's own setting. Its variant
    /// equals `base` to rounding (a relative factor `lo + u (hi - lo)` is 1 to within 1 ulp).
    pub fn published_point(&self, base: &Device) -> Result<Vec<f64>, RangesError> {
        self.factors
            .iter()
            .map(|f| {
                let own = own_value(base, &f.range.path)?;
                f.range
                    .unit_of_own(own)
                    .ok_or_else(|| RangesError::PublishedOutside {
                        factor: f.name.clone(),
                        value: own,
                    })
            })
            .collect()
    }

    /// The variant of `base` at a point of the unit cube (one coordinate per factor, in order).
    pub fn variant(&self, base: &Device, point: &[f64]) -> Result<Variant, RangesError> {
        if point.len() != self.len() || point.iter().any(|u| !(0.0..=1.0).contains(u)) {
            return Err(RangesError::Point {
                point: point.to_vec(),
                factors: self.len(),
            });
        }
        let (device, accel_scale) = at_unit(base, &self.ranges(), point)?;
        Ok(Variant {
            device,
            accel_scale,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::paper::setups::{comb, endstop, hertz_stop, with_stops};

    fn prototype(text: &str) -> Device {
        Device::from_toml_str(text, "test").unwrap()
    }

    fn value(r: &Ranges, v: &Variant, name: &str) -> f64 {
        let f = r.factors.iter().find(|f| f.name == name).unwrap();
        own_value(&v.device, &f.range.path).unwrap()
    }

    #[test]
    fn the_bundled_ranges_load_and_their_corners_are_valid_devices() {
        let file = RangesFile::bundled().unwrap();
        let p1 = prototype(include_str!("../../../data/prototype1.toml"));
        let p2 = prototype(include_str!("../../../data/prototype2.toml"));
        for (ranges, dev) in [(&file.prototype1, &p1), (&file.prototype2, &p2)] {
            assert_eq!(ranges.len(), 8);
            for corner in [0.0, 1.0] {
                let v = ranges.variant(dev, &vec![corner; ranges.len()]).unwrap();
                assert!(v.accel_scale > 0.0);
            }
        }
        assert_eq!(file.prototype1.switches(), [7]);
    }

    #[test]
    fn the_published_point_is_the_published_set() {
        // Tolerance: a relative factor lo + u (hi - lo) with u = (1 - lo) / (hi - lo) is 1 to
        // a few ulps, so each value is its own to 1e-14 relative.
        let file = RangesFile::bundled().unwrap();
        let p1 = prototype(include_str!("../../../data/prototype1.toml"));
        let p2 = prototype(include_str!("../../../data/prototype2.toml"));
        for (ranges, dev) in [(&file.prototype1, &p1), (&file.prototype2, &p2)] {
            let u = ranges.published_point(dev).unwrap();
            let v = ranges.variant(dev, &u).unwrap();
            for f in &ranges.factors {
                let a = own_value(&v.device, &f.range.path).unwrap();
                let b = own_value(dev, &f.range.path).unwrap();
                assert!((a - b).abs() <= 1e-14 * b.abs(), "{}: {a} vs {b}", f.name);
            }
            assert!((v.accel_scale - 1.0).abs() < 1e-14);
        }
        // A device whose b_im lies outside the absolute range has no published point.
        let wild = with_stops(&p1, |s| s.damping_n_s_per_m = 50.0);
        assert!(matches!(
            file.prototype1.published_point(&wild),
            Err(RangesError::PublishedOutside { factor, .. }) if factor == "impact_damping"
        ));
    }

    #[test]
    fn a_point_sets_each_factor_inside_its_range() {
        let file = RangesFile::bundled().unwrap();
        let r = &file.prototype1;
        let p1 = prototype(include_str!("../../../data/prototype1.toml"));
        let v = r
            .variant(&p1, &[0.5, 0.0, 1.0, 0.5, 0.15, 1.0, 0.0, 0.9])
            .unwrap();
        // Midpoint of a relative [0.8, 1.2] range is the published value itself: exact
        // arithmetic up to one rounding of 7e-6 * 1.0.
        assert!((endstop(&v.device).gap_m - 7e-6).abs() < 1e-18);
        assert!((v.device.mechanics.damping_n_s_per_m - 0.7 * 3.75e-3).abs() < 1e-15);
        assert!((v.device.mechanics.stiffness_n_per_m - 1.05 * 166.5).abs() < 1e-12);
        assert_eq!(comb(&v.device).cp_f, value(r, &v, "parasitic_capacitance"));
        assert!((endstop(&v.device).damping_n_s_per_m - 1.5).abs() < 1e-12);
        assert_eq!(hertz_stop(&v.device).youngs_modulus_pa, 190e9);
        assert_eq!(v.accel_scale, 0.8);
        assert!(endstop(&v.device).tension_free);
    }

    #[test]
    fn bad_ranges_and_points_are_named_errors() {
        let good = SENSITIVITY_TOML;
        let reversed = good.replacen("relative = [0.8, 1.2]", "relative = [1.2, 0.8]", 1);
        assert!(matches!(
            RangesFile::parse(&reversed),
            Err(RangesError::Range { field, .. }) if field == "prototype1.stops.both.gap_m"
        ));
        let both = good.replacen(
            "absolute = [0.0, 10.0]",
            "absolute = [0.0, 10.0]\nrelative = [1.0, 2.0]",
            1,
        );
        assert!(matches!(
            RangesFile::parse(&both),
            Err(RangesError::Range { field, .. })
                if field == "prototype1.stops.both.damping_n_s_per_m"
        ));
        let unknown = good.replacen(
            "name = \"endstop_gap\"",
            "name = \"endstop_gap\"\nmass = 1",
            1,
        );
        assert!(
            matches!(RangesFile::parse(&unknown), Err(RangesError::Parse(m)) if m.contains("mass"))
        );
        let twice = good.replacen(
            "path = \"mechanics.stiffness_n_per_m\"",
            "path = \"mechanics.damping_n_s_per_m\"",
            1,
        );
        assert!(matches!(
            RangesFile::parse(&twice),
            Err(RangesError::Range { field, .. }) if field == "prototype1.mechanics.damping_n_s_per_m"
        ));
        let file = RangesFile::bundled().unwrap();
        let p1 = prototype(include_str!("../../../data/prototype1.toml"));
        assert!(matches!(
            file.prototype1.variant(&p1, &[0.5; 7]),
            Err(RangesError::Point { .. })
        ));
        assert!(matches!(
            file.prototype1.variant(&p1, &[1.5; 8]),
            Err(RangesError::Point { .. })
        ));
        // A path the device does not have is named when a variant is made.
        let typo = good.replacen("transducer.cp_f", "transducer.cp_farad", 1);
        let typo = RangesFile::parse(&typo).unwrap();
        let e = typo.prototype1.variant(&p1, &[0.5; 8]).unwrap_err();
        assert!(e.to_string().contains("transducer.cp_farad"), "{e}");
    }
}
