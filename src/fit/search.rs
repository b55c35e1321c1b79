//! The search of a fit: the misfit on the branches ([`super::branch`]) or, where they cannot
//! be identified, on the stepped sweep ([`super::model`]); the rounds of one start; and the
//! global search, a design of starts ranked by a cheap model with the best few refined (see
//! the parent module's docs).
//!
//! The module reads better whole: the global search is the loop over the rounds of one start
//! (a refined start, its fallback to the stepped sweep, and the trial of a gap left beyond
//! every orbit's reach all return the same `Run` on the same `Problem`), and the design's
//! ranking stops a start's cheap sweep by the cost of the starts the loop will refine, which
//! its test checks against whole sweeps beside them.

use super::branch::{self, SetModel};
use super::lm::{
    self, levenberg_marquardt_resumed, levenberg_marquardt_tracked, LmResult, LmSettings, Tracked,
};
use super::model::design_values;
use super::params::{apply, Transform};
use super::report::{Refined, StartOrigin, StartTried};
use super::untouched;
use super::{
    model_values, FitError, FitSettings, SweepData, AGREE_REL, AGREE_SIGMA, MAX_ROUNDS,
    STATED_COST_ABS_TOL,
};
use crate::device::{Device, ParamRange};
use rayon::prelude::*;

/// What every evaluation needs: the device, the data, the free parameters with their
/// transforms, and the measured values with their weights.
pub(super) struct Problem<'a> {
    pub(super) device: &'a Device,
    pub(super) data: &'a [SweepData],
    pub(super) free: &'a [ParamRange],
    pub(super) tr: Vec<Transform>,
    pub(super) y: Vec<f64>,
    pub(super) sigma: Vec<f64>,
    /// Which measured values state their standard deviation (features always do).
    pub(super) stated: Vec<bool>,
}

impl Problem<'_> {
    pub(super) fn to_p(&self, u: &[f64]) -> Vec<f64> {
        self.tr.iter().zip(u).map(|(t, &u)| t.to_p(u)).collect()
    }

    fn weighted(&self, m: &[f64]) -> Vec<f64> {
        m.iter()
            .zip(&self.y)
            .zip(&self.sigma)
            .map(|((m, y), s)| (m - y) / s)
            .collect()
    }

    /// The branches of every data set identified afresh at `u`.
    fn identify(&self, u: &[f64]) -> Result<Vec<SetModel>, FitError> {
        let (d, scale) = apply(self.device, self.free, &self.to_p(u))?;
        self.data
            .iter()
            .map(|ds| branch::identify(&d, scale, ds).map_err(|l| FitError::Lost(l.0)))
            .collect()
    }

    /// The weighted SSR on the branches identified afresh at `u`.
    fn branch_ssr(&self, u: &[f64]) -> Result<f64, FitError> {
        let states = self.identify(u)?;
        Ok(self.residuals_of(&states).iter().map(|r| r * r).sum())
    }

    /// The weighted residuals of the models `states` (without following them).
    fn residuals_of(&self, states: &[SetModel]) -> Vec<f64> {
        let m: Vec<f64> = self
            .data
            .iter()
            .zip(states)
            .flat_map(|(ds, s)| s.values(ds))
            .collect();
        self.weighted(&m)
    }

    /// The largest difference between two sets of weighted residuals in units of its
    /// tolerance ([`AGREE_SIGMA`] standard deviations, or [`AGREE_REL`] of the value); at most
    /// 1 when they agree.
    fn disagreement(&self, a: &[f64], b: &[f64]) -> f64 {
        a.iter()
            .zip(b)
            .enumerate()
            .map(|(i, (a, b))| {
                let tol = if self.stated[i] {
                    AGREE_SIGMA
                } else {
                    AGREE_REL * self.y[i].abs() / self.sigma[i]
                };
                let d = (a - b).abs() / tol;
                if d.is_nan() {
                    f64::INFINITY
                } else {
                    d
                }
            })
            .fold(0.0, f64::max)
    }
}

/// The misfit on the branches, followed from the accepted point's.
struct OnBranches<'a, 'b>(&'a Problem<'b>);

impl Tracked for OnBranches<'_, '_> {
    type State = Vec<SetModel>;
    type Error = FitError;

