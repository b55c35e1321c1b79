//! A stop's gap the data do not touch at the best refined fit. Where no orbit of the model
//! reaches a stop, nothing the model computes moves with that stop's gap (the orbits are kept
//! as they are, [`super::clear`]): the gap's column of the misfit's Jacobian is exactly zero
//! and Levenberg-Marquardt cannot move it, however far the data are from the model. A gap
//! beyond every orbit's reach lies on a plateau of the misfit whose edge is that reach, and
//! the optimum can lie just inside it, where the largest orbits (those at the top of a branch,
//! before its fold) start to strike the stop. When the best refined fit is improbable, such a
//! gap is tried at a ladder of values inside the edge, the others held, each trial on the
//! branches identified there, and the lowest trial below the fit is refined as one more start.

use super::search::{Problem, Run};
use crate::laws::contact::Side;

/// The trials lie at `reach (1 - 2^-j)` for these `j`: a geometric ladder from within 1 % of
/// the edge to 12.5 % inside it, each step twice as deep as the last.
const LADDER: std::ops::RangeInclusive<i32> = 3..=7;

/// The parameters whose Jacobian column at the run's optimum is exactly zero (none when the
/// Jacobian is not the optimum's).
pub(super) fn untouched(run: &Run) -> Vec<usize> {
    let j = &run.lm.jacobian;
    if !run.lm.jacobian_at_u {
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

/// The lowest trial of an untouched gap of `run` with its SSR and the parameter's index, when
/// it lies below the run's SSR.
pub(super) fn lower_trial(pb: &Problem<'_>, run: &Run) -> Option<(Vec<f64>, f64, usize)> {
    let gaps: Vec<usize> = untouched(run)
        .into_iter()
        .filter(|&k| !gap_sides(&pb.free[k].path).is_empty())
        .collect();
    if gaps.is_empty() {
        return None;
    }
    let states = pb.identify(&run.lm.u).ok()?;
    let mut best: Option<(Vec<f64>, f64, usize)> = None;
    for k in gaps {
        let f = &pb.free[k];
        let reach = gap_sides(&f.path)
            .iter()
            .flat_map(|&side| states.iter().map(move |s| s.reach_m(side)))
            .fold(0.0, f64::max);
        for j in LADDER {
            let gap = reach * (1.0 - 0.5f64.powi(j));
            if !(f.lo < gap && gap < f.hi) {
                continue;
            }
            let mut u = run.lm.u.clone();
            u[k] = pb.tr[k].to_u(gap);
            let Ok(ssr) = pb.branch_ssr(&u) else {
                continue;
            };
            if ssr < run.ssr() && best.as_ref().is_none_or(|b| ssr < b.1) {
                best = Some((u, ssr, k));
            }
        }
    }
    best
}
