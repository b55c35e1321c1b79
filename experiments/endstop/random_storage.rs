//! The report of `endstop random` on a model with a storage (an interface circuit,
//! `[interface]`: a diode bridge, SSHI, SECE into a storage capacitor): for an ensemble of
//! band-limited white-noise records, or one measured acceleration record, each run from rest
//! with the pre-roll discarded, the DC power, the drive's power, their ratio (the efficiency),
//! the mean storage voltage and the energy ledger's closure of each record. The records are the
//! one record engine's (`endstop::study::record`): the affine modes of the circuit are
//! propagated exactly between switchings, the rest by Dormand-Prince with its events.
//!
//! The pre-roll ([`endstop::study::record::transient_s`]) covers the storage as well as the
//! mechanics: the storage charges towards its mean with the time constant of its DC load,
//! `R C_s`, often longer than the mass's ring-up; an open DC load has no steady mean under
//! noise and is refused before anything is written.

use anyhow::{bail, Result};
use endstop::device::Device;
use endstop::paper::setups::paper_record;
use endstop::study::record::{
    check_steady_mean, simulate_drive, storage_ensemble, SampledDrive, Scheme, StorageRecord,
    StorageSummary, DEFAULT_RTOL,
};
use endstop_experiments::fmt_sig;
use endstop_experiments::io::frame::frame;
use endstop_experiments::row;

use crate::random_args::{read_measured, MeasuredDrive, RandomArgs};
use crate::shared::{describe, start};

/// Runs `endstop random` on `device` (as loaded from `a.device`), whose model has a storage.
pub fn random(a: &RandomArgs, device: &Device) -> Result<()> {
    check_steady_mean(device)?;
    match (&a.accel_file, a.sine_g, a.psd) {
        (Some(path), _, _) => {
            let m = read_measured(a, device, Some(path))?;
            measured(a, m, &path.display().to_string())
        }
        (None, Some(_), _) => {
            let m = read_measured(a, device, None)?;
            let source = m.rec.source_name.clone();
            measured(a, m, &source)
        }
        (None, None, Some(psd)) => noise(a, psd),
        (None, None, None) => {
            bail!("give --psd (white noise), --sine-g (a sine) or --accel-file (a measured record)")
        }
    }
}

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

fn noise(a: &RandomArgs, psd: f64) -> Result<()> {
    a.check_noise(psd)?;
    let (mut exp, loaded, device) = start("endstop-random", &a.device, a.bias_v, a.out.clone())?;
    exp.seed = Some(a.seed);
    let mut spec = paper_record(&device, psd);
    spec.noise.duration_s = a.duration_s;
    eprintln!(
        "[endstop-random] {} records of {} s behind the `{}` interface",
        a.records,
        a.duration_s,
        device.interface.key()
    );
    let records = storage_ensemble(&device, &spec, a.seed, a.records as u64)?;
    let source = format!("noise {psd:e} g^2/Hz, seed {}", a.seed);
    exp.write_parquet(
        "records",
        &mut frame(rows(&records, &source))?,
        &device.params,
    )?;
    let StorageSummary {
        p_dc_w: p_dc,
        p_drive_w: p_drive,
        efficiency: eff,
        vdc_v: vdc,
    } = StorageSummary::of(&records);
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
        describe(&device),
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
        largest_residual(&records),
        records
            .iter()
            .map(|r| r.summary.exponential_steps)
            .sum::<u64>(),
        records.iter().map(|r| r.summary.stats.accepted).sum::<u64>(),
    ) + &crate::merit::noise_merits(
            &mut exp,
            &device,
            p_dc.mean,
            psd,
            spec.noise.mean_square_g2(),
        );
    exp.write_numbers_md(&md)?;
    print!("{md}");
    exp.finish()
}

fn measured(a: &RandomArgs, mut m: MeasuredDrive, file: &str) -> Result<()> {
    let (mut exp, loaded, device) = start("endstop-random", &a.device, a.bias_v, a.out.clone())?;
    m.times.lap("setup");
    let drive = SampledDrive {
        accel: m.accel.clone(),
        sample_rate_hz: m.fs,
        transient_samples: m.n_tr,
    };
    let record = simulate_drive(&device, &drive, DEFAULT_RTOL, Scheme::Exponential)?;
    let Some(r) = StorageRecord::of(record, 0) else {
        bail!("device `{}`: the record kept no storage books", device.name);
    };
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
        describe(&device),
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
            &device,
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
