//! The events between two accepted points of a branch (see the table in the parent module):
//! the location of a sign change of a test function (in [`super::test_functions`]) by the
//! root finder along the branch, and the location of grazing on the branch of the same device
//! without stops.

use nalgebra::Complex;

use crate::model::Model;
use crate::num::roots::{illinois, RootOptions, Sample};
use crate::ode::Stats;
use crate::study::orbit::{is_neutral, OrbitError, Shooter, NEUTRAL_BAND};

use super::corrector::Continuer;
use super::test_functions::{
    test_fold, test_grazing, test_minus_one, test_plus_one, test_torus, Gaps,
};
use super::{BranchPoint, Event, EventKind};

impl<M: Model<N> + Clone, const N: usize> Continuer<'_, '_, M, N> {
    /// Locates a sign change of `test` between `a` (index `k`) and `b`, at arclength `ds`.
    #[allow(clippy::too_many_arguments)]
    fn locate(
        &mut self,
        kind: EventKind,
        k: usize,
        a: &BranchPoint,
        b: &BranchPoint,
        ds: f64,
        test: fn(&BranchPoint, Gaps) -> f64,
        gaps: Gaps,
    ) -> Result<Event, OrbitError> {
        let tol_s = self.settings.locate_tol / self.settings.param_scale;
        let opts = RootOptions {
            f_tol: None,
            x_tol_abs: tol_s,
            x_tol_rel: 0.0,
            max_iter: 60,
        };
        let (fa, fb) = (test(a, gaps), test(b, gaps));
        // The best sample so far, kept outside the root finder: a corrector that fails close to
        // the event (at a branch point the bordered Jacobian is singular) ends the search with
        // the bracket reached, not with an error.
        let mut best = if fa.abs() <= fb.abs() {
            (0.0, fa, a.clone())
        } else {
            (ds, fb, b.clone())
        };
        let lo = Sample::new(0.0, fa, ());
        let hi = Sample::new(ds, fb, ());
        // The search's outcome is the best sample, whatever its end: a failed evaluation ends it
        // with the bracket reached, and where the test keeps its sign across the step (a torus
        // is found by the count of unstable multipliers, which also changes where multipliers
        // jump, as at a grazing, or cross together) the event still lies within the step,
        // placed at the end where its test is smaller.
        let _ = illinois(
            |s| -> Result<(f64, ()), OrbitError> {
                let (p, _) = self.point_at(a, s)?;
                let v = test(&p, gaps);
                if v.abs() < best.1.abs() {
                    best = (s, v, p);
                }
                Ok((v, ()))
            },
            lo,
            hi,
            &opts,
        );
        let (s_best, _, best) = best;
        Ok(Event {
            kind,
            param: best.orbit.param(self.settings.parameter),
            orbit: best.orbit,
            after_point: k,
            s: s_best,
            multiplier_crossing: false,
            at_grazing: false,
            stable_before: a.orbit.is_stable(),
            stable_after: b.orbit.is_stable(),
            contact: None,
            strikes: None,
        })
    }

