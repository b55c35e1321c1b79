//! Pseudo-arclength continuation of periodic orbits in a drive parameter (frequency or
//! amplitude), passing folds, with the detection and location of folds, branch points, period
//! doublings, torus bifurcations and grazing.
//!
//! # The branch
//! The unknowns are u = (z, q): the orbit's state at its section in scaled coordinates
//! ([`crate::study::orbit`]) and the parameter in units of [`ContinuationSettings::param_scale`].
//! From a point u_k with unit tangent t_k, the predictor u_k + ds t_k is corrected by Newton on
//!
//! P(z, q) - z = 0,   t_k . (u - u_k) = ds,
//!
//! whose Jacobian is the monodromy minus the identity bordered by dP/dq and t_k (Keller's
//! pseudo-arclength). The new tangent spans the kernel of [M - I | dP/dq], oriented along t_k.
//! Because the parameter is an unknown, the branch passes folds where a natural-parameter
//! continuation would stop. A step is rejected (and halved) when Newton fails, when the tangent
//! turns by more than [`ContinuationSettings::max_turn_rad`], or when the parameter moves by
//! more than [`ContinuationSettings::max_param_step`]; it grows after easy corrections. A step
//! below [`ContinuationSettings::ds_min`] is an error naming the last parameter value reached.
//!
//! # Events (Seydel; Kuznetsov, chapter 10)
//! Between two accepted points, sign changes of test functions mark events, each located by the
//! crate's root finder on the branch (arclength from the earlier point, every evaluation a
//! corrected orbit):
//!
//! | event | test function | |
//! |---|---|---|
//! | fold (turning point) | parameter component of the tangent | a real multiplier crosses +1 *and* the branch turns |
//! | branch point | prod (mu_i - 1) | a real multiplier crosses +1 where the branch does **not** turn (e.g. the symmetric impacting orbit losing stability to a pair of asymmetric ones) |
//! | period doubling | prod (mu_i + 1) | a real multiplier crosses -1 |
//! | torus | largest modulus - 1 | a complex pair leaves the unit circle |
//! | grazing | max |x| - x_max | the orbit starts or stops touching a stop |
//!
//! A +1 crossing is called a fold only where the branch turns: a crossing without a turn is a
//! branch point and is never presented as a fold. A turn at a grazing point, where the branch
//! has a corner rather than a smooth maximum, is a fold whose `at_grazing` flag is set.

use nalgebra::{Matrix4, SMatrix, SVector, Vector4};

use crate::drive::Sine;
use crate::num::roots::{illinois, RootOptions, Sample};
use crate::ode::Stats;
use crate::physics::contact::Side;
use crate::physics::harvester::{Harvester, State};
use crate::study::orbit::{
    Forcing, Orbit, OrbitError, Parameter, Shooter, ShootingConfig, CHORD_STEPS,
};

type Vector5 = SVector<f64, 5>;

type Matrix5 = SMatrix<f64, 5, 5>;

/// The gaps of a model's two sides (infinite where there is no stop), for the grazing test.
#[derive(Debug, Clone, Copy)]
struct Gaps {
    upper: f64,
    lower: f64,
}

impl Gaps {
    fn of(h: &Harvester<Sine>) -> Self {
        Self {
            upper: h.gap(Side::Upper),
            lower: h.gap(Side::Lower),
        }
    }

    fn smallest(self) -> f64 {
        self.upper.min(self.lower)
    }
}

/// Largest distance of a corrected point from its predictor, in arclength steps: beyond it
/// the step is rejected as having jumped to another branch.
const MAX_CORRECTION: f64 = 0.5;

/// Largest parameter step across a grazing, as a fraction of the largest step.
const GRAZING_STEP: f64 = 0.01;

/// An orbit is near grazing when its largest displacement is within this fraction of the gap
/// (where a corner of the branch is looked for).
const GRAZING_NEAR: f64 = 1e-3;

/// Largest factor by which the largest Floquet multiplier's modulus may change in one step.
const MAX_MULTIPLIER_RATIO: f64 = 2.0;

/// Settings of a continuation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContinuationSettings {
    /// The parameter varied.
    pub parameter: Parameter,
    /// First value (the branch starts here).
    pub start: f64,
    /// The continuation stops at the first point beyond this value (either side of `start`),
    /// or at the first point that falls back below `start` (beyond it, seen from `stop`).
    pub stop: f64,
    /// The parameter's unit in the arclength (Hz or g).
    pub param_scale: f64,
    /// First arclength step.
    pub ds_init: f64,
    /// Smallest arclength step (below it the branch cannot be continued).
    pub ds_min: f64,
    /// Largest arclength step.
    pub ds_max: f64,
    /// Largest change of the parameter per step (Hz or g).
    pub max_param_step: f64,
    /// Largest angle between successive tangents (rad).
    pub max_turn_rad: f64,
    /// Largest number of points.
    pub max_points: usize,
    /// Tolerance on the parameter of a located event (Hz or g).
    pub locate_tol: f64,
    /// Shooting settings.
    pub shooting: ShootingConfig,
}

