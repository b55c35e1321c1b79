//! PWSDDE-cont's two-degree-of-freedom impact Duffing oscillator (its demo `impd_osc_demo.m`)
//! against our continuation of the device `data/validation/pwsdde_impduff.toml` (cubic
//! springs, two stops between the masses with restitution, the force on the primary alone).
//! The reference numbers are PWSDDE-cont's, run under Octave with Chebyshev meshes of M = 20
//! (the demo's), 40, 60 and 80 points, stored with their provenance under
//! `data/references/pwsdde_impduff/`; the test reads its events off those files.
//!
//! The demo's second run, from omega = 0.7 (two impacts a period, one on each stop), is
//! compared where it ends at a grazing below (the impacts vanish), where it regains stability
//! by a Neimark-Sacker bifurcation, where it loses it at the symmetry-breaking pitchfork, and
//! where it ends at a grazing above (a strike more). Its first run, from omega = 1.5, is
//! compared from the start to its fold on either side: below, the pitchfork where it loses
//! stability and the fold; above, the fold. Between them ours loses and regains stability at a
//! Neimark-Sacker pair; PWSDDE-cont flags that window at M = 20, 40 and 60, while at M = 80 its
//! steps pass over it unflagged, so the finest mesh gives no reference there and the pair is
//! printed, not compared. The primary's half peak-to-peak amplitude is compared at both
//! starting points.
//!
//! Every row compares with the finest mesh, M = 80. The rows first compared with M = 20, the
//! mesh's error bounded by |M20 - M40|; the grazing above then missed that bound and was left
//! open on the reading that M = 20 is not converged there. That reading was made after the
//! miss, and M = 60 and 80 were run after it to test it: the grazing's change from mesh to
//! mesh shrinks from M40 -> M60 to M60 -> M80, so the reference moved to the finest mesh with
//! the same rule for every row (the other rows, and the first run's, are cases the rule was
//! not made from). Under that rule the grazing above still misses, and the cause is on
//! PWSDDE-cont's side. Its interior grazing test (`po_graze_det.m`) reads each stop's event
//! condition at the interior nodes of its Chebyshev mesh only, not on the interpolant between
//! them, so that its grazing is where the node nearest the orbit's free peak reaches the stop.
//! That node falls short of the peak by about half the peak's curvature times the node's
//! distance from it squared, a distance set by where the peak falls between the nodes: it is
//! bounded by a multiple of the node spacing squared, so it vanishes as M grows, but it is not
//! monotone in M (the peak may fall near a node at one mesh and between two at the next). Its
//! grazing lies above the orbit's by that shortfall over the rate at which the peak rises with
//! omega, and its orbits between the two cross the stop between nodes. The mesh-to-mesh change
//! that shrank from M = 40 to 80 was that shortfall's, not the approach to the orbit's
//! grazing, which lies below all four meshes' values. The rows after it reproduce the test on
//! our orbits: the node test of each mesh, evaluated on our orbits just below our grazing and
//! extrapolated to its zero, against PWSDDE-cont's grazing at every mesh. The grazing row
//! itself is reported open (its difference shown, not judged): the reference holds no grazing
//! of the orbit.
//!
//! Tolerances, each derived from the two sides' own errors before comparing:
//! * PWSDDE-cont's discretisation: the difference of its M = 80 and M = 60 values;
//! * a grazing is located by PWSDDE-cont's bisection (its orbits converged to its Newton
//!   tolerance, 1e-10; the bisection stops at a tenth of the smallest arclength step), a
//!   change of stability is not located: it lies between the step where it is flagged and the
//!   step before, so its reference is that bracket's middle and its error half the bracket;
//! * a fold is flagged at the step where the parameter's tangent changes sign, so it lies
//!   between two points either side of the turn, and its omega beyond both (half their gap is
//!   no bound: they may straddle the turn at nearly one omega). Its reference is the vertex of
//!   the parabola omega(a) through the outer of the two points and its neighbours, a the
//!   primary's amplitude (monotone through the turn); its error the vertex's whole distance
//!   from that point (the parabola's own error is of higher order in the step);
//! * an amplitude is read off 2000 samples of the Chebyshev interpolant over the period: a
//!   sampled maximum misses the true one by at most `A (2 pi / 2000)^2 / 2 < 5e-6 A` for a
//!   near-harmonic orbit, taken as 1e-5 of the amplitude;
//! * ours: our event location's tolerance (`LOCATE_TOL_RAD_S`) twice, and 1e-7 m on an
//!   amplitude (orbits integrated at the shooting's default tolerance). Our branch of
//!   one-period orbits ends at the grazing above (past it only an orbit of several periods is
//!   found): there the gap from its last orbit to that one is added;
//! * PWSDDE-cont's interior grazing test reproduced on our orbits: its bisection's last step
//!   (it stops when the arclength step falls to a tenth of the demo's smallest step, 1e-3, its
//!   last trial then within 2e-4 of the event along a unit tangent whose omega component is
//!   at most one), the extrapolation's quadratic term (the zero of the quadratic through our
//!   three orbits less that of the line through the nearer two), and our location twice.

