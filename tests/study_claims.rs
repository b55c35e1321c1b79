//! The study's fast claim evaluators at the published set against the scorecard's paths on
//! the same claims: the stepped up-sweeps of Figure 8 (kink and jumps), Figure 9's amplitude
//! sweeps (onsets and powers), Figure 13's yes/no claims, Table 3, and the ensemble claims of
//! Figures 12, 14 and 15 (the same protocol as the figures').

use endstop::device::Device;
use endstop::paper::claims::{Claims, Kind};
use endstop::paper::deviations::Variant;
use endstop::paper::deviations::{
    ensembles::study_ensemble_spec, evaluate, evaluate_quantitative, Evaluation, Outcome,
    Prototype, Scope,
};
use endstop::paper::ensembles::{protocol_spec, P1_BAND_HZ, P1_NPERSEG};
use endstop::paper::figures::fig08::{self, Fig8Curve};
use endstop::paper::figures::fig09::{self, Fig9Bias};
use endstop::paper::figures::fig12::FIG12_LEVELS;
use endstop::paper::figures::fig15::{self, Fig15};
use endstop::paper::figures::{fig13::Fig13, table3::Table3};
use endstop::paper::setups::{prototype2_setup, Prototypes, P1_BIAS_V, P2_BIAS_V};
use endstop::paper::Figure;
use endstop::progress::Silent;
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
    let fast = evaluate(Prototype::P1, &published(&p1), &claims, Scope::default()).unwrap();
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
                .run(&spec.device(&base), spec.accel_rms_g, &Silent)
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
    // The order of the jumps (F8-e): Figure 8's rule on the sweeps (every Hertz sweep jumps,
    // and the jumps fall as b_im grows) against the fast path's (every upper fold drops the
    // power by a jump's drop, and the folds fall).
    let jump = |i: usize| reports[i].jump.map(|t| t.value());
    let sweep_order = match (jump(1), jump(0), jump(2)) {
        (Some(j0), Some(j15), Some(j10)) => fig08::jumps_fall_as_bim_grows(j0, j15, j10),
        _ => false,
    };
    assert_eq!(
        find(&fast, "F8-e", "jump_order_by_bim").value,
        if sweep_order { 1.0 } else { 0.0 }
    );
    let both = Prototypes {
        prototype1: p1.clone(),
        prototype2: p1.clone(),
    };
    let t3 = Table3::claims(&Table3::run(&both, &|| {}).unwrap(), &claims).unwrap();
    // Every quantity of the claims file's T3-a, each compared: an empty selection (a renamed
    // claim, a table that lost a row) fails here instead of comparing nothing.
    let rows: Vec<_> = t3.iter().filter(|v| v.claim == "T3-a").collect();
    let stated = claims.claims.iter().filter(|c| c.id == "T3-a").count();
    assert!(
        stated > 0 && rows.len() == stated,
        "T3-a: {} rows of Table 3 for the claims file's {stated} quantities",
        rows.len()
    );
    for v in rows {
        let e = find(&fast, &v.claim, &v.quantity);
        // Same formula (eqs 15-18) on the same device: equal to rounding.
        assert!((e.value - v.ours.to_f64()).abs() <= 1e-12 * v.ours.to_f64().abs());
    }
}

/// Figure 13's yes/no claims by continuation agree with the stepped sweeps' verdicts, and
/// Table 3's second column is the same formula.
#[test]
fn prototype2_fast_path_matches_figure_13_and_table_3() {
    let claims = Claims::bundled().unwrap();
    let p2 = device(include_str!("../data/prototype2.toml"));
    let fast = evaluate(Prototype::P2, &published(&p2), &claims, Scope::default()).unwrap();
    let slow = Fig13::claims(&Fig13::run(&p2, &|| {}).unwrap(), &claims).unwrap();
    for v in &slow {
        let e = find(&fast, &v.claim, &v.quantity);
        assert_eq!(e.value, v.ours.to_f64(), "{} {}", v.claim, v.quantity);
    }
    let both = Prototypes {
        prototype1: p2.clone(),
        prototype2: p2.clone(),
    };
    let t3 = Table3::claims(&Table3::run(&both, &|| {}).unwrap(), &claims).unwrap();
    // Every quantity of the claims file's T3-b, each compared: an empty selection (a renamed
    // claim, a table that lost a row) fails here instead of comparing nothing.
    let rows: Vec<_> = t3.iter().filter(|v| v.claim == "T3-b").collect();
    let stated = claims.claims.iter().filter(|c| c.id == "T3-b").count();
    assert!(
        stated > 0 && rows.len() == stated,
        "T3-b: {} rows of Table 3 for the claims file's {stated} quantities",
        rows.len()
    );
    for v in rows {
        let e = find(&fast, &v.claim, &v.quantity);
        assert!((e.value - v.ours.to_f64()).abs() <= 1e-12 * v.ours.to_f64().abs());
    }
    assert!(fast.iter().all(|e| matches!(e.outcome, Outcome::Value(_))));
    // The calibration's objective (no continuations) is exactly the quantitative part.
    let objective =
        evaluate_quantitative(Prototype::P2, &published(&p2), &claims, Scope::default()).unwrap();
    let quantitative: Vec<_> = fast
        .into_iter()
        .filter(|e| e.kind == Kind::Quantitative)
        .collect();
    assert_eq!(objective, quantitative);
}

