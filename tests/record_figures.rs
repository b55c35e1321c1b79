//! The random-vibration figures (10, 11, 12, 14, 15) against the paper: every test runs the
//! figure's own `run` and `claims` from `endstop::paper` (the functions the experiment
//! binaries call, with the same levels, seeds, streams and records), asserts the verdict of
//! every claim value with the tolerances of `data/claims.toml`, and asserts that the verdict
//! holds over the value's whole 95 % interval (it is not decided by sampling noise). Beside
//! the verdicts, each test checks the physics behind them against an independent expectation
//! (eq 21, the linearised theory, the generator's exact level).
//!
//! The runs are shared (each is computed once per test process) with the snapshot regression
//! suite of our own numbers, `record_figures/regression.rs`, which this file includes so that the
//! ensembles are not simulated twice.
//!
//! Run time: about 230 ten-second records (a few tenths of a second each) on all cores.
//!
//! One record's own numerics (its specification, convergence and schemes) are
//! `record_simulation.rs`.

use std::collections::BTreeSet;
use std::sync::OnceLock;

use endstop::num::stats::MeanCi;
use endstop::paper::claims::{keys, Answer, ClaimKey, Value, Verdict};
use endstop::paper::ensembles::{protocol_spec, WidthReading, P2_BAND_HZ, P2_NPERSEG};
use endstop::paper::figures::fig10::{self, Fig10};
use endstop::paper::figures::fig11::{self, Fig11};
use endstop::paper::figures::fig12::{self, Fig12};
use endstop::paper::figures::fig14::{self, Fig14};
use endstop::paper::figures::fig15::{self, Fig15};
use endstop::paper::prototype2_records::Extras;
use endstop::paper::resolution;
use endstop::paper::setups::{prototype2_setup, ParamSet};
use endstop::paper::Figure;
use endstop::physics::linear::LinearResponse;
use endstop::physics::two_port::*;
use endstop::progress::Silent;
use endstop::study::ensemble::run_ensemble;
use endstop::study::record::*;
use endstop::G;

use crate::common;
#[path = "record_figures/regression.rs"]
mod regression;

use common::{claims, device};

use Verdict::{Deviates, Reproduced};

fn fig10_run() -> &'static fig10::Run {
    static RUN: OnceLock<fig10::Run> = OnceLock::new();
    RUN.get_or_init(|| Fig10::run(&(), &|| {}).unwrap())
}

/// The published and the calibrated prototype 1 (the devices of the parameter files; the
/// figures apply their setup themselves), computed once.
fn prototype1_sets() -> &'static endstop::paper::setups::Prototype1Sets {
    static SETS: OnceLock<endstop::paper::setups::Prototype1Sets> = OnceLock::new();
    SETS.get_or_init(common::prototype1_sets)
}

fn fig11_run() -> &'static fig11::Run {
    static RUN: OnceLock<fig11::Run> = OnceLock::new();
    RUN.get_or_init(|| Fig11::run(prototype1_sets(), &|| {}).unwrap())
}

fn fig12_run() -> &'static fig12::Run {
    static RUN: OnceLock<fig12::Run> = OnceLock::new();
    RUN.get_or_init(|| Fig12::run(prototype1_sets(), &|| {}).unwrap())
}

/// Figure 14's levels; the other end-stop readings and the convergence check of the chapter
/// are not part of any claim and are left out here.
fn fig14_run() -> &'static fig14::Run {
    static RUN: OnceLock<fig14::Run> = OnceLock::new();
    RUN.get_or_init(|| {
        let setup = fig14::Setup {
            prototype2: device("prototype2"),
            extras: Extras::NONE,
        };
        Fig14::run(&setup, &|| {}).unwrap()
    })
}

/// Figure 15 read from Figure 14's run, as the `fig14` binary writes it.
fn fig15_run() -> &'static fig15::Run {
    static RUN: OnceLock<fig15::Run> = OnceLock::new();
    RUN.get_or_init(|| fig15::Run::of(fig14_run()).expect("Figure 14 runs Figure 15's levels"))
}

