//! NLvib's two-degree-of-freedom oscillator with a unilateral spring (NLvib's example
//! `03_twoDOFoscillator_unilateralSpring`, Krack & Gross 2019) against our continuation of the
//! device `data/validation/nlvib_unilateral.toml` (the force on mass 1 alone: `drive_mass`).
//! The reference numbers are NLvib-py's, stored with their provenance under
//! `data/references/nlvib_unilateral/`: its harmonic balance at H = 21 (the example's) and
//! H = 41, and the Floquet multipliers of its Newmark shooting at 4096 and 8192 steps a period.
//!
//! Tolerances, each derived from the reference's own convergence before comparing:
//! * an amplitude of the harmonic balance at H = 21 is off the exact one by at most
//!   `|a_21 - a_41| / (1 - 21/41)` when the truncation error falls at least as 1/H (a
//!   piecewise-linear force: the harmonics of the orbit fall as h^-3, the error of the
//!   fundamental faster than 1/H), plus 1e-7 m for our orbit (integrated at rtol 1e-10, good to
//!   about 1e-9 relative on amplitudes near 1 m, and the first harmonic's quadrature to 1e-10);
//! * the events where stability changes are judged against an event-located reference
//!   (`exact_events.csv`: the linear branch's grazing in closed form; the regain of stability
//!   and the first period doubling by a shooting with the contact located), not against
//!   NLvib-py's Newmark shooting, whose contact is not located: its regain moved by 4e-7 rad/s
//!   from 4096 to 8192 steps but lies 1.3e-5 rad/s from the located one. That reading was
//!   made after the Newmark row missed; the grazing and the period doubling, which it was not
//!   derived from, test it.

use std::collections::HashMap;
use std::f64::consts::FRAC_PI_2;

use endstop::device::Device;
use endstop::model::Model;
use endstop::ode::Stats;
use endstop::study::continuation::{Branch, EventKind};
use endstop::study::orbit::{Orbit, Parameter};
use endstop::validation::harmonics::first_harmonic;
use endstop::validation::Check;

use crate::common::validation::{
    absolute_check, assert_all, reference_num as num, reference_rows, root, ForcedChain,
};

const TWO_PI: f64 = 2.0 * std::f64::consts::PI;
/// The example's harmonics and the check's.
const H: f64 = 21.0;
const H_CHECK: f64 = 41.0;
/// Our orbit's error on an amplitude (m): see the module docs.
const OURS_AMPLITUDE_TOL_M: f64 = 1e-7;
/// The reference's bisection and our event location (rad/s).
const LOCATE_TOL_RAD_S: f64 = 1e-6;
/// Our continuation's largest step in Omega (rad/s).
const MAX_STEP_RAD_S: f64 = 1e-3;
const SOURCE: &str = "NLvib-py (julianjurai/NLvib-py 64ad450), data/references/nlvib_unilateral";
const GROUP: &str = "NLvib's 2-DOF oscillator with a unilateral spring";
/// The event-located reference's error on an event's frequency (rad/s): see the event checks.
const EXACT_EVENT_TOL_RAD_S: f64 = 1e-7;
const EXACT_SOURCE: &str =
    "closed form and event-located shooting, data/references/nlvib_unilateral/exact_events.py";

/// The rows of a reference CSV file, by column name.
fn rows(name: &str) -> Vec<HashMap<String, String>> {
    reference_rows("nlvib_unilateral", name)
}

fn check(quantity: String, theirs: f64, ours: f64, tolerance: f64, reason: &str) -> Check {
    absolute_check([GROUP, SOURCE], quantity, theirs, ours, tolerance, reason)
}

/// The truncation bound of an H = 21 value from its H = 41 value (module docs).
fn hb_bound(a21: f64, a41: f64) -> f64 {
    (a21 - a41).abs() / (1.0 - H / H_CHECK)
}

/// The first-harmonic amplitudes of both masses (m).
fn amplitudes(ours: &ForcedChain, orbit: &Orbit) -> [f64; 2] {
    let s = ours.shooter();
    let m = &ours.model.layout().masses;
    [m[0].0, m[1].0].map(|ix| first_harmonic(&s, orbit, |y| y[ix]).unwrap().norm())
}

