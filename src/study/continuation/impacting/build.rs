//! The whole diagram of a rigid-stop device: the non-impacting branch, its grazings, and the
//! impacting branches started from them and from one another (see the parent module).
//!
//! The module reads better whole: it is one worklist ([`rigid_diagram`] and its builder), in
//! which the end of each branch queues the branches that start there, so every case reads
//! beside the others it hands work to.

use std::collections::VecDeque;

use nalgebra::DVector;

use crate::device::Device;
use crate::model::Model;
use crate::num::roots::{illinois, RootOptions, Sample};
use crate::ode::Stats;
use crate::progress::{Progress, Silent};
use crate::study::continuation::diagram_types::orbit_point;
use crate::study::continuation::{continue_branch, first_orbit, ContinuationSettings};
use crate::study::orbit::{Forcing, Orbit, OrbitError, Parameter, Shooter};

use super::bvp::{side_stops, ImpactSequence, Problem};
use super::follow::{test_excursion, test_speed, Followed, Follower, Node};
use super::{
    BranchEnd, BranchKind, Diagram, DiagramBranch, DiagramEvent, DiagramPoint, EndKind, EventKind,
};

/// What the diagram follows beyond the period-one orbits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DiagramSettings {
    /// Follow the period-two branch from every period doubling.
    pub period_two: bool,
    /// Periods of transient before the first non-impacting orbit is shot from rest.
    pub transient_periods: usize,
    /// Most branches followed.
    pub max_branches: usize,
}

impl Default for DiagramSettings {
    fn default() -> Self {
        Self {
            period_two: false,
            transient_periods: 200,
            max_branches: 40,
        }
    }
}

/// The largest distance (in the continuation's scaled metric: state over its scales, the
/// parameter over its scale) of an orbit from a branch's polyline for the orbit to lie on it:
/// the chords' error between points a step apart is far below, and distinct branches of one
/// impact sequence lie far further apart away from the points where they meet.
const ON_BRANCH: f64 = 1e-2;

/// A branch to be followed: a solved chain (or close to one) and the directions to take.
pub(super) struct Start {
    pub seq: ImpactSequence,
    pub forcing: Forcing,
    pub z: DVector<f64>,
    /// Unit directions in (z, q); `None`: both orientations of the kernel.
    pub dirs: Option<Vec<DVector<f64>>>,
    /// The grazing node or branch it starts from, for the branches' `meets`.
    pub from: From,
    /// How the new branch's first end is described.
    pub kind: EndKind,
}

#[derive(Debug, Clone, Copy)]
pub(super) enum From {
    /// A grazing of the non-impacting orbit.
    Grazing(usize),
    /// The end of a branch.
    Branch(usize),
    /// A bifurcation inside a branch.
    Inside(usize),
    /// The orbit reached from rest: followed both ways into one branch.
    Rest,
}

/// A grazing of the non-impacting orbit, where impacting branches begin or end.
pub(super) struct GrazingNode {
    pub param: f64,
    pub point: DiagramPoint,
    /// The non-impacting branch whose end it is.
    pub branch: usize,
    /// The impacting branches that begin or end there.
    pub impacting: Vec<usize>,
}

/// The diagram of `device` under the drive `start` (whose parameter value is the settings'
/// start), continued over the settings' range (see the module docs of the parent). The
/// device's stops must all be rigid and all the first mass's to the frame (a named
/// [`OrbitError::Invalid`] otherwise). `progress` is told of each branch as it is begun.
pub fn rigid_diagram(
    device: &Device,
    start: Forcing,
    settings: &ContinuationSettings,
    options: &DiagramSettings,
    progress: &dyn Progress,
) -> Result<Diagram, OrbitError> {
    settings.validate()?;
    crate::with_harvester!(device, |h| rigid_diagram_of(
        &h, start, settings, options, progress
    ))
}

