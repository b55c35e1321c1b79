//! The steady state a stepped sweep settles on, frequency by frequency: how many drive periods
//! it repeats after (its period on the stroboscopic section) and, for a period up to
//! [`MAX_PERIOD`], the largest Floquet multiplier of that orbit shot by Newton's method. The
//! harness that tells a period-doubling cascade or a chaotic band (no period found) from an
//! orbit of a higher period where the fit's model finds no stable orbit of one or two periods.
//!
//! Usage: `cargo run --release --example orbit_period -- device.toml accel_rms_g f_from_hz
//! f_to_hz step_hz` (the sweep's direction is from `f_from_hz` to `f_to_hz`).

use endstop::device::Device;
use endstop::model::Model;
use endstop::ode::Stats;
use endstop::physics::harvester::Harvester;
use endstop::study::orbit::{Forcing, Parameter, Shooter, ShootingOptions};
use nalgebra::SVector;

/// Longest period looked for (drive periods).
const MAX_PERIOD: usize = 32;
/// Drive periods settled at each frequency before the section is read.
const SETTLE_PERIODS: usize = 600;
/// Section points read at each frequency.
const READ_PERIODS: usize = 128;
/// Return distance (scaled state, relative to the state's norm) below which the section
/// repeats: the steady-state criterion of a stepped sweep is 1e-6 relative.
const REPEAT_REL: f64 = 1e-6;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let [path, accel, from, to, step] = a.as_slice() else {
        return Err("usage: orbit_period device.toml accel_rms_g f_from_hz f_to_hz step_hz".into());
    };
    let text = std::fs::read_to_string(path)?;
    let device = Device::from_toml_str(&text, path)?;
    let h = Harvester::<4>::new(&device)?;
    let (accel_rms_g, from, to, step): (f64, f64, f64, f64) =
        (accel.parse()?, from.parse()?, to.parse()?, step.parse()?);
    let shooter = Shooter::new(&h, ShootingOptions::default());
    let n = ((to - from).abs() / step).round() as usize;
    let mut y: SVector<f64, 4> = h.rest_state();
    println!("freq_hz period max_multiplier x_section_max_m");
    for i in 0..=n {
        let freq_hz = from + (to - from).signum() * step * i as f64;
        let forcing = Forcing {
            freq_hz,
            accel_rms_g,
        };
        for _ in 0..SETTLE_PERIODS {
            y = shooter.period_map(&forcing, 0.0, y)?;
        }
        let mut section = vec![y];
        for _ in 0..READ_PERIODS {
            y = shooter.period_map(&forcing, 0.0, y)?;
            section.push(y);
        }
        let last = section[READ_PERIODS];
        let x_section_max = section
            .iter()
            .map(|s| s[0])
            .fold(f64::NEG_INFINITY, f64::max);
        let period = (1..=MAX_PERIOD).find(|&k| {
            (0..READ_PERIODS - k).all(|j| {
                let (p, q) = (section[READ_PERIODS - j], section[READ_PERIODS - j - k]);
                shooter.norm(&(p - q)) <= REPEAT_REL * shooter.norm(&p)
            })
        });
        let multiplier = match period {
            Some(k) => {
                let mut stats = Stats::default();
                shooter
                    .solve_periods(&forcing, Parameter::Frequency, 0.0, last, k, &mut stats)
                    .map_or(f64::NAN, |o| o.max_multiplier_abs())
            }
            None => f64::NAN,
        };
        let period = period.map_or("none".to_string(), |k| k.to_string());
        println!("{freq_hz:.3} {period} {multiplier:.4} {x_section_max:.4e}");
    }
    Ok(())
}
