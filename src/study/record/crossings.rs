//! Guard crossings inside a sample interval of an affine mode, located on its exact solution,
//! so that an interval in which a mass strikes a rigid stop (of the frame or of another mass),
//! comes to rest on it or leaves it costs a few polynomial evaluations instead of a
//! Dormand-Prince integration.
//!
//! Over a sample interval an affine mode with the linearly interpolated drive is the
//! time-invariant `u' = A u` on the augmented state `u = (y, a, a', 1)` (`affine.rs`), whose
//! Taylor series `u(t) = Σ A^k u0 t^k / k!` converges like `‖t A‖^k / k!`. Where the interval
//! resolves the mode (the scaled `‖h A‖` at most
//! [`RESOLVED_NORM`](crate::ode::exponential::RESOLVED_NORM)) the series summed until its terms
//! fall below rounding ([`TAYLOR_TOL`], at most [`MAX_TERMS`] terms) is the exact propagator to
//! rounding, as for the one mass's free flight (`impacts.rs`). Every guard of the mode is
//! affine in the state and the drive, a row `g` on `u` (a resting contact's holding force
//! takes the drive's inertial force), so along the interval it is the polynomial
//! `Σ (g · A^k u0 / k!) t^k`: one dot product per term and guard.
//!
//! **Switches across modes.** An interval is walked from switch to switch ([`walk`]): a
//! rigid stop's penetration while apart is an impact, which the model's switch turns into a
//! rebound (the same mode) or a rest (the resting mode, when the relative speed is below the
//! model's stick criterion); a resting contact's holding force turning negative is its
//! release (the mode apart). Each switch is applied by the model's own
//! [`Model::switch`], and the walk goes on in the mode it leads to, on that mode's exact
//! solution, to the interval's end. While a contact rests the record holds it on its surface
//! ([`Rebounding::hold`]): the propagator keeps the constraint only to rounding, and the
//! released pair must leave the surface with zero relative speed, which the start check of a
//! stretch reads as leaving by the first derivative that is not zero.
//!
//! The first crossing is found as the one mass's rebounds are found in pieces: the interval is
//! cut into [`PIECES`] pieces, a piece on which a guard's rate changes sign is split at the
//! guard's extremum (safeguarded Newton on the rate's polynomial), and the first monotone
//! stretch whose guard goes from negative to non-negative holds the crossing, located by
//! safeguarded Newton on the guard's polynomial ([`impacts::newton`], never early by more than
//! a few ulps). The resolved interval makes each piece a small fraction of the mode's fastest
//! oscillation, so a guard has at most one extremum on a piece.
//!
//! The caller (`affine.rs`) reaches this search only for the intervals the Hermite bound of
//! [`super::affine`] does not clear, so most intervals cost nothing here.

use nalgebra::{SMatrix, SVector};

use crate::model::{AffineGuard, Contact, Mode, Model, SwitchKind};
use crate::ode::exponential::RESOLVED_NORM;
use crate::ode::phi::scaled;

use super::impacts::{self, Rebounds, MAX_REBOUNDS, MAX_TERMS, TAYLOR_TOL};
use super::stepping::POSITION;

/// Most guard pieces of a mode: two stops' (or a contact's boundary and bracket), the
/// conduction's two pieces while a bridge is off, and a switch's extremum.
pub(super) const MAX_GUARDS: usize = 5;
/// Pieces each interval is cut into for the search.
const PIECES: usize = 4;

/// Largest value (in units of the guard's scale) a guard may have at the start of a stretch
/// while it leaves zero ([`leaving`]): a state projected onto the guard's surface by a switch,
/// which lies on it only to rounding and leaves it.
const START_SLACK: f64 = 1e-9;

/// What a guard crossing inside an interval does on the exact path.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Handled {
    /// A rigid stop's penetration while apart: a rebound, or the contact comes to rest (a
    /// stick), both impacts.
    Impact,
    /// A resting contact's holding force changes sign: the contact opens.
    Release,
    /// Another switch (a circuit acts, a compliant contact): the interval goes to
    /// Dormand-Prince.
    Other,
}

/// A resting contact held on its surface by the record: the struck mass's (or the frame's)
/// position and velocity indices, the mover's, the side and the gap (see
/// [`Rebounding::hold`]).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Held {
    struck: Option<(usize, usize)>,
    mover: (usize, usize),
    side: f64,
    gap: f64,
}