    /// Locates a grazing between `a` and `b` on the branch of the same device with the stops
    /// removed, followed from whichever end does not touch a stop: that branch is smooth where
    /// the real one has the grazing singularity, and the orbit at which its largest |x|
    /// reaches x_max is exactly the grazing orbit (it exerts no contact force). Followed from
    /// `b`, it also tells which way along `b`'s tangent the stop is reached: `Some(true)` when
    /// along the tangent (it points back into the grazing), `Some(false)` when against it;
    /// `None` when followed from `a`.
    fn locate_grazing(
        &mut self,
        k: usize,
        a: &BranchPoint,
        b: &BranchPoint,
        ds: f64,
    ) -> Result<(Event, Option<bool>), OrbitError> {
        let gaps = Gaps::of(self.shooter.base);
        let free_model = self.shooter.base.without_contacts();
        let free = Shooter::with_scales(&free_model, self.shooter.cfg, self.shooter.scales())
            .measuring(self.shooter.base.contacts());
        let mut c = Continuer {
            shooter: &free,
            settings: self.settings,
            periods: self.periods,
            stats: Stats::default(),
        };
        let from_a = test_grazing(a, gaps) <= 0.0;
        // From the non-touching end towards the other one; from `b` the tangent inherited
        // from `a` may point either way (at a corner it points back into the corner), so both
        // directions are tried.
        // Each candidate with the way it runs along `b`'s tangent (none from `a`).
        let candidates: Vec<(BranchPoint, Option<bool>)> = if from_a {
            vec![(a.clone(), None)]
        } else {
            vec![
                (
                    BranchPoint {
                        orbit: b.orbit.clone(),
                        tangent: -b.tangent.clone(),
                    },
                    Some(false),
                ),
                (b.clone(), Some(true)),
            ]
        };
        // Bracket the crossing on the stop-free branch (it differs from the real one past the
        // grazing, so the crossing may lie a little beyond `ds`). After a hop over a corner
        // `ds` is the hop's length, which can be far longer than the stop-free branch can be
        // followed in one step: shorter steps are tried last.
        let mut found = None;
        let mut along_b = None;
        let tries = [
            1.0, 2.0, 4.0, 8.0, 0.5, 0.25, 0.125, 0.0625, 0.03125, 0.015625,
        ];
        'dirs: for (anchor, along) in candidates {
            for hi in tries.map(|f| f * ds) {
                if let Ok((p, _)) = c.point_at(&anchor, hi) {
                    if test_grazing(&p, gaps) > 0.0 {
                        found = Some((anchor, p, hi));
                        along_b = along;
                        break 'dirs;
                    }
                }
            }
        }
        let Some((anchor, end, hi)) = found else {
            return Err(OrbitError::NoConvergence {
                what: self.settings.parameter.label(),
                param: b.orbit.param(self.settings.parameter),
                iterations: 0,
                residual: b.orbit.residual,
            });
        };
        let mut e = c.locate(EventKind::Grazing, k, &anchor, &end, hi, test_grazing, gaps)?;
        self.stats += c.stats;
        if !from_a {
            e.s = ds - e.s.min(ds);
        }
        e.stable_before = a.orbit.is_stable();
        e.stable_after = b.orbit.is_stable();
        Ok((e, along_b))
    }

    /// Whether the change of the count of unstable multipliers between `a` and `b` can be a
    /// complex pair crossing the unit circle (a Neimark-Sacker point): the count of unstable
    /// multipliers off the real axis changes while that of real ones stays, and no rigid
    /// contact gains or loses a strike a period between them. Across such a grazing the
    /// multipliers jump (the saltation matrix of a strike at vanishing speed grows without
    /// bound; Nordmark, J. Sound Vib. 145, 1991), so that a changed count there is that jump,
    /// no continuous crossing; the grazing is reported as itself ([`Self::strike_events`]).
    fn pair_may_cross(&self, a: &BranchPoint, b: &BranchPoint) -> bool {
        let complex_unstable = |p: &BranchPoint| {
            let off_axis = |m: &&Complex<f64>| m.im.abs() >= NEUTRAL_BAND && m.norm() > 1.0;
            let off = p.orbit.multipliers.iter().filter(off_axis).count();
            (off, p.orbit.unstable_count() - off)
        };
        let (ca, ra) = complex_unstable(a);
        let (cb, rb) = complex_unstable(b);
        let contacts = self.shooter.base.contacts();
        let strikes = |p: &BranchPoint, k: usize| p.orbit.summary.contact_reach.strikes[k];
        let jump = (0..Gaps::of(self.shooter.base).len())
            .any(|k| contacts[k].rigid() && strikes(a, k) != strikes(b, k));
        ca != cb && ra == rb && !jump
    }

    // ANCHOR: events
    /// The events between points `k` and `k + 1` (at arclength `ds` along point k's
    /// tangent). `b` may have its tangent reversed: where the branch leaves contact at a
    /// corner (the impacting branch meets the non-impacting one at the grazing orbit and the
    /// parameter turns there), the tangent inherited from `a` points back into the corner, and
    /// the branch goes on away from the grazing orbit.
    pub(super) fn events_between(
        &mut self,
        k: usize,
        a: &BranchPoint,
        b: &mut BranchPoint,
        ds: f64,
    ) -> Result<Vec<Event>, OrbitError> {
        let gaps = Gaps::of(self.shooter.base);
        let mut out = Vec::new();
        let graze = (test_grazing(a, gaps) > 0.0) != (test_grazing(b, gaps) > 0.0);
        // At a rigid stop the multipliers diverge at grazing (the saltation matrix grows like
        // the inverse impact speed): the interval holds a non-smooth point, across which no
        // smooth event is tested for, and a turn there is not a fold. The branches that meet
        // at such a point are the business of `impacting`.
        let rigid = self.shooter.base.contacts().iter().any(|c| c.rigid());
        let mut corner = false;
        if graze {
            // Located on the stop-free branch; a failure leaves the grazing unlocated (the
            // branch itself is fine) rather than ending the continuation.
            if let Ok((g, along_b)) = self.locate_grazing(k, a, b, ds) {
                if a.orbit.is_impacting() && !b.orbit.is_impacting() {
                    // The branch goes on away from the grazing orbit: against the direction
                    // in which the stop-free branch from `b` reaches the stop. That direction
                    // is known even where `b` lies at the grazing orbit to rounding (its
                    // distance to the stop ~1e-15 m, the located grazing `b` itself), where
                    // the difference of the two orbits has no direction.
                    let back = match along_b {
                        Some(along) => along,
                        // Followed from `a` (its grazing test says free, though it impacts):
                        // the orbits' difference has a direction there.
                        None => {
                            let away = self.u_of(&b.orbit) - self.u_of(&g.orbit);
                            b.tangent.dot(&away) < 0.0
                        }
                    };
                    if back {
                        b.tangent = -b.tangent.clone();
                    }
                    corner = (a.param_tangent() > 0.0) != (b.param_tangent() > 0.0);
                }
                if corner && !rigid {
                    let mut fold = g.clone();
                    fold.kind = EventKind::Fold;
                    fold.multiplier_crossing =
                        (test_plus_one(a, gaps) > 0.0) != (test_plus_one(b, gaps) > 0.0);
                    fold.at_grazing = true;
                    out.push(fold);
                }
                out.push(g);
            }
        }
        let changes = |f: fn(&BranchPoint, Gaps) -> f64, b: &BranchPoint| {
            (f(a, gaps) > 0.0) != (f(b, gaps) > 0.0)
        };
        let turn = changes(test_fold, b);
        // A multiplier that enters or leaves the neutral band (`orbit::is_neutral`) changes
        // the sign of the +1 test without crossing: a conserved quantity appears or goes (a
        // circuit's switch stops or starts firing over the period), which is no branch point.
        // A true crossing in the same interval is then not reported.
        let neutral = |p: &BranchPoint| {
            let m = &p.orbit.multipliers;
            m.iter().filter(|m| is_neutral(**m, false)).count()
        };
        let plus1 = changes(test_plus_one, b) && neutral(a) == neutral(b);
        let minus1 = changes(test_minus_one, b);
        let torus = a.orbit.unstable_count() != b.orbit.unstable_count()
            && !plus1
            && !minus1
            && self.pair_may_cross(a, b);
        // At a corner the changes of stability belong to the corner (the fold above); across
        // a rigid stop's grazing they belong to no smooth event.
        if !(corner || graze && rigid) {
            let b = &*b;
            if turn {
                let mut e = self.locate(EventKind::Fold, k, a, b, ds, test_fold, gaps)?;
                e.multiplier_crossing = plus1;
                e.at_grazing = graze;
                out.push(e);
            } else if plus1 {
                out.push(self.locate(EventKind::BranchPoint, k, a, b, ds, test_plus_one, gaps)?);
            }
            if minus1 {
                out.push(self.locate(
                    EventKind::PeriodDoubling,
                    k,
                    a,
                    b,
                    ds,
                    test_minus_one,
                    gaps,
                )?);
            }
            if torus {
                out.push(self.locate(EventKind::Torus, k, a, b, ds, test_torus, gaps)?);
            }
        }
        out.extend(self.strike_events(k, a, b, ds));
        out.sort_by(|x, y| x.s.total_cmp(&y.s));
        Ok(out)
    }
    // ANCHOR_END: events

    /// The events across a corner crossed where the contact set changes, from `a` on one
    /// side to `b` on the other (at arclength `ds` along `a`'s tangent): the grazing, located
    /// on the stop-free branch (left unlocated if that fails), and a fold at grazing where the
    /// parameter turns there. No smooth event is tested for: the multipliers jump across the
    /// corner, so a change of their test functions belongs to it.
    pub(super) fn corner_events(
        &mut self,
        k: usize,
        a: &BranchPoint,
        b: &BranchPoint,
        ds: f64,
    ) -> Vec<Event> {
        let gaps = Gaps::of(self.shooter.base);
        let mut out = Vec::new();
        let graze = (test_grazing(a, gaps) > 0.0) != (test_grazing(b, gaps) > 0.0);
        if !graze {
            return out;
        }
        if let Ok((g, _)) = self.locate_grazing(k, a, b, ds) {
            if (test_fold(a, gaps) > 0.0) != (test_fold(b, gaps) > 0.0) {
                let mut fold = g.clone();
                fold.kind = EventKind::Fold;
                fold.at_grazing = true;
                out.push(fold);
            }
            out.push(g);
        }
        out
    }
}