use std::collections::HashMap;
use std::f64::consts::TAU;

use endstop::model::Model;
use endstop::ode::{Stats, Step};
use endstop::study::continuation::{Branch, EventKind};
use endstop::study::orbit::{Orbit, OrbitError, Parameter};
use endstop::validation::Check;
use nalgebra::SVector;

use crate::common::validation::{
    absolute_check, assert_all, device, reference_num as num, reference_rows, ForcedChain,
};

/// Our event location (rad/s).
const LOCATE_TOL_RAD_S: f64 = 1e-6;
/// Our continuation's largest step in omega (rad/s).
const MAX_STEP_RAD_S: f64 = 2e-3;
/// Our orbit's error on an amplitude (m).
const OURS_AMPLITUDE_TOL_M: f64 = 1e-7;
/// The reference's sampled maximum, relative to the amplitude (module docs).
const SAMPLED_PEAK_REL: f64 = 1e-5;
/// The reference's meshes: the one compared with and the next coarser, whose difference is the
/// reference's discretisation error.
const MESHES: [u32; 2] = [80, 60];
/// Every mesh of the reference, for the reproduction of its interior grazing test on our
/// orbits (module docs).
const ALL_MESHES: [u32; 4] = [20, 40, 60, 80];
/// PWSDDE-cont's bisection stops when its arclength step falls to a tenth of the demo's
/// smallest step (1e-3), its last trial then within twice that of the event along a unit
/// tangent whose omega component is at most one (rad/s).
const PWSDDE_BISECTION_RAD_S: f64 = 2e-4;
/// A point of our branch from 0.7 rad/s short of its end above (rad/s), where it is split.
const SPLIT_RAD_S: f64 = 2.0;
/// How far below our grazing above the three orbits lie whose node test is extrapolated to
/// its zero (rad/s).
const BELOW_GRAZING_RAD_S: [f64; 3] = [1e-3, 5e-4, 1e-5];
/// Largest step of the fixed-frequency march from the split to those orbits (rad/s).
const MARCH_RAD_S: f64 = 5e-3;
const SOURCE: &str =
    "PWSDDE-cont (Tudesz/PWSDDE-cont 01106f4) under Octave 7.3, data/references/pwsdde_impduff";
const GROUP: &str = "PWSDDE-cont's 2-DOF impact Duffing oscillator";

type Row = HashMap<String, String>;

/// One mesh's reading of the demo's branches.
struct Reference {
    rows: Vec<Row>,
}

impl Reference {
    /// The rows of the reference file of Chebyshev mesh `mesh`.
    fn new(mesh: u32) -> Self {
        Self {
            rows: reference_rows("pwsdde_impduff", &format!("points_M{mesh}.csv")),
        }
    }

    fn branch(&self, b: u32) -> Vec<&Row> {
        let mut v: Vec<&Row> = self
            .rows
            .iter()
            .filter(|r| num(r, "branch") as u32 == b)
            .collect();
        v.sort_by_key(|r| num(r, "index") as usize);
        v
    }

    /// The index on branch `b` of its `n`-th point (in the file's order) whose event text holds
    /// `text`.
    fn at(&self, b: u32, text: &str, n: usize) -> usize {
        self.branch(b)
            .iter()
            .enumerate()
            .filter(|(_, r)| r["event"].contains(text))
            .map(|(k, _)| k)
            .nth(n)
            .unwrap_or_else(|| panic!("no `{text}` number {n} on branch {b}"))
    }

    /// The index of the point before point `k` of branch `b` in the continuation's direction
    /// (away from the starting point).
    fn before(&self, b: u32, k: usize) -> usize {
        if k < self.at(b, "Starting point", 0) {
            k + 1
        } else {
            k - 1
        }
    }