#[test]
fn figure_15_alone_simulates_the_records_of_figure_14() {
    // Figure 15 run by itself (two records per level, the first of every level's streams)
    // gives the first records of Figure 14's ensembles, bit for bit.
    let setup = fig15::Setup {
        prototype2: device("prototype2"),
        records: 2,
    };
    let alone = Fig15::run(&setup, &|| {}).unwrap();
    for (a, b) in alone.levels.iter().zip(&fig15_run().levels) {
        assert_eq!(a.index, b.index);
        assert_eq!(a.sa(), b.sa());
        for (x, y) in a.ens.records.iter().zip(&b.ens.records) {
            assert_eq!(
                x.summary.p_total_w().to_bits(),
                y.summary.p_total_w().to_bits()
            );
        }
    }
}

/// Asserts that `values` are exactly the rows `expected` (claim, quantity, set) with no key
/// missing or repeated, that every claim of `experiment` in the claims file has a row for
/// every set named, and that each row has the expected verdict over its whole 95 % interval
/// `ours ± uncertainty`.
fn assert_verdicts(values: &[Value], experiment: &str, expected: &[(ClaimKey, ParamSet, Verdict)]) {
    assert_verdicts_straddling(values, experiment, expected, &[]);
}

/// [`assert_verdicts`], except that the rows `straddling` (claim, quantity, set) have their
/// expected verdict at `ours` only, and their 95 % interval must cross a tolerance edge (the
/// ensemble does not settle the verdict; the test fails when it comes to settle it, so that
/// the exception cannot outlive its reason).
fn assert_verdicts_straddling(
    values: &[Value],
    experiment: &str,
    expected: &[(ClaimKey, ParamSet, Verdict)],
    straddling: &[(ClaimKey, ParamSet)],
) {
    let c = claims();
    let row = |v: &'_ Value| (v.claim.clone(), v.quantity.clone(), v.set);
    let key = |k: ClaimKey, s: ParamSet| (k.id.to_string(), k.quantity.to_string(), s);
    let rows: Vec<_> = values.iter().map(row).collect();
    let unique: BTreeSet<_> = rows.iter().cloned().collect();
    assert_eq!(unique.len(), rows.len(), "a key appears twice: {rows:?}");
    let want: BTreeSet<_> = expected.iter().map(|&(k, s, _)| key(k, s)).collect();
    assert_eq!(unique, want, "rows of {experiment}");
    let sets: BTreeSet<ParamSet> = expected.iter().map(|e| e.1).collect();
    for claim in c.of_experiment(experiment) {
        for &set in &sets {
            assert!(
                unique.contains(&(claim.id.clone(), claim.quantity.clone(), set)),
                "{experiment} gives no value for ({}, {}) under {set}",
                claim.id,
                claim.quantity
            );
        }
    }
    for v in values {
        let claim = c.get(&v.claim, &v.quantity).expect("a claim of the file");
        let want = expected
            .iter()
            .find(|e| v.is(e.0) && v.set == e.1)
            .map(|e| e.2)
            .unwrap();
        let ci = v.uncertainty.unwrap_or(0.0);
        println!(
            "{} {} {}: ours {:.4} ± {ci:.3}, paper {} ± {:.3} ({})",
            v.claim,
            v.quantity,
            v.set,
            v.ours.to_f64(),
            claim.paper.to_f64(),
            claim.tolerance(),
            v.note
        );
        let key = row(v);
        // A number is judged across its interval; a yes/no has no interval.
        let spread = |x: f64| -> Vec<Answer> {
            match v.ours {
                Answer::Number(_) => vec![(x - ci).into(), (x + ci).into()],
                Answer::YesNo(_) => Vec::new(),
            }
        };
        let ours = v.ours.to_f64();
        if straddling.iter().any(|&(k, s)| v.is(k) && v.set == s) {
            assert_eq!(claim.verdict(Some(v.ours)), want, "{key:?}: {:?}", v.ours);
            assert!(
                spread(ours).iter().any(|&x| claim.verdict(Some(x)) != want),
                "{key:?}: {ours} ± {ci} no longer straddles a tolerance edge"
            );
            continue;
        }
        for x in std::iter::once(v.ours).chain(spread(ours)) {
            assert_eq!(
                claim.verdict(Some(x)),
                want,
                "{} {} {}: {x:?} within {ours} ± {ci}",
                v.claim,
                v.quantity,
                v.set,
            );
        }
    }
}

