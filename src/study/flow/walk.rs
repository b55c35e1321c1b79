//! The engine of [`super::SineFlow`]: exact steps on a grid of the drive period in the affine
//! modes, the events located on the exact solution, and Dormand-Prince in every other mode.
//! It carries either the state alone or the state with its variational equations
//! ([`Carrier`]).

use std::sync::Arc;

use nalgebra::{SMatrix, SVector};

use crate::drive::Sine;
use crate::model::{Driven, Mode, Model};
use crate::ode::phi::expm_n;
use crate::ode::MAX_SWITCHES_AT_ONE_TIME;
use crate::ode::{Dopri5, HybridSystem, Observer, Options, SolverError, Stats, Step, Vector};

use super::affine::AffineMode;
use super::grid::{grid_step, Propagators};
use super::phase::{turned, PhaseGrid};

/// A guard whose cubic estimate over a step peaks within this fraction of its scale below zero
/// is maximised on the exact solution (see the module docs of [`super`]).
pub const GRAZE_MARGIN: f64 = 1e-3;

/// What the engine integrates: a model's state under a sine, or the state with its variational
/// equations. The state is the head of the vector.
pub(crate) trait Carrier<const N: usize>: HybridSystem<Mode = Mode> {
    /// The model.
    type M: Model<N>;

    /// The model.
    fn model(&self) -> &Self::M;

    /// The drive.
    fn sine(&self) -> &Sine;

    /// True when the observers are shown every step with its dense output.
    const DENSE: bool;

    /// The vector over `[t, t + s]` in the affine mode `am`, given its value `z` at `t` and
    /// the state `y1` at `t + s`; `e` gives `e^{s L}`, called only by a carrier that needs it
    /// (the state alone does not, and the step to an event then skips its exponential).
    fn carry(
        &self,
        am: &AffineMode<N>,
        e: impl FnOnce() -> SMatrix<f64, N, N>,
        t: f64,
        s: f64,
        z: &Self::State,
        y1: &SVector<f64, N>,
    ) -> Self::State;
}

/// The state at the head of a carried vector.
#[inline(always)]
pub(crate) fn head<V: Vector, const N: usize>(z: &V) -> SVector<f64, N> {
    SVector::<f64, N>::from_column_slice(&z.components()[..N])
}

impl<M: Model<N>, const N: usize> Carrier<N> for Driven<'_, M, Sine, N> {
    type M = M;

    fn model(&self) -> &M {
        self.model
    }

    fn sine(&self) -> &Sine {
        &self.drive
    }

    const DENSE: bool = true;

    #[inline(always)]
    fn carry(
        &self,
        _: &AffineMode<N>,
        _: impl FnOnce() -> SMatrix<f64, N, N>,
        _: f64,
        _: f64,
        _: &SVector<f64, N>,
        y1: &SVector<f64, N>,
    ) -> SVector<f64, N> {
        *y1
    }
}

/// A located event: where in the step (s from its start), which guard, and the state there.
struct Located<const N: usize> {
    s: f64,
    index: usize,
    y: SVector<f64, N>,
}

/// The exact-and-Dormand-Prince integration of a [`Carrier`] (see [`super`]).
pub(crate) struct Engine<S: Carrier<N>, const N: usize> {
    sys: S,
    /// The affine modes (none when the free flight is not affine: then everything goes to
    /// Dormand-Prince).
    /// Shared, so that a step holds its mode while it changes the engine.
    modes: Option<Arc<[AffineMode<N>]>>,
    props: Vec<Propagators<N>>,
    h: f64,
    t: f64,
    z: S::State,
    mode: Mode,
    ode: Dopri5<S>,
    /// True when `ode` holds the current point.
    ode_current: bool,
    /// Counters of the exact steps and their events.
    stats: Stats,
    time_tol: f64,
    /// Switches made at the current time by the exact path.
    switches_here: u32,
    /// The model's state scales (for the guards' scales).
    scales: SVector<f64, N>,
    /// The drive's phase on the half-grid (see [`Engine::forced`]); none off the exact path.
    phases: Option<PhaseGrid>,
    /// True when a partial step shown to an observer takes `e^{sL}` as the square of its
    /// half-step's exponential (several masses; see [`Engine::exact`]).
    square_half: bool,
}