impl ContinuationSettings {
    /// Settings for a frequency continuation from `start` to `stop` (Hz) with parameter steps
    /// of at most `max_step_hz`: arclength unit 1 Hz, tangents turning by at most 10 degrees,
    /// events located to 1e-4 Hz, the default shooting settings.
    pub fn frequency(start: f64, stop: f64, max_step_hz: f64) -> Self {
        Self {
            parameter: Parameter::Frequency,
            start,
            stop,
            param_scale: 1.0,
            ds_init: 0.25 * max_step_hz,
            ds_min: 1e-7,
            ds_max: 4.0 * max_step_hz,
            max_param_step: max_step_hz,
            max_turn_rad: 10f64.to_radians(),
            max_points: 20_000,
            locate_tol: 1e-4,
            shooting: ShootingConfig::default(),
        }
    }

    /// Settings for an amplitude continuation from `start` to `stop` (g rms) with steps of
    /// at most `max_step_g`: arclength unit 0.1 g, events located to 1e-6 g.
    pub fn amplitude(start: f64, stop: f64, max_step_g: f64) -> Self {
        Self {
            parameter: Parameter::Amplitude,
            start,
            stop,
            param_scale: 0.1,
            ds_init: 2.5 * max_step_g,
            ds_min: 1e-8,
            ds_max: 40.0 * max_step_g,
            max_param_step: max_step_g,
            max_turn_rad: 10f64.to_radians(),
            max_points: 20_000,
            locate_tol: 1e-6,
            shooting: ShootingConfig::default(),
        }
    }

    /// The same with half the integrator tolerance.
    pub fn halved(&self) -> Self {
        Self {
            shooting: self.shooting.halved(),
            ..*self
        }
    }

    fn direction(&self) -> f64 {
        if self.stop >= self.start {
            1.0
        } else {
            -1.0
        }
    }

    /// True once the branch has left the range between `start` and `stop` on either side (a
    /// branch that turns back at a fold may run out below its start).
    fn beyond_stop(&self, p: f64) -> bool {
        (p - self.stop) * self.direction() > 0.0 || (self.start - p) * self.direction() > 0.0
    }

    fn validate(&self) -> Result<(), OrbitError> {
        let ok = self.start.is_finite()
            && self.stop.is_finite()
            && self.start > 0.0
            && self.stop > 0.0
            && self.start != self.stop
            && self.param_scale > 0.0
            && self.ds_min > 0.0
            && self.ds_init >= self.ds_min
            && self.ds_max >= self.ds_init
            && self.max_param_step > 0.0
            && self.max_turn_rad > 0.0
            && self.max_points >= 2
            && self.locate_tol > 0.0;
        if ok {
            Ok(())
        } else {
            Err(OrbitError::Invalid(format!(
                "continuation settings: {self:?} (positive, distinct start and stop; \
                 0 < ds_min <= ds_init <= ds_max)"
            )))
        }
    }
}

/// A point of a branch: the orbit and the unit tangent of the branch there.
#[derive(Debug, Clone, PartialEq)]
pub struct BranchPoint {
    /// The orbit.
    pub orbit: Orbit,
    /// Unit tangent (dz, dq) in scaled coordinates, oriented along the branch.
    pub tangent: Vector5,
}

impl BranchPoint {
    /// The parameter component of the tangent (its sign changes at a fold).
    pub fn param_tangent(&self) -> f64 {
        self.tangent[4]
    }
}

/// What happens at an event of a branch (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EventKind {
    /// The branch turns back in the parameter.
    Fold,
    /// A real multiplier crosses +1 where the branch does not turn.
    BranchPoint,
    /// A real multiplier crosses -1.
    PeriodDoubling,
    /// A complex pair of multipliers crosses the unit circle.
    Torus,
    /// The orbit's largest |x| reaches the stop.
    Grazing,
}

impl EventKind {
    /// Label for tables.
    pub fn label(self) -> &'static str {
        match self {
            EventKind::Fold => "fold",
            EventKind::BranchPoint => "branch point",
            EventKind::PeriodDoubling => "period doubling",
            EventKind::Torus => "torus",
            EventKind::Grazing => "grazing",
        }
    }
}

/// A located event.
#[derive(Debug, Clone, PartialEq)]
pub struct Event {
    /// What happens.
    pub kind: EventKind,
    /// Parameter value (Hz or g).
    pub param: f64,
    /// The orbit at the event.
    pub orbit: Orbit,
    /// Index of the branch point before the event.
    pub after_point: usize,
    /// Arclength from that point.
    pub s: f64,
    /// For a fold: a real multiplier crossed +1 in the same interval (a smooth fold); false
    /// for a corner of the branch.
    pub multiplier_crossing: bool,
    /// For a fold: the orbit grazes a stop in the same interval (a corner at grazing).
    pub at_grazing: bool,
    /// Stable on the side of the event before it (in the order of the branch).
    pub stable_before: bool,
    /// Stable on the side after it.
    pub stable_after: bool,
}

/// A continued branch of periodic orbits.
#[derive(Debug, Clone, PartialEq)]
pub struct Branch {
    /// The parameter varied.
    pub parameter: Parameter,
    /// Points in order along the branch.
    pub points: Vec<BranchPoint>,
    /// Located events in order along the branch.
    pub events: Vec<Event>,
    /// Integrator counters of every integration.
    pub stats: Stats,
    /// Rejected continuation steps.
    pub rejected_steps: usize,
}

