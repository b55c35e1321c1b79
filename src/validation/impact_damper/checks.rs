//! Our steady states of the impact damper against its closed form ([`super`]): at several
//! points (mass ratio, restitution, clearance, frequency) the orbit found by shooting, started
//! on the closed form's, against the closed form's primary amplitude, impact phase, particle
//! velocity and largest Floquet multiplier; and along a frequency line, where our largest
//! multiplier crosses 1 in modulus against where the closed form's stability condition changes
//! sign.
//!
//! # Tolerances, stated before the runs
//! - Orbit quantities, 1e-6 (relative; radians for the phase): shooting integrates at
//!   rtol 1e-10 and accepts a period-map residual of 5e-10 ([`ShootingOptions`]), an orbit
//!   accurate to about 1e-9; the fixed point's error is that residual amplified by
//!   `|(I - M)^-1|`, at most about `1 / (1 - |mu|)` = 30 for the multipliers up to 0.97 and
//!   a few for the unstable point's: 1e-6 leaves a factor 30 above that.
//! - The largest multiplier's modulus, 1e-5 relative: the monodromy of the variational
//!   equations and their saltation matrices is accurate to some 1e-8 (the integrator's
//!   tolerance times the steps' growth), and a simple eigenvalue moves by the same order; the
//!   room covers the residual's effect on the orbit the matrix is evaluated on.
//! - A stability boundary, the frequency step of the line: our crossing is bracketed by two
//!   shot points a step apart (we interpolate linearly between them, whose error is far below
//!   a step, but the step is what is guaranteed); the closed form's is located by bisection to
//!   1e-9 Hz. Every point of the line must be the closed form's orbit (its impact phase within
//!   the orbit checks' 1e-6 rad): shooting from a wrong guess can land on another orbit.

use nalgebra::SVector;
use std::f64::consts::PI;

use crate::device::Device;
use crate::model::Model;
use crate::ode::Stats;
use crate::physics::harvester::masses::MassChain;
use crate::study::orbit::{Forcing, Parameter, Shooter, ShootingOptions};
use crate::validation::{Check, Group, Measure, ValidationError};

use super::{ImpactDamper, SymmetricOrbit};

/// The drive of every check (RMS, g).
pub const ACCEL_RMS_G: f64 = 1.0;

/// The orbit checks' tolerance on the impact phase (rad), and the one that tells the
/// boundary line's orbits are the closed form's (module docs).
pub const PHASE_TOL_RAD: f64 = 1e-6;

/// Samples of a period on which the primary's amplitude is taken, on both sides.
pub const AMPLITUDE_SAMPLES: usize = 4096;

/// One point of the orbit checks: the device's particle, clearance and restitution, and the
/// drive's frequency.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Point {
    /// The particle's mass (kg); the primary's is the device file's 0.1 kg.
    pub particle_kg: f64,
    /// The total clearance d (m).
    pub clearance_m: f64,
    /// The coefficient of restitution.
    pub restitution: f64,
    /// The drive's frequency (Hz).
    pub freq_hz: f64,
}

/// The orbit checks' points on `data/validation/impact_damper.toml` (primary 0.1 kg at
/// 10 Hz, zeta 0.02): mass ratios 0.05, 0.1 and 0.2, restitution 0.3 to 0.8, clearances 20 to
/// 80 mm, 7 to 13 Hz; each a symmetric motion that exists and is admissible, all stable but the
/// last (whose largest multiplier is about 3: shooting finds unstable orbits too).
pub const POINTS: [Point; 8] = [
    Point {
        particle_kg: 5e-3,
        clearance_m: 0.02,
        restitution: 0.6,
        freq_hz: 12.0,
    },
    Point {
        particle_kg: 5e-3,
        clearance_m: 0.02,
        restitution: 0.6,
        freq_hz: 13.0,
    },
    Point {
        particle_kg: 5e-3,
        clearance_m: 0.04,
        restitution: 0.3,
        freq_hz: 11.0,
    },
    Point {
        particle_kg: 5e-3,
        clearance_m: 0.08,
        restitution: 0.8,
        freq_hz: 7.0,
    },
    Point {
        particle_kg: 1e-2,
        clearance_m: 0.02,
        restitution: 0.6,
        freq_hz: 12.0,
    },
    Point {
        particle_kg: 2e-2,
        clearance_m: 0.04,
        restitution: 0.3,
        freq_hz: 10.0,
    },
    Point {
        particle_kg: 2e-2,
        clearance_m: 0.02,
        restitution: 0.6,
        freq_hz: 11.0,
    },
    Point {
        particle_kg: 5e-3,
        clearance_m: 0.02,
        restitution: 0.6,
        freq_hz: 11.0,
    },
];

