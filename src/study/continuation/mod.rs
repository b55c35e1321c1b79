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
//! turns by more than [`ContinuationSettings::max_turn_rad`], when the parameter moves by more
//! than [`ContinuationSettings::max_param_step`], or for one of the other reasons of
//! [`Rejection`] (each rejection is kept in [`Branch::rejections`]); it grows after easy
//! corrections. Where the step falls below [`ContinuationSettings::ds_min`] at a grazing
//! orbit, the corner there is hopped over or crossed (the grazing located on the branch by
//! bisection and the predictor restarted past it), as is a grazing at which a rigid contact
//! gains a strike per period (its orbit past the grazing sought on the maps over one to four
//! drive periods, and taken where it is an orbit of one period); elsewhere it is an error
//! naming the last parameter value reached, or, where past such a grazing only an orbit of
//! several periods is found, naming that orbit's periods and parameter value. A branch
//! followed from an orbit of k drive periods is continued on the map over k periods. Where a
//! branch ends at such a grazing, the response goes on in steps with transients
//! ([`response_of_model`]): each stable orbit found from a transient begins a new branch, and
//! the values without one are measured and not continued.
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
//! | grazing | max |x| - x_max (for a rigid stop it strikes, the impact speed over w0) | the orbit starts or stops touching a stop |
//! | grazing of a contact | its free peak between strikes less its gap, or its slowest strike's speed over w0 | a rigid contact gains or loses a strike per period |
//!
//! A +1 crossing is called a fold only where the branch turns: a crossing without a turn is a
//! branch point and is never presented as a fold. A turn at a grazing point, where the branch
//! has a corner rather than a smooth maximum, is a fold whose `at_grazing` flag is set.

//!
//! # Files
//! `types.rs` holds the settings and what a branch is made of, `corrector.rs` the
//! predictor-corrector (Newton on the bordered system, tangents, the acceptance of a step,
//! corner hops), `corner.rs` the crossing of a corner where the contact set changes,
//! `strike.rs` the crossing of a grazing that adds a strike of a rigid contact,
//! `periods.rs` the search for an orbit on the maps over several periods, `resume.rs`
//! the response past a branch's end at such a grazing,
//! `events.rs` the test functions and the location of events; this file holds the
//! loop that drives them ([`continue_branch`]) and the entry points.

use nalgebra::{DVector, SVector};

use crate::model::Model;
use crate::ode::Stats;
use crate::progress::{share, Progress};
use crate::study::orbit::{Forcing, Orbit, OrbitError, Parameter, Shooter};

mod corner;
mod corrector;
mod diagram;
mod diagram_types;
mod events;
pub mod impacting;
mod periods;
mod resume;
mod strike;
mod test_functions;
mod types;

use corrector::Continuer;
pub use diagram::{
    all_stops_rigid, diagram, diagram_with_step, frequency_diagram, STEPPED_MEASURE_PERIODS,
};
pub use diagram_types::{
    BranchEnd, BranchKind, Diagram, DiagramBranch, DiagramEvent, DiagramPoint, EndKind,
    EventKind as DiagramEventKind,
};
pub use resume::{found_label, response_of_model, Piece, Response, ResumeSettings, SteppedPoint};
use strike::StrikeOutcome;
pub use types::{Branch, BranchPoint, ContinuationSettings, Event, EventKind, Rejection};

