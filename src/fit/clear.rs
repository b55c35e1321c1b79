//! Orbits that a change of the parameters cannot move. A stop acts only in contact, so where
//! the device differs from the one an orbit was found on only in one stop (its gap, law or
//! damping), and the orbit stays clear of that stop at both its old and its new gap, the
//! vector field along the orbit and around it is the same: the orbit, its multipliers and its
//! summary are the new device's too, and following it again by Newton's method would return
//! it to the integrator's tolerance at the cost of a linearised period. This is the case of a
//! gap's column of the misfit's Jacobian for every point on the other side's branch.

use crate::device::{Device, Stop};
use crate::laws::contact::Side;
use crate::study::orbit::Orbit;

/// How far from a stop an orbit must stay to be kept, relative to the gap: the orbit's
/// extremes are located on the dense output to the integrator's tolerance (1e-9 relative and
/// below), so a thousandth of the gap leaves them far clear, and an orbit that near grazing is
/// found afresh.
pub(super) const CLEAR_REL: f64 = 1e-3;

/// What a change of device leaves in place.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Unchanged {
    /// The devices are the same.
    Everything,
    /// The devices differ only in the stop on `side`; its smaller gap of the two (m; infinite
    /// where one of them has no stop there).
    AwayFrom { side: Side, gap_m: f64 },
}

fn stop_mut(d: &mut Device, side: Side) -> &mut Option<Stop> {
    match side {
        Side::Upper => &mut d.stops.upper,
        Side::Lower => &mut d.stops.lower,
    }
}

/// What the change from `old` to `new` leaves in place: `None` when they differ in more than
/// one stop or in anything else.
pub(super) fn unchanged(old: &Device, new: &Device) -> Option<Unchanged> {
    if old == new {
        return Some(Unchanged::Everything);
    }
    [Side::Upper, Side::Lower].into_iter().find_map(|side| {
        let mut probe = new.clone();
        *stop_mut(&mut probe, side) = old.stops.side(side).cloned();
        (probe == *old).then(|| {
            let gap = |d: &Device| d.stops.side(side).map_or(f64::INFINITY, |s| s.gap_m);
            Unchanged::AwayFrom {
                side,
                gap_m: gap(old).min(gap(new)),
            }
        })
    })
}

impl Unchanged {
    /// True when the orbit `o`, found on the old device, is the new device's orbit at the
    /// acceleration `accel_rms_g` (g rms): the same drive, and clear of the changed stop.
    pub(super) fn keeps(&self, o: &Orbit, accel_rms_g: f64) -> bool {
        if o.forcing.accel_rms_g != accel_rms_g {
            return false;
        }
        let limit = |gap_m: f64| gap_m * (1.0 - CLEAR_REL);
        match *self {
            Unchanged::Everything => true,
            Unchanged::AwayFrom {
                side: Side::Upper,
                gap_m,
            } => o.summary.x_upper_m < limit(gap_m),
            Unchanged::AwayFrom {
                side: Side::Lower,
                gap_m,
            } => -o.summary.x_lower_m < limit(gap_m),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::track::point_orbit;
    use super::*;

    fn device() -> Device {
        let text = include_str!(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/data/examples/em_asymmetric.toml"
        ));
        Device::from_toml_str(text, "em_asymmetric.toml").unwrap()
    }

    #[test]
    fn one_stop_changed_is_found_and_anything_else_is_not() {
        let old = device();
        assert_eq!(unchanged(&old, &old), Some(Unchanged::Everything));
        let mut new = old.clone();
        let up = new.stops.upper.as_mut().unwrap();
        up.gap_m *= 0.9;
        let g = up.gap_m;
        assert_eq!(
            unchanged(&old, &new),
            Some(Unchanged::AwayFrom {
                side: Side::Upper,
                gap_m: g
            })
        );
        new.stops.lower.as_mut().unwrap().gap_m *= 1.1;
        assert_eq!(unchanged(&old, &new), None, "both stops changed");
        let mut other = old.clone();
        other.stops.upper.as_mut().unwrap().damping_n_s_per_m += 1.0;
        other.mechanics.damping_n_s_per_m *= 1.01;
        assert_eq!(
            unchanged(&old, &other),
            None,
            "a stop and the damping changed"
        );
    }

    /// The premise: an orbit clear of the changed stop is the new device's orbit. At 0.05 g
    /// at resonance the example's orbit stays well inside both gaps; with the upper gap moved
    /// from 1 mm to 0.8 mm (the smaller gap, so that the model's scales change too) Newton's
    /// method on the new device from the old orbit returns it to 1e-7 relative (each is
    /// accurate to about 1e-9 by the shooting's defaults). With the gap moved just inside
    /// the orbit's reach, or another drive, the orbit is not kept.
    #[test]
    fn an_orbit_clear_of_the_changed_stop_is_the_new_devices_orbit() {
        use crate::drive::Sine;
        use crate::physics::harvester::Harvester;
        use crate::study::periodic::{steady_state_from_rest, SteadySettings};
        use nalgebra::SVector;

        let old = device();
        let f = old.suspension_omega_rad_s() / (2.0 * std::f64::consts::PI);
        let a = 0.05;
        let s = steady_state_from_rest(&old, Sine::from_rms_g(a, f), &SteadySettings::default())
            .unwrap();
        let o = point_orbit(
            &Harvester::<4>::new(&old).unwrap(),
            f,
            a,
            0.0,
            SVector::from_column_slice(&s.state),
            1,
        )
        .unwrap();
        assert!(o.summary.x_upper_m < 0.5e-3, "{}", o.summary.x_upper_m);
        let mut new = old.clone();
        new.stops.upper.as_mut().unwrap().gap_m = 0.8e-3;
        let u = unchanged(&old, &new).unwrap();
        assert!(u.keeps(&o, a));
        assert!(!u.keeps(&o, a * 1.01), "another drive");
        let h_new = Harvester::<4>::new(&new).unwrap();
        let fresh = point_orbit(&h_new, f, a, o.phase_rad, o.state_n(), 1).unwrap();
        let rel = |x: f64, y: f64| (x - y).abs() / y.abs();
        assert!(rel(fresh.summary.v1_rms_v, o.summary.v1_rms_v) < 1e-7);
        assert!(rel(fresh.summary.x_upper_m, o.summary.x_upper_m) < 1e-7);
        assert!(rel(fresh.max_multiplier_abs(), o.max_multiplier_abs()) < 1e-7);
        let mut near = old.clone();
        near.stops.upper.as_mut().unwrap().gap_m = o.summary.x_upper_m * (1.0 + 1e-4);
        assert!(
            !unchanged(&old, &near).unwrap().keeps(&o, a),
            "within reach"
        );
    }
}
