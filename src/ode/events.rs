//! Guard probing and event location on the dense output of one accepted step.
//!
//! The guards of the step's mode are evaluated at theta = 0 (the step's start) and at the
//! probes theta = 1/3, 2/3 and 1. For each guard, the first probe where it is positive gives a
//! bracket (previous probe, that probe), and the crossing is located on the dense output by the
//! crate's one root finder, [`crate::num::roots::illinois`], to the event time tolerance. The
//! earliest crossing over all guards is the event.
//!
//! A guard may also rise above zero and fall back between two probes (a trajectory grazing a
//! stop). Where the cubic through the four samples has an interior maximum near zero, the
//! guard is maximised on the dense output and, if it is positive there, the crossing before
//! the maximum is bracketed and located like any other (see `graze` for the criterion and
//! what can still be missed).

use std::convert::Infallible;

use crate::num::roots::{illinois, RootOptions, Sample};
use crate::ode::{HybridSystem, Step};

/// Interior probe points of a step (theta = (t - t0)/h), the end included.
pub(crate) const PROBES: [f64; 3] = [1.0 / 3.0, 2.0 / 3.0, 1.0];

/// Largest number of guard evaluations spent locating one crossing.
const MAX_LOCATE_EVALS: usize = 200;

/// Buffers for the guards' values, sized by the system's guard count on first use and kept
/// by the integrator between steps.
#[derive(Debug, Clone, Default)]
pub struct Scratch {
    /// One evaluation of every guard.
    values: Vec<f64>,
    /// Per guard, its values at theta = 0 and at the probes.
    samples: Vec<[f64; 4]>,
}

impl Scratch {
    /// The buffer of one evaluation of `count` guards.
    pub(crate) fn guards(&mut self, count: usize) -> &mut [f64] {
        self.values.resize(count, f64::NEG_INFINITY);
        &mut self.values
    }
}

/// Guard `i` of `mode` on the dense output of `step` at `theta`, evaluated into `buf`.
fn guard_at<S: HybridSystem>(
    sys: &S,
    mode: S::Mode,
    step: &Step<S::State>,
    theta: f64,
    i: usize,
    buf: &mut [f64],
) -> f64 {
    sys.guards_on_step(mode, step.t0 + theta * step.h, step, theta, buf);
    buf[i]
}

/// The earliest guard crossing within `step` (taken in `mode`) as (theta, guard index), with
/// theta the upper end of the final bracket (the event is never placed before the crossing),
/// located to `time_tol` seconds.
pub(crate) fn locate<S: HybridSystem>(
    sys: &S,
    mode: S::Mode,
    step: &Step<S::State>,
    time_tol: f64,
    scratch: &mut Scratch,
) -> Option<(f64, usize)> {
    let count = sys.guard_count();
    scratch.values.resize(count, f64::NEG_INFINITY);
    scratch.samples.resize(count, [0.0; 4]);
    let Scratch { values, samples } = scratch;
    // Per guard, its values at theta = 0 and at the probes (the stored end states at 0 and 1).
    for (k, &th) in THETAS.iter().enumerate() {
        let t = step.t0 + th * step.h;
        if th == 1.0 {
            sys.guards(mode, t, &step.y1, values);
        } else if th == 0.0 {
            sys.guards(mode, t, &step.y0, values);
        } else {
            sys.guards_on_step(mode, t, step, th, values);
        }
        for (s, gi) in samples.iter_mut().zip(values.iter()) {
            s[k] = *gi;
        }
    }
    let opts = RootOptions {
        f_tol: None,
        x_tol_abs: time_tol / step.h,
        x_tol_rel: 0.0,
        max_iter: MAX_LOCATE_EVALS,
    };
    let mut best: Option<(f64, usize)> = None;
    for (i, samples) in samples.iter().enumerate() {
        let samples = *samples;
        // The first probe where the guard is positive brackets a crossing with the one before.
        let first_positive = (1..4).find(|&k| samples[k] > 0.0);
        let mut bracket =
            first_positive.map(|k| ((THETAS[k - 1], samples[k - 1]), (THETAS[k], samples[k])));
        // A crossing and return between the probes before that (a grazing contact).
        let upper = first_positive.map_or(1.0, |k| THETAS[k - 1]);
        if upper > 0.0 {
            if let Some(b) = graze(sys, mode, step, i, &samples, upper, &opts, values) {
                bracket = Some(b);
            }
        }
        let Some((lo, hi)) = bracket else { continue };
        // A crossing after the earliest one found so far cannot be the event.
        if best.is_some_and(|(b, _)| b <= lo.0) {
            continue;
        }
        let th = crossing(sys, mode, step, i, lo, hi, &opts, values);
        if best.is_none_or(|(b, _)| th < b) {
            best = Some((th, i));
        }
    }
    best
}

