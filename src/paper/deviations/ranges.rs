//! The uncertain inputs of the sensitivity study and the multi-claim calibration: which device
//! parameters (and the drive's scale) may differ from the published values, and by how much
//! (`data/sensitivity.toml`, each range justified there).
//!
//! A point of the unit cube (one coordinate per [`Factor`], in [`Factor::ALL`] order) maps to a
//! [`Variant`]: a validated device and the factor by which the stated acceleration is scaled.

use serde::Deserialize;

use crate::device::{Device, ParamError};
use crate::paper::setups::{comb, comb_mut, endstop, hertz_stop, with_hertz, with_stops};

/// The ranges file compiled into the crate.
pub const SENSITIVITY_TOML: &str = include_str!("../../../data/sensitivity.toml");

/// An uncertain input.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Factor {
    /// End-stop gap xmax (`geometry.endstop_gap_m`).
    EndstopGap,
    /// Mechanical damping b (`mechanics.damping_n_s_per_m`).
    MechanicalDamping,
    /// Suspension stiffness km (`mechanics.stiffness_n_per_m`).
    Stiffness,
    /// Parasitic capacitance Cp (`electrical.cp_f`).
    ParasiticCapacitance,
    /// Impact damping b_im (`endstop.damping_n_s_per_m`).
    ImpactDamping,
    /// Young's modulus of the contact (`material.youngs_modulus_pa`).
    YoungsModulus,
    /// True over stated acceleration.
    AccelScale,
    /// Tension-free contact (`endstop.tension_free`).
    TensionFree,
}

impl Factor {
    /// Every factor, in the order of the unit-cube coordinates.
    pub const ALL: [Factor; 8] = [
        Factor::EndstopGap,
        Factor::MechanicalDamping,
        Factor::Stiffness,
        Factor::ParasiticCapacitance,
        Factor::ImpactDamping,
        Factor::YoungsModulus,
        Factor::AccelScale,
        Factor::TensionFree,
    ];

    /// The factor's key in `data/sensitivity.toml`.
    pub fn key(self) -> &'static str {
        match self {
            Factor::EndstopGap => "endstop_gap",
            Factor::MechanicalDamping => "mechanical_damping",
            Factor::Stiffness => "stiffness",
            Factor::ParasiticCapacitance => "parasitic_capacitance",
            Factor::ImpactDamping => "impact_damping",
            Factor::YoungsModulus => "youngs_modulus",
            Factor::AccelScale => "accel_scale",
            Factor::TensionFree => "tension_free",
        }
    }
}

/// Why the ranges file or a point could not be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RangesError {
    /// Not valid TOML for the schema (unknown or missing factor, wrong type).
    #[error("data/sensitivity.toml: {0}")]
    Parse(String),
    /// A range is malformed; `field` is the dotted key.
    #[error("data/sensitivity.toml: `{field}`: {why}")]
    Range {
        /// Dotted key, e.g. `prototype1.endstop_gap`.
        field: String,
        /// What is wrong.
        why: String,
    },
    /// A point has the wrong length or a coordinate outside [0, 1].
    #[error("point {0:?} is not in the unit cube of {n} factors", n = Factor::ALL.len())]
    Point(Vec<f64>),
    /// The device at a point fails validation.
    #[error(transparent)]
    Device(#[from] ParamError),
    /// The published value of a factor lies outside its range (no point of the cube is the
    /// published set).
    #[error("data/sensitivity.toml: the published {factor} ({value}) lies outside its range")]
    PublishedOutside {
        /// The factor's key.
        factor: &'static str,
        /// The published value (the factor on it for a relative range).
        value: f64,
    },
}

/// One factor's range as written in the file.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Span {
    /// A factor on the device's own value.
    pub relative: Option<[f64; 2]>,
    /// Absolute bounds in SI units.
    pub absolute: Option<[f64; 2]>,
    /// A switch: the two settings.
    pub discrete: Option<[bool; 2]>,
}

/// The ranges of one prototype.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Ranges {
    endstop_gap: Span,
    mechanical_damping: Span,
    stiffness: Span,
    parasitic_capacitance: Span,
    impact_damping: Span,
    youngs_modulus: Span,
    accel_scale: Span,
    tension_free: Span,
}

/// The ranges of both prototypes.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
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

    /// Parses and checks a ranges file.
    pub fn parse(text: &str) -> Result<Self, RangesError> {
        let file: RangesFile =
            toml::from_str(text).map_err(|e| RangesError::Parse(e.to_string()))?;
        file.prototype1.check("prototype1")?;
        file.prototype2.check("prototype2")?;
        Ok(file)
    }
}

