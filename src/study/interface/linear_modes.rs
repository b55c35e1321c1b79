//! The linear modes of a harvester with an interface circuit on the sample grid of a linearly
//! interpolated drive: each mode's exact propagator over one sample interval, its guards as
//! affine functions of the state, and the exact integrals over the interval of the energy
//! ledger's power terms and of the storage voltage.
//!
//! # The augmented state
//! Between switchings a mode of the circuit ([`crate::physics::interface`]) is
//! `y' = L y + c a(t) + d`, with the forward drops and a battery's voltage in `d`. Over a
//! sample interval the drive is `a(t_k + s) = a_k + a' s` with the constant slope
//! `a' = (a_{k+1} - a_k) / h`, so the augmented state `u = (y, a, a', 1)` obeys the
//! time-invariant `u' = A u`: one matrix exponential `e^{hA}` per mode advances any state
//! over any interval, for any stiffness (a coil that relaxes in a quarter of the interval is
//! integrated as exactly as a slow mode). The propagator comes from
//! [`crate::ode::phi::phi_functions`] (the series where the interval resolves the mode, which
//! gives each entry to rounding: a storage capacitor that loses 2.4e-5 of its charge per
//! interval needs that, or the error of its decay rate grows over a record).
//!
//! # Guards
//! Every guard of a linear mode (a stop's penetration, a linear contact's bracket, the bridge's
//! conduction threshold or current, the switch's velocity) is affine in the state, and so is
//! its rate: both are rows on `u`, evaluated at each sample. [`LinearMode::step`] refuses an
//! interval in which a guard may turn positive, and its caller hands that interval to
//! Dormand-Prince.
//!
//! # The ledger by Gram sums
//! Every power term of [`InterfaceAudit`] (the drive's `m a v`, the dampers' `b v^2`, the
//! coil's `Rc I^2`, the diodes' `2 V_F i + 2 R_on i^2`, the load's `Vs I_L(Vs)`) is a
//! quadratic form `u^T Q u` in a linear mode, and the storage voltage a linear one. Over an
//! interval its integral is `u_k^T W u_k` with `W = ∫_0^h e^{sA^T} Q e^{sA} ds`, computed once
//! per mode ([`weights`], Van Loan, IEEE Trans. Autom. Control 23, 1978, section 2, by the
//! doubling `W(2τ) = W(τ) + e^{τA^T} W(τ) e^{τA}` from a short span where 3-point
//! Gauss-Legendre is exact to rounding). A record therefore sums only the outer products
//! `u_k u_k^T` of each mode's intervals (its Gram sum) and contracts them with each `W` at the
//! end: the ledger costs one rank-one update per interval, and is exact for the exact steps.
//!
//! # Where a mode is linear, and how its matrices are found
//! A mode is linear when the suspension is linear, the contact is free, clipped, or a linear
//! spring with a viscous damper ([`Mode::Stuck`] is an algebraic phase of its own and a
//! nonlinear law is not affine), and the bridge's diodes are piecewise linear where the bridge
//! connects the element to the storage. Shockley diodes have no modes (their current is
//! exponential in the voltage at every instant), so a record with them stays on
//! Dormand-Prince. The matrices are read off the audit's own right-hand side and guards, by
//! evaluating them at a few states near a point inside the mode (a quadratic's coefficients
//! by polarisation) and checking the fit at another: the exact step integrates the same
//! equations as [`crate::ode::Dopri5`] does, by construction, and a mode whose fit fails the
//! check is left to Dormand-Prince.

use std::cell::Cell;

use nalgebra::{SMatrix, SVector};

use crate::drive::Excitation;
use crate::ode::phi::phi_functions;
use crate::ode::{HybridSystem, GAUSS_LEGENDRE_3};
use crate::physics::contact::{ContactDamping, ContactLaw, Mode, StopModel};
use crate::physics::harvester::State;
use crate::physics::interface::{
    Bridge, DiodeLaw, IfMode, InterfaceAudit, Interfaced, IF_AUDIT_DIM,
};
use crate::study::flow::{cubic_max, GRAZE_MARGIN};

/// Dimension of the augmented state `(x, v, e1, e2, a, a', 1)`.
pub(crate) const U: usize = 7;
/// The augmented state.
pub(crate) type UVec = SVector<f64, U>;
/// A matrix on the augmented state.
pub(crate) type UMat = SMatrix<f64, U, U>;

