//! The test functions of the events a branch is watched for (see the table in the parent
//! module): each is a scalar of one branch point that changes sign at its event. Both the
//! corrector (which watches grazing and the +1 multiplier while it steps) and the event
//! location along the branch read them here.

use crate::model::Model;

use super::BranchPoint;

/// The gaps of a model's two sides (infinite where there is no stop), for the grazing test.
#[derive(Debug, Clone, Copy)]
pub(super) struct Gaps {
    upper: f64,
    lower: f64,
    /// The suspension's natural frequency (rad/s), which turns an impact speed into a length.
    w0: f64,
}

impl Gaps {
    /// The gaps of the first mass's stops to the frame: the sides the orbit's summary measures.
    pub(super) fn of<M: Model<N>, const N: usize>(h: &M) -> Self {
        let (mut upper, mut lower) = (f64::INFINITY, f64::INFINITY);
        for c in h.contacts() {
            if c.mass == 0 && c.other.is_none() {
                if c.side > 0.0 {
                    upper = upper.min(c.gap);
                } else {
                    lower = lower.min(c.gap);
                }
            }
        }
        Self {
            upper,
            lower,
            w0: h.omega_rad_s(),
        }
    }

    pub(super) fn smallest(self) -> f64 {
        self.upper.min(self.lower)
    }
}

/// An orbit is near grazing when its largest displacement is within this fraction of the gap
/// (where a corner of the branch is looked for).
pub(super) const GRAZING_NEAR: f64 = 1e-3;

pub(super) fn test_fold(p: &BranchPoint, _: Gaps) -> f64 {
    p.param_tangent()
}
pub(super) fn test_plus_one(p: &BranchPoint, _: Gaps) -> f64 {
    p.orbit.det_minus_one()
}
pub(super) fn test_minus_one(p: &BranchPoint, _: Gaps) -> f64 {
    p.orbit.det_plus_one()
}
pub(super) fn test_torus(p: &BranchPoint, _: Gaps) -> f64 {
    p.orbit.max_multiplier_abs() - 1.0
}
/// How far an orbit is past grazing on its deeper side (m): the largest displacement less the
/// gap, or, once it strikes a rigid stop (which it never penetrates, so that the displacement
/// stays at the gap), its impact speed over `w0`. Both vanish at grazing.
pub(super) fn test_grazing(p: &BranchPoint, gaps: Gaps) -> f64 {
    let [upper, lower] = side_grazing(p, gaps);
    upper.max(lower)
}

/// [`test_grazing`] of each side (upper, lower): positive while the orbit touches that stop.
pub(super) fn side_grazing(p: &BranchPoint, gaps: Gaps) -> [f64; 2] {
    let s = &p.orbit.summary;
    let side = |reach: f64, gap: f64, speed: f64| {
        if speed > 0.0 {
            speed / gaps.w0
        } else {
            reach - gap
        }
    };
    [
        side(s.x_upper_m, gaps.upper, s.impact_speed_m_s[0]),
        side(-s.x_lower_m, gaps.lower, s.impact_speed_m_s[1]),
    ]
}

/// The stops an orbit touches (upper, lower): its contact set.
pub(super) fn contact_set(p: &BranchPoint, gaps: Gaps) -> [bool; 2] {
    side_grazing(p, gaps).map(|g| g > 0.0)
}