/// The affine modes of a model under a sine: every mode the model can be in whose affine
/// form it gives, or none when its free flight is not affine.
fn affine_modes<M: Model<N>, const N: usize>(model: &M, sine: &Sine) -> Option<Vec<AffineMode<N>>> {
    let unused = model.unused();
    let free = model.affine(Mode::FREE)?;
    let first = AffineMode::of(Mode::FREE, free, sine, unused)?;
    let mut modes = vec![first];
    for m in model.modes() {
        if m == Mode::FREE {
            continue;
        }
        if let Some(a) = model.affine(m) {
            if let Some(am) = AffineMode::of(m, a, sine, unused) {
                modes.push(am);
            }
        }
    }
    Some(modes)
}

impl<S: Carrier<N>, const N: usize> Engine<S, N> {
    /// An engine at `(t0, z0)` in `mode`; `exact` false sends everything to Dormand-Prince.
    pub(crate) fn new(
        sys: S,
        t0: f64,
        z0: S::State,
        mode: Mode,
        opts: Options<S::State>,
        exact: bool,
    ) -> Self {
        let time_tol = opts.event_time_tol;
        let model = sys.model();
        let modes = if exact {
            affine_modes(model, sys.sine()).map(Arc::from)
        } else {
            None
        };
        let exact_path = modes.is_some();
        let several_masses = model.layout().masses.len() > 1;
        let (h, props, phases) = match &modes {
            Some(m) => {
                let (h, steps) = grid_step(sys.sine().period_s(), m, model.unused());
                let props = m.iter().map(|a| Propagators::new(&a.l, h)).collect();
                let phases = Some(PhaseGrid::new(sys.sine(), steps, h));
                (h, props, phases)
            }
            None => (0.0, Vec::new(), None),
        };
        let scales = model.scales();
        Self {
            sys,
            modes,
            props,
            h,
            t: t0,
            z: z0,
            mode,
            ode_current: !exact_path,
            ode: Dopri5::new(t0, z0, mode, opts),
            stats: Stats::default(),
            time_tol,
            switches_here: 0,
            scales,
            phases,
            square_half: several_masses,
        }
    }

    /// The particular solution of `am` and the drive at time `t`: on the exact path the
    /// drive's phase on the half-grid is read from its table ([`PhaseGrid`]: one `sin_cos`
    /// per point of one period instead of one per point).
    #[inline(always)]
    fn forced(&mut self, am: &AffineMode<N>, t: f64) -> (SVector<f64, N>, f64) {
        match &mut self.phases {
            Some(g) => am.forced_at_phase(g.at(t)),
            None => am.forced(t),
        }
    }

    /// True when the affine modes are integrated exactly.
    pub(crate) fn is_exact(&self) -> bool {
        self.modes.is_some()
    }

    /// Current time (s).
    pub(crate) fn t(&self) -> f64 {
        self.t
    }

    /// Current vector.
    pub(crate) fn z(&self) -> S::State {
        self.z
    }

    /// Current mode.
    pub(crate) fn mode(&self) -> Mode {
        self.mode
    }

    /// Counters: the exact steps (each an accepted step with one right-hand-side evaluation)
    /// and their events, and Dormand-Prince's.
    pub(crate) fn stats(&self) -> Stats {
        let mut s = self.ode.stats();
        s += self.stats;
        s
    }

    /// Integrates to `t_end`, showing `observer` every step (with [`Carrier::DENSE`]) and
    /// every mode switch.
    pub(crate) fn integrate_observed<O: Observer<S::State, Mode>>(
        &mut self,
        t_end: f64,
        observer: &mut O,
    ) -> Result<(), SolverError> {
        while self.t < t_end {
            if self.ode_current {
                let modes = &self.modes;
                let back = self.ode.integrate_until(&self.sys, t_end, observer, |m| {
                    modes
                        .as_ref()
                        .is_some_and(|a| a.iter().any(|am| am.mode == m))
                })?;
                self.t = self.ode.t();
                self.z = self.ode.y();
                self.mode = self.ode.mode();
                if back {
                    self.ode_current = false;
                    self.switches_here = 0;
                }
            } else {
                let mode = self.mode;
                match self
                    .modes
                    .as_ref()
                    .and_then(|m| m.iter().position(|am| am.mode == mode))
                {
                    Some(i) => self.exact(i, t_end, observer)?,
                    None => self.hand_over(self.mode),
                }
            }
        }
        Ok(())
    }

    /// Gives the current point to Dormand-Prince, in `mode`.
    fn hand_over(&mut self, mode: Mode) {
        self.ode.restart_with_step(self.t, self.z, mode, self.h);
        self.ode_current = true;
    }

