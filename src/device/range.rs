//! A named device parameter with the interval a study may move it in: the free parameters of a
//! fit, the inputs of a Sobol study and the uncertain inputs of the deviations study
//! (`data/sensitivity.toml`). On a command line a range is written `PATH=LO..HI`
//! (`stops.both.damping_n_s_per_m=0.1..10`).
//!
//! A study moves a range over the unit interval: [`ParamRange::at`] maps a coordinate in
//! [0, 1] to the range (evenly in the value, in its logarithm, or to one of a switch's two
//! settings), and [`ParamRange::value`] to the parameter's value, which for a relative range
//! is that factor times the device's own value.

use super::{Device, ParamError};

/// The path of the one parameter that is not the device's: a factor on the stated base
/// acceleration (1 in every device).
pub const ACCEL_SCALE_PATH: &str = "drive.accel_scale";

/// How a range spreads the unit interval over its values.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Spacing {
    /// Evenly in the value.
    Linear,
    /// Evenly in the logarithm of the value (needs `lo > 0`).
    Log,
    /// Two settings, `lo` on the lower half of the unit interval and `hi` on the upper half
    /// (a yes/no switch: 0 is no, 1 is yes).
    Switch,
}

impl Spacing {
    /// The spacing of a range written without one: logarithmic for a positive range spanning
    /// a decade or more (a damping coefficient), linear otherwise.
    pub fn auto(lo: f64, hi: f64) -> Spacing {
        if lo > 0.0 && hi / lo >= 10.0 {
            Spacing::Log
        } else {
            Spacing::Linear
        }
    }
}

/// A device parameter (by its dotted path, see [`Device::param`], or [`ACCEL_SCALE_PATH`]) and
/// its interval.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamRange {
    /// Dotted path of the parameter, e.g. `stops.both.gap_m`.
    pub path: String,
    /// Lower end of the interval (a switch: its first setting).
    pub lo: f64,
    /// Upper end of the interval (a switch: its second setting).
    pub hi: f64,
    /// How the unit interval is spread over the range.
    pub spacing: Spacing,
    /// True when `lo` and `hi` are factors on the device's own value rather than values.
    pub relative: bool,
}

impl ParamRange {
    /// Parses `PATH=LO..HI`, `PATH=LO..HI:log` or `PATH=LO..HI:linear` (without a spacing,
    /// [`Spacing::auto`]); the errors name the path.
    ///
    /// ```
    /// use endstop::device::{ParamRange, Spacing};
    /// let r = ParamRange::parse("stops.both.damping_n_s_per_m=0.1..10:log").unwrap();
    /// assert_eq!((r.lo, r.hi, r.spacing), (0.1, 10.0, Spacing::Log));
    /// assert_eq!(ParamRange::parse("stops.both.gap_m=4e-6..8e-6").unwrap().spacing, Spacing::Linear);
    /// assert!(ParamRange::parse("mechanics.mass_kg=2..1").is_err());
    /// ```
    pub fn parse(text: &str) -> Result<ParamRange, ParamError> {
        let invalid = |field: &str, message: String| ParamError::Invalid {
            source_name: "range".into(),
            field: field.to_string(),
            message,
        };
        let (path, rest) = text.split_once('=').ok_or_else(|| {
            invalid(
                text,
                "expected PATH=LO..HI (for example stops.both.gap_m=4e-6..8e-6)".into(),
            )
        })?;
        let path = path.trim();
        if path.is_empty() {
            return Err(invalid(text, "the parameter's path is empty".into()));
        }
        let (interval, spacing) = match rest.rsplit_once(':') {
            Some((i, "log")) => (i, Some(Spacing::Log)),
            Some((i, "linear")) => (i, Some(Spacing::Linear)),
            Some((_, other)) => {
                return Err(invalid(
                    path,
                    format!("unknown spacing `{other}`: must be `log` or `linear`"),
                ))
            }
            None => (rest, None),
        };
        let (lo, hi) = interval
            .split_once("..")
            .ok_or_else(|| invalid(path, format!("`{interval}` is not LO..HI")))?;
        let number = |s: &str| {
            s.trim()
                .parse::<f64>()
                .map_err(|_| invalid(path, format!("`{s}` is not a number")))
        };
        let (lo, hi) = (number(lo)?, number(hi)?);
        ParamRange::new(path, lo, hi, spacing.unwrap_or(Spacing::auto(lo, hi)))
    }

