//! `endstop fit`: the I/O of fitting a device to measured sweeps ([`endstop::fit`]): reading
//! the measured CSV files (units in the header, checked), the free parameters from the command
//! line, and writing the fitted device with its provenance, the results table, the residuals
//! and the plots. Nothing is written unless the whole fit succeeds.
//!
//! # The measured-sweep file
//! ```text
//! # accel_rms_g = 0.3          (required: the stated RMS base acceleration, g)
//! # jump_hz = 723.4            (optional: the measured jump, with jump_sigma_hz)
//! # jump_sigma_hz = 1
//! # onset_hz = 666             (optional, up-sweeps: the impact onset, with onset_sigma_hz)
//! # onset_sigma_hz = 1
//! # grid_from_hz = 900         (optional: the simulated sweep's grid, needed without points)
//! # grid_to_hz = 2000
//! # grid_step_hz = 5
//! freq_hz,v1_rms_v,sigma_v     (or p_total_w with sigma_w; the sigma column is optional)
//! 600,0.1234,0.0025
//! ```
//! Other `#` lines are free comments. The CSV is parsed here rather than by a CSV crate because the file is a handful of numeric
//! columns plus `# key = value` metadata, and every error must name the file's line: polars'
//! reader (the workspace's frame library) reports neither, and a new dependency for it would
//! not remove the line bookkeeping.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::Parser;
use endstop::fit::{
    fit, model_sweep, Direction, Feature, FeatureKind, FitReport, FreeParam, LmSettings, Point,
    Quantity, SweepData, ACCEL_SCALE_PATH,
};
use polars::prelude::*;
use sha2::{Digest, Sha256};
use thiserror::Error;

use crate::plot::{LegendPos, LinePlot, Series, Style, PALETTE};
use crate::{fmt_sig, git_commit, load_device_file, write_atomic, Experiment};

/// Arguments of `endstop fit`.
#[derive(Parser, Debug)]
pub struct FitArgs {
    /// Device file (TOML): the starting values and every fixed parameter.
    #[arg(long)]
    pub device: PathBuf,
    /// Measured up-sweep (CSV, see the module docs); may be repeated.
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
}

/// A measured file or option that cannot be used.
#[derive(Debug, Error, PartialEq)]
pub enum FitInputError {
    /// The file has no header line.
    #[error("{file}: no header line (expected e.g. `freq_hz,v1_rms_v[,sigma_v]`)")]
    NoHeader {
        /// The file.
        file: String,
    },
    /// A column the reader does not know (a wrong unit, a typo).
    #[error("{file}:{line}: unknown column `{column}`; known columns: freq_hz, v1_rms_v, p_total_w, sigma_v, sigma_w")]
    UnknownColumn {
        /// The file.
        file: String,
        /// 1-based line.
        line: usize,
        /// The column as written.
        column: String,
    },
    /// A required column is absent.
    #[error("{file}:{line}: missing column: {what}")]
    MissingColumn {
        /// The file.
        file: String,
        /// 1-based line of the header.
        line: usize,
        /// What is missing.
        what: String,
    },
    /// A `# key = value` line with an unknown key or a value that is not a number.
    #[error("{file}:{line}: {message}")]
    Metadata {
        /// The file.
        file: String,
        /// 1-based line.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A row with the wrong number of fields, a field that is not a number, NaN or infinity.
    #[error("{file}:{line}: {message}")]
    Row {
        /// The file.
        file: String,
        /// 1-based line.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// Frequencies that neither rise nor fall strictly.
    #[error("{file}:{line}: frequency {freq_hz} Hz breaks the order of the previous rows (frequencies must rise or fall strictly)")]
    NotMonotonic {
        /// The file.
        file: String,
        /// 1-based line.
        line: usize,
        /// The frequency.
        freq_hz: f64,
    },
    /// Fewer measured values than free parameters.
    #[error(
        "{files}: {n} measured values (points and features) cannot determine {p} free parameters"
    )]
    TooFewPoints {
        /// The files.
        files: String,
        /// Measured values.
        n: usize,
        /// Free parameters.
        p: usize,
    },
    /// A `--free` option that is not `PATH=LO..HI`.
    #[error("--free `{given}`: expected PATH=LO..HI with numbers LO < HI, e.g. stops.both.gap_m=4e-6..8e-6")]
    FreeSyntax {
        /// The option as given.
        given: String,
    },
}

/// Parses `PATH=LO..HI`.
pub fn parse_free(s: &str) -> Result<FreeParam, FitInputError> {
    let err = || FitInputError::FreeSyntax { given: s.into() };
    let (path, range) = s.split_once('=').ok_or_else(err)?;
    let (lo, hi) = range.split_once("..").ok_or_else(err)?;
    let lo: f64 = lo.trim().parse().map_err(|_| err())?;
    let hi: f64 = hi.trim().parse().map_err(|_| err())?;
    if path.trim().is_empty() {
        return Err(err());
    }
    Ok(FreeParam {
        path: path.trim().into(),
        lo,
        hi,
    })
}

