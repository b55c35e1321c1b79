//! The nonlinear-spring rows of the book's validation chapter, each asserted: the exact
//! stationary law of random vibration for a hardening device, a bistable device with stops and
//! a linear device with asymmetric lossless stops; Kramers' escape rate over a double well's
//! barrier; NLvib's Duffing example. Cases in `endstop::validation::spring_cases`; each test
//! prints its checks and fails on the first one outside its tolerance.

use endstop::validation::spring_cases;

use crate::common::validation::{assert_all, device};

fn stationary(i: usize) {
    let (name, psd) = spring_cases::STATIONARY_CASES[i];
    let (_, checks) = spring_cases::stationary(&device(name), psd).unwrap();
    assert_all(&checks);
}

/// A hardening (Duffing) device: histogram, E[x^2], E[v^2] and load power against the exact
/// stationary law (40 records of 10 s).
#[test]
fn hardening_device_follows_the_exact_stationary_law() {
    stationary(0);
}

/// A bistable device with lossless linear stops: also the share of time past each stop and in
/// each well.
#[test]
fn bistable_device_with_stops_follows_the_exact_stationary_law() {
    stationary(1);
}

/// A linear device with an asymmetric lossless Hertz point stop and a linear stop.
#[test]
fn linear_device_with_asymmetric_lossless_stops_follows_the_exact_stationary_law() {
    stationary(2);
}

/// The well-to-well rate at three barrier heights against Kramers' law, and its slope in
/// dU/theta against -1 (3 x 48 records of 10 s).
#[test]
fn escape_over_the_barrier_follows_kramers_law() {
    let (_, checks) = spring_cases::kramers(&device(spring_cases::KRAMERS_DEVICE)).unwrap();
    assert_all(&checks);
}

/// NLvib's Duffing example: folds, amplitudes and stability of NLvib-py's harmonic balance for
/// H = 1 to 15 against our shooting continuation.
#[test]
fn nlvib_duffing_example_converges_to_our_branch() {
    use endstop::validation::nlvib_duffing::{self, DuffingReference, Ours};
    let dir =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data/references/nlvib_duffing");
    let reference = DuffingReference::parse(|name| {
        std::fs::read_to_string(dir.join(name)).map_err(|e| {
            endstop::validation::ValidationError::Reference {
                file: name.to_string(),
                message: e.to_string(),
            }
        })
    })
    .unwrap();
    let d = device("nlvib_duffing");
    let ours = Ours::new(&d);
    let branch = ours
        .branch(0.5, 1.6, spring_cases::NLVIB_DUFFING_MAX_STEP_RAD_S)
        .unwrap();
    let hb = nlvib_duffing::hb_convergence(&ours, &branch, &reference).unwrap();
    for c in &hb {
        eprintln!(
            "H = {}: folds {:?} ours {:?}, {} points, worst a1 difference {:e}",
            c.harmonics,
            c.folds,
            c.our_folds,
            c.points.len(),
            c.worst_amplitude_difference()
        );
    }
    assert_all(&nlvib_duffing::checks(&hb));
}