impl Branch {
    /// The events of one kind.
    pub fn events_of(&self, kind: EventKind) -> impl Iterator<Item = &Event> {
        self.events.iter().filter(move |e| e.kind == kind)
    }

    /// The upper fold: the fold away from grazing at the highest parameter value at which the
    /// branch loses stability (where an up-sweep leaves the upper branch); `None` without one.
    pub fn upper_fold(&self) -> Option<&Event> {
        self.events_of(EventKind::Fold)
            .filter(|e| !e.at_grazing && e.stable_before && !e.stable_after)
            .max_by(|a, b| a.param.total_cmp(&b.param))
    }

    /// The grazing points in branch order: grazing events and corners of the branch at
    /// grazing (a fold located at the grazing orbit).
    pub fn grazing_events(&self) -> impl Iterator<Item = &Event> {
        self.events
            .iter()
            .filter(|e| e.kind == EventKind::Grazing || e.at_grazing)
    }

    /// Largest plain-map residual |P(y) - y| / |y| over every point and event.
    pub fn max_residual(&self) -> f64 {
        self.points
            .iter()
            .map(|p| &p.orbit)
            .chain(self.events.iter().map(|e| &e.orbit))
            .map(|o| o.residual)
            .fold(0.0, f64::max)
    }

    /// The parameter values of the points.
    pub fn params(&self) -> impl Iterator<Item = f64> + '_ {
        self.points
            .iter()
            .map(move |p| p.orbit.param(self.parameter))
    }

    /// Every point of the branch at parameter `value`, corrected there: one orbit per crossing
    /// of `value` by the branch (in branch order).
    pub fn orbits_at(
        &self,
        shooter: &Shooter<'_>,
        value: f64,
        stats: &mut Stats,
    ) -> Result<Vec<Orbit>, OrbitError> {
        let mut out = Vec::new();
        for (k, w) in self.points.windows(2).enumerate() {
            let (a, b) = (
                w[0].orbit.param(self.parameter),
                w[1].orbit.param(self.parameter),
            );
            if (a - value) * (b - value) > 0.0 || (b == value && k + 2 < self.points.len()) {
                continue;
            }
            let start = if (a - value).abs() <= (b - value).abs() {
                &w[0].orbit
            } else {
                &w[1].orbit
            };
            let f = start.forcing.with(self.parameter, value);
            let mut o = shooter.solve(&f, self.parameter, start.phase_rad, start.state, stats)?;
            if !shooter.section_is_free(&o) {
                o = shooter.reanchor(&o, self.parameter, stats)?;
            }
            out.push(o);
        }
        Ok(out)
    }
}

/// A corrected point with the matrix whose kernel is the tangent.
struct Corrected {
    orbit: Orbit,
    /// [M - I | dP/dq] in scaled coordinates.
    jac: SMatrix<f64, 4, 5>,
    iterations: usize,
}

struct Continuer<'s, 'a> {
    shooter: &'s Shooter<'a>,
    settings: ContinuationSettings,
    stats: Stats,
}

impl Continuer<'_, '_> {
    fn p_of(&self, q: f64) -> f64 {
        q * self.settings.param_scale
    }

    fn u_of(&self, o: &Orbit) -> Vector5 {
        let z = o.state.component_div(&self.shooter.scales());
        Vector5::new(
            z[0],
            z[1],
            z[2],
            z[3],
            o.param(self.settings.parameter) / self.settings.param_scale,
        )
    }

