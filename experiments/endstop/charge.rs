//! `endstop charge`: the time for a storage capacitor behind an interface circuit
//! (`[interface]`: a diode bridge, SSHI, SECE) to reach a target voltage under a sine.

use std::path::PathBuf;

use anyhow::Result;
use clap::Parser;
use endstop::drive::Sine;
use endstop::study::charging::{charge as run_charge, ChargeSettings};

use crate::shared::start;
use endstop_experiments::fmt_sig;
use endstop_experiments::io::frame::frame;
use endstop_experiments::io::plot::{LegendPos, LinePlot, Series, Style, PALETTE};
use endstop_experiments::row;

/// The arguments of `endstop charge`.
#[derive(Parser, Debug)]
pub struct ChargeArgs {
    /// Device file (TOML) with an `[interface]` table, e.g. a copy of
    /// data/examples/piezo_bridge.toml.
    #[arg(long)]
    device: PathBuf,
    /// Drive frequency (Hz).
    #[arg(long, allow_hyphen_values = true)]
    freq_hz: f64,
    /// RMS base acceleration (g).
    #[arg(long, allow_hyphen_values = true)]
    accel_rms_g: f64,
    /// Storage voltage at the start (V).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    start_v: f64,
    /// Target storage voltage (V).
    #[arg(long, allow_hyphen_values = true)]
    target_v: f64,
    /// Periods over which the drive ramps up from zero (0: it starts at once, from rest at
    /// phase zero).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    ramp_periods: f64,
    /// Longest simulated time (s).
    #[arg(long, default_value_t = 600.0, allow_hyphen_values = true)]
    t_max_s: f64,
    /// Output directory; default: data/results/endstop-charge.
    #[arg(long)]
    out: Option<PathBuf>,
}

/// The most drive periods a charge may simulate (see [`charge`]).
const MAX_PERIODS: f64 = 1e7;

/// `endstop charge`: the time for the storage to reach a target under a sine.
pub fn charge(a: ChargeArgs) -> Result<()> {
    for (name, v) in [
        ("--freq-hz", a.freq_hz),
        ("--accel-rms-g", a.accel_rms_g),
        ("--t-max-s", a.t_max_s),
    ] {
        if !(v.is_finite() && v > 0.0) {
            anyhow::bail!("{name} must be a finite positive number, not {v}");
        }
    }
    for (name, v) in [("--start-v", a.start_v), ("--target-v", a.target_v)] {
        if !v.is_finite() {
            anyhow::bail!("{name} must be a finite voltage, not {v}");
        }
    }
    if a.target_v <= a.start_v {
        anyhow::bail!(
            "--target-v = {} V must be above --start-v = {} V",
            a.target_v,
            a.start_v
        );
    }
    // The longest run: a charge simulates every period, at some thousands of periods a
    // second, so that 1e7 periods is already hours.
    if a.t_max_s * a.freq_hz > MAX_PERIODS {
        anyhow::bail!(
            "--t-max-s = {} s is {:.3e} periods at {} Hz: must be at most {MAX_PERIODS:e} \
             periods (a storage still rising then needs a stronger drive or a smaller \
             capacitor, not a longer run)",
            a.t_max_s,
            a.t_max_s * a.freq_hz,
            a.freq_hz
        );
    }
    if !(a.ramp_periods.is_finite() && a.ramp_periods >= 0.0) {
        anyhow::bail!(
            "--ramp-periods must be a finite number >= 0, not {}",
            a.ramp_periods
        );
    }
    let (mut exp, loaded, device) = start("endstop-charge", &a.device, None, a.out.clone())?;
    let period = 1.0 / a.freq_hz;
    let settings = ChargeSettings {
        start_v: a.start_v,
        target_v: a.target_v,
        ramp_s: a.ramp_periods * period,
        t_max_s: a.t_max_s,
        sample_s: (a.t_max_s / 20_000.0).max(period / 8.0),
        block_s: (200.0 * period).min(a.t_max_s / 10.0),
        rtol: 1e-8,
    };
    let run = endstop_experiments::with_progress(100, "charging (% of the target)", |p| {
        run_charge(
            &device,
            Sine::from_rms_g(a.accel_rms_g, a.freq_hz),
            &settings,
            p,
        )
    })?;
    let rows = run
        .t_s
        .iter()
        .zip(&run.vs_v)
        .map(|(&t, &v)| row!["t_s" => t, "vs_v" => v])
        .collect::<Vec<_>>();
    exp.write_parquet("charge", &mut frame(rows)?, &device.params)?;
    exp.number("time_to_target_s", run.time_to_target_s);
    exp.number("stored_j", run.stored_j);
    // The run's conditions, so that a publisher states them from the run, not from its job.
    exp.number("freq_hz", a.freq_hz);
    exp.number("accel_rms_g", a.accel_rms_g);
    exp.number("start_v", a.start_v);
    exp.number("target_v", a.target_v);
    if let Some(c) = device.interface.storage_capacitance_f() {
        exp.number("storage_capacitance_f", c);
    }
    let md = format!(
        "Charging of `{}` ({} interface) at {} Hz, {} g rms, from {} V to {} V; the drive \
         starts at t = 0 from rest at phase zero{}.\n\n- time to the target: {} s\n- energy \
         stored on the way: {} uJ\n",
        loaded.file,
        device.interface.key(),
        a.freq_hz,
        a.accel_rms_g,
        a.start_v,
        a.target_v,
        if a.ramp_periods > 0.0 {
            format!(", ramped up over {} periods", a.ramp_periods)
        } else {
            ", at full amplitude at once".to_string()
        },
        fmt_sig(run.time_to_target_s, 4),
        fmt_sig(run.stored_j * 1e6, 4)
    );
    exp.write_numbers_md(&md)?;
    print!("{md}");
    let pts = run
        .t_s
        .iter()
        .copied()
        .zip(run.vs_v.iter().copied())
        .collect();
    let plot = LinePlot::new(
        &format!("Charging the storage: {}", device.name),
        "time [s]",
        "storage voltage V_s [V]",
        vec![Series::new("V_s", pts, PALETTE[0], Style::Line)],
    )
    .legend(LegendPos::LowerRight);
    exp.write_plot(&plot)?;
    exp.finish()
}