    /// The `n`-th change of stability flagged `text` on branch `b`: the bracket between the
    /// flagged point and the one before it.
    fn bracket(&self, b: u32, text: &str, n: usize) -> (f64, f64) {
        let br = self.branch(b);
        let k = self.at(b, text, n);
        let (om, other) = (num(br[k], "omega"), num(br[self.before(b, k)], "omega"));
        (om.min(other), om.max(other))
    }

    /// The fold of branch `b` below its start (`below`) or above it: the vertex of the parabola
    /// omega(amplitude) through the outer of the two points either side of the turn and its
    /// neighbours, and the vertex's distance from that point (module docs).
    fn fold(&self, b: u32, below: bool) -> (f64, f64) {
        let br = self.branch(b);
        let start = self.at(b, "Starting point", 0);
        let k = (0..br.len())
            .find(|&k| (k < start) == below && br[k]["event"].contains("Fold point"))
            .unwrap_or_else(|| panic!("no fold on branch {b}, below {below}"));
        let before = self.before(b, k);
        let earlier = self.before(b, before);
        let om = |i: usize| num(br[i], "omega");
        // The turn is a maximum of omega where omega rises towards it.
        let maximum = om(before) > om(earlier);
        let outer = if (om(k) > om(before)) == maximum {
            k
        } else {
            before
        };
        let [(a0, w0), (a1, w1), (a2, w2)] =
            [outer - 1, outer, outer + 1].map(|i| (num(br[i], "amp_x1"), om(i)));
        // Newton's form w0 + d1 (a - a0) + c (a - a0)(a - a1), its derivative zero at the vertex.
        let d1 = (w1 - w0) / (a1 - a0);
        let c = ((w2 - w1) / (a2 - a1) - d1) / (a2 - a0);
        let a = 0.5 * (a0 + a1) - d1 / (2.0 * c);
        let vertex = w0 + d1 * (a - a0) + c * (a - a0) * (a - a1);
        (vertex, (vertex - w1).abs())
    }

    /// The branch's two ends: its first and last points (their grazings).
    fn ends(&self, b: u32) -> (f64, f64) {
        let br = self.branch(b);
        (num(br[0], "omega"), num(br[br.len() - 1], "omega"))
    }

    /// x1's half peak-to-peak at the branch's starting point.
    fn start_amplitude(&self, b: u32) -> f64 {
        num(self.branch(b)[self.at(b, "Starting point", 0)], "amp_x1")
    }
}

/// The reference at the compared mesh and at the next coarser one.
fn references() -> [Reference; 2] {
    MESHES.map(Reference::new)
}

fn check(quantity: String, theirs: f64, ours: f64, tolerance: f64, reason: &str) -> Check {
    absolute_check([GROUP, SOURCE], quantity, theirs, ours, tolerance, reason)
}

/// The primary's half peak-to-peak displacement over an orbit (m).
fn amplitude(o: &Orbit) -> f64 {
    0.5 * (o.summary.x_upper_m - o.summary.x_lower_m)
}

/// The parameter (rad/s) of the `n`-th event of `kind` on our branch `b`.
fn nth(b: &Branch, kind: EventKind, n: usize) -> f64 {
    b.events_of(kind)
        .map(|e| e.param * TAU)
        .nth(n)
        .unwrap_or(f64::NAN)
}

fn print_events(name: &str, b: &Branch) {
    for e in &b.events {
        eprintln!(
            "ours ({name}): {} at omega = {} rad/s, stable {} -> {}",
            e.kind.label(),
            e.param * TAU,
            e.stable_before,
            e.stable_after
        );
    }
}

