//! `endstop fit`: the I/O of fitting a device to measured sweeps ([`endstop::fit`]): reading
//! the measured CSV files (units in the header, checked), the free parameters from the command
//! line, and writing the fitted device with its provenance, the results table, the residuals
//! and the plots. Nothing is written unless the whole fit succeeds.
//!
//! The measured files' format is in [`crate::reports::fit_csv`].

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::Parser;
use endstop::device::ParamRange;
use endstop::fit::{
    check_modelled, fit, model_curve, Direction, FitReport, FitSettings, SweepData,
    ACCEL_SCALE_PATH,
};
use polars::prelude::*;
use sha2::{Digest, Sha256};

use crate::io::legend::placed_clear;
use crate::io::plot::{LegendPos, LinePlot, Series, Style, PALETTE};
use crate::reports::fit_csv::{parse_free, parse_sweep, FitInputError};
use crate::{fmt_sig, git_commit, load_device_file, write_atomic, Experiment};

/// Arguments of `endstop fit`.
#[derive(Parser, Debug)]
pub struct FitArgs {
    /// Device file (TOML): the starting values and every fixed parameter.
    #[arg(long)]
    pub device: PathBuf,
    /// Measured up-sweep (CSV, see the `fit_csv` module docs and the book); may be repeated.
    #[arg(long)]
    pub up_sweep: Vec<PathBuf>,
    /// Measured down-sweep (CSV); may be repeated.
    #[arg(long)]
    pub down_sweep: Vec<PathBuf>,
    /// A free parameter and its range, `PATH=LO..HI` (e.g.
    /// `endstop.damping_n_s_per_m=0.1..10`); `drive.accel_scale` is a factor on every file's
    /// stated acceleration.
    #[arg(long, required = true)]
    pub free: Vec<String>,
    /// Output directory; default: data/results/endstop-fit.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// A measured output spectrum instead of sweeps, `PSD.csv:S[:N]` (see
    /// `crate::reports::spectrum_io`).
    #[arg(long)]
    pub spectrum: Option<String>,
}

fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// Runs `endstop fit`.
pub fn run(a: FitArgs) -> Result<()> {
    // A device with a part the fit does not model is refused before anything runs, for the
    // sweeps and the spectrum alike (the spectrum's model is the resistive record too).
    let loaded = load_device_file(&a.device)?;
    check_modelled(&loaded.device)?;
    if let Some(s) = &a.spectrum {
        return crate::reports::spectrum_io::run(&a.device, s, &a.free, a.out.clone());
    }
    let free: Vec<ParamRange> = a
        .free
        .iter()
        .map(|s| parse_free(s))
        .collect::<Result<_, _>>()?;
    let mut data = Vec::new();
    let mut hashes = Vec::new();
    for (files, dir) in [
        (&a.up_sweep, Direction::Up),
        (&a.down_sweep, Direction::Down),
    ] {
        for path in files {
            let bytes = std::fs::read(path)
                .with_context(|| format!("cannot read measured sweep {}", path.display()))?;
            let text = String::from_utf8_lossy(&bytes);
            let name = path.display().to_string();
            let d = parse_sweep(&text, &name, dir)?;
            hashes.push((name, sha256_hex(&bytes)));
            data.push(d);
        }
    }
    if data.is_empty() {
        anyhow::bail!("no measured data: give --up-sweep and/or --down-sweep");
    }
    let n: usize = data.iter().map(SweepData::n_values).sum();
    if n < free.len() {
        return Err(FitInputError::TooFewPoints {
            files: hashes
                .iter()
                .map(|h| h.0.clone())
                .collect::<Vec<_>>()
                .join(", "),
            n,
            p: free.len(),
        }
        .into());
    }
    for d in &data {
        d.validate()?;
    }
    endstop::fit::check_free(&loaded.device, &free)?;
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| crate::results_root().join("endstop-fit"));
    let out = if out.is_absolute() {
        out
    } else {
        std::env::current_dir().unwrap_or_default().join(out)
    };
    let mut exp = Experiment::start_in("endstop-fit", out);
    exp.uses(&loaded, &loaded.device.params);
    let report = crate::with_progress(1, "fit", |_| {
        fit(&loaded.device, &data, &free, &FitSettings::default())
    })?;
    let command: Vec<String> = std::env::args().collect();
    write_outputs(&mut exp, &report, &data, &hashes, &command.join(" "))?;
    if let Some(h) = report.headline() {
        eprintln!("[endstop-fit] {h}");
    }
    exp.finish()
}

