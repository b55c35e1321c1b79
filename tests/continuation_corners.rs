//! The continuation keeps its branch at corners whatever the last bits of the arithmetic:
//! Figure 13's branches at three points of the recorded history match whose branches pass
//! corners (an orbit starting to touch a stop where the branch turns) continue to the end of
//! the range, and with the drive amplitude changed by four ulps (the size of a differently
//! rounded `sin`) they have the same events. `examples/last_bits.rs` runs all 40 points of
//! `tests/fixtures/history_points.csv` both ways.

use endstop::device::{Device, StiffnessModel};
use endstop::paper::deviations::sweeps::{
    frequency_branch, P2_HERTZ_BIM, P2_LEVELS_G, P2_RANGE_HZ, P2_STEP_HZ,
};
use endstop::paper::deviations::RangesFile;
use endstop::paper::setups::{endstop, with_endstop, FIG13_BIAS_V};
use endstop::study::continuation::{Branch, ContinuationSettings};

use crate::common;

/// Runs 2, 4 and 6 of the first wave of prototype 2 (`tests/fixtures/history_points.csv`):
/// at run 2 the linear stop's branch stalled with either drive, at runs 4 and 6 the Hertz
/// stop's branch stalled with one of them.
const POINTS: [[f64; 8]; 3] = [
    [
        0.8895665758661684,
        0.1622832700042394,
        0.8676937526421881,
        0.9567709555348249,
        0.28157224702252764,
        0.6296371298352567,
        0.9988760919815375,
        0.7593736317045318,
    ],
    [
        0.006567485432423121,
        0.5496506590595835,
        0.2373222379981695,
        0.3079454545768192,
        0.24626456354527249,
        0.10617626031454266,
        0.07174169477943085,
        0.06184601422217495,
    ],
    [
        0.23379327175342884,
        0.975853719550558,
        0.17885053591754183,
        0.4521674386236036,
        0.4806309393457363,
        0.30226652297550977,
        0.6393133162178852,
        0.1861928819235077,
    ],
];

/// The drive's change: four ulps, the size of a differently rounded elementary function.
const ULPS: f64 = 4.0;

/// Two locations of one event agree to twice the locator's tolerance (each is within it).
fn same_event_tol_hz() -> f64 {
    2.0 * ContinuationSettings::frequency(P2_RANGE_HZ.0, P2_RANGE_HZ.1, P2_STEP_HZ).locate_tol
}

/// Figure 13's branch at 0.31 g with `law` at a point, its drive scaled by `scale`.
fn fig13_branch(point: &[f64], law: StiffnessModel, scale: f64) -> Branch {
    let ranges = RangesFile::bundled().unwrap();
    let variant = ranges
        .prototype2
        .variant(&common::prototype2(), point)
        .unwrap();
    let base: Device = variant.device.with_bias(FIG13_BIAS_V);
    let bim = match law {
        StiffnessModel::Hertz => P2_HERTZ_BIM,
        _ => endstop(&base).damping_n_s_per_m,
    };
    let accel = P2_LEVELS_G.1 * variant.accel_scale * scale;
    frequency_branch(
        &with_endstop(&base, law, bim),
        accel,
        P2_RANGE_HZ,
        P2_STEP_HZ,
        "F13 0.31 g",
    )
    .unwrap_or_else(|e| panic!("{law:?} at {accel} g: {e}"))
}

fn assert_same_events(a: &Branch, b: &Branch, what: &str) {
    let kinds = |x: &Branch| x.events.iter().map(|e| e.label()).collect::<Vec<_>>();
    assert_eq!(kinds(a), kinds(b), "{what}");
    for (x, y) in a.events.iter().zip(&b.events) {
        assert!(
            (x.param - y.param).abs() <= same_event_tol_hz(),
            "{what}: {} at {} Hz and {} Hz",
            x.label(),
            x.param,
            y.param
        );
    }
}

#[test]
#[ignore = "about a minute of continuations; CI runs it: cargo test --release --test all -- continuation_corners:: --ignored"]
fn figure_13_branches_keep_their_events_when_the_drive_moves_by_ulps() {
    let scale = 1.0 + ULPS * f64::EPSILON;
    for (k, point) in POINTS.iter().enumerate() {
        for law in [StiffnessModel::Linear, StiffnessModel::Hertz] {
            let what = format!("point {k}, {law:?}");
            let a = fig13_branch(point, law, 1.0);
            let b = fig13_branch(point, law, scale);
            eprintln!(
                "{what}: {:?}",
                a.events
                    .iter()
                    .map(|e| (e.label(), e.param))
                    .collect::<Vec<_>>()
            );
            assert_same_events(&a, &b, &what);
        }
    }
}
