//! Guard probing and event location on the dense output of one accepted step.
//!
//! The guards of the step's mode are evaluated at theta = 0 (the step's start) and at the
//! probes theta = 1/3, 2/3 and 1. For each guard, the first probe where it is positive gives a
//! bracket (previous probe, that probe), and the crossing is located on the dense output by the
//! crate's one root finder, [`crate::num::roots::illinois`], to the event time tolerance. The
//! earliest crossing over all guards is the event.

use std::convert::Infallible;

use crate::num::roots::{illinois, RootOptions, Sample};
use crate::ode::{HybridSystem, Step, MAX_GUARDS};

/// Interior probe points of a step (theta = (t - t0)/h), the end included.
pub(crate) const PROBES: [f64; 3] = [1.0 / 3.0, 2.0 / 3.0, 1.0];

/// Largest number of guard evaluations spent locating one crossing.
const MAX_LOCATE_EVALS: usize = 200;

/// The guards of `mode` on the dense output of `step` at `theta` (the stored end state at 1).
fn guards_at<S: HybridSystem<N>, const N: usize>(
    sys: &S,
    mode: S::Mode,
    step: &Step<N>,
    theta: f64,
) -> [f64; MAX_GUARDS] {
    let y = if theta == 1.0 {
        step.y1
    } else if theta == 0.0 {
        step.y0
    } else {
        step.at_theta(theta)
    };
    sys.guards(mode, step.t0 + theta * step.h, &y)
}

/// The earliest guard crossing within `step` (taken in `mode`) as (theta, guard index), with
/// theta the upper end of the final bracket (the event is never placed before the crossing),
/// located to `time_tol` seconds.
pub(crate) fn locate<S: HybridSystem<N>, const N: usize>(
    sys: &S,
    mode: S::Mode,
    step: &Step<N>,
    time_tol: f64,
) -> Option<(f64, usize)> {
    // Per guard: the last probe with g <= 0 and the first with g > 0, as (theta, g).
    let g0 = guards_at(sys, mode, step, 0.0);
    let mut lo: [(f64, f64); MAX_GUARDS] = std::array::from_fn(|i| (0.0, g0[i]));
    let mut hi: [Option<(f64, f64)>; MAX_GUARDS] = [None; MAX_GUARDS];
    for &th in &PROBES {
        let g = guards_at(sys, mode, step, th);
        for i in 0..MAX_GUARDS {
            if hi[i].is_some() {
                continue;
            }
            if g[i] > 0.0 {
                hi[i] = Some((th, g[i]));
            } else {
                lo[i] = (th, g[i]);
            }
        }
    }
    let opts = RootOptions {
        f_tol: None,
        x_tol_abs: time_tol / step.h,
        x_tol_rel: 0.0,
        max_iter: MAX_LOCATE_EVALS,
    };
    let mut best: Option<(f64, usize)> = None;
    for i in 0..MAX_GUARDS {
        let Some(h) = hi[i] else { continue };
        // A crossing after the earliest one found so far cannot be the event.
        if best.is_some_and(|(b, _)| b <= lo[i].0) {
            continue;
        }
        let th = crossing(sys, mode, step, i, lo[i], h, &opts);
        if best.is_none_or(|(b, _)| th < b) {
            best = Some((th, i));
        }
    }
    best
}

/// Locates the crossing of guard `i` between `lo` (g <= 0) and `hi` (g > 0) on the dense
/// output; returns the positive end of the final bracket.
fn crossing<S: HybridSystem<N>, const N: usize>(
    sys: &S,
    mode: S::Mode,
    step: &Step<N>,
    i: usize,
    lo: (f64, f64),
    hi: (f64, f64),
    opts: &RootOptions,
) -> f64 {
    let g = |th: f64| -> Result<(f64, ()), Infallible> {
        Ok((
            sys.guards(mode, step.t0 + th * step.h, &step.at_theta(th))[i],
            (),
        ))
    };
    let (a, b) = (Sample::new(lo.0, lo.1, ()), Sample::new(hi.0, hi.1, ()));
    match illinois(g, a, b, opts) {
        Ok(root) => root.positive.x,
        // The ends bracket by construction and the evaluation cannot fail.
        Err(_) => hi.0,
    }
}