/// The value of a claim number under a set in `values`.
fn value(values: &[Value], key: ClaimKey, set: ParamSet) -> &Value {
    values
        .iter()
        .find(|v| v.is(key) && v.set == set)
        .unwrap_or_else(|| panic!("no value {key} under {set}"))
}

#[test]
fn linear_theory_integrates_to_eq21() {
    // The linearised output PSD must integrate to eq 21's power (both are the linear
    // two-port); the rectangle rule on 0.01 Hz up to 20 kHz leaves a tail below 1e-4.
    for name in ["prototype1", "prototype2"] {
        let d = device(name);
        let df = 0.01;
        let n = (20_000.0 / df) as usize;
        let lin = LinearResponse::of(&d);
        let p: f64 = (1..n)
            .map(|i| lin.output_psd_w_per_hz(1e-4 * G * G, i as f64 * df))
            .sum::<f64>()
            * df;
        let e = eq21_power_w(&d, 1e-4);
        assert!((p / e - 1.0).abs() < 1e-4, "{name}: {p:e} vs eq 21 {e:e}");
    }
}

#[test]
fn f10_excitation_level_and_band() {
    let run = fig10_run();
    let values = Fig10::claims(run, claims()).unwrap();
    let published = ParamSet::Published;
    assert_verdicts(
        &values,
        Fig10::NAME,
        &[
            (keys::F10_LEVEL, published, Reproduced),
            (keys::F10_BAND, published, Reproduced),
        ],
    );
    // Independent expectation: the generator's exact level, within the records' CI (plus
    // 1e-5, a thousandth of the level, for the Hann window's leakage at the band ends).
    let level = value(&values, keys::F10_LEVEL, published);
    let ci = level.uncertainty.unwrap();
    assert!(
        (level.ours.to_f64() - run.spec.psd_g2_per_hz).abs() <= ci + 1e-5,
        "{level:?}"
    );
    // A brick-wall band seen through a Hann window falls to half at the edge itself: within
    // one bin (6.1 Hz).
    let edge = value(&values, keys::F10_BAND, published);
    let bin = run.records[0].psd.df();
    assert!(
        (edge.ours.to_f64() - run.spec.bandwidth_hz).abs() < bin,
        "{edge:?}"
    );
}

#[test]
fn f11_prototype1_stays_linear_at_low_levels() {
    let run = fig11_run();
    let values = Fig11::claims(run, claims()).unwrap();
    let mut expected = Vec::new();
    for set in ParamSet::BOTH {
        expected.push((keys::F11_BW_RATIO, set, Reproduced));
        expected.push((keys::F11_NO_IMPACT, set, Reproduced));
    }
    assert_verdicts(&values, Fig11::NAME, &expected);
    // Our value: the linear width of eqs 11-17 at the ratio's two levels, within the
    // jackknife CI plus one 24 Hz bin.
    let lin = run.linear.bw3db_hz();
    for set in ParamSet::BOTH {
        for i in [fig11::LOW, fig11::HIGH] {
            let w = WidthReading::HalfPower.mean_width(&run.level(set, i).ens);
            assert!(
                (w.estimate - lin).abs() <= w.ci95 + 24.5,
                "{set}: {w:?} vs {lin}"
            );
        }
    }
}

#[test]
fn f11_prototype1_linear_efficiency_agrees_with_eq21() {
    // In the linear regime (Figure 11's levels, no impact) every ensemble's efficiency
    // 2P/(m Sa) agrees with eq 21 within its 95 % CI (32 records: about 0.6 % of it). With
    // six records the ensembles read 0.6-0.9 % low, about two standard errors: sampling.
    let run = fig11_run();
    for set in ParamSet::BOTH {
        for l in run.set(set) {
            let e = l.ens.efficiency;
            let want = l.eq21_efficiency();
            println!("{set} {}: {e:?} vs eq 21 {want}", l.sa());
            assert_eq!(e.n, fig11::FIG11_REALISATIONS);
            assert!(
                (e.mean - want).abs() <= e.ci95,
                "{set} {}: {e:?} vs {want}",
                l.sa()
            );
        }
    }
}

