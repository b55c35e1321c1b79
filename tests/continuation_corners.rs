//! The continuation at a corner where the contact set changes: a symmetric orbit of
//! prototype 2 leaving both stiff stops at once on Figure 13's branch at 0.31 g, at a point of
//! the recorded history match (run 2 of prototype 2's first wave, whose continuation stalled
//! there). The branch is continued as given and with the drive amplitude scaled by
//! (1 + 4 eps), a change of the last bits of the arithmetic: both reach the end of the range
//! with the same events in the same order at the same frequencies.
//!
//! Where that branch with the Hertz stop leaves contact coming back down in frequency (a fold
//! at grazing), a step can land on the grazing orbit to rounding: runs 4, 6 and 11 of the same
//! wave stalled there one way of the last bits each. Continued as given and perturbed, each
//! reaches the end of the range with the same events.
//!
//! A corner of a contact between two masses: the example up-converter's driver starts to
//! strike its generator (a rigid stop between the masses) on its branch at 0.05 g, and the
//! branch goes on past it with the grazing located there. Further up the same branch the
//! orbit that strikes once per period meets a grazing where the next approach of the masses
//! after the impact reaches the gap (a second impact per period begins, the contact set
//! staying the same): the branch crosses it and reports it as a grazing of that contact. It
//! stops at the next such grazing, where a third impact per period begins; the response
//! resumes past it in steps with transients, finds a stable orbit again a few steps on and
//! reaches the end of its range, and an orbit of the branch found there agrees with a long
//! record at its frequency.

use std::sync::OnceLock;

use endstop::device::StiffnessModel;
use endstop::model::Model;
use endstop::ode::SolverError;
use endstop::paper::deviations::sweeps::{P2_HERTZ_BIM, P2_RANGE_HZ, P2_STEP_HZ};
use endstop::paper::deviations::RangesFile;
use endstop::paper::setups::{endstop, with_endstop, FIG13_BIAS_V};
use endstop::progress::Silent;
use endstop::study::continuation::impacting::DiagramSettings;
use endstop::study::continuation::{
    diagram_with_step, frequency_branch, Branch, BranchKind, ContinuationSettings, DiagramPoint,
    EventKind, Response, STEPPED_MEASURE_PERIODS,
};
use endstop::study::orbit::{Forcing, Orbit, OrbitError};
use endstop::study::steady::{settle_and_measure, Measurement, SettleSettings};
use nalgebra::SVector;

use crate::common;

/// The recorded history points: prototype, run, unit-cube coordinates (eight), failures.
const HISTORY_POINTS: &str = include_str!("fixtures/history_points.csv");

/// The unit-cube coordinates of history point `label` (`prototype:run`) of
/// `tests/fixtures/history_points.csv`.
fn history_point(label: &str) -> [f64; 8] {
    let line = HISTORY_POINTS
        .lines()
        .filter(|l| !l.starts_with('#'))
        .find(|l| l.splitn(3, ',').take(2).collect::<Vec<_>>().join(":") == label)
        .unwrap_or_else(|| panic!("no history point {label}"));
    let coords: Vec<f64> = line
        .split(',')
        .skip(2)
        .take(8)
        .map(|x| x.parse().expect("a coordinate"))
        .collect();
    coords.try_into().expect("eight coordinates")
}

/// The relative change of an event's frequency that counts as another event: the one the
/// `last_bits` example uses, a thousand times the events' location tolerance (1e-4 Hz at
/// ~700 Hz is 1.4e-7 relative), far above rounding and far below the distance between two
/// branches' events.
const REL_CHANGE: f64 = 1e-3;

/// Figure 13's 0.31 g branch of the deviations study at history point `label` with the
/// stop law `law` (its damping `bim`, or the prototype's), its drive scaled by `scale`.
fn fig13_branch(
    label: &str,
    law: StiffnessModel,
    bim: Option<f64>,
    scale: f64,
) -> Result<Branch, OrbitError> {
    let ranges = RangesFile::bundled().expect("the bundled ranges parse");
    let variant = ranges
        .prototype2
        .variant(&common::prototype2(), &history_point(label))
        .expect("the run lies in the unit cube");
    let base = variant.device.with_bias(FIG13_BIAS_V);
    let bim = bim.unwrap_or_else(|| endstop(&base).damping_n_s_per_m);
    let device = with_endstop(&base, law, bim);
    let accel = 0.31 * variant.accel_scale * scale;
    frequency_branch(
        &device,
        accel,
        P2_RANGE_HZ.0,
        P2_RANGE_HZ.1,
        P2_STEP_HZ,
        &Silent,
    )
}