/// Figure 9 at 1220 Hz: the amplitude continuation's first grazing point is the amplitude
/// sweep's refined onset and its orbit at 5.5 g has the sweep's power.
///
/// Tolerances: the onset is the same event (first contact) located two ways, the sweep's
/// bracket to its half-width, the continuation's to 1e-6 g; we allow the half-width plus the
/// sweep's 0.005 g refinement tolerance. The power of the periodic orbit and of the sweep's
/// steady state must agree within Figure 9's own convergence limit
/// ([`fig09::CONV_RMS_REL`]).
#[test]
fn prototype1_fast_path_matches_the_figure_9_sweeps() {
    let claims = Claims::bundled().unwrap();
    let p1 = device(include_str!("../data/prototype1.toml"));
    let fast = evaluate(Prototype::P1, &published(&p1), &claims, Scope::default()).unwrap();
    let protocol = fig09::Protocol::new(&p1);
    let curves = fig09::run_biases(&p1, &protocol.settings, &|| {}).unwrap();
    for c in &curves {
        let onset = c.report.onset.expect("every bias impacts by 8 g");
        let e = find(&fast, "F9-a", c.bias.onset_key().quantity);
        assert!(
            (e.value - onset.value()).abs() <= onset.half_width() + 0.005,
            "{:?}: grazing {} g vs onset {} g",
            c.bias,
            e.value,
            onset.value()
        );
    }
    for (bias, quantity) in [
        (Fig9Bias::V20, "p_sat_20v_nw"),
        (Fig9Bias::V40, "p_sat_40v_nw"),
    ] {
        let curve = curves.iter().find(|c| c.bias == bias).expect("every bias");
        let sweep = curve.report.at_stop().p1_w * 1e9;
        let e = find(&fast, "F9-b", quantity);
        assert!(
            (e.value / sweep - 1.0).abs() <= fig09::CONV_RMS_REL,
            "{quantity}: orbit {} nW vs sweep {sweep} nW",
            e.value
        );
    }
}

/// The study's ensembles are the figures' ensembles: at scale 1 and the figures' 32 records
/// the settings are Figure 12's and Figure 15's (less Figure 15's second segmenting, which no
/// study quantity reads), and a drive scale multiplies the level by its square and nothing
/// else (the streams stay the stated level's). With 4 records the study's prototype 2
/// quantities are Figure 15's and Figure 14's estimators on the same records: equal to
/// rounding.
#[test]
fn the_study_ensembles_are_the_figures_protocol() {
    let p1 = device(include_str!("../data/prototype1.toml")).with_bias(P1_BIAS_V);
    for sa in FIG12_LEVELS {
        let fig = protocol_spec(&p1, sa, P1_NPERSEG, P1_BAND_HZ, 32, false);
        assert_eq!(
            study_ensemble_spec(&p1, sa, (P1_NPERSEG, P1_BAND_HZ), 32, 1.0),
            fig
        );
        let mut scaled = study_ensemble_spec(&p1, sa, (P1_NPERSEG, P1_BAND_HZ), 32, 1.2);
        // 1.2 * 1.2 against 1.44: the same number to a few ulps.
        assert!((scaled.record.noise.psd_g2_per_hz / (1.44 * sa) - 1.0).abs() < 1e-15);
        scaled.record.noise.psd_g2_per_hz = sa;
        assert_eq!(scaled, fig);
    }
    let claims = Claims::bundled().unwrap();
    let p2 = device(include_str!("../data/prototype2.toml"));
    let dev = prototype2_setup(&p2);
    assert_eq!(dev, p2.with_bias(P2_BIAS_V));
    const R: usize = 4;
    let setup = fig15::Setup {
        prototype2: p2.clone(),
        records: R,
    };
    let run = Fig15::run(&setup, &|| {}).unwrap();
    let f = fig15::findings(&run, &claims);
    let scope = Scope {
        ensemble_records: Some(R),
    };
    let fast = evaluate_quantitative(Prototype::P2, &published(&p2), &claims, scope).unwrap();
    let all = evaluate(Prototype::P2, &published(&p2), &claims, scope).unwrap();
    assert_eq!(find(&fast, "F15-a", "peak_0p34e-3_hz").value, f.peak_hz);
    assert_eq!(
        find(&fast, "F15-a", "bw_0p34e-3_hz").value,
        f.widths[fig15::L034].estimate
    );
    assert_eq!(
        find(&fast, "F15-b", "bw_ratio_0p55e-3_over_0p34e-3").value,
        f.ratio.0
    );
    let widening = find(&all, "F15-c", "widening_up_1p69e-3").value;
    assert_eq!(widening, if f.widening_up { 1.0 } else { 0.0 });
    let eff = run.levels[fig15::L169].ens.efficiency.mean * 100.0;
    let e = find(&fast, "F14-b", "eff_1p69e-3_pct").value;
    // Mean of the records' efficiencies against the efficiency of the mean power: the same
    // sum in another order.
    assert!((e / eff - 1.0).abs() < 1e-12, "{e} vs {eff}");
}