    /// The next point of the grid after `t`, or `t_end` (with true when the step from `t` is a
    /// whole grid step).
    fn next_point(&self, t_end: f64) -> (f64, bool) {
        let h = self.h;
        let idx = self.t / h;
        let n = idx.round();
        let on_grid = (idx - n).abs() <= 1e-9;
        let next = if on_grid { n + 1.0 } else { idx.ceil() };
        let t_next = next * h;
        if t_next >= t_end - 1e-9 * h {
            // The end of the integration: a whole step when it lies on the next grid point.
            let whole = on_grid && (t_end - t_next).abs() <= 1e-9 * h;
            (t_end, whole)
        } else {
            (t_next, on_grid)
        }
    }

    /// Exact steps in the affine mode `i` until `t_end` or a switch out of it.
    fn exact<O: Observer<S::State, Mode>>(
        &mut self,
        i: usize,
        t_end: f64,
        observer: &mut O,
    ) -> Result<(), SolverError> {
        let modes = Arc::clone(self.modes.as_ref().expect("an affine mode has its modes"));
        let am = &modes[i];
        // A guard already positive at the start fires at once (as in Dormand-Prince); one
        // within the rounding of its affine row is at zero (see
        // `AffineGuard::positive_beyond_rounding`).
        let y: SVector<f64, N> = head(&self.z);
        if let Some(g) = am.guards.iter().find(|g| g.positive_beyond_rounding(&y)) {
            return self.switch(am, g.index, y, observer);
        }
        let t0 = self.t;
        let (p0, a0) = self.forced(am, t0);
        let mut at = Point {
            t: t0,
            y,
            p: p0,
            f: am.rhs_with(a0, &y),
        };
        while self.t < t_end {
            let (t1, whole) = self.next_point(t_end);
            let s = t1 - at.t;
            // A whole step reads `e^{hL}` from the grid's propagators (no copy); a partial
            // step computes `e^{sL}`, and one shown to the observer needs `e^{sL/2}` for its
            // midpoint: with several masses `e^{sL}` is its square (one exponential instead
            // of two).
            let partial = if whole {
                None
            } else if self.square_half && S::DENSE && O::SEES {
                let half = expm_n(&(am.l * (0.5 * s)));
                Some((half * half, Some(half)))
            } else {
                Some((expm_n(&(am.l * s)), None))
            };
            let (p1, a1) = self.forced(am, t1);
            let y1 = match &partial {
                Some((e, _)) => e * (at.y - at.p),
                None => self.props[i].step * (at.y - at.p),
            } + p1;
            let next = Point {
                t: t1,
                y: y1,
                p: p1,
                f: am.rhs_with(a1, &y1),
            };
            self.stats.accepted += 1;
            self.stats.rhs_evals += 1;
            if let Some(ev) = self.locate(i, am, &at, &next) {
                // The step to the event, then the switch.
                if ev.s > 0.0 {
                    if S::DENSE && O::SEES {
                        let (p_ev, a_ev) = self.forced(am, at.t + ev.s);
                        let end = Point {
                            t: at.t + ev.s,
                            y: ev.y,
                            p: p_ev,
                            f: am.rhs_with(a_ev, &ev.y),
                        };
                        self.show(am, observer, &at, &end, Half::Compute);
                    }
                    let e_ev = || expm_n(&(am.l * ev.s));
                    self.z = self.sys.carry(am, e_ev, at.t, ev.s, &self.z, &ev.y);
                    self.switches_here = 0;
                }
                self.t = at.t + ev.s;
                return self.switch(am, ev.index, ev.y, observer);
            }
            if S::DENSE && O::SEES {
                let half = match &partial {
                    None => Half::Whole(i),
                    Some((_, half)) => half.as_ref().map_or(Half::Compute, Half::Known),
                };
                self.show(am, observer, &at, &next, half);
            }
            self.z = match &partial {
                Some((e, _)) => self.sys.carry(am, || *e, at.t, s, &self.z, &y1),
                None => {
                    let step = &self.props[i].step;
                    self.sys.carry(am, || *step, at.t, s, &self.z, &y1)
                }
            };
            self.t = t1;
            self.switches_here = 0;
            at = next;
        }
        Ok(())
    }

