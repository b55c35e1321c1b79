//! The stops of a harvester as contacts of its [`Mode`]: the penetration and bracket of each
//! (eqs 1-2), its force and guards in each contact state, and what happens when a guard fires
//! (contact entry, exit, clipping, a rebound off a rigid stop or coming to rest on it).
//!
//! A proof mass on its frame stops is one contact per side: contact 0 is the stop at
//! `x = +gap` ([`Side::Upper`]), contact 1 the one at `x = -gap`. Each contact owns two guards:
//! `2 k` is its boundary (the penetration turning positive while apart, negative while
//! pressed or clipped) and `2 k + 1` its bracket (a tension-free contact's force turning
//! negative or positive again) or, resting on a rigid stop, the holding force turning away
//! from the stop. While the mass touches one of its stops the other is not watched.

use crate::laws::contact::{Side, StopModel};
use crate::model::{Contact, Mode};

/// An unused guard.
pub(crate) const OFF: f64 = f64::NEG_INFINITY;

/// The contact index of a side.
#[inline(always)]
pub fn contact_of(side: Side) -> usize {
    match side {
        Side::Upper => 0,
        Side::Lower => 1,
    }
}

/// The side of a contact index (0 upper, 1 lower).
#[inline(always)]
pub fn side_of(k: usize) -> Side {
    if k == 0 {
        Side::Upper
    } else {
        Side::Lower
    }
}

/// The stops of one proof mass and what they do (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameStops {
    /// The stop at x = +gap, if any.
    pub upper: Option<StopModel>,
    /// The stop at x = -gap, if any.
    pub lower: Option<StopModel>,
}

impl FrameStops {
    /// The stop on a side, if any.
    #[inline(always)]
    pub fn stop(&self, side: Side) -> Option<&StopModel> {
        match side {
            Side::Upper => self.upper.as_ref(),
            Side::Lower => self.lower.as_ref(),
        }
    }

    /// The gap on a side (m); infinite without a stop.
    #[inline(always)]
    pub fn gap(&self, side: Side) -> f64 {
        self.stop(side).map_or(f64::INFINITY, StopModel::gap)
    }

    /// Penetration delta into the stop on `side` (m; negative when not touching, -inf
    /// without a stop).
    #[inline(always)]
    pub fn penetration(&self, side: Side, x: f64) -> f64 {
        side.sign() * x - self.gap(side)
    }

    /// The bracket of eq 1 for a side at position `x` and velocity `v` (N): the spring force
    /// plus the contact damping.
    #[inline(always)]
    pub fn bracket(&self, side: Side, x: f64, v: f64) -> f64 {
        match self.stop(side) {
            Some(s) => s.bracket(self.penetration(side, x), side.sign() * v),
            None => 0.0,
        }
    }

    /// The side the mass touches in `mode`, with the contact's state.
    #[inline(always)]
    pub fn touching(mode: Mode) -> Option<(Side, Contact)> {
        match mode.contact(0) {
            Contact::Apart => match mode.contact(1) {
                Contact::Apart => None,
                c => Some((Side::Lower, c)),
            },
            c => Some((Side::Upper, c)),
        }
    }

    /// End-stop force F_im of eq 1 in a mode (N, along +x, as in eq 7's left-hand side); zero
    /// unless pressed into a compliant stop.
    #[inline(always)]
    pub fn force(&self, mode: Mode, x: f64, v: f64) -> f64 {
        match Self::touching(mode) {
            Some((side, Contact::Pressed)) => {
                let b = self.bracket(side, x, v);
                let tension_free = self.stop(side).is_some_and(StopModel::tension_free);
                let b = if tension_free { b.max(0.0) } else { b };
                side.sign() * b
            }
            _ => 0.0,
        }
    }

    /// True when the mass rests on a rigid stop in `mode`.
    #[inline(always)]
    pub fn resting(mode: Mode) -> Option<Side> {
        match Self::touching(mode) {
            Some((side, Contact::Resting)) => Some(side),
            _ => None,
        }
    }

    /// The contacts' guards of `mode` into `g[0..4]` (see the module docs); `holding` is the
    /// force that presses the mass onto a side's stop, asked only when it rests there.
    #[inline(always)]
    pub fn guards(&self, mode: Mode, x: f64, v: f64, holding: impl Fn(Side) -> f64, g: &mut [f64]) {
        match Self::touching(mode) {
            None => {
                g[0] = self.penetration(Side::Upper, x);
                g[1] = OFF;
                g[2] = self.penetration(Side::Lower, x);
                g[3] = OFF;
            }
            Some((side, c)) => {
                let k = 2 * contact_of(side);
                g[0] = OFF;
                g[1] = OFF;
                g[2] = OFF;
                g[3] = OFF;
                match c {
                    Contact::Pressed => {
                        g[k] = -self.penetration(side, x);
                        if self.stop(side).is_some_and(StopModel::tension_free) {
                            g[k + 1] = -self.bracket(side, x, v);
                        }
                    }
                    Contact::Clipped => {
                        g[k] = -self.penetration(side, x);
                        g[k + 1] = self.bracket(side, x, v);
                    }
                    Contact::Resting => g[k + 1] = -holding(side),
                    Contact::Apart => unreachable!("a touching contact is not apart"),
                }
            }
        }
    }

    /// The coefficient of restitution of the stop guard `index` reaches from free flight; zero
    /// for a compliant stop.
    pub fn restitution(&self, index: usize) -> f64 {
        match self.stop(side_of(index / 2)) {
            Some(&StopModel::Rigid { restitution, .. }) => restitution,
            _ => 0.0,
        }
    }
}