    fn residuals(
        &self,
        u: &[f64],
        from: &Vec<SetModel>,
    ) -> Result<(Vec<f64>, Vec<SetModel>), FitError> {
        let pb = self.0;
        let (d, scale) = apply(pb.device, pb.free, &pb.to_p(u))?;
        let states = pb
            .data
            .iter()
            .zip(from)
            .map(|(ds, prev)| branch::track(&d, scale, ds, prev).map_err(|l| FitError::Lost(l.0)))
            .collect::<Result<Vec<_>, _>>()?;
        Ok((pb.residuals_of(&states), states))
    }
}

/// Which model a search used.
#[derive(Debug, Clone, PartialEq)]
pub(super) enum Used {
    /// The branches; `disagreement` is that of the last fresh identification (at most 1: they
    /// agree), `None` when it failed.
    Branches {
        disagreement: Option<f64>,
        rounds: usize,
    },
    /// The stepped sweep, because the branches could not be identified.
    SteppedSweep { why: String },
}

/// The outcome of the search from one start.
pub(super) struct Run {
    pub(super) lm: LmResult,
    pub(super) used: Used,
    /// Evaluations of every round (the fresh identifications not counted).
    pub(super) evaluations: usize,
    /// Iterations of every round.
    pub(super) iterations: usize,
}

impl Run {
    pub(super) fn ssr(&self) -> f64 {
        self.lm.residuals.iter().map(|r| r * r).sum()
    }

    /// True when the search converged, on branches that agree with the ones identified afresh
    /// or on the stepped sweep (which has nothing to agree with).
    pub(super) fn settled(&self) -> bool {
        self.lm.stop.converged()
            && match self.used {
                Used::Branches { disagreement, .. } => disagreement.is_some_and(|d| d <= 1.0),
                Used::SteppedSweep { .. } => true,
            }
    }
}

/// The search from `u0`: on the branches, identified there and afresh after each round while
/// they differ; where they cannot be identified there, on the stepped sweep until it is near
/// its optimum and on the branches from there ([`stepped`]).
pub(super) fn search_from(
    pb: &Problem<'_>,
    u0: &[f64],
    settings: &LmSettings,
) -> Result<Run, FitError> {
    match pb.identify(u0) {
        Ok(states) => on_branches(pb, u0, states, settings),
        Err(e) => stepped(pb, u0, settings, e.to_string()),
    }
}

/// The rounds of the search on the branches from `u0`, whose branches `states` are
/// identified there.
fn on_branches(
    pb: &Problem<'_>,
    u0: &[f64],
    states: Vec<SetModel>,
    settings: &LmSettings,
) -> Result<Run, FitError> {
    let mut states = states;
    let mut u = u0.to_vec();
    let (mut evaluations, mut iterations) = (0, 0);
    for round in 1..=MAX_ROUNDS {
        let r0 = pb.residuals_of(&states);
        let (lm, followed) =
            levenberg_marquardt_tracked(&OnBranches(pb), &u, states, Some(r0), settings)?;
        evaluations += lm.evaluations;
        iterations += lm.iterations;
        let fresh = pb.identify(&lm.u);
        let disagreement = fresh
            .as_ref()
            .ok()
            .map(|f| pb.disagreement(&pb.residuals_of(f), &pb.residuals_of(&followed)));
        let done = disagreement.is_none_or(|d| d <= 1.0) || round == MAX_ROUNDS;
        if done {
            return Ok(Run {
                lm,
                used: Used::Branches {
                    disagreement,
                    rounds: round,
                },
                evaluations,
                iterations,
            });
        }
        states = fresh.expect("checked above");
        u = lm.u;
    }
    unreachable!("the last round returns")
}

/// The stepped-sweep search hands over to the branches once an accepted step lowers its cost
/// by less than this fraction: near a minimum of chi-square `c` a step that lowers it by
/// `1e-2 c` lies within about `sqrt(1e-2 c)` standard errors of it (`c` of the order of the
/// degrees of freedom), close enough for Newton's method to identify the branches the data
/// follow, where the start may lie in a region without them (a response that is not periodic
/// below the onset of impacts).
pub(super) const HANDOVER_COST_REL_TOL: f64 = 1e-2;

