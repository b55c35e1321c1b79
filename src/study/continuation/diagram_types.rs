//! The bifurcation diagram's parts: its orbits ([`DiagramPoint`], made from an orbit of the
//! period map by [`orbit_point`]), its labelled branches with their ends, and the events at
//! which branches meet or change stability. [`super::diagram`] builds a diagram of any device
//! from them, and [`super::impacting`] the diagram of a device whose stops are rigid.

use nalgebra::{Complex, DVector};

use crate::model::Model;
use crate::ode::Stats;
use crate::study::orbit::{Forcing, Orbit, OrbitError, OrbitSummary, Parameter, Shooter};

use super::impacting::bvp::{side_stops, ImpactSequence};

/// One periodic orbit of a branch of the diagram.
#[derive(Debug, Clone, PartialEq)]
pub struct DiagramPoint {
    /// The drive.
    pub forcing: Forcing,
    /// Drive periods of the orbit.
    pub periods: u32,
    /// Floquet multipliers of the orbit (of its whole period), largest modulus first; not
    /// finite at a grazing impact.
    pub multipliers: Vec<Complex<f64>>,
    /// Multipliers of the half-period map of a symmetric orbit.
    pub half_multipliers: Option<Vec<Complex<f64>>>,
    /// Whole-orbit measures (RMS voltages over the orbit's period; impacts over the whole
    /// orbit).
    pub summary: OrbitSummary,
    /// The drive phase (rad) and state at the orbit's first upward zero crossing of x.
    pub section: Option<(f64, DVector<f64>)>,
    /// The speed of each impact (m/s), in the order of the orbit's impact sequence.
    pub impact_speeds_m_s: Vec<f64>,
    /// How far the orbit's free flights stay from the stops (m): the smallest distance from
    /// a stop of an extremum of x between impacts (for an orbit without impacts, of its
    /// largest excursion to either side); zero at a grazing, negative past a stop.
    pub clearance_m: f64,
    /// True for a symmetric orbit (y(t + T/2) = S y(t)).
    pub symmetric: bool,
    /// The scaled residual of the orbit's equations.
    pub residual: f64,
    /// The mean over the orbit's periods of its states at drive phase zero (how two orbits
    /// are told apart, whichever period is taken as the first).
    pub fingerprint: DVector<f64>,
}

impl DiagramPoint {
    /// Largest modulus of the multipliers off the neutral band
    /// ([`crate::study::orbit::is_neutral`]).
    pub fn max_multiplier_abs(&self) -> f64 {
        crate::study::orbit::leading_abs(&self.multipliers)
    }

    /// True when every multiplier off the neutral band lies inside the unit circle.
    pub fn is_stable(&self) -> bool {
        self.max_multiplier_abs() < 1.0
    }

    /// Largest modulus of the half-period map's multipliers, for a symmetric orbit.
    pub fn half_multiplier_max_abs(&self) -> Option<f64> {
        self.half_multipliers.as_ref().map(|h| h[0].norm())
    }

    /// The phase by which the displacement lags the drive (degrees, in (-90, 270]): the
    /// drive's phase at the first upward zero crossing of x.
    pub fn phase_lag_deg(&self) -> Option<f64> {
        let lag = self.section.as_ref()?.0.to_degrees();
        Some(if lag > 270.0 { lag - 360.0 } else { lag })
    }
}

/// What a branch of the diagram is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum BranchKind {
    /// Orbits that touch no stop.
    NonImpacting,
    /// Orbits with this impact sequence.
    Impacting(ImpactSequence),
    /// One branch continued on the period map through grazing (a device with a compliant
    /// stop): its orbits touch the stops or not.
    Continued,
    /// Values of the parameter past the end of a branch at which no stable periodic orbit is
    /// found: the response measured after a transient, as a stepped sine measures it, not
    /// continued (its points are no orbits: no multipliers, a residual of NaN).
    Stepped,
}