/// What an affine mode needs to carry its intervals across its switches on the exact
/// solution: its augmented matrix, the augmented state's inverse scales, its guards as rows on
/// the augmented state with the model's guard index of each and what its crossing does, and
/// the resting contact it holds, if any.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Rebounding<const U: usize> {
    a: SMatrix<f64, U, U>,
    inv_scale: SVector<f64, U>,
    rows: Vec<SVector<f64, U>>,
    indices: Vec<usize>,
    handled: Vec<Handled>,
    held: Option<Held>,
}

impl<const U: usize> Rebounding<U> {
    /// The crossings of `mode` of `model` with the augmented matrix `a` (on the scales
    /// `scale`) and its guards `list` (as rows `rows`, value and rate of each in turn) on
    /// intervals of `h`; `None` where the mode has no rigid stop to meet or resting contact to
    /// release, or `h` does not resolve it.
    pub(super) fn of<M: Model<N>, const N: usize, const R: usize>(
        model: &M,
        mode: Mode,
        list: &[AffineGuard<N>],
        rows: &SMatrix<f64, R, U>,
        a: &SMatrix<f64, U, U>,
        scale: &SVector<f64, U>,
        h: f64,
    ) -> Option<Self> {
        let contacts = model.contacts();
        let handled: Vec<Handled> = list
            .iter()
            .map(|g| {
                let k = g.index / 2;
                let rigid = contacts
                    .get(k)
                    .is_some_and(|c| c.rigid() && c.gap.is_finite());
                match (rigid, g.index % 2, mode.contact(k)) {
                    (true, 0, Contact::Apart) => Handled::Impact,
                    (true, 1, Contact::Resting) => Handled::Release,
                    _ => Handled::Other,
                }
            })
            .collect();
        let held = (0..contacts.len())
            .find(|&k| mode.contact(k) == Contact::Resting)
            .and_then(|k| {
                let c = &contacts[k];
                let masses = &model.layout().masses;
                let mover = *masses.get(c.other.unwrap_or(c.mass))?;
                let struck = match c.other {
                    Some(_) => Some(*masses.get(c.mass)?),
                    None => None,
                };
                Some(Held {
                    struck,
                    mover,
                    side: c.side,
                    gap: c.gap,
                })
            });
        let any = handled.iter().any(|k| *k != Handled::Other);
        if U != N + 3 || !any || scaled(&(a * h), scale).norm() > RESOLVED_NORM {
            return None;
        }
        Some(Self {
            a: *a,
            inv_scale: scale.map(|s| 1.0 / s),
            rows: (0..list.len())
                .map(|j| rows.row(2 * j).transpose())
                .collect(),
            indices: list.iter().map(|g| g.index).collect(),
            handled,
            held,
        })
    }

    /// Puts a resting contact's mover back on the contact's surface with the struck mass's
    /// velocity (at rest on a frame stop): the exact propagator keeps the constraint only to
    /// rounding, and a pair that drifts apart by a rounding would read as leaving or meeting
    /// the stop again. The mover steps inside by ulps where the sum lands past the surface,
    /// as the model's own projection does.
    pub(super) fn hold<const N: usize>(&self, y: &mut SVector<f64, N>) {
        let Some(h) = self.held else {
            return;
        };
        let (ix, iv) = h.mover;
        let (xs, vs) = h.struck.map_or((0.0, 0.0), |(jx, jv)| (y[jx], y[jv]));
        y[iv] = vs;
        y[ix] = xs + h.side * h.gap;
        while h.side * (y[ix] - xs) - h.gap > 0.0 {
            y[ix] = if h.side > 0.0 {
                y[ix].next_down()
            } else {
                y[ix].next_up()
            };
        }
    }

    /// The first switch within `len` of the augmented state `u` on the exact solution:
    /// where the search ends, with the model's guard index of a crossing and what it does;
    /// `None` hands the interval to Dormand-Prince (see [`first_crossing`]).
    pub(super) fn search(&self, u: &SVector<f64, U>, len: f64) -> Option<Found<U>> {
        Some(
            match first_crossing(&self.a, &self.inv_scale, &self.rows, u, len)? {
                Search::Clear(end) => Found::Clear(end),
                Search::Crossing(tau, j, at) => {
                    Found::Switch(tau, self.indices[j], self.handled[j], at)
                }
            },
        )
    }
}