/// Theta of the guard samples: the start of the step and the probes.
const THETAS: [f64; 4] = [0.0, PROBES[0], PROBES[1], PROBES[2]];

/// Largest number of guard evaluations spent looking for the maximum of one guard.
const MAX_GRAZE_EVALS: usize = 60;

/// Looks for a grazing crossing of guard `i` on (0, `upper`), where every sample is <= 0:
/// when the cubic through the four samples has an interior maximum close enough to zero (its
/// distance to zero below the guard's variation over the step, `p* - min(samples)`), the
/// guard is maximised on the dense output around it (Brent's method, stopping at the first
/// positive value). Returns a bracket (g <= 0, g > 0) of the first crossing, if the guard does
/// rise above zero.
///
/// The cubic is exact for a guard quadratic in theta (a trajectory grazing a stop is locally
/// a parabola), so a grazing contact is found wherever it falls in the step. What may still be
/// missed: two maxima between the same pair of probes, and excursions above zero shorter than
/// the maximiser's resolution (sqrt(eps) relative in theta, plus the event time tolerance).
#[allow(clippy::too_many_arguments)]
fn graze<S: HybridSystem>(
    sys: &S,
    mode: S::Mode,
    step: &Step<S::State>,
    i: usize,
    samples: &[f64; 4],
    upper: f64,
    opts: &RootOptions,
    buf: &mut [f64],
) -> Option<((f64, f64), (f64, f64))> {
    let [s0, s1, s2, s3] = *samples;
    let s_max = max2(max2(s0, s1), max2(s2, s3));
    let s_min = -max2(max2(-s0, -s1), max2(-s2, -s3));
    // A cheap necessary condition first (most steps stop here): the cubic stays within
    // c + Lambda r of the samples' midrange c and half-range r, with Lambda = 1.63 the Lebesgue
    // constant of four equispaced nodes (2 used), so p* + (p* - s_min) > 0 needs
    // 3 s_max > 2 s_min. An unused guard (-inf) fails it; a NaN sample gives no maximum below.
    if 3.0 * s_max <= 2.0 * s_min || !s_min.is_finite() {
        return None;
    }
    let th_max = cubic_maximum(samples, upper)?;
    let p_max = cubic(samples, th_max);
    if p_max + (p_max - s_min) <= 0.0 {
        return None;
    }
    // Maximise on the dense output over one probe spacing either side of the estimate.
    let a = (th_max - PROBES[0]).max(0.0);
    let b = (th_max + PROBES[0]).min(upper);
    let mut evals = [(0.0, 0.0); MAX_GRAZE_EVALS];
    let mut n = 0;
    let positive = maximise(
        |th| {
            let v = guard_at(sys, mode, step, th, i, buf);
            if n < MAX_GRAZE_EVALS {
                evals[n] = (th, v);
                n += 1;
            }
            v
        },
        a,
        b,
        th_max,
        opts.x_tol_abs,
        MAX_GRAZE_EVALS,
    )?;
    // The non-positive end: the latest sample before the positive one (all are <= 0).
    let mut lo = (0.0, samples[0]);
    for (th, v) in THETAS
        .into_iter()
        .zip(*samples)
        .chain(evals[..n].iter().copied())
    {
        if th < positive.0 && th > lo.0 && v <= 0.0 {
            lo = (th, v);
        }
    }
    Some((lo, positive))
}

/// The larger of two values by plain comparison (cheaper than `f64::max`, which handles NaN).
#[inline(always)]
fn max2(a: f64, b: f64) -> f64 {
    if a > b {
        a
    } else {
        b
    }
}

/// The cubic through the samples at theta = 0, 1/3, 2/3, 1, at theta (Newton's form in
/// u = 3 theta).
fn cubic(s: &[f64; 4], theta: f64) -> f64 {
    let (d1, d2, d3) = differences(s);
    let u = 3.0 * theta;
    s[0] + u * (d1 + (u - 1.0) * (0.5 * d2 + (u - 2.0) * d3 / 6.0))
}

fn differences(s: &[f64; 4]) -> (f64, f64, f64) {
    (
        s[1] - s[0],
        s[2] - 2.0 * s[1] + s[0],
        s[3] - 3.0 * s[2] + 3.0 * s[1] - s[0],
    )
}

