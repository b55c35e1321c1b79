//! The test functions of the events a branch is watched for (see the table in the parent
//! module): each is a scalar of one branch point that changes sign at its event. Both the
//! corrector (which watches grazing and the +1 multiplier while it steps) and the event
//! location along the branch read them here.

use crate::model::{Model, MAX_CONTACTS};

use super::BranchPoint;

/// The gaps of a model's contacts (stops to the frame and between masses, in the order of
/// [`Model::contacts`]), for the grazing test.
#[derive(Debug, Clone, Copy)]
pub(super) struct Gaps {
    gap_m: [f64; MAX_CONTACTS],
    len: usize,
    /// The suspension's natural frequency (rad/s), which turns an impact speed into a length.
    w0: f64,
}

impl Gaps {
    /// The gaps of every contact of `h`.
    pub(super) fn of<M: Model<N>, const N: usize>(h: &M) -> Self {
        let mut gap_m = [f64::INFINITY; MAX_CONTACTS];
        let contacts = h.contacts();
        for (g, c) in gap_m.iter_mut().zip(&contacts) {
            *g = c.gap;
        }
        Self {
            gap_m,
            len: contacts.len().min(MAX_CONTACTS),
            w0: h.omega_rad_s(),
        }
    }

    /// The smallest gap (infinite without contacts).
    pub(super) fn smallest(self) -> f64 {
        self.gap_m.iter().fold(f64::INFINITY, |a, &g| a.min(g))
    }

    /// The number of contacts.
    pub(super) fn len(self) -> usize {
        self.len
    }

    /// The gap of contact `k` (m; infinite past the model's contacts).
    pub(super) fn gap(self, k: usize) -> f64 {
        self.gap_m.get(k).copied().unwrap_or(f64::INFINITY)
    }

    /// The suspension's natural frequency (rad/s).
    pub(super) fn w0(self) -> f64 {
        self.w0
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
/// How far an orbit is past grazing on its deepest contact (m): the largest approach of a
/// contact less its gap, or, once it strikes a rigid contact (which it never penetrates, so
/// that the approach stays at the gap), its impact speed over `w0`. Both vanish at grazing.
pub(super) fn test_grazing(p: &BranchPoint, gaps: Gaps) -> f64 {
    contact_grazing(p, gaps)
        .iter()
        .take(gaps.len)
        .fold(f64::NEG_INFINITY, |a, &g| a.max(g))
}

/// [`test_grazing`] of each contact (in the order of [`Model::contacts`]; negative infinity
/// past the model's contacts): positive while the orbit touches that contact.
pub(super) fn contact_grazing(p: &BranchPoint, gaps: Gaps) -> [f64; MAX_CONTACTS] {
    p.orbit
        .summary
        .contact_reach
        .grazing_m(&gaps.gap_m[..gaps.len], gaps.w0)
}

/// The contacts an orbit touches, bit `k` for contact `k`: its contact set.
pub(super) fn contact_set(p: &BranchPoint, gaps: Gaps) -> u32 {
    contact_grazing(p, gaps)
        .iter()
        .take(gaps.len)
        .enumerate()
        .filter(|(_, g)| **g > 0.0)
        .fold(0, |set, (k, _)| set | (1 << k))
}
