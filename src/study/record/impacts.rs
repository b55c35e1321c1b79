//! Rebounds off rigid stops located on the exact solution of a linear free flight, so that a
//! sample interval with impacts costs a few polynomial evaluations instead of a Dormand-Prince
//! integration.
//!
//! Between two input samples a linear free flight `y' = L y + c a(t)`, with the input linear in
//! time, `a = a0 + s t`, has the derivatives `y⁽¹⁾ = L y + c a0`, `y⁽²⁾ = L y⁽¹⁾ + c s`,
//! `y⁽ᵏ⁺¹⁾ = L y⁽ᵏ⁾`, and its Taylor series converges like `‖h L‖ᵏ/k!`. Where the sample
//! interval resolves the dynamics (the scaled `‖h L‖` at most
//! [`RESOLVED_NORM`](crate::ode::exponential::RESOLVED_NORM)) the series summed until its terms
//! fall below rounding ([`TAYLOR_TOL`], at most [`MAX_TERMS`] terms) is the exact propagator
//! to rounding, and the position is a polynomial in time. The first stop crossing in the
//! interval is found on that polynomial. Its terms past the quadratic bound how far the
//! velocity strays from its linear part and the position from its quadratic part over the
//! interval, so most intervals are decided by the state at their end: where the velocity keeps
//! its sign, the position is monotone and a stop between its ends holds the one crossing
//! (safeguarded Newton on the position's polynomial, from the secant's root); where the
//! quadratic part stays farther from the stops than the rest can reach, there is none. Any
//! other interval (a turning point within reach of a stop) is cut into [`PIECES`] pieces, a
//! piece whose velocity changes sign is split at its extremum (safeguarded Newton on the
//! velocity's polynomial), and the first monotone piece whose end lies past a stop holds the
//! crossing. There the model's own switch ([`Model::switch`]) applies the rebound, and the
//! rest of the interval is searched again from the new state. A motion too fast for a piece to
//! hold at most one extremum is not resolved by the sample interval (as the Hermite check of
//! the ordinary step assumes too).

use nalgebra::{SMatrix, SVector};

use crate::model::Model;
use crate::num::polynomial::quadratic_roots;

use super::stepping::{POSITION, VELOCITY};

/// Most terms of the Taylor series.
pub(super) const MAX_TERMS: usize = 40;

/// A term of the series is negligible below this fraction of the state's scaled size.
pub(super) const TAYLOR_TOL: f64 = 1e-17;

/// Pieces each interval is cut into for the search.
const PIECES: usize = 4;

/// Most rebounds in one interval; more is chatter, left to Dormand-Prince and the model's
/// resting modes.
pub(super) const MAX_REBOUNDS: usize = 16;

/// Root-finding iterations of the safeguarded Newton method.
const MAX_ITERATIONS: usize = 60;

/// A rigid stop of the first mass: its side (+1 or -1), gap (m) and guard index.
#[derive(Debug, Clone, Copy)]
pub(super) struct RigidStop {
    pub(super) side: f64,
    pub(super) gap: f64,
    pub(super) guard: usize,
}

/// The rigid stops of a model's first mass, if every stop it has is one and the free flight's
/// `L` is resolved by `dt` (see the module docs); `None` otherwise.
pub(super) fn rigid_stops<M: Model<N>, const N: usize>(model: &M) -> Option<Vec<RigidStop>> {
    let mut stops = Vec::new();
    for (k, c) in model.contacts().iter().enumerate() {
        if !c.gap.is_finite() {
            continue;
        }
        if c.mass != 0 || c.other.is_some() || !c.rigid() {
            return None;
        }
        stops.push(RigidStop {
            side: c.side,
            gap: c.gap,
            guard: 2 * k,
        });
    }
    (!stops.is_empty()).then_some(stops)
}

/// The rebounds of one interval: time into it (s) and |x| there (m).
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Rebounds {
    pub(super) at: [(f64, f64); MAX_REBOUNDS],
    pub(super) len: usize,
}

impl Rebounds {
    /// The rebounds found.
    pub(super) fn found(&self) -> &[(f64, f64)] {
        &self.at[..self.len]
    }
}

