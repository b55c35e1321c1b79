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
use super::impacting::{rigid_diagram, DiagramSettings};
use super::{branch_from_rest, Branch, ContinuationSettings, EventKind as BranchEventKind};

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
/// mass's to the frame, else the branch
/// continued from rest ([`branch_from_rest`]) as a diagram of one branch
/// ([`Diagram::from_branch`]). `progress` is told of each branch as it is begun.
pub fn diagram(
    device: &Device,
    start: Forcing,
    settings: &ContinuationSettings,
    options: &DiagramSettings,
    progress: &dyn Progress,
) -> Result<Diagram, OrbitError> {
    if rigid_diagram_applies(device) {
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
                point: orbit_point(shooter, &e.orbit, true, &mut stats)?,
                branches: vec![0],
                stable: vec![e.stable_before, e.stable_after],
                corner,
                contact: e.contact,
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
