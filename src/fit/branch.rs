//! The fit's model of a measured sweep on the branches of periodic orbits (see the parent
//! module's "Misfit"): identified once from the stepped sweep at the starting values, then
//! followed by Newton's method as the parameters move ([`super::track`]).
//!
//! A sweep follows one branch from its first frequency until the branch ends (at a fold, where
//! it jumps, or where it loses contact gradually) and then another. Each measured point is
//! assigned to one of the two: by the measured end of the branch when the data state it, else
//! by the stepped sweep at the identification. A point on the first branch is compared with
//! that branch's orbit at its frequency while the branch exists there, and with the fold's
//! orbit once the fold has moved below (for an up-sweep) its frequency, so that its model
//! value is continuous in the parameters as the fold passes it; a point on the second branch
//! is compared with the second branch's orbit. The onset and a gradual end of contact are
//! grazing orbits, a jump the fold: each moves smoothly with the parameters. Where a branch's
//! orbit has lost its stability by a period doubling, a point is compared with the stable
//! orbit of two drive periods born there, which the steady state follows past the doubling
//! and which joins the period-1 orbit at it.

use crate::device::Device;
use crate::physics::harvester::Harvester as Model4;

/// The fit's model: the paper's devices, four components.
type Harvester = Model4<4>;
use crate::study::orbit::Orbit;
use crate::study::stepped::{in_contact, SweepStep, Transition};
use crate::study::sweep::{BranchEndKind, DownEndKind};

use super::clear;
use super::model::SweepRun;
use super::track::{
    locate_fold, locate_grazing, point_orbit, quantity_of, track_fold, track_grazing, Fold,
    Grazing, Guess, Lost,
};
use super::{Direction, FeatureKind, SweepData};

/// What the model compares a measured point with.
#[derive(Debug, Clone, PartialEq)]
pub(super) enum PointModel {
    /// The stable orbit at the point's frequency on its branch.
    Orbit(Box<Orbit>),
    /// A point of the first branch beyond its fold: the fold's orbit.
    AtFold,
    /// A point of the second branch where that branch does not reach: the orbit where it
    /// ends nearest the point, followed at its own frequency.
    Nearest(Box<Orbit>),
}

impl PointModel {
    /// The orbit the point is compared with, where it is not the fold's.
    fn orbit(&self) -> Option<&Orbit> {
        match self {
            PointModel::Orbit(o) | PointModel::Nearest(o) => Some(o),
            PointModel::AtFold => None,
        }
    }
}

/// The model of a measured frequency feature.
#[derive(Debug, Clone, PartialEq)]
pub(super) enum Edge {
    /// A grazing orbit (the onset, or a gradual end of contact).
    Grazing(Grazing),
    /// The data set's fold (a jump).
    Fold,
    /// The sweep shows no such feature inside its grid: the grid end it lies beyond (constant,
    /// as the stepped sweep places it).
    Fixed(f64),
}

/// The model of one data set at one set of parameter values.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct SetModel {
    /// The onset feature's model (when the data set has one).
    onset: Option<Edge>,
    /// The branch end feature's model (when the data set has one).
    end: Option<Edge>,
    /// The model of the jump the points show (when they show one, [`SweepData::measured_jump`]).
    bracket: Option<Edge>,
    /// The fold ending the first branch, when the sweep jumps.
    fold: Option<Fold>,
    /// Each point: on the first branch, and its model.
    points: Vec<(bool, PointModel)>,
    /// The device the model was found on (what a change of parameters leaves in place is
    /// read against it, [`clear`]).
    device: Device,
}

/// The accelerations, grid and direction of a data set at an acceleration factor.
struct Setup {
    accel_rms_g: f64,
    lo: f64,
    hi: f64,
    /// Typical grid step (Hz).
    step: f64,
    /// +1 up, -1 down.
    dir: f64,
}

impl Setup {
    fn of(data: &SweepData, scale: f64) -> Self {
        let grid = data.grid();
        let lo = grid.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = grid.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        Self {
            accel_rms_g: data.accel_rms_g * scale,
            lo,
            hi,
            step: (hi - lo) / (grid.len() - 1).max(1) as f64,
            dir: match data.direction {
                Direction::Up => 1.0,
                Direction::Down => -1.0,
            },
        }
    }

    /// How far a fold is followed: half the grid's span beyond its end.
    fn fold_limit(&self) -> f64 {
        let span = self.hi - self.lo;
        if self.dir > 0.0 {
            self.hi + 0.5 * span
        } else {
            (self.lo - 0.5 * span).max(0.5 * self.lo)
        }
    }

    /// The one-mass model the branches are followed on; a device of several masses has none
    /// (the assembly says so), and its fit is the stepped sweep's.
    fn harvester(&self, device: &Device) -> Result<Harvester, Lost> {
        Harvester::new(device).map_err(|e| Lost(e.to_string()))
    }
}