/// The width-resolution study of prototype 1 (Figure 11's and 12's lowest levels at six
/// segment lengths), with the records of the figures.
fn resolution_study() -> &'static resolution::Study {
    static RUN: OnceLock<resolution::Study> = OnceLock::new();
    RUN.get_or_init(|| resolution::run(&device("prototype1"), resolution::RECORDS, &|| {}).unwrap())
}

#[test]
fn p1_width_estimator_bias_is_measured_on_the_linear_model() {
    // At the linear level the true width is the linearised PSD's. The Hann window of a short
    // segment smooths the peak and widens it: the bias falls as the segment grows, and at
    // the figures' 4096 samples (24.4 Hz bins) it is a few per cent of the width, positive.
    let s = resolution_study();
    let exact = s.exact_hz;
    for n in 0..resolution::NPERSEGS.len() {
        let lin = s.row(resolution::LINEAR, n);
        println!(
            "nperseg {}: linear {:.1} ± {:.1}, 7.4e-3 {:.1} ± {:.1}, exact {exact:.1}",
            resolution::NPERSEGS[n],
            lin.width.estimate,
            lin.width.ci95,
            s.row(1, n).width.estimate,
            s.row(1, n).width.ci95
        );
    }
    let b = |n: usize| s.bias_hz(n);
    // Shortest segment: a large bias (97.7 Hz bins on a 220 Hz peak), far beyond the CI.
    assert!(b(0) > 10.0 * s.row(resolution::LINEAR, 0).width.ci95);
    // Falling with the segment length down to the figures' segment.
    assert!(b(0) > b(1) && b(1) > b(2));
    let fig = resolution::FIGURES_NPERSEG;
    assert!(b(fig).abs() < 0.05 * exact, "bias {} of {exact}", b(fig));
    // Twice the figures' segment: unbiased within the CI.
    let next = s.row(resolution::LINEAR, fig + 1);
    assert!(b(fig + 1).abs() <= next.width.ci95, "{next:?} vs {exact}");
    // Figure 12's verdicts do not rest on the bias: with the measured bias taken off both
    // widths, each verdict the ensemble settles (its interval clear of the tolerance's edges)
    // is kept (the widths stay far below the paper's, the published ratio inside the
    // tolerance). A verdict the ensemble does not settle (the calibrated ratio, whose interval
    // reaches past the upper edge) is a verdict at the estimate either way; there the bias
    // must move the value by less than its interval.
    let values = Fig12::claims(fig12_run(), claims()).unwrap();
    let keeps = |set: ParamSet, q: ClaimKey, corrected: f64| {
        let c = claims().claim(q).unwrap();
        let v = value(&values, q, set);
        let ci = v
            .uncertainty
            .expect("the ensemble's values carry an interval");
        let (lo_edge, hi_edge) = (
            c.paper.to_f64() - c.tolerance(),
            c.paper.to_f64() + c.tolerance(),
        );
        let interval = v.ours.to_f64() - ci..=v.ours.to_f64() + ci;
        if interval.contains(&lo_edge) || interval.contains(&hi_edge) {
            assert!(
                (corrected - v.ours.to_f64()).abs() <= ci,
                "{set} {q}: {corrected} against {} ± {ci}",
                v.ours.to_f64()
            );
        } else {
            assert_eq!(
                c.verdict(Some(corrected.into())),
                c.verdict(Some(v.ours)),
                "{set} {q}: {corrected}"
            );
        }
    };
    for set in ParamSet::BOTH {
        for q in [keys::F12_BW_LOW, keys::F12_BW_HIGH] {
            keeps(set, q, value(&values, q, set).ours.to_f64() - b(fig));
        }
        let lo = value(&values, keys::F12_BW_LOW, set).ours.to_f64() - b(fig);
        let hi = value(&values, keys::F12_BW_HIGH, set).ours.to_f64() - b(fig);
        keeps(set, keys::F12_BW_RATIO, hi / lo);
    }
}

