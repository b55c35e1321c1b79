//! The design over a measured record ([`endstop::design::record`]) against the design over
//! the sine the record holds: a record of a sine, its pre-roll discarded, must give each
//! design the power of its periodic steady state under that sine, and so the same answer.
//!
//! The case: the piezoelectric cantilever of `data/examples/piezo_cantilever.toml` at its
//! 120 Hz resonance under 0.3 g rms, where it strikes its stopper, its load free over a decade
//! either side of the matched 26.5 kohm.

use std::sync::Arc;

use endstop::design::{
    Limits, Problem, RecordObjective, SearchSettings, Verdict, Vibration, LOAD_PATH,
};
use endstop::device::{Device, ParamRange, Spacing};
use endstop::drive::swept_sine_samples;
use endstop::progress::Silent;
use endstop::study::record::transient_s;

use crate::common;

const FREQ_HZ: f64 = 120.0;
const ACCEL_RMS_G: f64 = 0.3;
/// The record's sample rate: 400 samples a period.
const FS_HZ: f64 = 48e3;
/// Whole periods of the sine analysed after the pre-roll.
const PERIODS: usize = 60;

/// How closely the record's power must match the steady state's (relative). The record's
/// pre-roll is five mechanical ring-up times `2 m / b`, after which the free transient's
/// amplitude is at most `e^-5 = 0.7 %` of its start (less: the load and the stopper damp it
/// too), and the sine's linear interpolation between samples changes its mean square by
/// `(pi f / fs)^2 / 3`, about 1e-5 at 400 samples a period; the mean over whole periods
/// leaves no partial period. 1 % bounds the transient's share.
const REL_TOL: f64 = 0.01;

fn cantilever() -> Device {
    common::device("examples/piezo_cantilever")
}

fn ranges() -> Vec<ParamRange> {
    vec![ParamRange::new(LOAD_PATH, 2.65e3, 2.65e5, Spacing::Log).unwrap()]
}

fn sine_problem() -> Problem {
    let d = cantilever();
    Problem::new(
        d.clone(),
        vec![d.interface.clone()],
        ranges(),
        Vibration {
            freqs_hz: vec![FREQ_HZ],
            accel_rms_g: ACCEL_RMS_G,
        },
        Limits::default(),
    )
    .unwrap()
}

/// The sine as a record: the device's pre-roll and then [`PERIODS`] whole periods, sampled at
/// [`FS_HZ`] from rest.
fn sine_record() -> RecordObjective {
    let preroll = (transient_s(&cantilever()) * FS_HZ).round() as usize;
    let per_period = (FS_HZ / FREQ_HZ).round() as usize;
    let n = preroll + PERIODS * per_period;
    let peak = ACCEL_RMS_G * std::f64::consts::SQRT_2 * endstop::G;
    // `swept_sine_samples` gives samples 0..=n-1 for n-1: n in all.
    let accel = swept_sine_samples(peak, FREQ_HZ, FREQ_HZ, FS_HZ, 0, n - 1);
    assert_eq!(accel.len(), n);
    RecordObjective::new(Arc::from(accel), FS_HZ)
}

fn record_problem(limits: Limits) -> Result<Problem, endstop::design::DesignError> {
    let d = cantilever();
    Problem::under_record(
        d.clone(),
        vec![d.interface.clone()],
        ranges(),
        sine_record(),
        limits,
    )
}

fn settings() -> SearchSettings {
    SearchSettings {
        samples: 8,
        polish_starts: 1,
        max_iters: 20,
        ..SearchSettings::default()
    }
}

/// Each design's power over the record is its steady-state power under the sine.
#[test]
fn a_record_of_a_sine_gives_each_design_the_sines_power() {
    let (sine, rec) = (sine_problem(), record_problem(Limits::default()).unwrap());
    let r = rec.record.as_ref().unwrap();
    // The pre-roll of every load is the cantilever's own: its ring-up does not depend on it.
    assert_eq!(r.transient_s, transient_s(&cantilever()));
    assert_eq!(r.accel_m_s2.len() - r.transient_samples(), PERIODS * 400);
    for u in [0.0, 0.25, 0.5, 0.75, 1.0] {
        let (ps, pr) = (sine.evaluate(0, &[u]), rec.evaluate(0, &[u]));
        let (ws, wr) = (ps.power_w(), pr.power_w());
        let impacts_s = ps.result.as_ref().unwrap().impacts_per_s;
        let impacts_r = pr.result.as_ref().unwrap().impacts_per_s;
        eprintln!(
            "load {:.4e} ohm: sine {ws:.6e} W, record {wr:.6e} W ({:+.3e}); impacts/s {impacts_s} and {impacts_r}",
            ps.values[0],
            wr / ws - 1.0
        );
        assert!(ws > 0.0 && wr.is_finite());
        assert!(
            (wr / ws - 1.0).abs() < REL_TOL,
            "load {} ohm: record {wr} W against the sine's {ws} W",
            ps.values[0]
        );
        // The sine strikes the stopper once a period: so must the record.
        assert_eq!(impacts_s, FREQ_HZ);
        assert!((impacts_r - impacts_s).abs() <= 1.0 / (PERIODS as f64 / FREQ_HZ));
    }
}

/// The design over the record answers as the design over the sine: its answer, judged under
/// the sine, is within the tolerance of the sine's optimum.
#[test]
fn the_design_over_a_record_of_a_sine_is_the_design_over_the_sine() {
    let sine = sine_problem().solve(&settings(), &Silent).unwrap();
    let rec = record_problem(Limits::default())
        .unwrap()
        .solve(&settings(), &Silent)
        .unwrap();
    assert_eq!(rec.answer.verdict, Verdict::Optimum);
    let (ds, dr) = (&sine.answer.design, &rec.answer.design);
    let judged = sine_problem().evaluate(0, &dr.unit).power_w();
    eprintln!(
        "sine: {:.6e} W at {:.4e} ohm; record: {:.6e} W at {:.4e} ohm, {judged:.6e} W under the sine",
        ds.power_w(),
        ds.values[0],
        dr.power_w(),
        dr.values[0]
    );
    assert!((dr.power_w() / ds.power_w() - 1.0).abs() < REL_TOL);
    assert!(judged >= ds.power_w() * (1.0 - REL_TOL));
}

/// A record measures no impact speed or contact force: their limits are refused, by name; a
/// record shorter than the pre-roll the ranges need is refused; a record has no confirmation.
#[test]
fn a_record_problem_refuses_what_it_cannot_judge() {
    let limits = Limits {
        impact_speed_m_s: Some(0.1),
        ..Limits::default()
    };
    let e = record_problem(limits).unwrap_err().to_string();
    assert!(e.contains("impact speed"), "{e}");
    let d = cantilever();
    let short = RecordObjective::new(Arc::from(vec![0.0; 1000]), FS_HZ);
    let e = Problem::under_record(
        d.clone(),
        vec![d.interface.clone()],
        ranges(),
        short,
        Limits::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("give a longer record"), "{e}");
    let p = record_problem(Limits::default()).unwrap();
    let e = p.evaluate(0, &[0.5]);
    assert!(p.confirm(&e, 1).is_none());
}
