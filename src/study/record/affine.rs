//! The affine modes of a model on the sample grid of a linearly interpolated drive: each mode's
//! exact propagator over one sample interval, its guards as affine functions of the state with
//! their rates, and the exact integrals over the interval of the record's books (the
//! energy-ledger powers, the outputs and their squares).
//!
//! The module reads better whole: the propagator, the guard rows, the hand-over to the
//! rebound search and the books' Gram sums are built from one augmented state with one
//! scaling, and a reader checks each against that same construction.
//!
//! # The augmented state
//! An affine mode is `y' = L y + c a(t) + d` ([`crate::model::Model::affine`]; behind an
//! interface circuit the forward drops and a battery's voltage are in `d`). Over a sample
//! interval the drive is `a(t_k + s) = a_k + a' s` with the constant slope
//! `a' = (a_{k+1} - a_k) / h`, so the augmented state `u = (y, a, a', 1)` obeys the
//! time-invariant `u' = A u`: one matrix exponential `e^{hA}` per mode advances any state over
//! any interval, for any stiffness (a coil that relaxes in a quarter of the interval is
//! integrated as exactly as a slow mode). The propagator comes from
//! [`crate::ode::phi::phi_functions`] (the series where the interval resolves the mode, which
//! gives each entry to rounding: a storage capacitor that loses 2.4e-5 of its charge per
//! interval needs that, or the error of its decay rate grows over a record).
//!
//! Why this and not the exponential Adams step with a zero remainder (which is exact for the
//! same input too): the augmented propagator gives the guards at the interval's end, with
//! their rates, in the same product as the state, and its matrix exponential carries the
//! exact integrals of the books (below), which the Adams step's dense output would only
//! approximate by quadrature.
//!
//! # Guards
//! Every guard of an affine mode is affine in the state and the drive (the model hands its
//! pieces over, [`Model::driven_affine`]: a stop's penetration, a linear contact's bracket, a
//! resting contact's holding force, a bridge's conduction threshold or current, a switch's
//! velocity), and so is its rate: both are rows on `u`, evaluated at each sample.
//! [`AffineMode::step`] refuses an interval in which a guard may turn positive (its cubic
//! Hermite estimate from its exact values and rates at both ends comes within
//! [`GRAZE_MARGIN`] of zero, and so does the estimate on one of [`PARTS`] parts of the
//! interval within the margin's `PARTS^4`-th). There the
//! interval's crossings of rigid stops (rebounds, a contact that comes to rest) and a resting
//! contact's release are located on the exact solution of each mode in turn and applied by
//! the model's switch (`crossings.rs`); an interval with another switch (a circuit acts) goes
//! to Dormand-Prince, whose events are located on its dense output.
//!
//! # The books by Gram sums
//! In an affine mode every integrand of the books (the drive's `m a v`, the dampers' `b v^2`,
//! a coil's `Rc I^2`, the diodes' `2 V_F i + 2 R_on i^2`, the load's `Vs I_L(Vs)`; the outputs
//! and their squares) is a quadratic form `u^T Q u`. Over an interval its integral is
//! `u_k^T W u_k` with `W = ∫_0^h e^{sA^T} Q e^{sA} ds`, computed once per mode ([`weights`],
//! Van Loan, IEEE Trans. Autom. Control 23, 1978, section 2, by the doubling
//! `W(2τ) = W(τ) + e^{τA^T} W(τ) e^{τA}` from a short span where 3-point Gauss-Legendre is
//! exact to rounding). A record therefore sums only the outer products `u_k u_k^T` of each
//! mode's intervals (its Gram sum) and contracts them with each `W` when they are folded into
//! the books: one rank-one update per interval, exact for the exact steps. The forms `Q` are
//! read off the model's own powers and outputs by evaluating them at a few states near a point
//! inside the mode (a quadratic's coefficients by polarisation) and checking the fit at another;
//! a mode whose fit fails, or whose affine form misses its right-hand side, is left to
//! Dormand-Prince.

use nalgebra::{DMatrix, SMatrix, SVector};