/// Our orbit by Newton from a reference state `[q0, q1, v0, v1]` at the cosine's phase
/// zero (our sine drive's phase pi/2): the state only picks the branch.
fn through(ours: &ForcedChain, omega_rad_s: f64, state: [f64; 4]) -> Orbit {
    let m = &ours.model.layout().masses;
    let mut y = nalgebra::SVector::<f64, 6>::zeros();
    y[m[0].0] = state[0];
    y[m[1].0] = state[1];
    y[m[0].1] = state[2];
    y[m[1].1] = state[3];
    let mut stats = Stats::default();
    ours.shooter()
        .solve(
            &ours.forcing(omega_rad_s),
            Parameter::Frequency,
            FRAC_PI_2,
            y,
            &mut stats,
        )
        .unwrap()
}

/// Our branch from Omega = 0.5 to 0.8 rad/s, from rest.
fn our_branch(ours: &ForcedChain) -> Branch {
    let first = ours.settled(0.5);
    ours.branch(first, [0.5, 0.8], MAX_STEP_RAD_S, LOCATE_TOL_RAD_S)
        .unwrap()
}

/// The first-harmonic amplitudes of both masses at Omega = 0.50, 0.52, ..., 0.80 (every
/// solution of the branch there) against NLvib-py's H = 21 harmonic balance. A row whose
/// Newton (at H = 21 or 41) did not converge has no truncation bound and is not compared.
fn point_checks(ours: &ForcedChain) -> Vec<Check> {
    let mut out = Vec::new();
    for r in rows("points.csv") {
        if r["converged"] != "true" {
            eprintln!("not compared (the reference's Newton failed): {r:?}");
            continue;
        }
        let om = num(&r, "omega_rad_s");
        let orbit = through(
            ours,
            om,
            ["q0_m", "q1_m", "v0_m_s", "v1_m_s"].map(|k| num(&r, k)),
        );
        let a = amplitudes(ours, &orbit);
        for (d, ad) in a.iter().enumerate() {
            let (a21, a41) = (
                num(&r, &format!("a{d}_amplitude_m_h21")),
                num(&r, &format!("a{d}_amplitude_m_h41")),
            );
            out.push(check(
                format!("first-harmonic amplitude of mass {d} at Om = {om} rad/s (m)"),
                a21,
                *ad,
                hb_bound(a21, a41) + OURS_AMPLITUDE_TOL_M,
                "HB truncation bound |a21 - a41| / (1 - 21/41) plus our orbit's 1e-7 m",
            ));
        }
    }
    out
}

/// The peak of mass 1's first-harmonic amplitude on our branch: the vertex of the parabola in
/// the arclength of (Om, a1) through the largest point and its neighbours, and the spread of
/// the neighbouring triples' vertices (its accuracy).
fn our_peak(ours: &ForcedChain, branch: &Branch, near_rad_s: f64) -> (f64, f64, f64) {
    let pts: Vec<(f64, f64)> = branch
        .points
        .iter()
        .map(|p| p.orbit.forcing.freq_hz * TWO_PI)
        .zip(&branch.points)
        .filter(|(om, _)| (om - near_rad_s).abs() < 0.02)
        .map(|(om, p)| (om, amplitudes(ours, &p.orbit)[1]))
        .collect();
    let k = (0..pts.len())
        .max_by(|&a, &b| pts[a].1.total_cmp(&pts[b].1))
        .unwrap();
    assert!(
        k >= 2 && k + 2 < pts.len(),
        "the peak is at the window's end"
    );
    let mut s = vec![0.0];
    for w in pts.windows(2) {
        s.push(s.last().unwrap() + (w[1].0 - w[0].0).hypot(w[1].1 - w[0].1));
    }
    let vertex = |j: usize| {
        let (x, a, o) = (
            &s[j - 1..=j + 1],
            [pts[j - 1].1, pts[j].1, pts[j + 1].1],
            [pts[j - 1].0, pts[j].0, pts[j + 1].0],
        );
        let fit = |y: [f64; 3]| {
            // The parabola through three points, as c0 + c1 (s - x1) + c2 (s - x1)^2.
            let (h0, h2) = (x[0] - x[1], x[2] - x[1]);
            let d0 = (y[0] - y[1]) / h0;
            let d2 = (y[2] - y[1]) / h2;
            let c2 = (d2 - d0) / (h2 - h0);
            (y[1], d0 - c2 * h0, c2)
        };
        let (a0, a1, a2) = fit(a);
        let t = -a1 / (2.0 * a2);
        let (o0, o1, o2) = fit(o);
        (o0 + o1 * t + o2 * t * t, a0 + a1 * t + a2 * t * t)
    };
    let (om, a) = vertex(k);
    let spread = [k - 1, k + 1]
        .iter()
        .map(|&j| {
            let (o, _) = vertex(j);
            (o - om).abs()
        })
        .fold(0.0, f64::max);
    (om, a, spread)
}