/// Most guards of a mode: the contact's two, the conduction's two pieces while the bridge is
/// off (`±Vp` or `±Phi v` against `Vs + 2 V_F`), and the extremum's.
const MAX_GUARDS: usize = 5;
/// Rows of the guard matrix: each guard's value and its rate times the step.
const GUARD_ROWS: usize = 2 * MAX_GUARDS;
/// The guards' values and scaled rates at a state.
pub(crate) type GuardValues = SVector<f64, GUARD_ROWS>;

/// The integrals of a mode: the audit's accumulators (its states 4 to 14), then the storage
/// voltage.
pub(crate) const INTEGRALS: usize = IF_AUDIT_DIM - 4 + 1;

/// The outputs fitted: the audit's right-hand side and the storage voltage.
const OUTPUTS: usize = IF_AUDIT_DIM + 1;

/// A constant drive whose value the fit sets.
struct Held(Cell<f64>);

impl Excitation for Held {
    fn accel(&self, _t: f64) -> f64 {
        self.0.get()
    }
}

/// Equal parts of an interval on which a guard that comes near zero is looked at again
/// ([`LinearMode::step`]).
const PARTS: usize = 8;

/// Rows of a step's product: the next state's four, then the guards' at the next sample.
const STEP_ROWS: usize = 4 + GUARD_ROWS;

/// One linear mode on the sample grid (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct LinearMode {
    /// The columns of `[P; G e^{hA}]`: `P`, the state's rows of `e^{hA}`, gives the next
    /// state `P u_k`; `G` holds the guards as rows on `u` (row `2j` guard `j`'s value, row
    /// `2j + 1` its rate times the step, each divided by the guard's scale, the norm of its
    /// gradient on the state's characteristic scales, so that [`GRAZE_MARGIN`] applies to
    /// each; an unused guard is the constant -1), so that `G e^{hA} u_k` are the guards at
    /// the next sample. Plain columns, so that the product is a few vector operations.
    step_columns: [[f64; STEP_ROWS]; U],
    /// Guards in use (the first ones).
    used: usize,
    /// `G e^{i h A / PARTS}` for `i = 1 .. PARTS - 1`: the guards inside the interval.
    inner: [SMatrix<f64, GUARD_ROWS, U>; PARTS - 1],
    /// `G`.
    guards: SMatrix<f64, GUARD_ROWS, U>,
    /// `W` of each integral ([`INTEGRALS`]).
    pub(crate) weights: [UMat; INTEGRALS],
}

impl LinearMode {
    /// The augmented state at a sample: the state, the drive there and its slope to the next
    /// sample.
    #[inline(always)]
    pub(crate) fn augment(y: &State, a: f64, slope: f64) -> [f64; U] {
        [y[0], y[1], y[2], y[3], a, slope, 1.0]
    }

    /// The guards at the augmented state `u`.
    pub(crate) fn guards_at(&self, u: &[f64; U]) -> GuardValues {
        self.guards * UVec::from_column_slice(u)
    }

    /// The state one interval after `u0` (whose guards are `g0`) with its guards there, or
    /// `None` when a guard may turn positive inside the interval: its cubic Hermite estimate
    /// (exact values and rates at both ends) comes within [`GRAZE_MARGIN`] of zero.
    #[inline(always)]
    pub(crate) fn step(&self, u0: &[f64; U], g0: &GuardValues) -> Option<(State, GuardValues)> {
        let mut r = [0.0; STEP_ROWS];
        for (col, &uj) in self.step_columns.iter().zip(u0) {
            for (ri, ci) in r.iter_mut().zip(col) {
                *ri += ci * uj;
            }
        }
        let g1 = GuardValues::from_column_slice(&r[4..]);
        for j in 0..self.used {
            let (v0, d0, v1, d1) = (g0[2 * j], g0[2 * j + 1], g1[2 * j], g1[2 * j + 1]);
            // The Hermite basis functions of the slopes are at most 4/27 in absolute value and
            // those of the values are non-negative and sum to one.
            if v0.max(v1) + 4.0 / 27.0 * (d0.abs() + d1.abs()) < -GRAZE_MARGIN {
                continue;
            }
            if cubic_max(v0, d0, v1, d1) >= -GRAZE_MARGIN && !self.clear_on_parts(u0, g0, &g1) {
                return None;
            }
        }
        Some((State::new(r[0], r[1], r[2], r[3]), g1))
    }

