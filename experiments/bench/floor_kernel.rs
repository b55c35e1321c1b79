//! The floor kernel: a minimal exact event-driven integrator for one case, a linear
//! oscillator between rigid restitution stops under a cosine base acceleration, written for
//! speed alone, to measure the general record engine against (`bench/floor.rs`).
//!
//! The oscillator `x'' + 2 ζ ω0 x' + ω0² x = a(t)`, `a(t) = -A cos(ω t)` (the assembled
//! model's `m x'' = m a - b x' - k x`), has the particular solution `x_p = P cos ωt + Q sin ωt`
//! with `(ω0² - ω²) P + 2ζω0ω Q = -A` and `(ω0² - ω²) Q = 2ζω0ω P`. The kernel carries
//! `(u, w, c, s)`: the homogeneous part `u = x - x_p`, `w = v - v_p` and the forcing's phase
//! `c = cos ωt`, `s = sin ωt`. Over a time `τ` the homogeneous part decays and turns by the
//! damped free response and the phase rotates by `ωτ`, both in closed form; over an output
//! interval `h` these are fixed 2 x 2 products.
//!
//! An interval whose cubic Hermite interpolant of x (end values and slopes) stays
//! [`MARGIN`] of the gap clear of the stops cannot reach them: the interpolant is within
//! `h⁴ max|x''''| / 384` of the trajectory, about `(ωh)⁴/384 X` = 7e-12 m at 50 kHz for the
//! 25 um free amplitude `X`, far below the margin's 1 nm. Any other interval is searched on
//! the closed form: the interval is far shorter than the half period `π/ω0`, so x has at most
//! one extremum in it (velocity zeros of the oscillator are about `π/ω0` apart); that
//! extremum is found by safeguarded Newton on `v`, and the first stop crossing, in the
//! monotone piece that reaches past the stop, by safeguarded Newton on `x`. At the impact
//! `v+ = -e v-`, `x = ±gap`, and the rest of the interval is searched again.

use anyhow::{bail, Result};
use endstop::num::polynomial::hermite_range;

/// Clearance from the stops (fraction of the gap) the Hermite guard keeps.
pub const MARGIN: f64 = 1e-4;

/// Most impacts within one output interval; more is chatter, which this kernel does not
/// model (the general engine's resting modes do).
const MAX_IMPACTS_PER_INTERVAL: usize = 16;

/// Root-finding tolerance on time (s): far below a picosecond's displacement at these speeds.
const TIME_TOL_S: f64 = 1e-16;

/// The case: a 1-DOF oscillator between symmetric rigid stops under `a(t) = -A cos(ω t)`
/// from rest, sampled at `fs`.
#[derive(Debug, Clone, Copy)]
pub struct SineCase {
    /// Natural frequency f0 (Hz).
    pub f0_hz: f64,
    /// Damping ratio ζ.
    pub zeta: f64,
    /// Gap to each stop (m).
    pub gap_m: f64,
    /// Coefficient of restitution e.
    pub restitution: f64,
    /// Drive amplitude A (m/s^2).
    pub accel_m_s2: f64,
    /// Drive frequency (Hz).
    pub freq_hz: f64,
    /// Output sample rate (Hz).
    pub sample_rate_hz: f64,
    /// Simulated time (s).
    pub duration_s: f64,
}

/// What the kernel found: the impacts and the position at every output instant.
pub struct FloorRun {
    /// Impacts (rebounds off either stop).
    pub impacts: u64,
    /// x at `t = k / fs`, `k = 0 ..= duration fs` (m).
    pub x_m: Vec<f64>,
}

/// The closed forms of one case.
struct Closed {
    sigma: f64,
    wd: f64,
    w0sq: f64,
    w: f64,
    p: f64,
    q: f64,
}

impl Closed {
    fn of(c: &SineCase) -> Self {
        let w0 = 2.0 * std::f64::consts::PI * c.f0_hz;
        let w = 2.0 * std::f64::consts::PI * c.freq_hz;
        let sigma = c.zeta * w0;
        let detune = w0 * w0 - w * w;
        let d = detune * detune + (2.0 * sigma * w).powi(2);
        Self {
            sigma,
            wd: w0 * (1.0 - c.zeta * c.zeta).sqrt(),
            w0sq: w0 * w0,
            w,
            p: -c.accel_m_s2 * detune / d,
            q: -c.accel_m_s2 * 2.0 * sigma * w / d,
        }
    }

    /// The 2 x 2 homogeneous propagator over `tau` and the phase rotation's cos and sin.
    #[inline(always)]
    fn propagator(&self, tau: f64) -> ([f64; 4], f64, f64) {
        let e = (-self.sigma * tau).exp();
        let (sd, cd) = (self.wd * tau).sin_cos();
        let (sr, cr) = (self.w * tau).sin_cos();
        let k = e * sd / self.wd;
        (
            [
                e * cd + self.sigma * k,
                k,
                -self.w0sq * k,
                e * cd - self.sigma * k,
            ],
            cr,
            sr,
        )
    }

    /// `(u, w, c, s)` advanced by the propagator `(phi, cr, sr)`.
    #[inline(always)]
    fn advance(y: [f64; 4], phi: &[f64; 4], cr: f64, sr: f64) -> [f64; 4] {
        [
            phi[0] * y[0] + phi[1] * y[1],
            phi[2] * y[0] + phi[3] * y[1],
            y[2] * cr - y[3] * sr,
            y[3] * cr + y[2] * sr,
        ]
    }