/// The Taylor series of the free flight from one state over part of an interval.
struct Series<const N: usize> {
    /// `y⁽ᵏ⁾ / k!`.
    terms: [SVector<f64, N>; MAX_TERMS],
    len: usize,
    /// Over the span `len_s` the series was made for, with `p_k` the position's terms:
    /// `Σ_{k≥3} |p_k| len_s^k`, which bounds the position's departure from its quadratic part,
    /// and `Σ_{k≥3} k |p_k| len_s^k`, which over `len_s` bounds the velocity's departure from
    /// its linear part.
    tail_x: f64,
    tail_v: f64,
}

impl<const N: usize> Series<N> {
    /// The series at `y` with the input `a0` and its slope `s` (see the module docs); `None`
    /// where it does not fall below [`TAYLOR_TOL`] within [`MAX_TERMS`] terms over `len_s`.
    fn new(
        l: &SMatrix<f64, N, N>,
        c: &SVector<f64, N>,
        inv_scales: &SVector<f64, N>,
        y: &SVector<f64, N>,
        a0: f64,
        s: f64,
        len_s: f64,
    ) -> Option<Self> {
        let mut terms = [SVector::<f64, N>::zeros(); MAX_TERMS];
        terms[0] = *y;
        let size = y.component_mul(inv_scales).amax().max(1.0);
        let mut d = *y;
        // k! as the product 1 * 2 * ... * k, in that order.
        let (mut tau_k, mut k_factorial) = (1.0, 1.0);
        let (mut tail_x, mut tail_v) = (0.0, 0.0);
        for k in 1..MAX_TERMS {
            d = l * d;
            match k {
                1 => d += c * a0,
                2 => d += c * s,
                _ => {}
            }
            tau_k *= len_s / k as f64;
            k_factorial *= k as f64;
            terms[k] = d / k_factorial;
            // `d τ_k` is the term times `len_s^k`.
            let spanned = d * tau_k;
            if k > 2 {
                let p = spanned[POSITION].abs();
                tail_x += p;
                tail_v += k as f64 * p;
            }
            let scaled = spanned.component_mul(inv_scales).amax();
            if k > 2 && scaled <= TAYLOR_TOL * size {
                return Some(Self {
                    terms,
                    len: k + 1,
                    tail_x,
                    tail_v,
                });
            }
        }
        None
    }

    /// The state at `t`.
    fn at(&self, t: f64) -> SVector<f64, N> {
        let mut y = self.terms[self.len - 1];
        for k in (0..self.len - 1).rev() {
            y = y * t + self.terms[k];
        }
        y
    }

    /// Component `i` and its first derivative at `t`.
    fn component(&self, i: usize, t: f64) -> (f64, f64) {
        let (mut p, mut dp) = (self.terms[self.len - 1][i], 0.0);
        for k in (0..self.len - 1).rev() {
            dp = dp * t + p;
            p = p * t + self.terms[k][i];
        }
        (p, dp)
    }
}

/// One interval of a linear free flight from `y` with the input `a0`, `a1` at its ends, each
/// rebound off a rigid stop applied by `rebound` (the stop's guard, the state there, the input
/// there; true when the model stays in free flight, as [`Model::switch`] decides); the state at
/// its end and the rebounds, or `None` to hand the interval to Dormand-Prince (a series that
/// does not converge, a switch that does not stay in free flight, chatter).
#[allow(clippy::too_many_arguments)]
pub(super) fn interval<const N: usize>(
    l: &SMatrix<f64, N, N>,
    c: &SVector<f64, N>,
    inv_scales: &SVector<f64, N>,
    stops: &[RigidStop],
    y: &SVector<f64, N>,
    h: f64,
    [a0, a1]: [f64; 2],
    mut rebound: impl FnMut(usize, &mut SVector<f64, N>, f64) -> bool,
) -> Option<(SVector<f64, N>, Rebounds)> {
    let s = (a1 - a0) / h;
    let mut rebounds = Rebounds::default();
    let (mut from, mut t) = (*y, 0.0);
    loop {
        let left = h - t;
        let series = Series::new(l, c, inv_scales, &from, a0 + s * t, s, left)?;
        let (tau, stop) = match first_crossing(&series, stops, left) {
            Search::Crossing(tau, stop) => (tau, stop),
            Search::Clear(end) => return Some((end, rebounds)),
        };
        if rebounds.len == MAX_REBOUNDS {
            return None;
        }
        let mut at = series.at(tau);
        t += tau;
        if !rebound(stop.guard, &mut at, a0 + s * t) {
            return None;
        }
        rebounds.at[rebounds.len] = (t, at[POSITION].abs());
        rebounds.len += 1;
        from = at;
    }
}