/// The fitted device file: provenance as comments, then the device.
pub fn fitted_toml(report: &FitReport, hashes: &[(String, String)], command: &str) -> String {
    let mut s = String::new();
    if let Some(h) = report.headline() {
        s.push_str(&format!("# {h}\n"));
    }
    s.push_str("# Fitted by `endstop fit` (src/fit/mod.rs).\n");
    s.push_str(&format!(
        "# command: {command}\n# commit: {}\n",
        git_commit()
    ));
    for (f, h) in hashes {
        s.push_str(&format!("# data: {f} sha256 {h}\n"));
    }
    for p in &report.params {
        s.push_str(&format!(
            "# fitted {} = {:e} (std error {:e}; 95 % {:e} .. {:e}; chi-square per degree of \
             freedom {})\n",
            p.path,
            p.value,
            p.std_err,
            p.interval.0,
            p.interval.1,
            fmt_chi2(report.reduced_chi2)
        ));
    }
    if report.params.iter().any(|p| p.path == ACCEL_SCALE_PATH) {
        s.push_str(&format!(
            "# drive.accel_scale = {} is a property of the measurement, not of the device: it \
             is not in the file below\n",
            report.accel_scale
        ));
    }
    for w in &report.warnings {
        s.push_str(&format!("# WARNING {w}\n"));
    }
    s.push_str(&report.device.to_toml_string());
    s
}

/// The reduced chi-square for tables ("-" without degrees of freedom).
fn fmt_chi2(c: f64) -> String {
    if c.is_finite() {
        fmt_sig(c, 3)
    } else {
        "- (no degrees of freedom)".into()
    }
}

/// The results table, correlation and warnings in Markdown.
pub fn results_markdown(report: &FitReport) -> String {
    let mut md = String::new();
    if let Some(h) = report.headline() {
        md.push_str(&format!("**{h}**\n\n"));
    }
    md.push_str("| parameter | start | fitted | std error | 95 % interval | chi2/dof | range |\n|---|---|---|---|---|---|---|\n");
    for p in &report.params {
        md.push_str(&format!(
            "| `{}` | {} | {} | {} | {} .. {} | {} | {} .. {} |\n",
            p.path,
            fmt_sig(p.start, 4),
            fmt_sig(p.value, 5),
            fmt_sig(p.std_err, 3),
            fmt_sig(p.interval.0, 4),
            fmt_sig(p.interval.1, 4),
            fmt_chi2(report.reduced_chi2),
            fmt_sig(p.range.0, 3),
            fmt_sig(p.range.1, 3),
        ));
    }
    let p_value = report.chi2_p.map_or(String::new(), |p| {
        format!(" (probability of a larger chi-square {})", fmt_sig(p, 3))
    });
    md.push_str(&format!(
        "\nUncertainty: {}. Weighted SSR {} with {} degrees of freedom, chi-square per degree of \
         freedom {}{}. Model: {}; {} model evaluations ({} trial points could not be \
         evaluated), {} iterations, stop: {:?}; {} start(s) ranked by a plain stepped sweep, \
         {} refined, the reported one from {}.\n\n\
         Correlation of the estimates:\n\n|  | {} |\n|---|{}\n",
        report.uncertainty.describe(),
        fmt_sig(report.ssr, 4),
        report.dof,
        fmt_chi2(report.reduced_chi2),
        p_value,
        report.model,
        report.evaluations,
        report.failed_trials,
        report.iterations,
        report.stop,
        report.starts.len(),
        report.starts_refined(),
        report.starts[report.best_start].origin,
        report
            .params
            .iter()
            .map(|p| format!("`{}`", p.path))
            .collect::<Vec<_>>()
            .join(" | "),
        "---|".repeat(report.params.len()),
    ));
    for (p, row) in report.params.iter().zip(&report.correlation) {
        md.push_str(&format!(
            "| `{}` | {} |\n",
            p.path,
            row.iter()
                .map(|c| format!("{c:.3}"))
                .collect::<Vec<_>>()
                .join(" | ")
        ));
    }
    md.push_str(&starts_markdown(report));
    md.push_str(&format!(
        "\nSmallest over largest singular value of the column-scaled Jacobian: {:.3e} (a \
         combination is reported below {}).\n\n",
        report.singular_ratio,
        endstop::fit::SINGULAR_RATIO_WARN
    ));
    if report.warnings.is_empty() {
        md.push_str("Warnings: none.\n");
    } else {
        md.push_str("Warnings:\n\n");
        for w in &report.warnings {
            md.push_str(&format!("- {w}\n"));
        }
    }
    md
}