/// Where the search of an interval's stretch in one mode ends ([`Rebounding::search`]).
pub(super) enum Found<const U: usize> {
    /// A switch: the time into the stretch (s), the model's guard, what it does, and the
    /// augmented state there.
    Switch(f64, usize, Handled, SVector<f64, U>),
    /// No switch: the augmented state at the stretch's end.
    Clear(SVector<f64, U>),
}

/// What a walk across an interval's switches found: the state at its end, the mode there, the
/// time it spent in contact (s), and the impacts inside it (time into the interval, |x| of the
/// first mass there), the states at them before each reset in `states`.
pub(super) struct Walked<const N: usize> {
    pub(super) y: SVector<f64, N>,
    pub(super) mode: Mode,
    pub(super) contact_s: f64,
    pub(super) impacts: Rebounds,
}

/// The affine modes' data a walk reads: each mode's crossings, prepared when first met.
pub(super) trait ModeTable<const N: usize, const U: usize> {
    /// The crossings of `mode` of `model`, or `None` where it has none on the exact path.
    fn crossings_of<M: Model<N>>(&mut self, model: &M, mode: Mode) -> Option<&Rebounding<U>>;
}

/// The state one interval `h` after `y` in `mode` (the drive `a0` at its start and its slope
/// `slope`), each switch of the modes' [`Handled`] kinds located on the exact solution of
/// the mode it happens in and applied by the model's own switch ([`Model::switch`]): rebounds
/// off rigid stops, a contact that comes to rest, a resting contact's release; `None` to hand
/// the interval to Dormand-Prince: another guard fires, a mode without exact crossings is
/// entered, more than [`MAX_REBOUNDS`] impacts (chatter), or a series that does not converge.
#[allow(clippy::too_many_arguments)]
pub(super) fn walk<M: Model<N>, T: ModeTable<N, U>, const N: usize, const U: usize>(
    model: &M,
    table: &mut T,
    mode: Mode,
    y: &SVector<f64, N>,
    a0: f64,
    slope: f64,
    h: f64,
    states: &mut Vec<SVector<f64, N>>,
) -> Option<Walked<N>> {
    let augment = |y: &SVector<f64, N>, a: f64| {
        let mut u = SVector::<f64, U>::zeros();
        u.fixed_rows_mut::<N>(0).copy_from(y);
        u[N] = a;
        u[N + 1] = slope;
        u[U - 1] = 1.0;
        u
    };
    let head = |u: &SVector<f64, U>| u.fixed_rows::<N>(0).into_owned();
    let mut walked = Walked {
        y: *y,
        mode,
        contact_s: 0.0,
        impacts: Rebounds::default(),
    };
    let (mut u, mut t) = (augment(y, a0), 0.0);
    loop {
        let left = h - t;
        let here = table.crossings_of(model, walked.mode)?;
        let found = if left > 0.0 {
            here.search(&u, left)?
        } else {
            Found::Clear(u)
        };
        let (tau, index, handled, at) = match found {
            Found::Clear(end) => {
                walked.y = head(&end);
                here.hold(&mut walked.y);
                if walked.mode.in_contact() {
                    walked.contact_s += left.max(0.0);
                }
                return Some(walked);
            }
            Found::Switch(tau, index, handled, at) => (tau, index, handled, at),
        };
        if handled == Handled::Other {
            return None;
        }
        let mut ys = head(&at);
        here.hold(&mut ys);
        if walked.mode.in_contact() {
            walked.contact_s += tau;
        }
        t += tau;
        let a = a0 + slope * t;
        if handled == Handled::Impact {
            if walked.impacts.len == MAX_REBOUNDS {
                return None;
            }
            states.push(ys);
        }
        let next = model.switch(walked.mode, index, &mut ys, a);
        let kind = model.switch_kind(walked.mode, index, next);
        let expected = match handled {
            Handled::Impact => matches!(kind, SwitchKind::Rebound | SwitchKind::Stick),
            _ => kind == SwitchKind::Release,
        };
        if !expected {
            return None;
        }
        if handled == Handled::Impact {
            let w = &mut walked.impacts;
            w.at[w.len] = (t, ys[POSITION].abs());
            w.len += 1;
        }
        walked.mode = next;
        u = augment(&ys, a);
    }
}

