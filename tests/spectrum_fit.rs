//! `endstop fit --spectrum` recovers a known device: synthetic output spectra of prototype 2
//! with its mechanical damping and its drive off the published values (the "measurements",
//! each an ensemble of records on streams the design never uses) are fitted by the emulators
//! of one design, and the 95 % intervals must hold the truth as often as 95 % intervals do.

use endstop::device::{Device, ParamRange};
use endstop::fit::spectrum::{build_emulator, model_features, MeasuredSpectrum, SpectrumSettings};
use endstop::fit::ACCEL_SCALE_PATH;
use endstop::progress::Silent;
use endstop::study::ensemble::{run_ensemble, EnsembleSpec};

/// Figure 15's lowest level (g²/Hz), where prototype 2 at 15 V just reaches its stops.
const LEVEL: f64 = 0.34e-3;
/// The analysis band (Hz): Figure 15's.
const BAND: (f64, f64) = (500.0, 900.0);
/// Synthetic measurements.
const FITS: usize = 8;
/// Records each synthetic measurement averages.
const MEASURED_RECORDS: usize = 16;

fn p2() -> Device {
    Device::from_toml_str(include_str!("../data/prototype2.toml"), "prototype2")
        .unwrap()
        .with_bias(endstop::paper::setups::P2_BIAS_V)
}

#[test]
#[ignore = "about 30 s of ensembles on 2 cores, a characterisation of the intervals' coverage; CI runs it: cargo test --release --test all -- spectrum_fit:: --ignored"]
fn a_known_device_is_recovered_within_its_intervals() {
    let base = p2();
    let b = base.mechanics.damping_n_s_per_m;
    let free = vec![
        ParamRange::auto("mechanics.damping_n_s_per_m", 0.7 * b, 1.3 * b),
        ParamRange::auto(ACCEL_SCALE_PATH, 0.8, 1.25),
    ];
    let truth = (1.1 * b, 1.05);
    let settings = SpectrumSettings {
        per_param: 8,
        ..SpectrumSettings::default()
    };
    let em = build_emulator(&base, &free, LEVEL, BAND, settings, &|| {}).unwrap();
    // The features at the truth by the model itself (the design's streams), for the message.
    let device = base
        .with_param("mechanics.damping_n_s_per_m", truth.0)
        .unwrap();
    let at_truth = model_features(&device, LEVEL, truth.1, BAND, 16, (settings.seed, 0)).unwrap();
    let mut held = [0usize; 2];
    for k in 0..FITS {
        // A measurement: an ensemble of the true device on its own streams.
        let psd = LEVEL * truth.1 * truth.1;
        let mut spec = EnsembleSpec::for_device(
            &device,
            endstop::fit::spectrum::model_record(&device, psd),
            99,
            MEASURED_RECORDS,
        );
        spec.analysis_band_hz = BAND;
        spec.first_stream = 1000 + 100 * k as u64;
        let e = run_ensemble(&device, &spec, &Silent).unwrap();
        let m = MeasuredSpectrum {
            freq_hz: e.mean_spectrum.total.freq_hz.clone(),
            psd_w_per_hz: e.mean_spectrum.total.density.clone(),
            accel_psd_g2_per_hz: LEVEL,
            records: MEASURED_RECORDS,
        };
        let est = em.fit(&m).unwrap();
        eprintln!(
            "fit {k}: {:?}; features measured {:?}, emulated {:?}, model at the truth {:?}",
            est.params
                .iter()
                .map(|p| (p.mean, p.interval))
                .collect::<Vec<_>>(),
            est.measured,
            est.predicted,
            at_truth.0
        );
        for (j, t) in [truth.0, truth.1].iter().enumerate() {
            let (lo, hi) = est.params[j].interval;
            assert!(lo < hi, "an interval of zero width: {:?}", est.params[j]);
            held[j] += usize::from(lo <= *t && *t <= hi);
        }
    }
    // 95 % intervals hold the truth in 8 fits 7.6 times on average; fewer than 6 has
    // probability 0.6 % (binomial), so 6 is the least a correct interval passes with.
    for (j, h) in held.iter().enumerate() {
        eprintln!("{}: held the truth in {h} of {FITS} fits", free[j].path);
        assert!(*h >= 6, "{}: {h} of {FITS}", free[j].path);
    }
}
