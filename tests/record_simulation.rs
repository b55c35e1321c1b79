//! One random-vibration record as the figures simulate it (`endstop::study::record`): its
//! specification and the errors it names, its convergence with the tolerance and its
//! bookkeeping, the exponential free-flight scheme against Dormand-Prince on impact-free
//! records, and the fall-back to Dormand-Prince where the sample rate cannot resolve the
//! device. The figures built on these records are `record_figures.rs`.

use endstop::paper::setups::{paper_record, prototype1_setup, prototype2_setup};
use endstop::study::record::*;
use endstop::G;

use crate::common::device;

#[test]
fn record_spec_and_errors() {
    let d = prototype2_setup(&device("prototype2"));
    let spec = paper_record(&d, 1e-4);
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
fn a_device_faster_than_the_sample_rate_falls_back_to_dormand_prince() {
    // A suspension 10^4 times stiffer puts prototype 2's resonance near 67 kHz: the 10 us
    // sample interval does not resolve it (omega h ~ 4 > the bound of 2), and the pair's free
    // flight is nonlinear, so its remainder cannot be extrapolated from past samples. The
    // record is then integrated by Dormand-Prince throughout, sample for sample the record of
    // that scheme (it panicked), and says why.
    let mut dev = prototype2_setup(&device("prototype2"));
    dev.mechanics.stiffness_n_per_m *= 1e4;
    let mut spec = paper_record(&dev, 1e-4);
    spec.noise.duration_s = 0.01;
    assert_eq!(spec.scheme, Scheme::Exponential);
    let fast = simulate_record(&dev, &spec, 7, 3).unwrap();
    assert_eq!(fast.summary.exponential_steps, 0);
    assert_eq!(
        fast.summary.free_flight,
        FreeFlightPath::Dopri5(Fallback::Unresolved)
    );
    spec.scheme = Scheme::Dopri5;
    let reference = simulate_record(&dev, &spec, 7, 3).unwrap();
    assert_eq!(fast.v1_v, reference.v1_v);
}

#[test]
fn record_converges_and_keeps_its_bookkeeping() {
    // A short record in the linear regime at two tolerances: the trajectory, hence the mean
    // power, agrees to 1e-6 relative (the steps are bounded by the 10 us sample interval).
    let d = prototype2_setup(&device("prototype2"));
    let mut spec = paper_record(&d, 1e-4);
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
fn exponential_scheme_matches_dormand_prince_on_impact_free_records() {
    // The exponential free-flight step (the default scheme) against Dormand-Prince at a
    // thousand times tighter tolerance, on records without impacts (where one trajectory is
    // the notion of accuracy): the mean power agrees to 1e-6 relative (the target), and every
    // sample of V1 to 1e-5 of its RMS. Measured: a few 1e-9 on the power.
    for (name, dev, sa) in [
        ("prototype 2", prototype2_setup(&device("prototype2")), 1e-4),
        (
            "prototype 1",
            prototype1_setup(&device("prototype1")),
            4.42e-6,
        ),
    ] {
        let mut spec = paper_record(&dev, sa);
        spec.noise.duration_s = 1.0;
        assert_eq!(spec.scheme, Scheme::Exponential);
        let fast = simulate_record(&dev, &spec, 7, 3).unwrap();
        spec.scheme = Scheme::Dopri5;
        spec.rtol = DEFAULT_RTOL / 1000.0;
        let tight = simulate_record(&dev, &spec, 7, 3).unwrap();
        assert_eq!(fast.summary.impacts, 0, "{name}");
        // Nearly every sample interval went to the exponential step (the first few fill its
        // history).
        assert!(
            fast.summary.exponential_steps + 10
                >= fast.v1_v.len() as u64 + spec.transient_samples() as u64 - 1
        );
        let (pa, pb) = (fast.summary.p_total_w(), tight.summary.p_total_w());
        assert!((pa / pb - 1.0).abs() < 1e-6, "{name}: {pa:e} vs {pb:e}");
        let rms = (tight.v1_v.iter().map(|v| v * v).sum::<f64>() / tight.v1_v.len() as f64).sqrt();
        let worst = fast
            .v1_v
            .iter()
            .zip(&tight.v1_v)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(
            worst < 1e-5 * rms,
            "{name}: worst V1 difference {worst:e}, rms {rms:e}"
        );
    }
}

/// A device without a transducer: its record keeps no samples of its two load voltages, which
/// the model holds at zero, and reads them as zeros; its loads' power and output spectrum are
/// those of the zeros, bit for bit (a zero of positive sign, as the sum of zeros gives it).
#[test]
fn a_record_keeps_no_samples_of_the_outputs_a_device_without_a_transducer_lacks() {
    use endstop::device::Device;
    use endstop::signal::{welch, WelchOptions};
    let text = "name = \"plain\"\nparams = \"hypothetical\"\ndescription = \"a test\"\n\
        [mechanics]\nmass_kg = 1e-3\nstiffness_n_per_m = 39478.4\ndamping_n_s_per_m = 0.0628\n\
        [stops.both]\ngap_m = 1e-5\nlaw = \"restitution\"\ncoefficient = 0.6\n\
        [transducer]\nkind = \"none\"\n";
    let device = Device::from_toml_str(text, "plain.toml").unwrap();
    // 0.1 s of a 1 kHz sine of 10 m/s^2 at 50 kHz after 10 ms: it strikes the stops.
    let (fs, n_tr, n) = (50e3, 500, 5000);
    let accel: Vec<f64> = (0..n_tr + n)
        .map(|k| -10.0 * (2.0 * std::f64::consts::PI * 1e3 * k as f64 / fs).cos())
        .collect();
    let drive = SampledDrive {
        accel: accel.into(),
        sample_rate_hz: fs,
        transient_samples: n_tr,
    };
    let mut rec = simulate_drive(&device, &drive, DEFAULT_RTOL, Scheme::Exponential).unwrap();
    assert!(rec.summary.impacts > 0, "{:?}", rec.summary);
    assert_eq!(rec.samples, n);
    assert!(rec.v1_v.is_empty() && rec.v2_v.is_empty());
    assert_eq!(rec.outputs.len(), 2, "the outputs keep their names");
    assert_eq!(rec.output_samples(0).as_ref(), vec![0.0; n].as_slice());
    assert_eq!(rec.output_samples(1).as_ref(), vec![0.0; n].as_slice());
    assert_eq!(rec.summary.p_total_w().to_bits(), 0);
    let cfg = WelchOptions::half_overlap(1024);
    let rl = device.transducer.load_resistance_ohm();
    let psd = output_psd(&rec, rl, &cfg).unwrap();
    let zeros = welch(&vec![0.0; n], fs, &cfg).unwrap();
    assert_eq!(psd.load1.freq_hz, zeros.freq_hz);
    assert_eq!(psd.total.segments, zeros.segments);
    assert!(psd.total.density.iter().all(|d| d.to_bits() == 0));
    let [v1, v2] = rec.take_pair();
    assert_eq!((v1, v2), (vec![0.0; n], vec![0.0; n]));
}