/// PWSDDE-cont's interior grazing test on our orbit `o`: the event condition of each stop (the
/// approach of its masses less its gap) at the interior points of a Chebyshev mesh of `mesh`
/// points (the extrema of the Chebyshev polynomial of degree `mesh - 1`) on each segment
/// between impacts, the largest of them (m; negative while every node is short of both stops).
fn node_condition(ours: &ForcedChain, o: &Orbit, mesh: u32) -> f64 {
    let f = o.forcing;
    let period = f.period_s();
    let mut steps: Vec<Step<SVector<f64, 6>>> = Vec::new();
    ours.shooter()
        .flow(&f, o.phase_rad, o.state_n(), period, |s, _| {
            steps.push(s.clone())
        })
        .expect("our orbit integrates");
    let layout = ours.model.layout();
    // An impact ends a step: the velocities jump between it and the next.
    let jumps = |a: &Step<SVector<f64, 6>>, b: &Step<SVector<f64, 6>>| {
        layout
            .masses
            .iter()
            .any(|&(_, iv)| (b.y0[iv] - a.y1[iv]).abs() > 1e-9)
    };
    let impacts: Vec<f64> = steps
        .windows(2)
        .filter(|w| jumps(&w[0], &w[1]))
        .map(|w| w[1].t0)
        .collect();
    let at = |t: f64| {
        let t = t.rem_euclid(period);
        let k = steps
            .partition_point(|s| s.t0 + s.h < t)
            .min(steps.len() - 1);
        let s = &steps[k];
        s.at_theta(((t - s.t0) / s.h).clamp(0.0, 1.0))
    };
    let contacts = ours.model.contacts();
    let condition = |y: SVector<f64, 6>| {
        contacts
            .iter()
            .map(|c| {
                let ix = layout.masses[c.mass].0;
                let x = c.other.map_or(y[ix], |o| y[layout.masses[o].0] - y[ix]);
                c.side * x - c.gap
            })
            .fold(f64::NEG_INFINITY, f64::max)
    };
    let n = impacts.len();
    let strikes: u32 = o.summary.contact_reach.strikes.iter().sum();
    assert!(
        n > 0 && n == strikes as usize,
        "our orbit at omega = {} rad/s: {n} velocity jumps, {strikes} strikes",
        f.freq_hz * TAU
    );
    let last = mesh as usize - 1;
    (0..n)
        .flat_map(|i| {
            let a = impacts[i];
            let b = impacts.get(i + 1).copied().unwrap_or(impacts[0] + period);
            (1..last).map(move |j| {
                a + 0.5 * (b - a) * (1.0 - (std::f64::consts::PI * j as f64 / last as f64).cos())
            })
        })
        .map(|t| condition(at(t)))
        .fold(f64::NEG_INFINITY, f64::max)
}

/// The orbits of our one-period branch at `BELOW_GRAZING_RAD_S` below `above` (rad/s), each
/// shot at its fixed frequency from the one before, marched to from `from`.
fn orbits_below(ours: &ForcedChain, from: &Orbit, above: f64) -> Vec<Orbit> {
    let shooter = ours.shooter();
    let mut stats = Stats::default();
    let strikes = |o: &Orbit| o.summary.contact_reach.strikes;
    let mut orbit = from.clone();
    let mut om = from.forcing.freq_hz * TAU;
    let mut out = Vec::new();
    for target in BELOW_GRAZING_RAD_S.map(|d| above - d) {
        while om < target {
            om = (om + MARCH_RAD_S).min(target);
            let f = ours.forcing(om);
            let o = shooter
                .solve(
                    &f,
                    Parameter::Frequency,
                    orbit.phase_rad,
                    orbit.state_n(),
                    &mut stats,
                )
                .unwrap_or_else(|e| panic!("our orbit at omega = {om} rad/s: {e}"));
            assert_eq!(
                strikes(&o),
                strikes(from),
                "our orbit at omega = {om} rad/s"
            );
            orbit = o;
        }
        out.push(orbit.clone());
    }
    out
}

/// PWSDDE-cont's grazing above at mesh `mesh` reproduced on our orbits `below` (module docs):
/// the frequency where the node test reaches zero, extrapolated from them (rad/s), and its
/// error, the extrapolation's quadratic term.
fn node_grazing(ours: &ForcedChain, below: &[Orbit], mesh: u32) -> (f64, f64) {
    let w: Vec<f64> = below.iter().map(|o| o.forcing.freq_hz * TAU).collect();
    let h: Vec<f64> = below
        .iter()
        .map(|o| node_condition(ours, o, mesh))
        .collect();
    // Inverse interpolation, omega as a function of the test: linear through the last two,
    // quadratic through all three, at zero.
    let linear = w[2] - h[2] * (w[2] - w[1]) / (h[2] - h[1]);
    let quadratic = (0..3)
        .map(|i| {
            let others = (0..3).filter(|&j| j != i);
            w[i] * others
                .map(|j| (0.0 - h[j]) / (h[i] - h[j]))
                .product::<f64>()
        })
        .sum::<f64>();
    (quadratic, (quadratic - linear).abs())
}

