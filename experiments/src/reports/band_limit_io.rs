//! The recorded band-limit study of the validation chapter (`endstop::validation::band_limit`):
//! running it once and recording it (`cargo run --release --bin validation -- --band-study`),
//! reading the recording back, and the chapter's table of it.

use std::time::Instant;

use anyhow::{Context, Result};
use endstop::device::Device;
use endstop::validation::band_limit;

use crate::io::md::Table;
use crate::write_atomic;

/// Where the band-limit study is recorded.
pub const BAND_DIR: &str = "data/recorded/band-limit";

/// Runs the band-limit study (`endstop::validation::band_limit`) and records it under
/// [`BAND_DIR`]: every record as CSV, and the run's settings and cost as `run.json` (minutes
/// of processor time); the chapter reads the recording.
pub fn record_study() -> Result<()> {
    let dir = crate::root().join(BAND_DIR);
    let (started, cpu0) = (Instant::now(), crate::cpu_time_s());
    let mut records = Vec::new();
    let mut cells = Vec::new();
    for (i, case) in band_limit::DEVICES.iter().enumerate() {
        let device = case.device(&load_device(case.file)?)?;
        for b in band_limit::BANDWIDTHS_HZ {
            let (t, c) = (Instant::now(), crate::cpu_time_s());
            let rs = band_limit::run_cell(i, &device, b, band_limit::RECORDS_PER_CELL)
                .with_context(|| format!("{} at B = {b} Hz", case.label))?;
            let cpu = crate::cpu_time_s().zip(c).map(|(a, b)| a - b);
            eprintln!(
                "[band study] {} at B = {b} Hz: {} records in {:.0} s ({:.0} s of processor \
                 time)",
                case.label,
                rs.len(),
                t.elapsed().as_secs_f64(),
                cpu.unwrap_or(f64::NAN)
            );
            cells.push(serde_json::json!({
                "device": case.label,
                "bandwidth_hz": b,
                "wall_s": t.elapsed().as_secs_f64(),
                "cpu_time_s": cpu,
            }));
            records.extend(rs);
            // Written after every cell, so that an interrupted study keeps what it ran.
            write_atomic(
                &dir.join("records.csv"),
                band_limit::records_csv(&records)?.as_bytes(),
            )?;
        }
    }
    let run = serde_json::json!({
        "command": "cargo run --release --bin validation -- --band-study",
        "commit": crate::git_commit(),
        "endstop_version": env!("CARGO_PKG_VERSION"),
        "seed": band_limit::SEED,
        "psd_g2_per_hz": band_limit::PSD_G2_PER_HZ,
        "record_s": band_limit::RECORD_S,
        "records_per_cell": band_limit::RECORDS_PER_CELL,
        "samples_per_band": band_limit::SAMPLES_PER_BAND,
        "bandwidths_hz": band_limit::BANDWIDTHS_HZ,
        "devices": band_limit::DEVICES.iter().map(|d| serde_json::json!({
            "label": d.label,
            "file": format!("data/validation/{}.toml", d.file),
            "changes": d.changes,
        })).collect::<Vec<_>>(),
        "threads": rayon::current_num_threads(),
        "wall_s": started.elapsed().as_secs_f64(),
        "cpu_time_s": crate::cpu_time_s().zip(cpu0).map(|(a, b)| a - b),
        "cells": cells,
    });
    write_atomic(
        &dir.join("run.json"),
        serde_json::to_string_pretty(&run)?.as_bytes(),
    )?;
    Ok(())
}

/// A validation device, parsed (for the band study, which writes no results).
fn load_device(name: &str) -> Result<Device> {
    Ok(crate::load_device(&format!("validation/{name}"))?.device)
}