use crate::model::{AffineGuard, DrivenAffine, Mode, Model, MAX_OUTPUTS};
use crate::ode::phi::{expm_n, phi_functions};
use crate::ode::GAUSS_LEGENDRE_3;
use crate::study::flow::{cubic_max, GRAZE_MARGIN};

use super::books::{integrands, Books, Found};
use super::crossings::{walk, ModeTable, Rebounding, MAX_GUARDS};
use super::impacts::Rebounds;
use super::stepping::{self, FastPath, NoFast};
use super::{Fallback, FreeFlightPath, Record, RecordError, RecordObserver, SampledDrive};

/// Rows of the guard matrix: each guard's value and its rate times the step.
const GUARD_ROWS: usize = 2 * MAX_GUARDS;
/// The guards' values and scaled rates at a state.
type GuardValues = SVector<f64, GUARD_ROWS>;

/// Equal parts of an interval on which a guard that comes near zero is looked at again
/// ([`AffineMode::step`]).
const PARTS: usize = 8;

/// Runs a record of a model without a free-flight split on its affine modes, or on
/// Dormand-Prince throughout when it has none. The loop is compiled for the augmented state's
/// dimension `U = N + 3`.
pub(super) fn run<M: Model<N>, O: RecordObserver, const N: usize>(
    model: &M,
    drive: &SampledDrive,
    rtol: f64,
    observer: &mut O,
    books: Option<Books<N>>,
) -> Result<(Record, Option<Found>), RecordError> {
    let h = 1.0 / drive.sample_rate_hz;
    let integrals = books.as_ref().map(Books::integrands);
    if model.modes().iter().any(|m| model.affine(*m).is_some()) {
        macro_rules! on {
            ($u:literal) => {{
                let fast = AffineModes::<N, $u>::new(h, integrals);
                return stepping::run(model, drive, rtol, fast, observer, books);
            }};
        }
        match N {
            2 => on!(5),
            3 => on!(6),
            4 => on!(7),
            5 => on!(8),
            6 => on!(9),
            _ => {}
        }
    }
    let fast = NoFast(Fallback::NoExactMode);
    stepping::run(model, drive, rtol, fast, observer, books)
}

/// One affine mode on the sample grid (see the module docs), for the state's dimension `N` and
/// the augmented state's `U = N + 3`.
#[derive(Debug, Clone, PartialEq)]
struct AffineMode<const N: usize, const U: usize> {
    /// The columns of `P`, the state's rows of `e^{hA}`: the next state is `P u_k`. Plain
    /// columns of the state's fixed length, so that the product is a few vector operations
    /// on an accumulator held in registers.
    state_columns: [[f64; N]; U],
    /// The columns of `G e^{hA}`: `G` holds the guards as rows on `u` (row `2j` guard `j`'s
    /// value, row `2j + 1` its rate times the step, each divided by the guard's scale, the
    /// norm of its gradient on the state's characteristic scales, so that [`GRAZE_MARGIN`]
    /// applies to each; an unused guard is the constant -1), so that `G e^{hA} u_k` are the
    /// guards at the next sample. Columns, as the state's, so that a step sums the used
    /// guards' rows in the same pass over `u` as the state, a few vector operations per
    /// component of `u`.
    next_guard_columns: [[f64; GUARD_ROWS]; U],
    /// Guards in use (the first ones).
    used: usize,
    /// `G e^{i h A / PARTS}` for `i = 1 .. PARTS - 1`: the guards inside the interval.
    inner: [SMatrix<f64, GUARD_ROWS, U>; PARTS - 1],
    /// `G`.
    guards: SMatrix<f64, GUARD_ROWS, U>,
    /// `W` of each integrand of the books (none when the record keeps no books).
    weights: Vec<SMatrix<f64, U, U>>,
    /// The interval's rebounds off rigid stops on the exact solution, where the mode has
    /// rigid stops to meet (`crossings.rs`).
    rebounding: Option<Rebounding<U>>,
}