/// The first orbit of a branch: Newton at `forcing` from `guess` (the state at drive phase
/// zero), or, if that fails, from the state after a transient of `transient_periods` periods
/// from `guess`; its section is then moved into free flight.
pub fn first_orbit<M: Model<N>, const N: usize>(
    shooter: &Shooter<'_, M, N>,
    forcing: &Forcing,
    param: Parameter,
    guess: SVector<f64, N>,
    transient_periods: usize,
    stats: &mut Stats,
) -> Result<Orbit, OrbitError> {
    let o = match shooter.solve(forcing, param, 0.0, guess, stats) {
        Ok(o) => o,
        Err(_) => {
            let (y, _, st) = shooter
                .advance(
                    forcing,
                    0.0,
                    guess,
                    transient_periods as f64 * forcing.period_s(),
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
/// settings' start value) until the parameter passes `settings.stop`; `progress` is told of
/// every accepted point's parameter as the share of the way from the start to the stop.
pub fn continue_branch<M: Model<N> + Clone, const N: usize>(
    base: &M,
    first: Orbit,
    settings: &ContinuationSettings,
    progress: &dyn Progress,
) -> Result<Branch, OrbitError> {
    continue_branch_until(base, first, settings, progress, |_| false)
}

/// [`continue_branch`], ending early at the point after the first event for which
/// `until(event)` is true (the branch then ends with that event, located as always): a caller
/// that wants only the first fold need not follow the branch back from it.
pub fn continue_branch_until<M: Model<N> + Clone, const N: usize>(
    base: &M,
    first: Orbit,
    settings: &ContinuationSettings,
    progress: &dyn Progress,
    until: impl FnMut(&Event) -> bool,
) -> Result<Branch, OrbitError> {
    let followed = follow(base, first, settings, progress, until)?;
    match followed.end {
        None => Ok(followed.branch),
        Some(end) => Err(end.error),
    }
}

/// Why a branch ends short of its range: the error, and whether the branch ends at a grazing
/// that adds a strike of a rigid contact (where no orbit past it is found, or only one of
/// several periods).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Ending {
    pub error: OrbitError,
    pub at_strike: bool,
}

/// A branch as far as it is followed, and why it ends short of its range (`None`: it reaches
/// the end of the range, or the event asked for).
pub(crate) struct Followed {
    pub branch: Branch,
    pub end: Option<Ending>,
}

/// The loop of [`continue_branch_until`] on the map over `first.periods` drive periods (the
/// orbits of a branch have the first orbit's number of periods), keeping the points reached
/// where the branch ends short of its range. An error of the setup or of an event's location
/// is returned as an error.
pub(crate) fn follow<M: Model<N> + Clone, const N: usize>(
    base: &M,
    first: Orbit,
    settings: &ContinuationSettings,
    progress: &dyn Progress,
    mut until: impl FnMut(&Event) -> bool,
) -> Result<Followed, OrbitError> {
    settings.validate()?;
    let on_point = |p: f64| progress.fraction(share(settings.start, settings.stop, p));
    let shooter = Shooter::new(base, settings.shooting);
    let mut c = Continuer {
        shooter: &shooter,
        settings: *settings,
        periods: first.periods.max(1),
        stats: Stats::default(),
    };
    let param = settings.parameter;
    let dir = settings.direction();
    // The first tangent: the kernel oriented along the parameter's direction.
    let mut start_dir = DVector::zeros(N + 1);
    start_dir[N] = dir;
    let lin = c.linearise(&first.forcing, first.phase_rad, first.state_n())?;
    let jac = c.kernel_jacobian(&lin);
    let tangent = corrector::tangent(&jac, &start_dir).ok_or(OrbitError::Invalid(
        "the first orbit is singular (a fold or branch point): start elsewhere".into(),
    ))?;
    on_point(first.param(param));
    let mut points = vec![BranchPoint {
        orbit: first,
        tangent,
    }];
    let mut events = Vec::new();
    let mut ds = settings.ds_init;
    let mut rejections = Vec::new();
    let stalled = |p_last: f64| OrbitError::Stalled {
        what: param.label(),
        last_param: p_last,
        ds_min: settings.ds_min,
    };
    let end = loop {
        let last = points.last().expect("a branch has a point").clone();
        let p_last = last.orbit.param(param);
        if settings.beyond_stop(p_last) {
            break None;
        }
        if points.len() >= settings.max_points {
            break Some(Ending {
                error: OrbitError::TooManyPoints {
                    what: param.label(),
                    last_param: p_last,
                    points: settings.max_points,
                },
                at_strike: false,
            });
        }
        let accepted = c
            .point_at(&last, ds)
            .map_err(|_| Rejection::Corrector)
            .and_then(|(p, its)| c.judge(&last, &p, ds).map(|()| (p, its)));
        let (p, its) = match accepted {
            Ok(found) => found,
            Err(why) => {
                rejections.push(why);
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
                        let done = found.iter().any(&mut until);
                        events.extend(found);
                        on_point(p.orbit.param(param));
                        points.push(p);
                        if done {
                            break None;
                        }
                        ds = settings.ds_init;
                        continue;
                    }
                    // At a corner where the contact set changes on the free-flight side too
                    // (both stops of a symmetric orbit at once, or one stop while the other is
                    // in contact), the grazing is located and the branch goes on past it.
                    if let Some(x) =
                        c.cross_corner(&points, &last, settings.ds_min, settings.ds_init)
                    {
                        let k = points.len() - 1;
                        let mut g = x.grazing;
                        let mut found = Vec::new();
                        let from = if x.s_grazing > 0.0 {
                            found.extend(c.events_between(k, &last, &mut g, x.s_grazing)?);
                            points.push(g.clone());
                            g
                        } else {
                            last.clone()
                        };
                        let past = x.past;
                        let s_rest = x.s_past - x.s_grazing;
                        let k = points.len() - 1;
                        found.extend(c.corner_events(k, &from, &past, s_rest));
                        let done = found.iter().any(&mut until);
                        events.extend(found);
                        on_point(past.orbit.param(param));
                        points.push(past);
                        if done {
                            break None;
                        }
                        ds = (2.0 * x.s_past).clamp(settings.ds_min, settings.ds_init);
                        continue;
                    }
                    // At a grazing that adds a strike of a rigid contact (its free approach
                    // between strikes reaching the gap, the contact set unchanged), the
                    // orbit with the added strike is found and the branch goes on from it.
                    match c.cross_strike_grazing(points.len() - 1, &last) {
                        Some(StrikeOutcome::Crossed(x)) => {
                            let done = x.events.iter().any(&mut until);
                            events.extend(x.events);
                            on_point(x.past.orbit.param(param));
                            points.push(x.past);
                            if done {
                                break None;
                            }
                            ds = settings.ds_init;
                            continue;
                        }
                        // The continuation follows orbits of one period: past the grazing
                        // only an orbit of several periods is found, and the branch ends.
                        Some(StrikeOutcome::OtherPeriod(o)) => {
                            break Some(Ending {
                                error: OrbitError::OtherPeriod {
                                    what: param.label(),
                                    last_param: p_last,
                                    periods: o.periods,
                                    param: o.param(param),
                                },
                                at_strike: true,
                            });
                        }
                        Some(StrikeOutcome::NotFound) => {
                            break Some(Ending {
                                error: stalled(p_last),
                                at_strike: true,
                            });
                        }
                        None => {}
                    }
                    break Some(Ending {
                        error: stalled(p_last),
                        at_strike: false,
                    });
                }
                continue;
            }
        };
        let k = points.len() - 1;
        let mut p = p;
        let found = c.events_between(k, &last, &mut p, ds)?;
        let done = found.iter().any(&mut until);
        events.extend(found);
        on_point(p.orbit.param(param));
        // A failed move of the section keeps the point at its old one (still a valid orbit).
        let p = match c.reanchor(p.clone()) {
            Ok(q) => q,
            Err(_) => p,
        };
        points.push(p);
        if done {
            break None;
        }
        if its <= 2 {
            ds = (ds * 1.5).min(settings.ds_max);
        } else if its >= 5 {
            ds = (ds * 0.6).max(settings.ds_min);
        }
    };
    Ok(Followed {
        branch: Branch {
            parameter: param,
            points,
            events,
            stats: c.stats,
            rejections,
        },
        end,
    })
}

/// The branch of periodic orbits of `device` continued by `settings` from the drive `start`
/// (whose frequency or amplitude is the settings' start value), beginning with the orbit
/// reached from rest (shooting, after up to `transient_periods` periods of transient if Newton
/// does not converge from rest); `progress` as in [`continue_branch`].
pub fn branch_from_rest(
    device: &crate::device::Device,
    start: Forcing,
    settings: &ContinuationSettings,
    transient_periods: usize,
    progress: &dyn Progress,
) -> Result<Branch, OrbitError> {
    settings.validate()?;
    crate::with_harvester!(device, |h| branch_of_model(
        &h,
        start,
        settings,
        transient_periods,
        progress
    ))
}

/// The response of `device` over the settings' range from the drive `start`: the branch
/// continued from the orbit reached from rest (as [`branch_from_rest`], with
/// `resume.transient_periods` periods of transient at most), resumed past every grazing that
/// adds a strike at which a branch ends ([`response_of_model`]).
pub fn response_from_rest(
    device: &crate::device::Device,
    start: Forcing,
    settings: &ContinuationSettings,
    resume: &ResumeSettings,
    progress: &dyn Progress,
) -> Result<Response, OrbitError> {
    settings.validate()?;
    crate::with_harvester!(device, |h| {
        let (first, stats) = orbit_from_rest(&h, start, settings, resume.transient_periods)?;
        let mut r = response_of_model(&h, first, settings, resume, progress)?;
        r.stats += stats;
        Ok(r)
    })
}

/// The first orbit of a branch from rest ([`first_orbit`]) with the counters of its
/// integrations.
fn orbit_from_rest<M: Model<N>, const N: usize>(
    h: &M,
    start: Forcing,
    settings: &ContinuationSettings,
    transient_periods: usize,
) -> Result<(Orbit, Stats), OrbitError> {
    let shooter = Shooter::new(h, settings.shooting);
    let mut stats = Stats::default();
    let first = first_orbit(
        &shooter,
        &start,
        settings.parameter,
        h.rest_state(),
        transient_periods,
        &mut stats,
    )?;
    Ok((first, stats))
}

/// [`branch_from_rest`] on a model.
pub fn branch_of_model<M: Model<N> + Clone, const N: usize>(
    h: &M,
    start: Forcing,
    settings: &ContinuationSettings,
    transient_periods: usize,
    progress: &dyn Progress,
) -> Result<Branch, OrbitError> {
    let (first, stats) = orbit_from_rest(h, start, settings, transient_periods)?;
    let mut branch = continue_branch(h, first, settings, progress)?;
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
/// use endstop::progress::Silent;
/// use endstop::study::continuation::frequency_branch;
///
/// let text = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/prototype1.toml"));
/// let device = Device::from_toml_str(text, "prototype1.toml")?;
/// // Far below the stops (0.02 g rms): one stable branch, no events.
/// let branch = frequency_branch(&device, 0.02, 1000.0, 1100.0, 50.0, &Silent)?;
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
    progress: &dyn Progress,
) -> Result<Branch, OrbitError> {
    let start = Forcing {
        freq_hz: from_hz,
        accel_rms_g,
    };
    let settings = ContinuationSettings::frequency(from_hz, to_hz, max_step_hz);
    branch_from_rest(device, start, &settings, 200, progress)
}
