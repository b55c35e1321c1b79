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
//! interval is found on that polynomial: the interval is cut into [`PIECES`] pieces, a piece
//! whose velocity changes sign is split at its extremum (safeguarded Newton on the velocity's
//! polynomial), and the first monotone piece whose end lies past a stop holds the crossing
//! (safeguarded Newton on the position's). There the model's own switch ([`Model::switch`])
//! applies the rebound, and the rest of the interval is searched again from the new state. A
//! motion too fast for a piece to hold at most one extremum is not resolved by the sample
//! interval (as the Hermite check of the ordinary step assumes too).

use nalgebra::{SMatrix, SVector};

use crate::model::Model;

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
            let scaled = (d * tau_k).component_mul(inv_scales).amax();
            if k > 2 && scaled <= TAYLOR_TOL * size {
                return Some(Self { terms, len: k + 1 });
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
        let Some((tau, stop)) = first_crossing(&series, stops, left) else {
            return Some((series.at(left), rebounds));
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

/// The first time in `(0, len]` at which the position reaches a stop, with the stop (see the
/// module docs).
fn first_crossing<const N: usize>(
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
            let te = newton(ta, tb, va, |t| series.component(VELOCITY, t));
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
                    let tc = newton(t0, t1, f0, |t| {
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
/// Newton's method kept inside the bracket (bisection where a step leaves it); `f` returns the
/// value and its derivative. It ends when the bracket or the step is a few ulps of `b`, or at
/// the end of the bracket where the sign changes, so that the root it returns is never early
/// by more than that.
fn newton(mut a: f64, mut b: f64, fa: f64, f: impl Fn(f64) -> (f64, f64)) -> f64 {
    let sa = fa.signum();
    let tol = 4.0 * f64::EPSILON * b.abs();
    let mut t = 0.5 * (a + b);
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
        if (next - t).abs() <= tol || b - a <= tol {
            break;
        }
        t = next;
    }
    b
}