impl<const N: usize, const U: usize> AffineMode<N, U> {
    /// The augmented state at a sample: the state, the drive there and its slope to the next
    /// sample.
    #[inline(always)]
    fn augment(y: &SVector<f64, N>, a: f64, slope: f64) -> [f64; U] {
        let mut u = [0.0; U];
        u[..N].copy_from_slice(y.as_slice());
        u[N] = a;
        u[N + 1] = slope;
        u[U - 1] = 1.0;
        u
    }

    /// The guards at the augmented state `u`.
    fn guards_at(&self, u: &[f64; U]) -> GuardValues {
        self.guards * SVector::<f64, U>::from_column_slice(u)
    }

    /// The state one interval after `u0` (whose guards are `g0`), its used guards there
    /// written into `g1`, or `None` when a guard may turn positive inside the interval: its
    /// cubic Hermite estimate (exact values and rates at both ends) comes within
    /// [`GRAZE_MARGIN`] of zero.
    #[inline(always)]
    fn step(
        &self,
        u0: &[f64; U],
        g0: &GuardValues,
        g1: &mut GuardValues,
    ) -> Option<SVector<f64, N>> {
        // The unused guards' values are never read: the pass sums the used guards' rows only,
        // compiled for their count.
        let y1 = match self.used {
            0 => self.advance::<0>(u0, g1),
            1 => self.advance::<2>(u0, g1),
            2 => self.advance::<4>(u0, g1),
            3 => self.advance::<6>(u0, g1),
            4 => self.advance::<8>(u0, g1),
            _ => self.advance::<GUARD_ROWS>(u0, g1),
        };
        for j in 0..self.used {
            let (v0, d0, v1, d1) = (g0[2 * j], g0[2 * j + 1], g1[2 * j], g1[2 * j + 1]);
            // The Hermite basis functions of the slopes are at most 4/27 in absolute value and
            // those of the values are non-negative and sum to one.
            if v0.max(v1) + 4.0 / 27.0 * (d0.abs() + d1.abs()) < -GRAZE_MARGIN {
                continue;
            }
            if cubic_max(v0, d0, v1, d1) >= -GRAZE_MARGIN && !self.clear_on_parts(u0, g0, g1) {
                return None;
            }
        }
        Some(SVector::from(y1))
    }

    /// The state one interval after `u0` and the first `R` rows of the guards there (written
    /// into `g1`), in one pass over `u0` by columns: each sum runs over `u` in order from
    /// zero, the dot product of a row with `u0`.
    #[inline(always)]
    fn advance<const R: usize>(&self, u0: &[f64; U], g1: &mut GuardValues) -> [f64; N] {
        let mut y1 = [0.0; N];
        let mut g = [0.0; R];
        for ((col, guard_col), &uj) in self
            .state_columns
            .iter()
            .zip(&self.next_guard_columns)
            .zip(u0)
        {
            for (yi, ci) in y1.iter_mut().zip(col) {
                *yi += ci * uj;
            }
            for (gi, ci) in g.iter_mut().zip(guard_col) {
                *gi += ci * uj;
            }
        }
        g1.as_mut_slice()[..R].copy_from_slice(&g);
        y1
    }

    /// True when every guard stays clear of zero on each of [`PARTS`] equal parts of the
    /// interval: its cubic Hermite estimate on each part, from its exact values and rates at
    /// the parts' ends, stays below `-GRAZE_MARGIN / PARTS^4` (the estimate's error shrinks
    /// as the fourth power of the span). A guard that comes near zero without crossing (a
    /// bridge's voltage after conduction, which leaves the threshold with zero slope) then
    /// costs one more look, not an interval of Dormand-Prince.
    #[cold]
    fn clear_on_parts(&self, u0: &[f64; U], g0: &GuardValues, g1: &GuardValues) -> bool {
        let u = SVector::<f64, U>::from_column_slice(u0);
        let margin = GRAZE_MARGIN / (PARTS as f64).powi(4);
        let per_part = 1.0 / PARTS as f64;
        let mut prev = *g0;
        for i in 1..=PARTS {
            let next = if i < PARTS {
                self.inner[i - 1] * u
            } else {
                *g1
            };
            for j in 0..self.used {
                let peak = cubic_max(
                    prev[2 * j],
                    prev[2 * j + 1] * per_part,
                    next[2 * j],
                    next[2 * j + 1] * per_part,
                );
                if peak >= -margin {
                    return false;
                }
            }
            prev = next;
        }
        true
    }