/// Where the search of a stretch ends.
pub(super) enum Search<const U: usize> {
    /// The first crossing: the time into the stretch (s), the guard's position in the list
    /// and the augmented state there.
    Crossing(f64, usize, SVector<f64, U>),
    /// No crossing: the augmented state at the stretch's end.
    Clear(SVector<f64, U>),
}

/// A guard along the stretch: `Σ coef[k] t^k`.
#[derive(Clone, Copy)]
struct Poly {
    coef: [f64; MAX_TERMS],
    len: usize,
}

impl Poly {
    /// The value and first derivative at `t`.
    fn at(&self, t: f64) -> (f64, f64) {
        let (mut p, mut dp) = (self.coef[self.len - 1], 0.0);
        for k in (0..self.len - 1).rev() {
            dp = dp * t + p;
            p = p * t + self.coef[k];
        }
        (p, dp)
    }

    /// The first and second derivatives at `t`.
    fn rate_at(&self, t: f64) -> (f64, f64) {
        let (mut d1, mut d2) = (0.0, 0.0);
        for k in (1..self.len).rev() {
            let c = k as f64 * self.coef[k];
            d2 = d2 * t + d1;
            d1 = d1 * t + c;
        }
        (d1, d2)
    }
}

/// The first crossing in `(0, len]` of any guard of `rows` (each a row on the augmented state)
/// along `u' = a u` from `u0`, or the state at `len` (see the module docs); `inv_scale` holds
/// the inverse characteristic scales of the augmented state. `None` hands the stretch to
/// Dormand-Prince: a series that does not fall below rounding within [`MAX_TERMS`] terms, or a
/// guard that is non-negative at the start and not leaving (an event due now).
pub(super) fn first_crossing<const U: usize>(
    a: &SMatrix<f64, U, U>,
    inv_scale: &SVector<f64, U>,
    rows: &[SVector<f64, U>],
    u0: &SVector<f64, U>,
    len: f64,
) -> Option<Search<U>> {
    let (all, n) = series(a, inv_scale, u0, len)?;
    let terms = &all[..n];
    let mut polys = [Poly {
        coef: [0.0; MAX_TERMS],
        len: terms.len(),
    }; MAX_GUARDS];
    for (p, row) in polys.iter_mut().zip(rows) {
        for (c, w) in p.coef.iter_mut().zip(terms) {
            *c = row.dot(w);
        }
        let g0 = p.coef[0];
        if g0 >= 0.0 && !(g0 <= START_SLACK && leaving(&p.coef[1..p.len])) {
            return None;
        }
    }
    let polys = &polys[..rows.len().min(MAX_GUARDS)];
    let state = |t: f64| {
        let mut u = terms[terms.len() - 1];
        for w in terms[..terms.len() - 1].iter().rev() {
            u = u * t + w;
        }
        u
    };
    let mut ta = 0.0;
    for p in 1..=PIECES {
        let tb = len * p as f64 / PIECES as f64;
        let first = polys
            .iter()
            .enumerate()
            .filter_map(|(j, poly)| crossing_on(poly, ta, tb).map(|t| (t, j)))
            .min_by(|x, y| x.0.total_cmp(&y.0));
        if let Some((t, j)) = first {
            return Some(Search::Crossing(t, j, state(t)));
        }
        ta = tb;
    }
    Some(Search::Clear(state(len)))
}

/// True when a guard at zero leaves it: its first derivative at the start that is not zero
/// (of the Taylor coefficients `rates`) is negative. A pair released from rest together
/// leaves its stop with zero relative speed, and the relative acceleration that the release's
/// holding force turns negative.
fn leaving(rates: &[f64]) -> bool {
    rates.iter().find(|c| **c != 0.0).is_some_and(|c| *c < 0.0)
}

