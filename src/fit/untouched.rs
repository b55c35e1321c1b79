//! A stop's gap the data do not touch at the best refined fit. Where no orbit of the model
//! reaches a stop, nothing the model computes moves with that stop's gap (the orbits are kept
//! as they are, [`super::clear`]): the gap's column of the misfit's Jacobian is exactly zero
//! and Levenberg-Marquardt cannot move it, however far the data are from the model. A gap
//! beyond every orbit's reach lies on a plateau of the misfit whose edge is that reach, and
//! the optimum can lie just inside it, where the largest orbits (those at the top of a branch,
//! before its fold) start to strike the stop. When the best refined fit is improbable, such a
//! gap is tried at a ladder of values inside the edge, the others held, each trial on the
//! branches identified there, and the lowest trial below the fit is refined as one more start.

use super::branch::SetModel;
use super::lm::LmResult;
use super::params::Transform;
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

/// The lowest trial of an untouched gap at the search's optimum `lm` (of the free parameters
/// `free` with their transforms `tr`), with its SSR and the parameter's index, when it lies
/// below `ssr`, the optimum's. `identify` gives the branches identified at a point, `ssr_at`
/// the SSR on the branches identified there.
pub(super) fn lower_trial(
    free: &[ParamRange],
    tr: &[Transform],
    lm: &LmResult,
    ssr: f64,
    identify: impl Fn(&[f64]) -> Option<Vec<SetModel>>,
    ssr_at: impl Fn(&[f64]) -> Option<f64>,
) -> Option<(Vec<f64>, f64, usize)> {
    let gaps: Vec<usize> = untouched(lm)
        .into_iter()
        .filter(|&k| !gap_sides(&free[k].path).is_empty())
        .collect();
    if gaps.is_empty() {
        return None;
    }
    let states = identify(&lm.u)?;
    let mut best: Option<(Vec<f64>, f64, usize)> = None;
    for k in gaps {
        let f = &free[k];
        let reach = gap_sides(&f.path)
            .iter()
            .flat_map(|&side| states.iter().map(move |s| s.reach_m(side)))
            .fold(0.0, f64::max);
        for j in LADDER {
            let gap = reach * (1.0 - 0.5f64.powi(j));
            if !(f.lo < gap && gap < f.hi) {
                continue;
            }
            let mut u = lm.u.clone();
            u[k] = tr[k].to_u(gap);
            let Some(trial) = ssr_at(&u) else {
                continue;
            };
            if trial < ssr && best.as_ref().is_none_or(|b| trial < b.1) {
                best = Some((u, trial, k));
            }
        }
    }
    best
}