/// A change of stability flagged `text` (its `n`-th) on branch `b` against ours at `ours_om`.
fn stability_check(
    [fine, next]: &[Reference; 2],
    (b, text, n): (u32, &str, usize),
    what: &str,
    ours_om: f64,
) -> Check {
    let (af, bf) = fine.bracket(b, text, n);
    let (an, bn) = next.bracket(b, text, n);
    eprintln!("PWSDDE-cont {text} ({n}) on branch {b}: {MESHES:?} [{af}, {bf}], [{an}, {bn}]");
    let (mf, mn) = (0.5 * (af + bf), 0.5 * (an + bn));
    check(
        what.into(),
        mf,
        ours_om,
        0.5 * (bf - af) + (mf - mn).abs() + 2.0 * LOCATE_TOL_RAD_S,
        "half PWSDDE-cont's bracket, its middle's mesh change, our location twice",
    )
}

/// The primary's amplitude at the start `om` of branch `b` against our orbit there.
fn amplitude_check([fine, next]: &[Reference; 2], b: u32, om: f64, orbit: &Orbit) -> Check {
    let (af, an) = (fine.start_amplitude(b), next.start_amplitude(b));
    check(
        format!("primary's half peak-to-peak at omega = {om} rad/s (m)"),
        af,
        amplitude(orbit),
        (af - an).abs() + SAMPLED_PEAK_REL * af + OURS_AMPLITUDE_TOL_M,
        "the mesh change plus the sampled peak's 1e-5 relative plus our orbit's 1e-7 m",
    )
}

/// The demo's branch from omega = 0.7: its grazings, its Neimark-Sacker bifurcation and its
/// symmetry-breaking pitchfork against ours, and the amplitude at its start.
#[test]
fn pwsdde_impact_duffing_demo_matches_our_continuation() {
    let refs = references();
    let [fine, next] = &refs;
    // The demo's force cos(omega t) of 1 N acts on the primary.
    let ours = ForcedChain::new(&device("pwsdde_impduff"), 0, 1.0);
    let start = ours.settled(0.7);
    let down = ours
        .branch(start.clone(), [0.7, 0.6], MAX_STEP_RAD_S, LOCATE_TOL_RAD_S)
        .unwrap();
    // Our branch of one-period orbits ends at the grazing above, where a strike more begins:
    // past it the shooting finds only an orbit of several periods. That end is our grazing;
    // its error the gap to the orbit found past it, with our location. The branch is followed
    // in two legs, split short of that end: the first holds the pitchfork, and its last orbit
    // begins the march to the orbits that reproduce PWSDDE-cont's grazing test.
    let up = ours
        .branch(
            start.clone(),
            [0.7, SPLIT_RAD_S],
            MAX_STEP_RAD_S,
            LOCATE_TOL_RAD_S,
        )
        .unwrap();
    let split = up
        .points
        .last()
        .expect("a branch has a point")
        .orbit
        .clone();
    let split_om = split.forcing.freq_hz * TAU;
    let (above, above_gap) = match ours.branch(
        split.clone(),
        [split_om, 2.3],
        MAX_STEP_RAD_S,
        LOCATE_TOL_RAD_S,
    ) {
        Err(OrbitError::OtherPeriod {
            last_param, param, ..
        }) => (last_param * TAU, (param - last_param).abs() * TAU),
        Ok(b) => (nth(&b, EventKind::Grazing, 0), 0.0),
        Err(e) => panic!("our branch above {split_om} rad/s: {e}"),
    };
    eprintln!("ours: the one-period branch ends above at omega = {above} rad/s");
    print_events("down", &down);
    print_events("up", &up);
    let ours_tol = 2.0 * LOCATE_TOL_RAD_S;
    let mut checks = Vec::new();

    // The grazings at the branch's ends, located by both.
    let (lo_f, hi_f) = fine.ends(2);
    let (lo_n, hi_n) = next.ends(2);
    eprintln!("PWSDDE-cont ends: M = {MESHES:?}: [{lo_f}, {hi_f}], [{lo_n}, {hi_n}]");
    checks.push(check(
        "omega where the branch's impacts vanish, grazing below (rad/s)".into(),
        lo_f,
        nth(&down, EventKind::Grazing, 0),
        (lo_f - lo_n).abs() + ours_tol,
        "the mesh change plus our location twice",
    ));
    let mut graze_above = check(
        "omega where a strike more begins, grazing above (rad/s)".into(),
        hi_f,
        above,
        (hi_f - hi_n).abs() + above_gap + ours_tol,
        "the mesh change plus our branch's last gap plus our location twice",
    );
    // PWSDDE-cont's grazing above is where a node of its mesh reaches the stop, not where the
    // orbit does (see the module docs): reported with its difference, not judged; the rows
    // after it reproduce PWSDDE-cont's test on our orbits.
    graze_above.open = Some(
        "PWSDDE-cont's interior grazing test reads the stop's condition at its mesh nodes \
         only, so that its grazing lies past the orbit's by the nodes' shortfall at the free \
         peak; reproduced on our orbits in the rows below"
            .into(),
    );
    checks.push(graze_above);
    let below = orbits_below(&ours, &split, above);
    for mesh in ALL_MESHES {
        let theirs = Reference::new(mesh).ends(2).1;
        let (reproduced, extrapolation) = node_grazing(&ours, &below, mesh);
        eprintln!(
            "PWSDDE-cont M = {mesh}: grazing above {theirs}, its node test on our orbits \
             {reproduced} (extrapolation {extrapolation:e}), our grazing {above}"
        );
        checks.push(check(
            format!(
                "grazing above by PWSDDE-cont's node test at M = {mesh}, on our orbits (rad/s)"
            ),
            theirs,
            reproduced,
            PWSDDE_BISECTION_RAD_S + extrapolation + ours_tol,
            "PWSDDE-cont's bisection's last step, our extrapolation's quadratic term, our \
             location twice",
        ));
    }

    // The changes of stability, bracketed by PWSDDE-cont's steps.
    checks.push(stability_check(
        &refs,
        (2, "Hopf", 0),
        "omega where the branch regains stability, Neimark-Sacker (rad/s)",
        nth(&down, EventKind::Torus, 0),
    ));
    checks.push(stability_check(
        &refs,
        (2, "Saddle node", 0),
        "omega of the symmetry-breaking pitchfork (rad/s)",
        nth(&up, EventKind::BranchPoint, 0),
    ));
    checks.push(amplitude_check(&refs, 2, 0.7, &start));
    assert_all(&checks);
}