/// The frequency line of the boundary check (Hz) on the device file as it is, and its step:
/// the symmetric motion exists and is admissible all along it, stable in its middle.
pub const BOUNDARY_LINE_HZ: (f64, f64) = (11.2, 14.2);

/// The boundary line's step (Hz).
pub const BOUNDARY_STEP_HZ: f64 = 0.01;

/// `device` with a point's particle, clearance and restitution.
pub fn variant(device: &Device, p: &Point) -> Result<Device, ValidationError> {
    let mut d = device.with_param("masses.1.mass_kg", p.particle_kg);
    for k in 0..2 {
        d = d
            .and_then(|d| d.with_param(&format!("stops.{k}.gap_m"), 0.5 * p.clearance_m))
            .and_then(|d| d.with_param(&format!("stops.{k}.coefficient"), p.restitution));
    }
    d.map_err(|e| ValidationError::Device(e.to_string()))
}

/// Our orbit of one point, measured as the closed form's.
#[derive(Debug, Clone, PartialEq)]
pub struct Ours {
    /// The primary's largest |X| (absolute coordinates, m) on [`AMPLITUDE_SAMPLES`] times.
    pub amplitude_m: f64,
    /// The drive phase at the impact on the upper wall (rad).
    pub impact_phase_rad: f64,
    /// The particle's absolute velocity after that impact (m/s).
    pub u_after_m_s: f64,
    /// The largest Floquet multiplier's modulus.
    pub max_multiplier: f64,
}

/// The closed form's motion at `freq_hz` under the checks' drive (the larger impulse's root),
/// with the drive phase at its upper impact; an error when it does not exist or is not
/// admissible.
pub fn closed_form(
    damper: &ImpactDamper,
    freq_hz: f64,
) -> Result<(SymmetricOrbit, f64), ValidationError> {
    let w = 2.0 * PI * freq_hz;
    let accel = std::f64::consts::SQRT_2 * ACCEL_RMS_G * crate::G;
    let (force, lead) = damper.base_force(accel, w);
    let orbit = damper
        .symmetric_orbits(w, force)
        .into_iter()
        .next()
        .filter(|o| o.admissible)
        .ok_or_else(|| {
            ValidationError::Device(format!(
                "no admissible symmetric motion at {freq_hz} Hz ({damper:?})"
            ))
        })?;
    let phase = (orbit.force_phase_rad - lead).rem_euclid(2.0 * PI);
    Ok((orbit, phase))
}

