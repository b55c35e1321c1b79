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

use crate::device::Device;
use crate::model::Model;
use crate::ode::Stats;
use crate::progress::{Progress, Silent};
use crate::study::orbit::{Forcing, OrbitError, Shooter};

use super::diagram_types::{
    orbit_point, BranchEnd, BranchKind, Diagram, DiagramBranch, DiagramEvent, DiagramPoint,
    EndKind, EventKind,
};
use super::impacting::bvp::side_stops;
use super::impacting::{rigid_diagram, DiagramSettings};
use super::{
    found_label, response_from_rest, Branch, ContinuationSettings, EventKind as BranchEventKind,
    Piece, Response, ResumeSettings, SteppedPoint,
};

/// True when every stop of the device's model is rigid (and it has one): the model's
/// contacts ([`Model::contacts`]), so that a device of several masses counts its stops to the
/// frame and between masses. False for a device whose parts do not assemble (the study that
/// assembles it reports why).
pub fn all_stops_rigid(device: &Device) -> bool {
    crate::with_harvester!(
        device,
        |h| Ok::<_, crate::physics::harvester::AssemblyError>(model_stops_rigid(&h))
    )
    .unwrap_or(false)
}

/// True when every present contact of `model` (a finite gap) is rigid, and it has one.
fn model_stops_rigid<M: Model<N>, const N: usize>(model: &M) -> bool {
    let contacts = model.contacts();
    let mut present = contacts.iter().filter(|c| c.gap.is_finite()).peekable();
    present.peek().is_some() && present.all(|c| c.rigid())
}

/// True when the impacting-orbit diagram ([`rigid_diagram`]) follows every contact of the
/// device's model: all rigid, and all the first mass's stops to the frame (a stop between two
/// masses, or another mass's to the frame, is met by the branch continued from rest).
fn rigid_diagram_applies(device: &Device) -> bool {
    all_stops_rigid(device)
        && crate::with_harvester!(
            device,
            |h| Ok::<_, crate::physics::harvester::AssemblyError>(
                h.contacts()
                    .iter()
                    .filter(|c| c.gap.is_finite())
                    .all(|c| c.mass == 0 && c.other.is_none())
            )
        )
        .unwrap_or(false)
}

/// The diagram of `device` under the drive `start` (at the settings' start value) over the
/// settings' range: [`rigid_diagram`] for a device whose stops are all rigid and all the first
/// mass's to the frame, else the response from rest ([`response_from_rest`]: the branch
/// continued from rest, resumed past a grazing that adds a strike where it ends there, in
/// steps of the settings' largest parameter step) as a diagram ([`Diagram::from_response`]).
/// `progress` is told of each branch as it is begun.
pub fn diagram(
    device: &Device,
    start: Forcing,
    settings: &ContinuationSettings,
    options: &DiagramSettings,
    progress: &dyn Progress,
) -> Result<Diagram, OrbitError> {
    diagram_with_step(
        device,
        start,
        settings,
        options,
        settings.max_param_step,
        progress,
    )
}

/// Drive periods over which a stepped point is measured: enough for the mean number of
/// impacts a period of a response that repeats no period to two digits' resolution (a
/// hundredth of an impact a period is one impact in a hundred periods).
pub const STEPPED_MEASURE_PERIODS: usize = 100;

