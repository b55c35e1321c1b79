//! The free parameters of a fit: named by their dotted path, checked against the device, and
//! mapped to the unbounded coordinates the search works in (see the parent module's docs).

use serde::Serialize;

use super::{FitError, ACCEL_SCALE_PATH};
use crate::device::Device;

/// A free parameter: a device parameter by its dotted path ([`Device::param`]) or
/// [`ACCEL_SCALE_PATH`], searched within `lo..hi`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FreeParam {
    /// Dotted path.
    pub path: String,
    /// Lower end of the range.
    pub lo: f64,
    /// Upper end of the range.
    pub hi: f64,
}

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
    pub(super) fn new(lo: f64, hi: f64) -> Self {
        if lo > 0.0 && hi / lo >= 10.0 {
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
    free: &[FreeParam],
    p: &[f64],
) -> Result<(Device, f64), FitError> {
    let mut d = base.clone();
    let mut scale = 1.0;
    for (f, &v) in free.iter().zip(p) {
        if f.path == ACCEL_SCALE_PATH {
            scale = v;
        } else {
            d = d.with_param(&f.path, v).map_err(|error| FitError::Param {
                path: f.path.clone(),
                error,
            })?;
        }
    }
    Ok((d, scale))
}

/// The starting value of a free parameter in `device`.
fn start_value(device: &Device, f: &FreeParam) -> Result<f64, FitError> {
    if f.path == ACCEL_SCALE_PATH {
        Ok(1.0)
    } else {
        device.param(&f.path).map_err(|error| FitError::Param {
            path: f.path.clone(),
            error,
        })
    }
}

/// Checks the free parameters against `device`: each exists, is free once, its range is
/// finite with `lo < hi`, both ends are valid values of the device, and the device's value
/// lies strictly inside. Returns the starting values.
pub fn check_free(device: &Device, free: &[FreeParam]) -> Result<Vec<f64>, FitError> {
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
            let t = Transform::new(lo, hi);
            let u = t.to_u(p);
            assert!((t.to_p(u) - p).abs() <= 1e-12 * p.abs().max(1.0));
            let h = 1e-6;
            let fd = (t.to_p(u + h) - t.to_p(u - h)) / (2.0 * h);
            assert!((fd - t.dp_du(u)).abs() <= 1e-6 * fd.abs());
            assert!(t.to_p(40.0) <= hi && t.to_p(-40.0) >= lo);
        }
    }
}