fn edge_value(e: &Edge, fold: Option<&Fold>) -> f64 {
    match e {
        Edge::Grazing(g) => g.freq_hz,
        Edge::Fold => fold.map_or(f64::NAN, Fold::freq_hz),
        Edge::Fixed(f) => *f,
    }
}

impl SetModel {
    /// How far the model's orbits (its points' and its fold's) reach towards the stop on
    /// `side` (m; zero for none).
    pub(super) fn reach_m(&self, side: crate::laws::contact::Side) -> f64 {
        use crate::laws::contact::Side;
        let reach = |o: &Orbit| match side {
            Side::Upper => o.summary.x_upper_m,
            Side::Lower => -o.summary.x_lower_m,
        };
        self.points
            .iter()
            .filter_map(|(_, pm)| pm.orbit())
            .chain(self.fold.iter().map(|f| &f.orbit))
            .map(reach)
            .fold(0.0, f64::max)
    }

    /// The model's values for the data set: its points, then its features.
    pub(super) fn values(&self, data: &SweepData) -> Vec<f64> {
        let fold_value = self
            .fold
            .as_ref()
            .map(|f| quantity_of(data.quantity, &f.orbit));
        let mut out: Vec<f64> = self
            .points
            .iter()
            .map(|(_, pm)| match pm {
                PointModel::Orbit(o) | PointModel::Nearest(o) => quantity_of(data.quantity, o),
                PointModel::AtFold => fold_value.unwrap_or(f64::NAN),
            })
            .collect();
        for f in &data.features {
            let e = match f.kind {
                FeatureKind::Onset => self.onset.as_ref(),
                FeatureKind::BranchEnd => self.end.as_ref(),
            };
            out.push(e.map_or(f64::NAN, |e| edge_value(e, self.fold.as_ref())));
        }
        if let Some(b) = &self.bracket {
            out.push(edge_value(b, self.fold.as_ref()));
        }
        out
    }
}

/// The coarse sweep in its order, with its onset and branch end.
struct Path {
    values: Vec<f64>,
    steps: Vec<SweepStep>,
    onset: Option<Transition>,
    contact_at_start: bool,
    /// (a jump, the transition).
    end: Option<(bool, Transition)>,
}

impl Path {
    /// The path of the plain sweep `run` of a data set.
    fn of(run: &SweepRun) -> Self {
        match run {
            SweepRun::Up(r) => Path {
                values: r.sweep.values.clone(),
                onset: r.onset,
                contact_at_start: r.contact_at_start,
                end: r
                    .branch_end()
                    .map(|e| (e.kind == BranchEndKind::Jump, e.transition)),
                steps: r.sweep.steps.clone(),
            },
            SweepRun::Down(r) => Path {
                values: r.sweep.values.clone(),
                onset: None,
                contact_at_start: false,
                end: r.branch_end().map(|(k, t)| (k == DownEndKind::Jump, t)),
                steps: r.sweep.steps.clone(),
            },
        }
    }

    /// The last coarse step at or before `f` in the sweep's order.
    fn before(&self, f: f64, dir: f64) -> usize {
        self.values
            .iter()
            .rposition(|&v| (v - f) * dir <= 1e-9 * f.abs())
            .unwrap_or(0)
    }

    /// The coarse step nearest `f`.
    fn nearest(&self, f: f64) -> usize {
        (0..self.values.len())
            .min_by(|&a, &b| {
                (self.values[a] - f)
                    .abs()
                    .total_cmp(&(self.values[b] - f).abs())
            })
            .expect("a sweep has steps")
    }

    fn any_contact(&self) -> bool {
        self.steps.iter().any(|s| in_contact(&s.measurement))
    }

    /// The grazing inside the transition `t` between a step without contact and one with.
    fn grazing(&self, h: &Harvester, s: &Setup, t: &Transition) -> Result<Grazing, Lost> {
        let k = self.before(t.before, s.dir);
        if k + 1 >= self.steps.len() {
            return Err(Lost("a transition at the sweep's last step".into()));
        }
        let (free, other) = if in_contact(&self.steps[k].measurement) {
            (k + 1, k)
        } else {
            (k, k + 1)
        };
        locate_grazing(
            h,
            s.accel_rms_g,
            self.values[free],
            nalgebra::SVector::from_column_slice(self.steps[free].state.as_slice()),
            self.values[other],
        )
    }
}