    /// Newton on P(z, q) = z with t . (u - anchor) = s, from the predictor anchor + s t, at the
    /// section phase `phase` of the anchor's orbit.
    fn correct(
        &mut self,
        template: &Forcing,
        phase: f64,
        anchor: &Vector5,
        t: &Vector5,
        s: f64,
    ) -> Result<Corrected, OrbitError> {
        let param = self.settings.parameter;
        let sc = self.shooter.scales();
        let cfg = self.shooter.cfg;
        let mut u = anchor + t * s;
        let mut residual = f64::INFINITY;
        for it in 0..=cfg.max_newton {
            let q = u[4];
            let p = self.p_of(q);
            if !(p.is_finite() && p > 0.0) {
                break;
            }
            let forcing = template.with(param, p);
            let z = Vector4::new(u[0], u[1], u[2], u[3]);
            let y: State = z.component_mul(&sc);
            let lin = self
                .shooter
                .linearise(&forcing, param, phase, y, &mut self.stats)
                .map_err(|e| OrbitError::Solver {
                    what: param.label(),
                    param: p,
                    source: e,
                })?;
            let g = (lin.end - y).component_div(&sc);
            let m = self.shooter.scaled_monodromy(&lin.monodromy);
            let gq = lin.dp.component_div(&sc) * self.settings.param_scale;
            let arc = t.dot(&(u - anchor)) - s;
            residual = g.norm() / z.norm().max(1e-300);
            let mut jac = SMatrix::<f64, 4, 5>::zeros();
            jac.fixed_view_mut::<4, 4>(0, 0)
                .copy_from(&(m - Matrix4::identity()));
            jac.set_column(4, &gq);
            let mut big = Matrix5::zeros();
            big.fixed_view_mut::<4, 5>(0, 0).copy_from(&jac);
            big.set_row(4, &t.transpose());
            let lu = big.lu();
            if residual < cfg.residual_tol && arc.abs() <= 1e-9 * (1.0 + s.abs()) {
                // Polish on the plain period map by chord steps (see `Shooter::solve`).
                for _ in 0..CHORD_STEPS {
                    let p = self.p_of(u[4]);
                    let forcing = template.with(param, p);
                    let z = Vector4::new(u[0], u[1], u[2], u[3]);
                    let y: State = z.component_mul(&sc);
                    let (end, summary) = self
                        .shooter
                        .measure(&forcing, phase, y, &mut self.stats)
                        .map_err(|e| OrbitError::Solver {
                            what: param.label(),
                            param: p,
                            source: e,
                        })?;
                    let gp = (end - y).component_div(&sc);
                    let plain = gp.norm() / z.norm().max(1e-300);
                    if plain < cfg.residual_tol {
                        let orbit = self
                            .shooter
                            .orbit(&forcing, param, phase, y, m, plain, it, summary)?;
                        return Ok(Corrected {
                            orbit,
                            jac,
                            iterations: it,
                        });
                    }
                    residual = plain;
                    // The last row keeps the arclength condition.
                    let rhs = Vector5::new(-gp[0], -gp[1], -gp[2], -gp[3], 0.0);
                    let Some(du) = lu.solve(&rhs) else { break };
                    u += du;
                }
                break;
            }
            if it == cfg.max_newton {
                break;
            }
            let rhs = Vector5::new(-g[0], -g[1], -g[2], -g[3], -arc);
            let Some(du) = lu.solve(&rhs) else {
                break;
            };
            u += du;
        }
        Err(OrbitError::NoConvergence {
            what: param.label(),
            param: self.p_of(u[4]),
            iterations: cfg.max_newton,
            residual,
        })
    }

    /// The unit tangent spanning the kernel of `jac`, oriented along `prev`.
    fn tangent(jac: &SMatrix<f64, 4, 5>, prev: &Vector5) -> Option<Vector5> {
        let mut big = Matrix5::zeros();
        big.fixed_view_mut::<4, 5>(0, 0).copy_from(jac);
        big.set_row(4, &prev.transpose());
        let e5 = Vector5::new(0.0, 0.0, 0.0, 0.0, 1.0);
        let t = big.lu().solve(&e5)?;
        let n = t.norm();
        if !(n.is_finite() && n > 0.0) {
            return None;
        }
        let t = t / n;
        Some(if t.dot(prev) < 0.0 { -t } else { t })
    }

    /// The point at arclength `s` from `from` along its tangent, with its tangent.
    fn point_at(&mut self, from: &BranchPoint, s: f64) -> Result<(BranchPoint, usize), OrbitError> {
        let anchor = self.u_of(&from.orbit);
        let c = self.correct(
            &from.orbit.forcing,
            from.orbit.phase_rad,
            &anchor,
            &from.tangent,
            s,
        )?;
        let tangent = Self::tangent(&c.jac, &from.tangent).ok_or(OrbitError::NoConvergence {
            what: self.settings.parameter.label(),
            param: c.orbit.param(self.settings.parameter),
            iterations: c.iterations,
            residual: c.orbit.residual,
        })?;
        Ok((
            BranchPoint {
                orbit: c.orbit,
                tangent,
            },
            c.iterations,
        ))
    }

    /// Moves the section of a point into free flight (when its tangent's parameter component
    /// is large enough to orient the new tangent by it; near a fold the section waits).
    fn reanchor(&mut self, p: BranchPoint) -> Result<BranchPoint, OrbitError> {
        if self.shooter.section_is_free(&p.orbit) || p.param_tangent().abs() < 0.05 {
            return Ok(p);
        }
        let param = self.settings.parameter;
        let o = self.shooter.reanchor(&p.orbit, param, &mut self.stats)?;
        // The kernel at the new section, oriented so that the parameter moves the same way.
        let lin = self
            .shooter
            .linearise(&o.forcing, param, o.phase_rad, o.state, &mut self.stats)
            .map_err(|e| OrbitError::Solver {
                what: param.label(),
                param: o.param(param),
                source: e,
            })?;
        let sc = self.shooter.scales();
        let m = self.shooter.scaled_monodromy(&lin.monodromy);
        let mut jac = SMatrix::<f64, 4, 5>::zeros();
        jac.fixed_view_mut::<4, 4>(0, 0)
            .copy_from(&(m - Matrix4::identity()));
        jac.set_column(4, &(lin.dp.component_div(&sc) * self.settings.param_scale));
        let sign = p.param_tangent().signum();
        let e = Vector5::new(0.0, 0.0, 0.0, 0.0, sign);
        let tangent = Self::tangent(&jac, &e).ok_or(OrbitError::NoConvergence {
            what: param.label(),
            param: o.param(param),
            iterations: 0,
            residual: o.residual,
        })?;
        Ok(BranchPoint { orbit: o, tangent })
    }

