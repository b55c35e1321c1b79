//! The objects the fit's model follows as the parameters move (see the parent module's
//! "Misfit"): a periodic orbit at a measured frequency, the grazing orbit where a branch
//! starts or stops touching a stop, and the fold where a branch ends. Each is found again at
//! new parameter values by Newton's method from where it was, so that an evaluation of the
//! misfit costs a few periods of integration per measured value instead of a sweep.

use crate::ode::Stats;
use crate::physics::harvester::Harvester as Model4;

/// The fit's model: the paper's devices, four components.
type Harvester = Model4<4>;
type State = nalgebra::SVector<f64, 4>;
use crate::progress::Silent;
use crate::study::continuation::{continue_branch_until, ContinuationSettings, Event, EventKind};
use crate::study::orbit::{
    FoldSearch, Forcing, Orbit, Parameter, Shooter, ShootingOptions, DISTINCT_REL,
};

use super::Quantity;

/// Why an object could not be followed to new parameter values (a trial of the search is then
/// rejected, or the model falls back to the stepped sweep).
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Lost(pub(super) String);

impl<E: std::error::Error> From<E> for Lost {
    fn from(e: E) -> Self {
        Lost(e.to_string())
    }
}

/// A located grazing frequency is converged when a secant step is below this (Hz, relative):
/// far below the change a finite-difference step of the parameters causes (1e-6 to 1e-3).
const GRAZING_REL_TOL: f64 = 1e-10;

/// Tolerance of a located fold (Hz, as arclength along the branch): the fold's frequency is
/// stationary along the branch, so its error is of the order of this squared.
const FOLD_LOCATE_TOL_HZ: f64 = 1e-5;

/// Newton iterations for an orbit followed from nearby parameter values (the default
/// shooting settings otherwise): from a good guess Newton converges in three or four, and a
/// branch that has ended is given up early. Fewer lose the orbits of the long steps a search
/// needs (with 5 the recovery family's cases 15 and 18 end at chi-square per degree of
/// freedom 2.2 and 3.2 instead of 1.1); more gain nothing (with 16 cases 15, 20 and 21 take
/// the same time within the host's noise); the `fit_cost` example measures both. Each
/// iteration integrates the variational equations; leading them with chord steps on the plain
/// period map with the previous orbit's monodromy cut those integrations by about a third in
/// case 13, but case 4 then ended at chi-square per degree of freedom 6.2 instead of 1.2 (a
/// chord step leaving the branch near a fold, where that matrix minus the identity is nearly
/// singular, is the suspected cause, not shown), so every iteration is Newton's own.
const TRACK_MAX_NEWTON: usize = 8;

fn shooting() -> ShootingOptions {
    ShootingOptions {
        max_newton: TRACK_MAX_NEWTON,
        ..ShootingOptions::default()
    }
}

/// The value of a measured quantity on an orbit.
pub(super) fn quantity_of(q: Quantity, o: &Orbit) -> f64 {
    match q {
        Quantity::V1RmsV => o.summary.v1_rms_v,
        Quantity::PTotalW => o.summary.p_total_w,
    }
}

fn forcing(freq_hz: f64, accel_rms_g: f64) -> Forcing {
    Forcing {
        freq_hz,
        accel_rms_g,
    }
}

/// The periodic orbit of `h` at `freq_hz` by Newton from `guess` (the state at drive phase
/// `phase_rad`), with its section moved into free flight; refused unless stable (a measured
/// steady state is stable).
fn stable_orbit(
    h: &Harvester,
    freq_hz: f64,
    accel_rms_g: f64,
    phase_rad: f64,
    guess: State,
) -> Result<Orbit, Lost> {
    let o = orbit(h, freq_hz, accel_rms_g, phase_rad, guess)?;
    if !o.is_stable() {
        return Err(Lost(format!(
            "the orbit at {freq_hz} Hz is unstable (largest multiplier {:.4})",
            o.max_multiplier_abs()
        )));
    }
    Ok(o)
}