/// How a branch ends.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EndKind {
    /// Past the parameter range.
    Range,
    /// An impact speed falls to zero: the orbit grazes a stop there.
    Grazing,
    /// A flight reaches a stop with zero velocity: a new impact begins there.
    NewContact,
    /// An asymmetric orbit returns to the symmetric orbits (at their pitchfork).
    Symmetric,
    /// The branch begins at a bifurcation of another branch (a pitchfork or a period
    /// doubling).
    Bifurcation,
    /// The branch begins at the orbit reached from rest (followed one way only).
    Rest,
    /// The steps fell below their minimum.
    Stalled,
    /// The budget of points ran out.
    Budget,
    /// The branch ends at a grazing that adds a strike of a rigid contact, past which no
    /// orbit is found from its last orbit.
    Strike,
    /// An orbit found from the state after a transient: a branch begins there, and the
    /// stepped points before it end.
    Found,
}

impl EndKind {
    /// Label for tables.
    pub fn label(self) -> &'static str {
        match self {
            EndKind::Range => "end of the range",
            EndKind::Grazing => "grazing (an impact speed reaches zero)",
            EndKind::NewContact => "grazing (a flight reaches a stop)",
            EndKind::Symmetric => "returns to the symmetric orbits",
            EndKind::Bifurcation => "starts at a bifurcation",
            EndKind::Rest => "the orbit reached from rest",
            EndKind::Stalled => "stalled",
            EndKind::Budget => "point budget",
            EndKind::Strike => "a grazing that adds a strike (no orbit found past it)",
            EndKind::Found => "an orbit found after a transient",
        }
    }
}

/// One end of a branch.
#[derive(Debug, Clone, PartialEq)]
pub struct BranchEnd {
    /// How it ends.
    pub kind: EndKind,
    /// The parameter there (Hz or g).
    pub param: f64,
    /// The residual distance to the end's condition at the last point: the impact speed
    /// (m/s) at a grazing, the distance of the flight from the stop (m) at a new contact, the
    /// asymmetry (m/s) at a symmetric orbit; zero otherwise.
    pub residual: f64,
    /// The other branches that meet there.
    pub meets: Vec<usize>,
}

/// A branch of the diagram.
#[derive(Debug, Clone, PartialEq)]
pub struct DiagramBranch {
    /// What its orbits are.
    pub kind: BranchKind,
    /// A unique label ("non-impacting", "symmetric, 2 impacts a period", ...).
    pub label: String,
    /// Its orbits in order.
    pub points: Vec<DiagramPoint>,
    /// Where its first point is.
    pub start: BranchEnd,
    /// Where its last point is.
    pub end: BranchEnd,
}

/// What happens at an event of the diagram.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EventKind {
    /// An orbit touches a stop with zero velocity: a branch with one impact more begins or
    /// ends; the multipliers jump (not a smooth bifurcation).
    Grazing,
    /// The branch turns back (a multiplier through +1 with a turn).
    Fold,
    /// A multiplier through +1 without a turn.
    BranchPoint,
    /// A multiplier of a symmetric orbit's half-period map through -1: the symmetric orbit
    /// gains or loses stability to a pair of asymmetric orbits.
    SymmetryBreaking,
    /// A multiplier through -1.
    PeriodDoubling,
    /// A complex pair through the unit circle.
    Torus,
    /// A stable orbit found from the state after a transient past the end of a branch: a new
    /// branch begins there (its orbit's least number of drive periods in
    /// [`DiagramPoint::periods`]).
    BranchFound,
}

impl EventKind {
    /// Label for tables.
    pub fn label(self) -> &'static str {
        match self {
            EventKind::Grazing => "grazing",
            EventKind::Fold => "fold",
            EventKind::BranchPoint => "branch point",
            EventKind::SymmetryBreaking => "symmetry-breaking pitchfork",
            EventKind::PeriodDoubling => "period doubling",
            EventKind::Torus => "torus",
            EventKind::BranchFound => "branch found",
        }
    }
}

