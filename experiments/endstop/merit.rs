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

/// The normalised power density of `power_w` delivered under a vibration of RMS acceleration
/// `accel_rms_g` (g) (Beeby et al., J. Micromech. Microeng. 17 (2007) 1257: `P / (V a_rms^2)`,
/// [`merit::normalised_power_density`]), with `V` the device's `[size] volume_m3`. Records
/// `normalised_power_density_kg_s_per_m3` and `volume_m3` and returns the line for
/// `numbers.md`; without a volume, no key and a line saying it needs one; nothing without a
/// finite power.
pub(crate) fn power_density(
    exp: &mut Experiment,
    device: &Device,
    power_w: f64,
    accel_rms_g: f64,
) -> String {
    if !power_w.is_finite() {
        return String::new();
    }
    let density = device.size.map(|size| {
        let v = size.volume_m3;
        let npd = merit::normalised_power_density(power_w, v, accel_rms_g * endstop::G);
        exp.number("normalised_power_density_kg_s_per_m3", npd);
        exp.number("volume_m3", v);
        (npd, v)
    });
    power_density_line(density)
}

/// The line of `numbers.md` for a normalised power density and the volume it is over (kg s
/// m^-3, m^3), or saying that it needs the device's volume.
pub(crate) fn power_density_line(density: Option<(f64, f64)>) -> String {
    match density {
        Some((npd, v)) => format!(
            "- normalised power density (Beeby et al. 2007: P / (V a_rms^2), V = {} m^3): {} kg \
             s m^-3\n",
            fmt_sig(v, 3),
            fmt_sig(npd, 3)
        ),
        None => "- normalised power density: needs the device volume (`[size] volume_m3` in the \
                 device file)\n"
            .to_string(),
    }
}

/// The figures of merit of a mean power `power_w` under band-limited white noise of
/// two-sided density `psd_g2_per_hz` (g^2/Hz) and mean square `mean_square_g2` (g^2, `2 B Sa`
/// over the band `B`): the power per unit density `P / Sa` (kg, with `Sa` in (m/s^2)^2/Hz; the
/// broadband bound of a linear resonator under white noise, `m Sa / 2`, makes it at most half
/// the proof mass: the `2P/(m Sa)` already reported is its ratio to that bound) as
/// `power_per_sa_kg`, and the normalised power density at the noise's RMS acceleration
/// ([`power_density`]). Returns the lines for `numbers.md`; nothing without a finite power.
pub(crate) fn noise_merits(
    exp: &mut Experiment,
    device: &Device,
    power_w: f64,
    psd_g2_per_hz: f64,
    mean_square_g2: f64,
) -> String {
    if !power_w.is_finite() {
        return String::new();
    }
    let per_sa = power_w / (psd_g2_per_hz * endstop::G * endstop::G);
    exp.number("power_per_sa_kg", per_sa);
    format!(
        "- power per unit two-sided acceleration density P / Sa: {} kg (Sa in (m/s^2)^2/Hz)\n",
        fmt_sig(per_sa, 4)
    ) + &power_density(exp, device, power_w, mean_square_g2.sqrt())
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
    let edge = |e: Option<f64>, beyond: &str| {
        e.map_or(beyond.to_string(), |f| format!("{} Hz", fmt_sig(f, 5)))
    };
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
        "- half-power band of the power (Rao 2011, section 3.4): {width}, from {} to {} \
         about the peak at {} Hz\n",
        edge(b.lower_hz, "below the sweep's start"),
        edge(b.upper_hz, "above the sweep's end"),
        fmt_sig(b.peak_hz, 5)
    );
    Some((line, b))
}

/// For a sine drive (`--sine-g`, its peak in g, at `--freq-hz`), the harvester effectiveness of
/// the power `power_w` it delivers ([`effectiveness`]) and its normalised power density
/// ([`power_density`]); for a measured record, whose vibration is not the sine the bound is
/// for, the power density alone, at the analysed record's RMS acceleration `record_rms_g`.
pub(crate) fn drive_merits(
    exp: &mut Experiment,
    a: &RandomArgs,
    device: &Device,
    power_w: f64,
    record_rms_g: f64,
) -> String {
    match (a.accel_file.is_none(), a.sine_g, a.freq_hz) {
        (true, Some(peak_g), Some(freq_hz)) => {
            let rms_g = peak_g / std::f64::consts::SQRT_2;
            effectiveness(exp, device, power_w, rms_g, freq_hz)
                + &power_density(exp, device, power_w, rms_g)
        }
        _ => power_density(exp, device, power_w, record_rms_g),
    }
}
