//! Integration tests of `endstop::broadband`: the random-vibration claims of Figures 10-15,
//! asserted with the claims file's tolerances.
//!
//! Each test runs the same protocol as its experiment (same levels, seed, streams and number
//! of records, from `endstop::broadband`), so the values asserted here are the ones the
//! scorecard shows. Where the paper's claim is reproduced, the test asserts the `reproduced`
//! verdict and checks our value against an independent expectation (eq 21, the linearised
//! theory, the generator's exact level). Where it deviates, the test asserts our value
//! (against the same kind of physical expectation) and the `deviates` verdict, and that the
//! deviation is larger than our 95 % confidence interval, so it is not a sampling accident.
//!
//! Run time: about 140 ten-second records (a few tenths of a second each) on all cores.

use endstop::device::Device;
use endstop::drive::noise::NoiseSpec;
use endstop::num::stats::*;
use endstop::paper::claims::Claim;
use endstop::paper::claims::Claims;
use endstop::paper::claims::Verdict;
use endstop::paper::ensembles::*;
use endstop::paper::fig11::*;
use endstop::paper::fig12::*;
use endstop::paper::fig14::*;
use endstop::paper::fig15::*;
use endstop::paper::setups::*;
use endstop::physics::two_port::*;
use endstop::signal::bandwidth::*;
use endstop::signal::welch;
use endstop::signal::WelchConfig;
use endstop::study::ensemble::*;
use endstop::study::record::*;
use endstop::G;

fn device(name: &str) -> Device {
    let path = format!("{}/data/{name}.toml", env!("CARGO_MANIFEST_DIR"));
    Device::from_toml_str(&std::fs::read_to_string(&path).unwrap(), &path).unwrap()
}

fn claim(id: &str, quantity: &str) -> Claim {
    Claims::bundled()
        .map(|c| c.claims)
        .unwrap()
        .into_iter()
        .find(|c| c.id == id && c.quantity == quantity)
        .unwrap_or_else(|| panic!("claim {id}/{quantity} not in data/claims.toml"))
}

/// Asserts the verdict of our value, and that the verdict holds over our whole 95 % interval
/// `ours ± ci` (the comparison is not decided by sampling noise).
fn assert_verdict(id: &str, quantity: &str, ours: f64, ci: f64, expected: Verdict) {
    let c = claim(id, quantity);
    let v = c.verdict(Some(ours));
    println!(
        "{id} {quantity}: ours {ours:.4} ± {ci:.3}, paper {} ± {:.3} -> {}",
        c.paper,
        c.tolerance(),
        v.label()
    );
    assert_eq!(
        v, expected,
        "{id} {quantity}: ours {ours} ± {ci}, paper {}",
        c.paper
    );
    for x in [ours - ci, ours + ci] {
        assert_eq!(
            c.verdict(Some(x)),
            expected,
            "{id} {quantity}: the verdict changes within the 95 % interval ({ours} ± {ci})"
        );
    }
}

fn run(
    device: &Device,
    levels: &[f64],
    nperseg: usize,
    band: (f64, f64),
    n: usize,
    alt: bool,
) -> Vec<Ensemble> {
    let cases: Vec<EnsembleCase> = levels
        .iter()
        .map(|&sa| EnsembleCase {
            device: device.clone(),
            spec: protocol_spec(device, sa, nperseg, band, n, alt),
        })
        .collect();
    run_ensembles(&cases, || {}).unwrap()
}

#[test]
fn linear_theory_integrates_to_eq21() {
    // The linearised output PSD must integrate to eq 21's power (both are the linear
    // two-port); the rectangle rule on 0.01 Hz up to 20 kHz leaves a tail below 1e-4.
    for name in ["prototype1", "prototype2"] {
        let d = device(name);
        let df = 0.01;
        let n = (20_000.0 / df) as usize;
        let p: f64 = (1..n)
            .map(|i| linear_output_psd_w_per_hz(&d, 1e-4, i as f64 * df))
            .sum::<f64>()
            * df;
        let e = eq21_power_w(&d, 1e-4);
        assert!((p / e - 1.0).abs() < 1e-4, "{name}: {p:e} vs eq 21 {e:e}");
    }
}