    /// Hops over a corner of the branch at an orbit `last` that (nearly) grazes a stop.
    /// From an impacting `last`: shoots at fixed parameter values stepping away from `last` in
    /// the direction opposite to its tangent's parameter component (the non-impacting branch
    /// leaves the corner that way), then the other way, and returns the first non-impacting
    /// orbit found. From a non-impacting `last` (the free-flight branch arriving at grazing,
    /// where a large impact damping makes the impacting branch leave at an angle that no
    /// arclength step converges across): steps on along its tangent and returns the first
    /// impacting orbit. The tangent is oriented along the direction stepped. `None` when
    /// `last` is not near grazing or nothing is found within `max_step`.
    fn corner_hop(&mut self, last: &BranchPoint, max_step: f64) -> Option<BranchPoint> {
        let gaps = Gaps::of(self.shooter.base);
        let near = test_grazing(last, gaps).abs() <= GRAZING_NEAR * gaps.smallest();
        if !near {
            return None;
        }
        let param = self.settings.parameter;
        let p0 = last.orbit.param(param);
        let leaving_contact = last.orbit.is_impacting();
        let ahead = last.param_tangent().signum();
        let dirs: &[f64] = if leaving_contact {
            &[-ahead, ahead]
        } else {
            &[ahead]
        };
        for &dir in dirs {
            let mut step = 1e-4 * max_step;
            while step <= max_step {
                let f = last.orbit.forcing.with(param, p0 + dir * step);
                let solved = self.shooter.solve(
                    &f,
                    param,
                    last.orbit.phase_rad,
                    last.orbit.state,
                    &mut self.stats,
                );
                if let Ok(o) = solved {
                    if o.is_impacting() != leaving_contact {
                        let sc = self.shooter.scales();
                        let lin = self
                            .shooter
                            .linearise(&o.forcing, param, o.phase_rad, o.state, &mut self.stats)
                            .ok()?;
                        let m = self.shooter.scaled_monodromy(&lin.monodromy);
                        let mut jac = SMatrix::<f64, 4, 5>::zeros();
                        jac.fixed_view_mut::<4, 4>(0, 0)
                            .copy_from(&(m - Matrix4::identity()));
                        jac.set_column(4, &(lin.dp.component_div(&sc) * self.settings.param_scale));
                        let e = Vector5::new(0.0, 0.0, 0.0, 0.0, dir);
                        let tangent = Self::tangent(&jac, &e)?;
                        return Some(BranchPoint { orbit: o, tangent });
                    }
                }
                step *= 4.0;
            }
        }
        None
    }

    /// Locates a sign change of `test` between `a` (index `k`) and `b`, at arclength `ds`.
    #[allow(clippy::too_many_arguments)]
    fn locate(
        &mut self,
        kind: EventKind,
        k: usize,
        a: &BranchPoint,
        b: &BranchPoint,
        ds: f64,
        test: fn(&BranchPoint, Gaps) -> f64,
        gaps: Gaps,
    ) -> Result<Event, OrbitError> {
        let tol_s = self.settings.locate_tol / self.settings.param_scale;
        let opts = RootOptions {
            f_tol: None,
            x_tol_abs: tol_s,
            x_tol_rel: 0.0,
            max_iter: 60,
        };
        let (fa, fb) = (test(a, gaps), test(b, gaps));
        // The best sample so far, kept outside the root finder: a corrector that fails close to
        // the event (at a branch point the bordered Jacobian is singular) ends the search with
        // the bracket reached, not with an error.
        let mut best = if fa.abs() <= fb.abs() {
            (0.0, fa, a.clone())
        } else {
            (ds, fb, b.clone())
        };
        let lo = Sample::new(0.0, fa, ());
        let hi = Sample::new(ds, fb, ());
        let root = illinois(
            |s| -> Result<(f64, ()), OrbitError> {
                let (p, _) = self.point_at(a, s)?;
                let v = test(&p, gaps);
                if v.abs() < best.1.abs() {
                    best = (s, v, p);
                }
                Ok((v, ()))
            },
            lo,
            hi,
            &opts,
        );
        if let Err(crate::num::roots::RootError::NotBracketed { .. }) = root {
            unreachable!("the ends bracket a sign change by construction")
        }
        let (s_best, _, best) = best;
        Ok(Event {
            kind,
            param: best.orbit.param(self.settings.parameter),
            orbit: best.orbit,
            after_point: k,
            s: s_best,
            multiplier_crossing: false,
            at_grazing: false,
            stable_before: a.orbit.is_stable(),
            stable_after: b.orbit.is_stable(),
        })
    }

