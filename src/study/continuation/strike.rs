//! The crossing of a grazing that adds a strike per period: an orbit that strikes a rigid
//! contact approaches it again between its strikes, and where that free approach reaches the
//! gap one more strike per period begins while the set of contacts touched stays the same
//! (a grazing bifurcation of the impact number; Nordmark, J. Sound Vib. 145, 1991). The
//! period map's derivatives grow like the inverse square root of the distance past that
//! grazing, so that no arclength step of the ordinary predictor-corrector converges across
//! it, as at a corner where the contact set changes ([`super::corner`]). The crossing treats
//! it as that corner is treated, as an event of the hybrid continuation (Dankowicz and
//! Schilder, *Recipes for Continuation*, 2013): the first orbit with the added strike is
//! shot at fixed parameter values stepping away from the last point (the corner hop's
//! search, on the maps over one to four drive periods where the one-period map's Newton
//! iteration misses it: [`super::periods`]), the grazing between them is located by
//! bisection on the parameter with the contact's strike test ([`crate::study::orbit::ContactReach::strike_grazing_m`]), and the
//! predictor restarts from the orbit past it with that orbit's own tangent. Each rigid
//! contact's strike test is also watched between accepted points, so that a step that
//! passes such a grazing reports it.
//!
//! A compliant contact needs no such crossing: its contact force grows from zero with the
//! depth of contact, so that the period map stays continuously differentiable across the
//! start of a touch and the ordinary steps pass it.

use crate::model::Model;
use crate::num::roots::{illinois, RootOptions, Sample};
use crate::study::orbit::Orbit;

use super::corrector::Continuer;
use super::periods::Shot;
use super::test_functions::{test_fold, Gaps, GRAZING_NEAR};
use super::{BranchPoint, Event, EventKind};

/// The strikes of contact `k` a period.
fn strikes(p: &BranchPoint, k: usize) -> u32 {
    p.orbit.summary.contact_reach.strikes[k]
}

/// The strike test of contact `k` at `o` for an orbit that strikes it `n` times before the
/// grazing (see [`crate::study::orbit::ContactReach::strike_grazing_m`]).
fn strike_test(o: &Orbit, gaps: Gaps, k: usize, n: u32) -> Option<f64> {
    o.summary
        .contact_reach
        .strike_grazing_m(k, n, gaps.gap(k), gaps.w0())
}

/// A grazing that adds a strike, crossed: its events (the grazing, and a fold at grazing
/// where the parameter turns there) and the first point past it.
pub(super) struct StrikeCrossing {
    /// The events at the grazing, in branch order.
    pub events: Vec<Event>,
    /// The first point with the added strike.
    pub past: BranchPoint,
}

/// What the search past a grazing that adds a strike finds.
pub(super) enum StrikeOutcome {
    /// The grazing crossed onto the orbits of one period with the added strike.
    Crossed(StrikeCrossing),
    /// No orbit of one period with the added strike, but an orbit of several drive periods
    /// (its least number in [`Orbit::periods`]): the first found, nearest the last point.
    OtherPeriod(Orbit),
    /// The last point is at such a grazing, and no orbit is found past it (or the branch
    /// follows orbits of several periods, whose grazings the search does not cross).
    NotFound,
}

impl<M: Model<N>, const N: usize> Continuer<'_, '_, M, N> {
    /// The rigid contacts of the model, by index.
    fn rigid_contacts(&self) -> Vec<usize> {
        let contacts = self.shooter.base.contacts();
        (0..Gaps::of(self.shooter.base).len())
            .filter(|&k| contacts[k].rigid())
            .collect()
    }

