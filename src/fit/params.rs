//! The free parameters of a fit: device parameters with ranges ([`ParamRange`], by their
//! dotted path), checked against the device, and mapped to the unbounded coordinates the search
//! works in (see the parent module's docs).

use super::{FitError, ACCEL_SCALE_PATH};
use crate::device::{own_value, with_values, Device, ParamError, ParamRange, Spacing};

/// How a free parameter maps to the unbounded coordinate.
#[derive(Debug, Clone, Copy)]
pub(super) struct Transform {
    a: f64,
    b: f64,
    log: bool,
    lo: f64,
    hi: f64,
}

impl Transform {
    /// The transform of a free parameter: of its logarithm for a log-spaced range.
    pub(super) fn of(range: &ParamRange) -> Self {
        Self::new(range.lo, range.hi, range.spacing == Spacing::Log)
    }

    fn new(lo: f64, hi: f64, log: bool) -> Self {
        if log {
            Self {
                a: lo.ln(),
                b: hi.ln(),
                log: true,
                lo,
                hi,
            }
        } else {
            Self {
                a: lo,
                b: hi,
                log: false,
                lo,
                hi,
            }
        }
    }
    pub(super) fn to_p(self, u: f64) -> f64 {
        let s = 1.0 / (1.0 + (-u).exp());
        let y = self.a + (self.b - self.a) * s;
        // Clamped: rounding must not put a value an ulp outside a range whose ends were
        // checked (a gap an ulp wider than the finger overlap is refused).
        let p = if self.log { y.exp() } else { y };
        p.clamp(self.lo, self.hi)
    }
    pub(super) fn to_u(self, p: f64) -> f64 {
        let y = if self.log { p.ln() } else { p };
        let s = (y - self.a) / (self.b - self.a);
        (s / (1.0 - s)).ln()
    }
    /// u at the fraction `s` of the (log-)range.
    pub(super) fn to_u_frac(self, s: f64) -> f64 {
        (s / (1.0 - s)).ln()
    }
    /// dp/du.
    pub(super) fn dp_du(self, u: f64) -> f64 {
        let s = 1.0 / (1.0 + (-u).exp());
        let dy = (self.b - self.a) * s * (1.0 - s);
        if self.log {
            dy * self.to_p(u)
        } else {
            dy
        }
    }
}

/// The device and acceleration factor at parameter values `p`.
pub(super) fn apply(
    base: &Device,
    free: &[ParamRange],
    p: &[f64],
) -> Result<(Device, f64), FitError> {
    with_values(base, free, p).map_err(|error| param_error(free, error))
}

/// A device's refusal of the free parameters' values, naming the parameter at fault (the
/// field the device names, or every free path when it names none).
fn param_error(free: &[ParamRange], error: ParamError) -> FitError {
    let path = match error.field() {
        Some(field) => field.to_string(),
        None => free
            .iter()
            .map(|f| f.path.as_str())
            .collect::<Vec<_>>()
            .join(", "),
    };
    FitError::Param { path, error }
}

/// The starting value of a free parameter in `device`.
fn start_value(device: &Device, f: &ParamRange) -> Result<f64, FitError> {
    own_value(device, &f.path).map_err(|error| FitError::Param {
        path: f.path.clone(),
        error,
    })
}

/// Checks the free parameters against `device`: each exists, is free once, its range is
/// finite with `lo < hi`, both ends are valid values of the device, and the device's value
/// lies strictly inside. Returns the starting values.
pub fn check_free(device: &Device, free: &[ParamRange]) -> Result<Vec<f64>, FitError> {
    if free.is_empty() {
        return Err(FitError::NoFreeParam);
    }
    let mut starts = Vec::new();
    for (i, f) in free.iter().enumerate() {
        if free[..i].iter().any(|g| g.path == f.path) {
            return Err(FitError::Duplicate {
                path: f.path.clone(),
            });
        }
        let range_err = |what: &str| FitError::Range {
            path: f.path.clone(),
            lo: f.lo,
            hi: f.hi,
            what: what.into(),
        };
        let p0 = start_value(device, f)?;
        if !(f.lo.is_finite() && f.hi.is_finite() && f.lo < f.hi) {
            return Err(range_err("must be finite with lo < hi"));
        }
        if f.relative || f.spacing == Spacing::Switch {
            return Err(range_err(
                "must be a range of values (not of factors, not a switch)",
            ));
        }
        if f.spacing == Spacing::Log && f.lo <= 0.0 {
            return Err(range_err("must be positive for log spacing"));
        }
        if f.path == ACCEL_SCALE_PATH {
            if f.lo <= 0.0 {
                return Err(range_err("must be positive (a factor on the acceleration)"));
            }
        } else {
            for end in [f.lo, f.hi] {
                device
                    .with_param(&f.path, end)
                    .map_err(|error| FitError::Param {
                        path: f.path.clone(),
                        error,
                    })?;
            }
        }
        if !(p0 > f.lo && p0 < f.hi) {
            return Err(range_err(&format!(
                "must contain the device's value {p0:e} (the starting point) strictly inside"
            )));
        }
        starts.push(p0);
    }
    Ok(starts)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transforms_round_trip_inside_the_range() {
        for (lo, hi, p) in [(4e-6, 8e-6, 5e-6), (0.1, 10.0, 1.5), (-1.0, 1.0, 0.3)] {
            let t = Transform::new(lo, hi, Spacing::auto(lo, hi) == Spacing::Log);
            let u = t.to_u(p);
            assert!((t.to_p(u) - p).abs() <= 1e-12 * p.abs().max(1.0));
            let h = 1e-6;
            let fd = (t.to_p(u + h) - t.to_p(u - h)) / (2.0 * h);
            assert!((fd - t.dp_du(u)).abs() <= 1e-6 * fd.abs());
            assert!(t.to_p(40.0) <= hi && t.to_p(-40.0) >= lo);
        }
    }
}