    /// Locates a grazing between `a` and `b` on the branch of the same device with the stops
    /// removed, followed from whichever end does not touch a stop: that branch is smooth where
    /// the real one has the grazing singularity, and the orbit at which its largest |x|
    /// reaches x_max is exactly the grazing orbit (it exerts no contact force).
    fn locate_grazing(
        &mut self,
        k: usize,
        a: &BranchPoint,
        b: &BranchPoint,
        ds: f64,
    ) -> Result<Event, OrbitError> {
        let gaps = Gaps::of(self.shooter.base);
        let free_model = self.shooter.base.without_stops();
        let free = Shooter::with_scales(&free_model, self.shooter.cfg, self.shooter.scales());
        let mut c = Continuer {
            shooter: &free,
            settings: self.settings,
            stats: Stats::default(),
        };
        let from_a = test_grazing(a, gaps) <= 0.0;
        // From the non-touching end towards the other one; from `b` the tangent inherited
        // from `a` may point either way (at a corner it points back into the corner), so both
        // directions are tried.
        let candidates: Vec<BranchPoint> = if from_a {
            vec![a.clone()]
        } else {
            vec![
                BranchPoint {
                    orbit: b.orbit.clone(),
                    tangent: -b.tangent,
                },
                b.clone(),
            ]
        };
        // Bracket the crossing on the stop-free branch (it differs from the real one past the
        // grazing, so the crossing may lie a little beyond `ds`).
        let mut found = None;
        'dirs: for anchor in candidates {
            let mut hi = ds;
            for _ in 0..4 {
                if let Ok((p, _)) = c.point_at(&anchor, hi) {
                    if test_grazing(&p, gaps) > 0.0 {
                        found = Some((anchor, p, hi));
                        break 'dirs;
                    }
                }
                hi *= 2.0;
            }
        }
        let Some((anchor, end, hi)) = found else {
            return Err(OrbitError::NoConvergence {
                what: self.settings.parameter.label(),
                param: b.orbit.param(self.settings.parameter),
                iterations: 0,
                residual: b.orbit.residual,
            });
        };
        let mut e = c.locate(EventKind::Grazing, k, &anchor, &end, hi, test_grazing, gaps)?;
        self.stats += c.stats;
        if !from_a {
            e.s = ds - e.s.min(ds);
        }
        e.stable_before = a.orbit.is_stable();
        e.stable_after = b.orbit.is_stable();
        Ok(e)
    }

    // ANCHOR: events
    /// The events between points `k` and `k + 1` (at arclength `ds` along point k's
    /// tangent). `b` may have its tangent reversed: where the branch leaves contact at a
    /// corner (the impacting branch meets the non-impacting one at the grazing orbit and the
    /// parameter turns there), the tangent inherited from `a` points back into the corner, and
    /// the branch goes on away from the grazing orbit.
    fn events_between(
        &mut self,
        k: usize,
        a: &BranchPoint,
        b: &mut BranchPoint,
        ds: f64,
    ) -> Result<Vec<Event>, OrbitError> {
        let gaps = Gaps::of(self.shooter.base);
        let mut out = Vec::new();
        let graze = (test_grazing(a, gaps) > 0.0) != (test_grazing(b, gaps) > 0.0);
        let mut corner = false;
        if graze {
            // Located on the stop-free branch; a failure leaves the grazing unlocated (the
            // branch itself is fine) rather than ending the continuation.
            if let Ok(g) = self.locate_grazing(k, a, b, ds) {
                if a.orbit.is_impacting() && !b.orbit.is_impacting() {
                    let away = self.u_of(&b.orbit) - self.u_of(&g.orbit);
                    if b.tangent.dot(&away) < 0.0 {
                        b.tangent = -b.tangent;
                    }
                    corner = (a.param_tangent() > 0.0) != (b.param_tangent() > 0.0);
                }
                if corner {
                    let mut fold = g.clone();
                    fold.kind = EventKind::Fold;
                    fold.multiplier_crossing =
                        (test_plus_one(a, gaps) > 0.0) != (test_plus_one(b, gaps) > 0.0);
                    fold.at_grazing = true;
                    out.push(fold);
                }
                out.push(g);
            }
        }
        let changes = |f: fn(&BranchPoint, Gaps) -> f64, b: &BranchPoint| {
            (f(a, gaps) > 0.0) != (f(b, gaps) > 0.0)
        };
        let turn = changes(test_fold, b);
        let plus1 = changes(test_plus_one, b);
        let minus1 = changes(test_minus_one, b);
        let torus = a.orbit.unstable_count() != b.orbit.unstable_count() && !plus1 && !minus1;
        // At a corner the changes of stability belong to the corner (the fold above).
        if !corner {
            let b = &*b;
            if turn {
                let mut e = self.locate(EventKind::Fold, k, a, b, ds, test_fold, gaps)?;
                e.multiplier_crossing = plus1;
                e.at_grazing = graze;
                out.push(e);
            } else if plus1 {
                out.push(self.locate(EventKind::BranchPoint, k, a, b, ds, test_plus_one, gaps)?);
            }
            if minus1 {
                out.push(self.locate(
                    EventKind::PeriodDoubling,
                    k,
                    a,
                    b,
                    ds,
                    test_minus_one,
                    gaps,
                )?);
            }
            if torus {
                out.push(self.locate(EventKind::Torus, k, a, b, ds, test_torus, gaps)?);
            }
        }
        out.sort_by(|x, y| x.s.total_cmp(&y.s));
        Ok(out)
    }
    // ANCHOR_END: events
}

fn test_fold(p: &BranchPoint, _: Gaps) -> f64 {
    p.param_tangent()
}
fn test_plus_one(p: &BranchPoint, _: Gaps) -> f64 {
    p.orbit.det_minus_one()
}
fn test_minus_one(p: &BranchPoint, _: Gaps) -> f64 {
    p.orbit.det_plus_one()
}
fn test_torus(p: &BranchPoint, _: Gaps) -> f64 {
    p.orbit.max_multiplier_abs() - 1.0
}
fn test_grazing(p: &BranchPoint, gaps: Gaps) -> f64 {
    let s = &p.orbit.summary;
    (s.x_upper_m - gaps.upper).max(-s.x_lower_m - gaps.lower)
}