/// Where the search of a stretch ends: the first stop crossing (the time into the stretch and
/// the stop), or the state at the stretch's end where it has none.
enum Search<const N: usize> {
    Crossing(f64, RigidStop),
    Clear(SVector<f64, N>),
}

/// The first time in `(0, len]` at which the position reaches a stop, with the stop, or the
/// state at `len` (see the module docs).
///
/// Most stretches are decided by the bounds of the series' tail beyond its quadratic part,
/// `x(t) = x0 + v0 t + q2 t² + r(t)`: where the velocity keeps its sign over the stretch the
/// position is monotone; where the velocity's linear part heads for zero, it is monotone at
/// least up to where that part comes within the tail's reach of zero, past which lies the
/// turning point; on such a monotone stretch only a stop between its ends can be reached (the
/// nearest such one). Where none is, and the position's quadratic part stays farther from
/// every stop than the tail can reach, the stretch has no crossing. Any other stretch (a
/// turning point within reach of a stop) is searched in pieces ([`piecewise_crossing`]).
fn first_crossing<const N: usize>(series: &Series<N>, stops: &[RigidStop], len: f64) -> Search<N> {
    let end = series.at(len);
    let [x0, v0, q2] = [0, 1, 2].map(|k| series.terms[k][POSITION]);
    // v(t) = v0 + 2 q2 t + r'(t) with |r'| <= tail_v / len over the stretch.
    let (vb, rate_tail) = (v0 + 2.0 * q2 * len, series.tail_v / len);
    if v0.min(vb) > rate_tail || v0.max(vb) < -rate_tail {
        return match monotone_crossing(series, stops, len, end[POSITION]) {
            Some((tc, stop)) => Search::Crossing(tc, stop),
            None => Search::Clear(end),
        };
    }
    // |v0 + 2 q2 t| = |2 q2| (t_v - t) before its zero t_v.
    let monotone_until = -v0 / (2.0 * q2) - rate_tail / (2.0 * q2).abs();
    if monotone_until > 0.0 && monotone_until < len {
        let x = series.component(POSITION, monotone_until).0;
        if let Some((tc, stop)) = monotone_crossing(series, stops, monotone_until, x) {
            return Search::Crossing(tc, stop);
        }
    }
    // |r| <= tail_x over the stretch.
    let quadratic = |t: f64| x0 + t * (v0 + t * q2);
    let (mut lo, mut hi) = (x0.min(quadratic(len)), x0.max(quadratic(len)));
    let vertex = -v0 / (2.0 * q2);
    if vertex > 0.0 && vertex < len {
        lo = lo.min(quadratic(vertex));
        hi = hi.max(quadratic(vertex));
    }
    let clear = stops.iter().all(|stop| {
        let reach = if stop.side > 0.0 { hi } else { -lo };
        reach + series.tail_x < stop.gap
    });
    if clear {
        return Search::Clear(end);
    }
    match piecewise_crossing(series, stops, len) {
        Some((tc, stop)) => Search::Crossing(tc, stop),
        None => Search::Clear(end),
    }
}