/// Shoots the device's orbit at `freq_hz` from the closed form's, cut a quarter period after
/// its upper impact (mid-flight), and measures it.
pub fn shoot(device: &Device, freq_hz: f64) -> Result<Ours, ValidationError> {
    let damper = ImpactDamper::of(device)?;
    let (cf, impact_phase) = closed_form(&damper, freq_hz)?;
    let h = MassChain::<6>::new(device).map_err(crate::study::orbit::OrbitError::from)?;
    let [(x0, v0), (x1, v1)] = h.layout().masses[..] else {
        return Err(ValidationError::Device("two masses expected".into()));
    };
    let w = 2.0 * PI * freq_hz;
    let accel = std::f64::consts::SQRT_2 * ACCEL_RMS_G * crate::G;
    // The frame's motion y_b = (A / w^2) sin(theta) and its velocity at drive phase theta.
    let frame = |theta: f64| (accel / (w * w) * theta.sin(), accel / w * theta.cos());
    let period = 1.0 / freq_hz;
    let section = (impact_phase + 0.5 * PI).rem_euclid(2.0 * PI);
    let s = damper.state_at(&cf, 0.25 * period);
    let (yb, vb) = frame(section);
    let mut guess = SVector::<f64, 6>::zeros();
    guess[x0] = s[0] - yb;
    guess[v0] = s[1] - vb;
    guess[x1] = s[2] - yb;
    guess[v1] = s[3] - vb;
    let forcing = Forcing {
        freq_hz,
        accel_rms_g: ACCEL_RMS_G,
    };
    let shooter = Shooter::new(&h, ShootingOptions::default());
    let mut stats = Stats::default();
    let orbit = shooter.solve(&forcing, Parameter::Frequency, section, guess, &mut stats)?;
    // One period from the section: the primary's absolute displacement on the sample times,
    // and the first jump of the particle's velocity on the upper wall.
    let mut amplitude = 0.0f64;
    let mut next = 0usize;
    let mut last: Option<SVector<f64, 6>> = None;
    let mut upper: Option<(f64, f64)> = None;
    shooter
        .flow(&forcing, section, orbit.state_n(), period, |step, _| {
            while next < AMPLITUDE_SAMPLES {
                let t = period * next as f64 / AMPLITUDE_SAMPLES as f64;
                if t > step.t1() {
                    break;
                }
                let y = step.at(t);
                amplitude = amplitude.max((y[x0] + frame(section + w * t).0).abs());
                next += 1;
            }
            if let Some(prev) = last {
                let jump = (step.y0[v1] - prev[v1]).abs();
                if upper.is_none() && jump > 0.0 && step.y0[x1] > step.y0[x0] {
                    let theta = section + w * step.t0;
                    upper = Some((theta, step.y0[v1] + frame(theta).1));
                }
            }
            last = Some(step.y1);
        })
        .map_err(|e| shooter.solver_err(Parameter::Frequency, &forcing, e))?;
    let (theta, u_after) = upper.ok_or_else(|| {
        ValidationError::Device(format!("{freq_hz} Hz: our orbit meets no upper wall"))
    })?;
    Ok(Ours {
        amplitude_m: amplitude,
        impact_phase_rad: theta.rem_euclid(2.0 * PI),
        u_after_m_s: u_after,
        max_multiplier: orbit.max_multiplier_abs(),
    })
}

const SOURCE: &str = "closed form derived from Masri & Caughey (1966)'s conditions";

/// The orbit checks at every point of [`POINTS`] on `device` (the impact damper file).
pub fn orbit_checks(device: &Device) -> Result<Vec<Check>, ValidationError> {
    let mut g = Group::new("impact damper: symmetric orbit");
    for p in &POINTS {
        let d = variant(device, p)?;
        let damper = ImpactDamper::of(&d)?;
        let (cf, phase) = closed_form(&damper, p.freq_hz)?;
        let ours = shoot(&d, p.freq_hz)?;
        let at = format!(
            "mu {:.2}, e {}, d {} mm, {} Hz",
            p.particle_kg / damper.primary_kg,
            p.restitution,
            p.clearance_m * 1e3,
            p.freq_hz
        );
        let orbit_reason = "shooting's orbit is accurate to about 1e-9, amplified by at most \
                            1 / (1 - |mu|) near the boundary";
        g.add(
            SOURCE,
            &format!("{at}: primary amplitude (m)"),
            damper.primary_amplitude_m(&cf, AMPLITUDE_SAMPLES),
            ours.amplitude_m,
            Measure::Relative,
            1e-6,
            orbit_reason,
        );
        let dphase = (ours.impact_phase_rad - phase + PI).rem_euclid(2.0 * PI) - PI;
        g.add(
            SOURCE,
            &format!("{at}: drive phase at the upper impact (rad)"),
            phase,
            phase + dphase,
            Measure::Absolute,
            PHASE_TOL_RAD,
            orbit_reason,
        );
        g.add(
            SOURCE,
            &format!("{at}: particle velocity after the impact (m/s)"),
            cf.u_after_m_s,
            ours.u_after_m_s,
            Measure::Relative,
            1e-6,
            orbit_reason,
        );
        g.add(
            "stability derived from Masri & Caughey's perturbation (saltation on the closed form)",
            &format!("{at}: largest Floquet multiplier's modulus"),
            damper.max_multiplier_abs(&cf),
            ours.max_multiplier,
            Measure::Relative,
            1e-5,
            "the variational monodromy is accurate to some 1e-8; a simple eigenvalue moves alike",
        );
    }
    Ok(g.into_checks())
}

