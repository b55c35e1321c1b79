//! Analytic claims (F5-a, F5-b, T3-a, T3-b, eq 21 of F14-a) against the paper, through the
//! same `claims` functions as the fig05 and table3 binaries, with the tolerances of
//! `data/claims.toml`; parameter validation. Our own values are pinned in
//! `tests/regression_analytic.rs`.

use endstop::device::Device;
use endstop::device::ParamError;
use endstop::paper::claims::{keys, ClaimKey, Value, Verdict};
use endstop::paper::figures::fig05::Fig05;
use endstop::paper::figures::table3::Table3;
use endstop::paper::qm::EQ21_QM;
use endstop::paper::setups::ParamSet;
use endstop::paper::Figure;
use endstop::physics::hertz::HertzLine;
use endstop::physics::hertz::EQ19_FIT_RANGE_M;
use endstop::physics::hertz::EQ19_FIT_SAMPLES;
use endstop::physics::two_port::TwoPort;

use Verdict::{Deviates, Reproduced};

use crate::common;
use common::{claims, device, device_text as text, prototypes};

/// Asserts that `values` are exactly the rows of `expected`, all under the published set,
/// with the expected verdicts, and returns our values in that order.
fn assert_verdicts(values: &[Value], expected: &[(ClaimKey, Verdict)]) -> Vec<f64> {
    let got: Vec<(&str, &str)> = values
        .iter()
        .map(|v| (v.claim.as_str(), v.quantity.as_str()))
        .collect();
    let want: Vec<(&str, &str)> = expected.iter().map(|e| (e.0.id, e.0.quantity)).collect();
    assert_eq!(got, want);
    expected
        .iter()
        .zip(values)
        .map(|(&(key, verdict), v)| {
            assert_eq!(v.set, ParamSet::Published);
            let c = claims().claim(key).unwrap();
            println!(
                "{key}: ours {}, paper {} ± {}",
                v.ours.to_f64(),
                c.paper.to_f64(),
                c.tolerance()
            );
            assert_eq!(c.verdict(Some(v.ours)), verdict, "{key}: {:?}", v.ours);
            v.ours.to_f64()
        })
        .collect()
}

fn fig05_values() -> Vec<Value> {
    let run = Fig05::run(&prototypes(), &|| {}).unwrap();
    Fig05::claims(&run, claims()).unwrap()
}

#[test]
fn f5a_delta0_of_both_prototypes_and_f5b_deviates_under_our_reading() {
    assert_verdicts(
        &fig05_values(),
        &[
            (keys::F5A_DELTA0_P1, Reproduced),
            (keys::F5A_DELTA0_P2, Reproduced),
            (keys::F5B_EQ19_COEFFICIENT, Deviates),
        ],
    );
}

#[test]
fn f5b_eq19_coefficient_is_converged_and_the_secant_reading_matches_the_print() {
    let run = Fig05::run(&prototypes(), &|| {}).unwrap();
    let fits = run.prototypes[0].fits;
    let c = fits.paper_reading();
    let h = HertzLine::of_device(&device("prototype1")).unwrap();
    // The quadrature is converged: 10x more samples moves it by < 1e-6 relative, 10x fewer by
    // < 1e-5.
    let finer = h
        .linear_fits(EQ19_FIT_RANGE_M, 10 * EQ19_FIT_SAMPLES)
        .paper_reading();
    assert!(((finer - c) / c).abs() < 1e-6, "{c} vs {finer}");
    let coarse = h.linear_fits(EQ19_FIT_RANGE_M, 1001).paper_reading();
    assert!(((coarse - c) / c).abs() < 1e-5, "{c} vs {coarse}");
    // The secant reading lands on the printed value within its 1 % tolerance.
    let claim = claims().claim(keys::F5B_EQ19_COEFFICIENT).unwrap();
    assert_eq!(claim.verdict(Some(fits.secant.into())), Reproduced);
    // The coefficient does not depend on E or nu.
    let d = endstop::paper::setups::with_hertz(&device("prototype1"), |h| {
        h.youngs_modulus_pa = 130e9;
        h.poisson_ratio = 0.28;
    });
    let c2 = HertzLine::of_device(&d)
        .unwrap()
        .linear_fits(EQ19_FIT_RANGE_M, EQ19_FIT_SAMPLES)
        .paper_reading();
    assert!(((c2 - c) / c).abs() < 1e-12);
}

fn table3_values() -> Vec<Value> {
    let run = Table3::run(&prototypes(), &|| {}).unwrap();
    Table3::claims(&run, claims()).unwrap()
}