/// The recorded band-limit study's cells (`data/recorded/band-limit/records.csv`), each with
/// every record the study states.
pub fn recorded_cells() -> Result<Vec<band_limit::BandCell>> {
    let path = crate::root().join(BAND_DIR).join("records.csv");
    let text = std::fs::read_to_string(&path)
        .with_context(|| format!("cannot read the recorded study {}", path.display()))?;
    let records = band_limit::parse_records(&text)?;
    let mut cells = Vec::new();
    for (i, case) in band_limit::DEVICES.iter().enumerate() {
        // The devices' files are the chapter's, already among its parameter files.
        let device = case.device(&load_device(case.file)?)?;
        for b in band_limit::BANDWIDTHS_HZ {
            cells.push(band_limit::BandCell::of(
                i,
                &device,
                b,
                &records,
                band_limit::RECORDS_PER_CELL,
            )?);
        }
    }
    Ok(cells)
}

/// Where the independent simulation of the study's rigid-stop cells is stored.
pub const INDEPENDENT_CSV: &str = "data/references/rigid_band_limit/cells.csv";

/// The independent simulation's cells ([`band_limit::parse_independent`]).
pub fn independent_cells() -> Result<Vec<band_limit::IndependentCell>> {
    let path = crate::root().join(INDEPENDENT_CSV);
    let text = std::fs::read_to_string(&path)
        .with_context(|| format!("cannot read the independent simulation {}", path.display()))?;
    Ok(band_limit::parse_independent(&text)?)
}

/// The band-limit study's table and verdict.
pub fn table_md(cells: &[band_limit::BandCell]) -> Result<String> {
    let verdict = band_limit::BandVerdict::of(cells)?;
    let mut t = Table::new([
        "device",
        "B (kHz)",
        "impacts per s",
        "time on a stop",
        "shortfall (95 %)",
        "estimate",
        "of which the damper",
        "measured / estimated impact part (95 %)",
        "z",
        "estimate inside the interval",
    ]);
    for c in cells {
        t.row([
            band_limit::DEVICES[c.device].label.to_string(),
            format!("{}", c.bandwidth_hz / 1e3),
            format!("{:.1}", c.impacts_per_s),
            format!("{:.2} %", 100.0 * c.contact_fraction),
            format!(
                "{:.3} % +- {:.3} %",
                100.0 * c.shortfall.mean,
                100.0 * c.shortfall.ci95
            ),
            format!("{:.3} %", 100.0 * c.estimate),
            format!("{:.3} %", 100.0 * c.damper_part),
            match c.impact_ratio() {
                (r, ci) if r.is_finite() => format!("{r:.2} +- {ci:.2}"),
                _ => "-".into(),
            },
            format!("{:+.2}", c.z()),
            if c.estimate_inside() { "yes" } else { "**no**" }.to_string(),
        ]);
    }
    let cases: Vec<String> = band_limit::DEVICES
        .iter()
        .map(|d| format!("{} ({})", d.label, d.why))
        .collect();
    Ok(format!(
        "The recorded study (`{BAND_DIR}/`, made by `cargo run --release --bin validation -- \
         --band-study`, its cost and commit in `run.json` there): {} records of {} s per cell \
         (seed {}), at {} g^2/Hz, each band sampled at {} times its width. Devices: {}.\n\n{}\n\
         **chi-squared = {:.1} over {} cells against {:.1} at {:.0} %: the estimate is {} the \
         study (p = {:.2e}).** The rigid stops' drive row of the table above is therefore {}.\n",
        band_limit::RECORDS_PER_CELL,
        band_limit::RECORD_S,
        band_limit::SEED,
        band_limit::PSD_G2_PER_HZ,
        band_limit::SAMPLES_PER_BAND,
        cases.join("; "),
        t.render(),
        verdict.chi2,
        verdict.dof,
        verdict.bound,
        100.0 * band_limit::CONFIDENCE,
        if verdict.consistent() {
            "consistent with"
        } else {
            "**not** consistent with"
        },
        verdict.p_value,
        if verdict.consistent() {
            "judged with the estimate"
        } else {
            "shown without a verdict, with the limit this study finds stated in the row"
        },
    ))
}