#[test]
fn record_spec_and_errors() {
    let d = prototype2_setup(&device("prototype2"));
    let spec = RecordSpec::paper(&d, 1e-4);
    // 5 ring-up times 2m/b = 5 x 96 ms, rounded up to whole milliseconds.
    assert!((spec.transient_s - 0.48).abs() < 1e-12);
    assert_eq!(spec.transient_samples(), 48_000);
    assert_eq!(spec.analysed_samples(), 1_000_000);
    let mut bad = spec;
    bad.rtol = 0.0;
    let msg = simulate_record(&d, &bad, 1, 0).unwrap_err().to_string();
    assert!(msg.contains("rtol = 0"), "{msg}");
    let mut bad = spec;
    bad.transient_s = -1.0;
    let msg = simulate_record(&d, &bad, 1, 0).unwrap_err().to_string();
    assert!(msg.contains("transient_s = -1"), "{msg}");
    let mut bad = spec;
    bad.noise.sample_rate_hz = 15e3;
    assert!(simulate_record(&d, &bad, 1, 0).is_err());
}

#[test]
fn record_converges_and_keeps_its_bookkeeping() {
    // A short record in the linear regime at two tolerances: the trajectory, hence the mean
    // power, agrees to 1e-6 relative (the steps are bounded by the 10 us sample interval).
    let d = prototype2_setup(&device("prototype2"));
    let mut spec = RecordSpec::paper(&d, 1e-4);
    spec.noise.duration_s = 1.0;
    let a = simulate_record(&d, &spec, 7, 3).unwrap();
    spec.rtol = 1e-10;
    let b = simulate_record(&d, &spec, 7, 3).unwrap();
    let (pa, pb) = (a.summary.p_total_w(), b.summary.p_total_w());
    assert!((pa / pb - 1.0).abs() < 1e-6, "{pa:e} vs {pb:e}");
    assert_eq!(a.v1_v.len(), 100_000);
    assert_eq!(a.summary.impacts, 0);
    assert_eq!(a.summary.contact_fraction, 0.0);
    // The steps land on every sample instant (breakpoints): at least one step per sample.
    assert!(a.summary.stats.accepted >= 148_000 - 1);
    // The applied acceleration has the generator's variance 2 B Sa (1 s: ~0.5 % scatter).
    let target = 2.0 * 10e3 * 1e-4 * G * G;
    assert!((a.summary.accel_mean_square_si / target - 1.0).abs() < 0.03);
    // Antisymmetric linear response: the two loads carry the same power.
    assert!((a.summary.p1_w / a.summary.p2_w - 1.0).abs() < 1e-3);
}

#[test]
fn f10_excitation_level_and_band() {
    // As the fig10 experiment: 16 records at 1e-2 g^2/Hz, Welch 2^14, level over 100-9500 Hz.
    let spec = NoiseSpec::paper(1e-2);
    let first = first_stream_for_level(1e-2);
    let cfg = WelchConfig::half_overlap(1 << 14);
    let (mut levels, mut edges) = (Vec::new(), Vec::new());
    for i in 0..16 {
        let a = endstop::drive::noise::generate(&spec, DEFAULT_SEED, first + i).unwrap();
        let g: Vec<f64> = a.iter().map(|x| x / G).collect();
        let p = welch(&g, spec.sample_rate_hz, &cfg).unwrap();
        let level = p.two_sided_level_in_band(100.0, 9500.0);
        levels.push(level);
        edges.push(upper_band_edge_hz(&p, 2.0 * level, 0.5));
    }
    let level = MeanCi::of(&levels);
    let edge = MeanCi::of(&edges);
    // Independent expectation: the generator's exact level, within the ensemble's CI (plus
    // 1e-3 for the Hann window's tiny leakage at the band ends).
    assert!((level.mean - 1e-2).abs() <= level.ci95 + 1e-5, "{level:?}");
    // A brick-wall band seen through a Hann window falls to half at the edge itself: within
    // one bin (6.1 Hz).
    assert!((edge.mean - 10e3).abs() < 6.1, "{edge:?}");
    assert_verdict(
        "F10",
        "excitation_psd_g2_per_hz",
        level.mean,
        level.ci95,
        Verdict::Reproduced,
    );
    assert_verdict(
        "F10",
        "excitation_band_hz",
        edge.mean,
        edge.ci95,
        Verdict::Reproduced,
    );
}

