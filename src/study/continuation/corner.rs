//! The crossing of a corner of the branch where its contact set changes: the stops its orbits
//! touch. Near a stiff compliant stop the period map is smooth on either side of the grazing
//! orbit but its derivatives change over a depth of contact far below any arclength step (the
//! grazing singularity of a piecewise-smooth flow; di Bernardo et al., *Piecewise-smooth
//! Dynamical Systems*, 2008): the multipliers jump and the tangent turns across it,
//! so that every step of the ordinary predictor-corrector is refused and the step shrinks to
//! nothing at the corner. The crossing treats the corner as an event, as the hybrid
//! continuation of COCO (Dankowicz and Schilder, *Recipes for Continuation*, 2013)
//! and the event location of BifurcationKit do: the first point past the corner with the
//! contact set predicted from the grazing distances is found at the longest arclength that
//! converges near its predictor, the
//! grazing orbit between them is located by bisection on the arclength with the changed
//! contact's grazing distance as its test, and the predictor restarts from the point on the new
//! side with that side's own tangent.

use crate::model::Model;
use crate::num::roots::{illinois, RootOptions, Sample};

use super::corrector::Continuer;
use super::test_functions::{contact_grazing, contact_set, Gaps, GRAZING_NEAR};
use super::BranchPoint;

/// Largest distance of the point past the corner from its predictor, in arclength steps (as
/// the corrector's acceptance of a step).
const MAX_CORRECTION: f64 = 0.5;

/// Ratio of successive trial arclengths past the corner (longest first).
const TRIAL_RATIO: f64 = 4.0;

/// A corner crossed: the located grazing orbit, the first point past it, and their arclengths
/// from the corner's start along its tangent.
pub(super) struct Crossing {
    /// The orbit nearest the grazing on the old contact set's side.
    pub grazing: BranchPoint,
    /// Arclength of [`Crossing::grazing`] from the start.
    pub s_grazing: f64,
    /// The first point past the corner with a predicted contact set.
    pub past: BranchPoint,
    /// Arclength of [`Crossing::past`] from the start.
    pub s_past: f64,
}

impl<M: Model<N>, const N: usize> Continuer<'_, '_, M, N> {
    /// Crosses the corner at which `last` (a point at which no step is accepted, after
    /// `before` on the branch) stands: its contact nearest grazing (a stop to the frame or
    /// between two masses), or every contact within [`GRAZING_NEAR`] of its gap, changes,
    /// and the point past
    /// the corner is the first corrected point at arclengths `ds_max`, `ds_max` / 4, ... down
    /// to `ds_min` along `last`'s tangent whose contact set is that prediction, that lies near
    /// its predictor and within the largest parameter step. `None` when `last` is near no
    /// grazing or no such point is found.
    pub(super) fn cross_corner(
        &mut self,
        before: &[BranchPoint],
        last: &BranchPoint,
        ds_min: f64,
        ds_max: f64,
    ) -> Option<Crossing> {
        let gaps = Gaps::of(self.shooter.base);
        let near = GRAZING_NEAR * gaps.smallest();
        let distance = contact_grazing(last, gaps);
        let nearest =
            (0..gaps.len()).min_by(|&i, &j| distance[i].abs().total_cmp(&distance[j].abs()))?;
        // The contact set of the branch before the corner, read at the latest earlier point
        // whose nearest contact is clear of it by more than the integration's relative
        // tolerance of the gap (at `last`, and at points crowded behind it, that contact's
        // distance is ~1e-17 m, of either sign).
        let clear = self.shooter.cfg.rtol * gaps.smallest();
        let from = before
            .iter()
            .rev()
            .find(|p| contact_grazing(p, gaps)[nearest].abs() > clear)
            .map_or(contact_set(last, gaps), |p| contact_set(p, gaps));
        let changing = (0..gaps.len())
            .filter(|&k| distance[k].abs() <= near)
            .fold(0u32, |set, k| set | (1 << k));
        if changing == 0 {
            return None;
        }
        // The nearest contact changes, or every near contact at once (a symmetric orbit
        // grazing both stops): a contact within `near` may still be deep in it on the scale of
        // a stiff stop's penetration.
        let predicted = [from ^ (1 << nearest), from ^ changing];
        let anchor = self.u_of(&last.orbit);
        let param = self.settings.parameter;
        let p_last = last.orbit.param(param);
        // The longest trial first: the restart lies as deep past the corner as the branch
        // allows, where its multipliers and tangent vary on the scale of the step again.
        let mut s = ds_max;
        let (past, s_past) = loop {
            if s < ds_min {
                return None;
            }
            if let Ok((p, _)) = self.point_at(last, s) {
                let predictor = &anchor + &last.tangent * s;
                let close = (self.u_of(&p.orbit) - predictor).norm() <= MAX_CORRECTION * s;
                let short = (p.orbit.param(param) - p_last).abs() <= self.settings.max_param_step;
                if close && short && predicted.contains(&contact_set(&p, gaps)) {
                    break (p, s);
                }
            }
            s /= TRIAL_RATIO;
        };
        let (grazing, s_grazing) = self.locate_contact_change(last, &past, s_past, nearest, gaps);
        Some(Crossing {
            grazing,
            s_grazing,
            past,
            s_past,
        })
    }

    /// The point between `a` and `b` (at arclength `ds` along `a`'s tangent) nearest the
    /// change of contact `k`, on `a`'s side of it, with its arclength: bisection by the root
    /// finder on the contact's grazing distance (`a` itself if every trial fails).
    fn locate_contact_change(
        &mut self,
        a: &BranchPoint,
        b: &BranchPoint,
        ds: f64,
        k: usize,
        gaps: Gaps,
    ) -> (BranchPoint, f64) {
        let f = |p: &BranchPoint| contact_grazing(p, gaps)[k];
        let (fa, fb) = (f(a), f(b));
        let opts = RootOptions {
            f_tol: None,
            x_tol_abs: self.settings.locate_tol / self.settings.param_scale,
            x_tol_rel: 0.0,
            max_iter: 60,
        };
        let before = fa > 0.0;
        let mut best = (a.clone(), 0.0);
        // The root finder's result is read from the samples kept here: a failed corrector
        // inside the bracket ends the search with the bracket reached.
        let _ = illinois(
            |s| -> Result<(f64, ()), ()> {
                let (p, _) = self.point_at(a, s).map_err(|_| ())?;
                let v = f(&p);
                if (v > 0.0) == before && s > best.1 {
                    best = (p, s);
                }
                Ok((v, ()))
            },
            Sample::new(0.0, fa, ()),
            Sample::new(ds, fb, ()),
            &opts,
        );
        best
    }
}