    /// A range of values, checked: finite ends with `lo < hi` (a switch: two different
    /// settings), and `lo > 0` for log spacing.
    pub fn new(path: &str, lo: f64, hi: f64, spacing: Spacing) -> Result<ParamRange, ParamError> {
        let range = ParamRange {
            path: path.to_string(),
            lo,
            hi,
            spacing,
            relative: false,
        };
        range.checked()
    }

    /// A range of values with the default spacing ([`Spacing::auto`]), not checked here: a
    /// fit checks its free parameters against the device ([`crate::fit::check_free`]), a study
    /// with [`ParamRange::check`].
    pub fn auto(path: &str, lo: f64, hi: f64) -> ParamRange {
        ParamRange {
            path: path.to_string(),
            lo,
            hi,
            spacing: Spacing::auto(lo, hi),
            relative: false,
        }
    }

    /// A range of factors on the device's own value, checked as [`ParamRange::new`] and
    /// positive.
    pub fn relative(
        path: &str,
        lo: f64,
        hi: f64,
        spacing: Spacing,
    ) -> Result<ParamRange, ParamError> {
        let range = ParamRange {
            relative: true,
            ..ParamRange::new(path, lo, hi, spacing)?
        };
        range.checked()
    }

    /// The range if its ends are consistent (see [`ParamRange::new`]).
    fn checked(self) -> Result<ParamRange, ParamError> {
        let out_of_range = |value: f64, range: &str| ParamError::OutOfRange {
            source_name: "range".into(),
            field: self.path.clone(),
            value,
            range: range.to_string(),
        };
        let (lo, hi) = (self.lo, self.hi);
        if !lo.is_finite() {
            return Err(out_of_range(lo, "finite"));
        }
        if self.spacing == Spacing::Switch {
            if !(hi.is_finite() && hi != lo) {
                return Err(out_of_range(hi, &format!("a setting other than {lo:e}")));
            }
        } else if !(hi.is_finite() && hi > lo) {
            return Err(out_of_range(
                hi,
                &format!("finite and above the lower end {lo:e}"),
            ));
        }
        if self.spacing == Spacing::Log && lo <= 0.0 {
            return Err(out_of_range(lo, "> 0 for log spacing"));
        }
        if self.relative && lo.min(hi) <= 0.0 {
            return Err(out_of_range(
                lo.min(hi),
                "> 0 (a factor on the device's own value)",
            ));
        }
        Ok(self)
    }

    /// Checks the range against a device: the path names one of its parameters, and the device
    /// is valid at both ends (a gap range reaching below zero fails here, naming the field).
    pub fn check(&self, device: &Device) -> Result<(), ParamError> {
        for u in [0.0, 1.0] {
            at_unit(device, std::slice::from_ref(self), &[u])?;
        }
        Ok(())
    }

    /// The point of the range at unit coordinate `u` in [0, 1] (0 is `lo`, 1 is `hi`): a value,
    /// or for a relative range a factor.
    pub fn at(&self, u: f64) -> f64 {
        match self.spacing {
            Spacing::Linear => self.lo + u * (self.hi - self.lo),
            Spacing::Log => (self.lo.ln() + u * (self.hi.ln() - self.lo.ln())).exp(),
            Spacing::Switch if u < 0.5 => self.lo,
            Spacing::Switch => self.hi,
        }
    }

    /// The unit coordinate of a point of the range (the inverse of [`ParamRange::at`]; for a
    /// switch, the middle of the half that selects the setting, NaN for another value).
    pub fn unit(&self, point: f64) -> f64 {
        match self.spacing {
            Spacing::Linear => (point - self.lo) / (self.hi - self.lo),
            Spacing::Log => (point / self.lo).ln() / (self.hi / self.lo).ln(),
            Spacing::Switch if point == self.lo => 0.25,
            Spacing::Switch if point == self.hi => 0.75,
            Spacing::Switch => f64::NAN,
        }
    }

    /// The parameter's value at unit coordinate `u`, given the device's own value `own`
    /// (used by a relative range only).
    pub fn value(&self, own: f64, u: f64) -> f64 {
        if self.relative {
            own * self.at(u)
        } else {
            self.at(u)
        }
    }