/// [`rigid_diagram`] on a model whose contacts are all rigid.
pub fn rigid_diagram_of<M: Model<N> + Clone, const N: usize>(
    h: &M,
    start: Forcing,
    settings: &ContinuationSettings,
    options: &DiagramSettings,
    progress: &dyn Progress,
) -> Result<Diagram, OrbitError> {
    let param = settings.parameter;
    let contacts = h.contacts();
    let present: Vec<_> = contacts.iter().filter(|c| c.gap.is_finite()).collect();
    if present.is_empty() || !present.iter().all(|c| c.rigid()) {
        return Err(OrbitError::Invalid(
            "the impacting-orbit diagram needs a device whose stops are all rigid".into(),
        ));
    }
    // Its grazings and impact maps are those of the first mass against the frame.
    if let Some(c) = present.iter().find(|c| c.mass != 0 || c.other.is_some()) {
        let (i, j) = (c.mass, c.other);
        let mass = |k: usize| h.layout().mass_name(k).unwrap_or("?").to_string();
        return Err(OrbitError::Invalid(format!(
            "the impacting-orbit diagram follows the first mass's stops to the frame only; \
             this model has a stop {}: continue its branch from rest instead",
            match j {
                Some(j) => format!("between `{}` and `{}`", mass(j), mass(i)),
                None => format!("from `{}` to the frame", mass(i)),
            }
        )));
    }
    let (lo, hi) = (
        settings.start.min(settings.stop),
        settings.start.max(settings.stop),
    );
    let free = h.without_contacts();
    let shooter = Shooter::new(&free, settings.shooting);
    let sym = h.mirror();
    let mut stats = Stats::default();
    progress.stage("non-impacting");
    let first = first_orbit(
        &shooter,
        &start,
        param,
        free.rest_state(),
        options.transient_periods,
        &mut stats,
    )?;
    let ni = continue_branch(&free, first, settings, &Silent)?;
    stats += ni.stats;
    let [(g_up, _), (g_lo, _)] = side_stops(h);
    let gaps = (g_up, g_lo);
    let reach = |o: &Orbit| (o.summary.x_upper_m - gaps.0).max(-o.summary.x_lower_m - gaps.1);

    let mut b = Builder {
        h,
        shooter: &shooter,
        sym,
        settings: *settings,
        options: *options,
        start,
        lo,
        hi,
        branches: Vec::new(),
        events: Vec::new(),
        grazings: Vec::new(),
        queue: VecDeque::new(),
        stats: Stats::default(),
    };
    // The real stretches of the non-impacting branch, each ended by its located grazings.
    let orbits: Vec<&Orbit> = ni.points.iter().map(|p| &p.orbit).collect();
    let mut run: Vec<DiagramPoint> = Vec::new();
    let mut run_start = BranchEnd {
        kind: EndKind::Range,
        param: orbits[0].param(param),
        residual: 0.0,
        meets: Vec::new(),
    };
    let mut pending_start_grazing: Option<usize> = None;
    for (i, o) in orbits.iter().enumerate() {
        let real = reach(o) <= 0.0;
        if real {
            run.push(b.ni_point(o)?);
        }
        let Some(next) = orbits.get(i + 1) else { break };
        if real == (reach(next) <= 0.0) {
            continue;
        }
        let g = b.locate_ni_grazing(o, next, &reach)?;
        let residual = reach(&g);
        let gp = b.ni_point(&g)?;
        let node = b.grazings.len();
        if real {
            run.push(gp.clone());
            let idx = b.branches.len();
            b.branches.push(DiagramBranch {
                kind: BranchKind::NonImpacting,
                label: "non-impacting".into(),
                points: std::mem::take(&mut run),
                start: run_start.clone(),
                end: BranchEnd {
                    kind: EndKind::NewContact,
                    param: g.param(param),
                    residual,
                    meets: Vec::new(),
                },
            });
            if let Some(n) = pending_start_grazing.take() {
                b.grazings[n].branch = idx;
            }
            b.grazings.push(GrazingNode {
                param: g.param(param),
                point: gp,
                branch: idx,
                impacting: Vec::new(),
            });
        } else {
            run.push(gp.clone());
            run_start = BranchEnd {
                kind: EndKind::NewContact,
                param: g.param(param),
                residual,
                meets: Vec::new(),
            };
            pending_start_grazing = Some(node);
            b.grazings.push(GrazingNode {
                param: g.param(param),
                point: gp,
                branch: usize::MAX,
                impacting: Vec::new(),
            });
        }
        b.grazing_starts(node, &g)?;
    }
    if run.len() >= 2 {
        let idx = b.branches.len();
        let end_param = run.last().map_or(0.0, |p| p.forcing.get(param));
        b.branches.push(DiagramBranch {
            kind: BranchKind::NonImpacting,
            label: "non-impacting".into(),
            points: run,
            start: run_start,
            end: BranchEnd {
                kind: EndKind::Range,
                param: end_param,
                residual: 0.0,
                meets: Vec::new(),
            },
        });
        if let Some(n) = pending_start_grazing {
            b.grazings[n].branch = idx;
        }
    }
    b.drain(progress);
    // The orbits reached from rest at either end of the range, unless on a branch already
    // followed (an impacting branch that meets no grazing inside the range).
    for at in [settings.start, settings.stop] {
        if let Some(s) = b.seed_from_rest(at) {
            b.queue.push_back(s);
            b.drain(progress);
        }
    }
    b.finish(stats)
}

