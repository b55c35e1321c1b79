//! The response past the end of a branch at a grazing that adds a strike, where no orbit past
//! the grazing is found from the branch's last orbit (and past any other point where a branch's
//! step falls below its minimum: the response goes on the same way, and the end is kept with
//! what it was, [`Ended`]).
//!
//! Past such a grazing of a rigid contact the orbit with the added strike may not exist at
//! all: the grazing bifurcation of an impacting orbit can lead at once to orbits of several
//! periods or to a response that repeats no period (Nordmark, J. Sound Vib. 145, 1991; di
//! Bernardo et al., *Piecewise-smooth Dynamical Systems*, 2008, chapter 4), and any orbit
//! there lies far (in the period map's own metric) from the last orbit before the grazing.
//! The response therefore resumes as a stepped sine does: the parameter is stepped past the
//! branch's farthest point by a given step, and at each value the state settles for a
//! transient of some drive periods (from the last orbit's state, then from the state the
//! previous value left). The state after the transient seeds Newton's method on the maps over
//! one to [`super::periods::MAX_PERIODS`] drive periods ([`Continuer::stable_orbit_from`]);
//! the first stable orbit found (of its least number of periods) begins a new branch, which
//! is continued on its own map ([`super::follow`]) and may end at such a grazing in its turn.
//! Where none is found, the response there is the state's over some drive periods, a point
//! measured and not continued ([`SteppedPoint`]).

use nalgebra::{DVector, SVector};

use crate::model::Model;
use crate::ode::Stats;
use crate::progress::Progress;
use crate::study::orbit::{Forcing, Orbit, OrbitError, OrbitSummary, Parameter, Shooter};

use super::corrector::Continuer;
use super::{follow, Branch, ContinuationSettings};

/// How the response resumes where a branch ends at a grazing that adds a strike.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ResumeSettings {
    /// The parameter's step between the values tried past the end (Hz or g): the stepped
    /// sweep's step.
    pub step: f64,
    /// Drive periods of transient at each value tried, before the maps are seeded.
    pub transient_periods: usize,
    /// Drive periods over which a point without a periodic orbit is measured.
    pub measure_periods: usize,
}

impl ResumeSettings {
    fn validate(&self) -> Result<(), OrbitError> {
        if self.step.is_finite()
            && self.step > 0.0
            && self.transient_periods > 0
            && self.measure_periods > 0
        {
            Ok(())
        } else {
            Err(OrbitError::Invalid(format!(
                "resume settings: {self:?} (a finite positive step, at least one period of \
                 transient and of measurement)"
            )))
        }
    }
}

/// A value of the parameter at which no stable periodic orbit of one to four (the
/// continuation's largest period count) drive periods is found from the state after the transient:
/// the response over [`SteppedPoint::periods`] drive periods from that state, as a stepped
/// sine measures it (not an orbit, and not continued).
#[derive(Debug, Clone, PartialEq)]
pub struct SteppedPoint {
    /// The drive.
    pub forcing: Forcing,
    /// Drive phase at the start of the measurement (rad).
    pub phase_rad: f64,
    /// The state at the start of the measurement.
    pub state: DVector<f64>,
    /// Drive periods measured.
    pub periods: usize,
    /// The measures over those periods (impacts counted over all of them).
    pub summary: OrbitSummary,
}

impl SteppedPoint {
    /// Impacts per drive period over the measurement.
    pub fn impacts_per_period(&self) -> f64 {
        f64::from(self.summary.impacts) / self.periods as f64
    }
}

/// A branch of a response that ends short of the range, after which the response resumes.
#[derive(Debug, Clone, PartialEq)]
pub struct Ended {
    /// The branch's index in [`Response::pieces`].
    pub piece: usize,
    /// Why it ends: [`OrbitError::Stalled`] or [`OrbitError::OtherPeriod`].
    pub error: OrbitError,
    /// It ends at a grazing that adds a strike of a rigid contact (else where the step fell
    /// below its minimum elsewhere).
    pub at_strike: bool,
}

/// A piece of a response, in the order of the parameter.
#[derive(Debug, Clone, PartialEq)]
pub enum Piece {
    /// A continued branch of periodic orbits (of [`Orbit::periods`] drive periods each).
    Continued(Branch),
    /// Consecutive values of the parameter without a stable periodic orbit found.
    Stepped(Vec<SteppedPoint>),
}

/// The response over a parameter range: the branch continued from its first orbit and, where
/// a branch ends at a grazing that adds a strike, the stepped points and the branches found
/// past it (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Response {
    /// The parameter varied.
    pub parameter: Parameter,
    /// The pieces in order.
    pub pieces: Vec<Piece>,
    /// Where a branch ends short of the range and the response resumed past it, in order.
    pub ends: Vec<Ended>,
    /// Integrator counters of the transients, seeds and measurements (each branch keeps its
    /// own).
    pub stats: Stats,
}

impl Response {
    /// The continued branches in order.
    pub fn branches(&self) -> impl Iterator<Item = &Branch> {
        self.pieces.iter().filter_map(|p| match p {
            Piece::Continued(b) => Some(b),
            Piece::Stepped(_) => None,
        })
    }

    /// The points not continued, in order.
    pub fn stepped(&self) -> impl Iterator<Item = &SteppedPoint> {
        self.pieces
            .iter()
            .filter_map(|p| match p {
                Piece::Stepped(s) => Some(s),
                Piece::Continued(_) => None,
            })
            .flatten()
    }