fn orbit(
    h: &Harvester,
    freq_hz: f64,
    accel_rms_g: f64,
    phase_rad: f64,
    guess: State,
) -> Result<Orbit, Lost> {
    let shooter = Shooter::new(h, shooting());
    let mut stats = Stats::default();
    let f = forcing(freq_hz, accel_rms_g);
    orbit_of(&shooter, &f, phase_rad, guess, 1, &mut stats)
}

/// The orbit of `periods` drive periods under `f` by Newton from `guess`, with its section
/// moved into free flight.
fn orbit_of(
    shooter: &Shooter<'_, Harvester, 4>,
    f: &Forcing,
    phase_rad: f64,
    guess: State,
    periods: usize,
    stats: &mut Stats,
) -> Result<Orbit, Lost> {
    let p = Parameter::Frequency;
    let o = shooter.solve_periods(f, p, phase_rad, guess, periods, stats)?;
    if shooter.section_is_free(&o) {
        Ok(o)
    } else {
        Ok(shooter.reanchor(&o, p, stats)?)
    }
}

/// The stable orbit a measured point is compared with: as [`stable_orbit`] from an orbit of
/// `periods` drive periods (1 or 2), and where the period-1 orbit has lost its stability by a
/// period doubling, the orbit of two periods born there (past the doubling the steady state
/// is that orbit while it is stable). A fixed point of the two-period map that one period
/// leaves in place is the period-1 orbit (the doubling has moved past the point): it is
/// followed as such, so that the value is continuous as the doubling passes.
pub(super) fn point_orbit(
    h: &Harvester,
    freq_hz: f64,
    accel_rms_g: f64,
    phase_rad: f64,
    guess: State,
    periods: usize,
) -> Result<Orbit, Lost> {
    let shooter = Shooter::new(h, shooting());
    let mut stats = Stats::default();
    let f = forcing(freq_hz, accel_rms_g);
    let p = Parameter::Frequency;
    let mut o = orbit_of(&shooter, &f, phase_rad, guess, periods, &mut stats)?;
    if o.periods == 2 && shooter.one_period_split(&o, p)? <= DISTINCT_REL {
        o = orbit_of(&shooter, &f, o.phase_rad, o.state_n(), 1, &mut stats)?;
    }
    if o.periods == 1 && o.is_flip_unstable() {
        o = shooter.period_doubled(&o, &f, p, &mut stats)?;
    }
    if !o.is_stable() {
        return Err(Lost(format!(
            "the orbit of {} period(s) at {freq_hz} Hz is unstable (largest multiplier {:.4})",
            o.periods,
            o.max_multiplier_abs()
        )));
    }
    Ok(o)
}

/// A grazing orbit: where the branch of the device without its stops reaches a stop. Before
/// the first contact (and after the last) the device's orbit is that orbit, so the frequency
/// at which its largest excursion equals the gap is where contact starts (or ends), and it
/// moves smoothly with the parameters.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Grazing {
    /// Frequency (Hz).
    pub(super) freq_hz: f64,
    /// The stop-free orbit's state at drive phase zero.
    pub(super) state: State,
    /// Slope of the grazing test (m per Hz) there, for the next secant step.
    pub(super) slope: f64,
}

/// How far the stop-free orbit `o` reaches past the nearer stop of `h` (m; zero at grazing).
fn past_stop(h: &Harvester, o: &Orbit) -> f64 {
    use crate::laws::contact::Side;
    let s = &o.summary;
    (s.x_upper_m - h.gap(Side::Upper)).max(-s.x_lower_m - h.gap(Side::Lower))
}

