//! Analytic claims (F5-a, F5-b, T3-a, T3-b, eq 21 of F14-a) against the paper, with the
//! tolerances of `data/claims.toml`; parameter validation; and bad input to an experiment.

use endstop::device::Device;
use endstop::device::ParamError;
use endstop::paper::claims::Claim;
use endstop::paper::claims::Claims;
use endstop::paper::claims::Verdict;
use endstop::physics::hertz::HertzLine;
use endstop::physics::hertz::EQ19_FIT_RANGE_M;
use endstop::physics::hertz::EQ19_FIT_SAMPLES;
use endstop::physics::two_port::TwoPort;
use endstop::physics::two_port::EQ21_QM;
use endstop::physics::two_port::TABLE3_QM;

const CLAIMS: &str = include_str!("../data/claims.toml");

fn claim(id: &str, quantity: &str) -> Claim {
    Claims::parse(CLAIMS)
        .map(|c| c.claims)
        .unwrap()
        .into_iter()
        .find(|c| c.id == id && c.quantity == quantity)
        .unwrap_or_else(|| panic!("no claim {id}/{quantity} in data/claims.toml"))
}

fn text(name: &str) -> String {
    std::fs::read_to_string(format!("{}/data/{name}.toml", env!("CARGO_MANIFEST_DIR"))).unwrap()
}

fn device(name: &str) -> Device {
    Device::from_toml_str(&text(name), name).unwrap()
}

#[test]
fn f5a_delta0_of_both_prototypes() {
    let d1 = HertzLine::of(&device("prototype1")).delta_scale_m() * 1e6;
    let d2 = HertzLine::of(&device("prototype2")).delta_scale_m() * 1e6;
    assert_eq!(
        claim("F5-a", "delta0_p1_um").verdict(Some(d1)),
        Verdict::Reproduced
    );
    assert_eq!(
        claim("F5-a", "delta0_p2_um").verdict(Some(d2)),
        Verdict::Reproduced
    );
}

#[test]
fn f5b_eq19_coefficient_deviates_under_the_least_squares_reading() {
    let h = HertzLine::of(&device("prototype1"));
    let fits = h.linear_fits(EQ19_FIT_RANGE_M, EQ19_FIT_SAMPLES);
    let c = fits.paper_reading();
    // Our value: 0.0556 (4 % below the printed 0.058). The quadrature is converged: 10x more
    // samples moves it by < 1e-6 relative, so a 1e-4 absolute window is about rounding only.
    let finer = h
        .linear_fits(EQ19_FIT_RANGE_M, 10 * EQ19_FIT_SAMPLES)
        .paper_reading();
    assert!(((finer - c) / c).abs() < 1e-6, "{c} vs {finer}");
    let coarse = h.linear_fits(EQ19_FIT_RANGE_M, 1001).paper_reading();
    assert!(((coarse - c) / c).abs() < 1e-5, "{c} vs {coarse}");
    assert!((c - 0.0556).abs() < 1e-4, "through-origin coefficient {c}");
    assert_eq!(
        claim("F5-b", "eq19_coefficient").verdict(Some(c)),
        Verdict::Deviates
    );
    // The secant reading lands on the printed value within its 1 % tolerance.
    assert_eq!(
        claim("F5-b", "eq19_coefficient").verdict(Some(fits.secant)),
        Verdict::Reproduced
    );
    // The coefficient does not depend on E or nu.
    let mut d = device("prototype1");
    d.material.youngs_modulus_pa = 130e9;
    d.material.poisson_ratio = 0.28;
    let c2 = HertzLine::of(&d)
        .linear_fits(EQ19_FIT_RANGE_M, EQ19_FIT_SAMPLES)
        .paper_reading();
    assert!(((c2 - c) / c).abs() < 1e-12);
}

