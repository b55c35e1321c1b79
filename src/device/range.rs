//! A named device parameter with the interval a study may move it in: the free parameters of a
//! fit and the uncertain inputs of a sensitivity study, written `PATH=LO..HI` on a command line
//! (`stops.both.damping_n_s_per_m=0.1..10`).

use super::{Device, ParamError};

/// How a study spreads a range's points: evenly in the value, or evenly in its logarithm (for
/// a positive range spanning more than a decade, such as a damping coefficient).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Spacing {
    /// Evenly in the value.
    Linear,
    /// Evenly in the logarithm of the value (needs `lo > 0`).
    Log,
}

/// A device parameter (by its dotted path, see [`Device::param`]) and its interval.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamRange {
    /// Dotted path of the parameter, e.g. `stops.both.gap_m`.
    pub path: String,
    /// Lower end of the interval.
    pub lo: f64,
    /// Upper end of the interval.
    pub hi: f64,
    /// How points are spread over the interval.
    pub spacing: Spacing,
}

impl ParamRange {
    /// Parses `PATH=LO..HI` (linear spacing) or `PATH=LO..HI:log`.
    ///
    /// ```
    /// use endstop::device::{ParamRange, Spacing};
    /// let r = ParamRange::parse("stops.both.damping_n_s_per_m=0.1..10:log").unwrap();
    /// assert_eq!((r.lo, r.hi, r.spacing), (0.1, 10.0, Spacing::Log));
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
        let (interval, spacing) = match rest.rsplit_once(':') {
            Some((i, "log")) => (i, Spacing::Log),
            Some((i, "linear")) => (i, Spacing::Linear),
            Some((_, other)) => {
                return Err(invalid(
                    path,
                    format!("unknown spacing `{other}`: must be `log` or `linear`"),
                ))
            }
            None => (rest, Spacing::Linear),
        };
        let (lo, hi) = interval
            .split_once("..")
            .ok_or_else(|| invalid(path, format!("`{interval}` is not LO..HI")))?;
        let number = |s: &str| {
            s.trim()
                .parse::<f64>()
                .map_err(|_| invalid(path, format!("`{s}` is not a number")))
        };
        ParamRange::new(path, number(lo)?, number(hi)?, spacing)
    }

    /// A range, checked: finite ends with `lo < hi`, and `lo > 0` for log spacing.
    pub fn new(path: &str, lo: f64, hi: f64, spacing: Spacing) -> Result<ParamRange, ParamError> {
        let out_of_range = |value: f64, range: &str| ParamError::OutOfRange {
            source_name: "range".into(),
            field: path.to_string(),
            value,
            range: range.to_string(),
        };
        if !lo.is_finite() {
            return Err(out_of_range(lo, "finite"));
        }
        if !(hi.is_finite() && hi > lo) {
            return Err(out_of_range(
                hi,
                &format!("finite and above the lower end {lo:e}"),
            ));
        }
        if spacing == Spacing::Log && lo <= 0.0 {
            return Err(out_of_range(lo, "> 0 for log spacing"));
        }
        Ok(ParamRange {
            path: path.to_string(),
            lo,
            hi,
            spacing,
        })
    }

    /// Checks the range against a device: the path names one of its parameters, and the device
    /// is valid at both ends (a gap range reaching below zero fails here, naming the field).
    pub fn check(&self, device: &Device) -> Result<(), ParamError> {
        device.param(&self.path)?;
        device.with_param(&self.path, self.lo)?;
        device.with_param(&self.path, self.hi)?;
        Ok(())
    }

    /// The value at unit coordinate `u` in [0, 1] (0 is `lo`, 1 is `hi`).
    pub fn at(&self, u: f64) -> f64 {
        match self.spacing {
            Spacing::Linear => self.lo + u * (self.hi - self.lo),
            Spacing::Log => self.lo * (self.hi / self.lo).powf(u),
        }
    }

    /// The unit coordinate of a value (the inverse of [`ParamRange::at`]).
    pub fn unit(&self, value: f64) -> f64 {
        match self.spacing {
            Spacing::Linear => (value - self.lo) / (self.hi - self.lo),
            Spacing::Log => (value / self.lo).ln() / (self.hi / self.lo).ln(),
        }
    }
}

/// The device at a point of the unit cube, one coordinate per range in order.
pub fn device_at(
    device: &Device,
    ranges: &[ParamRange],
    unit: &[f64],
) -> Result<Device, ParamError> {
    let mut dev = device.clone();
    for (r, &u) in ranges.iter().zip(unit) {
        dev = dev.with_param(&r.path, r.at(u))?;
    }
    Ok(dev)
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
        ] {
            let e = ParamRange::parse(text).unwrap_err();
            assert_eq!(e.field(), Some(field), "{text}: {e}");
        }
    }
}