#[test]
fn f14a_linear_regime_efficiency_agrees_with_eq21() {
    // The four lowest levels of Figure 14 (no impacts), 8 records each, pooled.
    let d = prototype2_setup(&device("prototype2"));
    let ens = run(
        &d,
        &FIG14_LEVELS[..4],
        P2_NPERSEG,
        P2_BAND_HZ,
        FIG14_REALISATIONS,
        false,
    );
    for e in &ens {
        assert!(e.no_impact(), "impact at {}", e.psd_g2_per_hz());
    }
    let refs: Vec<&Ensemble> = ens.iter().collect();
    let eff = pooled_efficiency(&d, &refs);
    let theory = eq21_efficiency(&d);
    println!("pooled efficiency {eff:?}, eq 21 {theory}");
    // The test's tolerance is the ensemble's own 95 % CI, measured: about 1.3 % (absolute)
    // from 32 records whose efficiencies scatter by about 4 %. It must be small enough to
    // mean something: below 2.5 %.
    assert!(eff.ci95 < 0.025, "ensemble too noisy: {eff:?}");
    assert!(
        (eff.mean - theory).abs() <= eff.ci95,
        "simulated {} ± {} vs eq 21 {theory}",
        eff.mean,
        eff.ci95
    );
    assert_verdict(
        "F14-a",
        "eff_sim_linear_pct",
        eff.mean * 100.0,
        eff.ci95 * 100.0,
        Verdict::Reproduced,
    );
    // The ensemble-mean output PSD follows the linearised theory bin by bin near the peak:
    // the mean over 600-750 Hz of the ratio is 1 within its scatter.
    let e = &ens[3];
    let ratios: Vec<f64> = e
        .mean_spectrum
        .total
        .freq_hz
        .iter()
        .zip(&e.mean_spectrum.total.density)
        .filter(|(f, _)| (600.0..=750.0).contains(*f))
        .map(|(f, p)| p / linear_output_psd_w_per_hz(&d, e.psd_g2_per_hz(), *f))
        .collect();
    let r = MeanCi::of(&ratios);
    println!("PSD ratio to linear theory over 600-750 Hz: {r:?}");
    assert!((r.mean - 1.0).abs() < 0.05, "{r:?}");
}

