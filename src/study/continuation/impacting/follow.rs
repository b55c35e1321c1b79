//! Pseudo-arclength continuation of one branch of impacting orbits ([`super::bvp`]): Newton on
//! the bordered system, steps that grow and shrink, the test functions of its events, and
//! their location on the branch.
//!
//! A branch ends where its orbits stop being real (an impact speed reaches zero, or a flight
//! reaches a stop: a grazing, located to the continuation's tolerance and reported with the
//! residual impact speed or excursion there), where an asymmetric branch reaches the
//! symmetric orbits it bifurcated from, or past the range. Along it, and only between two of
//! its own points (never across a grazing, where the multipliers diverge), the smooth
//! events are located: folds (the parameter turns), branch points (a multiplier crosses +1
//! where the branch does not turn), period doublings (-1), torus bifurcations (a complex
//! pair), and on a symmetric branch the symmetry-breaking pitchfork (-1 of the half-period
//! map).

use nalgebra::{DMatrix, DVector};

use crate::num::roots::{illinois, RootOptions, Sample};
use crate::ode::Stats;
use crate::study::continuation::ContinuationSettings;
use crate::study::orbit::{is_neutral, leading_abs, shifted_product, Forcing};

use super::bvp::{Closure, Evaluated, ImpactOrbitInfo, Problem};
use super::{DiagramPoint, EndKind, EventKind};

/// A test function on a node whose sign change marks an event.
type NodeTest = fn(&Node) -> f64;

/// A solved point of the branch.
#[derive(Debug, Clone)]
pub(super) struct Node {
    pub forcing: Forcing,
    /// Scaled unknowns.
    pub z: DVector<f64>,
    /// Unit tangent in (z, q), q the parameter over its scale.
    pub t: DVector<f64>,
    pub info: ImpactOrbitInfo,
    pub point: DiagramPoint,
    /// The signed asymmetry of a mirror-structured chain (zero on a symmetric orbit; see
    /// [`Problem::asymmetry`]), NaN for other chains.
    pub asymmetry: f64,
}

/// A located event of a branch, before it joins the diagram.
#[derive(Debug, Clone)]
pub(super) struct Found {
    pub kind: EventKind,
    pub node: Node,
    pub stable_before: bool,
    pub stable_after: bool,
}

/// How the branch ended.
#[derive(Debug, Clone)]
pub(super) struct Ending {
    pub kind: EndKind,
    /// The residual of the end's test there: the impact speed (m/s), the excursion past the
    /// stop (m), or the scaled asymmetry.
    pub residual: f64,
}

/// A followed branch.
#[derive(Debug, Clone)]
pub(super) struct Followed {
    pub nodes: Vec<Node>,
    pub events: Vec<Found>,
    pub ending: Ending,
}

pub(super) struct Follower<'p, 'a, M, const N: usize> {
    pub problem: &'p Problem<'a, M, N>,
    pub settings: ContinuationSettings,
    /// The asymmetry of a mirror-structured periodic orbit is watched (the branch ends when
    /// it returns to the symmetric orbits).
    pub watch_asymmetry: bool,
    pub stats: Stats,
}

/// Largest distance of a corrected point from its predictor, in arclength steps.
const MAX_CORRECTION: f64 = 0.5;

/// Most points of one branch of the diagram (a branch whose steps stay tiny, as where two
/// impacts merge into a chattering sequence, ends at this budget).
const MAX_BRANCH_POINTS: usize = 2000;

impl<M: crate::model::Model<N>, const N: usize> Follower<'_, '_, M, N> {
    fn q_of(&self, f: &Forcing) -> f64 {
        f.get(self.settings.parameter) / self.settings.param_scale
    }

    fn u_of(&self, n: &Node) -> DVector<f64> {
        let m = n.z.len();
        let mut u = DVector::zeros(m + 1);
        u.rows_mut(0, m).copy_from(&n.z);
        u[m] = self.q_of(&n.forcing);
        u
    }

    /// [jz | jp * scale].
    fn bordered(&self, ev: &Evaluated<N>) -> DMatrix<f64> {
        let m = ev.jz.nrows();
        let mut j = DMatrix::zeros(m, m + 1);
        j.view_mut((0, 0), (m, m)).copy_from(&ev.jz);
        j.set_column(m, &(&ev.jp * self.settings.param_scale));
        j
    }