    /// The mode `mode` of `model` for the interval `h` with the weights of `integrals`
    /// integrands of the books (none: the record keeps no books), or `None` when it is not
    /// affine (see the module docs).
    fn of<M: Model<N>>(model: &M, mode: Mode, h: f64, integrals: Option<usize>) -> Option<Self> {
        if U != N + 3 {
            return None;
        }
        let DrivenAffine { affine, drive } = model.driven_affine(mode)?;
        let sc = model.scales();
        let (ix, iv) = model.layout().masses.first().copied().unwrap_or((0, 1));
        let a_scale = sc[iv] / sc[ix] * sc[iv];
        let base = inside(model, mode);
        let mut a = SMatrix::<f64, U, U>::zeros();
        for i in 0..N {
            for j in 0..N {
                a[(i, j)] = affine.l[(i, j)];
            }
            a[(i, N)] = affine.c[i];
            a[(i, U - 1)] = affine.d[i];
        }
        a[(N, N + 1)] = 1.0;
        if !matches_rhs(model, mode, &a, &base, a_scale) {
            return None;
        }
        let mut scale = SVector::<f64, U>::repeat(1.0);
        for i in 0..N {
            scale[i] = sc[i];
        }
        scale[N] = a_scale;
        scale[N + 1] = a_scale / h;
        let q = match integrals {
            Some(count) => {
                let mut z = base.as_slice().to_vec();
                z.push(a_scale);
                let mut eps: Vec<f64> = sc.iter().map(|s| 0.25 * s).collect();
                eps.push(0.25 * a_scale);
                let f = |z: &[f64]| {
                    let mut v = vec![0.0; count];
                    let y = SVector::<f64, N>::from_column_slice(&z[..N]);
                    integrands(model, mode, &y, z[N], &mut v);
                    v
                };
                fit_quadratic::<N, U>(f, &z, &eps)?
            }
            None => Vec::new(),
        };
        let (e, weights) = weights(&a, &q, h, &scale);
        let part = {
            let d = SMatrix::<f64, U, U>::from_diagonal(&scale);
            let d_inv = SMatrix::<f64, U, U>::from_diagonal(&scale.map(|s| 1.0 / s));
            d * expm_n(&(d_inv * a * d * (h / PARTS as f64))) * d_inv
        };
        let (guards, used) = guard_rows::<N, U>(&affine.guards, &drive, &a, h, &scale)?;
        let rebounding = Rebounding::of(model, mode, &affine.guards, &guards, &a, &scale, h);
        let next_guards = guards * e;
        let mut power = part;
        let inner = std::array::from_fn(|_| {
            let g = guards * power;
            power *= part;
            g
        });
        let state_columns = std::array::from_fn(|j| std::array::from_fn(|i| e[(i, j)]));
        let next_guard_columns =
            std::array::from_fn(|j| std::array::from_fn(|i| next_guards[(i, j)]));
        Some(Self {
            state_columns,
            next_guard_columns,
            used,
            inner,
            guards,
            weights,
            rebounding,
        })
    }
}

/// A point inside `mode` of `model`: the rest state, or for a contact past the stop and moving
/// on into it, so that a tension-free stop's bracket is positive.
fn inside<M: Model<N>, const N: usize>(model: &M, mode: Mode) -> SVector<f64, N> {
    let mut y = SVector::<f64, N>::zeros();
    let sc = model.scales();
    if let Some((k, _)) = mode.touching() {
        if let Some(c) = model.contacts().get(k) {
            // The mass that moves into the contact: the frame's contact's own, or the other
            // mass of a contact between two (their separation grows towards it).
            let mover = c.other.unwrap_or(c.mass);
            if let Some(&(ix, iv)) = model.layout().masses.get(mover) {
                y[ix] = c.side * (c.gap + sc[ix]);
                y[iv] = c.side * sc[iv];
            }
        }
    }
    for &i in model.unused() {
        y[i] = 0.0;
    }
    y
}