/// The crossing of the nearest stop between the position at 0 and `x1` at `t1`, over which the
/// position is monotone, by safeguarded Newton from the root of the position's quadratic part
/// (the secant's root where that has none in the stretch).
fn monotone_crossing<const N: usize>(
    series: &Series<N>,
    stops: &[RigidStop],
    t1: f64,
    x1: f64,
) -> Option<(f64, RigidStop)> {
    let [x0, v0, q2] = [0, 1, 2].map(|k| series.terms[k][POSITION]);
    let stop = stops
        .iter()
        .filter(|s| s.side * x0 - s.gap < 0.0 && s.side * x1 - s.gap >= 0.0)
        .min_by(|a, b| a.gap.total_cmp(&b.gap))?;
    let (side, gap) = (stop.side, stop.gap);
    let (f0, f1) = (side * x0 - gap, side * x1 - gap);
    let inside = |t: &f64| *t > 0.0 && *t < t1;
    let start = quadratic_roots(side * q2, side * v0, f0)
        .into_iter()
        .flatten()
        .filter(inside)
        .min_by(f64::total_cmp)
        .unwrap_or(t1 * f0 / (f0 - f1));
    let tc = newton(0.0, t1, f0, start, |t| {
        let (x, v) = series.component(POSITION, t);
        (side * x - gap, side * v)
    });
    Some((tc, *stop))
}

/// The first time in `(0, len]` at which the position reaches a stop, with the stop, by the
/// search in [`PIECES`] pieces (see the module docs).
fn piecewise_crossing<const N: usize>(
    series: &Series<N>,
    stops: &[RigidStop],
    len: f64,
) -> Option<(f64, RigidStop)> {
    let x = |t: f64| series.component(POSITION, t);
    let mut ta = 0.0;
    let (mut xa, mut va) = x(ta);
    for p in 1..=PIECES {
        let tb = len * p as f64 / PIECES as f64;
        let (xb, vb) = x(tb);
        // The piece's extremum, where the velocity changes sign.
        let mut nodes = [(ta, xa), (tb, xb), (tb, xb)];
        if va * vb < 0.0 {
            let te = newton(ta, tb, va, 0.5 * (ta + tb), |t| {
                series.component(VELOCITY, t)
            });
            nodes[1] = (te, x(te).0);
        }
        for w in nodes.windows(2) {
            let ((t0, x0), (t1, x1)) = (w[0], w[1]);
            if t1 <= t0 {
                continue;
            }
            for stop in stops {
                let (f0, f1) = (stop.side * x0 - stop.gap, stop.side * x1 - stop.gap);
                if f1 >= 0.0 && f0 < 0.0 {
                    let tc = newton(t0, t1, f0, 0.5 * (t0 + t1), |t| {
                        let (x, v) = x(t);
                        (stop.side * x - stop.gap, stop.side * v)
                    });
                    return Some((tc, *stop));
                }
            }
        }
        (ta, xa, va) = (tb, xb, vb);
    }
    None
}