/// Asserts that `plain` and `perturbed` (one branch as given and with its drive scaled by a
/// few ulps) have the same events in the same order, each at the same parameter to
/// [`REL_CHANGE`], and both reach `end_hz`; `what` names the case.
fn assert_same_branch(what: &str, plain: &Branch, perturbed: &Branch, end_hz: f64) {
    let events = |b: &Branch| {
        b.events
            .iter()
            .map(|e| (e.label(), e.param))
            .collect::<Vec<_>>()
    };
    let (a, b) = (events(plain), events(perturbed));
    assert_eq!(
        a.iter().map(|e| &e.0).collect::<Vec<_>>(),
        b.iter().map(|e| &e.0).collect::<Vec<_>>(),
        "{what}: the same events in the same order: {a:?} against {b:?}"
    );
    for ((kind, x), (_, y)) in a.iter().zip(&b) {
        assert!(
            (x - y).abs() <= REL_CHANGE * x.abs(),
            "{what}: {kind} at {x} Hz as given and {y} Hz perturbed"
        );
    }
    for br in [plain, perturbed] {
        let last = br.params().last().expect("a branch has points");
        assert!(
            last >= end_hz,
            "{what}: the branch ends at {last} Hz, not past {end_hz} Hz"
        );
    }
}

#[test]
fn a_corner_gives_the_same_events_whatever_the_last_bits() {
    // Run 2 of prototype 2, whose continuation stalled at this corner in the record.
    let branch = |scale: f64| {
        fig13_branch("p2:2", StiffnessModel::Linear, None, scale)
            .unwrap_or_else(|e| panic!("p2:2 scaled by {scale:e}: {e}"))
    };
    let plain = branch(1.0);
    let perturbed = branch(1.0 + 4.0 * f64::EPSILON);
    assert!(
        plain.grazing_events().next().is_some(),
        "the branch reaches the stops: {:?}",
        plain.events
    );
    assert_same_branch("p2:2", &plain, &perturbed, P2_RANGE_HZ.1);
}

/// Runs 4, 6 and 11 of prototype 2 in `tests/fixtures/history_points.csv`: Figure 13's
/// 0.31 g branch with the Hertz stop stalled at the corner where it leaves contact coming back
/// down in frequency, one way of the last bits each (4 and 11 with the drive scaled by
/// 1 + 4 eps, 6 as given), where the step that crossed the grazing landed on the grazing
/// orbit to rounding.
const HERTZ_RUNS: [&str; 3] = ["p2:4", "p2:6", "p2:11"];

#[test]
fn a_step_landing_on_the_grazing_orbit_keeps_the_branch_whatever_the_last_bits() {
    for label in HERTZ_RUNS {
        let run = |scale: f64| {
            fig13_branch(label, StiffnessModel::Hertz, Some(P2_HERTZ_BIM), scale)
                .unwrap_or_else(|e| panic!("{label} scaled by {scale:e}: {e}"))
        };
        let (plain, perturbed) = (run(1.0), run(1.0 + 4.0 * f64::EPSILON));
        assert!(
            plain.grazing_events().next().is_some(),
            "{label}: the branch reaches the stop: {:?}",
            plain.events
        );
        assert_same_branch(label, &plain, &perturbed, P2_RANGE_HZ.1);
    }
}

/// The onset of impacts of the up-converter's branch lies at 19.1246 Hz, below the stall
/// stated by the next test: the branch is continued to a little past it.
const ONSET_RANGE_HZ: (f64, f64) = (17.0, 19.25);

