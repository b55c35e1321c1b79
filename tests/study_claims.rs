//! The study's fast claim evaluators at the published set against the scorecard's paths on
//! the same claims: the stepped up-sweeps of Figure 8 (kink and jumps), Figure 13's yes/no
//! claims and Table 3.

use endstop::device::Device;
use endstop::paper::claims::{Claims, Kind};
use endstop::paper::fig08::{self, Fig8Curve};
use endstop::paper::sensitivity::Variant;
use endstop::paper::setups::P1_BIAS_V;
use endstop::paper::study::{evaluate, evaluate_quantitative, Evaluation, Outcome, Prototype};
use endstop::paper::{fig13, table3};
use rayon::prelude::*;

fn device(text: &str) -> Device {
    Device::from_toml_str(text, "test").unwrap()
}

fn published(d: &Device) -> Variant {
    Variant {
        device: d.clone(),
        accel_scale: 1.0,
    }
}

fn find<'a>(e: &'a [Evaluation], claim: &str, quantity: &str) -> &'a Evaluation {
    e.iter()
        .find(|e| e.quantity.claim == claim && e.quantity.quantity == quantity)
        .unwrap_or_else(|| panic!("({claim}, {quantity}) is evaluated"))
}

/// Figure 8 at 5.5 g: the continuation's first grazing point is the sweep's refined impact
/// onset, and each upper fold is where the sweep leaves the impacting branch.
///
/// Tolerance: the onset is the same event (first contact) located by two methods, the sweep's
/// bracket to its half-width plus the continuation's 1e-4 Hz; we allow 0.1 Hz (the sweeps'
/// refinement tolerance). A jump is located by the sweep at or after the fold (its blocks
/// accept the dying orbit for a while past it; the response study's ghost table), never
/// before it by more than its bracket; we require fold <= sweep end + bracket and a
/// difference below 1/20 of the claim's tolerance, so that the normalised deviations the study
/// works on move by at most 0.05 (the resolution the study reports them to).
#[test]
fn prototype1_fast_path_matches_the_figure_8_sweeps_and_table_3() {
    let claims = Claims::bundled().unwrap();
    let p1 = device(include_str!("../data/prototype1.toml"));
    let fast = evaluate(Prototype::P1, &published(&p1), &claims).unwrap();
    let base = p1.with_bias(P1_BIAS_V);
    let settings = fig08::sweep_settings(&base);
    let curves = [
        ("F8-c", "jump_hertz_bim1p5_hz", Fig8Curve::Hertz1p5),
        ("F8-d", "jump_hertz_bim0_hz", Fig8Curve::Hertz0),
        ("F8-e", "jump_hertz_bim10_hz", Fig8Curve::Hertz10),
        ("F8-f", "jump_linear_bim2_hz", Fig8Curve::Linear2),
    ];
    let reports: Vec<_> = curves
        .par_iter()
        .map(|(_, _, c)| {
            let spec = c.spec();
            settings
                .run(&spec.device(&base), spec.accel_rms_g, |_| {})
                .unwrap()
        })
        .collect();
    let onset = reports[0].onset.expect("the 5.5 g sweep impacts");
    let kink = find(&fast, "F8-b", "impact_onset_5p5g_hz");
    assert!(
        (kink.value - onset.value()).abs() <= onset.half_width() + 0.1,
        "grazing {} vs onset {}",
        kink.value,
        onset.value()
    );
    for ((id, q, _), r) in curves.iter().zip(&reports) {
        let end = r.branch_end().expect("the branch ends").transition;
        let e = find(&fast, id, q);
        let fold = e.outcome.value().expect("a fold");
        let tol = claims.get(id, q).unwrap().tolerance();
        assert!(
            fold <= end.value() + end.half_width(),
            "{id}: fold {fold} after the sweep's end {}",
            end.value()
        );
        assert!(
            (fold - end.value()).abs() <= tol / 20.0,
            "{id}: fold {fold} vs sweep {}",
            end.value()
        );
    }
    let t3 = table3::claims(&table3::run(&p1, &p1), &claims);
    for v in t3.iter().filter(|v| v.claim == "T3-a") {
        let e = find(&fast, &v.claim, &v.quantity);
        // Same formula (eqs 15-18) on the same device: equal to rounding.
        assert!((e.value - v.ours).abs() <= 1e-12 * v.ours.abs());
    }
}

/// Figure 13's yes/no claims by continuation agree with the stepped sweeps' verdicts, and
/// Table 3's second column is the same formula.
#[test]
fn prototype2_fast_path_matches_figure_13_and_table_3() {
    let claims = Claims::bundled().unwrap();
    let p2 = device(include_str!("../data/prototype2.toml"));
    let fast = evaluate(Prototype::P2, &published(&p2), &claims).unwrap();
    let slow = fig13::claims(&fig13::run(&p2, &|| {}).unwrap(), &claims).unwrap();
    for v in &slow {
        let e = find(&fast, &v.claim, &v.quantity);
        assert_eq!(e.value, v.ours, "{} {}", v.claim, v.quantity);
    }
    let t3 = table3::claims(&table3::run(&p2, &p2), &claims);
    for v in t3.iter().filter(|v| v.claim == "T3-b") {
        let e = find(&fast, &v.claim, &v.quantity);
        assert!((e.value - v.ours).abs() <= 1e-12 * v.ours.abs());
    }
    assert!(fast.iter().all(|e| matches!(e.outcome, Outcome::Value(_))));
    // The calibration's objective (no continuations) is exactly the quantitative part.
    let objective = evaluate_quantitative(Prototype::P2, &published(&p2), &claims).unwrap();
    let quantitative: Vec<_> = fast
        .into_iter()
        .filter(|e| e.kind == Kind::Quantitative)
        .collect();
    assert_eq!(objective, quantitative);
}