    /// The unit tangent spanning the kernel of `j`, oriented along `prev`.
    pub(super) fn tangent(j: &DMatrix<f64>, prev: &DVector<f64>) -> Option<DVector<f64>> {
        let m = j.nrows();
        let mut big = DMatrix::zeros(m + 1, m + 1);
        big.view_mut((0, 0), (m, m + 1)).copy_from(j);
        big.set_row(m, &prev.transpose());
        let mut e = DVector::zeros(m + 1);
        e[m] = 1.0;
        let t = big.lu().solve(&e)?;
        let n = t.norm();
        if !(n.is_finite() && n > 0.0) {
            return None;
        }
        let t = t / n;
        Some(if t.dot(prev) < 0.0 { -t } else { t })
    }

    /// A node from a solved (z, forcing) with its tangent oriented along `prev`.
    pub(super) fn node(
        &mut self,
        forcing: Forcing,
        z: DVector<f64>,
        ev: &Evaluated<N>,
        prev: &DVector<f64>,
        residual: f64,
    ) -> Option<Node> {
        let t = Self::tangent(&self.bordered(ev), prev)?;
        let info = self.problem.info(&forcing, &z, ev);
        let (summary, section, fingerprint) = self
            .problem
            .measures(&forcing, &z, ev, &mut self.stats)
            .ok()?;
        let asymmetry = self.problem.asymmetry(&z);
        let point = DiagramPoint {
            forcing,
            periods: self.problem.seq.periods(),
            multipliers: info.multipliers.clone(),
            half_multipliers: info.half_multipliers.clone(),
            summary,
            section: section.map(|(p, y)| (p, DVector::from_column_slice(y.as_slice()))),
            impact_speeds_m_s: info.speeds_m_s.clone(),
            clearance_m: -info.excursion_m,
            symmetric: self.problem.seq.closure == Closure::Mirror,
            residual,
            fingerprint: DVector::from_column_slice(fingerprint.as_slice()),
        };
        Some(Node {
            forcing,
            z,
            t,
            info,
            point,
            asymmetry,
        })
    }

    /// Newton on the bordered system from the predictor anchor + s t (or, with `t` `None`,
    /// at the anchor's fixed parameter).
    pub(super) fn correct(
        &mut self,
        template: &Forcing,
        anchor: &DVector<f64>,
        t: &DVector<f64>,
        s: f64,
    ) -> Option<(Node, usize)> {
        let m = anchor.len() - 1;
        let cfg = self.settings.shooting;
        let param = self.settings.parameter;
        let mut u = anchor + t * s;
        for it in 0..=cfg.max_newton {
            let p = u[m] * self.settings.param_scale;
            if !(p.is_finite() && p > 0.0) {
                return None;
            }
            let forcing = template.with(param, p);
            let z = u.rows(0, m).into_owned();
            let ev = self.problem.evaluate(&forcing, &z, &mut self.stats).ok()?;
            let res = ev.r.norm();
            let arc = t.dot(&(&u - anchor)) - s;
            if res < cfg.residual_tol && arc.abs() <= 1e-10 * (1.0 + s.abs()) {
                let n = self.node(forcing, z, &ev, t, res)?;
                return Some((n, it));
            }
            if it == cfg.max_newton {
                return None;
            }
            let mut big = DMatrix::zeros(m + 1, m + 1);
            big.view_mut((0, 0), (m, m + 1))
                .copy_from(&self.bordered(&ev));
            big.set_row(m, &t.transpose());
            let mut rhs = DVector::zeros(m + 1);
            rhs.rows_mut(0, m).copy_from(&(-&ev.r));
            rhs[m] = -arc;
            let du = big.lu().solve(&rhs)?;
            if !du.iter().all(|x| x.is_finite()) {
                return None;
            }
            u += du;
        }
        None
    }

    /// The node at arclength `s` from `from` along its tangent.
    pub(super) fn step(&mut self, from: &Node, s: f64) -> Option<(Node, usize)> {
        let anchor = self.u_of(from);
        let t = from.t.clone();
        self.correct(&from.forcing, &anchor, &t, s)
    }

    /// The first reason a step from `a` to `b` (at arclength `ds`) is not accepted.
    fn rejected(&self, a: &Node, b: &Node, ds: f64) -> bool {
        let s = &self.settings;
        let param = s.parameter;
        let dp = (b.forcing.get(param) - a.forcing.get(param)).abs();
        let predicted = self.u_of(a) + &a.t * ds;
        b.t.dot(&a.t) < s.max_turn_rad.cos()
            || dp > s.max_param_step
            || (self.u_of(b) - predicted).norm() > MAX_CORRECTION * ds
    }