#[test]
fn f12_prototype1_bandwidth_grows_with_impacts() {
    let run = fig12_run();
    let values = Fig12::claims(run, claims()).unwrap();
    let mut expected = Vec::new();
    for set in ParamSet::BOTH {
        // The paper's 380 and 600 Hz are not reached (the half-power widths are far
        // smaller): deviates; the growth ratio is reproduced.
        expected.push((keys::F12_BW_LOW, set, Deviates));
        expected.push((keys::F12_BW_HIGH, set, Deviates));
        expected.push((keys::F12_BW_RATIO, set, Reproduced));
    }
    // With 32 records the calibrated set's ratio, 1.86 ± 0.05, lies inside the paper's
    // 1.58 ± 20 % but its interval reaches past the upper edge (1.895): reproduced at the
    // estimate, not settled by the ensemble.
    assert_verdicts_straddling(
        &values,
        Fig12::NAME,
        &expected,
        &[(keys::F12_BW_RATIO, ParamSet::Calibrated)],
    );
    // Our values: the impacts widen the band beyond the linear width, and more at the higher
    // level, where the mass hits the stops more often.
    let lin = run.linear.bw3db_hz();
    for set in ParamSet::BOTH {
        let (lo, hi) = (
            &run.level(set, fig12::LOW).ens,
            &run.level(set, fig12::HIGH).ens,
        );
        assert!(lo.impacts > 0 && hi.impacts > lo.impacts, "{set}");
        let w_lo = value(&values, keys::F12_BW_LOW, set);
        let w_hi = value(&values, keys::F12_BW_HIGH, set);
        let (c_lo, c_hi) = (w_lo.uncertainty.unwrap(), w_hi.uncertainty.unwrap());
        assert!(
            w_hi.ours.to_f64() - c_hi > lin,
            "{set}: {w_hi:?} vs linear {lin}"
        );
        assert!(
            w_hi.ours.to_f64() - c_hi > w_lo.ours.to_f64() + c_lo,
            "{set}: {w_lo:?} {w_hi:?}"
        );
    }
}

#[test]
fn f14_prototype2_efficiency_follows_eq21_then_falls() {
    let run = fig14_run();
    let values = Fig14::claims(run, claims()).unwrap();
    let published = ParamSet::Published;
    assert_verdicts(
        &values,
        Fig14::NAME,
        &[
            (keys::F14A_EFF_SIM_LINEAR, published, Reproduced),
            (keys::F14B_EFF, published, Deviates),
            (keys::F14B_SUBLINEAR, published, Reproduced),
        ],
    );
    let f = fig14::findings(run);
    let theory = eq21_efficiency(&run.device);
    // The four lowest levels stay clear of the stops, so at least 32 records are pooled.
    assert!(f.linear_levels.starts_with(&[0, 1, 2, 3]), "{f:?}");
    // The test's tolerance is the pool's own 95 % CI (about 1.3 %, absolute, from records
    // whose efficiencies scatter by about 4 %); it must be small enough to mean something:
    // below 2.5 %.
    assert!(f.pooled.ci95 < 0.025, "ensemble too noisy: {:?}", f.pooled);
    assert!(
        (f.pooled.mean - theory).abs() <= f.pooled.ci95,
        "simulated {:?} vs eq 21 {theory}",
        f.pooled
    );
    // F14-b: well below eq 21 (the stops dissipate and detune), beyond the CI.
    let b = &run.levels[fig14::F14B_LEVEL].ens.efficiency;
    assert!(b.mean + b.ci95 < theory, "{b:?}");
    // The ensemble-mean output PSD of the fourth level follows the linearised theory bin by
    // bin near the peak: the mean over 600-750 Hz of the ratio is 1 within 5 %.
    let l = &run.levels[3];
    let m = &l.ens.mean_spectrum.total;
    let lin = l.linear_psd(&m.freq_hz);
    let ratios: Vec<f64> = m
        .freq_hz
        .iter()
        .zip(m.density.iter().zip(&lin.density))
        .filter(|(f, _)| (600.0..=750.0).contains(*f))
        .map(|(_, (p, q))| p / q)
        .collect();
    let r = MeanCi::of(&ratios);
    assert!((r.mean - 1.0).abs() < 0.05, "{r:?}");
}

