//! Grazing of a linear oscillator with a rigid stop: below the first contact the orbit is the
//! linear response, whose amplitude `m A / |k - m w^2 + j w c|` equals the gap at the two
//! frequencies of [`Oscillator::grazing_rad_s`] around the resonance. The continuation must
//! locate its grazing points there: once going up in frequency from below the lower one, once
//! going down from above the upper one, each run started from rest on the non-impacting
//! branch and stopped at the resonance `sqrt(k/m)`.
//!
//! The grazing test function is the largest displacement less the gap, located on the
//! integrator's dense output, and the event is located on the branch to the continuation's
//! `locate_tol`; the check holds the frequency to that tolerance.

use crate::device::{Device, StopLaw, Transducer};
use crate::physics::closed_forms::Oscillator;
use crate::progress::Silent;
use crate::study::continuation::{branch_from_rest, ContinuationSettings};
use crate::study::orbit::Forcing;
use crate::validation::{Check, Group, Measure, ValidationError};

/// The continuation's grazing frequencies of `device` (one rigid stop, no transducer) under
/// `accel_rms_g` against the closed form: up from `from_hz` and down from `to_hz` to the
/// resonance, with parameter steps of at most `max_step_hz`, events located to
/// `locate_tol_hz`.
pub fn grazing_checks(
    device: &Device,
    accel_rms_g: f64,
    (from_hz, to_hz): (f64, f64),
    max_step_hz: f64,
    locate_tol_hz: f64,
) -> Result<Vec<Check>, ValidationError> {
    let stops: Vec<_> = device.stops.present().collect();
    let [(_, stop)] = stops.as_slice() else {
        return Err(ValidationError::Device(format!(
            "{}: the check needs exactly one stop",
            device.name
        )));
    };
    if !matches!(stop.law, StopLaw::Restitution { .. }) || device.transducer != Transducer::None {
        return Err(ValidationError::Device(format!(
            "{}: the check needs a rigid (restitution) stop and no transducer",
            device.name
        )));
    }
    let m = &device.mechanics;
    let osc = Oscillator {
        mass_kg: m.mass_kg,
        stiffness_n_per_m: m.stiffness_n_per_m,
        damping_n_s_per_m: m.damping_n_s_per_m,
    };
    let amplitude = std::f64::consts::SQRT_2 * accel_rms_g * crate::G;
    let analytic_hz: Vec<f64> = osc
        .grazing_rad_s(amplitude, stop.gap_m)
        .into_iter()
        .map(|w| w / (2.0 * std::f64::consts::PI))
        .collect();
    let [lower, upper] = analytic_hz.as_slice() else {
        return Err(ValidationError::Device(format!(
            "{}: the linear response does not reach the gap on both sides of resonance",
            device.name
        )));
    };
    let resonance_hz = device.suspension_omega_rad_s() / (2.0 * std::f64::consts::PI);
    let mut g = Group::new(&format!("grazing: {}", device.name));
    for (label, reference, start, stop_hz) in [
        ("lower", *lower, from_hz, resonance_hz),
        ("upper", *upper, to_hz, resonance_hz),
    ] {
        let mut settings = ContinuationSettings::frequency(start, stop_hz, max_step_hz);
        settings.locate_tol = locate_tol_hz;
        let forcing = Forcing {
            freq_hz: start,
            accel_rms_g,
        };
        let branch = branch_from_rest(device, forcing, &settings, 200, &Silent)?;
        let events: Vec<f64> = branch.grazing_events().map(|e| e.param).collect();
        g.add(
            "the branch crosses the gap once",
            &format!("grazing events on the branch from {start:.6} Hz to the resonance"),
            1.0,
            events.len() as f64,
            Measure::Absolute,
            0.0,
            "a count",
        );
        let ours = events.first().copied().unwrap_or(f64::NAN);
        g.add(
            "closed form: m A / |k - m w^2 + j w c| = gap",
            &format!("{label} grazing frequency (Hz), from {start:.6} Hz"),
            reference,
            ours,
            Measure::Absolute,
            locate_tol_hz,
            "the event is located to its tolerance on the branch",
        );
    }
    Ok(g.into_checks())
}