/// The terms `A^k u0 / k!` of the series over `len`, until a term spanned over `len` falls
/// below [`TAYLOR_TOL`] of the state's scaled size (past the quadratic term); `None` where
/// that takes more than [`MAX_TERMS`] terms. The terms are held on the stack (with how many
/// there are): the search runs inside the record's stepping loop, which allocates nothing.
fn series<const U: usize>(
    a: &SMatrix<f64, U, U>,
    inv_scale: &SVector<f64, U>,
    u0: &SVector<f64, U>,
    len: f64,
) -> Option<([SVector<f64, U>; MAX_TERMS], usize)> {
    let size = u0.component_mul(inv_scale).amax().max(1.0);
    let mut terms = [SVector::<f64, U>::zeros(); MAX_TERMS];
    terms[0] = *u0;
    let mut spanned_factor = 1.0;
    for k in 1..MAX_TERMS {
        let next = a * terms[k - 1] / k as f64;
        spanned_factor *= len;
        let scaled = next.component_mul(inv_scale).amax() * spanned_factor;
        terms[k] = next;
        if k > 2 && scaled <= TAYLOR_TOL * size {
            return Some((terms, k + 1));
        }
    }
    None
}

/// The first time in `(ta, tb]` at which `poly` goes from negative to non-negative, splitting
/// the piece at the extremum where its rate changes sign.
fn crossing_on(poly: &Poly, ta: f64, tb: f64) -> Option<f64> {
    let (ga, da) = poly.at(ta);
    let (gb, db) = poly.at(tb);
    let mut nodes = [(ta, ga), (tb, gb), (tb, gb)];
    if da * db < 0.0 {
        let te = impacts::newton(ta, tb, da, 0.5 * (ta + tb), |t| poly.rate_at(t));
        nodes[1] = (te, poly.at(te).0);
    }
    nodes.windows(2).find_map(|w| {
        let ((t0, g0), (t1, g1)) = (w[0], w[1]);
        (t1 > t0 && g0 < 0.0 && g1 >= 0.0).then(|| {
            let start = t0 + (t1 - t0) * g0 / (g0 - g1);
            impacts::newton(t0, t1, g0, start, |t| poly.at(t))
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `x'' = -w^2 x` with `u = (x, v, 1)` and the guard `x - gap`: an oscillation of
    /// amplitude `x0` (released from rest at `x0`, heading down) crosses `-gap` at
    /// `acos(-gap / x0) / w`; the search finds that time to a few ulps of the interval and
    /// the state there, and finds no crossing over an interval that ends before it.
    #[test]
    fn a_released_oscillator_crosses_where_the_cosine_says() {
        let w = 2.0 * std::f64::consts::PI * 1000.0;
        let a = SMatrix::<f64, 3, 3>::new(0.0, 1.0, 0.0, -w * w, 0.0, 0.0, 0.0, 0.0, 0.0);
        let inv_scale = SVector::<f64, 3>::new(1e5, 1e5 / w, 1.0);
        let (x0, gap) = (1e-5, 0.9e-5);
        // The guard `-x - gap` on (x, v, 1), divided by its scale 1e-5.
        let row = SVector::<f64, 3>::new(-1e5, 0.0, -gap * 1e5);
        let u0 = SVector::<f64, 3>::new(x0, 0.0, 1.0);
        let t_cross = (-gap / x0).acos() / w;
        let len = 1.1 * t_cross;
        // A resolved stretch: the search is meant for sample intervals, so check it on one
        // that ends just past the crossing, from a state just before it.
        let before = 0.95 * t_cross;
        let (c, s) = ((w * before).cos(), (w * before).sin());
        let u = SVector::<f64, 3>::new(x0 * c, -x0 * w * s, 1.0);
        let Some(Search::Crossing(t, j, at)) =
            first_crossing(&a, &inv_scale, &[row], &u, len - before)
        else {
            panic!("a crossing");
        };
        assert_eq!(j, 0);
        // Newton ends within 4 ulps of the root; the root's own rounding is that of the
        // guard's value divided by its rate.
        let tol = 16.0 * f64::EPSILON * len;
        assert!((before + t - t_cross).abs() <= tol, "{t:e}");
        assert!((at[0] + gap).abs() <= 1e-12 * x0, "{:e}", at[0]);
        match first_crossing(&a, &inv_scale, &[row], &u0, 0.5 * t_cross) {
            Some(Search::Clear(end)) => {
                let x = x0 * (0.5 * w * t_cross).cos();
                assert!((end[0] - x).abs() <= 1e-12 * x0);
            }
            _ => panic!("no crossing over the first half"),
        }
    }
}