#[test]
fn t3a_prototype1_at_30v() {
    let tp = TwoPort::of(&device("prototype1").with_bias(30.0));
    let qm = tp.qm(TABLE3_QM);
    assert_eq!(
        claim("T3-a", "k2_pct_p1").verdict(Some(tp.k2 * 100.0)),
        Verdict::Reproduced
    );
    assert_eq!(
        claim("T3-a", "qm_p1").verdict(Some(qm)),
        Verdict::Reproduced
    );
    assert_eq!(
        claim("T3-a", "k2qm_p1").verdict(Some(tp.k2 * qm)),
        Verdict::Reproduced
    );
}

#[test]
fn t3b_prototype2_at_15v_k2_deviates_by_a_hair() {
    let tp = TwoPort::of(&device("prototype2").with_bias(15.0));
    let qm = tp.qm(TABLE3_QM);
    // Eq 18 with Table 2 gives k^2 = 2.5453 %, 1.004 % above the printed 2.52 %: just outside
    // the 1 % tolerance. Closed-form arithmetic, so 1e-4 % is about rounding only.
    assert!(
        (tp.k2 * 100.0 - 2.5453).abs() < 1e-4,
        "k2 = {}",
        tp.k2 * 100.0
    );
    assert_eq!(
        claim("T3-b", "k2_pct_p2").verdict(Some(tp.k2 * 100.0)),
        Verdict::Deviates
    );
    assert_eq!(
        claim("T3-b", "qm_p2").verdict(Some(qm)),
        Verdict::Reproduced
    );
    // k^2 Qm inherits the k^2 excess: 5.18 vs 5.125.
    assert!((tp.k2 * qm - 5.1816).abs() < 1e-3, "k2 Qm = {}", tp.k2 * qm);
    assert_eq!(
        claim("T3-b", "k2qm_p2").verdict(Some(tp.k2 * qm)),
        Verdict::Deviates
    );
}

#[test]
fn f14a_eq21_efficiency_of_prototype2() {
    let tp = TwoPort::of(&device("prototype2").with_bias(15.0));
    let eff = tp.broadband_efficiency(tp.qm(EQ21_QM)) * 100.0;
    assert_eq!(
        claim("F14-a", "eff_eq21_pct").verdict(Some(eff)),
        Verdict::Reproduced
    );
    // Prototype 1's "about 3 %".
    let tp1 = TwoPort::of(&device("prototype1").with_bias(30.0));
    let eff1 = tp1.broadband_efficiency(tp1.qm(EQ21_QM)) * 100.0;
    assert!(
        (eff1 - 3.0).abs() < 0.5,
        "prototype 1 eq 21 efficiency {eff1} %"
    );
}

#[test]
fn eq21_power_is_linear_in_the_input_psd() {
    let tp = TwoPort::of(&device("prototype2").with_bias(15.0));
    let q = tp.qm(EQ21_QM);
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
        ("c0_f = 1.6e-12", "c0_f = -1.6e-12", "electrical.c0_f"),
        ("cp_f = 17.3e-12", "cp_f = -1e-12", "electrical.cp_f"),
        (
            "endstop_gap_m = 7e-6",
            "endstop_gap_m = 12e-6",
            "geometry.endstop_gap_m",
        ),
        (
            "poisson_ratio = 0.22",
            "poisson_ratio = 0.7",
            "material.poisson_ratio",
        ),
        (
            "youngs_modulus_pa = 169e9",
            "youngs_modulus_pa = 0.0",
            "material.youngs_modulus_pa",
        ),
        (
            "load_resistance_ohm = 4.9e6",
            "load_resistance_ohm = inf",
            "electrical.load_resistance_ohm",
        ),
        (
            "damping_n_s_per_m = 1.5",
            "damping_n_s_per_m = -1.5",
            "endstop.damping_n_s_per_m",
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
    let bad_law = replace(&t, "stiffness = \"hertz\"", "stiffness = \"rubber\"");
    assert!(Device::from_toml_str(&bad_law, "p1.toml").is_err());
}