    /// Follows the branch from `start` along its tangent until it ends (see the module docs).
    /// `start` may lie on the boundary of the real orbits (a grazing or the symmetric orbit
    /// of a pitchfork): the ending tests are then armed from the first step on.
    pub(super) fn follow(&mut self, start: Node, lo: f64, hi: f64) -> Followed {
        let s = self.settings;
        let param = s.parameter;
        let mut nodes = vec![start];
        let mut events = Vec::new();
        let mut ds = s.ds_init;
        let ending = loop {
            let a = nodes.last().expect("a branch has a node").clone();
            let p = a.forcing.get(param);
            if nodes.len() > 1 && (p < lo || p > hi) {
                break Ending {
                    kind: EndKind::Range,
                    residual: 0.0,
                };
            }
            if nodes.len() >= s.max_points.min(MAX_BRANCH_POINTS) {
                break Ending {
                    kind: EndKind::Budget,
                    residual: 0.0,
                };
            }
            let stepped = self.step(&a, ds).filter(|(b, _)| !self.rejected(&a, b, ds));
            let Some((b, its)) = stepped else {
                ds *= 0.5;
                if ds < s.ds_min {
                    break Ending {
                        kind: EndKind::Stalled,
                        residual: 0.0,
                    };
                }
                continue;
            };
            let k = nodes.len() - 1;
            // The ends of the real orbits, in the order they come along the step.
            if let Some((kind, node, residual, _)) = self.ending_between(&a, &b, ds, k == 0) {
                // The step into the end of the branch holds no smooth event: its end is a
                // grazing or the pitchfork it returns to, where multipliers jump or pass +1.
                nodes.push(node);
                break Ending { kind, residual };
            }
            // Nor does the first step from a start at a bifurcation or a grazing.
            if k > 0 {
                events.extend(self.smooth_events(&a, &b, ds));
            }
            nodes.push(b);
            if its <= 2 {
                ds = (ds * 1.5).min(s.ds_max);
            } else if its >= 5 {
                ds = (ds * 0.6).max(s.ds_min);
            }
        };
        Followed {
            nodes,
            events,
            ending,
        }
    }

    /// The first end of the real orbits between `a` and `b`: its kind, the located node and
    /// the residual of its test there. From a start on the boundary (`first`), a test that is
    /// zero at `a` does not count.
    fn ending_between(
        &mut self,
        a: &Node,
        b: &Node,
        ds: f64,
        first: bool,
    ) -> Option<(EndKind, Node, f64, f64)> {
        let mut tests: Vec<(EndKind, NodeTest)> = vec![
            (EndKind::Grazing, test_speed as NodeTest),
            (EndKind::NewContact, |n| -test_excursion(n)),
        ];
        if self.watch_asymmetry {
            tests.push((EndKind::Symmetric, test_asymmetry));
        }
        let mut best: Option<(f64, EndKind, Node, f64)> = None;
        for (kind, f) in tests {
            let (fa, fb) = (f(a), f(b));
            let crossed = if kind == EndKind::Symmetric {
                fa * fb < 0.0
            } else {
                fa > 0.0 && fb <= 0.0
            };
            if !crossed
                || (first && fa.abs() < 1e-12 * (1.0 + fb.abs()) && kind != EndKind::Symmetric)
            {
                continue;
            }
            let node = self.locate(a, b, ds, f);
            let Some((s_at, n)) = node else { continue };
            let residual = match kind {
                EndKind::Grazing => test_speed(&n),
                EndKind::NewContact => test_excursion(&n),
                _ => f(&n),
            };
            if best.as_ref().is_none_or(|x| s_at < x.0) {
                best = Some((s_at, kind, n, residual));
            }
        }
        best.map(|(s, k, n, r)| (k, n, r, s))
    }

