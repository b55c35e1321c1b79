//! The whole diagram of a rigid-stop device: the non-impacting branch, its grazings, and the
//! impacting branches started from them and from one another (see the parent module).

use std::collections::VecDeque;

use nalgebra::{DMatrix, DVector};

use crate::device::Device;
use crate::drive::Sine;
use crate::num::roots::{illinois, RootOptions, Sample};
use crate::ode::Stats;
use crate::physics::contact::{Side, StopModel};
use crate::physics::harvester::Harvester;
use crate::study::continuation::{continue_branch, first_orbit, ContinuationSettings};
use crate::study::orbit::{mirror, Forcing, Orbit, OrbitError, Parameter, Shooter};

use super::bvp::{Closure, ImpactSequence, Problem};
use super::follow::{Follower, Found, Node};
use super::segment::fly;
use super::{
    BranchEnd, BranchKind, Diagram, DiagramBranch, DiagramEvent, DiagramPoint, EndKind, EventKind,
};

/// What the diagram follows beyond the period-one orbits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DiagramOptions {
    /// Follow the period-two branch from every period doubling.
    pub period_two: bool,
    /// Periods of transient before the first non-impacting orbit is shot from rest.
    pub transient_periods: usize,
    /// Most branches followed.
    pub max_branches: usize,
}

impl Default for DiagramOptions {
    fn default() -> Self {
        Self {
            period_two: false,
            transient_periods: 200,
            max_branches: 40,
        }
    }
}

/// A branch to be followed: a solved chain (or close to one) and the directions to take.
struct Start {
    seq: ImpactSequence,
    forcing: Forcing,
    z: DVector<f64>,
    /// Unit directions in (z, q); `None`: both orientations of the kernel.
    dirs: Option<Vec<DVector<f64>>>,
    /// The grazing node or branch it starts from, for the branches' `meets`.
    from: From,
    /// How the new branch's first end is described.
    kind: EndKind,
}

#[derive(Debug, Clone, Copy)]
enum From {
    /// A grazing of the non-impacting orbit.
    Grazing(usize),
    /// The end of a branch.
    Branch(usize),
    /// A bifurcation inside a branch.
    Inside(usize),
}

/// A grazing of the non-impacting orbit, where impacting branches begin or end.
struct GrazingNode {
    param: f64,
    point: DiagramPoint,
    /// The non-impacting branch whose end it is.
    branch: usize,
    /// The impacting branches that begin or end there.
    impacting: Vec<usize>,
}

/// The diagram of `device` under the drive `start` (whose parameter value is the settings'
/// start), continued over the settings' range (see the module docs of the parent). The
/// device's stops must all be rigid. `progress` is told of each branch as it is begun.
pub fn rigid_diagram(
    device: &Device,
    start: Forcing,
    settings: &ContinuationSettings,
    options: &DiagramOptions,
    mut progress: impl FnMut(&str),
) -> Result<Diagram, OrbitError> {
    settings.validate()?;
    let param = settings.parameter;
    let h = Harvester::new(device, start.sine(0.0));
    let stops: Vec<_> = [h.upper, h.lower].into_iter().flatten().collect();
    if stops.is_empty() || !stops.iter().all(|s| matches!(s, StopModel::Rigid { .. })) {
        return Err(OrbitError::Invalid(
            "the impacting-orbit diagram needs a device whose stops are all rigid".into(),
        ));
    }
    let (lo, hi) = (
        settings.start.min(settings.stop),
        settings.start.max(settings.stop),
    );
    let free = h.without_stops();
    let shooter = Shooter::new(&free, settings.shooting);
    let sym = mirror(&h);
    let mut stats = Stats::default();
    progress("non-impacting");
    let first = first_orbit(
        &shooter,
        &start,
        param,
        free.rest_state(),
        options.transient_periods,
        &mut stats,
    )?;
    let ni = continue_branch(&free, first, settings, |_| {})?;
    stats += ni.stats;
    let gaps = (h.gap(Side::Upper), h.gap(Side::Lower));
    let reach = |o: &Orbit| (o.summary.x_upper_m - gaps.0).max(-o.summary.x_lower_m - gaps.1);

    let mut b = Builder {
        h: &h,
        shooter: &shooter,
        sym,
        settings: *settings,
        options: *options,
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
    while let Some(s) = b.queue.pop_front() {
        if b.branches.len() >= options.max_branches {
            break;
        }
        progress(&s.seq.describe());
        b.follow_start(s);
    }
    b.finish(stats)
}

struct Builder<'a> {
    h: &'a Harvester<Sine>,
    /// Shooting on the device without its stops (the non-impacting branch).
    shooter: &'a Shooter<'a>,
    sym: Option<nalgebra::Matrix4<f64>>,
    settings: ContinuationSettings,
    options: DiagramOptions,
    lo: f64,
    hi: f64,
    branches: Vec<DiagramBranch>,
    events: Vec<DiagramEvent>,
    grazings: Vec<GrazingNode>,
    queue: VecDeque<Start>,
    stats: Stats,
}