/// The stop-free orbit at `freq_hz` from `guess` (phase zero) and how far it reaches past the
/// stop.
fn free_test(
    h: &Harvester,
    free: &Harvester,
    freq_hz: f64,
    accel_rms_g: f64,
    guess: State,
) -> Result<(f64, State), Lost> {
    // Without stops the section at phase zero is always in free flight: no re-anchoring.
    let shooter = Shooter::new(free, shooting());
    let mut stats = Stats::default();
    let o = shooter.solve(
        &forcing(freq_hz, accel_rms_g),
        Parameter::Frequency,
        0.0,
        guess,
        &mut stats,
    )?;
    Ok((past_stop(h, &o), o.state_n()))
}

/// Secant iteration on the grazing test from (f0, g0) with slope `slope`, the stop-free orbit
/// at f0 being `y0`; each step at most `max_step_hz`.
fn secant(
    h: &Harvester,
    accel_rms_g: f64,
    (mut f0, mut g0, mut y0): (f64, f64, State),
    mut slope: f64,
    max_step_hz: f64,
) -> Result<Grazing, Lost> {
    let free = h.without_stops();
    for _ in 0..40 {
        if !(slope.is_finite() && slope != 0.0) {
            return Err(Lost(format!("grazing near {f0} Hz: flat test")));
        }
        let df = (-g0 / slope).clamp(-max_step_hz, max_step_hz);
        let f1 = f0 + df;
        if f1 <= 0.0 {
            return Err(Lost("grazing: frequency left the positive axis".into()));
        }
        let (g1, y1) = free_test(h, &free, f1, accel_rms_g, y0)
            .map_err(|e| Lost(format!("grazing near {f0} Hz: {}", e.0)))?;
        if g1 != g0 {
            slope = (g1 - g0) / (f1 - f0);
        }
        (f0, g0, y0) = (f1, g1, y1);
        if df.abs() <= GRAZING_REL_TOL * f1 {
            return Ok(Grazing {
                freq_hz: f1,
                state: y1,
                slope,
            });
        }
    }
    Err(Lost(format!("grazing near {f0} Hz: no convergence")))
}

/// Locates the grazing between `f_free` (where the device's orbit, from `y_free` at phase
/// zero, does not touch a stop) and `f_other` (where it does).
pub(super) fn locate_grazing(
    h: &Harvester,
    accel_rms_g: f64,
    f_free: f64,
    y_free: State,
    f_other: f64,
) -> Result<Grazing, Lost> {
    let free = h.without_stops();
    let ctx = |e: Lost| {
        Lost(format!(
            "grazing between {f_free} and {f_other} Hz: {}",
            e.0
        ))
    };
    let (g0, y0) = free_test(h, &free, f_free, accel_rms_g, y_free).map_err(ctx)?;
    let (g1, y1) = free_test(h, &free, f_other, accel_rms_g, y0).map_err(ctx)?;
    let slope = (g1 - g0) / (f_other - f_free);
    let span = (f_other - f_free).abs();
    // Start from the end nearer the root.
    let start = if g0.abs() <= g1.abs() {
        (f_free, g0, y0)
    } else {
        (f_other, g1, y1)
    };
    secant(h, accel_rms_g, start, slope, span)
}

/// The grazing of `h` near `from` (its frequency at the parameters before).
pub(super) fn track_grazing(
    h: &Harvester,
    accel_rms_g: f64,
    from: &Grazing,
) -> Result<Grazing, Lost> {
    let free = h.without_stops();
    let (g0, y0) = free_test(h, &free, from.freq_hz, accel_rms_g, from.state)?;
    secant(
        h,
        accel_rms_g,
        (from.freq_hz, g0, y0),
        from.slope,
        0.05 * from.freq_hz,
    )
}

/// A state from which Newton's method may find the orbit at a frequency.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Guess {
    /// Frequency (Hz).
    pub(super) freq_hz: f64,
    /// Drive phase of the state (rad).
    pub(super) phase_rad: f64,
    /// The state.
    pub(super) state: State,
}

impl Guess {
    pub(super) fn of(o: &Orbit) -> Self {
        Self {
            freq_hz: o.forcing.freq_hz,
            phase_rad: o.phase_rad,
            state: o.state_n(),
        }
    }
}