#[test]
fn the_upconverter_branch_crosses_the_onset_of_impacts_between_its_masses() {
    let device = common::upconverter();
    // The largest step of `endstop response --from 10 --to 40` (a hundredth of the range).
    let (from_hz, to_hz) = ONSET_RANGE_HZ;
    let branch = frequency_branch(&device, 0.05, from_hz, to_hz, 0.3, &Silent)
        .expect("the branch passes the onset of impacts");
    let last = branch.params().last().expect("a branch has points");
    assert!(last >= to_hz, "the branch ends at {last} Hz");
    // The grazing of the stop between the masses (the model's only contact): the first point
    // that strikes it lies past the grazing, every point before it is free of impacts.
    let first_impacting = branch
        .points
        .iter()
        .position(|p| p.orbit.is_impacting())
        .expect("the branch reaches the stop between the masses");
    let grazing = branch
        .events
        .iter()
        .find(|e| e.kind == EventKind::Grazing)
        .unwrap_or_else(|| panic!("no grazing among {:?}", events(&branch)));
    assert_eq!(
        grazing.after_point + 1,
        first_impacting,
        "the grazing lies between the last free point and the first impacting one"
    );
    // At the located grazing the driver's largest excursion towards the generator equals the
    // gap: the orbit is located to 1e-4 Hz on the branch, over which the excursion moves by
    // far less than a thousandth of the 0.5 mm gap (its slope is a few mm per Hz).
    let gap_m = 0.5e-3;
    let reach = &grazing.orbit.summary.contact_reach;
    assert_eq!(reach.len, 1, "one contact");
    assert!(
        (reach.reach_m[0] - gap_m).abs() <= 1e-3 * gap_m,
        "the grazing orbit reaches {} m of the {gap_m} m gap",
        reach.reach_m[0]
    );
}

/// Where the masses' next approach after the strike comes within about 1e-9 m of the gap
/// (19.2753 Hz) a second strike per period begins with the contact set unchanged: the period
/// map's derivatives grow without bound there, as at any grazing of a rigid stop (Nordmark,
/// J. Sound Vib. 145, 1991). The branch crosses it: a grazing of the stop between the masses
/// is reported there, the orbits before it strike once a period and those after it more
/// often, and the branch reaches 19.32 Hz, short of the next such grazing.
const SECOND_STRIKE_HZ: f64 = 19.2753;

/// Where the orbit striking twice a period meets the grazing that adds a third strike: the
/// crossing finds no orbit striking three times a period by Newton at fixed frequencies from
/// the last point, on the maps over one to four drive periods (the first orbit it finds,
/// 0.03 Hz on, strikes four times a period), nor any orbit of several periods, and the
/// branch stops there.
const THIRD_STRIKE_HZ: f64 = 19.3299;

#[test]
fn the_upconverter_branch_crosses_the_grazing_that_adds_a_second_strike() {
    let device = common::upconverter();
    let branch = frequency_branch(&device, 0.05, 17.0, 19.32, 0.3, &Silent)
        .expect("the branch crosses the grazing that adds a strike");
    let last = branch.params().last().expect("a branch has points");
    assert!(last >= 19.32, "the branch ends at {last} Hz");
    let added = branch
        .events
        .iter()
        .find(|e| e.kind == EventKind::Grazing && e.contact == Some(0))
        .unwrap_or_else(|| panic!("no grazing adding a strike among {:?}", events(&branch)));
    // The grazing is located to 1e-4 Hz; the stall measured its place to 1e-7 Hz, and the
    // window allows for the location tolerance ten times over.
    assert!(
        (added.param - SECOND_STRIKE_HZ).abs() < 1e-3,
        "the second strike begins at {} Hz",
        added.param
    );
    let strikes = |i: usize| branch.points[i].orbit.summary.contact_reach.strikes[0];
    assert_eq!(
        strikes(added.after_point),
        1,
        "one strike before the grazing"
    );
    assert!(
        strikes(added.after_point + 1) >= 2,
        "{} strikes after it",
        strikes(added.after_point + 1)
    );
    // At the located grazing the free approach between strikes reaches the gap: within a
    // thousandth of the 0.5 mm gap, as for the onset above (the location tolerance of 1e-4 Hz
    // times a slope of a few mm per Hz).
    let gap_m = 0.5e-3;
    let reach = &added.orbit.summary.contact_reach;
    assert!(
        (reach.free_peak_m[0] - gap_m).abs() <= 1e-3 * gap_m,
        "the grazing orbit's free approach reaches {} m of the {gap_m} m gap",
        reach.free_peak_m[0]
    );
    // The first point past the grazing lies above it in frequency (the branch goes on).
    assert!(
        branch.points[added.after_point + 1].orbit.forcing.freq_hz > SECOND_STRIKE_HZ,
        "the branch goes on above the grazing"
    );
}

