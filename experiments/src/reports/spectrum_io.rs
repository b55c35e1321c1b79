//! `endstop fit --spectrum PSD.csv:S[:N]`: the I/O of fitting a device to a measured output
//! spectrum under random vibration ([`endstop::fit::spectrum`]).
//!
//! The CSV has a header `freq_hz,psd_w_per_hz` (the output power PSD of both loads, W/Hz) and
//! one row per bin; `S` is the stated two-sided acceleration PSD of the drive (g²/Hz) and `N`
//! (default 1) how many 10 s records the measured PSD averages. Writes the estimates with their
//! 95 % intervals (`summary.json`, `spectrum_fit.parquet`), the design's features
//! (`spectrum_design.parquet`), the fitted device (`fitted.toml`, the maximum-posterior values)
//! and a plot of the measured spectrum beside the model's at the fit. Nothing is written unless
//! the whole fit succeeds.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use endstop::device::ParamRange;
use endstop::fit::spectrum::{
    build_emulator, MeasuredSpectrum, SpectrumEstimate, SpectrumSettings, FEATURES,
};
use endstop::fit::ACCEL_SCALE_PATH;
use endstop::progress::Silent;
use endstop::study::ensemble::{run_ensemble, EnsembleSpec};

use crate::io::frame::frame;
use crate::io::plot::{LinePlot, Series, Style, PALETTE};
use crate::reports::fit_csv::parse_free;
use crate::{fmt_sig, load_device_file, row, write_atomic, Experiment};

/// A `--spectrum` argument: the file, the stated level and the measured record count.
pub fn parse_spec(s: &str) -> Result<(PathBuf, f64, usize)> {
    let mut parts = s.rsplitn(3, ':').collect::<Vec<_>>();
    parts.reverse();
    let bad = || {
        anyhow::anyhow!(
            "--spectrum {s:?}: expected PSD.csv:S or PSD.csv:S:N (S the stated acceleration PSD \
             in g²/Hz, N the records the measured PSD averages)"
        )
    };
    // `PSD.csv:S` splits into two parts, `PSD.csv:S:N` into three (a path may hold colons
    // only before the last two).
    let (path, level, records) = match parts.as_slice() {
        [p, a, b] if a.parse::<f64>().is_ok() => (p.to_string(), *a, *b),
        [p, a, b] => (format!("{p}:{a}"), *b, "1"),
        [p, a] => (p.to_string(), *a, "1"),
        _ => return Err(bad()),
    };
    let level: f64 = level.parse().map_err(|_| bad())?;
    let records: usize = records.parse().map_err(|_| bad())?;
    if level.is_nan() || level <= 0.0 || level.is_infinite() || records == 0 {
        return Err(bad());
    }
    Ok((PathBuf::from(path), level, records))
}

/// Reads a measured spectrum CSV (header `freq_hz,psd_w_per_hz`).
pub fn read_spectrum(path: &Path, level: f64, records: usize) -> Result<MeasuredSpectrum> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read measured spectrum {}", path.display()))?;
    let mut lines = text
        .lines()
        .filter(|l| !l.trim().is_empty() && !l.starts_with('#'));
    let header: Vec<&str> = lines
        .next()
        .map(|h| h.split(',').map(str::trim).collect())
        .unwrap_or_default();
    if header != ["freq_hz", "psd_w_per_hz"] {
        anyhow::bail!(
            "{}: the header must be `freq_hz,psd_w_per_hz` (got {header:?})",
            path.display()
        );
    }
    let (mut f, mut s) = (Vec::new(), Vec::new());
    for (i, l) in lines.enumerate() {
        let cells: Vec<&str> = l.split(',').map(str::trim).collect();
        let num = |c: &str| -> Result<f64> {
            c.parse().with_context(|| {
                format!("{}: row {}: {c:?} is not a number", path.display(), i + 1)
            })
        };
        if cells.len() != 2 {
            anyhow::bail!(
                "{}: row {} has {} cells, not 2",
                path.display(),
                i + 1,
                cells.len()
            );
        }
        f.push(num(cells[0])?);
        s.push(num(cells[1])?);
    }
    let m = MeasuredSpectrum {
        freq_hz: f,
        psd_w_per_hz: s,
        accel_psd_g2_per_hz: level,
        records,
    };
    m.validate()
        .with_context(|| format!("measured spectrum {}", path.display()))?;
    Ok(m)
}

/// Runs `endstop fit --spectrum` (one spectrum; its free parameters from `--free`).
pub fn run(device: &Path, spectrum: &str, free: &[String], out: Option<PathBuf>) -> Result<()> {
    let loaded = load_device_file(device)?;
    let free: Vec<ParamRange> = free
        .iter()
        .map(|s| parse_free(s))
        .collect::<Result<_, _>>()?;
    let (path, level, records) = parse_spec(spectrum)?;
    let measured = read_spectrum(&path, level, records)?;
    let settings = SpectrumSettings::default();
    let out = out.unwrap_or_else(|| crate::results_root().join("endstop-fit-spectrum"));
    let out = if out.is_absolute() {
        out
    } else {
        std::env::current_dir().unwrap_or_default().join(out)
    };
    let n = settings.per_param * free.len();
    let em = crate::with_progress(n, "spectrum design", |tick| {
        build_emulator(
            &loaded.device,
            &free,
            level,
            measured.band(),
            settings,
            tick,
        )
    })?;
    let est = em.fit(&measured)?;
    let mut exp = Experiment::start_in("endstop-fit-spectrum", out);
    exp.uses(&loaded, &loaded.device.params);
    write_outputs(&mut exp, &loaded.device, &em, &est, &measured, &path)?;
    exp.finish()
}

