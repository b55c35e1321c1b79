//! Figures of merit a designer reports, each with its source.
//!
//! * **Harvester effectiveness** (P. D. Mitcheson, E. M. Yeatman, G. K. Rao, A. S. Holmes and
//!   T. C. Green, "Energy harvesting from human and machine motion for wireless electronic
//!   devices", Proc. IEEE 96(9) (2008) 1457, the section on harvester effectiveness): the
//!   power delivered over the largest power of an ideal velocity-damped resonant generator of
//!   the same proof mass and internal displacement limit under the same vibration. That bound
//!   ([`vdrg_bound_w`]) is derived here from the generator's equation, as the paper does: at
//!   resonance the mass's amplitude is `Z = m w^2 Y0 / (c w)` for a base displacement
//!   amplitude `Y0` and damping `c`; the damping that makes `Z` the limit `Z_l`,
//!   `c = m w Y0 / Z_l`, extracts `c w^2 Z_l^2 / 2`, so
//!   `P_max = Y0 Z_l w^3 m / 2 = m A Z_l w / 2` with the acceleration amplitude
//!   `A = w^2 Y0`. (The bound over every architecture, `(2 / pi) Y0 Z_l w^3 m`, is the
//!   Coulomb-damped generator's, Mitcheson et al., J. Microelectromech. Syst. 13(3) (2004)
//!   429; [`architecture_bound_w`].) Neither paper's text could be read in this build (the
//!   stored public pages searched hold neither), so no equation number is cited: the
//!   formulas are derived above, not read. The bound is checked instead against an independent
//!   computation, our own steady state of a linear velocity-damped generator driven at
//!   resonance, whose load takes exactly `m A w Z / 2` (times its share of the damping) at
//!   its stroke `Z`, and the bound when that stroke is `Z_l` (`tests/design.rs`,
//!   `the_vdrg_bound_is_our_resonant_generator_at_its_stroke`).
//! * **Half-power bandwidth** ([`half_power_band`]): the range of frequencies over which the
//!   power is at least half its largest value, the -3 dB band of a resonance (for a lightly
//!   damped linear oscillator `f0 / Q`; S. S. Rao, *Mechanical Vibrations*, 5th ed., 2011,
//!   section 3.4, the quality factor and bandwidth), read from a sweep with linear
//!   interpolation between its points.
//! * **Normalised power density** ([`normalised_power_density`]): the power over the device's
//!   volume and the square of the RMS base acceleration, `NPD = P / (V a_rms^2)` (kg s m^-3),
//!   the figure S. P. Beeby, R. N. Torah, M. J. Tudor, P. Glynne-Jones, T. O'Donnell,
//!   C. R. Saha and S. Roy compare generators by ("A micro electromagnetic generator for
//!   vibration energy harvesting", J. Micromech. Microeng. 17 (2007) 1257, its comparison
//!   with the literature) and the reviews after it tabulate: a resonant generator's power grows
//!   as the acceleration squared and (at one shape) as its volume, so the quotient compares
//!   devices driven and built differently. The text of the paper could not be read in this
//!   build (its stored abstract names the figure only), so whether its acceleration is the
//!   RMS or the amplitude is not read from it: here it is the RMS, the one level a noise has
//!   as well as a sine (with a sine's amplitude `A = sqrt(2) a_rms` the quotient is half).
//!   It needs the device's volume, `[size] volume_m3` ([`crate::device::size`]).
//! * **Charging time** to a target voltage: the time the storage takes to charge from empty
//!   with nothing drawing, by [`crate::study::charging`] on the design with its DC load open
//!   ([`charging_time_s`]).

use crate::device::{DcLoad, Device};
use crate::drive::Sine;
use crate::progress::Progress;
use crate::study::charging::{charge, ChargeError, ChargeSettings};

/// The largest power of an ideal velocity-damped resonant generator (W): proof mass `mass_kg`,
/// internal displacement limit `limit_m` (amplitude), under a sine of RMS acceleration
/// `accel_rms_m_s2` at `freq_hz`: `m A Z_l w / 2` with `A = sqrt(2) a_rms` (module docs).
pub fn vdrg_bound_w(mass_kg: f64, limit_m: f64, accel_rms_m_s2: f64, freq_hz: f64) -> f64 {
    let w = 2.0 * std::f64::consts::PI * freq_hz;
    0.5 * mass_kg * std::f64::consts::SQRT_2 * accel_rms_m_s2 * limit_m * w
}

/// The bound over every architecture of Mitcheson et al. (2004), `(2 / pi) Y0 Z_l w^3 m` (W),
/// in the arguments of [`vdrg_bound_w`].
pub fn architecture_bound_w(mass_kg: f64, limit_m: f64, accel_rms_m_s2: f64, freq_hz: f64) -> f64 {
    4.0 / std::f64::consts::PI * vdrg_bound_w(mass_kg, limit_m, accel_rms_m_s2, freq_hz)
}

/// The harvester effectiveness of a power `power_w` (module docs): over [`vdrg_bound_w`].
pub fn effectiveness(
    power_w: f64,
    mass_kg: f64,
    limit_m: f64,
    accel_rms_m_s2: f64,
    freq_hz: f64,
) -> f64 {
    power_w / vdrg_bound_w(mass_kg, limit_m, accel_rms_m_s2, freq_hz)
}

/// The displacement limit of a device for the bound: its smallest stop gap, or `None` without
/// stops.
pub fn displacement_limit_m(device: &Device) -> Option<f64> {
    device.stops.smallest_gap_m()
}