impl Ranges {
    /// The span of one factor.
    pub fn span(&self, f: Factor) -> &Span {
        match f {
            Factor::EndstopGap => &self.endstop_gap,
            Factor::MechanicalDamping => &self.mechanical_damping,
            Factor::Stiffness => &self.stiffness,
            Factor::ParasiticCapacitance => &self.parasitic_capacitance,
            Factor::ImpactDamping => &self.impact_damping,
            Factor::YoungsModulus => &self.youngs_modulus,
            Factor::AccelScale => &self.accel_scale,
            Factor::TensionFree => &self.tension_free,
        }
    }

    fn check(&self, table: &str) -> Result<(), RangesError> {
        for f in Factor::ALL {
            let err = |why: &str| RangesError::Range {
                field: format!("{table}.{}", f.key()),
                why: why.to_string(),
            };
            let s = self.span(f);
            let discrete = f == Factor::TensionFree;
            match (s.relative, s.absolute, s.discrete) {
                (None, None, Some([a, b])) if discrete => {
                    if a == b {
                        return Err(err("the two settings of a switch must differ"));
                    }
                }
                (Some([lo, hi]), None, None) | (None, Some([lo, hi]), None) if !discrete => {
                    if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
                        return Err(err("the range must be finite with lo <= hi"));
                    }
                    // b_im may be zero (no impact loss); every other factor scales a positive
                    // physical value and must stay positive.
                    let floor_ok = if f == Factor::ImpactDamping {
                        lo >= 0.0
                    } else {
                        lo > 0.0
                    };
                    if !floor_ok {
                        return Err(err("the range must not reach a non-physical value"));
                    }
                }
                _ if discrete => return Err(err("a switch is written `discrete = [a, b]`")),
                _ => {
                    return Err(err(
                        "give exactly one of `relative = [lo, hi]` or `absolute = [lo, hi]`",
                    ))
                }
            }
        }
        Ok(())
    }

    /// The point of the unit cube whose variant is `base` itself (the published set): for a
    /// range, where the device's own value lies in it (the factor 1 of a relative range); for
    /// the switch, the middle of the half that selects the device's own setting. Its variant
    /// equals `base` to rounding (a relative factor `lo + u (hi - lo)` is 1 to within 1 ulp).
    pub fn published_point(&self, base: &Device) -> Result<Vec<f64>, RangesError> {
        Factor::ALL
            .iter()
            .map(|&f| {
                let s = self.span(f);
                if let Some([a, _]) = s.discrete {
                    return Ok(if endstop(base).tension_free == a {
                        0.25
                    } else {
                        0.75
                    });
                }
                let (value, [lo, hi]) = match (s.relative, s.absolute) {
                    (Some(r), _) => (1.0, r),
                    (_, Some(r)) => (own_value(base, f), r),
                    _ => unreachable!("checked on load: a range is relative or absolute"),
                };
                let outside = RangesError::PublishedOutside {
                    factor: f.key(),
                    value,
                };
                if !(lo..=hi).contains(&value) {
                    return Err(outside);
                }
                Ok(if hi > lo {
                    (value - lo) / (hi - lo)
                } else {
                    0.5
                })
            })
            .collect()
    }

    /// The variant of `base` at a point of the unit cube (coordinates in [`Factor::ALL`] order).
    pub fn variant(&self, base: &Device, point: &[f64]) -> Result<Variant, RangesError> {
        if point.len() != Factor::ALL.len() || point.iter().any(|u| !(0.0..=1.0).contains(u)) {
            return Err(RangesError::Point(point.to_vec()));
        }
        let mut device = base.clone();
        let mut accel_scale = 1.0;
        for (&f, &u) in Factor::ALL.iter().zip(point) {
            let s = self.span(f);
            if let Some([a, b]) = s.discrete {
                device = device.with_tension_free(if u < 0.5 { a } else { b });
                continue;
            }
            let value = |own: f64| match (s.relative, s.absolute) {
                (Some([lo, hi]), _) => own * (lo + u * (hi - lo)),
                (_, Some([lo, hi])) => lo + u * (hi - lo),
                _ => own,
            };
            match f {
                Factor::EndstopGap => device = device.with_stop_gap(value(endstop(&device).gap_m)),
                Factor::MechanicalDamping => {
                    device.mechanics.damping_n_s_per_m = value(device.mechanics.damping_n_s_per_m)
                }
                Factor::Stiffness => {
                    device.mechanics.stiffness_n_per_m = value(device.mechanics.stiffness_n_per_m)
                }
                Factor::ParasiticCapacitance => {
                    comb_mut(&mut device).cp_f = value(comb(&device).cp_f)
                }
                Factor::ImpactDamping => {
                    let b = value(endstop(&device).damping_n_s_per_m);
                    device = with_stops(&device, |s| s.damping_n_s_per_m = b)
                }
                Factor::YoungsModulus => {
                    let e = value(hertz_stop(&device).youngs_modulus_pa);
                    device = with_hertz(&device, |h| h.youngs_modulus_pa = e)
                }
                Factor::AccelScale => accel_scale = value(1.0),
                Factor::TensionFree => {}
            }
        }
        device.validate(&format!("{} (sensitivity variant)", base.name))?;
        Ok(Variant {
            device,
            accel_scale,
        })
    }
}