#[test]
fn f15_and_f14b_prototype2_nonlinear_regime() {
    let d = prototype2_setup(&device("prototype2"));
    let ens = run(
        &d,
        &FIG15_LEVELS,
        P2_NPERSEG,
        P2_BAND_HZ,
        FIG15_REALISATIONS,
        false,
    );
    let (e34, e55, e169) = (&ens[0], &ens[1], &ens[2]);
    let lin = linear_widths(&d, P2_BAND_HZ.0, P2_BAND_HZ.1);

    // F15-a, peak: the ensemble-mean peak lies within a bin of the linearised resonance
    // (impacts at 0.34e-3 are rare), and reproduces 675 Hz.
    let peak = e34.mean_spectrum.total.peak().0;
    let lin_peak = lin.half_power.unwrap().peak_hz;
    let bin = e34.mean_spectrum.total.df();
    assert!((peak - lin_peak).abs() <= bin, "{peak} vs {lin_peak}");
    let peaks = MeanCi::of(&e34.single_peak_hz());
    assert_verdict(
        "F15-a",
        "peak_0p34e-3_hz",
        peak,
        (0.5 * bin).hypot(peaks.ci95),
        Verdict::Reproduced,
    );

    // F15-a, 3 dB width: at least the linear width (impacts only widen), and reproduced.
    let w34 = e34.mean_width(0.5);
    println!(
        "width at 0.34e-3: {w34:?}, linear theory {}",
        lin.bw3db_hz()
    );
    assert!(w34.estimate + w34.ci95 >= lin.bw3db_hz());
    assert_verdict(
        "F15-a",
        "bw_0p34e-3_hz",
        w34.estimate,
        w34.ci95,
        Verdict::Reproduced,
    );

    // F15-b: the width grows from 0.34e-3 to 0.55e-3 (our value: a ratio above 1 beyond its
    // CI), but by much less than the paper's 3.7: deviates.
    let (ratio, ratio_ci) = e55.mean_width(0.5).ratio(&w34);
    assert!(ratio - ratio_ci > 1.0, "ratio {ratio} ± {ratio_ci}");
    assert_verdict(
        "F15-b",
        "bw_ratio_0p55e-3_over_0p34e-3",
        ratio,
        ratio_ci,
        Verdict::Deviates,
    );

    // F15-c: at 1.69e-3 the upper half-power edge moves up more than the lower moves down.
    let (up, down) = edge_shifts(e34, e169).unwrap();
    println!("edge shifts to 1.69e-3: up {up} Hz, down {down} Hz");
    let widening = if up > down && up > 0.0 { 1.0 } else { 0.0 };
    assert_verdict(
        "F15-c",
        "widening_up_1p69e-3",
        widening,
        0.0,
        Verdict::Reproduced,
    );
    // ... and the peak itself moves up (the stops stiffen the oscillator).
    assert!(e169.mean_spectrum.total.peak().0 > peak + bin);

    // F14-b, from Figure 14's 8 records at 1.69e-3 (the first 8 of these: same streams).
    let mut e8 = e169.clone();
    e8.records.truncate(FIG14_REALISATIONS);
    let eff: Vec<f64> = e8
        .records
        .iter()
        .map(|r| efficiency(&d, r.summary.p_total_w(), 1.69e-3))
        .collect();
    let eff = MeanCi::of(&eff);
    // Our value: well below eq 21 (the stops dissipate and detune), and deviating from the
    // paper's 35.4 % beyond our CI.
    assert!(eff.mean + eff.ci95 < eq21_efficiency(&d));
    assert_verdict(
        "F14-b",
        "eff_1p69e-3_pct",
        eff.mean * 100.0,
        eff.ci95 * 100.0,
        Verdict::Deviates,
    );
    // Sublinear growth over these levels, starting from eq 21's efficiency as the linear
    // value (its CI set to zero).
    let linear = MeanCi {
        mean: eq21_efficiency(&d),
        std: 0.0,
        ci95: 0.0,
        n: 1,
    };
    let sub = sublinear_growth(&linear, &[e34, e55, e169]);
    assert_verdict(
        "F14-b",
        "sublinear_power_growth",
        if sub { 1.0 } else { 0.0 },
        0.0,
        Verdict::Reproduced,
    );
}