/// The search on the stepped sweep (the model of [`super::model`]) from `u0`, where the
/// branches cannot be identified (`why`): a loose search ([`HANDOVER_COST_REL_TOL`]) to near
/// its optimum, then the branches from there when they can be identified and their search
/// settles no worse than the stepped sweep's (each stepped evaluation costs a whole sweep to a
/// tight steady state, each on the branches a few periods per measured value); else the
/// stepped search carried on to its own tolerances where the loose one stopped short of them.
fn stepped(
    pb: &Problem<'_>,
    u0: &[f64],
    settings: &LmSettings,
    why: String,
) -> Result<Run, FitError> {
    let tight = LmSettings {
        fd_step: settings.fd_step.max(lm::STEPPED_FD_STEP),
        ..*settings
    };
    // The Jacobian where the loose search converges serves only a search carried on there
    // (each of its columns a whole sweep): it is differenced when the branches do not take
    // over.
    let loose = LmSettings {
        cost_rel_tol: tight.cost_rel_tol.max(HANDOVER_COST_REL_TOL),
        jacobian_at_stop: false,
        ..tight
    };
    let (mut near, last) =
        levenberg_marquardt_tracked(&Stepped(pb), u0, Costs::none(), None, &loose)?;
    let near_ssr = last.here;
    if let Ok(states) = pb.identify(&near.u) {
        if let Ok(mut run) = on_branches(pb, &near.u, states, settings) {
            run.evaluations += near.evaluations;
            run.iterations += near.iterations;
            if run.settled() && run.ssr() <= near_ssr {
                return Ok(run);
            }
        }
    }
    if !near.jacobian_at_u {
        near.jacobian = lm::jacobian(&Stepped(pb), &near.u, &near.residuals, &last, tight.fd_step)?;
        near.evaluations += pb.free.len();
        near.jacobian_at_u = true;
    }
    // The loose search stopped where the tight one would not have: carry it on from its
    // point, Jacobian and damping, so that it takes the tight search's own steps.
    let drop = last.before - last.here;
    let step = last
        .u_here
        .iter()
        .zip(&last.u_before)
        .map(|(a, b)| (a - b) * (a - b))
        .sum::<f64>()
        .sqrt();
    let loose_stop = near.stop == lm::Termination::CostConverged
        && !(drop < tight.cost_rel_tol * last.before || drop < tight.cost_abs_tol);
    let short = loose_stop && step >= tight.step_tol;
    let lm = if short {
        let (r0, j0) = (near.residuals.clone(), near.jacobian.clone());
        let rest = LmSettings {
            lambda0: near.lambda,
            max_iter: tight.max_iter.saturating_sub(near.iterations),
            ..tight
        };
        let (more, _) = levenberg_marquardt_resumed(&Stepped(pb), &near.u, last, r0, j0, &rest)?;
        LmResult {
            evaluations: near.evaluations + more.evaluations - 1,
            iterations: near.iterations + more.iterations,
            failed_trials: near.failed_trials + more.failed_trials,
            ..more
        }
    } else if loose_stop {
        // Where the tight search stops by the step's length.
        LmResult {
            stop: lm::Termination::StepConverged,
            ..near
        }
    } else {
        near
    };
    Ok(Run {
        evaluations: lm.evaluations,
        iterations: lm.iterations,
        lm,
        used: Used::SteppedSweep { why },
    })
}

/// The weighted SSR and the point of an evaluation and of the accepted point it was evaluated
/// from: what the stepped search carries, so that the last accepted step's decrease and length
/// are known.
#[derive(Debug, Clone, PartialEq)]
struct Costs {
    here: f64,
    before: f64,
    u_here: Vec<f64>,
    u_before: Vec<f64>,
}

impl Costs {
    fn none() -> Costs {
        Costs {
            here: f64::NAN,
            before: f64::NAN,
            u_here: Vec::new(),
            u_before: Vec::new(),
        }
    }
}

/// The misfit on the stepped sweep.
struct Stepped<'a, 'b>(&'a Problem<'b>);

impl Tracked for Stepped<'_, '_> {
    type State = Costs;
    type Error = FitError;

    fn residuals(&self, u: &[f64], from: &Costs) -> Result<(Vec<f64>, Costs), FitError> {
        let pb = self.0;
        let (d, scale) = apply(pb.device, pb.free, &pb.to_p(u))?;
        let mut m = Vec::with_capacity(pb.y.len());
        for ds in pb.data {
            m.extend(model_values(&d, scale, ds)?);
        }
        let r = pb.weighted(&m);
        let here = r.iter().map(|x| x * x).sum();
        Ok((
            r,
            Costs {
                here,
                before: from.here,
                u_here: u.to_vec(),
                u_before: from.u_here.clone(),
            },
        ))
    }
}

