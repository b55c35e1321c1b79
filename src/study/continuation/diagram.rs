//! The bifurcation diagram of a device in one drive parameter: every branch of periodic orbits
//! found, each labelled, with its ends and the events at which branches meet or change
//! stability ([`frequency_diagram`]).
//!
//! For a device whose stops are all rigid the diagram is built by [`impacting`] (the
//! non-impacting branch, its grazings and every impacting branch met from them). For any other
//! device it is the one branch continued from rest by [`continue_branch`] on the period map,
//! where a compliant stop makes the flow continuous through grazing (the contact force starts
//! from zero), so that the multipliers pass grazing continuously and the branch's events are
//! located as on a smooth branch; a branch point of a symmetric orbit is named by its
//! half-period map ([`crate::study::orbit::HalfMap`]).

use nalgebra::{Complex, DVector};

use crate::device::Device;
use crate::model::Model;
use crate::ode::Stats;
use crate::progress::{Progress, Silent};
use crate::study::orbit::{Forcing, Orbit, OrbitError, OrbitSummary, Parameter, Shooter};

use super::impacting::{rigid_diagram, DiagramOptions, ImpactSequence};
use super::{branch_from_rest, Branch, ContinuationSettings, EventKind as BranchEventKind};

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
}

impl DiagramEvent {
    /// Label for tables: the kind, and at a corner (a grazing where the branch turns) that the
    /// fold there is non-smooth.
    pub fn label(&self) -> String {
        if self.corner {
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

/// True when every stop of the device is rigid (and it has one).
pub fn all_stops_rigid(device: &Device) -> bool {
    let stops: Vec<_> = device.stops.present().map(|(_, s)| s).collect();
    !stops.is_empty()
        && stops
            .iter()
            .all(|s| matches!(s.law, crate::device::StopLaw::Restitution { .. }))
}

/// The diagram of `device` under the drive `start` (at the settings' start value) over the
/// settings' range: [`rigid_diagram`] for a device whose stops are all rigid, else the branch
/// continued from rest ([`branch_from_rest`]) as a diagram of one branch
/// ([`Diagram::from_branch`]). `progress` is told of each branch as it is begun.
pub fn diagram(
    device: &Device,
    start: Forcing,
    settings: &ContinuationSettings,
    options: &DiagramOptions,
    progress: &dyn Progress,
) -> Result<Diagram, OrbitError> {
    if all_stops_rigid(device) {
        return rigid_diagram(device, start, settings, options, progress);
    }
    progress.stage("periodic orbits from rest");
    let branch = branch_from_rest(device, start, settings, options.transient_periods, &Silent)?;
    crate::with_harvester!(device, |h| {
        let shooter = Shooter::new(&h, settings.shooting);
        Diagram::from_branch(&shooter, &branch)
    })
}

/// The diagram of `device` at `accel_rms_g` (g rms) in frequency from `from_hz` to `to_hz`,
/// with parameter steps of at most `max_step_hz` ([`diagram`] with
/// [`ContinuationSettings::frequency`] and the default options).
///
/// ```
/// use endstop::device::Device;
/// use endstop::progress::Silent;
/// use endstop::study::continuation::{frequency_diagram, DiagramEventKind as EventKind, EndKind};
///
/// let text = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/examples/rigid_restitution.toml"));
/// let device = Device::from_toml_str(text, "rigid_restitution.toml")?;
/// let d = frequency_diagram(&device, 0.3, 600.0, 640.0, 2.0, &Silent)?;
/// // The non-impacting orbit grazes both stops twice; no period doubling anywhere.
/// assert_eq!(d.events_of(EventKind::Grazing).count(), 2);
/// assert_eq!(d.events_of(EventKind::PeriodDoubling).count(), 0);
/// let sym = d.branch("symmetric, 2 impacts a period").unwrap();
/// assert_eq!(sym.end.kind, EndKind::Range);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn frequency_diagram(
    device: &Device,
    accel_rms_g: f64,
    from_hz: f64,
    to_hz: f64,
    max_step_hz: f64,
    progress: &dyn Progress,
) -> Result<Diagram, OrbitError> {
    let start = Forcing {
        freq_hz: from_hz,
        accel_rms_g,
    };
    let settings = ContinuationSettings::frequency(from_hz, to_hz, max_step_hz);
    diagram(
        device,
        start,
        &settings,
        &DiagramOptions::default(),
        progress,
    )
}

/// How close to -1 a multiplier of a symmetric orbit's half-period map must be at a located
/// branch point for the point to be named a symmetry-breaking pitchfork (the branch point is
/// located to 1e-4 Hz, where the multiplier of the period map is within about 1e-3 of +1).
const HALF_MINUS_ONE_TOL: f64 = 0.02;

impl Diagram {
    /// A continued branch as a diagram of one branch: its orbits, and its events as the
    /// diagram names them (a fold at a grazing corner is a grazing with `corner` set; a branch
    /// point of a symmetric orbit whose half-period map has a multiplier at -1 is a
    /// symmetry-breaking pitchfork). `shooter` is the branch's, for the fingerprints and the
    /// half-period maps.
    pub fn from_branch<M: Model<N>, const N: usize>(
        shooter: &Shooter<'_, M, N>,
        branch: &Branch,
    ) -> Result<Self, OrbitError> {
        let mut stats = Stats::default();
        let points = branch
            .points
            .iter()
            .map(|p| orbit_point(shooter, &p.orbit, false, &mut stats))
            .collect::<Result<Vec<_>, _>>()?;
        let mut events: Vec<DiagramEvent> = Vec::new();
        for e in &branch.events {
            let corner = e.kind == BranchEventKind::Fold && e.at_grazing;
            let kind = match e.kind {
                _ if corner => EventKind::Grazing,
                BranchEventKind::Fold => EventKind::Fold,
                BranchEventKind::BranchPoint => {
                    let half = shooter.half_map(&e.orbit, &mut stats)?;
                    let at_minus_one = half.as_ref().is_some_and(|h| {
                        h.multipliers
                            .iter()
                            .any(|m| (m + 1.0).norm() < HALF_MINUS_ONE_TOL)
                    });
                    if at_minus_one {
                        EventKind::SymmetryBreaking
                    } else {
                        EventKind::BranchPoint
                    }
                }
                BranchEventKind::PeriodDoubling => EventKind::PeriodDoubling,
                BranchEventKind::Torus => EventKind::Torus,
                BranchEventKind::Grazing => EventKind::Grazing,
            };
            // The corner and its grazing are one point: kept once, as the corner.
            if kind == EventKind::Grazing {
                if let Some(prev) = events.iter_mut().find(|x| {
                    x.kind == EventKind::Grazing && (x.param - e.param).abs() < 1e-9 * e.param.abs()
                }) {
                    prev.corner |= corner;
                    continue;
                }
            }
            events.push(DiagramEvent {
                kind,
                param: e.param,
                point: orbit_point(shooter, &e.orbit, true, &mut stats)?,
                branches: vec![0],
                stable: vec![e.stable_before, e.stable_after],
                corner,
            });
        }
        events.sort_by(|a, b| a.param.total_cmp(&b.param));
        let end = |p: &DiagramPoint| BranchEnd {
            kind: EndKind::Range,
            param: p.forcing.get(branch.parameter),
            residual: 0.0,
            meets: Vec::new(),
        };
        let (first, last) = (end(&points[0]), end(&points[points.len() - 1]));
        let mut all = branch.stats;
        all += stats;
        Ok(Diagram {
            parameter: branch.parameter,
            branches: vec![DiagramBranch {
                kind: BranchKind::Continued,
                label: "periodic orbits".into(),
                points,
                start: first,
                end: last,
            }],
            events,
            stats: all,
        })
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
    let [(g_up, _), (g_lo, _)] = super::impacting::side_stops(shooter.base);
    let clearance_m = (g_up - o.summary.x_upper_m).min(g_lo + o.summary.x_lower_m);
    let symmetric = half.is_some();
    Ok(DiagramPoint {
        forcing: o.forcing,
        periods: 1,
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