/// A fold that ends a branch in the sweep's direction: the fold orbit, and states of the
/// branch before it (in the sweep's order) from which the next location starts.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Fold {
    /// The orbit at the fold.
    pub(super) orbit: Orbit,
    /// States of the branch before the fold, in the sweep's order.
    pub(super) before: Vec<Guess>,
    /// +1: the fold ends an up-sweep's branch; -1: a down-sweep's.
    pub(super) dir: f64,
}

impl Fold {
    /// Frequency (Hz).
    pub(super) fn freq_hz(&self) -> f64 {
        self.orbit.forcing.freq_hz
    }

    /// True when `freq_hz` lies beyond the fold in the sweep's direction (where the branch
    /// before it does not exist).
    pub(super) fn beyond(&self, freq_hz: f64) -> bool {
        (freq_hz - self.freq_hz()) * self.dir >= 0.0
    }

    /// The state before the fold nearest `freq_hz` (a Newton guess).
    pub(super) fn nearest(&self, freq_hz: f64) -> Guess {
        self.before
            .iter()
            .copied()
            .min_by(|a, b| {
                (a.freq_hz - freq_hz)
                    .abs()
                    .total_cmp(&(b.freq_hz - freq_hz).abs())
            })
            .unwrap_or(Guess::of(&self.orbit))
    }
}

/// A fold followed by Newton's method is taken for the one it follows when its multiplier
/// nearest 1 lies this close to 1: at a smooth fold M - I is singular, and the fold's location
/// to [`FOLD_LOCATE_TOL_HZ`] leaves the multiplier within about that of 1 times the branch's
/// curvature; the corner of a branch at a grazing, where the branch turns without a
/// multiplier at 1, is far from it.
const FOLD_MULTIPLIER_TOL: f64 = 0.02;

/// Largest move of a fold followed by Newton's method, relative to its frequency (as a
/// grazing's, [`track_grazing`]): a fold further away is located afresh.
const FOLD_MOVE_REL: f64 = 0.05;

/// The fold of `h` near `from` (the fold at the parameters before), by Newton's method on the
/// fold itself ([`Shooter::fold_near`]) instead of a continuation up to it; the states before
/// it are kept as Newton guesses. Refused unless the fold found is the one followed: as far
/// from the old as [`FOLD_MOVE_REL`] allows, short of `limit_hz`, a multiplier at 1, the
/// branch turning back against the sweep's direction there (the branch's other fold turns the
/// other way), and the same contacts, or other contacts that the stable branch half a sweep
/// step before it has too (the parameters moved the fold onto that branch). The states before
/// it are those of the fold it started from: they serve as Newton guesses only while no point
/// crosses the fold (see `branch::track`).
pub(super) fn track_fold(
    h: &Harvester,
    accel_rms_g: f64,
    from: &Fold,
    limit_hz: f64,
    max_step_hz: f64,
) -> Result<Fold, Lost> {
    let shooter = Shooter::new(h, shooting());
    let mut stats = Stats::default();
    let mut start = from.orbit.clone();
    start.forcing.accel_rms_g = accel_rms_g;
    let search = FoldSearch {
        param: Parameter::Frequency,
        param_scale: 1.0,
        tol: FOLD_LOCATE_TOL_HZ,
        max_step: max_step_hz,
    };
    let found = shooter.fold_near(&start, &search, &mut stats)?;
    let o = found.orbit;
    let (f_old, f_new) = (from.freq_hz(), o.forcing.freq_hz);
    let near_one = o
        .multipliers
        .iter()
        .map(|m| (m - 1.0).norm())
        .fold(f64::INFINITY, f64::min);
    // A fold whose impact count changed (the parameters moved it onto a branch with more or
    // fewer impacts per period) is kept when the branch it ends is that fold's: the stable
    // orbit Newton finds half a step before it has the fold's impact count.
    let impacts = o.summary.impacts;
    let same_branch = || {
        let f_side = f_new - from.dir * 0.5 * max_step_hz;
        stable_orbit(h, f_side, accel_rms_g, o.phase_rad, o.state_n())
            .is_ok_and(|side| side.summary.impacts == impacts)
    };
    if (f_new - f_old).abs() > FOLD_MOVE_REL * f_old
        || (f_new - limit_hz) * from.dir > 0.0
        || near_one > FOLD_MULTIPLIER_TOL
        || found.curvature * from.dir >= 0.0
        || (impacts != from.orbit.summary.impacts && !same_branch())
    {
        return Err(Lost(format!(
            "fold followed from {f_old} Hz to {f_new} Hz is another (multiplier off 1 by \
             {near_one:.3e}, {} impacts, curvature {:.3e})",
            o.summary.impacts, found.curvature
        )));
    }
    Ok(Fold {
        orbit: o,
        before: from.before.clone(),
        dir: from.dir,
    })
}