/// The branch alone (without the resumption) still ends at the third strike, with the error
/// that names where (see [`THIRD_STRIKE_HZ`]): the resumption below starts there.
#[test]
fn the_upconverter_branch_alone_stops_where_a_third_strike_per_period_begins() {
    let device = common::upconverter();
    match frequency_branch(&device, 0.05, 17.0, 25.0, 0.3, &Silent) {
        // The step halves to the smallest arclength (1e-7 Hz) before it stops: the stall lies
        // within far less than 1e-3 Hz of the grazing, which the window allows for.
        Err(OrbitError::Stalled { last_param, .. }) => assert!(
            (last_param - THIRD_STRIKE_HZ).abs() < 1e-3,
            "the branch stalls at {last_param} Hz"
        ),
        Err(other) => panic!("the branch fails otherwise: {other}"),
        Ok(b) => panic!(
            "the branch reaches {:?} Hz: the third strike is crossed, replace this test",
            b.params().last()
        ),
    }
}

/// The up-converter's response from 17 to 25 Hz, past the third strike, computed once.
fn upconverter_response() -> &'static Response {
    static RESPONSE: OnceLock<Response> = OnceLock::new();
    RESPONSE.get_or_init(|| common::upconverter_response(17.0, 25.0))
}

#[test]
fn the_upconverter_response_resumes_past_the_third_strike_and_completes_its_range() {
    let r = upconverter_response();
    assert!(
        r.reach(1.0) >= 25.0 - common::UPCONVERTER_RESUME_STEP_HZ,
        "the response reaches {} Hz, not the end of the range",
        r.reach(1.0)
    );
    // The first branch ends at the third strike, where the resumption takes over.
    let first = r.branches().next().expect("a first branch");
    let end = first.params().fold(f64::NEG_INFINITY, f64::max);
    assert!(
        (end - THIRD_STRIKE_HZ).abs() < 1e-3,
        "the first branch ends at {end} Hz"
    );
    let stop = r
        .ends
        .first()
        .expect("the first branch ends short of the range");
    assert!(
        stop.piece == 0 && stop.at_strike && matches!(stop.error, OrbitError::Stalled { .. }),
        "the first branch ends with a stall at the strike: {stop:?}"
    );
    // The new path fires: a stable orbit found from a transient past the end begins a new
    // branch within a few steps of it, and every branch found starts past the first's end.
    let found = r.found();
    let &(periods, at_hz) = found.first().unwrap_or_else(|| panic!("no branch found"));
    assert!(
        at_hz > end && at_hz <= end + 5.0 * common::UPCONVERTER_RESUME_STEP_HZ,
        "the first branch found (period {periods}) is at {at_hz} Hz"
    );
    assert!((1..=4).contains(&periods), "{periods} periods");
    for b in r.branches().skip(1) {
        let o = &b.points[0].orbit;
        assert!(o.is_stable(), "a branch found is stable where found");
        assert!(o.param(b.parameter) > end);
    }
    // Stepped points lie between the branches, each at a frequency no branch covers there.
    for s in r.stepped() {
        assert!(s.forcing.freq_hz > end && s.periods == STEPPED_MEASURE_PERIODS);
    }
}

/// The relative difference allowed between a continued orbit's RMS voltage and a long record's
/// at the same frequency: ten times the record's steady-state criterion (two blocks of 120
/// periods within 1e-4 of each other), far above the integrators' errors (rtol 1e-10).
const RECORD_RMS_REL: f64 = 1e-3;

