//! A stop's gap the data do not touch at the best refined fit. Where no orbit of the model
//! reaches a stop, nothing the model computes moves with that stop's gap (the orbits are kept
//! as they are, [`super::clear`]): the gap's column of the misfit's Jacobian is exactly zero
//! and Levenberg-Marquardt cannot move it, however far the data are from the model. A gap
//! beyond every orbit's reach lies on a plateau of the misfit whose edge is that reach, and
//! the optimum can lie just inside it, where the largest orbits (those at the top of a branch,
//! before its fold) start to strike the stop. When the best refined fit is improbable, such a
//! gap is tried at a ladder of values inside the edge, the others held, each trial on the
//! branches followed there from the fit's, rung by rung from the edge inwards (as steps of the
//! search would be, each an evaluation that costs a few periods per measured value), and the
//! lowest trial below the fit is refined as one more start.
//! A start whose gap lies beyond every orbit's reach is met the same way before it is refined:
//! the trial there is a descent along the one direction Levenberg-Marquardt cannot see, and the
//! refinement goes from the lowest trial below the start itself, where it can move that gap
//! back out if the data want it there (inside the reach its column is no longer zero).

use super::branch::SetModel;
use super::clear::CLEAR_REL;
use super::lm::LmResult;
use super::problem::Problem;
use crate::device::ParamRange;
use crate::laws::contact::Side;

/// The trials lie at `reach (1 - 2^-j)` for these `j`: a geometric ladder from within 1 % of
/// the edge to 12.5 % inside it, each step twice as deep as the last.
const LADDER: std::ops::RangeInclusive<i32> = 3..=7;

/// The parameters whose Jacobian column at the search's optimum `lm` is exactly zero (none when
/// the Jacobian is not the optimum's).
pub(super) fn untouched(lm: &LmResult) -> Vec<usize> {
    let j = &lm.jacobian;
    if !lm.jacobian_at_u {
        return Vec::new();
    }
    (0..j.ncols())
        .filter(|&k| j.column(k).iter().all(|&x| x == 0.0))
        .collect()
}

/// The sides whose gap the free parameter `path` is.
fn gap_sides(path: &str) -> &'static [Side] {
    match path {
        "stops.upper.gap_m" => &[Side::Upper],
        "stops.lower.gap_m" => &[Side::Lower],
        "stops.both.gap_m" => &[Side::Upper, Side::Lower],
        _ => &[],
    }
}

/// The gap parameters among `free` (at the values `p`) that lie beyond every orbit of
/// `states` by more than the margin at which orbits are kept ([`CLEAR_REL`]): those whose
/// column of the misfit's Jacobian there is exactly zero.
pub(super) fn beyond_reach(free: &[ParamRange], p: &[f64], states: &[SetModel]) -> Vec<usize> {
    (0..free.len())
        .filter(|&k| {
            let sides = gap_sides(&free[k].path);
            !sides.is_empty()
                && sides.iter().all(|&side| {
                    states
                        .iter()
                        .all(|s| s.reach_m(side) < p[k] * (1.0 - CLEAR_REL))
                })
        })
        .collect()
}

/// The lowest trial of the gaps `gaps` (indices into the problem's free parameters) moved
/// inside the reach of the orbits `states` at `u`, the other parameters held, with its SSR,
/// the parameter's index and the branches followed there, when it lies below `ssr`, the SSR
/// at `u`; a rung where the branches are lost is skipped. The rungs of a gap are taken from
/// the edge inwards, each followed from the last one reached (from `u` and `states` for the
/// first): a homotopy in the gap, each rung's orbits found by Newton's method from those of a
/// nearby gap rather than of the start's.
pub(super) fn lower_trial(
    pb: &Problem<'_>,
    u: &[f64],
    gaps: &[usize],
    states: &[SetModel],
    ssr: f64,
) -> Option<(Vec<f64>, f64, usize, Vec<SetModel>)> {
    let (free, tr) = (pb.free, &pb.tr);
    let mut best: Option<(Vec<f64>, f64, usize, Vec<SetModel>)> = None;
    for &k in gaps
        .iter()
        .filter(|&&k| !gap_sides(&free[k].path).is_empty())
    {
        let f = &free[k];
        let reach = gap_sides(&f.path)
            .iter()
            .flat_map(|&side| states.iter().map(move |s| s.reach_m(side)))
            .fold(0.0, f64::max);
        let mut from: (Vec<f64>, Vec<SetModel>) = (u.to_vec(), states.to_vec());
        for j in LADDER.rev() {
            let gap = reach * (1.0 - 0.5f64.powi(j));
            if !(f.lo < gap && gap < f.hi) {
                continue;
            }
            let mut v = u.to_vec();
            v[k] = tr[k].to_u(gap);
            let Some((c, followed)) = pb.followed_ssr(&v, &from.0, &from.1) else {
                continue;
            };
            if c < ssr && best.as_ref().is_none_or(|b| c < b.1) {
                best = Some((v.clone(), c, k, followed.clone()));
            }
            from = (v, followed);
        }
    }
    best
}