#[test]
fn t3_coupling_and_quality_factors_with_eq21() {
    let ours = assert_verdicts(
        &table3_values(),
        &[
            (keys::T3A_K2_P1, Reproduced),
            (keys::T3A_QM_P1, Reproduced),
            (keys::T3A_K2QM_P1, Reproduced),
            // Eq 18 with Table 2 gives k^2 just outside the 1 % tolerance of the printed 2.52 %,
            // and k^2 Qm inherits the excess.
            (keys::T3B_K2_P2, Deviates),
            (keys::T3B_QM_P2, Reproduced),
            (keys::T3B_K2QM_P2, Deviates),
            (keys::F14A_EFF_EQ21, Reproduced),
        ],
    );
    // "By a hair": prototype 2's k^2 misses the printed value by less than twice the
    // tolerance (a rounding of the paper's inputs, not a different formula).
    let c = claims().claim(keys::T3B_K2_P2).unwrap();
    assert!(
        (ours[3] - c.paper.to_f64()).abs() < 2.0 * c.tolerance(),
        "{}",
        ours[3]
    );
}

#[test]
fn prototype1_eq21_efficiency_is_about_3_percent() {
    // The paper's "about 3 %" for prototype 1 (no tolerance class: "about" read as ± 0.5 %).
    let run = Table3::run(&prototypes(), &|| {}).unwrap();
    let eff1 = run.prototypes[0].eq21_efficiency() * 100.0;
    assert!(
        (eff1 - 3.0).abs() < 0.5,
        "prototype 1 eq 21 efficiency {eff1} %"
    );
}

#[test]
fn eq21_power_is_linear_in_the_input_psd() {
    let tp = TwoPort::of(&device("prototype2").with_bias(15.0));
    let q = EQ21_QM.of(&tp);
    let p1 = tp.broadband_power_w(1.0, q);
    let p2 = tp.broadband_power_w(3.0, q);
    assert!((p2 / p1 - 3.0).abs() < 1e-12);
}

fn replace(text: &str, from: &str, to: &str) -> String {
    assert!(text.contains(from), "{from} not in file");
    text.replacen(from, to, 1)
}

#[test]
fn validation_names_the_field_the_value_and_the_range() {
    let t = text("prototype1");
    let cases = [
        ("mass_kg = 2.8e-6", "mass_kg = -2.8e-6", "mechanics.mass_kg"),
        (
            "stiffness_n_per_m = 166.5",
            "stiffness_n_per_m = 0.0",
            "mechanics.stiffness_n_per_m",
        ),
        (
            "damping_n_s_per_m = 3.75e-3",
            "damping_n_s_per_m = nan",
            "mechanics.damping_n_s_per_m",
        ),
        ("c0_f = 1.6e-12", "c0_f = -1.6e-12", "transducer.c0_f"),
        ("cp_f = 17.3e-12", "cp_f = -1e-12", "transducer.cp_f"),
        ("gap_m = 7e-6", "gap_m = 12e-6", "stops.both.gap_m"),
        (
            "poisson_ratio = 0.22",
            "poisson_ratio = 0.7",
            "stops.both.poisson_ratio",
        ),
        (
            "youngs_modulus_pa = 169e9",
            "youngs_modulus_pa = 0.0",
            "stops.both.youngs_modulus_pa",
        ),
        (
            "load_resistance_ohm = 4.9e6",
            "load_resistance_ohm = inf",
            "transducer.load_resistance_ohm",
        ),
        (
            "damping_n_s_per_m = 1.5",
            "damping_n_s_per_m = -1.5",
            "stops.both.damping_n_s_per_m",
        ),
    ];
    for (from, to, field) in cases {
        let err = Device::from_toml_str(&replace(&t, from, to), "p1.toml").unwrap_err();
        let msg = err.to_string();
        assert!(
            matches!(&err, ParamError::OutOfRange { field: f, .. } if f == field),
            "{to}: {msg}"
        );
        assert!(
            msg.contains("p1.toml") && msg.contains(field) && msg.contains("must be"),
            "{msg}"
        );
    }
}

#[test]
fn unknown_and_missing_fields_are_rejected() {
    let t = text("prototype1");
    let unknown = replace(&t, "mass_kg = 2.8e-6", "mass_kg = 2.8e-6\nmas_kg = 1.0");
    let err = Device::from_toml_str(&unknown, "p1.toml")
        .unwrap_err()
        .to_string();
    assert!(err.contains("mas_kg"), "{err}");
    let missing = replace(&t, "mass_kg = 2.8e-6", "");
    let err = Device::from_toml_str(&missing, "p1.toml")
        .unwrap_err()
        .to_string();
    assert!(err.contains("mass_kg"), "{err}");
    let bad_law = replace(&t, "law = \"hertz_line\"", "law = \"rubber\"");
    assert!(Device::from_toml_str(&bad_law, "p1.toml").is_err());
}