#[test]
fn f11_and_f12_prototype1_bandwidths() {
    let published = device("prototype1");
    let calibrated = endstop::paper::calibration::calibrate_prototype1(&published)
        .unwrap()
        .device;
    for (set, dev) in [("published", &published), ("calibrated", &calibrated)] {
        let d = prototype1_setup(dev);
        let lin = linear_widths(&d, P1_BAND_HZ.0, P1_BAND_HZ.1);

        // F11: the lowest and highest levels of Figure 11.
        let lo_hi = [FIG11_LEVELS[0], FIG11_LEVELS[2]];
        let f11 = run(
            &d,
            &lo_hi,
            P1_NPERSEG,
            P1_BAND_HZ,
            FIG11_REALISATIONS,
            false,
        );
        let impacts: u64 = f11.iter().map(|e| e.impacts).sum();
        assert_verdict(
            "F11",
            "linear_regime_no_impact",
            if impacts == 0 { 1.0 } else { 0.0 },
            0.0,
            Verdict::Reproduced,
        );
        let (w_lo, w_hi) = (f11[0].mean_width(0.5), f11[1].mean_width(0.5));
        // Our value: the linear width of eqs 11-17 at both levels, within the jackknife CI
        // plus one 24 Hz bin.
        for w in [w_lo, w_hi] {
            assert!(
                (w.estimate - lin.bw3db_hz()).abs() <= w.ci95 + 24.5,
                "{set}: {w:?} vs {}",
                lin.bw3db_hz()
            );
        }
        let (r, rci) = w_hi.ratio(&w_lo);
        assert_verdict(
            "F11",
            "bw_ratio_3p49e-4_over_4p42e-6",
            r,
            rci,
            Verdict::Reproduced,
        );

        // F12: the lowest and highest levels of Figure 12.
        let lo_hi = [FIG12_LEVELS[0], FIG12_LEVELS[2]];
        let f12 = run(
            &d,
            &lo_hi,
            P1_NPERSEG,
            P1_BAND_HZ,
            FIG12_REALISATIONS,
            false,
        );
        let (w_lo, w_hi) = (f12[0].mean_width(0.5), f12[1].mean_width(0.5));
        println!(
            "{set}: F12 widths {w_lo:?} {w_hi:?}; linear {}",
            lin.bw3db_hz()
        );
        // Our values: the impacts widen the band beyond the linear width, and more at the
        // higher level.
        assert!(f12[0].impacts > 0 && f12[1].impacts > f12[0].impacts);
        assert!(w_hi.estimate - w_hi.ci95 > lin.bw3db_hz());
        assert!(w_hi.estimate - w_hi.ci95 > w_lo.estimate + w_lo.ci95);
        // The paper's 380 and 600 Hz are not reached (the half-power widths are far smaller):
        // deviates; the growth ratio is reproduced.
        assert_verdict(
            "F12",
            "bw_7p4e-3_hz",
            w_lo.estimate,
            w_lo.ci95,
            Verdict::Deviates,
        );
        assert_verdict(
            "F12",
            "bw_2p85e-2_hz",
            w_hi.estimate,
            w_hi.ci95,
            Verdict::Deviates,
        );
        let (r, rci) = w_hi.ratio(&w_lo);
        assert_verdict(
            "F12",
            "bw_ratio_2p85e-2_over_7p4e-3",
            r,
            rci,
            Verdict::Reproduced,
        );
    }
}

#[test]
fn impacting_regime_statistics_converge() {
    // With impacts, nearby trajectories part after a few impacts, so a record at two
    // tolerances gives two different (equally valid) samples; the statistics must agree. Eight
    // records at 1.69e-3 (as Figure 14) at the default and at a hundred times tighter
    // tolerance: the mean powers agree within their combined 95 % CI, and within 1 %.
    let d = prototype2_setup(&device("prototype2"));
    let mut means = Vec::new();
    for rtol in [DEFAULT_RTOL, DEFAULT_RTOL / 100.0] {
        let mut spec = protocol_spec(
            &d,
            1.69e-3,
            P2_NPERSEG,
            P2_BAND_HZ,
            FIG14_REALISATIONS,
            false,
        );
        spec.record.rtol = rtol;
        let e = run_ensemble(&d, &spec, || {}).unwrap();
        println!(
            "rtol {rtol:e}: power {:?}, impacts {}",
            e.power_w, e.impacts
        );
        assert!(e.impacts > 0);
        means.push(e.power_w);
    }
    let (a, b) = (means[0], means[1]);
    assert!(
        (a.mean - b.mean).abs() <= a.ci95.hypot(b.ci95),
        "{a:?} vs {b:?}"
    );
    assert!((a.mean / b.mean - 1.0).abs() < 0.01, "{a:?} vs {b:?}");
}