/// The point `k` (from 1) of the Sobol sequence in the transformed box: each parameter's
/// range with a twentieth cut off at either end (a start at an end would sit where the
/// transform is flat).
fn sobol_start(tr: &[Transform], k: usize) -> Vec<f64> {
    tr.iter()
        .enumerate()
        .map(|(d, t)| {
            let s = f64::from(sobol_burley::sample(k as u32, d as u32, 0x5eed));
            t.to_u_frac(0.05 + 0.9 * s)
        })
        .collect()
}

/// A partial SSR counts as above a bound only when it exceeds it by this relative margin: the
/// partial and the whole SSR sum their terms in different orders, and the rounding of a sum of
/// n non-negative terms stays below n times the unit roundoff (1.1e-16), far below this margin
/// for any data set (at most 100 000 points, [`crate::study::sweep::MAX_STEPS`]).
const PARTIAL_SSR_MARGIN: f64 = 1e-9;

/// The cheap model's cost at a design point.
enum DesignCost {
    /// The weighted SSR (infinite where the model cannot be evaluated).
    Whole(f64),
    /// The sweeps were stopped once the weighted SSR of the points swept so far (this value,
    /// a lower bound of the whole) exceeded the bound.
    Cut(f64),
}

/// The weighted SSR of the cheap model ([`design_values`]) at `u`, its sweeps stopped as soon
/// as the SSR of the points they have fixed exceeds `bound()` (called at each point: the
/// bound may fall while the sweeps run).
fn design_ssr(pb: &Problem<'_>, u: &[f64], bound: &dyn Fn() -> f64) -> DesignCost {
    let mut partial = 0.0;
    let eval = |partial: &mut f64| -> Result<DesignCost, FitError> {
        let (d, scale) = apply(pb.device, pb.free, &pb.to_p(u))?;
        let mut m = Vec::with_capacity(pb.y.len());
        for ds in pb.data {
            let offset = m.len();
            let mut on_point = |j: usize, value: f64| {
                let r = (value - pb.y[offset + j]) / pb.sigma[offset + j];
                *partial += r * r;
                *partial * (1.0 - PARTIAL_SSR_MARGIN) > bound()
            };
            let Some(values) = design_values(&d, scale, ds, &mut on_point)? else {
                return Ok(DesignCost::Cut(*partial));
            };
            m.extend(values);
        }
        let c: f64 = pb.weighted(&m).iter().map(|r| r * r).sum();
        Ok(DesignCost::Whole(c))
    };
    match eval(&mut partial) {
        Ok(DesignCost::Whole(c)) if c.is_finite() => DesignCost::Whole(c),
        Ok(DesignCost::Cut(c)) => DesignCost::Cut(c),
        _ => DesignCost::Whole(f64::INFINITY),
    }
}

/// The `k`-th smallest of `costs` (from 1), infinite when there are fewer.
fn kth_smallest(costs: &[f64], k: usize) -> f64 {
    let mut sorted = costs.to_vec();
    sorted.sort_by(f64::total_cmp);
    sorted
        .get(k.wrapping_sub(1))
        .copied()
        .unwrap_or(f64::INFINITY)
}

/// The design's costs at `us`, the sweeps of a point stopped once the SSR of its points so far
/// exceeds the `keep`-th smallest whole cost found so far: such a point is ranked after the
/// `keep` best whatever the rest of its sweeps, so the best `keep` and their costs are those
/// of the whole sweeps, whatever the order in which the points are evaluated.
fn design_costs(pb: &Problem<'_>, us: &[Vec<f64>], keep: usize) -> Vec<DesignCost> {
    let whole = std::sync::Mutex::new(Vec::<f64>::new());
    let bound = || kth_smallest(&whole.lock().unwrap_or_else(|e| e.into_inner()), keep);
    us.par_iter()
        .map(|u| {
            let cost = design_ssr(pb, u, &bound);
            if let DesignCost::Whole(c) = cost {
                if c.is_finite() {
                    whole.lock().unwrap_or_else(|e| e.into_inner()).push(c);
                }
            }
            cost
        })
        .collect()
}