/// The device's own value of a continuous factor (the acceleration's scale is 1).
fn own_value(d: &Device, f: Factor) -> f64 {
    match f {
        Factor::EndstopGap => endstop(d).gap_m,
        Factor::MechanicalDamping => d.mechanics.damping_n_s_per_m,
        Factor::Stiffness => d.mechanics.stiffness_n_per_m,
        Factor::ParasiticCapacitance => comb(d).cp_f,
        Factor::ImpactDamping => endstop(d).damping_n_s_per_m,
        Factor::YoungsModulus => hertz_stop(d).youngs_modulus_pa,
        Factor::AccelScale => 1.0,
        Factor::TensionFree => f64::from(u8::from(endstop(d).tension_free)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn prototype(text: &str) -> Device {
        Device::from_toml_str(text, "test").unwrap()
    }

    #[test]
    fn the_bundled_ranges_load_and_their_corners_are_valid_devices() {
        let file = RangesFile::bundled().unwrap();
        let p1 = prototype(include_str!("../../../data/prototype1.toml"));
        let p2 = prototype(include_str!("../../../data/prototype2.toml"));
        for (ranges, dev) in [(&file.prototype1, &p1), (&file.prototype2, &p2)] {
            for corner in [0.0, 1.0] {
                let v = ranges.variant(dev, &[corner; 8]).unwrap();
                assert!(v.accel_scale > 0.0);
            }
        }
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
            for f in Factor::ALL {
                let (a, b) = (own_value(&v.device, f), own_value(dev, f));
                assert!((a - b).abs() <= 1e-14 * b.abs(), "{f:?}: {a} vs {b}");
            }
            assert!((v.accel_scale - 1.0).abs() < 1e-14);
        }
        // A device whose b_im lies outside the absolute range has no published point.
        let wild = with_stops(&p1, |s| s.damping_n_s_per_m = 50.0);
        assert!(matches!(
            file.prototype1.published_point(&wild),
            Err(RangesError::PublishedOutside {
                factor: "impact_damping",
                ..
            })
        ));
    }

    #[test]
    fn a_point_sets_each_factor_inside_its_range() {
        let file = RangesFile::bundled().unwrap();
        let p1 = prototype(include_str!("../../../data/prototype1.toml"));
        let v = file
            .prototype1
            .variant(&p1, &[0.5, 0.0, 1.0, 0.5, 0.15, 1.0, 0.0, 0.9])
            .unwrap();
        // Midpoint of a relative [0.8, 1.2] range is the published value itself: exact
        // arithmetic up to one rounding of 7e-6 * 1.0.
        assert!((endstop(&v.device).gap_m - 7e-6).abs() < 1e-18);
        assert!((v.device.mechanics.damping_n_s_per_m - 0.7 * 3.75e-3).abs() < 1e-15);
        assert!((v.device.mechanics.stiffness_n_per_m - 1.05 * 166.5).abs() < 1e-12);
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
            Err(RangesError::Range { field, .. }) if field == "prototype1.endstop_gap"
        ));
        let both = good.replacen(
            "impact_damping = { absolute = [0.0, 10.0] }",
            "impact_damping = { absolute = [0.0, 10.0], relative = [1.0, 2.0] }",
            1,
        );
        assert!(matches!(
            RangesFile::parse(&both),
            Err(RangesError::Range { field, .. }) if field == "prototype1.impact_damping"
        ));
        let unknown = good.replacen(
            "[prototype1]",
            "[prototype1]\nmass = { relative = [1, 2] }",
            1,
        );
        assert!(
            matches!(RangesFile::parse(&unknown), Err(RangesError::Parse(m)) if m.contains("mass"))
        );
        let file = RangesFile::bundled().unwrap();
        let p1 = prototype(include_str!("../../../data/prototype1.toml"));
        assert!(matches!(
            file.prototype1.variant(&p1, &[0.5; 7]),
            Err(RangesError::Point(_))
        ));
        assert!(matches!(
            file.prototype1.variant(&p1, &[1.5; 8]),
            Err(RangesError::Point(_))
        ));
    }
}