    /// Crosses the grazing that adds a strike at `last` (point `k_last` of the branch, at
    /// which no step is accepted): the rigid contact whose free peak is nearest its gap, if
    /// within [`GRAZING_NEAR`] of the smallest gap, gains a strike. The point past it is the
    /// first orbit that strikes that contact once more (and every other contact as often as
    /// `last`), shot at fixed parameter values ahead of `last` up to the largest parameter
    /// step, then behind it (where the branch turns back at the grazing), each on the maps
    /// over one to [`super::periods::MAX_PERIODS`] drive periods ([`Continuer::shoot_periods`]). Where no
    /// such orbit of one period is found, the first orbit of several periods found is
    /// returned instead; [`StrikeOutcome::NotFound`] when no orbit is found, and at once on a
    /// branch of orbits of several periods. `None` when `last` is near no such grazing.
    pub(super) fn cross_strike_grazing(
        &mut self,
        k_last: usize,
        last: &BranchPoint,
    ) -> Option<StrikeOutcome> {
        let gaps = Gaps::of(self.shooter.base);
        let near = GRAZING_NEAR * gaps.smallest();
        let distance = |k: usize| strike_test(&last.orbit, gaps, k, strikes(last, k));
        let k = self
            .rigid_contacts()
            .into_iter()
            .filter_map(|k| distance(k).map(|d| (k, d)))
            .filter(|(_, d)| d.abs() <= near)
            .min_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))?
            .0;
        if self.periods > 1 {
            return Some(StrikeOutcome::NotFound);
        }
        let n = strikes(last, k);
        let len = gaps.len();
        let before: Vec<u32> = (0..len).map(|j| strikes(last, j)).collect();
        let added = |o: &Orbit| {
            let r = &o.summary.contact_reach;
            (0..len).all(|j| r.strikes[j] == before[j] + u32::from(j == k))
        };
        let ahead = last.param_tangent().signum();
        let (past, dir) = match self.shoot_strike(last, ahead, added) {
            Some(Ok(found)) => found,
            Some(Err(other)) => return Some(StrikeOutcome::OtherPeriod(other)),
            None => return Some(StrikeOutcome::NotFound),
        };
        let past = self.reanchor(past.clone()).unwrap_or(past);
        let grazing = self.locate_strike_by_param(last, &past, dir, k, n, gaps);
        let mut events = Vec::new();
        let e = Event {
            kind: EventKind::Grazing,
            param: grazing.param(self.settings.parameter),
            orbit: grazing,
            after_point: k_last,
            s: 0.0,
            multiplier_crossing: false,
            at_grazing: false,
            stable_before: last.orbit.is_stable(),
            stable_after: past.orbit.is_stable(),
            contact: Some(k),
            strikes: Some(n),
        };
        if (test_fold(last, gaps) > 0.0) != (test_fold(&past, gaps) > 0.0) {
            let mut fold = e.clone();
            fold.kind = EventKind::Fold;
            fold.at_grazing = true;
            events.push(fold);
        }
        events.push(e);
        Some(StrikeOutcome::Crossed(StrikeCrossing { events, past }))
    }

    /// The first orbit of one period that `added` takes, shot at fixed parameter values
    /// stepping from `last` in the direction `ahead` by 1e-4 of the largest parameter step,
    /// four times that, ... up to the largest step, then the other way, each on the maps over
    /// one to [`super::periods::MAX_PERIODS`] drive periods from `last`'s state: with its tangent and the
    /// direction it lies in. Where there is none, the first orbit of several periods found
    /// (`Err`); `None` when neither is found.
    fn shoot_strike(
        &mut self,
        last: &BranchPoint,
        ahead: f64,
        added: impl Fn(&Orbit) -> bool,
    ) -> Option<Result<(BranchPoint, f64), Orbit>> {
        let param = self.settings.parameter;
        let p0 = last.orbit.param(param);
        let max_step = self.settings.max_param_step;
        let mut other = None;
        for dir in [ahead, -ahead] {
            let mut step = 1e-4 * max_step;
            while step <= max_step {
                let f = last.orbit.forcing.with(param, p0 + dir * step);
                match self.shoot_periods(&f, &last.orbit, &added) {
                    Some(Shot::One(o)) => {
                        if let Some(p) = self.with_tangent(o, dir) {
                            return Some(Ok((p, dir)));
                        }
                    }
                    Some(Shot::Several(o)) if other.is_none() => other = Some(o),
                    _ => {}
                }
                step *= 4.0;
            }
        }
        other.map(Err)
    }

    /// The orbit nearest the grazing of contact `k` between `a` (striking it `n` times) and
    /// `b` (one more), on `a`'s side: bisection by the root finder on the parameter from `a`'s
    /// value towards `b`'s (in the direction `dir`), each trial shot at its fixed value from
    /// `a`'s state and else from `b`'s, on the strike test (`a`'s orbit if every trial fails).
    fn locate_strike_by_param(
        &mut self,
        a: &BranchPoint,
        b: &BranchPoint,
        dir: f64,
        k: usize,
        n: u32,
        gaps: Gaps,
    ) -> Orbit {
        let param = self.settings.parameter;
        let (pa, pb) = (a.orbit.param(param), b.orbit.param(param));
        let (Some(fa), Some(fb)) = (
            strike_test(&a.orbit, gaps, k, n),
            strike_test(&b.orbit, gaps, k, n),
        ) else {
            return a.orbit.clone();
        };
        let opts = RootOptions {
            f_tol: None,
            x_tol_abs: self.settings.locate_tol,
            x_tol_rel: 0.0,
            max_iter: 60,
        };
        let mut best = (a.orbit.clone(), 0.0);
        // The root finder's result is read from the samples kept here: a trial that fails
        // (no orbit, or another count of strikes) ends the search with the bracket reached.
        let _ = illinois(
            |d| -> Result<(f64, ()), ()> {
                let f = a.orbit.forcing.with(param, pa + dir * d);
                let phase = a.orbit.phase_rad;
                let o = [&a.orbit, &b.orbit]
                    .into_iter()
                    .find_map(|from| self.solve(&f, phase, from.state_n()).ok())
                    .ok_or(())?;
                let v = strike_test(&o, gaps, k, n).ok_or(())?;
                if v < 0.0 && d > best.1 {
                    best = (o, d);
                }
                Ok((v, ()))
            },
            Sample::new(0.0, fa, ()),
            Sample::new((pb - pa).abs(), fb, ()),
            &opts,
        );
        best.0
    }

    /// The grazings that add or remove a strike of a rigid contact between the accepted
    /// points `a` (index `k`) and `b` (at arclength `ds` along `a`'s tangent), each located by
    /// bisection on the arclength with its contact's strike test (at the trial nearest it on
    /// `a`'s side; at `a` if every trial fails).
    pub(super) fn strike_events(
        &mut self,
        k: usize,
        a: &BranchPoint,
        b: &BranchPoint,
        ds: f64,
    ) -> Vec<Event> {
        let gaps = Gaps::of(self.shooter.base);
        let mut out = Vec::new();
        for c in self.rigid_contacts() {
            let (na, nb) = (strikes(a, c), strikes(b, c));
            // A touch that starts or ends (no strike on one side) is the contact set's
            // grazing, reported by the grazing test; a jump by more than one strike is no
            // single grazing.
            if na.min(nb) == 0 || na.abs_diff(nb) != 1 {
                continue;
            }
            let n = na.min(nb);
            let (Some(fa), Some(fb)) = (
                strike_test(&a.orbit, gaps, c, n),
                strike_test(&b.orbit, gaps, c, n),
            ) else {
                continue;
            };
            let opts = RootOptions {
                f_tol: None,
                x_tol_abs: self.settings.locate_tol / self.settings.param_scale,
                x_tol_rel: 0.0,
                max_iter: 60,
            };
            let side_a = fa > 0.0;
            let mut best = (a.orbit.clone(), 0.0);
            let _ = illinois(
                |s| -> Result<(f64, ()), ()> {
                    let (p, _) = self.point_at(a, s).map_err(|_| ())?;
                    let v = strike_test(&p.orbit, gaps, c, n).ok_or(())?;
                    if (v > 0.0) == side_a && s > best.1 {
                        best = (p.orbit, s);
                    }
                    Ok((v, ()))
                },
                Sample::new(0.0, fa, ()),
                Sample::new(ds, fb, ()),
                &opts,
            );
            let (orbit, s) = best;
            out.push(Event {
                kind: EventKind::Grazing,
                param: orbit.param(self.settings.parameter),
                orbit,
                after_point: k,
                s,
                multiplier_crossing: false,
                at_grazing: false,
                stable_before: a.orbit.is_stable(),
                stable_after: b.orbit.is_stable(),
                contact: Some(c),
                strikes: Some(n),
            });
        }
        out
    }
}
