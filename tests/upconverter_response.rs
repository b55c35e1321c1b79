//! The up-converter's whole response at 0.05 g from 10 to 40 Hz, as `endstop response
//! --device data/examples/upconverter.toml --from 10 --to 40 --accel-rms-g 0.05` computes it
//! (its largest continuation step a hundredth of the range, the resumption in the stepped
//! sweep's default step of 0.1 Hz after transients of 200 periods): its Neimark-Sacker
//! events are complex pairs of multipliers crossing the unit circle, and the grazings that
//! add a strike a period, some a few 1e-5 Hz apart, are each reported once and told apart by
//! their counts of strikes.

use std::sync::OnceLock;

use endstop::study::continuation::{Branch, BranchPoint, Event, EventKind, Response};
use endstop::study::orbit::NEUTRAL_BAND;

use crate::common;

/// The response, computed once for the tests of this file.
fn response() -> &'static Response {
    static RESPONSE: OnceLock<Response> = OnceLock::new();
    RESPONSE.get_or_init(|| common::upconverter_response(10.0, 40.0))
}

/// The largest modulus of a multiplier off the real axis (NaN without one).
fn pair_modulus(p: &BranchPoint) -> f64 {
    p.orbit
        .multipliers
        .iter()
        .filter(|m| m.im.abs() >= NEUTRAL_BAND)
        .map(|m| m.norm())
        .fold(f64::NAN, f64::max)
}

/// How far from the unit circle the located orbit's complex pair may lie: the events are
/// located to 1e-4 Hz, and the steepest change of the pair's modulus on this run is about
/// 360 per Hz (from 1.114 to 0.843 between 19.28398 and 19.28474 Hz), 0.036 over that
/// tolerance.
const LOCATED_MODULUS_TOL: f64 = 0.05;

fn strikes(p: &BranchPoint) -> u32 {
    p.orbit.summary.contact_reach.strikes[0]
}

fn events_of(b: &Branch, kind: EventKind) -> impl Iterator<Item = &Event> {
    b.events.iter().filter(move |e| e.kind == kind)
}

#[test]
fn each_torus_event_is_a_complex_pair_crossing_the_unit_circle() {
    let r = response();
    let mut found = 0;
    for b in r.branches() {
        for e in events_of(b, EventKind::Torus) {
            found += 1;
            let (a, z) = (&b.points[e.after_point], &b.points[e.after_point + 1]);
            let f = e.param;
            // No jump: the stop between the masses is struck as often on both sides.
            assert_eq!(
                strikes(a),
                strikes(z),
                "a strike gained or lost across {f} Hz"
            );
            // The pair lies on either side of the circle at the two points, and on it (to
            // the location's tolerance) at the event.
            let (ma, mz) = (pair_modulus(a), pair_modulus(z));
            assert!(
                (ma - 1.0) * (mz - 1.0) < 0.0,
                "at {f} Hz the pair's modulus goes from {ma} to {mz}"
            );
            let at = e
                .orbit
                .multipliers
                .iter()
                .filter(|m| m.im.abs() >= NEUTRAL_BAND)
                .map(|m| (m.norm() - 1.0).abs())
                .fold(f64::INFINITY, f64::min);
            assert!(
                at <= LOCATED_MODULUS_TOL,
                "at {f} Hz the located orbit's pair lies {at} off the unit circle"
            );
        }
    }
    assert!(found > 0, "no Neimark-Sacker point found on this run");
}

#[test]
fn each_grazing_that_adds_a_strike_is_reported_once_with_its_strikes() {
    let r = response();
    let mut near_pair = false;
    for b in r.branches() {
        let g: Vec<_> = events_of(b, EventKind::Grazing)
            .filter(|e| e.contact == Some(0))
            .collect();
        for e in &g {
            // The count is that of the point before it or the one after, the lesser one.
            let n = e.strikes.expect("a grazing of a strike states its count");
            let (a, z) = (&b.points[e.after_point], &b.points[e.after_point + 1]);
            assert_eq!(n, strikes(a).min(strikes(z)), "at {} Hz", e.param);
            assert!(e.label().contains(&format!("{n} to {} strikes", n + 1)));
        }
        for (i, x) in g.iter().enumerate() {
            for y in &g[i + 1..] {
                assert!(
                    x.strikes != y.strikes || (x.param - y.param).abs() > 1e-4,
                    "one grazing twice: {} and {} Hz, {:?} strikes",
                    x.param,
                    y.param,
                    x.strikes
                );
                near_pair |= (x.param - y.param).abs() < 1e-4;
            }
        }
    }
    // Between 20.2395 and 20.2397 Hz the branch found at 20.2361 Hz crosses the grazings from
    // 17 to 18 and from 18 to 19 strikes a period, 6e-5 Hz apart: two events, two labels.
    assert!(near_pair, "no two grazings within 1e-4 Hz on this run");
}
