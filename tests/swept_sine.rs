//! The swept sine ([`ChirpSweep`]) against what it must find, on the piezoelectric example of
//! `data/examples/` (a linear free flight and a one-sided linear stop) at the drive of the
//! book's "Model your own harvester" chapter.
//!
//! Swept down from above its resonance, the response follows the linear orbit, whose amplitude
//! grows as the drive nears the resonance, until it reaches the stop's gap: the high grazing
//! frequency of the linear response, computed here from the linear model alone. A swept sine
//! meets it late: the response's envelope relaxes to the steady amplitude within the ring-up
//! time tau = 1/(pi w) of the half-power width w (at the resonance; faster on its flank), so
//! that it lags the drive by at most about `rate * tau` in frequency, and a window of `c`
//! cycles locates the first contact to within the frequency the drive sweeps in one window,
//! `rate * c / f`. As the rate falls the first contact must therefore converge on the
//! grazing, within `rate * (tau + c / f)` of it. Swept up, the
//! response climbs onto the impacting orbits at the low grazing and stays on them past the high
//! one, up to their fold: its last contact lies above the down-sweep's first (hysteresis).

use endstop::device::Device;
use endstop::physics::linear::LinearResponse;
use endstop::study::chirp::{half_power_band, ChirpReport, ChirpSweep};
use endstop::study::steady::settle_settings;

fn piezo() -> Device {
    let path = format!(
        "{}/data/examples/piezo_cantilever.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    let text = std::fs::read_to_string(&path).unwrap();
    Device::from_toml_str(&text, &path).unwrap()
}

/// The drive of the book's chapter (g rms).
const ACCEL_RMS_G: f64 = 0.5;

/// Cycles per window of the swept sines (as `endstop response --sweep-rate`).
const WINDOW_CYCLES: usize = 4;

/// The frequency between `lo` and `hi` at which the linear response's displacement amplitude
/// at `ACCEL_RMS_G` equals `gap_m`, by bisection to 1e-9 Hz (the amplitude is monotone there).
fn grazing_hz(device: &Device, gap_m: f64, mut lo: f64, mut hi: f64) -> f64 {
    let lin = LinearResponse::of(device);
    let amp = std::f64::consts::SQRT_2 * ACCEL_RMS_G * endstop::G;
    let excess = |f: f64| lin.displacement_per_accel(f) * amp - gap_m;
    let rising = excess(lo) < excess(hi);
    assert!(
        (excess(lo) > 0.0) != (excess(hi) > 0.0),
        "no grazing between {lo} and {hi} Hz"
    );
    while hi - lo > 1e-9 {
        let mid = 0.5 * (lo + hi);
        if (excess(mid) > 0.0) == rising {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    0.5 * (lo + hi)
}

fn sweep(device: &Device, from_hz: f64, to_hz: f64, rate_hz_per_s: f64) -> ChirpReport {
    ChirpSweep {
        from_hz,
        to_hz,
        rate_hz_per_s,
        window_cycles: WINDOW_CYCLES,
        cfg: settle_settings(device, from_hz),
    }
    .run(device, ACCEL_RMS_G)
    .unwrap()
}

#[test]
fn the_swept_down_first_contact_converges_on_the_grazing_as_the_rate_falls() {
    let device = piezo();
    let band = half_power_band(&device).expect("a resonance");
    let (f0, w) = (band.peak_hz, band.width_hz);
    let gap_m = device.stops.upper.as_ref().expect("an upper stop").gap_m;
    let graze_hi = grazing_hz(&device, gap_m, f0, f0 + 20.0 * w);
    let graze_lo = grazing_hz(&device, gap_m, f0 - 20.0 * w, f0);
    let tau_s = 1.0 / (std::f64::consts::PI * w);
    eprintln!(
        "linear resonance {f0:.4} Hz, half-power width {w:.4} Hz, tau {tau_s:.4} s; \
         grazing at {graze_lo:.4} and {graze_hi:.4} Hz"
    );
    // Rates at which the envelope's lag rate * tau is w/4, w/8 and w/16.
    let rates: Vec<f64> = [4.0, 8.0, 16.0].iter().map(|k| w / (k * tau_s)).collect();
    let mut misses = Vec::new();
    let mut slowest_first = f64::NAN;
    for &rate in &rates {
        let down = sweep(&device, graze_hi + 4.0 * w, graze_hi - 2.0 * w, rate);
        let first = down
            .first_contact_hz
            .expect("the swept-down response touches the stop");
        let bound = rate * (tau_s + WINDOW_CYCLES as f64 / graze_hi);
        eprintln!(
            "swept down at {rate:.3} Hz/s: first contact at {first:.4} Hz, {:+.4} Hz from \
             the grazing (bound {bound:.4} Hz)",
            first - graze_hi
        );
        misses.push((first - graze_hi).abs());
        slowest_first = first;
        assert!(
            (first - graze_hi).abs() <= bound,
            "at {rate} Hz/s the first contact {first} Hz is more than {bound} Hz from the \
             grazing at {graze_hi} Hz"
        );
    }
    assert!(
        misses.windows(2).all(|p| p[1] < p[0]),
        "the first contact does not approach the grazing as the rate falls: {misses:?}"
    );
    // Hysteresis: swept up at the fastest rate, from below the low grazing through the
    // chapter's range, the response leaves the stop above where the slowest down-sweep met it.
    let up = sweep(&device, graze_lo - 4.0 * w, 200.0, rates[0]);
    let first_up = up
        .first_contact_hz
        .expect("the swept-up response touches the stop");
    let last_up = up
        .last_contact_hz
        .expect("the swept-up response leaves the stop");
    eprintln!("swept up: first contact at {first_up:.4} Hz, last at {last_up:.4} Hz");
    assert!(
        (first_up - graze_lo).abs() <= rates[0] * (tau_s + WINDOW_CYCLES as f64 / graze_lo),
        "swept up, the first contact {first_up} Hz is not at the low grazing {graze_lo} Hz"
    );
    assert!(
        last_up > slowest_first,
        "no hysteresis: swept up the last contact is at {last_up} Hz, swept down the first \
         at {slowest_first} Hz"
    );
}