/// True when the augmented matrix `a` of `mode` gives its right-hand side at states about
/// `base` to rounding (1e-9 of each row's largest term): the model's affine form and its
/// equations agree.
fn matches_rhs<M: Model<N>, const N: usize, const U: usize>(
    model: &M,
    mode: Mode,
    a: &SMatrix<f64, U, U>,
    base: &SVector<f64, N>,
    a_scale: f64,
) -> bool {
    let sc = model.scales();
    let unused = model.unused();
    let pattern = [0.3, -0.7, 0.45, 0.2, -0.55, 0.35, -0.25, 0.6, -0.15];
    for p in 0..3 {
        let mut y = *base;
        for i in 0..N {
            if !unused.contains(&i) {
                y[i] += 0.2 * pattern[(i + 3 * p) % pattern.len()] * sc[i];
            }
        }
        let acc = pattern[(N + p) % pattern.len()] * a_scale;
        let f = model.rhs(mode, &y, acc);
        for i in 0..N {
            let mut g = a[(i, N)] * acc + a[(i, U - 1)];
            let mut size = f[i].abs() + g.abs();
            for j in 0..N {
                g += a[(i, j)] * y[j];
                size += (a[(i, j)] * y[j]).abs();
            }
            if (f[i] - g).abs() > 1e-9 * size {
                return false;
            }
        }
    }
    true
}

/// The guards of a mode as rows on `u` (see [`AffineMode`]), guard `j` with the coefficient
/// `drive[j]` on the drive, and how many there are, or `None` when there are more than
/// [`MAX_GUARDS`] or one is constant; `scale` holds the augmented state's scales.
fn guard_rows<const N: usize, const U: usize>(
    list: &[AffineGuard<N>],
    drive: &[f64],
    a: &SMatrix<f64, U, U>,
    h: f64,
    scale: &SVector<f64, U>,
) -> Option<(SMatrix<f64, GUARD_ROWS, U>, usize)> {
    if list.len() > MAX_GUARDS || drive.len() != list.len() {
        return None;
    }
    let mut rows = SMatrix::<f64, GUARD_ROWS, U>::zeros();
    for (j, (g, &w)) in list.iter().zip(drive).enumerate() {
        let mut value = SVector::<f64, U>::zeros();
        value.fixed_rows_mut::<N>(0).copy_from(&g.n);
        value[N] = w;
        let norm = value.component_mul(scale).norm();
        if !(norm > 0.0 && norm.is_finite()) {
            return None;
        }
        value /= norm;
        value[U - 1] = g.g0 / norm;
        let rate = a.transpose() * value * h;
        rows.set_row(2 * j, &value.transpose());
        rows.set_row(2 * j + 1, &rate.transpose());
    }
    for j in list.len()..MAX_GUARDS {
        rows[(2 * j, U - 1)] = -1.0;
    }
    Some((rows, list.len()))
}