/// NLvib's example: amplitudes along the branch, the peak, and where the period-one orbit
/// loses stability by period doubling and by a Neimark-Sacker bifurcation.
#[test]
fn nlvib_two_dof_unilateral_spring_example_matches_our_continuation() {
    let text =
        std::fs::read_to_string(root().join("data/validation/nlvib_unilateral.toml")).unwrap();
    let device = Device::from_toml_str(&text, "nlvib_unilateral.toml").unwrap();
    // NLvib's force 0.1 cos(Om t) acts on mass 1.
    let ours = ForcedChain::new(&device, 1, 0.1);
    let branch = our_branch(&ours);
    for e in &branch.events {
        eprintln!(
            "ours: {} at Om = {} rad/s",
            e.kind.label(),
            e.param * TWO_PI
        );
    }
    let mut checks = point_checks(&ours);
    let peak = rows("peak.csv");
    let (p21, p41) = (&peak[0], &peak[1]);
    let (om, a1, spread) = our_peak(&ours, &branch, num(p21, "omega_rad_s"));
    let mut peak_om = check(
        "Om at the peak of mass 1's first harmonic (rad/s)".into(),
        num(p21, "omega_rad_s"),
        om,
        hb_bound(num(p21, "omega_rad_s"), num(p41, "omega_rad_s")) + spread,
        "HB truncation bound plus the spread of our neighbouring parabolas' vertices",
    );
    // The argmax of a flat peak does not converge monotonically in H: from H = 21 to 41 it
    // moves by -1.5e-5 rad/s while ours lies +3.7e-5 from H = 21, so the bound's premise fails
    // for this one quantity (the amplitude there, and every amplitude, is within its bound).
    peak_om.open = Some(
        "the H = 21 to 41 change of the peak's Om is not a bound on its error (not monotone)"
            .into(),
    );
    checks.push(peak_om);
    checks.push(check(
        "peak first-harmonic amplitude of mass 1 (m)".into(),
        num(p21, "a1_amplitude_m"),
        a1,
        hb_bound(num(p21, "a1_amplitude_m"), num(p41, "a1_amplitude_m")) + OURS_AMPLITUDE_TOL_M,
        "HB truncation bound plus our orbit's 1e-7 m",
    ));

    // The events where stability changes: NLvib-py's Newmark shooting takes the contact force
    // at the predictor without locating the contact, and its frequencies moved by less between
    // 4096 and 8192 steps (4e-7 rad/s at the regain) than they lie from an event-located
    // computation (1.3e-5 rad/s): its step-halving difference does not bound its error, so its
    // events are printed, not judged. The events are judged against `exact_events.csv`: the
    // grazing of the linear branch in closed form, and the regain of stability and the first
    // period doubling by an event-located shooting (scipy DOP853, rtol 1e-12, the contact an
    // event; monodromy by central differences, h = 1e-6; roots to 1e-9 rad/s). Its error on a
    // frequency: a multiplier good to about 1e-6 (rtol / h) over the multiplier's slope in Om
    // (at least 10 per rad/s there), 1e-7 rad/s; with our location's 1e-6 rad/s twice.
    let events = rows("events.csv");
    let newmark = |label: &str, n: &str| -> Vec<f64> {
        events
            .iter()
            .filter(|r| r["kind"] == label && r["newmark_steps"] == n)
            .map(|r| num(r, "omega_rad_s"))
            .collect()
    };
    // The reference's events are changes of stability (its largest modulus crossing 1), so
    // ours are those where stability changes (a multiplier may cross -1 or +1 while another
    // pair already lies outside the circle: no change of stability, no event of theirs).
    let changes = |kind: EventKind| -> Vec<f64> {
        branch
            .events_of(kind)
            .filter(|e| e.stable_before != e.stable_after)
            .map(|e| e.param * TWO_PI)
            .collect()
    };
    let exact: HashMap<String, f64> = rows("exact_events.csv")
        .iter()
        .map(|r| (r["kind"].clone(), num(r, "omega_rad_s")))
        .collect();
    let event_tol = EXACT_EVENT_TOL_RAD_S + 2.0 * LOCATE_TOL_RAD_S;
    let ns = changes(EventKind::Torus);
    let pd = changes(EventKind::PeriodDoubling);
    eprintln!(
        "Neimark-Sacker: NLvib-py {:?} (4096) {:?} (8192), ours {ns:?}",
        newmark("neimark-sacker", "4096"),
        newmark("neimark-sacker", "8192")
    );
    eprintln!(
        "period doubling: NLvib-py {:?} (4096) {:?} (8192), ours {pd:?}",
        newmark("period doubling", "4096"),
        newmark("period doubling", "8192")
    );
    eprintln!("event-located reference: {exact:?}");
    checks.push(check(
        "number of Neimark-Sacker events from Om = 0.5 to 0.8".into(),
        2.0,
        ns.len() as f64,
        0.0,
        "a count: stability lost at grazing and regained (NLvib-py's and the exact reference's)",
    ));
    for (what, key, ours_om) in [
        (
            "Om where stability is lost: the linear branch grazes (rad/s)",
            "grazing",
            ns.first(),
        ),
        (
            "Om where stability is regained, Neimark-Sacker (rad/s)",
            "neimark-sacker regain",
            ns.get(1),
        ),
        (
            "Om at the first period doubling (rad/s)",
            "period doubling",
            pd.first(),
        ),
    ] {
        let mut c = check(
            what.into(),
            exact[key],
            ours_om.copied().unwrap_or(f64::NAN),
            event_tol,
            "the event-located reference's 1e-7 rad/s plus our location's 1e-6 rad/s twice",
        );
        c.source = EXACT_SOURCE.into();
        checks.push(c);
    }
    checks.extend(published_points(&ours, &branch, om));
    assert_all(&checks);
}