const KEYS: [&str; 8] = [
    "accel_rms_g",
    "jump_hz",
    "jump_sigma_hz",
    "onset_hz",
    "onset_sigma_hz",
    "grid_from_hz",
    "grid_to_hz",
    "grid_step_hz",
];

/// Parses a measured-sweep file's text (see the module docs); `file` names it in errors.
pub fn parse_sweep(
    text: &str,
    file: &str,
    direction: Direction,
) -> Result<SweepData, FitInputError> {
    let mut meta: BTreeMap<&str, (f64, usize)> = BTreeMap::new();
    let mut header: Option<(usize, usize, Quantity, Option<usize>, usize)> = None;
    let mut rows: Vec<(usize, Point)> = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let l = raw.trim();
        if l.is_empty() {
            continue;
        }
        if let Some(c) = l.strip_prefix('#') {
            // A `# key = value` line has a single word before the `=`; other comments are
            // free text.
            let kv = c.split_once('=').filter(|(k, _)| {
                let k = k.trim();
                !k.is_empty() && k.chars().all(|ch| ch.is_ascii_alphanumeric() || ch == '_')
            });
            if let Some((k, v)) = kv {
                let k = k.trim();
                let Some(key) = KEYS.iter().find(|&&x| x == k) else {
                    return Err(FitInputError::Metadata {
                        file: file.into(),
                        line,
                        message: format!("unknown key `{k}`; known keys: {}", KEYS.join(", ")),
                    });
                };
                let v: f64 = v
                    .trim()
                    .parse()
                    .ok()
                    .filter(|x: &f64| x.is_finite())
                    .ok_or_else(|| FitInputError::Metadata {
                        file: file.into(),
                        line,
                        message: format!("`{k}` must be a finite number, got `{}`", v.trim()),
                    })?;
                meta.insert(key, (v, line));
            }
            continue;
        }
        let fields: Vec<&str> = l.split(',').map(str::trim).collect();
        match header {
            None => {
                let mut freq = None;
                let mut value = None;
                let mut sigma = None;
                for (j, c) in fields.iter().enumerate() {
                    match *c {
                        "freq_hz" => freq = Some(j),
                        "v1_rms_v" => value = Some((j, Quantity::V1RmsV)),
                        "p_total_w" => value = Some((j, Quantity::PTotalW)),
                        "sigma_v" | "sigma_w" => sigma = Some((j, *c)),
                        _ => {
                            return Err(FitInputError::UnknownColumn {
                                file: file.into(),
                                line,
                                column: (*c).into(),
                            })
                        }
                    }
                }
                let missing = |what: &str| FitInputError::MissingColumn {
                    file: file.into(),
                    line,
                    what: what.into(),
                };
                let freq = freq.ok_or_else(|| missing("freq_hz"))?;
                let (vj, q) = value.ok_or_else(|| missing("v1_rms_v or p_total_w"))?;
                let sigma = match sigma {
                    Some((j, name)) => {
                        let want = if q == Quantity::V1RmsV {
                            "sigma_v"
                        } else {
                            "sigma_w"
                        };
                        if name != want {
                            return Err(missing(&format!(
                                "{want} (the standard deviation in the unit of {})",
                                q.column()
                            )));
                        }
                        Some(j)
                    }
                    None => None,
                };
                header = Some((freq, vj, q, sigma, fields.len()));
            }
            Some((fj, vj, _, sj, ncol)) => {
                let row_err = |message: String| FitInputError::Row {
                    file: file.into(),
                    line,
                    message,
                };
                if fields.len() != ncol {
                    return Err(row_err(format!(
                        "{} fields where the header has {ncol}",
                        fields.len()
                    )));
                }
                let num = |j: usize| -> Result<f64, FitInputError> {
                    let v: f64 = fields[j]
                        .parse()
                        .map_err(|_| row_err(format!("`{}` is not a number", fields[j])))?;
                    if !v.is_finite() {
                        return Err(row_err(format!("`{}` is not a finite number", fields[j])));
                    }
                    Ok(v)
                };
                rows.push((
                    line,
                    Point {
                        freq_hz: num(fj)?,
                        value: num(vj)?,
                        sigma: sj.map(num).transpose()?,
                    },
                ));
            }
        }
    }
    let Some((_, _, quantity, _, _)) = header else {
        return Err(FitInputError::NoHeader { file: file.into() });
    };
    // Frequencies rise or fall strictly; the points are put in sweep order.
    if rows.len() >= 2 {
        let rising = rows[1].1.freq_hz > rows[0].1.freq_hz;
        for w in rows.windows(2) {
            let ok = if rising {
                w[1].1.freq_hz > w[0].1.freq_hz
            } else {
                w[1].1.freq_hz < w[0].1.freq_hz
            };
            if !ok {
                return Err(FitInputError::NotMonotonic {
                    file: file.into(),
                    line: w[1].0,
                    freq_hz: w[1].1.freq_hz,
                });
            }
        }
    }
    let mut points: Vec<Point> = rows.into_iter().map(|r| r.1).collect();
    points.sort_by(|a, b| match direction {
        Direction::Up => a.freq_hz.total_cmp(&b.freq_hz),
        Direction::Down => b.freq_hz.total_cmp(&a.freq_hz),
    });
    let get = |k: &str| meta.get(k).map(|v| v.0);
    let need = |k: &str, because: &str| {
        get(k).ok_or_else(|| FitInputError::Metadata {
            file: file.into(),
            line: 1,
            message: format!("missing `# {k} = ...` ({because})"),
        })
    };
    let accel_rms_g = need(
        "accel_rms_g",
        "the stated RMS acceleration of the sweep, in g",
    )?;
    let mut features = Vec::new();
    for (kind, k, ks) in [
        (FeatureKind::Onset, "onset_hz", "onset_sigma_hz"),
        (FeatureKind::BranchEnd, "jump_hz", "jump_sigma_hz"),
    ] {
        if let Some(f) = get(k) {
            features.push(Feature {
                kind,
                freq_hz: f,
                sigma_hz: need(ks, &format!("the standard deviation of `{k}`, Hz"))?,
            });
        }
    }
    let grid_hz = match (get("grid_from_hz"), get("grid_to_hz"), get("grid_step_hz")) {
        (None, None, None) => None,
        (Some(a), Some(b), Some(s)) if a > 0.0 && b > a && s > 0.0 && s <= b - a => {
            let mut g = endstop::study::stepped::linspace_step(a, b, s);
            if direction == Direction::Down {
                g.reverse();
            }
            Some(g)
        }
        _ => {
            return Err(FitInputError::Metadata {
                file: file.into(),
                line: meta.get("grid_from_hz").map_or(1, |v| v.1),
                message: "the grid needs all of grid_from_hz < grid_to_hz and a positive \
                          grid_step_hz not larger than the range"
                    .into(),
            })
        }
    };
    Ok(SweepData {
        label: file.into(),
        direction,
        accel_rms_g,
        quantity,
        points,
        grid_hz,
        features,
    })
}

fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// Runs `endstop fit`.
pub fn run(a: FitArgs) -> Result<()> {
    let loaded = load_device_file(&a.device)?;
    let free: Vec<FreeParam> = a
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
    let n: usize = data.iter().map(SweepData::len).sum();
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
        fit(&loaded.device, &data, &free, &LmSettings::default())
    })?;
    let command: Vec<String> = std::env::args().collect();
    write_outputs(&mut exp, &report, &data, &hashes, &command.join(" "))?;
    exp.finish()
}

/// The fitted device file: provenance as comments, then the device.
pub fn fitted_toml(report: &FitReport, hashes: &[(String, String)], command: &str) -> String {
    let mut s = String::new();
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
            "# fitted {} = {:e} (std error {:e}; 95 % {:e} .. {:e})\n",
            p.path, p.value, p.std_err, p.interval.0, p.interval.1
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

/// The results table, correlation and warnings in Markdown.
pub fn results_markdown(report: &FitReport) -> String {
    let mut md = String::from("| parameter | start | fitted | std error | 95 % interval | range |\n|---|---|---|---|---|---|\n");
    for p in &report.params {
        md.push_str(&format!(
            "| `{}` | {} | {} | {} | {} .. {} | {} .. {} |\n",
            p.path,
            fmt_sig(p.start, 4),
            fmt_sig(p.value, 5),
            fmt_sig(p.std_err, 3),
            fmt_sig(p.interval.0, 4),
            fmt_sig(p.interval.1, 4),
            fmt_sig(p.range.0, 3),
            fmt_sig(p.range.1, 3),
        ));
    }
    md.push_str(&format!(
        "\nUncertainty: {}. Weighted SSR {} with {} degrees of freedom; {} sweep evaluations, \
         {} iterations, stop: {:?}.\n\nCorrelation of the estimates:\n\n|  | {} |\n|---|{}\n",
        report.uncertainty.describe(),
        fmt_sig(report.ssr, 4),
        report.dof,
        report.evaluations,
        report.iterations,
        report.stop,
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
        let m = model_sweep(&report.device, report.accel_scale, d)?;
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
        for f in &d.features {
            let model_f = match f.kind {
                FeatureKind::Onset => m.onset_hz,
                FeatureKind::BranchEnd => m.branch_end_hz,
            };
            feature_lines.push((f.freq_hz, model_f, c, f.kind.label(), name.clone()));
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
        series.push(Series::new(
            &format!("{name}: measured {what}"),
            vec![(f, y0), (f, y1)],
            c,
            Style::Dashed,
        ));
        if let Some(g) = model_f {
            series.push(Series::new("", vec![(g, y0), (g, y1)], c, Style::Line));
        }
    }
    let q = data[0].quantity.column();
    exp.write_plot(
        &LinePlot::new(
            "Measured data and the fitted model",
            "frequency (Hz)",
            q,
            series,
        )
        .legend(LegendPos::UpperLeft),
    )?;
    exp.write_extra_plot(
        "endstop-fit-residuals",
        &LinePlot::new(
            "Residuals (model - measured) / sigma, points and features",
            "frequency (Hz)",
            "normalised residual",
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