pub(super) struct Builder<'a, M, const N: usize> {
    pub h: &'a M,
    /// Shooting on the device without its stops (the non-impacting branch).
    pub shooter: &'a Shooter<'a, M, N>,
    pub sym: Option<nalgebra::SMatrix<f64, N, N>>,
    pub settings: ContinuationSettings,
    pub options: DiagramSettings,
    /// The drive at the start of the range.
    pub start: Forcing,
    pub lo: f64,
    pub hi: f64,
    pub branches: Vec<DiagramBranch>,
    pub events: Vec<DiagramEvent>,
    pub grazings: Vec<GrazingNode>,
    pub queue: VecDeque<Start>,
    pub stats: Stats,
}

impl<M: Model<N> + Clone, const N: usize> Builder<'_, M, N> {
    /// Follows every queued start (and what they lead to) up to the budget of branches.
    fn drain(&mut self, progress: &dyn Progress) {
        while let Some(s) = self.queue.pop_front() {
            if self.branches.len() >= self.options.max_branches {
                self.queue.clear();
                break;
            }
            progress.stage(&s.seq.describe());
            self.follow_start(s);
        }
    }

    pub(super) fn param(&self) -> Parameter {
        self.settings.parameter
    }

    /// A non-impacting orbit as a point of the diagram (with its half-period map on a
    /// symmetric device).
    fn ni_point(&mut self, o: &Orbit) -> Result<DiagramPoint, OrbitError> {
        let mut p = orbit_point(self.shooter, o, self.sym.is_some(), &mut self.stats)?;
        // Measured from the device's stops (the shooter's model has none).
        let [(g_up, _), (g_lo, _)] = side_stops(self.h);
        p.clearance_m = (g_up - o.summary.x_upper_m).min(g_lo + o.summary.x_lower_m);
        Ok(p)
    }

    /// The grazing between two orbits of the non-impacting branch on either side of it, by
    /// the root finder on the parameter (each evaluation an orbit shot at a fixed value).
    fn locate_ni_grazing(
        &mut self,
        a: &Orbit,
        b: &Orbit,
        reach: &dyn Fn(&Orbit) -> f64,
    ) -> Result<Orbit, OrbitError> {
        let param = self.param();
        let (pa, pb) = (a.param(param), b.param(param));
        let opts = RootOptions {
            f_tol: None,
            x_tol_abs: 1e-10 * pa.abs().max(pb.abs()),
            x_tol_rel: 0.0,
            max_iter: 80,
        };
        let mut best = if reach(a).abs() <= reach(b).abs() {
            a.clone()
        } else {
            b.clone()
        };
        let shooter = self.shooter;
        let stats = &mut self.stats;
        let root = illinois(
            |p| -> Result<(f64, ()), OrbitError> {
                let from = if (p - pa).abs() <= (p - pb).abs() {
                    a
                } else {
                    b
                };
                let f = from.forcing.with(param, p);
                let o = shooter.solve(&f, param, from.phase_rad, from.state_n(), stats)?;
                let v = reach(&o);
                if v.abs() < reach(&best).abs() {
                    best = o;
                }
                Ok((v, ()))
            },
            Sample::new(pa, reach(a), ()),
            Sample::new(pb, reach(b), ()),
            &opts,
        );
        match root {
            Ok(_) => Ok(best),
            Err(crate::num::roots::RootError::Eval(e)) => Err(e),
            Err(_) => Ok(best),
        }
    }

    /// The distance, in the continuation's metric (the parameter over its scale and the
    /// fingerprint over the state scales), from a point to the nearest segment of a branch's
    /// polyline.
    fn distance_to(&self, branch: &DiagramBranch, p: &DiagramPoint) -> f64 {
        let v = |q: &DiagramPoint| {
            let sc = self.h.scales();
            let mut out = [0.0; 5];
            out[0] = q.forcing.get(self.param()) / self.settings.param_scale;
            for i in 0..4 {
                out[1 + i] = q.fingerprint[i] / sc[i];
            }
            out
        };
        let x = v(p);
        let mut best = f64::INFINITY;
        for w in branch.points.windows(2) {
            let (a, b) = (v(&w[0]), v(&w[1]));
            let ab: Vec<f64> = (0..5).map(|i| b[i] - a[i]).collect();
            let ax: Vec<f64> = (0..5).map(|i| x[i] - a[i]).collect();
            let l2: f64 = ab.iter().map(|c| c * c).sum();
            let t = if l2 > 0.0 {
                (ab.iter().zip(&ax).map(|(p, q)| p * q).sum::<f64>() / l2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let d: f64 = (0..5)
                .map(|i| (ax[i] - t * ab[i]).powi(2))
                .sum::<f64>()
                .sqrt();
            best = best.min(d);
        }
        best
    }

    /// The scaled distance between two points in the same metric.
    fn gap_between(&self, a: &DiagramPoint, b: &DiagramPoint) -> f64 {
        let sc = self.h.scales();
        let dq =
            (a.forcing.get(self.param()) - b.forcing.get(self.param())) / self.settings.param_scale;
        let mut s = dq * dq;
        for i in 0..4 {
            s += ((a.fingerprint[i] - b.fingerprint[i]) / sc[i]).powi(2);
        }
        s.sqrt()
    }

    /// Follows a start in each of its directions whose first step is a real orbit not on a
    /// branch already followed.
    fn follow_start(&mut self, s: Start) {
        let param = self.param();
        let Ok(problem) = Problem::new(self.h, s.seq.clone(), param, self.settings.shooting.rtol)
        else {
            return;
        };
        let watch = problem.asymmetry(&s.z).is_finite();
        let mut fol = Follower {
            problem: &problem,
            settings: self.settings,
            watch_asymmetry: watch,
            stats: Stats::default(),
        };
        let m = s.z.len();
        let mut u0 = DVector::zeros(m + 1);
        u0.rows_mut(0, m).copy_from(&s.z);
        u0[m] = s.forcing.get(param) / self.settings.param_scale;
        let mut eq = DVector::zeros(m + 1);
        eq[m] = 1.0;
        // The chain solved at the start's parameter value.
        let Some((start, _)) = fol.correct(&s.forcing, &u0, &eq, 0.0) else {
            self.stats += fol.stats;
            return;
        };
        let dirs = s
            .dirs
            .clone()
            .unwrap_or_else(|| vec![start.t.clone(), -start.t.clone()]);
        let probe_ds = 0.05 * self.settings.ds_init;
        let mut followed = Vec::new();
        for d in dirs {
            let mut n0 = start.clone();
            n0.t = d.normalize();
            let Some((probe, _)) = fol.step(&n0, probe_ds) else {
                continue;
            };
            if !super::follow::admissible(&probe) {
                continue;
            }
            let on = if matches!(s.from, From::Rest) {
                // The orbit from rest lies inside a branch already followed, if at all: the
                // start itself is on its polyline, to the chords' error.
                self.on_branch(&s.seq, &n0.point)
            } else {
                self.duplicate_of(&s.seq, &probe.point, &n0.point)
            };
            if let Some(k) = on {
                self.note_meeting(s.from, k);
                if matches!(s.from, From::Rest) {
                    // The orbit from rest lies on a branch already followed.
                    self.stats += fol.stats;
                    return;
                }
                continue;
            }
            let f = fol.follow(n0, self.lo, self.hi);
            if matches!(s.from, From::Rest) {
                followed.push(f);
            } else {
                self.add_branch(&s, &problem, None, f, watch);
            }
        }
        if matches!(s.from, From::Rest) && !followed.is_empty() {
            let fwd = followed.remove(0);
            self.add_branch(&s, &problem, followed.pop(), fwd, watch);
        }
        self.stats += fol.stats;
    }

    /// The branch already followed that passes through `p` (the same impacts on each side and
    /// periods, and `p` within [`ON_BRANCH`] of its polyline in the continuation's metric).
    fn on_branch(&self, seq: &ImpactSequence, p: &DiagramPoint) -> Option<usize> {
        let sides = seq.impacts_per_side();
        self.branches.iter().position(|b| match &b.kind {
            BranchKind::Impacting(q) => {
                q.impacts_per_side() == sides
                    && q.periods() == seq.periods()
                    && self.distance_to(b, p) < ON_BRANCH
            }
            BranchKind::NonImpacting | BranchKind::Continued | BranchKind::Stepped => false,
        })
    }

    /// The branch already followed on which `probe` (a small step from `start`) lies: the
    /// same impacts on each side and periods, and the probe on its polyline (far closer to
    /// it than to the start).
    fn duplicate_of(
        &self,
        seq: &ImpactSequence,
        probe: &DiagramPoint,
        start: &DiagramPoint,
    ) -> Option<usize> {
        let moved = self.gap_between(probe, start);
        let sides = seq.impacts_per_side();
        self.branches.iter().position(|b| match &b.kind {
            BranchKind::Impacting(q) => {
                q.impacts_per_side() == sides
                    && q.periods() == seq.periods()
                    && self.distance_to(b, probe) < 0.05 * moved
            }
            BranchKind::NonImpacting | BranchKind::Continued | BranchKind::Stepped => false,
        })
    }

    fn note_meeting(&mut self, from: From, k: usize) {
        match from {
            From::Grazing(n) => {
                if !self.grazings[n].impacting.contains(&k) {
                    self.grazings[n].impacting.push(k);
                }
            }
            From::Branch(j) => {
                // Branch j's end lies on branch k.
                if !self.branches[j].end.meets.contains(&k) {
                    self.branches[j].end.meets.push(k);
                }
            }
            From::Inside(_) | From::Rest => {}
        }
    }

    /// Adds a followed branch (from a start on the orbit from rest, its two halves, `back`
    /// reversed before `fwd`), its events, and the starts its ends lead to.
    fn add_branch(
        &mut self,
        s: &Start,
        problem: &Problem<'_, M, N>,
        back: Option<Followed>,
        fwd: Followed,
        watch: bool,
    ) {
        let param = self.param();
        let idx = self.branches.len();
        let first = &fwd.nodes[0];
        let last = fwd.nodes.last().expect("a followed branch has a node");
        let end_of = |f: &Followed| {
            let n = f.nodes.last().expect("a followed branch has a node");
            BranchEnd {
                kind: f.ending.kind,
                param: n.forcing.get(param),
                residual: f.ending.residual,
                meets: Vec::new(),
            }
        };
        let mut start_end = match &back {
            Some(b) => end_of(b),
            None => BranchEnd {
                kind: s.kind,
                param: first.forcing.get(param),
                residual: match s.kind {
                    EndKind::Grazing => test_speed(first),
                    EndKind::NewContact => test_excursion(first),
                    _ => 0.0,
                },
                meets: Vec::new(),
            },
        };
        match s.from {
            From::Grazing(n) => {
                self.grazings[n].impacting.push(idx);
                start_end.meets.push(self.grazings[n].branch);
            }
            From::Branch(j) => {
                start_end.meets.push(j);
                if !self.branches[j].end.meets.contains(&idx) {
                    self.branches[j].end.meets.push(idx);
                }
            }
            From::Inside(j) => start_end.meets.push(j),
            From::Rest => {}
        }
        let label = {
            let base = s.seq.describe();
            let base = if watch {
                format!("asymmetric, {base}")
            } else {
                base
            };
            let same = self
                .branches
                .iter()
                .filter(|b| b.label.starts_with(&base))
                .count();
            if same == 0 {
                base
            } else {
                format!("{base} #{}", same + 1)
            }
        };
        let mut nodes: Vec<&Node> = Vec::new();
        if let Some(b) = &back {
            nodes.extend(b.nodes.iter().skip(1).rev());
        }
        nodes.extend(fwd.nodes.iter());
        self.branches.push(DiagramBranch {
            kind: BranchKind::Impacting(s.seq.clone()),
            label,
            points: nodes.iter().map(|n| n.point.clone()).collect(),
            start: start_end,
            end: end_of(&fwd),
        });
        for f in back.iter().chain(std::iter::once(&fwd)) {
            for e in &f.events {
                self.events.push(DiagramEvent {
                    kind: e.kind,
                    param: e.node.forcing.get(param),
                    point: e.node.point.clone(),
                    branches: vec![idx],
                    stable: vec![e.stable_before, e.stable_after],
                    corner: false,
                    contact: None,
                    strikes: None,
                });
                self.starts_at_event(idx, problem, e);
            }
        }
        if let Some(b) = &back {
            let n = b.nodes.last().expect("a followed branch has a node");
            self.starts_at_end(idx, problem, n, b.ending.kind);
        }
        self.starts_at_end(idx, problem, last, fwd.ending.kind);
    }

    /// The grazing events and the meetings of the branches at them; events sorted.
    fn finish(mut self, ni_stats: Stats) -> Result<Diagram, OrbitError> {
        let param = self.param();
        for g in &self.grazings {
            let mut branches = Vec::new();
            if g.branch != usize::MAX {
                branches.push(g.branch);
            }
            branches.extend(g.impacting.iter().copied());
            branches.dedup();
            let stable = branches
                .iter()
                .map(|&b| {
                    let pts = &self.branches[b].points;
                    // The point next to the grazing: the second from whichever end is nearer.
                    let near_start = (pts[0].forcing.get(param) - g.param).abs()
                        <= (pts[pts.len() - 1].forcing.get(param) - g.param).abs();
                    let k = if near_start {
                        1.min(pts.len() - 1)
                    } else {
                        pts.len().saturating_sub(2)
                    };
                    pts[k].is_stable()
                })
                .collect();
            self.events.push(DiagramEvent {
                kind: EventKind::Grazing,
                param: g.param,
                point: g.point.clone(),
                branches,
                stable,
                corner: false,
                contact: None,
                strikes: None,
            });
        }
        for (i, g) in self.grazings.iter().enumerate() {
            let _ = i;
            if g.branch == usize::MAX {
                continue;
            }
            let ni = g.branch;
            for &b in &g.impacting {
                let near_start = (self.branches[ni].start.param - g.param).abs()
                    < (self.branches[ni].end.param - g.param).abs();
                let end = if near_start {
                    &mut self.branches[ni].start
                } else {
                    &mut self.branches[ni].end
                };
                if !end.meets.contains(&b) {
                    end.meets.push(b);
                }
            }
        }
        self.events.sort_by(|a, b| a.param.total_cmp(&b.param));
        let mut stats = ni_stats;
        stats += self.stats;
        Ok(Diagram {
            parameter: param,
            branches: self.branches,
            events: self.events,
            stats,
        })
    }
}
