//! The measured data of `endstop fit` ([`crate::reports::fit_io`]): the measured-sweep CSV file and the
//! `--free PATH=LO..HI` option, read with errors that name the file and line.
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

use endstop::device::{ParamError, ParamRange};
use endstop::fit::{Direction, Feature, FeatureKind, Point, Quantity, SweepData};
use thiserror::Error;

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
    /// A `--free` option that is not a range `PATH=LO..HI` ([`ParamRange::parse`]).
    #[error("--free `{given}`: {error}")]
    Free {
        /// The option as given.
        given: String,
        /// What is wrong, naming the parameter.
        error: ParamError,
    },
}

/// Parses a `--free` option, `PATH=LO..HI` ([`ParamRange::parse`]).
pub fn parse_free(s: &str) -> Result<ParamRange, FitInputError> {
    ParamRange::parse(s).map_err(|error| FitInputError::Free {
        given: s.into(),
        error,
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

/// The `# key = value` lines read so far: each known key's value and its line.
type Metadata = BTreeMap<&'static str, (f64, usize)>;

/// The header's columns: the frequency's, the value's with its quantity, the standard
/// deviation's if any, and how many there are.
#[derive(Debug, Clone, Copy)]
struct Header {
    freq: usize,
    value: usize,
    quantity: Quantity,
    sigma: Option<usize>,
    columns: usize,
}

/// Parses a measured-sweep file's text (see the module docs); `file` names it in errors.
pub fn parse_sweep(
    text: &str,
    file: &str,
    direction: Direction,
) -> Result<SweepData, FitInputError> {
    let mut meta = Metadata::new();
    let mut header: Option<Header> = None;
    let mut rows: Vec<(usize, Point)> = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let l = raw.trim();
        if l.is_empty() {
            continue;
        }
        if let Some(c) = l.strip_prefix('#') {
            if let Some((key, v)) = metadata_line(c, file, line)? {
                meta.insert(key, (v, line));
            }
            continue;
        }
        let fields: Vec<&str> = l.split(',').map(str::trim).collect();
        match header {
            None => header = Some(parse_header(&fields, file, line)?),
            Some(h) => rows.push((line, parse_row(&h, &fields, file, line)?)),
        }
    }
    let Some(Header { quantity, .. }) = header else {
        return Err(FitInputError::NoHeader { file: file.into() });
    };
    check_monotonic(&rows, file)?;
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
    let grid_hz = grid(&meta, file, direction)?;
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

/// A comment line's `key = value` (the text after the `#`), if it is one: a single word
/// before the `=`; other comments are free text and give `None`.
fn metadata_line(
    comment: &str,
    file: &str,
    line: usize,
) -> Result<Option<(&'static str, f64)>, FitInputError> {
    let kv = comment.split_once('=').filter(|(k, _)| {
        let k = k.trim();
        !k.is_empty() && k.chars().all(|ch| ch.is_ascii_alphanumeric() || ch == '_')
    });
    let Some((k, v)) = kv else {
        return Ok(None);
    };
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
    Ok(Some((*key, v)))
}

/// The header line's columns.
fn parse_header(fields: &[&str], file: &str, line: usize) -> Result<Header, FitInputError> {
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
    Ok(Header {
        freq,
        value: vj,
        quantity: q,
        sigma,
        columns: fields.len(),
    })
}

/// One data row under `header`.
fn parse_row(
    header: &Header,
    fields: &[&str],
    file: &str,
    line: usize,
) -> Result<Point, FitInputError> {
    let ncol = header.columns;
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
    Ok(Point {
        freq_hz: num(header.freq)?,
        value: num(header.value)?,
        sigma: header.sigma.map(num).transpose()?,
    })
}

/// Frequencies rise or fall strictly (the rows with their lines, in file order).
fn check_monotonic(rows: &[(usize, Point)], file: &str) -> Result<(), FitInputError> {
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
    Ok(())
}

/// The simulated sweep's grid of the `grid_*` keys, in sweep order: none without them, all
/// three or an error.
fn grid(
    meta: &Metadata,
    file: &str,
    direction: Direction,
) -> Result<Option<Vec<f64>>, FitInputError> {
    let get = |k: &str| meta.get(k).map(|v| v.0);
    match (get("grid_from_hz"), get("grid_to_hz"), get("grid_step_hz")) {
        (None, None, None) => Ok(None),
        (Some(a), Some(b), Some(s)) if a > 0.0 && b > a && s > 0.0 && s <= b - a => {
            let mut g = endstop::study::stepped::linspace_step(a, b, s);
            if direction == Direction::Down {
                g.reverse();
            }
            Ok(Some(g))
        }
        _ => Err(FitInputError::Metadata {
            file: file.into(),
            line: meta.get("grid_from_hz").map_or(1, |v| v.1),
            message: "the grid needs all of grid_from_hz < grid_to_hz and a positive \
                      grid_step_hz not larger than the range"
                .into(),
        }),
    }
}
