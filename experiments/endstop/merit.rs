//! The designer's figures of merit that `endstop sweep` and `endstop random` report beside
//! their own numbers: new keys of `summary.json` and new lines of `numbers.md`, computed by the
//! functions `endstop design` uses ([`endstop::design::merit`], whose docs derive each formula
//! and cite its source), so that the three commands share one formula each.

use endstop::design::merit;
use endstop::device::Device;
use endstop_experiments::{fmt_sig, Experiment};

use crate::random_args::RandomArgs;

/// The harvester effectiveness of `power_w` delivered under a sine of `accel_rms_g` (g rms) at
/// `freq_hz` (Mitcheson, Yeatman, Rao, Holmes and Green, Proc. IEEE 96(9) (2008) 1457, the
/// section on harvester effectiveness: the power over the largest power of an ideal
/// velocity-damped resonant generator of the same proof mass and displacement limit,
/// `m A Z_l w / 2`, [`merit::vdrg_bound_w`]), with the limit `Z_l` the device's smallest stop
/// gap and `m` its first mass. Records `effectiveness` and `effectiveness_limit_m` and returns
/// the line for `numbers.md`; nothing for a device without stops (no displacement limit) or
/// without a finite power.
pub(crate) fn effectiveness(
    exp: &mut Experiment,
    device: &Device,
    power_w: f64,
    accel_rms_g: f64,
    freq_hz: f64,
) -> String {
    let Some(limit_m) = merit::displacement_limit_m(device) else {
        return String::new();
    };
    if !power_w.is_finite() {
        return String::new();
    }
    let e = merit::effectiveness(
        power_w,
        device.mechanics.mass_kg,
        limit_m,
        accel_rms_g * endstop::G,
        freq_hz,
    );
    exp.number("effectiveness", e);
    exp.number("effectiveness_limit_m", limit_m);
    format!(
        "- harvester effectiveness at {} Hz (Mitcheson et al. 2008: the power over the ideal \
         velocity-damped resonant generator's m A Z_l w / 2, with Z_l = {} m the smallest stop \
         gap): {}\n",
        fmt_sig(freq_hz, 5),
        fmt_sig(limit_m, 3),
        fmt_sig(e, 3)
    )
}

/// The half-power band of the powers `power_w` at the increasing frequencies `freqs_hz` (the
/// -3 dB band of a resonance, `f0 / Q` for a lightly damped linear oscillator: S. S. Rao,
/// *Mechanical Vibrations*, 5th ed., 2011, section 3.4; read with linear interpolation by
/// [`merit::half_power_band`]). Records `half_power_peak_hz` and each edge inside the sweep
/// (`half_power_lower_hz`, `half_power_upper_hz`) and, with both, `half_power_width_hz`;
/// returns the line for `numbers.md` and the band, neither without a positive power.
pub(crate) fn half_power(
    exp: &mut Experiment,
    freqs_hz: &[f64],
    power_w: &[f64],
) -> Option<(String, merit::HalfPowerBand)> {
    let b = merit::half_power_band(freqs_hz, power_w)?;
    exp.number("half_power_peak_hz", b.peak_hz);
    let edge = |e: Option<f64>, beyond: &str| e.map_or(beyond.to_string(), |f| fmt_sig(f, 5));
    if let Some(f) = b.lower_hz {
        exp.number("half_power_lower_hz", f);
    }
    if let Some(f) = b.upper_hz {
        exp.number("half_power_upper_hz", f);
    }
    let width = match b.width_hz() {
        Some(w) => {
            exp.number("half_power_width_hz", w);
            format!("{} Hz wide", fmt_sig(w, 4))
        }
        None => "wider than the sweep".to_string(),
    };
    let line = format!(
        "- half-power band of the power (Rao 2011, section 3.4): {width}, from {} to {} Hz \
         about the peak at {} Hz\n",
        edge(b.lower_hz, "below the sweep"),
        edge(b.upper_hz, "above the sweep"),
        fmt_sig(b.peak_hz, 5)
    );
    Some((line, b))
}

/// For a sine drive (`--sine-g`, its peak in g, at `--freq-hz`), the harvester effectiveness of
/// the power `power_w` it delivers ([`effectiveness`]); nothing for a measured
/// record, whose vibration is not the sine the bound is for.
pub(crate) fn sine_effectiveness(
    exp: &mut Experiment,
    a: &RandomArgs,
    device: &Device,
    power_w: f64,
) -> String {
    match (a.accel_file.is_none(), a.sine_g, a.freq_hz) {
        (true, Some(peak_g), Some(freq_hz)) => effectiveness(
            exp,
            device,
            power_w,
            peak_g / std::f64::consts::SQRT_2,
            freq_hz,
        ),
        _ => String::new(),
    }
}