/// [`diagram`], where the response is resumed past a grazing that adds a strike in steps of
/// `step` (Hz or g; a stepped sweep's step), each after `options.transient_periods` periods of
/// transient, a point without an orbit measured over [`STEPPED_MEASURE_PERIODS`] periods.
pub fn diagram_with_step(
    device: &Device,
    start: Forcing,
    settings: &ContinuationSettings,
    options: &DiagramSettings,
    step: f64,
    progress: &dyn Progress,
) -> Result<Diagram, OrbitError> {
    if rigid_diagram_applies(device) {
        return rigid_diagram(device, start, settings, options, progress);
    }
    progress.stage("periodic orbits from rest");
    let resume = ResumeSettings {
        step,
        transient_periods: options.transient_periods,
        measure_periods: STEPPED_MEASURE_PERIODS,
    };
    let response = response_from_rest(device, start, settings, &resume, &Silent)?;
    crate::with_harvester!(device, |h| {
        let shooter = Shooter::new(&h, settings.shooting);
        Diagram::from_response(&shooter, &response)
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
        &DiagramSettings::default(),
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
        let mut stats = branch.stats;
        let part = BranchPart {
            index: 0,
            label: "periodic orbits".into(),
            start: EndKind::Range,
            end: EndKind::Range,
        };
        let (b, mut events) = diagram_branch(shooter, branch, part, &mut stats)?;
        events.sort_by(|a, b| a.param.total_cmp(&b.param));
        Ok(Diagram {
            parameter: branch.parameter,
            branches: vec![b],
            events,
            stats,
        })
    }

    /// A response as a diagram: each continued branch as in [`Diagram::from_branch`] (the
    /// first labelled "periodic orbits", each found from a transient by its orbits' periods
    /// and where it is found, with an event of kind [`EventKind::BranchFound`] there), and each
    /// run of stepped points as a branch of kind [`BranchKind::Stepped`].
    pub fn from_response<M: Model<N>, const N: usize>(
        shooter: &Shooter<'_, M, N>,
        response: &Response,
    ) -> Result<Self, OrbitError> {
        let param = response.parameter;
        let mut stats = response.stats;
        let mut branches: Vec<DiagramBranch> = Vec::new();
        let mut events = Vec::new();
        let count = response.pieces.len();
        for (i, piece) in response.pieces.iter().enumerate() {
            let index = branches.len();
            // How the piece before ends and the next begins.
            let before = response.ends.iter().find(|e| e.piece + 1 == i);
            let start = match (piece, before) {
                _ if i == 0 => EndKind::Range,
                (Piece::Continued(_), _) => EndKind::Found,
                (Piece::Stepped(_), Some(e)) if !e.at_strike => EndKind::Stalled,
                (Piece::Stepped(_), _) => EndKind::Strike,
            };
            let ended = response.ends.iter().find(|e| e.piece == i);
            let end = match (piece, ended) {
                (Piece::Continued(_), Some(e)) if e.at_strike => EndKind::Strike,
                (Piece::Continued(_), Some(_)) => EndKind::Stalled,
                _ if i + 1 == count => EndKind::Range,
                (Piece::Continued(_), None) => EndKind::Range,
                (Piece::Stepped(_), _) => EndKind::Found,
            };
            match piece {
                Piece::Continued(b) => {
                    stats += b.stats;
                    let first = &b.points[0].orbit;
                    let label = if i == 0 {
                        "periodic orbits".to_string()
                    } else {
                        found_label(first.periods, first.param(param), param)
                    };
                    let part = BranchPart {
                        index,
                        label,
                        start,
                        end,
                    };
                    let (db, evs) = diagram_branch(shooter, b, part, &mut stats)?;
                    if i > 0 {
                        events.push(DiagramEvent {
                            kind: EventKind::BranchFound,
                            param: first.param(param),
                            point: db.points[0].clone(),
                            branches: vec![index],
                            stable: vec![true],
                            corner: false,
                            contact: None,
                            strikes: None,
                        });
                    }
                    branches.push(db);
                    events.extend(evs);
                }
                Piece::Stepped(points) => {
                    let points: Vec<DiagramPoint> =
                        points.iter().map(|p| stepped_point(shooter, p)).collect();
                    let at = |p: &DiagramPoint| BranchEnd {
                        kind: start,
                        param: p.forcing.get(param),
                        residual: 0.0,
                        meets: Vec::new(),
                    };
                    let (first, mut last) = (at(&points[0]), at(&points[points.len() - 1]));
                    last.kind = end;
                    let from = first.param;
                    branches.push(DiagramBranch {
                        kind: BranchKind::Stepped,
                        label: format!("not continued from {from:.4}"),
                        points,
                        start: first,
                        end: last,
                    });
                }
            }
        }
        events.sort_by(|a, b| a.param.total_cmp(&b.param));
        Ok(Diagram {
            parameter: param,
            branches,
            events,
            stats,
        })
    }
}

/// Where a branch goes in a diagram: its index, label and how its ends are described.
struct BranchPart {
    index: usize,
    label: String,
    start: EndKind,
    end: EndKind,
}

/// A continued branch as a branch of a diagram with its events (see
/// [`Diagram::from_branch`]); `stats` accumulates the integrations made for them.
fn diagram_branch<M: Model<N>, const N: usize>(
    shooter: &Shooter<'_, M, N>,
    branch: &Branch,
    part: BranchPart,
    stats: &mut Stats,
) -> Result<(DiagramBranch, Vec<DiagramEvent>), OrbitError> {
    let points = branch
        .points
        .iter()
        .map(|p| orbit_point(shooter, &p.orbit, false, stats))
        .collect::<Result<Vec<_>, _>>()?;
    let mut events: Vec<DiagramEvent> = Vec::new();
    for e in &branch.events {
        let corner = e.kind == BranchEventKind::Fold && e.at_grazing;
        let kind = match e.kind {
            _ if corner => EventKind::Grazing,
            BranchEventKind::Fold => EventKind::Fold,
            BranchEventKind::BranchPoint => {
                let half = shooter.half_map(&e.orbit, stats)?;
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
                x.kind == EventKind::Grazing
                    && x.contact == e.contact
                    && (x.param - e.param).abs() < 1e-9 * e.param.abs()
            }) {
                prev.corner |= corner;
                continue;
            }
        }
        events.push(DiagramEvent {
            kind,
            param: e.param,
            point: orbit_point(shooter, &e.orbit, true, stats)?,
            branches: vec![part.index],
            stable: vec![e.stable_before, e.stable_after],
            corner,
            contact: e.contact,
            strikes: e.strikes,
        });
    }
    let end = |p: &DiagramPoint, kind: EndKind| BranchEnd {
        kind,
        param: p.forcing.get(branch.parameter),
        residual: 0.0,
        meets: Vec::new(),
    };
    let (first, last) = (
        end(&points[0], part.start),
        end(&points[points.len() - 1], part.end),
    );
    Ok((
        DiagramBranch {
            kind: BranchKind::Continued,
            label: part.label,
            points,
            start: first,
            end: last,
        },
        events,
    ))
}

/// A stepped point as a point of a diagram: its measures over its periods, no multipliers,
/// a residual of NaN (it is no orbit), its state at the start of the measurement as its
/// fingerprint.
fn stepped_point<M: Model<N>, const N: usize>(
    shooter: &Shooter<'_, M, N>,
    p: &SteppedPoint,
) -> DiagramPoint {
    let speeds = p
        .summary
        .impact_speed_m_s
        .iter()
        .copied()
        .filter(|s| *s > 0.0)
        .collect();
    let [(g_up, _), (g_lo, _)] = side_stops(shooter.base);
    DiagramPoint {
        forcing: p.forcing,
        periods: p.periods as u32,
        multipliers: Vec::new(),
        half_multipliers: None,
        summary: p.summary.clone(),
        section: None,
        impact_speeds_m_s: speeds,
        clearance_m: (g_up - p.summary.x_upper_m).min(g_lo + p.summary.x_lower_m),
        symmetric: false,
        residual: f64::NAN,
        fingerprint: p.state.clone(),
    }
}