/// Starts tried, each further from the old fold, before a fold is given up as lost.
const FOLD_TRIES: usize = 4;

/// Follows the branch of `h` in the direction `dir` until it folds back, no further than
/// `limit_hz`, with parameter steps of at most `max_step_hz`, from the first of the states
/// `before` (in the sweep's order) at least `max_step_hz` short of `near_hz` whose stable
/// orbit Newton finds (trying earlier ones while it does not); returns the first fold at
/// which the branch loses stability (away from a grazing corner).
pub(super) fn locate_fold(
    h: &Harvester,
    accel_rms_g: f64,
    before: &[Guess],
    near_hz: f64,
    dir: f64,
    limit_hz: f64,
    max_step_hz: f64,
) -> Result<Fold, Lost> {
    let candidates: Vec<usize> = (0..before.len())
        .rev()
        .filter(|&i| (near_hz - before[i].freq_hz) * dir >= max_step_hz)
        .take(FOLD_TRIES)
        .collect();
    let mut last_err = Lost(format!("fold: no state a step before {near_hz} Hz"));
    for i in candidates {
        let g = &before[i];
        match fold_from(h, accel_rms_g, g, limit_hz, max_step_hz) {
            Ok((orbit, points)) => {
                let mut kept: Vec<Guess> = before[..i].to_vec();
                kept.extend(points);
                return Ok(Fold {
                    orbit,
                    before: kept,
                    dir,
                });
            }
            Err(e) => last_err = e,
        }
    }
    Err(last_err)
}

/// The fold ahead of the stable orbit Newton finds from `g`, and the branch's stable states
/// before it.
fn fold_from(
    h: &Harvester,
    accel_rms_g: f64,
    g: &Guess,
    limit_hz: f64,
    max_step_hz: f64,
) -> Result<(Orbit, Vec<Guess>), Lost> {
    let f_start = g.freq_hz;
    let ctx = |e: Lost| Lost(format!("fold from {f_start} Hz: {}", e.0));
    let first = stable_orbit(h, f_start, accel_rms_g, g.phase_rad, g.state).map_err(ctx)?;
    let mut settings = ContinuationSettings::frequency(f_start, limit_hz, max_step_hz);
    settings.locate_tol = FOLD_LOCATE_TOL_HZ;
    let jump = |e: &Event| e.kind == EventKind::Fold && !e.at_grazing && e.stable_before;
    // The branch ends at that fold: what lies beyond it is not needed.
    let branch =
        continue_branch_until(h, first, &settings, &Silent, jump).map_err(|e| ctx(e.into()))?;
    let Some(fold) = branch.events.iter().find(|e| jump(e)) else {
        return Err(Lost(format!(
            "no fold between {f_start} and {limit_hz} Hz on the branch"
        )));
    };
    let points = branch.points[..=fold.after_point]
        .iter()
        .map(|p| &p.orbit)
        .filter(|o| o.is_stable())
        .map(Guess::of)
        .collect();
    Ok((fold.orbit.clone(), points))
}