/// The model of `data` on `device` with the acceleration factor `scale`, identified from the
/// plain stepped sweep ([`SweepRun::plain`], see the module docs).
pub(super) fn identify(device: &Device, scale: f64, data: &SweepData) -> Result<SetModel, Lost> {
    let s = Setup::of(data, scale);
    let h = s.harvester(device)?;
    let path = Path::of(&SweepRun::plain(device, scale, data)?);
    let a = s.accel_rms_g;
    // The fold, when the sweep jumps, and the last coarse step before it. A branch that the
    // sweep leaves without a confirmed jump (a power drop below the sweep's criterion) may
    // still end at a fold just before the loss of contact: then the fold is its end.
    let has = |kind| data.features.iter().any(|f| f.kind == kind);
    let needs_fold = has(FeatureKind::BranchEnd) || !data.points.is_empty();
    let (fold, k_jump) = match path.end {
        Some((jump, t)) if needs_fold => {
            let k = path.before(t.before, s.dir);
            // The steps of the first branch up to the last before the transition.
            let before: Vec<Guess> = (0..=k)
                .map(|i| Guess {
                    freq_hz: path.values[i],
                    phase_rad: 0.0,
                    state: nalgebra::SVector::from_column_slice(path.steps[i].state.as_slice()),
                })
                .collect();
            let limit = if jump {
                s.fold_limit()
            } else {
                t.after + s.dir * s.step
            };
            // From the last step before the transition (a step short of its far end).
            let near = path.values[k] + s.dir * s.step;
            match locate_fold(&h, a, &before, near, s.dir, limit, s.step) {
                Ok(fold) => (Some(fold), Some(k)),
                Err(e) if jump => return Err(e),
                Err(_) => (None, None),
            }
        }
        _ => (None, None),
    };
    let onset = if has(FeatureKind::Onset) {
        Some(match &path.onset {
            Some(t) => Edge::Grazing(path.grazing(&h, &s, t)?),
            None if path.contact_at_start => Edge::Fixed(s.lo),
            None => Edge::Fixed(s.hi),
        })
    } else {
        None
    };
    // The end of the first branch: the fold, a grazing, or the grid's end it lies beyond (a
    // constant: the search cannot move it, and the rounds identify afresh).
    let end_edge = || -> Result<Edge, Lost> {
        Ok(match &path.end {
            Some(_) if fold.is_some() => Edge::Fold,
            Some((_, t)) => Edge::Grazing(path.grazing(&h, &s, t)?),
            None if s.dir > 0.0 && path.any_contact() => Edge::Fixed(s.hi),
            None => Edge::Fixed(s.lo),
        })
    };
    let end = if has(FeatureKind::BranchEnd) {
        Some(end_edge()?)
    } else {
        None
    };
    let jump = data.measured_jump();
    let bracket = match jump {
        Some(_) => Some(end_edge()?),
        None => None,
    };
    // Which branch a point lies on: the measurement says, by the jump its points show, else
    // by its stated branch end; else the stepped sweep at these values. The points come
    // first: a stated end has an uncertainty of its own, which can place it past a measured
    // frequency at which the points have already jumped.
    let measured_end = data.points_jump().map(|j| j.mid_hz()).or(data
        .features
        .iter()
        .find(|f| f.kind == FeatureKind::BranchEnd)
        .map(|f| f.freq_hz));
    let mut points = Vec::with_capacity(data.points.len());
    for p in &data.points {
        let f = p.freq_hz;
        let j = path.nearest(f);
        let step_orbit = |j: usize| {
            point_orbit(
                &h,
                f,
                a,
                0.0,
                nalgebra::SVector::from_column_slice(path.steps[j].state.as_slice()),
                1,
            )
        };
        let (Some(fold), Some(k)) = (&fold, k_jump) else {
            points.push((true, PointModel::Orbit(Box::new(step_orbit(j)?))));
            continue;
        };
        let first = match measured_end {
            Some(fm) => (f - fm) * s.dir < 0.0,
            None => j <= k,
        };
        let pm = if first {
            if fold.beyond(f) {
                PointModel::AtFold
            } else if j <= k {
                PointModel::Orbit(Box::new(step_orbit(j)?))
            } else {
                let g = fold.nearest(f);
                PointModel::Orbit(Box::new(point_orbit(&h, f, a, g.phase_rad, g.state, 1)?))
            }
        } else if j > k {
            PointModel::Orbit(Box::new(step_orbit(j)?))
        } else {
            second_branch_back(&h, a, &path, k, j, f)?
        };
        points.push((first, pm));
    }
    Ok(SetModel {
        onset,
        end,
        bracket,
        fold,
        points,
        device: device.clone(),
    })
}