impl Builder<'_> {
    fn param(&self) -> Parameter {
        self.settings.parameter
    }

    /// A non-impacting orbit as a point of the diagram.
    fn ni_point(&mut self, o: &Orbit) -> Result<DiagramPoint, OrbitError> {
        let half = if self.sym.is_some() {
            self.shooter.half_map(o, &mut self.stats)?
        } else {
            None
        };
        let fingerprint = self
            .shooter
            .state_at_phase(o, 0.0)
            .map_err(|e| OrbitError::Solver {
                what: self.param().label(),
                param: o.param(self.param()),
                source: e,
            })?;
        let w = 2.0 * std::f64::consts::PI * o.forcing.freq_hz;
        let section = o.summary.upcrossing_s.map(|t| {
            let phase = (o.phase_rad + w * t).rem_euclid(2.0 * std::f64::consts::PI);
            (phase, o.state)
        });
        Ok(DiagramPoint {
            forcing: o.forcing,
            periods: 1,
            multipliers: o.multipliers,
            half_multipliers: half.map(|h| h.multipliers),
            summary: o.summary,
            section,
            impact_speeds_m_s: Vec::new(),
            symmetric: half.is_some(),
            residual: o.residual,
            fingerprint,
        })
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
                let o = shooter.solve(&f, param, from.phase_rad, from.state, stats)?;
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

    /// The impacting branches that begin at a grazing of the non-impacting orbit: one impact
    /// at each stop it grazes, and the symmetric orbit where it grazes both of a symmetric
    /// device.
    fn grazing_starts(&mut self, node: usize, g: &Orbit) -> Result<(), OrbitError> {
        let param = self.param();
        let f = g.forcing;
        let w = 2.0 * std::f64::consts::PI * f.freq_hz;
        let model = self.h.without_stops().with_excitation(f.sine(g.phase_rad));
        let fl = fly(
            &model,
            param,
            g.state,
            f.period_s(),
            self.settings.shooting.rtol,
            &self.h.scales(),
            &[],
            &mut self.stats,
        )
        .map_err(|e| OrbitError::Solver {
            what: param.label(),
            param: g.param(param),
            source: e,
        })?;
        let top = fl
            .extrema
            .iter()
            .filter(|x| x.maximum)
            .max_by(|a, b| a.state[0].total_cmp(&b.state[0]));
        let bottom = fl
            .extrema
            .iter()
            .filter(|x| !x.maximum)
            .min_by(|a, b| a.state[0].total_cmp(&b.state[0]));
        let tol = 1e-6 * self.h.x_scale();
        let mut grazed = Vec::new();
        if let Some(x) = top.filter(|x| (x.state[0] - self.h.gap(Side::Upper)).abs() <= tol) {
            grazed.push((Side::Upper, *x));
        }
        if let Some(x) = bottom.filter(|x| (-x.state[0] - self.h.gap(Side::Lower)).abs() <= tol) {
            grazed.push((Side::Lower, *x));
        }
        for (side, x) in &grazed {
            let seq = ImpactSequence {
                sides: vec![*side],
                closure: Closure::Periodic(1),
            };
            let mut z = DVector::zeros(self.h.active_states());
            let problem = Problem::new(self.h, seq.clone(), param, self.settings.shooting.rtol)
                .map_err(OrbitError::Invalid)?;
            problem.pack(&mut z, 0, g.phase_rad + w * x.t, &x.state);
            self.queue.push_back(Start {
                seq,
                forcing: f,
                z,
                dirs: None,
                from: From::Grazing(node),
                kind: EndKind::Grazing,
            });
        }
        if grazed.len() == 2 && self.sym.is_some() {
            let (side, x) = grazed[0];
            let seq = ImpactSequence {
                sides: vec![side],
                closure: Closure::Mirror,
            };
            let problem = Problem::new(self.h, seq.clone(), param, self.settings.shooting.rtol)
                .map_err(OrbitError::Invalid)?;
            let mut z = DVector::zeros(self.h.active_states());
            problem.pack(&mut z, 0, g.phase_rad + w * x.t, &x.state);
            self.queue.push_back(Start {
                seq,
                forcing: f,
                z,
                dirs: None,
                from: From::Grazing(node),
                kind: EndKind::Grazing,
            });
        }
        Ok(())
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
        for d in dirs {
            let mut n0 = start.clone();
            n0.t = d.normalize();
            let Some((probe, _)) = fol.step(&n0, probe_ds) else {
                continue;
            };
            if !Follower::admissible(&probe) {
                continue;
            }
            let moved = self.gap_between(&probe.point, &n0.point);
            // A branch already followed passes here: the same impacts on each side, and
            // the probe on its polyline (far closer to it than to the start).
            let sides = s.seq.impacts_per_side();
            let duplicate = self
                .branches
                .iter()
                .enumerate()
                .find(|(_, b)| match &b.kind {
                    BranchKind::Impacting(q) => {
                        q.impacts_per_side() == sides
                            && q.periods() == s.seq.periods()
                            && self.distance_to(b, &probe.point) < 0.05 * moved
                    }
                    BranchKind::NonImpacting | BranchKind::Continued => false,
                });
            if let Some((k, _)) = duplicate {
                self.note_meeting(s.from, k);
                continue;
            }
            let followed = fol.follow(n0, self.lo, self.hi);
            self.add_branch(&s, &problem, followed, watch);
        }
        self.stats += fol.stats;
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
            From::Inside(_) => {}
        }
    }

    /// Adds a followed branch, its events, and the starts its end leads to.
    fn add_branch(
        &mut self,
        s: &Start,
        problem: &Problem<'_>,
        f: super::follow::Followed,
        watch: bool,
    ) {
        let param = self.param();
        let idx = self.branches.len();
        let first = &f.nodes[0];
        let last = f.nodes.last().expect("a followed branch has a node");
        let mut start_end = BranchEnd {
            kind: s.kind,
            param: first.forcing.get(param),
            residual: match s.kind {
                EndKind::Grazing => super::follow::test_speed(first),
                EndKind::NewContact => super::follow::test_excursion(first),
                _ => 0.0,
            },
            meets: Vec::new(),
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
        }
        let end = BranchEnd {
            kind: f.ending.kind,
            param: last.forcing.get(param),
            residual: f.ending.residual,
            meets: Vec::new(),
        };
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
        self.branches.push(DiagramBranch {
            kind: BranchKind::Impacting(s.seq.clone()),
            label,
            points: f.nodes.iter().map(|n| n.point.clone()).collect(),
            start: start_end,
            end,
        });
        for e in &f.events {
            self.events.push(DiagramEvent {
                kind: e.kind,
                param: e.node.forcing.get(param),
                point: e.node.point.clone(),
                branches: vec![idx],
                stable: vec![e.stable_before, e.stable_after],
                corner: false,
            });
            self.starts_at_event(idx, problem, e);
        }
        self.starts_at_end(idx, problem, last, f.ending.kind);
    }

    /// The branch a smooth event leads to: the asymmetric pair at a symmetry-breaking
    /// pitchfork, the period-two branch at a period doubling.
    fn starts_at_event(&mut self, idx: usize, problem: &Problem<'_>, e: &Found) {
        let n = &e.node;
        let seq = &problem.seq;
        let (new_seq, z, both) = match (e.kind, seq.closure) {
            (EventKind::SymmetryBreaking, Closure::Mirror) => {
                let s = self.sym.expect("a symmetric chain has the mirror");
                let mut sides = seq.sides.clone();
                sides.extend(seq.sides.iter().map(|x| match x {
                    Side::Upper => Side::Lower,
                    Side::Lower => Side::Upper,
                }));
                let new_seq = ImpactSequence {
                    sides,
                    closure: Closure::Periodic(1),
                };
                let k = seq.len();
                let mut z = DVector::zeros(2 * n.z.len());
                let Ok(full) = Problem::new(self.h, new_seq.clone(), self.param(), problem.rtol)
                else {
                    return;
                };
                for i in 0..k {
                    let y = problem.pre_state(&n.z, i);
                    let ph = problem.phase(&n.z, i);
                    full.pack(&mut z, i, ph, &y);
                    full.pack(&mut z, i + k, ph + std::f64::consts::PI, &(s * y));
                }
                (new_seq, z, true)
            }
            (EventKind::PeriodDoubling, Closure::Periodic(1)) if self.options.period_two => {
                let mut sides = seq.sides.clone();
                sides.extend(seq.sides.iter().copied());
                let new_seq = ImpactSequence {
                    sides,
                    closure: Closure::Periodic(2),
                };
                let k = seq.len();
                let mut z = DVector::zeros(2 * n.z.len());
                let Ok(full) = Problem::new(self.h, new_seq.clone(), self.param(), problem.rtol)
                else {
                    return;
                };
                for i in 0..k {
                    let y = problem.pre_state(&n.z, i);
                    let ph = problem.phase(&n.z, i);
                    full.pack(&mut z, i, ph, &y);
                    full.pack(&mut z, i + k, ph + 2.0 * std::f64::consts::PI, &y);
                }
                (new_seq, z, false)
            }
            _ => return,
        };
        let Ok(full) = Problem::new(self.h, new_seq.clone(), self.param(), problem.rtol) else {
            return;
        };
        let Ok(ev) = full.evaluate(&n.forcing, &z, &mut self.stats) else {
            return;
        };
        let Some(w) = null_vector(&ev.jz) else { return };
        let mut d = DVector::zeros(z.len() + 1);
        d.rows_mut(0, z.len()).copy_from(&w);
        let dirs = if both { vec![d.clone(), -d] } else { vec![d] };
        self.queue.push_back(Start {
            seq: new_seq,
            forcing: n.forcing,
            z,
            dirs: Some(dirs),
            from: From::Inside(idx),
            kind: EndKind::Bifurcation,
        });
    }

    /// The branch the end of branch `idx` leads to.
    fn starts_at_end(&mut self, idx: usize, problem: &Problem<'_>, last: &Node, kind: EndKind) {
        let seq = &problem.seq;
        let param = self.param();
        let n = seq.len();
        let d = problem.d;
        match kind {
            EndKind::Grazing if n == 1 => {
                // The orbit loses its only impact: the non-impacting orbit's grazing.
                let p = last.forcing.get(param);
                let near = self
                    .grazings
                    .iter()
                    .enumerate()
                    .min_by(|a, b| (a.1.param - p).abs().total_cmp(&(b.1.param - p).abs()));
                if let Some((g, node)) = near {
                    if (node.param - p).abs() <= self.settings.max_param_step {
                        self.grazings[g].impacting.push(idx);
                        let ni = self.grazings[g].branch;
                        self.branches[idx].end.meets.push(ni);
                    }
                }
            }
            EndKind::Grazing => {
                let k = (0..n)
                    .min_by(|a, b| last.info.speeds_m_s[*a].total_cmp(&last.info.speeds_m_s[*b]))
                    .expect("a chain has an impact");
                // Without the impact whose speed vanished: its flight now touches the stop
                // there, so the new branch starts at a new contact.
                let mut sides = seq.sides.clone();
                sides.remove(k);
                let new_seq = ImpactSequence {
                    sides,
                    closure: seq.closure,
                };
                let mut z = DVector::zeros((n - 1) * d);
                let mut j = 0;
                for i in 0..n {
                    if i == k {
                        continue;
                    }
                    z.rows_mut(j * d, d).copy_from(&last.z.rows(i * d, d));
                    j += 1;
                }
                self.queue.push_back(Start {
                    seq: new_seq,
                    forcing: last.forcing,
                    z,
                    dirs: None,
                    from: From::Branch(idx),
                    kind: EndKind::NewContact,
                });
            }
            EndKind::NewContact => {
                let Some((k, t, side, y)) = last.info.excursion_at else {
                    return;
                };
                // With an impact where the flight touches the stop, at zero speed: the new
                // branch starts at a grazing impact.
                let w = 2.0 * std::f64::consts::PI * last.forcing.freq_hz;
                let mut sides = seq.sides.clone();
                sides.insert(k + 1, side);
                let new_seq = ImpactSequence {
                    sides,
                    closure: seq.closure,
                };
                let Ok(p2) = Problem::new(self.h, new_seq.clone(), param, problem.rtol) else {
                    return;
                };
                let mut z = DVector::zeros((n + 1) * d);
                let mut j = 0;
                for i in 0..n {
                    z.rows_mut(j * d, d).copy_from(&last.z.rows(i * d, d));
                    j += 1;
                    if i == k {
                        p2.pack(&mut z, j, problem.phase(&last.z, k) + w * t, &y);
                        j += 1;
                    }
                }
                self.queue.push_back(Start {
                    seq: new_seq,
                    forcing: last.forcing,
                    z,
                    dirs: None,
                    from: From::Branch(idx),
                    kind: EndKind::Grazing,
                });
            }
            EndKind::Symmetric => {
                // Back on the symmetric orbits: their branch, if not followed yet.
                let h = n / 2;
                let new_seq = ImpactSequence {
                    sides: seq.sides[..h].to_vec(),
                    closure: Closure::Mirror,
                };
                let z = last.z.rows(0, h * d).into_owned();
                self.queue.push_back(Start {
                    seq: new_seq,
                    forcing: last.forcing,
                    z,
                    dirs: None,
                    from: From::Branch(idx),
                    kind: EndKind::Bifurcation,
                });
            }
            _ => {}
        }
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

/// The unit vector spanning the (numerical) kernel of a square matrix: the right singular
/// vector of its smallest singular value.
fn null_vector(j: &DMatrix<f64>) -> Option<DVector<f64>> {
    let svd = j.clone().svd(false, true);
    let v_t = svd.v_t?;
    let (k, _) = svd
        .singular_values
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(b.1))?;
    Some(v_t.row(k).transpose().normalize())
}