fn write_outputs(
    exp: &mut Experiment,
    base: &endstop::device::Device,
    em: &endstop::fit::spectrum::SpectrumEmulator,
    est: &SpectrumEstimate,
    measured: &MeasuredSpectrum,
    path: &Path,
) -> Result<()> {
    let mut rows = Vec::new();
    for p in &est.params {
        exp.number(&format!("{}_mean", p.path), p.mean);
        exp.number(&format!("{}_best", p.path), p.best);
        exp.number(&format!("{}_lo95", p.path), p.interval.0);
        exp.number(&format!("{}_hi95", p.path), p.interval.1);
        rows.push(row![
            "parameter" => p.path.as_str(),
            "mean" => p.mean,
            "best" => p.best,
            "lo95" => p.interval.0,
            "hi95" => p.interval.1,
        ]);
    }
    for (k, name) in FEATURES.iter().enumerate() {
        exp.number(&format!("{name}_measured"), est.measured[k]);
        exp.number(&format!("{name}_predicted"), est.predicted[k]);
        exp.number(&format!("{name}_implausibility"), est.implausibility[k]);
    }
    exp.number("effective_samples", est.effective_samples);
    exp.write_parquet("spectrum_fit", &mut frame(rows)?, "fitted")?;
    let mut design = Vec::new();
    // One row per design point and free parameter, with the point's features.
    for (k, (u, (v, var))) in em
        .design
        .iter()
        .zip(em.values.iter().zip(&em.variances))
        .enumerate()
    {
        for (f, s) in em.free.iter().zip(u) {
            design.push(row![
                "point" => k as u64,
                "parameter" => f.path.as_str(),
                "value" => f.at(*s),
                "ln_band_power" => v[0],
                "centroid_hz" => v[1],
                "spread_hz" => v[2],
                "ln_band_power_var" => var[0],
                "centroid_hz_var" => var[1],
                "spread_hz_var" => var[2],
            ]);
        }
    }
    exp.write_parquet("spectrum_design", &mut frame(design)?, "design")?;
    // The model at the maximum-posterior values, one ensemble, beside the measurement.
    let mut device = base.clone();
    let mut scale = 1.0;
    for p in &est.params {
        if p.path == ACCEL_SCALE_PATH {
            scale = p.best;
        } else {
            device = device.with_param(&p.path, p.best)?;
        }
    }
    let psd = measured.accel_psd_g2_per_hz * scale * scale;
    let mut spec = EnsembleSpec::for_device(
        &device,
        endstop::fit::spectrum::model_record(&device, psd),
        em.settings.seed,
        em.settings.records,
    );
    spec.analysis_band_hz = measured.band();
    let e = run_ensemble(&device, &spec, &Silent)?;
    let model = &e.mean_spectrum.total;
    exp.write_plot(&LinePlot::new(
        "Measured output spectrum and the model at the fit",
        "frequency (Hz)",
        "output power PSD (W/Hz)",
        vec![
            Series::new(
                "measured",
                measured
                    .freq_hz
                    .iter()
                    .copied()
                    .zip(measured.psd_w_per_hz.iter().copied())
                    .collect(),
                PALETTE[0],
                Style::Points,
            ),
            Series::new(
                &format!("model at the fit ({} records)", em.settings.records),
                model
                    .freq_hz
                    .iter()
                    .copied()
                    .zip(model.density.iter().copied())
                    .collect(),
                PALETTE[3],
                Style::Line,
            ),
        ],
    ))?;
    let mut toml = format!(
        "# Fitted by `endstop fit --spectrum` (src/fit/spectrum.rs) to {} at {} g²/Hz stated: \
         the maximum-posterior values.\n",
        path.display(),
        measured.accel_psd_g2_per_hz
    );
    for p in &est.params {
        toml.push_str(&format!(
            "# fitted {} = {:e} (posterior mean {:e}; 95 % {:e} .. {:e})\n",
            p.path, p.best, p.mean, p.interval.0, p.interval.1
        ));
    }
    toml.push_str(&device.to_toml_string());
    endstop::device::Device::from_toml_str(&toml, "fitted.toml")?;
    write_atomic(&exp.dir.join("fitted.toml"), toml.as_bytes())?;
    let mut md = String::from(
        "Fit of a measured output spectrum (`endstop fit --spectrum`).\n\n| parameter | \
         posterior mean | maximum posterior | 95 % interval |\n|---|---|---|---|\n",
    );
    for p in &est.params {
        md.push_str(&format!(
            "| `{}` | {} | {} | {} .. {} |\n",
            p.path,
            fmt_sig(p.mean, 4),
            fmt_sig(p.best, 4),
            fmt_sig(p.interval.0, 4),
            fmt_sig(p.interval.1, 4)
        ));
    }
    md.push_str(
        "\n| feature | measured | emulated at the fit | implausibility |\n|---|---|---|---|\n",
    );
    for (k, name) in FEATURES.iter().enumerate() {
        md.push_str(&format!(
            "| `{name}` | {} | {} | {} |\n",
            fmt_sig(est.measured[k], 5),
            fmt_sig(est.predicted[k], 5),
            fmt_sig(est.implausibility[k], 3)
        ));
    }
    exp.write_numbers_md(&md)?;
    Ok(())
}