    /// Locates a sign change of `f` between `a` and `b` (at arclength `ds` along `a`'s
    /// tangent): the arclength and the node with the smallest |f|.
    fn locate(&mut self, a: &Node, b: &Node, ds: f64, f: NodeTest) -> Option<(f64, Node)> {
        let tol_s = self.settings.locate_tol / self.settings.param_scale * 1e-3;
        let opts = RootOptions {
            f_tol: None,
            x_tol_abs: tol_s,
            x_tol_rel: 0.0,
            max_iter: 80,
        };
        let (fa, fb) = (f(a), f(b));
        let mut best = if fa.abs() <= fb.abs() {
            (0.0, fa, a.clone())
        } else {
            (ds, fb, b.clone())
        };
        let root = illinois(
            |s| -> Result<(f64, ()), ()> {
                let (n, _) = self.step(a, s).ok_or(())?;
                let v = f(&n);
                if v.abs() < best.1.abs() {
                    best = (s, v, n);
                }
                Ok((v, ()))
            },
            Sample::new(0.0, fa, ()),
            Sample::new(ds, fb, ()),
            &opts,
        );
        root.ok()?;
        Some((best.0, best.2))
    }

    /// The smooth events between two points of the branch (none across an interval whose
    /// end multipliers are not finite: the branch's first point is a grazing orbit).
    fn smooth_events(&mut self, a: &Node, b: &Node, ds: f64) -> Vec<Found> {
        let finite = |n: &Node| n.info.multipliers.iter().all(|m| m.norm().is_finite());
        if !finite(a) || !finite(b) {
            return Vec::new();
        }
        let changes = |f: NodeTest| (f(a) > 0.0) != (f(b) > 0.0);
        let turn = changes(test_fold);
        let plus1 = changes(test_plus_one);
        let minus1 = changes(test_minus_one);
        let half_minus1 = a.info.half_multipliers.is_some() && changes(test_half_minus_one);
        let torus = !plus1 && !minus1 && !half_minus1 && unstable(a) != unstable(b);
        let mut found: Vec<(EventKind, NodeTest)> = Vec::new();
        if turn {
            found.push((EventKind::Fold, test_fold));
        } else if plus1 && !half_minus1 {
            found.push((EventKind::BranchPoint, test_plus_one));
        }
        if half_minus1 {
            found.push((EventKind::SymmetryBreaking, test_half_minus_one));
        }
        if minus1 {
            found.push((EventKind::PeriodDoubling, test_minus_one));
        }
        if torus {
            found.push((EventKind::Torus, test_torus));
        }
        let mut out = Vec::new();
        for (kind, f) in found {
            if let Some((_, node)) = self.locate(a, b, ds, f) {
                out.push(Found {
                    kind,
                    node,
                    stable_before: a.point.is_stable(),
                    stable_after: b.point.is_stable(),
                });
            }
        }
        out
    }
}

fn unstable(n: &Node) -> usize {
    n.info
        .multipliers
        .iter()
        .filter(|m| !is_neutral(**m, false) && m.norm() > 1.0)
        .count()
}

/// The smallest impact speed (m/s): zero at a grazing impact.
pub(super) fn test_speed(n: &Node) -> f64 {
    n.info
        .speeds_m_s
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min)
}

/// The largest excursion of a flight past a stop (m): zero where a new contact begins.
pub(super) fn test_excursion(n: &Node) -> f64 {
    n.info.excursion_m
}

fn test_fold(n: &Node) -> f64 {
    n.t[n.t.len() - 1]
}

fn test_plus_one(n: &Node) -> f64 {
    match &n.info.half_multipliers {
        // On a symmetric branch a +1 of the period map is either a +1 of the half map (a fold
        // or branch point within the symmetric orbits) or a -1 (the pitchfork, tested apart).
        Some(h) => shifted_product(h, -1.0, true),
        None => shifted_product(&n.info.multipliers, -1.0, false),
    }
}

fn test_minus_one(n: &Node) -> f64 {
    shifted_product(&n.info.multipliers, 1.0, false)
}

fn test_half_minus_one(n: &Node) -> f64 {
    n.info
        .half_multipliers
        .as_ref()
        .map_or(1.0, |h| shifted_product(h, 1.0, true))
}

fn test_torus(n: &Node) -> f64 {
    leading_abs(&n.info.multipliers) - 1.0
}

/// The signed asymmetry of a mirror-structured chain (set by the diagram in the node's
/// point): zero on a symmetric orbit.
fn test_asymmetry(n: &Node) -> f64 {
    n.asymmetry
}

/// True while a node's orbit is real: every impact speed positive and no flight past a stop.
pub(super) fn admissible(n: &Node) -> bool {
    test_speed(n) > 0.0 && test_excursion(n) < 0.0
}
