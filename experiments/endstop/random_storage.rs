//! The report of `endstop random` on a model with a storage (an interface circuit,
//! `[interface]`: a diode bridge, SSHI, SECE into a storage capacitor): for an ensemble of
//! band-limited white-noise records, or one measured acceleration record, each run from rest
//! with the pre-roll discarded, the DC power, the drive's power, their ratio (the efficiency),
//! the mean storage voltage and the energy ledger's closure of each record. The records and
//! the refusal of an open DC load (no steady mean under noise) are the library's one random
//! path (`endstop::study::random`); this file writes what it returns.
//!
//! The pre-roll ([`endstop::study::record::transient_s`]) covers the storage as well as the
//! mechanics: the storage charges towards its mean with the time constant of its DC load,
//! `R C_s`, often longer than the mass's ring-up.

use anyhow::Result;
use endstop::device::Device;
use endstop::study::record::{RecordSpec, StorageRecord, StorageSummary};
use endstop_experiments::io::frame::frame;
use endstop_experiments::row;
use endstop_experiments::{fmt_sig, Experiment, LoadedDevice};

use crate::random_args::{MeasuredDrive, RandomArgs};
use crate::shared::describe;

/// The per-record table's rows.
fn rows(records: &[StorageRecord], source: &str) -> Vec<endstop_experiments::io::frame::Row> {
    records
        .iter()
        .enumerate()
        .map(|(k, r)| {
            row![
                "realisation" => k as u64,
                "source" => source.to_string(),
                "p_dc_w" => r.p_dc_w,
                "p_drive_w" => r.p_drive_w,
                "efficiency" => r.efficiency(),
                "vdc_v" => r.vdc_v,
                "ledger_relative_residual" => r.ledger.relative_residual(),
                "steps" => r.summary.stats.accepted,
                "exact_steps" => r.summary.exponential_steps,
            ]
        })
        .collect()
}

/// Writes the report of the noise ensemble `records` (of the record `spec` at `psd` g^2/Hz).
pub fn noise(
    a: &RandomArgs,
    mut exp: Experiment,
    loaded: &LoadedDevice,
    device: &Device,
    psd: f64,
    spec: &RecordSpec,
    records: &[StorageRecord],
) -> Result<()> {
    eprintln!(
        "[endstop-random] {} records of {} s behind the `{}` interface",
        records.len(),
        a.duration_s,
        device.interface.key()
    );
    let source = format!("noise {psd:e} g^2/Hz, seed {}", a.seed);
    exp.write_parquet(
        "records",
        &mut frame(rows(records, &source))?,
        &device.params,
    )?;
    let StorageSummary {
        p_dc_w: p_dc,
        p_drive_w: p_drive,
        efficiency: eff,
        vdc_v: vdc,
    } = StorageSummary::of(records);
    exp.number("p_dc_w", p_dc.mean);
    exp.number("p_dc_ci95_w", p_dc.ci95);
    exp.number("p_drive_w", p_drive.mean);
    exp.number("efficiency", eff.mean);
    exp.number("efficiency_ci95", eff.ci95);
    exp.number("vdc_v", vdc.mean);
    let md =
        format!(
        "Random vibration of `{}` ({} set; {}; `{}` interface): {} records of band-limited white \
         noise ({} g^2/Hz two-sided, {} Hz band, sampled at {} Hz), {} s each after a pre-roll \
         of {} s from rest (the longer of five ring-up times and five storage time constants), \
         seed {}; means with 95 % intervals over the records (Student t).\n\n\
         - DC power: {} +- {} uW\n\
         - the drive's power: {} +- {} uW\n\
         - efficiency (DC power over the drive's power): {} +- {}\n\
         - mean storage voltage: {} +- {} V\n\
         - energy ledger: largest relative residual {}\n\
         - steps: {} sample intervals propagated exactly, of {} in all (the rest by \
         Dormand-Prince with its events located)\n",
        loaded.file,
        device.params,
        describe(device),
        device.interface.key(),
        records.len(),
        psd,
        fmt_sig(spec.noise.bandwidth_hz, 4),
        fmt_sig(spec.noise.sample_rate_hz, 4),
        a.duration_s,
        fmt_sig(spec.transient_s, 4),
        a.seed,
        fmt_sig(p_dc.mean * 1e6, 4),
        fmt_sig(p_dc.ci95 * 1e6, 2),
        fmt_sig(p_drive.mean * 1e6, 4),
        fmt_sig(p_drive.ci95 * 1e6, 2),
        fmt_sig(eff.mean, 3),
        fmt_sig(eff.ci95, 2),
        fmt_sig(vdc.mean, 4),
        fmt_sig(vdc.ci95, 2),
        largest_residual(records),
        records
            .iter()
            .map(|r| r.summary.exponential_steps)
            .sum::<u64>(),
        records.iter().map(|r| r.summary.stats.accepted).sum::<u64>(),
    ) + &crate::merit::noise_merits(
            &mut exp,
            device,
            p_dc.mean,
            psd,
            spec.noise.mean_square_g2(),
        );
    exp.write_numbers_md(&md)?;
    print!("{md}");
    exp.finish()
}