/// The first orbit of a branch: Newton at `forcing` from `guess` (the state at drive phase
/// zero), or, if that fails, from the state after a transient of `transient_periods` periods
/// from `guess`; its section is then moved into free flight.
pub fn first_orbit(
    shooter: &Shooter<'_>,
    forcing: &Forcing,
    param: Parameter,
    guess: State,
    transient_periods: usize,
    stats: &mut Stats,
) -> Result<Orbit, OrbitError> {
    let o = match shooter.solve(forcing, param, 0.0, guess, stats) {
        Ok(o) => o,
        Err(_) => {
            let (y, _, st) = shooter
                .flow(
                    forcing,
                    0.0,
                    guess,
                    transient_periods as f64 * forcing.period_s(),
                    |_, _| {},
                )
                .map_err(|e| OrbitError::Solver {
                    what: param.label(),
                    param: forcing.get(param),
                    source: e,
                })?;
            *stats += st;
            shooter.solve(forcing, param, 0.0, y, stats)?
        }
    };
    if shooter.section_is_free(&o) {
        Ok(o)
    } else {
        shooter.reanchor(&o, param, stats)
    }
}

/// Continues the branch of periodic orbits of `base` through `first` (an orbit at the
/// settings' start value) until the parameter passes `settings.stop`; `on_point(p)` is called
/// with the parameter of every accepted point.
pub fn continue_branch(
    base: &Harvester<Sine>,
    first: Orbit,
    settings: &ContinuationSettings,
    mut on_point: impl FnMut(f64),
) -> Result<Branch, OrbitError> {
    settings.validate()?;
    let shooter = Shooter::new(base, settings.shooting);
    let mut c = Continuer {
        shooter: &shooter,
        settings: *settings,
        stats: Stats::default(),
    };
    let param = settings.parameter;
    let dir = settings.direction();
    // The first tangent: the kernel oriented along the parameter's direction.
    let start_dir = Vector5::new(0.0, 0.0, 0.0, 0.0, dir);
    let lin = shooter
        .linearise(
            &first.forcing,
            param,
            first.phase_rad,
            first.state,
            &mut c.stats,
        )
        .map_err(|e| OrbitError::Solver {
            what: param.label(),
            param: first.param(param),
            source: e,
        })?;
    let sc = shooter.scales();
    let mut jac = SMatrix::<f64, 4, 5>::zeros();
    jac.fixed_view_mut::<4, 4>(0, 0)
        .copy_from(&(shooter.scaled_monodromy(&lin.monodromy) - Matrix4::identity()));
    jac.set_column(4, &(lin.dp.component_div(&sc) * settings.param_scale));
    let tangent = Continuer::tangent(&jac, &start_dir).ok_or(OrbitError::Invalid(
        "the first orbit is singular (a fold or branch point): start elsewhere".into(),
    ))?;
    on_point(first.param(param));
    let mut points = vec![BranchPoint {
        orbit: first,
        tangent,
    }];
    let mut events = Vec::new();
    let mut ds = settings.ds_init;
    let mut rejected = 0;
    let cos_max = settings.max_turn_rad.cos();
    loop {
        let last = points.last().expect("a branch has a point").clone();
        let p_last = last.orbit.param(param);
        if settings.beyond_stop(p_last) {
            break;
        }
        if points.len() >= settings.max_points {
            return Err(OrbitError::TooManyPoints {
                what: param.label(),
                last_param: p_last,
                points: settings.max_points,
            });
        }
        let attempt = c.point_at(&last, ds);
        let accepted = match attempt {
            Ok((p, its)) => {
                let dp = (p.orbit.param(param) - p_last).abs();
                // The corrector must stay near its predictor: a correction much longer than
                // the step has left the branch (near a grazing corner it can land on another
                // branch that passes close by).
                let predicted = c.u_of(&last.orbit) + last.tangent * ds;
                let moved = (c.u_of(&p.orbit) - predicted).norm();
                // The largest multiplier moves continuously along a branch: a step that
                // changes it by more than a factor MAX_MULTIPLIER_RATIO is refined (near a
                // grazing corner the corrector can land on a neighbouring branch that is close
                // in state but differs in stability).
                let (ma, mb) = (
                    last.orbit.max_multiplier_abs(),
                    p.orbit.max_multiplier_abs(),
                );
                let jumped = (mb / ma).max(ma / mb) > MAX_MULTIPLIER_RATIO;
                // A step that starts or stops touching the stops is kept short: a long one can
                // leave an impacting branch for the non-impacting one across a narrow loop of
                // the branch (a fold just past the grazing) without passing the fold.
                let crossed = p.orbit.is_impacting() != last.orbit.is_impacting();
                let long_crossing = crossed && dp > GRAZING_STEP * settings.max_param_step;
                // A free-flight branch that turns back at grazing with no change of stability
                // has not folded (a smooth fold moves a multiplier through +1): the corrector
                // has slid back along the branch it came on, unable to step across a corner
                // (an impacting branch that leaves at an angle, as with a large impact
                // damping). Refined, and hopped over below when the step is exhausted.
                let gaps = Gaps::of(c.shooter.base);
                let graze_tol = GRAZING_NEAR * gaps.smallest();
                let slid_back = !crossed
                    && !last.orbit.is_impacting()
                    && test_grazing(&last, gaps).abs() <= graze_tol
                    && (p.param_tangent() > 0.0) != (last.param_tangent() > 0.0)
                    && p.orbit.is_stable() == last.orbit.is_stable()
                    && (test_plus_one(&p, gaps) > 0.0) == (test_plus_one(&last, gaps) > 0.0);
                if p.tangent.dot(&last.tangent) < cos_max
                    || dp > settings.max_param_step
                    || moved > MAX_CORRECTION * ds
                    || jumped
                    || long_crossing
                    || slid_back
                {
                    None
                } else {
                    Some((p, its))
                }
            }
            Err(_) => None,
        };
        let Some((p, its)) = accepted else {
            rejected += 1;
            ds *= 0.5;
            if ds < settings.ds_min {
                // At a corner of the branch (an impacting orbit grazing a stop, where the
                // impacting branch meets the non-impacting one at an angle) no arclength step
                // along the old tangent converges: hop over the corner onto the other branch.
                if let Some(p) = c.corner_hop(&last, settings.max_param_step) {
                    let k = points.len() - 1;
                    let mut p = p;
                    // Events are bracketed over the hop's own length, not the exhausted step.
                    let hop = (c.u_of(&p.orbit) - c.u_of(&last.orbit)).norm();
                    let found = c.events_between(k, &last, &mut p, hop)?;
                    events.extend(found);
                    on_point(p.orbit.param(param));
                    points.push(p);
                    ds = settings.ds_init;
                    continue;
                }
                return Err(OrbitError::Stalled {
                    what: param.label(),
                    last_param: p_last,
                    ds_min: settings.ds_min,
                });
            }
            continue;
        };
        let k = points.len() - 1;
        let mut p = p;
        let found = c.events_between(k, &last, &mut p, ds)?;
        events.extend(found);
        on_point(p.orbit.param(param));
        // A failed move of the section keeps the point at its old one (still a valid orbit).
        let p = match c.reanchor(p.clone()) {
            Ok(q) => q,
            Err(_) => p,
        };
        points.push(p);
        if its <= 2 {
            ds = (ds * 1.5).min(settings.ds_max);
        } else if its >= 5 {
            ds = (ds * 0.6).max(settings.ds_min);
        }
    }
    Ok(Branch {
        parameter: param,
        points,
        events,
        stats: c.stats,
        rejected_steps: rejected,
    })
}

