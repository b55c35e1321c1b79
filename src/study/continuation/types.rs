//! What a continuation is given and what it gives: its settings, the points and events of a
//! branch, and why a step was rejected.

use nalgebra::DVector;

use crate::model::Model;
use crate::ode::Stats;
use crate::study::orbit::{Orbit, OrbitError, Parameter, Shooter, ShootingOptions};

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
    pub shooting: ShootingOptions,
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
            shooting: ShootingOptions::default(),
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
            shooting: ShootingOptions::default(),
        }
    }

    /// The same with half the integrator tolerance.
    pub fn halved(&self) -> Self {
        Self {
            shooting: self.shooting.halved(),
            ..*self
        }
    }

    pub(super) fn direction(&self) -> f64 {
        if self.stop >= self.start {
            1.0
        } else {
            -1.0
        }
    }

    /// True once the branch has left the range between `start` and `stop` on either side (a
    /// branch that turns back at a fold may run out below its start).
    pub(super) fn beyond_stop(&self, p: f64) -> bool {
        (p - self.stop) * self.direction() > 0.0 || (self.start - p) * self.direction() > 0.0
    }

    pub(super) fn validate(&self) -> Result<(), OrbitError> {
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
    /// Unit tangent (dz, dq) in scaled coordinates, oriented along the branch: the state's
    /// components, then the parameter's.
    pub tangent: DVector<f64>,
}

impl BranchPoint {
    /// The parameter component of the tangent (its sign changes at a fold).
    pub fn param_tangent(&self) -> f64 {
        self.tangent[self.tangent.len() - 1]
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
    /// For a grazing at which a rigid contact gains or loses a strike per period while the
    /// set of contacts touched stays the same: that contact (its index in
    /// [`crate::model::Model::contacts`]).
    pub contact: Option<usize>,
    /// For a grazing of a contact that gains or loses a strike per period: the lesser number
    /// of that contact's strikes a period on its two sides (the grazing lies between that
    /// number and one more), which tells apart two such grazings a little apart.
    pub strikes: Option<u32>,
}

impl Event {
    /// Label for tables: the kind, and for a fold where the orbit grazes a stop (a corner of
    /// the branch) that it is at grazing.
    pub fn label(&self) -> String {
        if let (EventKind::Grazing, Some(k)) = (self.kind, self.contact) {
            match self.strikes {
                Some(n) => format!("grazing of contact {k} ({n} to {} strikes a period)", n + 1),
                None => format!("grazing of contact {k} (a strike more or less per period)"),
            }
        } else if self.at_grazing {
            format!("{} (at grazing)", self.kind.label())
        } else {
            self.kind.label().to_string()
        }
    }
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
    /// Why each rejected step was rejected, in branch order (a rejected step is halved and
    /// tried again).
    pub rejections: Vec<Rejection>,
}

impl Branch {
    /// The number of rejected continuation steps.
    pub fn rejected_steps(&self) -> usize {
        self.rejections.len()
    }

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
    pub fn orbits_at<M: Model<N>, const N: usize>(
        &self,
        shooter: &Shooter<'_, M, N>,
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
            let mut o =
                shooter.solve(&f, self.parameter, start.phase_rad, start.state_n(), stats)?;
            if !shooter.section_is_free(&o) {
                o = shooter.reanchor(&o, self.parameter, stats)?;
            }
            out.push(o);
        }
        Ok(out)
    }
}

/// Why a corrected step is not accepted onto the branch (the step is then halved and tried
/// again; see [`ContinuationSettings`] for the limits).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Rejection {
    /// Newton did not converge, or the kernel of the corrected point gives no tangent.
    Corrector,
    /// The tangent turned by more than [`ContinuationSettings::max_turn_rad`].
    Turn,
    /// The parameter moved by more than [`ContinuationSettings::max_param_step`].
    ParamStep,
    /// The corrected point lies far from its predictor (more than half a step): it has left
    /// the branch, e.g. for another branch passing close by near a grazing corner.
    LeftPredictor,
    /// The largest multiplier's modulus changed by more than a factor 2: a neighbouring
    /// branch close in state but of another stability.
    MultiplierJump,
    /// The step starts or stops touching the stops over more than a hundredth of
    /// [`ContinuationSettings::max_param_step`]: a long one can cross a narrow loop of the
    /// branch (a fold just past the grazing) without passing the fold.
    LongCrossing,
    /// A free-flight branch turned back at grazing with no change of stability: the
    /// corrector slid back along the branch it came on instead of stepping across a corner.
    SlidBack,
}

impl Rejection {
    /// Label for tables.
    pub fn label(self) -> &'static str {
        match self {
            Rejection::Corrector => "corrector failed",
            Rejection::Turn => "tangent turned",
            Rejection::ParamStep => "parameter step",
            Rejection::LeftPredictor => "left the predictor",
            Rejection::MultiplierJump => "multiplier jump",
            Rejection::LongCrossing => "long grazing crossing",
            Rejection::SlidBack => "slid back at grazing",
        }
    }
}