/// The homogeneous quadratic forms on `u` (its `a'` unused) of each output of `f`, a
/// quadratic function of `z = (y, a)`, by polarisation about `base` with steps `eps`; `None`
/// when the fit misses `f` at another point by more than rounding (1e-9 of the form's size).
fn fit_quadratic<const N: usize, const U: usize>(
    f: impl Fn(&[f64]) -> Vec<f64>,
    base: &[f64],
    eps: &[f64],
) -> Option<Vec<SMatrix<f64, U, U>>> {
    let d = N + 1;
    let at = |off: &[f64]| {
        let z: Vec<f64> = (0..d).map(|i| base[i] + off[i] * eps[i]).collect();
        f(&z)
    };
    let unit = |i: usize, s: f64| {
        let mut o = vec![0.0; d];
        o[i] = s;
        o
    };
    let f0 = at(&vec![0.0; d]);
    let m = f0.len();
    let plus: Vec<Vec<f64>> = (0..d).map(|i| at(&unit(i, 1.0))).collect();
    let minus: Vec<Vec<f64>> = (0..d).map(|i| at(&unit(i, -1.0))).collect();
    let beta = |i: usize, k: usize| (plus[i][k] - minus[i][k]) / 2.0;
    let diag = |i: usize, k: usize| (plus[i][k] + minus[i][k]) / 2.0 - f0[k];
    // In the scaled offsets o (z = base + eps o): f = f0 + beta . o + o^T H o, written on
    // (o, 1) as a symmetric form for each output, then mapped to (z, 1) and onto u.
    let mut h: Vec<DMatrix<f64>> = (0..m)
        .map(|k| {
            let mut hk = DMatrix::<f64>::zeros(d + 1, d + 1);
            hk[(d, d)] = f0[k];
            for i in 0..d {
                hk[(i, i)] = diag(i, k);
                hk[(i, d)] = beta(i, k) / 2.0;
                hk[(d, i)] = beta(i, k) / 2.0;
            }
            hk
        })
        .collect();
    for i in 0..d {
        for j in i + 1..d {
            let mut o = vec![0.0; d];
            o[i] = 1.0;
            o[j] = 1.0;
            let fij = at(&o);
            for (k, hk) in h.iter_mut().enumerate() {
                let cross = fij[k] - f0[k] - beta(i, k) - beta(j, k) - diag(i, k) - diag(j, k);
                hk[(i, j)] = cross / 2.0;
                hk[(j, i)] = cross / 2.0;
            }
        }
    }
    // o = T (z, 1).
    let mut t = DMatrix::<f64>::zeros(d + 1, d + 1);
    for i in 0..d {
        t[(i, i)] = 1.0 / eps[i];
        t[(i, d)] = -base[i] / eps[i];
    }
    t[(d, d)] = 1.0;
    let pattern = [0.3, -0.7, 0.45, 0.2, -0.55, 0.35, -0.25, 0.6, -0.15];
    let check: Vec<f64> = (0..d).map(|i| pattern[i % pattern.len()]).collect();
    let fc = at(&check);
    let mut oc = DMatrix::<f64>::from_element(d + 1, 1, 1.0);
    for (i, c) in check.iter().enumerate() {
        oc[(i, 0)] = *c;
    }
    // (z, 1) to u = (y, a, a', 1).
    let map = |i: usize| if i < d { i } else { U - 1 };
    let mut out = Vec::with_capacity(m);
    for (k, hk) in h.iter().enumerate() {
        let size = hk.iter().map(|v| v.abs()).sum::<f64>();
        let value = (oc.transpose() * hk * &oc)[(0, 0)];
        if (value - fc[k]).abs() > 1e-9 * size {
            return None;
        }
        let qz = t.transpose() * hk * &t;
        let mut qk = SMatrix::<f64, U, U>::zeros();
        for i in 0..=d {
            for j in 0..=d {
                qk[(map(i), map(j))] = qz[(i, j)];
            }
        }
        out.push(qk);
    }
    Some(out)
}

