//! Snapshot regression suite of our own random-vibration numbers (Figures 10, 11, 12, 14, 15): the
//! widths, efficiencies and contact statistics of the figures' ensembles, pinned with `insta`
//! under `tests/snapshots/` so that a change in any of them shows. These are characterisation
//! numbers, not claims; the claims' verdicts are asserted in `tests/record_figures.rs`, which
//! includes this module so that both share one simulation of each figure.
//!
//! Rounding (the records are seeded, so the numbers are deterministic; the rounding decides
//! which changes of the code count as a regression):
//! * an ensemble without impacts (and the generated noise of Figure 10): 4 significant
//!   digits. Without impacts the trajectory itself converges: a 1000 times tighter integrator
//!   tolerance moves a record's power by less than 1e-6 (relative,
//!   `record_converges_and_keeps_its_bookkeeping`), far below the 5e-5 of the fourth digit;
//! * an ensemble with impacts: to the decade of its 95 % half-width, the last digit a
//!   value with its CI would be printed with (30.33 ± 0.29 is pinned as 30.3, 244.6 ± 10.3
//!   as 240). With impacts a record does not converge (nearby trajectories part after a few
//!   impacts); only the statistics do, within their CI: a hundred times tighter tolerance
//!   moves the mean power at 1.69e-3 g²/Hz by less than 1 %
//!   (`impacting_regime_statistics_converge`). Digits below the CI are sampling noise.
//!
//! So a change that leaves every trajectory alone keeps every snapshot, and a legitimate
//! change of the integrator or of the model's arithmetic, which changes the impacting
//! trajectories, can move those numbers by a fraction of their CI and flip their last pinned
//! digit: review it (`INSTA_UPDATE=always cargo test --release --test all -- record_figures::regression`,
//! then `git diff tests/snapshots`) and accept it when every move is within the CI. A change
//! that draws other realisations of the records (the excitation's synthesis) moves every
//! number, with or without impacts, and is reviewed the same way.

use std::fmt::Write;

use endstop::num::stats::MeanCi;
use endstop::paper::claims::{keys, Value};
use endstop::paper::ensembles::{level_label, Level, WidthReading};
use endstop::paper::figures::fig10::{self, Fig10};
use endstop::paper::figures::fig11::{self, Fig11};
use endstop::paper::figures::fig12::{self, Fig12};
use endstop::paper::figures::fig14::{self, Fig14};
use endstop::paper::figures::fig15::{self, Fig15};
use endstop::paper::setups::ParamSet;
use endstop::paper::Figure;

use super::{claims, fig10_run, fig11_run, fig12_run, fig14_run, fig15_run};

/// `x` rounded to `n` significant digits (fixed notation from 1e-3 to 1e5, scientific
/// outside).
fn sig(x: f64, n: i32) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let e = x.abs().log10().floor() as i32;
    if !(-3..5).contains(&e) {
        return format!("{:.*e}", (n - 1).max(0) as usize, x);
    }
    let unit = 10f64.powi(e - n + 1);
    let decimals = (n - 1 - e).max(0) as usize;
    format!("{:.decimals$}", (x / unit).round() * unit + 0.0)
}

/// `x` as pinned (see the module docs): 4 significant digits when `converged`, else down to
/// the decade of its 95 % half-width `ci` (0 when `x` is below that decade; 3 significant
/// digits when `ci` is not a positive number).
fn pin(x: f64, ci: f64, converged: bool) -> String {
    if converged || !x.is_finite() {
        return sig(x, 4);
    }
    if !(ci.is_finite() && ci > 0.0) {
        return sig(x, 3);
    }
    let digits = x.abs().log10().floor() as i32 - ci.log10().floor() as i32 + 1;
    if digits < 1 {
        return "0".to_string();
    }
    sig(x, digits)
}

/// One line per claim value: key, our value pinned, and the rounding used.
fn claim_lines(out: &mut String, values: &[Value], converged: impl Fn(&Value) -> bool) {
    for v in values {
        let ci = v.uncertainty.unwrap_or(f64::NAN);
        writeln!(
            out,
            "{} {} {}: {}",
            v.claim,
            v.quantity,
            v.set,
            pin(v.ours.to_f64(), ci, converged(v))
        )
        .unwrap();
    }
}