/// The demo's branch from omega = 1.5, each way to its fold: the pitchfork met below and the
/// folds against ours, and the amplitude at its start.
#[test]
fn pwsdde_impact_duffing_first_branch_folds_match_our_continuation() {
    let refs = references();
    let [fine, next] = &refs;
    let ours = ForcedChain::new(&device("pwsdde_impduff"), 0, 1.0);
    let start = ours.settled(1.5);
    let to_fold = |to: f64| {
        ours.branch_until(
            start.clone(),
            [1.5, to],
            MAX_STEP_RAD_S,
            LOCATE_TOL_RAD_S,
            |e| e.kind == EventKind::Fold,
        )
        .unwrap_or_else(|e| panic!("our branch from 1.5 rad/s towards {to} rad/s: {e}"))
    };
    let (down, up) = (to_fold(1.0), to_fold(3.5));
    print_events("down from 1.5", &down);
    print_events("up from 1.5", &up);
    let mut checks = vec![amplitude_check(&refs, 1, 1.5, &start)];

    // Below the start: the symmetry-breaking pitchfork, then the fold.
    checks.push(stability_check(
        &refs,
        (1, "Saddle node", 0),
        "first branch: omega of the pitchfork below the start (rad/s)",
        nth(&down, EventKind::BranchPoint, 0),
    ));
    // Above it ours loses and regains stability at a Neimark-Sacker pair, which the finest mesh
    // steps over unflagged (module docs): its flags are printed.
    let flags = fine
        .branch(1)
        .iter()
        .filter(|r| r["event"].contains("Hopf"))
        .count();
    eprintln!(
        "PWSDDE-cont M = {}: {flags} Neimark-Sacker flags on the first branch",
        MESHES[0]
    );
    for (below, our_branch) in [(true, &down), (false, &up)] {
        let ((vf, cf), (vn, _)) = (fine.fold(1, below), next.fold(1, below));
        eprintln!("PWSDDE-cont fold (below {below}): {MESHES:?}: {vf} (vertex moved {cf}), {vn}");
        let side = if below { "below" } else { "above" };
        checks.push(check(
            format!("first branch: omega of the fold {side} the start (rad/s)"),
            vf,
            nth(our_branch, EventKind::Fold, 0),
            cf + (vf - vn).abs() + 2.0 * LOCATE_TOL_RAD_S,
            "the parabola's move from the outer flagged point, the mesh change, our location twice",
        ));
    }
    assert_all(&checks);
}