/// The table of the starts: each start's values, its cheap misfit, and its refinement.
fn starts_markdown(report: &FitReport) -> String {
    let names: Vec<String> = report
        .params
        .iter()
        .map(|p| format!("`{}`", p.path))
        .collect();
    let mut md = format!(
        "\nStarts (ranked by the weighted SSR of a plain stepped sweep; the best refined by \
         Levenberg-Marquardt on the branches):\n\n| start | {} | stepped-sweep SSR | \
         refined SSR | refined to | |\n|---|{}---|---|---|---|\n",
        names.join(" | "),
        "---|".repeat(names.len()),
    );
    let vals = |v: &[f64], sep: &str| {
        v.iter()
            .map(|x| fmt_sig(*x, 4))
            .collect::<Vec<_>>()
            .join(sep)
    };
    for (i, s) in report.starts.iter().enumerate() {
        let (refined_ssr, to) = match &s.refined {
            Some(r) => (
                format!(
                    "{}{}",
                    fmt_sig(r.ssr, 4),
                    if r.settled { "" } else { " (not settled)" }
                ),
                vals(&r.values, ", "),
            ),
            None => ("-".into(), "-".into()),
        };
        let design = if s.design_ssr.is_nan() {
            "-".to_string()
        } else if s.design_cut {
            format!("> {} (sweep stopped)", fmt_sig(s.design_ssr, 4))
        } else {
            fmt_sig(s.design_ssr, 4)
        };
        let reported = if i == report.best_start {
            "reported"
        } else {
            ""
        };
        md.push_str(&format!(
            "| {} | {} | {design} | {refined_ssr} | {to} | {reported} |\n",
            s.origin,
            vals(&s.values, " | "),
        ));
    }
    md
}