/// Where `f(x) - 1` changes sign on the grid `xs` with values `ys`: the brackets' indices.
fn brackets(ys: &[f64]) -> Vec<usize> {
    (0..ys.len().saturating_sub(1))
        .filter(|&k| (ys[k] - 1.0).signum() != (ys[k + 1] - 1.0).signum())
        .collect()
}

/// The stability boundaries along [`BOUNDARY_LINE_HZ`]: ours (linear interpolation between
/// shot points) against the closed form's (bisection), each crossing one check, and their
/// counts.
pub fn boundary_checks(device: &Device) -> Result<Vec<Check>, ValidationError> {
    let damper = ImpactDamper::of(device)?;
    let (from, to) = BOUNDARY_LINE_HZ;
    let n = ((to - from) / BOUNDARY_STEP_HZ).round() as usize;
    let freqs: Vec<f64> = (0..=n)
        .map(|k| from + BOUNDARY_STEP_HZ * k as f64)
        .collect();
    let cf_max = |f: f64| -> Result<f64, ValidationError> {
        let (cf, _) = closed_form(&damper, f)?;
        Ok(damper.max_multiplier_abs(&cf))
    };
    let mut ours = Vec::with_capacity(freqs.len());
    let mut theirs = Vec::with_capacity(freqs.len());
    let mut elsewhere = 0usize;
    for &f in &freqs {
        let o = shoot(device, f)?;
        let (_, phase) = closed_form(&damper, f)?;
        if ((o.impact_phase_rad - phase + PI).rem_euclid(2.0 * PI) - PI).abs() > PHASE_TOL_RAD {
            elsewhere += 1;
        }
        ours.push(o.max_multiplier);
        theirs.push(cf_max(f)?);
    }
    let ours_at: Vec<f64> = brackets(&ours)
        .into_iter()
        .map(|k| {
            let (a, b) = (ours[k] - 1.0, ours[k + 1] - 1.0);
            freqs[k] + BOUNDARY_STEP_HZ * a / (a - b)
        })
        .collect();
    let mut theirs_at = Vec::new();
    for k in brackets(&theirs) {
        let (mut lo, mut hi) = (freqs[k], freqs[k + 1]);
        let below = theirs[k] < 1.0;
        while hi - lo > 1e-9 {
            let mid = 0.5 * (lo + hi);
            if (cf_max(mid)? < 1.0) == below {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        theirs_at.push(0.5 * (lo + hi));
    }
    let mut g = Group::new("impact damper: stability boundary");
    g.add(
        SOURCE,
        &format!(
            "points of the line whose orbit's impact phase is off the closed form's by more \
             than {PHASE_TOL_RAD:e} rad"
        ),
        0.0,
        elsewhere as f64,
        Measure::Absolute,
        0.0,
        "a count: every multiplier compared is the closed-form orbit's",
    );
    g.add(
        SOURCE,
        &format!("crossings of |mu| = 1 from {from} to {to} Hz in steps of {BOUNDARY_STEP_HZ} Hz"),
        theirs_at.len() as f64,
        ours_at.len() as f64,
        Measure::Absolute,
        0.0,
        "a count",
    );
    for (k, (t, o)) in theirs_at.iter().zip(&ours_at).enumerate() {
        g.add(
            SOURCE,
            &format!("stability boundary {} (Hz)", k + 1),
            *t,
            *o,
            Measure::Absolute,
            BOUNDARY_STEP_HZ,
            "our crossing is bracketed by shot points a step apart",
        );
    }
    Ok(g.into_checks())
}