/// A located event.
#[derive(Debug, Clone, PartialEq)]
pub struct DiagramEvent {
    /// What happens.
    pub kind: EventKind,
    /// The parameter (Hz or g).
    pub param: f64,
    /// The orbit at the event.
    pub point: DiagramPoint,
    /// The branches that meet there: for a smooth event its own branch; for a grazing, every
    /// branch that begins or ends at it.
    pub branches: Vec<usize>,
    /// Stability beside the event: for a smooth event before and after it along its branch;
    /// for a grazing, of each branch of `branches` next to it.
    pub stable: Vec<bool>,
    /// For a grazing: the branch turns back there, meeting the other side at an angle (a
    /// non-smooth fold, the border-collision of two orbits; di Bernardo et al. 2008, section
    /// 4.2), rather than passing through.
    pub corner: bool,
    /// For a grazing at which a rigid contact gains or loses a strike per period (the set of
    /// contacts touched unchanged): that contact (its index in
    /// [`crate::model::Model::contacts`]).
    pub contact: Option<usize>,
    /// For a grazing of a contact that gains or loses a strike per period: the lesser number
    /// of that contact's strikes a period on its two sides (the grazing lies between that
    /// number and one more), which tells apart two such grazings a little apart.
    pub strikes: Option<u32>,
}

impl DiagramEvent {
    /// Label for tables: the kind, and at a corner (a grazing where the branch turns) that the
    /// fold there is non-smooth.
    pub fn label(&self) -> String {
        if let (EventKind::Grazing, Some(k)) = (self.kind, self.contact) {
            match self.strikes {
                Some(n) => format!("grazing of contact {k} ({n} to {} strikes a period)", n + 1),
                None => format!("grazing of contact {k} (a strike more or less per period)"),
            }
        } else if self.kind == EventKind::BranchFound {
            format!("period-{} branch found", self.point.periods)
        } else if self.corner {
            format!(
                "{} (non-smooth fold: the branch turns there)",
                self.kind.label()
            )
        } else {
            self.kind.label().to_string()
        }
    }
}

/// The bifurcation diagram of a device in one parameter.
#[derive(Debug, Clone, PartialEq)]
pub struct Diagram {
    /// The parameter.
    pub parameter: Parameter,
    /// The branches.
    pub branches: Vec<DiagramBranch>,
    /// The located events, in increasing parameter.
    pub events: Vec<DiagramEvent>,
    /// Integrator counters of every integration.
    pub stats: Stats,
}

impl Diagram {
    /// The events of one kind.
    pub fn events_of(&self, kind: EventKind) -> impl Iterator<Item = &DiagramEvent> {
        self.events.iter().filter(move |e| e.kind == kind)
    }

    /// The branch labelled `label`.
    pub fn branch(&self, label: &str) -> Option<&DiagramBranch> {
        self.branches.iter().find(|b| b.label == label)
    }
}

/// An orbit of the period map as a point of a diagram (its half-period map with `half`).
pub(crate) fn orbit_point<M: Model<N>, const N: usize>(
    shooter: &Shooter<'_, M, N>,
    o: &Orbit,
    half: bool,
    stats: &mut Stats,
) -> Result<DiagramPoint, OrbitError> {
    let half = if half {
        shooter.half_map(o, stats)?
    } else {
        None
    };
    let fingerprint = shooter
        .state_at_phase(o, 0.0)
        .map_err(|e| OrbitError::Solver {
            what: "the state at drive phase zero",
            param: o.forcing.freq_hz,
            source: e,
        })?;
    let w = 2.0 * std::f64::consts::PI * o.forcing.freq_hz;
    let section = o.summary.upcrossing_s.map(|t| {
        let phase = (o.phase_rad + w * t).rem_euclid(2.0 * std::f64::consts::PI);
        (phase, o.state.clone())
    });
    let mut speeds = Vec::new();
    for s in o.summary.impact_speed_m_s {
        if s > 0.0 {
            speeds.push(s);
        }
    }
    let [(g_up, _), (g_lo, _)] = side_stops(shooter.base);
    let clearance_m = (g_up - o.summary.x_upper_m).min(g_lo + o.summary.x_lower_m);
    let symmetric = half.is_some();
    Ok(DiagramPoint {
        forcing: o.forcing,
        periods: o.periods as u32,
        multipliers: o.multipliers.clone(),
        half_multipliers: half.map(|h| h.multipliers),
        summary: o.summary.clone(),
        section,
        impact_speeds_m_s: speeds,
        clearance_m,
        symmetric,
        residual: o.residual,
        fingerprint: DVector::from_column_slice(fingerprint.as_slice()),
    })
}