    /// Position, velocity and acceleration of `(u, w, c, s)`.
    #[inline(always)]
    fn kinematics(&self, y: [f64; 4]) -> (f64, f64, f64) {
        let (xp, vp) = (
            self.p * y[2] + self.q * y[3],
            self.w * (self.q * y[2] - self.p * y[3]),
        );
        let (x, v) = (y[0] + xp, y[1] + vp);
        let ah = -self.w0sq * y[0] - 2.0 * self.sigma * y[1];
        (x, v, ah - self.w * self.w * xp)
    }

    /// The state `tau` after `y`: one closed-form evaluation.
    #[inline(always)]
    fn at(&self, y: [f64; 4], tau: f64) -> [f64; 4] {
        let (phi, cr, sr) = self.propagator(tau);
        Self::advance(y, &phi, cr, sr)
    }

    /// `(u, w, c, s)` of a position and velocity at the phase `(c, s)`.
    #[inline(always)]
    fn split_xv(&self, x: f64, v: f64, c: f64, s: f64) -> [f64; 4] {
        let (xp, vp) = (self.p * c + self.q * s, self.w * (self.q * c - self.p * s));
        [x - xp, v - vp, c, s]
    }
}

/// Runs the case; fails on chatter (see [`MAX_IMPACTS_PER_INTERVAL`]).
pub fn run(case: &SineCase) -> Result<FloorRun> {
    let cl = Closed::of(case);
    let h = 1.0 / case.sample_rate_hz;
    let n = (case.duration_s * case.sample_rate_hz).round() as usize;
    let (phi, cr, sr) = cl.propagator(h);
    let gap = case.gap_m;
    let bound = gap * (1.0 - MARGIN);
    // From rest at t = 0: x = v = 0, phase (1, 0).
    let mut y = cl.split_xv(0.0, 0.0, 1.0, 0.0);
    let mut x_m = Vec::with_capacity(n + 1);
    x_m.push(0.0);
    let mut impacts = 0u64;
    let (mut x0, mut v0, _) = cl.kinematics(y);
    for _ in 0..n {
        let next = Closed::advance(y, &phi, cr, sr);
        let (x1, v1, _) = cl.kinematics(next);
        if hermite_within(x0, h * v0, x1, h * v1, bound) {
            y = next;
        } else {
            let mut from = y;
            let mut left = h;
            let mut hits = 0;
            loop {
                match first_impact(&cl, from, left, gap) {
                    None => {
                        y = cl.at(from, left);
                        break;
                    }
                    Some((tau, side)) => {
                        hits += 1;
                        impacts += 1;
                        if hits > MAX_IMPACTS_PER_INTERVAL {
                            bail!("chatter: more than {MAX_IMPACTS_PER_INTERVAL} impacts in one interval");
                        }
                        let at = cl.at(from, tau);
                        let (_, v, _) = cl.kinematics(at);
                        from = cl.split_xv(side * gap, -case.restitution * v, at[2], at[3]);
                        left -= tau;
                    }
                }
            }
        }
        let (x, v, _) = cl.kinematics(y);
        (x0, v0) = (x, v);
        x_m.push(x);
    }
    Ok(FloorRun { impacts, x_m })
}

/// The first time in `(0, len]` at which x reaches a stop from `y`, with the stop's side; see
/// the module docs.
fn first_impact(cl: &Closed, y: [f64; 4], len: f64, gap: f64) -> Option<(f64, f64)> {
    let (x0, v0, _) = cl.kinematics(y);
    let end = cl.at(y, len);
    let (x1, v1, _) = cl.kinematics(end);
    // The one extremum, where v changes sign.
    let mut pieces = [(0.0, x0), (len, x1), (len, x1)];
    if v0 * v1 < 0.0 {
        let te = newton(0.0, len, v0, |t| {
            let (_, v, a) = cl.kinematics(cl.at(y, t));
            (v, a)
        });
        let (xe, _, _) = cl.kinematics(cl.at(y, te));
        pieces[1] = (te, xe);
    }
    // The first monotone piece that ends past a stop holds the crossing.
    for w in pieces.windows(2) {
        let ((ta, xa), (tb, xb)) = (w[0], w[1]);
        if tb <= ta {
            continue;
        }
        for side in [1.0, -1.0] {
            if side * xb >= gap && side * xa < gap {
                let fa = side * xa - gap;
                let t = newton(ta, tb, fa, |t| {
                    let (x, v, _) = cl.kinematics(cl.at(y, t));
                    (side * x - gap, side * v)
                });
                return Some((t, side));
            }
        }
    }
    None
}

/// The root of `f` in `[a, b]` where `f(a)` has the sign of `fa` and `f(b)` the other, by
/// Newton's method kept inside the bracket (bisection where a step leaves it); `f` returns the
/// value and its derivative.
fn newton(mut a: f64, mut b: f64, fa: f64, f: impl Fn(f64) -> (f64, f64)) -> f64 {
    let sa = fa.signum();
    let mut t = 0.5 * (a + b);
    for _ in 0..60 {
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
        if (next - t).abs() <= TIME_TOL_S || b - a <= TIME_TOL_S {
            return next;
        }
        t = next;
    }
    t
}

/// The cubic Hermite interpolant of x over an interval (end values `x0`, `x1`, end slopes
/// times the interval `m0`, `m1`) stays inside `(-bound, bound)`: the bound of the end values
/// plus `4/27 (|m0| + |m1|)` (the slope basis functions' largest magnitude), else the cubic's
/// interior extrema.
#[inline(always)]
fn hermite_within(x0: f64, m0: f64, x1: f64, m1: f64, bound: f64) -> bool {
    let slack = 4.0 / 27.0 * (m0.abs() + m1.abs());
    if x0.abs().max(x1.abs()) + slack < bound {
        return true;
    }
    let (min, max) = hermite_range(x0, m0, x1, m1);
    min.abs().max(max.abs()) < bound
}