/// `e^{hA}` and `W_i = ∫_0^h e^{sA^T} Q_i e^{sA} ds` for each integrand `Q_i`, computed on the
/// scaled `D^-1 A D` (`D` the diagonal of `scale`) by doubling from a span `τ` with
/// `|τ D^-1 A D| <= 1/64`, where 3-point Gauss-Legendre is exact to rounding (see the module
/// docs).
fn weights<const U: usize>(
    a: &SMatrix<f64, U, U>,
    q: &[SMatrix<f64, U, U>],
    h: f64,
    scale: &SVector<f64, U>,
) -> (SMatrix<f64, U, U>, Vec<SMatrix<f64, U, U>>) {
    let d = SMatrix::<f64, U, U>::from_diagonal(scale);
    let d_inv = SMatrix::<f64, U, U>::from_diagonal(&scale.map(|s| 1.0 / s));
    let a_s = d_inv * a * d;
    let norm = (a_s * h).norm();
    let doublings = if norm > 1.0 / 64.0 {
        (norm * 64.0).log2().ceil() as i32
    } else {
        0
    };
    let tau = h / 2f64.powi(doublings);
    let nodes = GAUSS_LEGENDRE_3.map(|(x, w)| (expm_n(&(a_s * (x * tau))), w * tau));
    let mut w: Vec<SMatrix<f64, U, U>> = q
        .iter()
        .map(|qi| {
            let qs = d * qi * d;
            nodes
                .iter()
                .map(|(e, wt)| e.transpose() * qs * e * *wt)
                .sum()
        })
        .collect();
    let mut e = expm_n(&(a_s * tau));
    for _ in 0..doublings {
        for wi in w.iter_mut() {
            *wi += e.transpose() * *wi * e;
        }
        e = e * e;
    }
    // The propagator itself by the φ functions' series where the step resolves the mode (every
    // entry to rounding), not by the squarings: a storage capacitor that loses 2.4e-5 of its
    // charge per interval (RL Cs = 0.42 s) would otherwise carry the squarings' 1e-14 into its
    // decay rate as 4e-10, a bias that grows over a record.
    let e = phi_functions(&(a * h), 0, scale)[0];
    (e, w.into_iter().map(|wi| d_inv * wi * d_inv).collect())
}

/// A Gram sum `Σ u_k u_k^T`, by columns.
#[derive(Debug, Clone, Copy)]
struct Gram<const U: usize>([[f64; U]; U]);

impl<const U: usize> Gram<U> {
    /// Adds `u u^T`.
    #[inline(always)]
    fn add(&mut self, u: &[f64; U]) {
        for (col, &uj) in self.0.iter_mut().zip(u) {
            for (c, ui) in col.iter_mut().zip(u) {
                *c += ui * uj;
            }
        }
    }
}

/// The affine modes of a record met so far, each prepared when first met, with each mode's
/// Gram sum `Σ u_k u_k^T` over the intervals it advanced since the books last took them.
struct Modes<const N: usize, const U: usize> {
    h: f64,
    /// The books' integrands, when the record keeps them.
    integrals: Option<usize>,
    /// Each mode met, its affine form if it has one, and its Gram sum.
    entries: Vec<(Mode, Option<AffineMode<N, U>>, Gram<U>)>,
}

impl<const N: usize, const U: usize> Modes<N, U> {
    /// The index of `mode`, preparing it when it is new.
    fn index<M: Model<N>>(&mut self, model: &M, mode: Mode) -> usize {
        if let Some(i) = self.entries.iter().position(|(m, _, _)| *m == mode) {
            return i;
        }
        let affine = AffineMode::of(model, mode, self.h, self.integrals);
        self.entries.push((mode, affine, Gram([[0.0; U]; U])));
        self.entries.len() - 1
    }
}

impl<const N: usize, const U: usize> ModeTable<N, U> for Modes<N, U> {
    fn crossings_of<M: Model<N>>(&mut self, model: &M, mode: Mode) -> Option<&Rebounding<U>> {
        let i = self.index(model, mode);
        self.entries[i].1.as_ref()?.rebounding.as_ref()
    }
}

/// The record's fast path for a model without a free-flight split: its affine modes
/// ([`Modes`]), the current one's guards, and what the last interval met inside it.
pub(super) struct AffineModes<const N: usize, const U: usize> {
    modes: Modes<N, U>,
    /// The current mode and its entry.
    current: Option<(Mode, usize)>,
    /// The current mode's guards at the current sample, where [`Self::guards_known`]: kept
    /// apart from the mode, so that a step reads them in place.
    guards_now: GuardValues,
    /// Whether [`Self::guards_now`] holds the guards at the current sample.
    guards_known: bool,
    /// The impacts inside the last interval.
    rebounds: Rebounds,
    /// The states at those impacts, before each reset.
    rebound_states: Vec<SVector<f64, N>>,
    /// The mode at the last interval's end and its time in contact (s), where switches inside
    /// it were applied on the exact solution.
    inside: Option<(Mode, f64)>,
}