/// The root of `f` in `[a, b]` where `f(a)` has the sign of `fa` and `f(b)` the other, by
/// Newton's method from `start` (inside the bracket) kept inside the bracket (bisection where
/// a step leaves it); `f` returns the value and its derivative. It ends when the bracket is a
/// few ulps of `b` (and returns `b`, past the root), or when a step is (and returns the root
/// the step points to: `b` where the last iterate lies past the root, else the step's end,
/// since iterates that approach from before the root, as on a concave rising function, leave
/// `b` at an older iterate), so that the root it returns is never early by more than a few
/// ulps.
pub(super) fn newton(
    mut a: f64,
    mut b: f64,
    fa: f64,
    start: f64,
    f: impl Fn(f64) -> (f64, f64),
) -> f64 {
    let sa = fa.signum();
    let tol = 4.0 * f64::EPSILON * b.abs();
    let mut t = if start > a && start < b {
        start
    } else {
        0.5 * (a + b)
    };
    for _ in 0..MAX_ITERATIONS {
        let (y, dy) = f(t);
        if y == 0.0 {
            return t;
        }
        if y.signum() == sa {
            a = t;
        } else {
            b = t;
        }
        let step = t - y / dy;
        let next = if dy != 0.0 && step > a && step < b {
            step
        } else {
            0.5 * (a + b)
        };
        if b - a <= tol {
            break;
        }
        if (next - t).abs() <= tol {
            return if y.signum() == sa { next } else { b };
        }
        t = next;
    }
    b
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 1 kHz oscillator (ζ = 0.005) over a 50 kHz sample interval, scaled to 10 um, between
    /// stops at ±10 um.
    fn oscillator() -> (
        SMatrix<f64, 2, 2>,
        SVector<f64, 2>,
        SVector<f64, 2>,
        [RigidStop; 2],
    ) {
        let w0 = 2.0 * std::f64::consts::PI * 1000.0;
        let l = SMatrix::<f64, 2, 2>::new(0.0, 1.0, -w0 * w0, -2.0 * 0.005 * w0);
        let c = SVector::<f64, 2>::new(0.0, 1.0);
        let inv_scales = SVector::<f64, 2>::new(1.0 / 1e-5, 1.0 / (w0 * 1e-5));
        let stop = |side: f64, guard| RigidStop {
            side,
            gap: 1e-5,
            guard,
        };
        (l, c, inv_scales, [stop(1.0, 0), stop(-1.0, 2)])
    }

    /// Over two grids of states, one around both stops (approaches at speed, departures) and
    /// one just short of the upper stop at low speeds (turning points just short of it and
    /// just past it), the search by the tail's bounds finds what the search in pieces finds:
    /// no crossing, or the same stop at the same time to rounding (both end Newton's method
    /// within 4 ulps of the root), and its state at the end is the series' own.
    #[test]
    fn the_bounded_search_finds_what_the_pieces_find() {
        let (l, c, inv_scales, stops) = oscillator();
        let len = 2e-5;
        let wide = |i: usize, j: usize| (-12e-6 + 0.6e-6 * i as f64, -0.2 + 0.01 * j as f64);
        let near = |i: usize, j: usize| (9.95e-6 + 1.25e-9 * i as f64, -0.005 + 5e-4 * j as f64);
        for grid in [wide, near] {
            let (mut crossings, mut clear) = (0, 0);
            for (i, j) in (0..=40).flat_map(|i| (0..=40).map(move |j| (i, j))) {
                let (x, v) = grid(i, j);
                let y = SVector::<f64, 2>::new(x, v);
                let Some(series) = Series::new(&l, &c, &inv_scales, &y, -10.0, 3e3, len) else {
                    panic!("the series converges at {x:e}, {v:e}");
                };
                let pieces = piecewise_crossing(&series, &stops, len);
                match (first_crossing(&series, &stops, len), pieces) {
                    (Search::Crossing(t, stop), Some((tp, sp))) => {
                        assert_eq!(stop.guard, sp.guard, "{x:e}, {v:e}");
                        // A few ulps of the time, and the time a few ulps of the position
                        // take at the crossing's speed (a slow crossing is ill-conditioned).
                        let speed = series.component(POSITION, tp).1.abs();
                        let tol = 16.0 * f64::EPSILON * (len + stop.gap / speed);
                        assert!((t - tp).abs() <= tol, "{x:e}, {v:e}: {t:e} vs {tp:e}");
                        crossings += 1;
                    }
                    (Search::Clear(end), None) => {
                        assert_eq!(end, series.at(len));
                        clear += 1;
                    }
                    (found, pieces) => panic!(
                        "{x:e}, {v:e}: bounds {}, pieces {pieces:?}",
                        matches!(found, Search::Crossing(..))
                    ),
                }
            }
            assert!(
                crossings > 100 && clear > 100,
                "{crossings} crossings, {clear} clear"
            );
        }
    }

    /// On a concave rising function (a mass decelerating onto a stop), whose Newton iterates
    /// approach the root from below, the root returned is the root to a few ulps, wherever it
    /// lies in the bracket.
    #[test]
    fn newton_returns_the_root_when_its_iterates_approach_from_below() {
        let len = 2e-5;
        for k in 1..200 {
            let root = len * k as f64 / 200.0;
            // f(t) = 0.14 (t - root) - 200 (t - root)^2 (concave, rising on [0, len]).
            let f = |t: f64| {
                let d = t - root;
                (0.14 * d - 200.0 * d * d, 0.14 - 400.0 * d)
            };
            let t = newton(0.0, len, f(0.0).0, 0.5 * len, f);
            assert!(
                (t - root).abs() <= 8.0 * f64::EPSILON * len,
                "{t:e} vs {root:e}"
            );
        }
    }
}