/// The branch of periodic orbits of `device` continued by `settings` from the drive `start`
/// (whose frequency or amplitude is the settings' start value), beginning with the orbit
/// reached from rest (shooting, after up to `transient_periods` periods of transient if Newton
/// does not converge from rest); `on_point(p)` is called with the parameter of every accepted
/// point.
pub fn branch_from_rest(
    device: &crate::device::Device,
    start: Forcing,
    settings: &ContinuationSettings,
    transient_periods: usize,
    on_point: impl FnMut(f64),
) -> Result<Branch, OrbitError> {
    settings.validate()?;
    let h = Harvester::new(device, Sine::from_rms_g(start.accel_rms_g, start.freq_hz));
    let shooter = Shooter::new(&h, settings.shooting);
    let mut stats = Stats::default();
    let first = first_orbit(
        &shooter,
        &start,
        settings.parameter,
        h.rest_state(),
        transient_periods,
        &mut stats,
    )?;
    let mut branch = continue_branch(&h, first, settings, on_point)?;
    branch.stats += stats;
    Ok(branch)
}

/// The branch of periodic orbits of `device` driven at `accel_rms_g` (g rms), continued in
/// frequency from `from_hz` to `to_hz` with parameter steps of at most `max_step_hz`
/// ([`ContinuationSettings::frequency`]), from the orbit reached from rest at `from_hz`
/// ([`branch_from_rest`], 200 periods of transient at most).
///
/// ```
/// use endstop::device::Device;
/// use endstop::study::continuation::frequency_branch;
///
/// let text = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/prototype1.toml"));
/// let device = Device::from_toml_str(text, "prototype1.toml")?;
/// // Far below the stops (0.02 g rms): one stable branch, no events.
/// let branch = frequency_branch(&device, 0.02, 1000.0, 1100.0, 50.0, |_| {})?;
/// assert!(branch.params().last().unwrap() >= 1100.0);
/// assert!(branch.points.iter().all(|p| p.orbit.is_stable()));
/// assert!(branch.events.is_empty());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn frequency_branch(
    device: &crate::device::Device,
    accel_rms_g: f64,
    from_hz: f64,
    to_hz: f64,
    max_step_hz: f64,
    on_point: impl FnMut(f64),
) -> Result<Branch, OrbitError> {
    let start = Forcing {
        freq_hz: from_hz,
        accel_rms_g,
    };
    let settings = ContinuationSettings::frequency(from_hz, to_hz, max_step_hz);
    branch_from_rest(device, start, &settings, 200, on_point)
}