impl<const N: usize, const U: usize> AffineModes<N, U> {
    /// No mode yet, on intervals of `h`, with the books' `integrals` integrands.
    fn new(h: f64, integrals: Option<usize>) -> Self {
        Self {
            modes: Modes {
                h,
                integrals,
                entries: Vec::new(),
            },
            current: None,
            guards_now: GuardValues::zeros(),
            guards_known: false,
            rebounds: Rebounds::default(),
            rebound_states: Vec::new(),
            inside: None,
        }
    }
}

impl<M: Model<N>, const N: usize, const U: usize> FastPath<M, N> for AffineModes<N, U> {
    const RHS_EVALS: u64 = 0;

    fn path(&self) -> FreeFlightPath {
        FreeFlightPath::Affine
    }

    #[inline(always)]
    fn step(
        &mut self,
        model: &M,
        _t0: f64,
        y: &SVector<f64, N>,
        mode: Mode,
        [a0, a1]: [f64; 2],
        _outputs: &mut [f64; MAX_OUTPUTS],
        books: Option<&mut Books<N>>,
    ) -> Option<(SVector<f64, N>, bool)> {
        self.rebounds.len = 0;
        self.rebound_states.clear();
        self.inside = None;
        let index = match self.current {
            Some((m, i)) if m == mode => i,
            _ => {
                self.guards_known = false;
                let i = self.modes.index(model, mode);
                self.current = Some((mode, i));
                i
            }
        };
        let (_, affine, gram) = &mut self.modes.entries[index];
        let affine = affine.as_ref()?;
        let h = self.modes.h;
        let slope = (a1 - a0) / h;
        let u0 = AffineMode::<N, U>::augment(y, a0, slope);
        if !self.guards_known {
            self.guards_now = affine.guards_at(&u0);
        }
        let mut g1 = GuardValues::zeros();
        let Some(mut y1) = affine.step(&u0, &self.guards_now, &mut g1) else {
            self.guards_known = false;
            // A guard may fire: the switches the exact solution locates (rigid stops'
            // rebounds, a contact that comes to rest or is released), where the books (which
            // take whole intervals of one mode) are not kept.
            if books.is_some() {
                return None;
            }
            let walked = walk(
                model,
                &mut self.modes,
                mode,
                y,
                a0,
                slope,
                h,
                &mut self.rebound_states,
            )?;
            self.rebounds = walked.impacts;
            self.inside = Some((walked.mode, walked.contact_s));
            self.current = Some((walked.mode, self.modes.index(model, walked.mode)));
            return Some((walked.y, false));
        };
        if let Some(r) = affine.rebounding.as_ref() {
            r.hold(&mut y1);
        }
        if let Some(b) = books {
            b.open(model, mode, y);
            gram.add(&u0);
            b.close(mode, &y1);
        }
        self.guards_now = g1;
        self.guards_known = true;
        Some((y1, false))
    }

    fn rebounds(&self) -> &[(f64, f64)] {
        self.rebounds.found()
    }

    fn rebound_states(&self) -> &[SVector<f64, N>] {
        &self.rebound_states
    }

    fn inside(&self) -> Option<(Mode, f64)> {
        self.inside
    }

    fn after_dopri(&mut self, _model: &M, _y: &SVector<f64, N>, _mode: Mode, _switched: bool) {
        self.guards_known = false;
    }

    /// Each integral over the intervals the affine modes advanced since the last fold:
    /// `Σ_modes Σ_ij W_ij G_ij`.
    fn flush(&mut self, books: &mut Books<N>) {
        let Some(count) = self.modes.integrals else {
            return;
        };
        let mut out = vec![0.0; count];
        for (_, affine, gram) in self.modes.entries.iter_mut() {
            if let Some(affine) = affine {
                let g = SMatrix::<f64, U, U>::from_fn(|i, j| gram.0[j][i]);
                for (o, w) in out.iter_mut().zip(&affine.weights) {
                    *o += w.component_mul(&g).sum();
                }
            }
            *gram = Gram([[0.0; U]; U]);
        }
        books.add(&out);
    }
}