    /// True when every guard stays clear of zero on each of [`PARTS`] equal parts of the
    /// interval: its cubic Hermite estimate on each part, from its exact values and rates at
    /// the parts' ends, stays below `-GRAZE_MARGIN / PARTS^4` (the estimate's error shrinks
    /// as the fourth power of the span). A guard that comes near zero without crossing (the
    /// bridge's voltage after conduction, which leaves the threshold with zero slope) then
    /// costs one more look, not an interval of Dormand-Prince.
    #[cold]
    fn clear_on_parts(&self, u0: &[f64; U], g0: &GuardValues, g1: &GuardValues) -> bool {
        let u = UVec::from_column_slice(u0);
        let margin = GRAZE_MARGIN / (PARTS as f64).powi(4);
        let mut prev = *g0;
        for i in 1..=PARTS {
            let next = if i < PARTS {
                self.inner[i - 1] * u
            } else {
                *g1
            };
            for j in 0..self.used {
                let per_part = 1.0 / PARTS as f64;
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

    /// The mode `mode` of `audit` for the interval `h`, or `None` when it is not linear (see
    /// the module docs).
    pub(crate) fn of<E: Excitation>(
        audit: &InterfaceAudit<E>,
        mode: IfMode,
        h: f64,
    ) -> Option<Self> {
        let model = &audit.0;
        if !is_linear(model, mode) {
            return None;
        }
        let held = model.with_excitation(Held(Cell::new(0.0)));
        let sc = model.scales();
        let w0 = sc[1] / sc[0];
        let a_scale = w0 * sc[1];
        // A point inside the mode: past the stop and moving on into it in contact, so that a
        // tension-free stop's bracket is positive.
        let mut base = SVector::<f64, 5>::new(0.0, 0.0, 0.0, 0.0, a_scale);
        if let Mode::Contact(side) | Mode::Clipped(side) = mode.contact {
            let s = side.sign();
            base[0] = s * (model.h.gap(side) + sc[0]);
            base[1] = s * sc[1];
        }
        let eps = SVector::<f64, 5>::new(
            0.25 * sc[0],
            0.25 * sc[1],
            0.25 * sc[2],
            0.25 * sc[3],
            0.25 * a_scale,
        );
        let audit_held = InterfaceAudit(held);
        let rates = |z: &SVector<f64, 5>| {
            audit_held.0.h.excitation.0.set(z[4]);
            let mut w = SVector::<f64, IF_AUDIT_DIM>::zeros();
            w.fixed_rows_mut::<4>(0).copy_from(&z.fixed_rows::<4>(0));
            let r = audit_held.rhs(mode, 0.0, &w);
            let mut out = SVector::<f64, OUTPUTS>::zeros();
            out.fixed_rows_mut::<IF_AUDIT_DIM>(0).copy_from(&r);
            out[IF_AUDIT_DIM] = z[3];
            out
        };
        let (q, affine) = fit_quadratic(rates, &base, &eps)?;
        // The state's rows of A are affine: their quadratic parts vanish.
        if !affine[..4].iter().all(|&x| x) {
            return None;
        }
        let mut a = UMat::zeros();
        for (k, qk) in q.iter().take(4).enumerate() {
            for j in 0..5 {
                a[(k, j)] = 2.0 * qk[(j, U - 1)];
            }
            a[(k, U - 1)] = qk[(U - 1, U - 1)];
        }
        a[(4, 5)] = 1.0;
        let scale =
            UVec::from_column_slice(&[sc[0], sc[1], sc[2], sc[3], a_scale, a_scale / h, 1.0]);
        let integrands: [UMat; INTEGRALS] = std::array::from_fn(|i| q[4 + i]);
        let (e, weights) = weights(&a, &integrands, h, &scale);
        let part = {
            let d = UMat::from_diagonal(&scale);
            let d_inv = UMat::from_diagonal(&scale.map(|s| 1.0 / s));
            d * (d_inv * a * d * (h / PARTS as f64)).exp() * d_inv
        };
        let (guards, used) = guard_rows(model, mode, &a, h)?;
        let next_guards = guards * e;
        let mut power = part;
        let inner = std::array::from_fn(|_| {
            let g = guards * power;
            power *= part;
            g
        });
        let step_columns = std::array::from_fn(|j| {
            std::array::from_fn(|i| {
                if i < 4 {
                    e[(i, j)]
                } else {
                    next_guards[(i - 4, j)]
                }
            })
        });
        Some(Self {
            step_columns,
            used,
            inner,
            guards,
            weights,
        })
    }
}

/// True when a mode of `model` can be linear: its free flight is (see the module docs). A
/// model without one (Shockley diodes, a nonlinear suspension) goes to Dormand-Prince
/// throughout.
pub(crate) fn has_linear_modes<E: Excitation>(model: &Interfaced<E>) -> bool {
    let free = IfMode {
        contact: Mode::Free,
        bridge: Bridge::Off,
        heading: crate::physics::interface::Heading::Up,
    };
    is_linear(model, free)
}

/// True when `mode` is linear (see the module docs).
fn is_linear<E: Excitation>(model: &Interfaced<E>, mode: IfMode) -> bool {
    let c = &model.circuit;
    let bridge = !c.bridge_between_extrema() || matches!(c.diode, DiodeLaw::PiecewiseLinear { .. });
    let contact = match mode.contact {
        Mode::Free => true,
        Mode::Contact(side) | Mode::Clipped(side) => matches!(
            model.h.stop(side),
            Some(StopModel::Compliant {
                law: ContactLaw::Linear(_),
                damping: ContactDamping::Viscous(_),
                ..
            })
        ),
        Mode::Stuck(_) => false,
    };
    bridge && contact && !model.h.spring.nonlinear
}

/// The guards of `mode` as rows on `u` (see [`LinearMode`]) and how many there are, or `None`
/// when one is not affine.
fn guard_rows<E: Excitation>(
    model: &Interfaced<E>,
    mode: IfMode,
    a: &UMat,
    h: f64,
) -> Option<(SMatrix<f64, GUARD_ROWS, U>, usize)> {
    let c = &model.circuit;
    let sc = model.scales();
    type Guard<'a> = Box<dyn Fn(&State) -> f64 + 'a>;
    let mut list: Vec<Guard> = Vec::new();
    for i in 0..2 {
        list.push(Box::new(move |y: &State| {
            model.h.guard_values(mode.contact, 0.0, y)[i]
        }));
    }
    if mode.bridge == Bridge::Off && c.has_conduction_events() {
        // |drive| - (Vs + 2 V_F), scaled as the circuit's guard: one affine piece per sign.
        for s in [1.0, -1.0] {
            list.push(Box::new(move |y: &State| {
                (s * c.drive_voltage(y) - y[3] - c.path_drop()) / sc[3]
            }));
        }
    } else {
        list.push(Box::new(move |y: &State| model.circuit_guards(mode, y)[0]));
    }
    list.push(Box::new(move |y: &State| model.circuit_guards(mode, y)[1]));
    // Probed about the state where the fit of the dynamics was (a contact's point is inside
    // the stop); affine guards do not care where.
    let mut base = State::zeros();
    if let Mode::Contact(side) | Mode::Clipped(side) = mode.contact {
        base[0] = side.sign() * (model.h.gap(side) + sc[0]);
        base[1] = side.sign() * sc[1];
    }
    let mut rows = SMatrix::<f64, GUARD_ROWS, U>::zeros();
    let mut used = 0;
    for g in &list {
        let g0 = g(&base);
        if g0 == f64::NEG_INFINITY {
            continue;
        }
        let mut n = State::zeros();
        for j in 0..4 {
            let mut p = base;
            p[j] += 0.25 * sc[j];
            let mut m = base;
            m[j] -= 0.25 * sc[j];
            n[j] = (g(&p) - g(&m)) / (0.5 * sc[j]);
        }
        let offset = g0 - n.dot(&base);
        let norm = n.component_mul(&sc).norm();
        let probe = base + State::new(0.1 * sc[0], -0.2 * sc[1], 0.15 * sc[2], 0.05 * sc[3]);
        if !(norm > 0.0 && (g(&probe) - n.dot(&probe) - offset).abs() <= 1e-9 * norm) {
            return None;
        }
        if used == MAX_GUARDS {
            return None;
        }
        let value = UVec::from_column_slice(&[n[0], n[1], n[2], n[3], 0.0, 0.0, offset]) / norm;
        let rate = a.transpose() * value * h;
        rows.set_row(2 * used, &value.transpose());
        rows.set_row(2 * used + 1, &rate.transpose());
        used += 1;
    }
    for j in used..MAX_GUARDS {
        rows[(2 * j, U - 1)] = -1.0;
    }
    Some((rows, used))
}

/// The homogeneous quadratic forms on `u` (its `a'` unused) of each output of `f`, a
/// quadratic function of `(y, a)`, by polarisation about `base` with steps `eps`, and whether
/// each is affine (its quadratic part within rounding of zero); `None` when the fit misses `f`
/// at another point by more than rounding.
fn fit_quadratic<F: Fn(&SVector<f64, 5>) -> SVector<f64, OUTPUTS>>(
    f: F,
    base: &SVector<f64, 5>,
    eps: &SVector<f64, 5>,
) -> Option<([UMat; OUTPUTS], [bool; OUTPUTS])> {
    let at = |d: &[f64; 5]| f(&(base + SVector::<f64, 5>::from_fn(|i, _| d[i] * eps[i])));
    let unit = |i: usize, s: f64| {
        let mut d = [0.0; 5];
        d[i] = s;
        d
    };
    let f0 = at(&[0.0; 5]);
    let plus: [_; 5] = std::array::from_fn(|i| at(&unit(i, 1.0)));
    let minus: [_; 5] = std::array::from_fn(|i| at(&unit(i, -1.0)));
    let beta: [_; 5] = std::array::from_fn(|i| (plus[i] - minus[i]) / 2.0);
    let diag: [_; 5] = std::array::from_fn(|i| (plus[i] + minus[i]) / 2.0 - f0);
    // In the scaled offsets d (z = base + eps d): f = f0 + beta . d + d^T H d, written on
    // (d, 1) as a symmetric 6 x 6 form for each output, then mapped to (z, 1) and onto u.
    let mut h = vec![SMatrix::<f64, 6, 6>::zeros(); OUTPUTS];
    for (k, hk) in h.iter_mut().enumerate() {
        hk[(5, 5)] = f0[k];
        for i in 0..5 {
            hk[(i, i)] = diag[i][k];
            hk[(i, 5)] = beta[i][k] / 2.0;
            hk[(5, i)] = beta[i][k] / 2.0;
        }
    }
    for i in 0..5 {
        for j in i + 1..5 {
            let mut d = [0.0; 5];
            d[i] = 1.0;
            d[j] = 1.0;
            let fij = at(&d);
            for (k, hk) in h.iter_mut().enumerate() {
                let cross = fij[k] - f0[k] - beta[i][k] - beta[j][k] - diag[i][k] - diag[j][k];
                hk[(i, j)] = cross / 2.0;
                hk[(j, i)] = cross / 2.0;
            }
        }
    }
    // d = T (z, 1).
    let mut t = SMatrix::<f64, 6, 6>::zeros();
    for i in 0..5 {
        t[(i, i)] = 1.0 / eps[i];
        t[(i, 5)] = -base[i] / eps[i];
    }
    t[(5, 5)] = 1.0;
    let check = [0.3, -0.7, 0.45, 0.2, -0.55];
    let fc = at(&check);
    let dc = SVector::<f64, 6>::from_fn(|i, _| if i < 5 { check[i] } else { 1.0 });
    let mut out = [UMat::zeros(); OUTPUTS];
    let mut affine = [false; OUTPUTS];
    for (k, (hk, qk)) in h.iter().zip(out.iter_mut()).enumerate() {
        let size = hk.iter().map(|v| v.abs()).sum::<f64>();
        if (dc.dot(&(hk * dc)) - fc[k]).abs() > 1e-9 * size {
            return None;
        }
        let quadratic = hk
            .fixed_view::<5, 5>(0, 0)
            .iter()
            .map(|v| v.abs())
            .sum::<f64>();
        affine[k] = quadratic <= 1e-9 * size;
        let qz = t.transpose() * hk * t;
        // (z, 1) to u = (y, a, a', 1).
        let map = |i: usize| if i < 5 { i } else { U - 1 };
        for i in 0..6 {
            for j in 0..6 {
                qk[(map(i), map(j))] = qz[(i, j)];
            }
        }
    }
    Some((out, affine))
}

/// `e^{hA}` and `W_i = ∫_0^h e^{sA^T} Q_i e^{sA} ds` for each integrand `Q_i`, computed on the
/// scaled `D^-1 A D` (`D` the diagonal of `scale`) by doubling from a span `τ` with
/// `|τ D^-1 A D| <= 1/64`, where 3-point Gauss-Legendre is exact to rounding (see the module
/// docs).
fn weights(a: &UMat, q: &[UMat; INTEGRALS], h: f64, scale: &UVec) -> (UMat, [UMat; INTEGRALS]) {
    let d = UMat::from_diagonal(scale);
    let d_inv = UMat::from_diagonal(&scale.map(|s| 1.0 / s));
    let a_s = d_inv * a * d;
    let norm = (a_s * h).norm();
    let doublings = if norm > 1.0 / 64.0 {
        (norm * 64.0).log2().ceil() as i32
    } else {
        0
    };
    let tau = h / 2f64.powi(doublings);
    let nodes = GAUSS_LEGENDRE_3.map(|(x, w)| ((a_s * (x * tau)).exp(), w * tau));
    let mut w: [UMat; INTEGRALS] = std::array::from_fn(|i| {
        let qs = d * q[i] * d;
        nodes
            .iter()
            .map(|(e, wt)| e.transpose() * qs * e * *wt)
            .sum()
    });
    let mut e = (a_s * tau).exp();
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
    (e, w.map(|wi| d_inv * wi * d_inv))
}

/// A Gram sum `Σ u_k u_k^T`, by columns.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Gram([[f64; U]; U]);

impl Gram {
    /// Adds `u u^T`.
    #[inline(always)]
    pub(crate) fn add(&mut self, u: &[f64; U]) {
        for (col, &uj) in self.0.iter_mut().zip(u) {
            for (c, ui) in col.iter_mut().zip(u) {
                *c += ui * uj;
            }
        }
    }
}

/// The linear modes of a record met so far, each computed when first met, with each mode's
/// Gram sum `Σ u_k u_k^T` over the analysed intervals it advanced.
#[derive(Debug)]
pub(crate) struct LinearModes<'a, E: Excitation> {
    audit: &'a InterfaceAudit<E>,
    h: f64,
    /// Each mode met, its linear form if it has one, and its Gram sum.
    entries: Vec<(IfMode, Option<LinearMode>, Gram)>,
}

impl<'a, E: Excitation> LinearModes<'a, E> {
    /// No mode yet, for `audit` on intervals of `h`.
    pub(crate) fn new(audit: &'a InterfaceAudit<E>, h: f64) -> Self {
        Self {
            audit,
            h,
            entries: Vec::new(),
        }
    }

    /// The index of `mode`, computing its linear form when it is new.
    pub(crate) fn index(&mut self, mode: IfMode) -> usize {
        if let Some(i) = self.entries.iter().position(|(m, _, _)| *m == mode) {
            return i;
        }
        let linear = LinearMode::of(self.audit, mode, self.h);
        self.entries.push((mode, linear, Gram::default()));
        self.entries.len() - 1
    }

    /// The linear form of the mode at `index` and its Gram sum.
    #[inline(always)]
    pub(crate) fn get(&mut self, index: usize) -> (Option<&LinearMode>, &mut Gram) {
        let (_, l, g) = &mut self.entries[index];
        (l.as_ref(), g)
    }

    /// Each integral ([`INTEGRALS`]) over the analysed intervals the linear modes advanced:
    /// `Σ_modes Σ_ij W_ij G_ij`.
    pub(crate) fn integrals(&self) -> [f64; INTEGRALS] {
        let mut out = [0.0; INTEGRALS];
        for (_, l, g) in &self.entries {
            if let Some(l) = l {
                let g = UMat::from_fn(|i, j| g.0[j][i]);
                for (o, w) in out.iter_mut().zip(&l.weights) {
                    *o += w.component_mul(&g).sum();
                }
            }
        }
        out
    }
}