/// One line per level: widths of the ensemble-mean PSD (both readings), efficiency, time in
/// contact and the mean single-record 3 dB width, each pinned.
fn level_line(out: &mut String, l: &Level) {
    let e = &l.ens;
    let conv = e.no_impact();
    let [w3, w6] = WidthReading::ALL.map(|r| r.mean_width(e));
    let single = MeanCi::of(&e.single_bw3db_hz());
    writeln!(
        out,
        "{} {}: bw3db {} Hz, bw6db {} Hz, efficiency {} %, contact {}, single bw3db {} Hz",
        l.set,
        level_label(l.sa()),
        pin(w3.estimate, w3.ci95, conv),
        pin(w6.estimate, w6.ci95, conv),
        pin(e.efficiency.mean * 100.0, e.efficiency.ci95 * 100.0, conv),
        pin(e.contact_fraction.mean, e.contact_fraction.ci95, conv),
        pin(single.mean, single.ci95, conv),
    )
    .unwrap();
}

fn snapshot(name: &str, text: &str) {
    insta::with_settings!({ snapshot_path => "../snapshots", prepend_module_to_snapshot => false }, {
        insta::assert_snapshot!(format!("record_{name}"), text);
    });
}

#[test]
fn regression_fig10_generated_noise() {
    let run = fig10_run();
    let f = fig10::findings(run);
    let mut s = String::new();
    claim_lines(&mut s, &Fig10::claims(run, claims()).unwrap(), |_| true);
    writeln!(s, "mean square: {} g²", sig(f.mean_square.mean, 4)).unwrap();
    writeln!(s, "example level: {} g²/Hz", sig(f.example_level, 4)).unwrap();
    writeln!(s, "example edge: {} Hz", sig(f.example_edge_hz, 4)).unwrap();
    writeln!(
        s,
        "example bin scatter: {}",
        sig(f.example_bin_relative_std, 4)
    )
    .unwrap();
    snapshot("fig10", &s);
}

#[test]
fn regression_fig11_prototype1_low_levels() {
    let run = fig11_run();
    let mut s = String::new();
    // Every level of Figure 11 is free of impacts (asserted in tests/record_figures.rs).
    claim_lines(&mut s, &Fig11::claims(run, claims()).unwrap(), |_| true);
    for set in ParamSet::BOTH {
        let f = fig11::findings(run, set);
        let r = &f.single_ratio;
        writeln!(
            s,
            "{set}: half-amplitude ratio {}, single-record ratio mean {} std {}",
            sig(f.ratio_half_amplitude.0, 4),
            sig(r.mean, 4),
            sig(r.std, 4)
        )
        .unwrap();
    }
    for l in &run.levels {
        level_line(&mut s, l);
    }
    snapshot("fig11", &s);
}

#[test]
fn regression_fig12_prototype1_high_levels() {
    let run = fig12_run();
    let mut s = String::new();
    claim_lines(&mut s, &Fig12::claims(run, claims()).unwrap(), |_| false);
    for set in ParamSet::BOTH {
        let f = fig12::findings(run, set, WidthReading::HalfAmplitude);
        writeln!(
            s,
            "{set}: half-amplitude ratio {}",
            pin(f.ratio.0, f.ratio.1, false)
        )
        .unwrap();
    }
    for l in &run.levels {
        level_line(&mut s, l);
    }
    snapshot("fig12", &s);
}

#[test]
fn regression_fig14_prototype2_efficiency() {
    let run = fig14_run();
    let f = fig14::findings(run);
    let mut s = String::new();
    let pooled = |v: &Value| v.is(keys::F14A_EFF_SIM_LINEAR);
    claim_lines(&mut s, &Fig14::claims(run, claims()).unwrap(), pooled);
    writeln!(s, "linear levels: {:?}", f.linear_levels).unwrap();
    writeln!(s, "frequent-contact levels: {:?}", f.frequent_levels).unwrap();
    for l in &run.levels {
        level_line(&mut s, l);
    }
    snapshot("fig14", &s);
}

#[test]
fn regression_fig15_prototype2_spectra() {
    let run = fig15_run();
    let f = fig15::findings(run, claims());
    let mut s = String::new();
    claim_lines(&mut s, &Fig15::claims(run, claims()).unwrap(), |_| false);
    let r = &f.ratio_half_amplitude;
    writeln!(s, "half-amplitude ratio: {}", pin(r.0, r.1, false)).unwrap();
    let r = &f.ratio_169;
    writeln!(s, "3 dB ratio 1.69e-3 / 0.34e-3: {}", pin(r.0, r.1, false)).unwrap();
    for l in &run.levels {
        level_line(&mut s, l);
    }
    snapshot("fig15", &s);
}