    /// The branches found from a transient (every continued branch after the first): the
    /// least number of drive periods of their orbits and the parameter value each is found
    /// at.
    pub fn found(&self) -> Vec<(usize, f64)> {
        self.branches()
            .skip(1)
            .map(|b| {
                let o = &b.points[0].orbit;
                (o.periods, o.param(b.parameter))
            })
            .collect()
    }

    /// The farthest parameter value reached, by a branch or a stepped point, in the direction
    /// `dir` (+1 or -1).
    pub fn reach(&self, dir: f64) -> f64 {
        let branch = self.branches().flat_map(|b| b.params());
        let stepped = self.stepped().map(|s| s.forcing.get(self.parameter));
        branch
            .chain(stepped)
            .fold(f64::NEG_INFINITY, |m, p| m.max(dir * p))
            * dir
    }
}

/// The label of a branch found from a transient.
pub fn found_label(periods: usize, param: f64, parameter: Parameter) -> String {
    let unit = match parameter {
        Parameter::Frequency => "Hz",
        Parameter::Amplitude => "g",
    };
    format!("period-{periods} branch found at {param:.4} {unit}")
}

/// The response of `base` over the settings' range from `first` (an orbit at the settings'
/// start value): the branch continued from it ([`super::continue_branch`]), resumed as
/// `resume` says (see the module docs) past every point where a branch ends short of the
/// range because its step falls below the minimum (at a grazing that adds a strike, or
/// elsewhere) or only an orbit of several periods is found past such a grazing. Any other
/// error of a branch is returned as the error.
pub fn response_of_model<M: Model<N> + Clone, const N: usize>(
    base: &M,
    first: Orbit,
    settings: &ContinuationSettings,
    resume: &ResumeSettings,
    progress: &dyn Progress,
) -> Result<Response, OrbitError> {
    settings.validate()?;
    resume.validate()?;
    let param = settings.parameter;
    let dir = settings.direction();
    let shooter = Shooter::new(base, settings.shooting);
    let mut c = Continuer {
        shooter: &shooter,
        settings: *settings,
        periods: 1,
        stats: Stats::default(),
    };
    let mut out = Response {
        parameter: param,
        pieces: Vec::new(),
        ends: Vec::new(),
        stats: Stats::default(),
    };
    let mut next = Some(first);
    while let Some(orbit) = next.take() {
        let from = ContinuationSettings {
            start: orbit.param(param),
            ..*settings
        };
        let followed = follow(base, orbit, &from, progress, |_| false)?;
        let branch = followed.branch;
        if let Some(end) = followed.end {
            let resumable = matches!(
                end.error,
                OrbitError::Stalled { .. } | OrbitError::OtherPeriod { .. }
            );
            if !resumable {
                return Err(end.error);
            }
            out.ends.push(Ended {
                piece: out.pieces.len(),
                error: end.error,
                at_strike: end.at_strike,
            });
        }
        // The farthest point reached: where the branch ends at a strike, or where it turns
        // back below its start.
        let far = branch
            .points
            .iter()
            .max_by(|a, b| (dir * a.orbit.param(param)).total_cmp(&(dir * b.orbit.param(param))))
            .expect("a branch has a point")
            .orbit
            .clone();
        out.pieces.push(Piece::Continued(branch));
        if settings.beyond_stop(far.param(param)) {
            break;
        }
        let mut stepped = Vec::new();
        let mut p = far.param(param) + dir * resume.step;
        let mut y: SVector<f64, N> = far.state_n();
        let phase = far.phase_rad;
        while (p - settings.stop) * dir < 0.0 {
            let forcing = far.forcing.with(param, p);
            y = c.settle(&forcing, phase, y, resume.transient_periods)?;
            if let Some(o) = c.stable_orbit_from(&forcing, phase, y) {
                next = Some(o);
                break;
            }
            let (end, summary) = shooter
                .measure_periods(&forcing, phase, y, resume.measure_periods, &mut c.stats)
                .map_err(|e| shooter.solver_err(param, &forcing, e))?;
            progress.fraction(crate::progress::share(settings.start, settings.stop, p));
            stepped.push(SteppedPoint {
                forcing,
                phase_rad: phase,
                state: DVector::from_column_slice(y.as_slice()),
                periods: resume.measure_periods,
                summary,
            });
            y = end;
            p += dir * resume.step;
        }
        if !stepped.is_empty() {
            out.pieces.push(Piece::Stepped(stepped));
        }
    }
    out.stats += c.stats;
    Ok(out)
}

impl<M: Model<N>, const N: usize> Continuer<'_, '_, M, N> {
    /// The state after `periods` drive periods from `y` at drive phase `phase_rad`.
    pub(super) fn settle(
        &mut self,
        forcing: &Forcing,
        phase_rad: f64,
        y: SVector<f64, N>,
        periods: usize,
    ) -> Result<SVector<f64, N>, OrbitError> {
        let duration_s = periods as f64 * forcing.period_s();
        let (end, _, st) = self
            .shooter
            .advance(forcing, phase_rad, y, duration_s)
            .map_err(|e| self.shooter.solver_err(self.settings.parameter, forcing, e))?;
        self.stats += st;
        Ok(end)
    }
}