/// The normalised power density (kg s m^-3, module docs) of a power `power_w` delivered by a
/// device of volume `volume_m3` under a vibration of RMS acceleration `accel_rms_m_s2`:
/// `P / (V a_rms^2)`.
pub fn normalised_power_density(power_w: f64, volume_m3: f64, accel_rms_m_s2: f64) -> f64 {
    power_w / (volume_m3 * accel_rms_m_s2 * accel_rms_m_s2)
}

/// A half-power band read from a sweep.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct HalfPowerBand {
    /// Frequency of the largest power (Hz).
    pub peak_hz: f64,
    /// Largest power (W).
    pub peak_w: f64,
    /// Lower edge (Hz); `None` when the power is above half at the sweep's first point.
    pub lower_hz: Option<f64>,
    /// Upper edge (Hz); `None` when the power is above half at the sweep's last point.
    pub upper_hz: Option<f64>,
}

impl HalfPowerBand {
    /// The width (Hz), when both edges lie inside the sweep.
    pub fn width_hz(&self) -> Option<f64> {
        Some(self.upper_hz? - self.lower_hz?)
    }
}

/// The half-power band of the powers `power_w` at increasing `freqs_hz` (module docs): the
/// edges are the crossings of half the peak nearest the peak on either side; `None` without a
/// positive finite power.
pub fn half_power_band(freqs_hz: &[f64], power_w: &[f64]) -> Option<HalfPowerBand> {
    let (k, &peak_w) = power_w
        .iter()
        .enumerate()
        .filter(|(_, p)| p.is_finite())
        .max_by(|a, b| a.1.total_cmp(b.1))?;
    if peak_w.is_nan() || peak_w <= 0.0 {
        return None;
    }
    let half = 0.5 * peak_w;
    let cross = |i: usize, j: usize| {
        let (p0, p1) = (power_w[i], power_w[j]);
        freqs_hz[i] + (half - p0) / (p1 - p0) * (freqs_hz[j] - freqs_hz[i])
    };
    let lower = (1..=k)
        .rev()
        .find(|&i| power_w[i - 1] < half)
        .map(|i| cross(i - 1, i));
    let upper = (k + 1..power_w.len())
        .find(|&j| power_w[j] < half)
        .map(|j| cross(j - 1, j));
    Some(HalfPowerBand {
        peak_hz: freqs_hz[k],
        peak_w,
        lower_hz: lower,
        upper_hz: upper,
    })
}

/// The time the storage of `device` takes to charge from 0 V to `target_v` under `sine` with
/// its DC load open (module docs), simulated for at most `t_max_s`; `None` for a device
/// without a storage (the resistive interface).
pub fn charging_time_s(
    device: &Device,
    sine: Sine,
    target_v: f64,
    t_max_s: f64,
    progress: &dyn Progress,
) -> Option<Result<f64, ChargeError>> {
    let mut open = device.clone();
    *open.interface.load_mut()? = DcLoad::Open;
    let settings = ChargeSettings {
        start_v: 0.0,
        target_v,
        ramp_s: 0.0,
        t_max_s,
        sample_s: t_max_s / 1000.0,
        block_s: (t_max_s / 100.0).max(sine.period_s()),
        rtol: 1e-8,
    };
    Some(charge(&open, sine, &settings, progress).map(|run| run.time_to_target_s))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_half_power_band_of_a_triangle_is_its_half_width() {
        // A triangle peaking at 10 with height 4 over 8..12: half power at 9 and 11.
        let f = [8.0, 9.5, 10.0, 10.5, 12.0];
        let p = [0.0, 3.0, 4.0, 3.0, 0.0];
        let b = half_power_band(&f, &p).unwrap();
        assert_eq!((b.peak_hz, b.peak_w), (10.0, 4.0));
        // The straight lines interpolate the triangle exactly: rounding only.
        assert!((b.width_hz().unwrap() - 2.0).abs() < 1e-12);
        let cut = half_power_band(&f[1..], &p[1..]).unwrap();
        assert!(cut.lower_hz.is_none() && cut.upper_hz.is_some());
    }

    #[test]
    fn the_normalised_power_density_is_power_over_volume_and_acceleration_squared() {
        // By hand: 2 uW from 0.5 cm^3 under 0.5 m/s^2 rms: 2e-6 / (5e-7 * 0.25) = 16 kg s m^-3
        // (the amplitude in place of the RMS would give 8, the acceleration unsquared 8).
        let npd = normalised_power_density(2e-6, 5e-7, 0.5);
        // Two roundings of 5e-7 and the quotient: a few ulps, 1e-14 relative.
        assert!((npd / 16.0 - 1.0).abs() < 1e-14, "{npd}");
    }

    #[test]
    fn the_vdrg_bound_is_the_resonant_generator_at_its_limit() {
        // m = 1 g, Z_l = 1 mm, A = 1 m/s^2 amplitude at 50 Hz: c = m w Y0 / Z_l with
        // Y0 = A / w^2 extracts c w^2 Z_l^2 / 2.
        let (m, zl, a, f) = (1e-3, 1e-3, 1.0, 50.0);
        let w = 2.0 * std::f64::consts::PI * f;
        let c = m * w * (a / (w * w)) / zl;
        let direct = 0.5 * c * w * w * zl * zl;
        let bound = vdrg_bound_w(m, zl, a / std::f64::consts::SQRT_2, f);
        assert!((bound / direct - 1.0).abs() < 1e-12);
    }
}