fn write_outputs(
    exp: &mut Experiment,
    report: &FitReport,
    data: &[SweepData],
    hashes: &[(String, String)],
    command: &str,
) -> Result<()> {
    let r = &report.residuals;
    let mut df = df!(
        "dataset" => r.iter().map(|x| x.dataset.clone()).collect::<Vec<_>>(),
        "what" => r.iter().map(|x| x.what.clone()).collect::<Vec<_>>(),
        "freq_hz" => r.iter().map(|x| x.freq_hz).collect::<Vec<_>>(),
        "measured" => r.iter().map(|x| x.measured).collect::<Vec<_>>(),
        "model" => r.iter().map(|x| x.model).collect::<Vec<_>>(),
        "sigma" => r.iter().map(|x| x.sigma).collect::<Vec<_>>(),
    )?;
    exp.write_parquet("residuals", &mut df, "fitted")?;
    for p in &report.params {
        exp.number(&format!("{}_fitted", p.path), p.value);
        exp.number(&format!("{}_std_err", p.path), p.std_err);
        exp.number(&format!("{}_lo95", p.path), p.interval.0);
        exp.number(&format!("{}_hi95", p.path), p.interval.1);
    }
    exp.number("ssr", report.ssr);
    exp.number("reduced_chi2", report.reduced_chi2);
    exp.number("starts_tried", report.starts.len() as f64);
    exp.number("starts_refined", report.starts_refined() as f64);
    exp.number("singular_ratio", report.singular_ratio);
    exp.number("warnings", report.warnings.len() as f64);

    // Data against the fitted model's sweep over each data set's grid (measured features as
    // dashed vertical lines, the model's as solid ones), and the normalised residuals.
    let mut series = Vec::new();
    let mut resid = Vec::new();
    let (mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut feature_lines = Vec::new();
    for (k, d) in data.iter().enumerate() {
        let c = PALETTE[k % PALETTE.len()];
        let name = Path::new(&d.label)
            .file_name()
            .map_or(d.label.clone(), |f| f.to_string_lossy().into_owned());
        let m = model_curve(&report.device, report.accel_scale, d)?;
        for &(_, v) in &m.curve {
            y0 = y0.min(v);
            y1 = y1.max(v);
        }
        series.push(Series::new(
            &format!("{name}: fitted model ({}-sweep)", d.direction.label()),
            m.curve.clone(),
            c,
            Style::Line,
        ));
        let rows: Vec<_> = r
            .iter()
            .filter(|x| x.dataset == d.label && x.what == "point")
            .collect();
        if !rows.is_empty() {
            series.push(Series::new(
                &format!("{name}: measured"),
                rows.iter().map(|x| (x.freq_hz, x.measured)).collect(),
                c,
                Style::Points,
            ));
        }
        // The fitted model's features: those of the residual rows (the located grazing and
        // fold), in the data set's order of features.
        let model_features: Vec<f64> = r
            .iter()
            .filter(|x| x.dataset == d.label && x.what != "point")
            .map(|x| x.model)
            .collect();
        for (f, &model_f) in d.features.iter().zip(&model_features) {
            feature_lines.push((f.freq_hz, Some(model_f), c, f.kind.label(), name.clone()));
        }
        resid.push(Series::new(
            &name,
            r.iter()
                .filter(|x| x.dataset == d.label)
                .map(|x| (x.freq_hz, (x.model - x.measured) / x.sigma))
                .collect(),
            c,
            Style::Points,
        ));
    }
    for (f, model_f, c, what, name) in feature_lines {
        let measured = Series::new(
            &format!("{name}: measured {what}"),
            vec![(f, y0), (f, y1)],
            c,
            Style::Dashed,
        );
        // The fitted model's feature in the next colour, so that it shows beside the measured
        // one it lies on when the fit is close.
        if let Some(g) = model_f {
            let next = PALETTE
                .iter()
                .position(|p| *p == c)
                .map_or(c, |i| PALETTE[(i + 1) % PALETTE.len()]);
            series.push(Series::new(
                &format!("{name}: fitted model's {what}"),
                vec![(g, y0), (g, y1)],
                next,
                Style::Line,
            ));
        }
        // Drawn after the model's, so that a dashed line on top of a solid one shows.
        series.push(measured);
    }
    // The axis names the quantity with its unit (the column name in parentheses).
    let q = match data[0].quantity {
        endstop::fit::data::Quantity::V1RmsV => "RMS voltage of load 1 [V] (v1_rms_v)",
        endstop::fit::data::Quantity::PTotalW => "power of the loads [W] (p_total_w)",
    };
    exp.write_plot(&placed_clear(
        LinePlot::new(
            "Measured data and the fitted model",
            "frequency [Hz]",
            q,
            series,
        )
        .legend(LegendPos::UpperLeft),
    ))?;
    exp.write_extra_plot(
        "endstop-fit-residuals",
        &LinePlot::new(
            "Residuals (model - measured) / sigma, points and features",
            "frequency [Hz]",
            "normalised residual (model - measured) / sigma",
            resid,
        ),
    )?;
    let fitted = fitted_toml(report, hashes, command);
    // The written device must load again: validate before writing.
    endstop::device::Device::from_toml_str(&fitted, "fitted.toml")?;
    write_atomic(&exp.dir.join("fitted.toml"), fitted.as_bytes())?;
    let mut md = String::from("Fit of measured sweeps (`endstop fit`).\n\n");
    md.push_str(&results_markdown(report));
    exp.write_numbers_md(&md)?;
    Ok(())
}