    /// The unit coordinate at which the parameter takes the device's own value `own`, or
    /// `None` when the range does not hold it.
    pub fn unit_of_own(&self, own: f64) -> Option<f64> {
        let point = if self.relative { 1.0 } else { own };
        let (lo, hi) = (self.lo.min(self.hi), self.lo.max(self.hi));
        let u = self.unit(point);
        ((lo..=hi).contains(&point) && u.is_finite()).then_some(u)
    }
}

/// A device's value of a parameter by its path ([`ACCEL_SCALE_PATH`] is 1).
pub fn own_value(device: &Device, path: &str) -> Result<f64, ParamError> {
    if path == ACCEL_SCALE_PATH {
        Ok(1.0)
    } else {
        device.param(path)
    }
}

/// The device and the acceleration scale with each range's parameter at its value, in order
/// (the scale is 1 unless a range is [`ACCEL_SCALE_PATH`]); the device is validated once, with
/// every parameter set.
pub fn with_values(
    device: &Device,
    ranges: &[ParamRange],
    values: &[f64],
) -> Result<(Device, f64), ParamError> {
    let mut accel_scale = 1.0;
    let mut set = Vec::with_capacity(ranges.len());
    for (r, &value) in ranges.iter().zip(values) {
        if r.path == ACCEL_SCALE_PATH {
            accel_scale = value;
        } else {
            set.push((r.path.as_str(), value));
        }
    }
    Ok((device.with_params(&set)?, accel_scale))
}

/// The device and the acceleration scale at a point of the unit cube, one coordinate per range
/// in order (see [`with_values`]).
pub fn at_unit(
    device: &Device,
    ranges: &[ParamRange],
    unit: &[f64],
) -> Result<(Device, f64), ParamError> {
    let values = ranges
        .iter()
        .zip(unit)
        .map(|(r, &u)| Ok(r.value(own_value(device, &r.path)?, u)))
        .collect::<Result<Vec<f64>, ParamError>>()?;
    with_values(device, ranges, &values)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn at_and_unit_are_inverse() {
        for spacing in [Spacing::Linear, Spacing::Log] {
            let r = ParamRange::new("x", 0.1, 10.0, spacing).unwrap();
            for u in [0.0, 0.25, 0.5, 1.0] {
                // Round trip through exp/ln: a few ulps.
                assert!((r.unit(r.at(u)) - u).abs() < 1e-12, "{spacing:?} {u}");
            }
        }
        let log = ParamRange::new("x", 0.1, 10.0, Spacing::Log).unwrap();
        assert!((log.at(0.5) - 1.0).abs() < 1e-12);
        let switch = ParamRange::new("x", 0.0, 1.0, Spacing::Switch).unwrap();
        assert_eq!((switch.at(0.49), switch.at(0.5)), (0.0, 1.0));
        assert_eq!((switch.unit(0.0), switch.unit(1.0)), (0.25, 0.75));
        assert!(switch.unit_of_own(0.5).is_none());
    }

    #[test]
    fn a_relative_range_scales_the_own_value() {
        let r = ParamRange::relative("x", 0.8, 1.2, Spacing::Linear).unwrap();
        assert_eq!(r.value(7.0, 0.5), 7.0 * (0.8 + 0.5 * (1.2 - 0.8)));
        // The own value sits where the factor is 1, whatever it is.
        assert!((r.unit_of_own(123.0).unwrap() - 0.5).abs() < 1e-15);
        assert!(ParamRange::relative("x", 0.0, 1.2, Spacing::Linear).is_err());
    }

    #[test]
    fn bad_ranges_name_the_field() {
        for (text, field) in [
            ("mechanics.mass_kg", "mechanics.mass_kg"),
            ("a.b=1..x", "a.b"),
            ("a.b=2..1", "a.b"),
            ("a.b=0..1:log", "a.b"),
            ("a.b=0..1:cubic", "a.b"),
            ("a.b=nan..1", "a.b"),
            ("=1..2", "=1..2"),
        ] {
            let e = ParamRange::parse(text).unwrap_err();
            assert_eq!(e.field(), Some(field), "{text}: {e}");
        }
    }

    #[test]
    fn the_default_spacing_is_log_over_a_decade_of_positive_values() {
        let s = |t: &str| ParamRange::parse(t).unwrap().spacing;
        assert_eq!(s("a=0.1..20"), Spacing::Log);
        assert_eq!(s("a=4e-6..9.9e-6"), Spacing::Linear);
        assert_eq!(s("a=0..20"), Spacing::Linear);
        assert_eq!(s("a=0.1..20:linear"), Spacing::Linear);
    }
}
