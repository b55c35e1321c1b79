//! The interfaces' records: charging an open storage from 0 V, and random ensembles behind
//! every interface (the cost of a record against the resistive load is the benchmark's,
//! `experiments/bench/interfaces.rs`).

use anyhow::Result;
use endstop::device::Device;
use endstop::drive::noise::NoiseSpec;
use endstop::drive::Sine;
use endstop::study::charging::{charge, ChargeSettings};
use endstop::study::record::{storage_ensemble, transient_s, RecordSpec, Scheme, DEFAULT_RTOL};

use super::{resonance_hz, variants, ACCEL_RMS_G, SEED};
use crate::io::frame::frame;
use crate::io::md::Table;
use crate::io::plot::{LegendPos, LinePlot, Series, Style, PALETTE};
use crate::{fmt_sig, row, write_atomic, Experiment, LoadedDevice};

/// The device with its storage's DC load removed (the storage charges open), for any interface
/// with a storage.
fn open_storage(d: &Device) -> Device {
    let mut open = d.clone();
    if let Some(load) = open.interface.load_mut() {
        *load = endstop::device::DcLoad::Open;
    }
    open
}

/// Charging an open storage from 0 V at the cantilever's resonance behind every interface, the
/// drive ramped over 20 periods.
pub(super) fn charging(exp: &mut Experiment, piezo: &LoadedDevice) -> Result<()> {
    let f0 = resonance_hz(&piezo.device);
    let cs = ChargeSettings {
        start_v: 0.0,
        target_v: 5.0,
        ramp_s: 20.0 / f0,
        t_max_s: 60.0,
        sample_s: 1e-3,
        block_s: 0.5,
        rtol: 1e-8,
    };
    let mut rows = Vec::new();
    let mut series = Vec::new();
    let mut t = Table::new(["interface", "time to 5 V (s)"]);
    for (k, (name, d)) in variants(&piezo.device).into_iter().enumerate() {
        let open = open_storage(&d);
        let run = crate::with_progress(100, &format!("charging, {name} (% of 5 V)"), |p| {
            charge(&open, Sine::from_rms_g(ACCEL_RMS_G, f0), &cs, p)
        })?;
        if name == "full_bridge" {
            exp.number("charge_time_to_5v_s", run.time_to_target_s);
        }
        exp.number(&format!("charge_time_to_5v_{name}_s"), run.time_to_target_s);
        t.row([name.to_string(), fmt_sig(run.time_to_target_s, 4)]);
        rows.extend(
            run.t_s
                .iter()
                .zip(&run.vs_v)
                .map(|(&t, &v)| row!["interface" => name, "t_s" => t, "vs_v" => v]),
        );
        series.push(Series::new(
            name,
            run.t_s
                .iter()
                .copied()
                .zip(run.vs_v.iter().copied())
                .collect(),
            PALETTE[k % PALETTE.len()],
            Style::Line,
        ));
    }
    let t_end = series
        .iter()
        .flat_map(|s| s.points.last().map(|p| p.0))
        .fold(0.0f64, f64::max);
    // Drawn first, under the curves: a curve that approaches the target from below runs
    // along it, and would be hidden by a line drawn over it.
    series.insert(
        0,
        Series::new(
            "target",
            vec![(0.0, cs.target_v), (t_end, cs.target_v)],
            PALETTE[5],
            Style::Dashed,
        ),
    );
    exp.write_parquet("charging", &mut frame(rows)?, "hypothetical")?;
    exp.write_extra_plot(
        "interfaces_charging",
        &LinePlot::new(
            &format!(
                "Charging 10 uF from 0 V behind each interface, {} Hz, {ACCEL_RMS_G} g rms",
                fmt_sig(f0, 4)
            ),
            "time [s]",
            "storage voltage V_s [V]",
            series,
        )
        .legend(LegendPos::LowerRight),
    )?;
    write_atomic(
        &exp.book_dir.join("charging.md"),
        format!(
            "With the drive ramped up over 20 periods from rest at phase zero, at {} Hz and \
             {ACCEL_RMS_G} g rms, the 10 uF storage of `piezo_bridge.toml` (load removed) \
             reaches 5 V after (SSHI with Q = {}, SECE with an efficiency of {}; each curve \
             ends with the {} s block of integration in which it reached the target):\n\n{}",
            fmt_sig(f0, 4),
            super::SSHI_Q,
            super::SECE_EFFICIENCY,
            fmt_sig(cs.block_s, 2),
            t.render()
        )
        .as_bytes(),
    )?;
    Ok(())
}

/// Eight 2 s records behind every interface of the cantilever, at 1e-4 g^2/Hz, each after a
/// pre-roll that lets the storage settle.
pub(super) fn ensembles(exp: &mut Experiment, piezo: &LoadedDevice) -> Result<()> {
    // The level (g²/Hz, two-sided), each record's analysed length (s) and the records per
    // interface.
    const LEVEL: f64 = 1e-4;
    const SECS: f64 = 2.0;
    const RECORDS: u64 = 8;
    // The pre-roll covers the storage's settling (five R_L C_s, `transient_s`) and at least
    // the time that rings the cantilever up (s).
    const MIN_PRE_ROLL_S: f64 = 1.0;
    let spec = |secs: f64, d: &Device| -> Result<RecordSpec> {
        Ok(RecordSpec {
            noise: NoiseSpec {
                duration_s: secs,
                ..endstop::paper::setups::paper_noise(LEVEL)
            },
            transient_s: transient_s(d).max(MIN_PRE_ROLL_S),
            rtol: DEFAULT_RTOL,
            scheme: Scheme::Exponential,
        })
    };
    let mut t = Table::new([
        "interface",
        "records",
        "pre-roll (s)",
        "mean DC power (uW)",
        "mean efficiency",
        "largest relative ledger residual",
    ]);
    let mut rows = Vec::new();
    for (name, d) in variants(&piezo.device) {
        eprintln!("[interfaces] ensemble, {name}");
        let spec = spec(SECS, &d)?;
        let ens = storage_ensemble(&d, &spec, SEED, RECORDS)?;
        let n = ens.len() as f64;
        for (k, r) in ens.iter().enumerate() {
            rows.push(row!["interface" => name, "stream" => k, "p_dc_w" => r.p_dc_w, "p_drive_w" => r.p_drive_w, "vdc_v" => r.vdc_v]);
        }
        t.row([
            name.into(),
            ens.len().to_string(),
            fmt_sig(spec.transient_s, 4),
            fmt_sig(ens.iter().map(|r| r.p_dc_w).sum::<f64>() / n * 1e6, 4),
            fmt_sig(ens.iter().map(|r| r.efficiency()).sum::<f64>() / n, 3),
            format!(
                "{:.1e}",
                ens.iter()
                    .map(|r| r.ledger.relative_residual().abs())
                    .fold(0.0, f64::max)
            ),
        ]);
    }
    exp.write_parquet("ensembles", &mut frame(rows)?, "hypothetical")?;
    let md = format!(
        "Per interface: {RECORDS} records of band-limited white noise at {LEVEL:e} g²/Hz \
         (two-sided), {SECS} s analysed each, seed {SEED}, after a pre-roll of the longer of \
         five storage time constants and {MIN_PRE_ROLL_S} s (the cantilever's ring-up).\n\n{}",
        t.render()
    );
    write_atomic(&exp.book_dir.join("ensembles.md"), md.as_bytes())?;
    Ok(())
}
