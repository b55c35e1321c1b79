//! The nonlinear-spring rows of the book's validation chapter, each asserted: the exact
//! stationary law of random vibration for a hardening device, a bistable device with stops and
//! a linear device with asymmetric lossless stops; the escape over a double well's barrier
//! (passages and settled escapes, at moderate and light damping); NLvib's Duffing example.
//! Cases in `endstop::validation::spring_cases`; each test prints its checks and fails on the
//! first one outside its tolerance.

use endstop::validation::spring_cases;

use crate::common::validation::{assert_all, device};

fn stationary(i: usize) {
    let (name, psd) = spring_cases::STATIONARY_CASES[i];
    let (_, checks) = spring_cases::stationary(&device(name), psd).unwrap();
    assert_all(&checks);
}

/// A hardening (Duffing) device: histogram, E[x^2] and E[v^2] against the exact
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

fn escapes(i: usize) {
    let case = spring_cases::ESCAPE_CASES[i];
    let (levels, checks) = spring_cases::escapes(&device(case.file), &case).unwrap();
    for l in &levels {
        eprintln!("{:?}", l.theory);
    }
    assert_all(&checks);
}

/// Moderate damping: at two barrier heights the barrier passages against Rice's count on the
/// exact law, and the escapes that settle in the other well against Kramers' rate (2 x 48
/// records of 10 s).
#[test]
fn escape_at_moderate_damping_follows_kramers_rate() {
    escapes(0);
}

/// Light damping: the barrier passages against Rice's count, and the settled escapes, several
/// times fewer, against the energy-diffusion limit (160 records of 10 s).
#[test]
fn escape_at_light_damping_follows_the_energy_diffusion_limit() {
    escapes(1);
}

/// Mel'nikov and Meshkov's depopulation factor has its limits (HTB 1990): `A(Delta) / Delta
/// -> 1` as `Delta -> 0`, its next order about `0.82 sqrt(Delta)` (so within 10 % at 1e-2),
/// and `A -> 1` for a large loss (within `exp(-Delta / 4)`).
#[test]
fn the_depopulation_factor_has_its_limits() {
    use endstop::validation::kramers::depopulation;
    let small = depopulation(1e-4) / 1e-4;
    assert!((small - 1.0).abs() < 0.02, "{small}");
    assert!((depopulation(1e-2) / 1e-2 - 1.0).abs() < 0.1);
    assert!(1.0 - depopulation(40.0) < (-10.0f64).exp());
    let one = depopulation(1.0);
    assert!(one > 0.4 && one < 0.5, "{one}");
}

/// The energy-diffusion rate of the quartic well tends to its high-barrier form
/// `gamma (I_b / theta) (w_0 / 2 pi) exp(-dU / theta)` as `theta / dU` falls (a finite
/// barrier's corrections are of order `theta / dU` and its logarithm), and the barrier orbit's
/// action is its closed form `(8/3) x_w sqrt(m dU)` (quadrature to 1e-9).
#[test]
fn the_energy_diffusion_rate_tends_to_its_high_barrier_form() {
    use endstop::validation::kramers::{barrier_action_j_s, energy_diffusion_escape_per_s};
    let (m, xw, du) = (1e-3, 1e-4, 1e-6);
    let ib = barrier_action_j_s(m, xw, du);
    assert!((ib / (8.0 / 3.0 * xw * (m * du).sqrt()) - 1.0).abs() < 1e-9);
    let w0 = (8.0 * du / (m * xw * xw)).sqrt();
    let ratio = |beta: f64| {
        let theta = du / beta;
        let high = ib / theta * w0 / (2.0 * std::f64::consts::PI) * (-beta).exp();
        energy_diffusion_escape_per_s(m, xw, du, 1.0, theta) / high
    };
    let (r10, r40, r160) = (ratio(10.0), ratio(40.0), ratio(160.0));
    eprintln!("ratios at dU/theta = 10, 40, 160: {r10} {r40} {r160}");
    assert!((r160 - 1.0).abs() < (r40 - 1.0).abs(), "{r40} {r160}");
    assert!((r40 - 1.0).abs() < (r10 - 1.0).abs(), "{r10} {r40}");
    assert!((r160 - 1.0).abs() < 0.05, "{r160}");
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
    let ours = Ours::new(&d).unwrap();
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