/// Writes the report of the record `r` of the sampled drive `m` (read from `file`).
pub fn measured(
    a: &RandomArgs,
    mut exp: Experiment,
    loaded: &LoadedDevice,
    device: &Device,
    mut m: MeasuredDrive,
    file: &str,
    r: StorageRecord,
) -> Result<()> {
    m.times.lap("integrating");
    exp.write_parquet(
        "records",
        &mut frame(rows(
            std::slice::from_ref(&r),
            &format!("measured record {file}"),
        ))?,
        &device.params,
    )?;
    exp.number("p_dc_w", r.p_dc_w);
    exp.number("p_drive_w", r.p_drive_w);
    exp.number("efficiency", r.efficiency());
    exp.number("vdc_v", r.vdc_v);
    let md = format!(
        "Measured drive on `{}` ({} set; {}; `{}` interface): record `{file}` ({} samples at {} \
         Hz, {} s), resampled to {} Hz; the first {} s discarded (the longer of five ring-up \
         times and five storage time constants).\n\n\
         - DC power: {} uW; the drive's power: {} uW; efficiency {}\n\
         - mean storage voltage: {} V\n\
         - energy ledger: relative residual {}\n\
         - steps: {} sample intervals propagated exactly, of {} in all (the rest by \
         Dormand-Prince with its events located)\n",
        loaded.file,
        device.params,
        describe(device),
        device.interface.key(),
        m.rec.accel_si.len(),
        fmt_sig(m.rec.sample_rate_hz, 6),
        fmt_sig(m.rec.duration_s(), 4),
        m.fs,
        fmt_sig(m.preroll_s, 4),
        fmt_sig(r.p_dc_w * 1e6, 4),
        fmt_sig(r.p_drive_w * 1e6, 4),
        fmt_sig(r.efficiency(), 3),
        fmt_sig(r.vdc_v, 4),
        largest_residual(std::slice::from_ref(&r)),
        r.summary.exponential_steps,
        r.summary.stats.accepted,
    );
    let md = md
        + &crate::merit::drive_merits(
            &mut exp,
            a,
            device,
            r.p_dc_w,
            r.summary.accel_mean_square_si.sqrt() / endstop::G,
        );
    exp.write_numbers_md(&md)?;
    print!("{md}");
    m.times.lap("output");
    m.times.report("endstop-random", &mut exp);
    exp.finish()
}

/// The largest relative residual of the records' energy ledgers, for the text.
fn largest_residual(records: &[StorageRecord]) -> String {
    format!(
        "{:.1e}",
        records
            .iter()
            .map(|r| r.ledger.relative_residual().abs())
            .fold(0.0, f64::max)
    )
}