/// The indices of the best `keep` of the design's costs `ssr`, best first, among those whose
/// cheap model could be evaluated (the first, the device's values, when there is none, or no
/// design).
fn best_ranked(ssr: &[f64], keep: usize) -> Vec<usize> {
    let mut order: Vec<usize> = (0..ssr.len())
        .filter(|&i| ssr.len() == 1 || ssr[i].is_finite())
        .collect();
    order.sort_by(|&a, &b| ssr[a].total_cmp(&ssr[b]));
    order.truncate(keep);
    if order.is_empty() {
        order.push(0);
    }
    order
}

/// The searches of a fit: the design (the device's values and [`FitSettings::design_points`] points
/// of a Sobol sequence) ranked by the cheap model's SSR, then the best
/// [`FitSettings::refine`] refined by Levenberg-Marquardt in that order, stopping early at a
/// refined start that settles with a chi-square within `chi2_limit` (when the standard
/// deviations are stated). Returns the best refined run (settled first, then the smallest SSR),
/// every start with what became of it, and the index of the best among them.
pub(super) fn search(
    pb: &Problem<'_>,
    u_file: &[f64],
    settings: &FitSettings,
    all_stated: bool,
    chi2_limit: Option<f64>,
) -> Result<(Run, Vec<StartTried>, usize), FitError> {
    let mut lm = settings.lm;
    if all_stated {
        lm.cost_abs_tol = lm.cost_abs_tol.max(STATED_COST_ABS_TOL);
    }
    let us: Vec<Vec<f64>> = std::iter::once(u_file.to_vec())
        .chain((1..=settings.design_points(pb.free.len())).map(|k| sobol_start(&pb.tr, k)))
        .collect();
    let mut starts: Vec<StartTried> = us
        .iter()
        .enumerate()
        .map(|(i, u)| StartTried {
            origin: if i == 0 {
                StartOrigin::DeviceFile
            } else {
                StartOrigin::Sobol(i)
            },
            values: pb.to_p(u),
            design_ssr: f64::NAN,
            design_cut: false,
            refined: None,
        })
        .collect();
    // One design point alone (no design) is refined without being ranked.
    if starts.len() > 1 {
        let costs = design_costs(pb, &us, settings.refine.max(1));
        for (s, cost) in starts.iter_mut().zip(costs) {
            match cost {
                DesignCost::Whole(c) => {
                    s.design_ssr = c;
                }
                DesignCost::Cut(c) => {
                    s.design_ssr = c;
                    s.design_cut = true;
                }
            }
        }
    }
    let ssr: Vec<f64> = starts.iter().map(|s| s.design_ssr).collect();
    let order = best_ranked(&ssr, settings.refine.max(1));
    let mut best: Option<(Run, usize)> = None;
    let mut last_err = None;
    let good = |r: &Run| r.settled() && chi2_limit.is_some_and(|l| r.ssr() <= l);
    let improbable = |r: &Run| chi2_limit.is_some_and(|l| r.ssr() > l);
    for i in order {
        let run = match search_from(pb, &us[i], &lm) {
            Ok(run) => run,
            Err(e) => {
                last_err = Some(e);
                continue;
            }
        };
        starts[i].refined = Some(Refined {
            ssr: run.ssr(),
            settled: run.settled(),
            values: pb.to_p(&run.lm.u),
        });
        // A gap this fit leaves beyond every orbit's reach, tried inside it
        // ([`untouched`]) before the next start.
        let moved = improbable(&run)
            .then(|| {
                untouched::lower_trial(
                    pb.free,
                    &pb.tr,
                    &run.lm,
                    run.ssr(),
                    |u| pb.identify(u).ok(),
                    |u| pb.branch_ssr(u).ok(),
                )
            })
            .flatten()
            .and_then(|(u, _, k)| Some((search_from(pb, &u, &lm).ok()?, u, k)));
        let mut runs = vec![(run, i)];
        if let Some((next, u, k)) = moved {
            starts.push(StartTried {
                origin: StartOrigin::Untouched {
                    from: i,
                    param: pb.free[k].path.clone(),
                },
                values: pb.to_p(&u),
                design_ssr: f64::NAN,
                design_cut: false,
                refined: Some(Refined {
                    ssr: next.ssr(),
                    settled: next.settled(),
                    values: pb.to_p(&next.lm.u),
                }),
            });
            runs.push((next, starts.len() - 1));
        }
        let mut done = false;
        for (run, j) in runs {
            done |= good(&run);
            let better = best
                .as_ref()
                .is_none_or(|(b, _)| (run.settled(), -run.ssr()) > (b.settled(), -b.ssr()));
            if better {
                best = Some((run, j));
            }
        }
        if done {
            break;
        }
    }
    match best {
        Some((run, i)) => Ok((run, starts, i)),
        None => Err(last_err.unwrap_or_else(|| {
            FitError::Lost("the model could not be evaluated at any start of the design".into())
        })),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::family::recovery_family;
    use crate::fit::{check_free, measured, REFINE_DEFAULT};

    /// The design of recovery-family case `case` (from 1) ranked with its sweeps stopped
    /// early and with every sweep whole: the starts kept for refinement must be the same, in
    /// the same order, with bit-identical costs, and each stopped start's partial SSR must be
    /// a lower bound of its whole SSR above the last kept one's. Returns how many were stopped.
    fn cut_ranking_matches_whole(case: usize) -> usize {
        let c = &recovery_family()[case - 1];
        let (data, start) = (c.data().unwrap(), c.start_device().unwrap());
        let tr: Vec<Transform> = c.free.iter().map(Transform::of).collect();
        let u0: Vec<f64> = tr
            .iter()
            .zip(check_free(&start, &c.free).unwrap())
            .map(|(t, v)| t.to_u(v))
            .collect();
        let (y, sigma, stated) = measured(&data);
        let pb = Problem {
            device: &start,
            data: &data,
            free: &c.free,
            tr,
            y,
            sigma,
            stated,
        };
        let us: Vec<Vec<f64>> = std::iter::once(u0)
            .chain(
                (1..=FitSettings::default().design_points(c.free.len()))
                    .map(|k| sobol_start(&pb.tr, k)),
            )
            .collect();
        let ssr_of = |costs: &[DesignCost]| -> Vec<f64> {
            costs
                .iter()
                .map(|d| match d {
                    DesignCost::Whole(c) | DesignCost::Cut(c) => *c,
                })
                .collect()
        };
        let cut_costs = design_costs(&pb, &us, REFINE_DEFAULT);
        let cut = ssr_of(&cut_costs);
        let whole_costs = design_costs(&pb, &us, usize::MAX);
        assert!(whole_costs
            .iter()
            .all(|d| matches!(d, DesignCost::Whole(..))));
        let whole = ssr_of(&whole_costs);
        let (kept_cut, kept_whole) = (
            best_ranked(&cut, REFINE_DEFAULT),
            best_ranked(&whole, REFINE_DEFAULT),
        );
        assert_eq!(kept_cut, kept_whole, "{}", c.name);
        let last_kept = whole[*kept_whole.last().unwrap()];
        let mut stopped = 0;
        for (i, (a, b)) in cut.iter().zip(&whole).enumerate() {
            if let DesignCost::Whole(..) = cut_costs[i] {
                assert_eq!(a.to_bits(), b.to_bits(), "{}: start {i}", c.name);
            } else {
                // The margin of the comparison covers the different order of summation.
                stopped += 1;
                assert!(!kept_whole.contains(&i), "{}: start {i}", c.name);
                assert!(
                    *a <= *b * (1.0 + PARTIAL_SSR_MARGIN),
                    "{}: start {i}",
                    c.name
                );
                assert!(*a > last_kept, "{}: start {i}", c.name);
            }
        }
        stopped
    }

    #[test]
    fn stopping_the_design_sweeps_early_keeps_the_same_starts() {
        // One case of the family (a cheap one) in every run, where the design stops sweeps.
        assert!(cut_ranking_matches_whole(19) > 0);
    }

    /// The two slow cases of the family whose designs stop the most sweeps (13 and 16: 4 and 5
    /// of 13 in the cost harness), about two minutes; every case takes some forty, too long
    /// for CI's ignored tests.
    #[test]
    #[ignore = "about two minutes on 2 cores; CI runs it with the ignored tests"]
    fn stopping_the_design_sweeps_early_keeps_the_same_starts_in_the_slow_cases() {
        for case in [13, 16] {
            assert!(
                cut_ranking_matches_whole(case) > 0,
                "case {case}: no sweep stopped"
            );
        }
    }
}