    /// Shows the step from `a` to `b` to the observer, with the quartic dense output through
    /// the exact midpoint. Called only where the carrier is dense and the observer sees its
    /// steps: the work is that of showing alone.
    fn show<O: Observer<S::State, Mode>>(
        &mut self,
        am: &AffineMode<N>,
        observer: &mut O,
        a: &Point<N>,
        b: &Point<N>,
        half: Half<'_, N>,
    ) {
        let s = b.t - a.t;
        let p_mid = self.forced(am, a.t + 0.5 * s).0;
        let d = a.y - a.p;
        let y_mid = match half {
            Half::Whole(i) => self.props[i].dyadic(1) * d,
            Half::Known(m) => m * d,
            Half::Compute => expm_n(&(am.l * (0.5 * s))) * d,
        } + p_mid;
        let step = Step::from_ends_and_midpoint(
            a.t,
            s,
            [widen(&a.y), widen(&y_mid), widen(&b.y)],
            [widen(&a.f), widen(&b.f)],
        );
        observer.step(&step, self.mode);
    }

    /// The switch through guard `index` of the affine mode `am` at the current time, where the
    /// state is `y`: by the carrier's own switch when the new mode is affine, else by handing
    /// the point to Dormand-Prince, which fires the guard at once.
    fn switch<O: Observer<S::State, Mode>>(
        &mut self,
        am: &AffineMode<N>,
        index: usize,
        y: SVector<f64, N>,
        observer: &mut O,
    ) -> Result<(), SolverError> {
        let mut z = self.z;
        z.components_mut()[..N].copy_from_slice(y.as_slice());
        let mut z_new = z;
        let to = self.sys.switch(am.mode, index, self.t, &mut z_new);
        let affine = self
            .modes
            .as_ref()
            .is_some_and(|m| m.iter().any(|am| am.mode == to));
        if affine {
            self.switches_here += 1;
            if self.switches_here > MAX_SWITCHES_AT_ONE_TIME {
                return Err(SolverError::Chattering {
                    t: self.t,
                    switches: self.switches_here,
                    modes: vec![format!("{:?}", am.mode), format!("{to:?}")],
                    state: y.iter().copied().collect(),
                });
            }
            observer.switched(self.t, am.mode, to);
            self.stats.events += 1;
            self.z = z_new;
            self.mode = to;
        } else {
            // Dormand-Prince takes the point in the old mode, where the guard is positive: it
            // fires at once, and Dormand-Prince goes on until an affine mode is back.
            self.z = z;
            self.hand_over(am.mode);
        }
        Ok(())
    }

    /// The earliest crossing of a guard of `am` within the step from `a` to `b`, on the exact
    /// solution (see [`super`]).
    fn locate(
        &mut self,
        i: usize,
        am: &AffineMode<N>,
        a: &Point<N>,
        b: &Point<N>,
    ) -> Option<Located<N>> {
        let s = b.t - a.t;
        let mut best: Option<Located<N>> = None;
        for g in am.guards.iter() {
            let (g0, g1) = (g.at(&a.y), g.at(&b.y));
            let upper = if g1 > 0.0 {
                Some((s, b.y))
            } else {
                // An interior maximum near zero (a grazing trajectory).
                let (d0, d1) = (g.n.dot(&a.f) * s, g.n.dot(&b.f) * s);
                if !(d0 > 0.0 && d1 < 0.0) {
                    continue;
                }
                let scale: f64 =
                    g.n.iter()
                        .zip(self.scales.iter())
                        .map(|(n, c)| (n * c).abs())
                        .sum();
                if cubic_max(g0, d0, g1, d1) < -GRAZE_MARGIN * scale {
                    continue;
                }
                let (s_max, y_max) = self.bisect(i, am, a, s, |y, drive| {
                    g.n.dot(&am.rhs_with(drive, y)) <= 0.0
                });
                (g.at(&y_max) > 0.0).then_some((s_max, y_max))
            };
            let Some((s_hi, y_hi)) = upper else { continue };
            if best.as_ref().is_some_and(|b| b.s <= 0.0) {
                continue;
            }
            let (s_ev, y_ev) = self.bisect_with(i, am, a, s_hi, Some(y_hi), |y, _| g.at(y) > 0.0);
            if best.as_ref().is_none_or(|b| s_ev < b.s) {
                best = Some(Located {
                    s: s_ev,
                    index: g.index,
                    y: y_ev,
                });
            }
        }
        best
    }