/// The interior local maximum of the cubic through the samples, if it lies in (0, upper).
fn cubic_maximum(s: &[f64; 4], upper: f64) -> Option<f64> {
    let (d1, d2, d3) = differences(s);
    // p'(u) = A u^2 + B u + C with u = 3 theta; a maximum where p' = 0 and p'' = 2 A u + B < 0.
    let (qa, qb, qc) = (0.5 * d3, d2 - d3, d1 - 0.5 * d2 + d3 / 3.0);
    let u = if qa.abs() <= 1e-12 * (qb.abs() + qc.abs()) {
        // (Nearly) a parabola.
        if qb >= 0.0 {
            return None;
        }
        -qc / qb
    } else {
        let disc = qb * qb - 4.0 * qa * qc;
        if disc <= 0.0 {
            return None;
        }
        // The two roots without cancellation; the maximum is the one where p'' < 0.
        let q = -0.5 * (qb + qb.signum() * disc.sqrt());
        [q / qa, qc / q]
            .into_iter()
            .find(|&u| 2.0 * qa * u + qb < 0.0)?
    };
    let theta = u / 3.0;
    (theta > 0.0 && theta < upper).then_some(theta)
}

/// Brent's minimisation (golden section with parabolic steps) of -f on [a, b] from x0, stopping
/// at the first point where f > 0 (returned as (x, f)); None if the maximum found is <= 0.
/// `x_tol` is the absolute part of the tolerance on x, beside sqrt(eps) relative.
fn maximise(
    mut f: impl FnMut(f64) -> f64,
    mut a: f64,
    mut b: f64,
    x0: f64,
    x_tol: f64,
    max_evals: usize,
) -> Option<(f64, f64)> {
    const GOLD: f64 = 0.381_966_011_250_105_1; // (3 - sqrt 5) / 2
    let sqrt_eps = f64::EPSILON.sqrt();
    let (mut x, mut w, mut v) = (x0, x0, x0);
    let fx0 = f(x);
    if fx0 > 0.0 {
        return Some((x, fx0));
    }
    // Minimise phi = -f.
    let (mut fx, mut fw, mut fv) = (-fx0, -fx0, -fx0);
    let (mut d, mut e) = (0.0f64, 0.0f64);
    for _ in 1..max_evals {
        let xm = 0.5 * (a + b);
        let tol1 = sqrt_eps * x.abs() + x_tol / 3.0;
        let tol2 = 2.0 * tol1;
        if (x - xm).abs() <= tol2 - 0.5 * (b - a) {
            break;
        }
        let mut golden = true;
        if e.abs() > tol1 {
            let r = (x - w) * (fx - fv);
            let mut q = (x - v) * (fx - fw);
            let mut p = (x - v) * q - (x - w) * r;
            q = 2.0 * (q - r);
            if q > 0.0 {
                p = -p;
            }
            q = q.abs();
            let e_prev = e;
            e = d;
            if p.abs() < (0.5 * q * e_prev).abs() && p > q * (a - x) && p < q * (b - x) {
                d = p / q;
                let u = x + d;
                if u - a < tol2 || b - u < tol2 {
                    d = tol1.copysign(xm - x);
                }
                golden = false;
            }
        }
        if golden {
            e = if x >= xm { a - x } else { b - x };
            d = GOLD * e;
        }
        let u = if d.abs() >= tol1 {
            x + d
        } else {
            x + tol1.copysign(d)
        };
        let gu = f(u);
        if gu > 0.0 {
            return Some((u, gu));
        }
        let fu = -gu;
        if fu <= fx {
            if u >= x {
                a = x;
            } else {
                b = x;
            }
            (v, fv, w, fw, x, fx) = (w, fw, x, fx, u, fu);
        } else {
            if u < x {
                a = u;
            } else {
                b = u;
            }
            if fu <= fw || w == x {
                (v, fv, w, fw) = (w, fw, u, fu);
            } else if fu <= fv || v == x || v == w {
                (v, fv) = (u, fu);
            }
        }
    }
    None
}

/// Locates the crossing of guard `i` between `lo` (g <= 0) and `hi` (g > 0) on the dense
/// output; returns the positive end of the final bracket.
#[allow(clippy::too_many_arguments)]
fn crossing<S: HybridSystem>(
    sys: &S,
    mode: S::Mode,
    step: &Step<S::State>,
    i: usize,
    lo: (f64, f64),
    hi: (f64, f64),
    opts: &RootOptions,
    buf: &mut [f64],
) -> f64 {
    let g = |th: f64| -> Result<(f64, ()), Infallible> {
        Ok((guard_at(sys, mode, step, th, i, buf), ()))
    };
    let (a, b) = (Sample::new(lo.0, lo.1, ()), Sample::new(hi.0, hi.1, ()));
    match illinois(g, a, b, opts) {
        Ok(root) => root.positive.x,
        // The ends bracket by construction and the evaluation cannot fail.
        Err(_) => hi.0,
    }
}