#[test]
fn an_orbit_past_the_third_strike_matches_a_long_record() {
    let r = upconverter_response();
    let device = common::upconverter();
    // The first branch found, at its most strongly attracting point (the smallest largest
    // multiplier, which a record settles onto soonest): a continued orbit, not the one the
    // transient seeded.
    let b = r
        .branches()
        .nth(1)
        .expect("a branch found past the third strike");
    let p = b
        .points
        .iter()
        .skip(1)
        .min_by(|x, y| {
            x.orbit
                .max_multiplier_abs()
                .total_cmp(&y.orbit.max_multiplier_abs())
        })
        .expect("a continued point");
    let o = &p.orbit;
    let f_hz = o.forcing.freq_hz;
    assert!(o.is_stable(), "the orbit at {f_hz} Hz is stable");
    // A long record at that frequency from the orbit's state put a tenth off it: 2400 periods to settle (a hundred and fifty ring-up times 2m/b of the
    // driver), then blocks of 120 periods (a multiple of every orbit's period up to four).
    let cfg = SettleSettings {
        rtol: 1e-10,
        block_periods: 120,
        settle_blocks: 20,
        rel_change_tol: 1e-4,
        max_blocks: 20,
    };
    let m =
        endstop::with_harvester!(&device, |h| long_record(&h, o, &cfg)).expect("the record runs");
    assert!(m.converged, "the record settles at {f_hz} Hz");
    let rel = (m.v1_rms_v / o.summary.v1_rms_v - 1.0).abs();
    assert!(
        rel <= RECORD_RMS_REL,
        "at {f_hz} Hz the record's RMS {} V against the orbit's {} V ({rel:e})",
        m.v1_rms_v,
        o.summary.v1_rms_v
    );
}

/// The steady state from the orbit's section state scaled by 1.1 (every component a tenth
/// off the orbit) under its drive, settled and measured by `cfg`.
fn long_record<M: Model<N>, const N: usize>(
    h: &M,
    o: &Orbit,
    cfg: &SettleSettings,
) -> Result<Measurement, SolverError> {
    let y: SVector<f64, N> = o.state_n::<N>() * 1.1;
    let sine = o.forcing.sine(o.phase_rad);
    settle_and_measure(h, sine, y, h.mode_of(&y), o.forcing.accel_rms_g, cfg).map(|r| r.0)
}

fn events(b: &Branch) -> Vec<(String, f64)> {
    b.events.iter().map(|e| (e.label(), e.param)).collect()
}

/// The up-converter's diagram over the third strike in a fine step, as `endstop response
/// --device data/examples/upconverter.toml --from 19 --to 19.6 --step 0.01 --accel-rms-g
/// 0.05` computes it: past the strike the branches found stall among grazings and changes of
/// stability (one of which keeps its event test's sign across its step: it is found by the
/// count of unstable multipliers and placed within the step), one stretch has no stable orbit of up to four periods and
/// is measured, not continued, and the diagram reaches the end of its range.
#[test]
fn the_upconverter_diagram_in_a_fine_step_reaches_its_end_through_measured_points() {
    let device = common::upconverter();
    let (from_hz, to_hz, step_hz) = (19.0, 19.6, 0.01);
    let start = Forcing {
        freq_hz: from_hz,
        accel_rms_g: 0.05,
    };
    let settings = ContinuationSettings::frequency(from_hz, to_hz, step_hz);
    let d = diagram_with_step(
        &device,
        start,
        &settings,
        &DiagramSettings::default(),
        step_hz,
        &Silent,
    )
    .expect("the diagram is computed");
    let reach = d
        .branches
        .iter()
        .flat_map(|b| &b.points)
        .map(|p| p.forcing.freq_hz)
        .fold(f64::NEG_INFINITY, f64::max);
    assert!(
        reach >= to_hz - step_hz,
        "the diagram reaches {reach} Hz, not the end of the range"
    );
    let measured: Vec<&DiagramPoint> = d
        .branches
        .iter()
        .filter(|b| b.kind == BranchKind::Stepped)
        .flat_map(|b| &b.points)
        .collect();
    assert!(
        !measured.is_empty(),
        "no stretch without a stable orbit: the measured path is not reached"
    );
    for p in measured {
        assert!(
            p.multipliers.is_empty() && p.residual.is_nan() && p.forcing.freq_hz > THIRD_STRIKE_HZ,
            "a measured point is no orbit and lies past the third strike: {} Hz",
            p.forcing.freq_hz
        );
        assert_eq!(p.periods as usize, STEPPED_MEASURE_PERIODS);
    }
}
