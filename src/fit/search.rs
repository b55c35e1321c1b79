//! The global search of a fit: a design of starts ranked by a cheap model (the stepped sweep
//! with short blocks), the best few refined from one start each ([`super::start`]), and a
//! gap left beyond every orbit's reach tried inside it ([`super::untouched`]); see the parent
//! module's docs.
//!
//! The module reads better whole: the design's ranking stops a start's cheap sweep by the
//! cost of the starts the loop will refine, which its test checks against whole sweeps beside
//! them.

use super::model::design_values;
use super::params::{apply, Transform};
use super::problem::{Problem, Run};
use super::report::{Refined, StartOrigin, StartTried};
use super::start::search_from;
use super::untouched;
use super::{FitError, FitSettings, STATED_COST_ABS_TOL};
use rayon::prelude::*;
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
    let refined = |run: &Run| Refined {
        ssr: run.ssr(),
        settled: run.settled(),
        values: pb.to_p(&run.lm.u),
    };
    let untouched_start = |from: usize, u: &[f64], k: usize, of_fit: bool, run: &Run| StartTried {
        origin: StartOrigin::Untouched {
            from,
            param: pb.free[k].path.clone(),
            of_fit,
        },
        values: pb.to_p(u),
        design_ssr: f64::NAN,
        design_cut: false,
        refined: Some(refined(run)),
    };
    for i in order {
        // A gap beyond every orbit's reach at the start is tried inside it first
        // ([`untouched`]); the refinement goes from the lowest trial below the start.
        let identified = pb.identify(&us[i]);
        let inside = identified.as_ref().ok().and_then(|states| {
            let gaps = untouched::beyond_reach(pb.free, &pb.to_p(&us[i]), states);
            let ssr: f64 = pb.residuals_of(states).iter().map(|r| r * r).sum();
            untouched::lower_trial(pb, &us[i], &gaps, states, ssr)
        });
        let (u0, identified, moved_at) = match inside {
            Some((u, _, k, states)) => (u, Ok(states), Some(k)),
            None => (us[i].clone(), identified, None),
        };
        let run = match search_from(pb, &u0, identified, &lm, chi2_limit) {
            Ok(run) => run,
            Err(e) => {
                last_err = Some(e);
                continue;
            }
        };
        let j = match moved_at {
            Some(k) => {
                starts.push(untouched_start(i, &u0, k, false, &run));
                starts.len() - 1
            }
            None => {
                starts[i].refined = Some(refined(&run));
                i
            }
        };
        // A gap this fit leaves beyond every orbit's reach, tried inside it before the next
        // start.
        let moved = improbable(&run)
            .then(|| {
                let gaps = untouched::untouched(&run.lm);
                if gaps.is_empty() {
                    return None;
                }
                let states = match &run.identified {
                    Some(states) => states.clone(),
                    None => pb.identify(&run.lm.u).ok()?,
                };
                untouched::lower_trial(pb, &run.lm.u, &gaps, &states, run.ssr())
            })
            .flatten()
            .and_then(|(u, _, k, states)| {
                let next = search_from(pb, &u, Ok(states), &lm, chi2_limit).ok()?;
                Some((next, u, k))
            });
        let mut runs = vec![(run, j)];
        if let Some((next, u, k)) = moved {
            starts.push(untouched_start(j, &u, k, true, &next));
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
