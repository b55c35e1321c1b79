//! Records of a linear free flight between rigid stops: every sample interval, those with
//! rebounds included, is advanced on the exact solution (`study::record`'s `impacts.rs`), and
//! the record agrees with Dormand-Prince everywhere at a tight tolerance.

use std::sync::Arc;

use endstop::device::Device;
use endstop::study::record::{simulate_drive, SampledDrive, Scheme, DEFAULT_RTOL};

/// A 1 kHz oscillator (zeta = 0.005) between rigid stops at +-10 um (e = 0.6) with the
/// transducer block `transducer`.
fn device(transducer: &str) -> Device {
    let w0 = 2.0 * std::f64::consts::PI * 1000.0;
    let (m, zeta) = (1e-3, 0.005);
    let text = format!(
        "name = \"rebounds\"\nparams = \"test\"\ndescription = \"rigid stops\"\n\
         [mechanics]\nmass_kg = {m:e}\nstiffness_n_per_m = {:e}\ndamping_n_s_per_m = {:e}\n\
         [stops.both]\ngap_m = 1e-5\nlaw = \"restitution\"\ncoefficient = 0.6\n{transducer}\n",
        m * w0 * w0,
        2.0 * zeta * m * w0
    );
    Device::from_toml_str(&text, "rebounds.toml").unwrap()
}

/// `a = -10 cos(2 pi 1000 t)` m/s^2 sampled at 50 kHz for 0.5 s from rest.
fn sine() -> SampledDrive {
    let fs = 50e3;
    let accel: Arc<[f64]> = (0..=25_000)
        .map(|k| -10.0 * (2.0 * std::f64::consts::PI * 1000.0 * k as f64 / fs).cos())
        .collect();
    SampledDrive {
        accel,
        sample_rate_hz: fs,
        transient_samples: 0,
    }
}

/// The record by the fast path (default tolerance) and by Dormand-Prince everywhere at rtol
/// 1e-10: the same impacts (about 1000), every interval fast, and the RMS displacement and
/// the load's power equal to 1e-6 relatively. The fast path is exact to rounding and locates
/// each rebound to a few ulps of time; the reference's error is of the order of its
/// tolerance per impact, and a rebound's error decays by e = 0.6 at the next, so 1e-6 bounds
/// both with a margin without hiding a rebound's lost or shifted impulse (a rebound time off
/// by 1e-9 of an interval shifts x_rms by about 1e-5 here).
#[test]
fn a_linear_free_flight_between_rigid_stops_is_exact_through_its_rebounds() {
    let piezo = "[transducer]\nkind = \"piezoelectric\"\ncoupling_n_per_v = 2e-4\n\
                 capacitance_f = 1e-8\nload_resistance_ohm = 2e5";
    for transducer in ["[transducer]\nkind = \"none\"", piezo] {
        let d = device(transducer);
        let drive = sine();
        let fast = simulate_drive(&d, &drive, DEFAULT_RTOL, Scheme::Exponential).unwrap();
        let reference = simulate_drive(&d, &drive, 1e-10, Scheme::Dopri5).unwrap();
        let (f, r) = (fast.summary, reference.summary);
        assert!(r.impacts > 900, "{transducer}: {} impacts", r.impacts);
        assert_eq!(f.impacts, r.impacts, "{transducer}");
        assert_eq!(
            f.exponential_steps as usize,
            drive.accel.len() - 1,
            "{transducer}"
        );
        let rel = |a: f64, b: f64| (a - b).abs() / b.abs();
        assert!(
            rel(f.x_rms_m, r.x_rms_m) < 1e-6,
            "{transducer}: {f:?} {r:?}"
        );
        if r.p_total_w() > 0.0 {
            assert!(rel(f.p_total_w(), r.p_total_w()) < 1e-6, "{transducer}");
        }
        assert!(rel(f.x_peak_m, r.x_peak_m) < 1e-9, "{transducer}");
    }
}