/// A point the data place after the jump but the model before it (at `f`, nearest the coarse
/// step `j <= k`): the second branch followed back from the first step after the model's jump
/// (step `k + 1`); where that branch ends before reaching `f`, the orbit where it ends.
fn second_branch_back(
    h: &Harvester,
    a: f64,
    path: &Path,
    k: usize,
    j: usize,
    f: f64,
) -> Result<PointModel, Lost> {
    let start = nalgebra::SVector::from_column_slice(path.steps[k + 1].state.as_slice());
    let mut o = point_orbit(h, path.values[k + 1], a, 0.0, start, 1)
        .map_err(|e| Lost(format!("second branch at the jump: {}", e.0)))?;
    for i in (j..=k).rev() {
        let fi = if i == j { f } else { path.values[i] };
        match point_orbit(h, fi, a, o.phase_rad, o.state_n(), o.periods) {
            Ok(next) => o = next,
            Err(_) => return Ok(PointModel::Nearest(Box::new(o))),
        }
    }
    Ok(PointModel::Orbit(Box::new(o)))
}

/// The fold of `h` from the fold `f` at nearby parameter values: by Newton's method from
/// where it was, while no point of the first branch that lay beyond it comes to lie before
/// it; else (or where Newton's method loses it) by a continuation up to it. A point that
/// crosses the fold starts from the states before it, and those are fresh only from a
/// continuation (Newton's method keeps the old ones).
fn follow_fold(
    h: &Harvester,
    a: f64,
    s: &Setup,
    f: &Fold,
    data: &SweepData,
    points: &[(bool, PointModel)],
) -> Result<Fold, Lost> {
    if let Ok(new) = track_fold(h, a, f, s.fold_limit(), s.step) {
        let crossed = data.points.iter().zip(points).any(|(p, (first, pm))| {
            *first && matches!(pm, PointModel::AtFold) && !new.beyond(p.freq_hz)
        });
        if !crossed {
            return Ok(new);
        }
    }
    locate_fold(h, a, &f.before, f.freq_hz(), f.dir, s.fold_limit(), s.step)
}

/// The model of `data` on `device` with the acceleration factor `scale`, followed from the
/// model `prev` at nearby parameter values. An orbit of `prev` that the change of device
/// cannot move (it differs only in a stop the orbit stays clear of, [`clear`]) is kept as it
/// is.
pub(super) fn track(
    device: &Device,
    scale: f64,
    data: &SweepData,
    prev: &SetModel,
) -> Result<SetModel, Lost> {
    let s = Setup::of(data, scale);
    let h = s.harvester(device)?;
    let a = s.accel_rms_g;
    let unchanged = clear::unchanged(&prev.device, device);
    let kept = |o: &Orbit| unchanged.is_some_and(|u| u.keeps(o, a));
    let fold = match &prev.fold {
        Some(f) if kept(&f.orbit) => Some(f.clone()),
        Some(f) => Some(follow_fold(&h, a, &s, f, data, &prev.points)?),
        None => None,
    };
    let edge = |e: &Option<Edge>| -> Result<Option<Edge>, Lost> {
        Ok(match e {
            Some(Edge::Grazing(g)) => Some(Edge::Grazing(track_grazing(&h, a, g)?)),
            other => other.clone(),
        })
    };
    let onset = edge(&prev.onset)?;
    let end = edge(&prev.end)?;
    let bracket = edge(&prev.bracket)?;
    let mut points = Vec::with_capacity(prev.points.len());
    for (p, (first, pm)) in data.points.iter().zip(&prev.points) {
        let f = p.freq_hz;
        let ctx = |e: Lost| Lost(format!("point at {f} Hz: {}", e.0));
        let pm = match (&fold, first) {
            (Some(fold), true) if fold.beyond(f) => PointModel::AtFold,
            (_, _) if pm.orbit().is_some_and(kept) => pm.clone(),
            (Some(fold), true) => {
                let (ph, y, n) = match pm {
                    PointModel::Orbit(o) | PointModel::Nearest(o) => {
                        (o.phase_rad, o.state_n(), o.periods)
                    }
                    PointModel::AtFold => {
                        let g = fold.nearest(f);
                        (g.phase_rad, g.state, 1)
                    }
                };
                PointModel::Orbit(Box::new(point_orbit(&h, f, a, ph, y, n).map_err(ctx)?))
            }
            _ => match pm {
                PointModel::Orbit(o) => PointModel::Orbit(Box::new(
                    point_orbit(&h, f, a, o.phase_rad, o.state_n(), o.periods).map_err(ctx)?,
                )),
                PointModel::Nearest(o) => {
                    let fo = o.forcing.freq_hz;
                    PointModel::Nearest(Box::new(
                        point_orbit(&h, fo, a, o.phase_rad, o.state_n(), o.periods).map_err(ctx)?,
                    ))
                }
                PointModel::AtFold => return Err(Lost("a point at a fold that vanished".into())),
            },
        };
        points.push((*first, pm));
    }
    Ok(SetModel {
        onset,
        end,
        bracket,
        fold,
        points,
        device: device.clone(),
    })
}