#[test]
fn f15_prototype2_spectra_widen_upwards() {
    let run = fig15_run();
    let values = Fig15::claims(run, claims()).unwrap();
    let published = ParamSet::Published;
    assert_verdicts(
        &values,
        Fig15::NAME,
        &[
            (keys::F15A_PEAK, published, Reproduced),
            (keys::F15A_BW, published, Reproduced),
            // The width grows, but by much less than the paper's 3.7.
            (keys::F15B_BW_RATIO, published, Deviates),
            (keys::F15C_WIDENING_UP, published, Reproduced),
        ],
    );
    let lin = &run.linear;
    let e34 = &run.levels[fig15::L034].ens;
    let bin = e34.mean_spectrum.total.df();
    // The peak is not below the linearised resonance by more than a bin: the stops only
    // stiffen. No upper bound is asserted here beyond the claim's own verdict above: the peak
    // of the mean PSD is the arg-max of a noisy top (a 32-record run puts it 1.1 bins above),
    // and a bound chosen after seeing the number tests nothing, so the value is pinned in the
    // regression snapshot (tests/snapshots/record_fig15.snap) instead.
    let peak = value(&values, keys::F15A_PEAK, published).ours.to_f64();
    let lin_peak = lin.half_power.unwrap().peak_hz;
    assert!(peak >= lin_peak - bin, "{peak} vs {lin_peak}");
    // The width is at least the linear width (impacts only widen).
    let w = value(&values, keys::F15A_BW, published);
    assert!(
        w.ours.to_f64() + w.uncertainty.unwrap() >= lin.bw3db_hz(),
        "{w:?}"
    );
    // The ratio is above 1 beyond its CI: the width does grow.
    let r = value(&values, keys::F15B_BW_RATIO, published);
    assert!(r.ours.to_f64() - r.uncertainty.unwrap() > 1.0, "{r:?}");
    // ... and at 1.69e-3 the peak itself moves up (the stops stiffen the oscillator).
    let e169 = &run.levels[fig15::L169].ens;
    assert!(e169.mean_spectrum.total.peak().0 > peak + bin);
}

#[test]
fn impacting_regime_statistics_converge() {
    // With impacts, nearby trajectories part after a few impacts, so a record at two
    // tolerances gives two different (equally valid) samples; the statistics must agree.
    // Figure 14's records at 1.69e-3 against the first half of them again with Dormand-Prince
    // everywhere (no exponential free-flight step) at a hundred times tighter tolerance (half,
    // to keep the test's time): the
    // mean powers agree within their combined 95 % CI, and within 1 %.
    let d = prototype2_setup(&device("prototype2"));
    let a = &fig14_run().levels[fig14::F14B_LEVEL].ens;
    assert_eq!(a.spec.record.rtol, DEFAULT_RTOL);
    assert!(a.impacts > 0);
    let mut spec = protocol_spec(
        &d,
        fig14::FIG14_LEVELS[fig14::F14B_LEVEL],
        P2_NPERSEG,
        P2_BAND_HZ,
        fig14::FIG14_REALISATIONS / 2,
        false,
    );
    spec.record.rtol = DEFAULT_RTOL / 100.0;
    spec.record.scheme = Scheme::Dopri5;
    let b = run_ensemble(&d, &spec, &Silent).unwrap();
    // The same streams on both sides: the first half of the default ensemble.
    let first: Vec<f64> = a.records[..spec.realisations]
        .iter()
        .map(|r| r.summary.p_total_w())
        .collect();
    let a_half = MeanCi::of(&first);
    println!("power {a_half:?} vs tight {:?}", b.power_w);
    assert!(b.impacts > 0);
    let (a, b) = (a_half, b.power_w);
    assert!(
        (a.mean - b.mean).abs() <= a.ci95.hypot(b.ci95),
        "{a:?} vs {b:?}"
    );
    assert!((a.mean / b.mean - 1.0).abs() < 0.01, "{a:?} vs {b:?}");
}