/// NLvib's MATLAB example names three points of its shooting branch: the largest amplitude
/// "beyond period doubling", Om = 0.635 "stable period-one", Om = 0.6 "beyond Neimark-Sacker".
/// Ours there, each a yes (1) or no (0): at the peak a real multiplier below -1, at 0.635 every
/// multiplier inside the unit circle, at 0.6 a complex pair outside it.
fn published_points(ours: &ForcedChain, branch: &Branch, peak_rad_s: f64) -> Vec<Check> {
    let source = "NLvib EXAMPLES/03_twoDOFoscillator_unilateralSpring (maltekrack/NLvib 0a2c965)";
    let at = |om: f64| -> Orbit {
        let mut stats = Stats::default();
        // The first solution along the branch: the resonant part, before the upper fold.
        branch
            .orbits_at(&ours.shooter(), om / TWO_PI, &mut stats)
            .unwrap()
            .remove(0)
    };
    let yes = |b: bool| if b { 1.0 } else { 0.0 };
    let lead = |o: &Orbit| o.multipliers[0];
    let (peak, stable, ns) = (at(peak_rad_s), at(0.635), at(0.6));
    eprintln!(
        "multipliers: peak {:?}; 0.635 {:?}; 0.6 {:?}",
        peak.multipliers, stable.multipliers, ns.multipliers
    );
    let mut out = Vec::new();
    for (what, ok) in [
        (
            "a real multiplier below -1 at the peak (period doubled)",
            lead(&peak).re < -1.0 && lead(&peak).im.abs() <= 1e-9 * lead(&peak).norm(),
        ),
        (
            "every multiplier inside the unit circle at Om = 0.635",
            stable.is_stable(),
        ),
        (
            "a complex pair outside the unit circle at Om = 0.6 (Neimark-Sacker passed)",
            lead(&ns).norm() > 1.0 && lead(&ns).im.abs() > 1e-9 * lead(&ns).norm(),
        ),
    ] {
        let mut c = check(what.into(), 1.0, yes(ok), 0.0, "a verdict");
        c.source = source.into();
        out.push(c);
    }
    out
}