    /// The first point of `(0, s]` after `a` where `past(y, drive)` holds, with the drive's
    /// acceleration `drive` there (it does at `s`, where
    /// the state is `y_s` if known, and not at 0, and once it holds it keeps holding over the
    /// step), to the event time tolerance, with the state there: bisection on the exact
    /// solution through the propagators `e^{h L / 2^j}`.
    fn bisect_with(
        &mut self,
        i: usize,
        am: &AffineMode<N>,
        a: &Point<N>,
        s: f64,
        y_s: Option<SVector<f64, N>>,
        past: impl Fn(&SVector<f64, N>, f64) -> bool,
    ) -> (f64, SVector<f64, N>) {
        let (mut lo, mut y_lo, mut p_lo) = (0.0, a.y, a.p);
        let (mut hi, mut y_hi) = (s, y_s);
        // On the exact path the drive's phase at the lower end is carried and turned by
        // the dyadic rotations (see `phase.rs`) instead of a `sin_cos` per halving.
        let mut phase_lo = self.phases.as_mut().map(|g| g.at(a.t));
        let mut j = 0usize;
        while hi - lo > self.time_tol && j < 63 {
            j += 1;
            let ds = self.h * 0.5f64.powi(j as i32);
            if lo + ds >= hi {
                continue;
            }
            let (phase_c, (p_c, drive_c)) = match (self.phases.as_mut(), phase_lo) {
                (Some(g), Some(ph)) => {
                    let ph_c = turned(ph, g.turn(j));
                    (Some(ph_c), am.forced_at_phase(ph_c))
                }
                _ => (None, self.forced(am, a.t + lo + ds)),
            };
            let y_c = self.props[i].dyadic(j) * (y_lo - p_lo) + p_c;
            if past(&y_c, drive_c) {
                (hi, y_hi) = (lo + ds, Some(y_c));
            } else {
                (lo, y_lo, p_lo, phase_lo) = (lo + ds, y_c, p_c, phase_c);
            }
        }
        let y = match y_hi {
            Some(y) => y,
            None => expm_n(&(am.l * hi)) * (a.y - a.p) + self.forced(am, a.t + hi).0,
        };
        (hi, y)
    }

    /// [`Engine::bisect_with`] without the state at `s`.
    fn bisect(
        &mut self,
        i: usize,
        am: &AffineMode<N>,
        a: &Point<N>,
        s: f64,
        past: impl Fn(&SVector<f64, N>, f64) -> bool,
    ) -> (f64, SVector<f64, N>) {
        self.bisect_with(i, am, a, s, None, past)
    }
}

/// Where `e^{sL/2}` comes from for the midpoint of a step of length `s` shown to the observer.
enum Half<'a, const N: usize> {
    /// A whole step of affine mode `i`: the grid's `e^{hL/2}`.
    Whole(usize),
    /// Already computed.
    Known(&'a SMatrix<f64, N, N>),
    /// Computed by the step.
    Compute,
}

/// A point of an exact step: time, state, the particular solution and the right-hand side
/// there.
#[derive(Debug, Clone, Copy)]
struct Point<const N: usize> {
    t: f64,
    y: SVector<f64, N>,
    p: SVector<f64, N>,
    f: SVector<f64, N>,
}

/// The largest value of the cubic Hermite interpolant with end values `g0`, `g1` and end
/// slopes times the step `d0`, `d1` on [0, 1].
pub(crate) fn cubic_max(g0: f64, d0: f64, g1: f64, d1: f64) -> f64 {
    // p(th) = g0 + d0 th + b th^2 + c th^3.
    let b = 3.0 * (g1 - g0) - 2.0 * d0 - d1;
    let c = 2.0 * (g0 - g1) + d0 + d1;
    let p = |th: f64| g0 + th * (d0 + th * (b + th * c));
    let mut best = g0.max(g1);
    // p'(th) = d0 + 2 b th + 3 c th^2.
    let (qa, qb, qc) = (3.0 * c, 2.0 * b, d0);
    let mut consider = |th: f64| {
        if th > 0.0 && th < 1.0 {
            best = best.max(p(th));
        }
    };
    if qa == 0.0 {
        if qb != 0.0 {
            consider(-qc / qb);
        }
    } else {
        let disc = qb * qb - 4.0 * qa * qc;
        if disc >= 0.0 {
            let r = disc.sqrt();
            consider((-qb + r) / (2.0 * qa));
            consider((-qb - r) / (2.0 * qa));
        }
    }
    best
}

/// A state as a carried vector's head (zeros elsewhere), for the dense steps of the state.
#[inline(always)]
fn widen<V: Vector, const N: usize>(y: &SVector<f64, N>) -> V {
    let mut z = V::zeros();
    let c = z.components_mut();
    let n = c.len().min(N);
    c[..n].copy_from_slice(&y.as_slice()[..n]);
    z
}
