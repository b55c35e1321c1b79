//! Reading ngspice's `wrdata` output back (see [`crate::spice`]).

use thiserror::Error;

/// Failure to read ngspice output.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum SpiceError {
    /// The output is empty or has no header line.
    #[error("wrdata output is empty")]
    Empty,
    /// A line does not have the expected number of numeric columns.
    #[error("wrdata line {line}: expected {expected} numeric columns, found `{text}`")]
    BadLine {
        /// 1-based line number.
        line: usize,
        /// Columns expected from the header.
        expected: usize,
        /// The offending line (truncated).
        text: String,
    },
    /// A requested column is not in the header.
    #[error("wrdata output has no column `{0}`")]
    NoColumn(String),
    /// The data do not cover a requested time window.
    #[error("time window {t0:e} .. {t1:e} s not covered by the data ({first:e} .. {last:e} s)")]
    Window {
        /// Requested start (s).
        t0: f64,
        /// Requested end (s).
        t1: f64,
        /// First time in the data (s).
        first: f64,
        /// Last time in the data (s).
        last: f64,
    },
}

/// A table read from ngspice's `wrdata` with `wr_singlescale` and `wr_vecnames`: a header of
/// vector names (the first is `time`) and one row per time point.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Waveforms {
    /// Column names (lower case), `time` first.
    pub names: Vec<String>,
    /// Time points (s).
    pub time: Vec<f64>,
    /// One vector per column after `time`.
    pub columns: Vec<Vec<f64>>,
}

/// Parses the text of a `wrdata` file (see
/// [`Transient::wrdata_file`](super::Transient::wrdata_file)).
pub fn parse_wrdata(text: &str) -> Result<Waveforms, SpiceError> {
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let (_, header) = lines.next().ok_or(SpiceError::Empty)?;
    let names: Vec<String> = header
        .split_whitespace()
        .map(|n| n.to_ascii_lowercase())
        .collect();
    if names.is_empty() {
        return Err(SpiceError::Empty);
    }
    let ncol = names.len();
    let mut time = Vec::new();
    let mut columns = vec![Vec::new(); ncol - 1];
    for (i, line) in lines {
        let vals: Result<Vec<f64>, _> = line.split_whitespace().map(str::parse::<f64>).collect();
        match vals {
            Ok(v) if v.len() == ncol => {
                time.push(v[0]);
                for (c, x) in columns.iter_mut().zip(&v[1..]) {
                    c.push(*x);
                }
            }
            _ => {
                return Err(SpiceError::BadLine {
                    line: i + 1,
                    expected: ncol,
                    text: line.chars().take(120).collect(),
                })
            }
        }
    }
    Ok(Waveforms {
        names,
        time,
        columns,
    })
}

impl Waveforms {
    /// The samples of a column by name (`v(n1)`, case-insensitive).
    pub fn column(&self, name: &str) -> Result<&[f64], SpiceError> {
        let key = name.to_ascii_lowercase();
        self.names
            .iter()
            .skip(1)
            .position(|n| *n == key)
            .map(|i| self.columns[i].as_slice())
            .ok_or(SpiceError::NoColumn(name.to_string()))
    }

    /// Number of time points.
    pub fn len(&self) -> usize {
        self.time.len()
    }

    /// True if there are no time points.
    pub fn is_empty(&self) -> bool {
        self.time.is_empty()
    }

    fn check_window(&self, t0: f64, t1: f64) -> Result<(), SpiceError> {
        let first = self.time.first().copied().unwrap_or(f64::NAN);
        let last = self.time.last().copied().unwrap_or(f64::NAN);
        // Allow a relative slack of 1e-9 of the window for the float time stamps.
        let slack = 1e-9 * (t1 - t0).abs();
        let ordered = t0.partial_cmp(&t1) == Some(std::cmp::Ordering::Less);
        if self.time.len() < 2 || !ordered || first > t0 + slack || last < t1 - slack {
            return Err(SpiceError::Window {
                t0,
                t1,
                first,
                last,
            });
        }
        Ok(())
    }

    /// The pieces `t[k]..t[k + 1]` of the time grid that overlap [t0, t1], as (k, a, b) with
    /// a..b the non-empty overlap (after [`Waveforms::check_window`], so there are two or more
    /// time points).
    fn pieces(&self, t0: f64, t1: f64) -> impl Iterator<Item = (usize, f64, f64)> + '_ {
        let t = &self.time;
        (0..t.len() - 1).filter_map(move |k| {
            let a = t[k].max(t0);
            let b = t[k + 1].min(t1);
            if b <= a {
                None
            } else {
                Some((k, a, b))
            }
        })
    }

    /// Integral of g(y) over [t0, t1] for the column `name`, with y linearly interpolated
    /// between time points and each piece integrated by Simpson's rule (exact for g(y) = y^2).
    fn integrate(
        &self,
        name: &str,
        t0: f64,
        t1: f64,
        g: impl Fn(f64) -> f64,
    ) -> Result<f64, SpiceError> {
        self.check_window(t0, t1)?;
        let y = self.column(name)?;
        let t = &self.time;
        let at = |k: usize, tt: f64| {
            let h = t[k + 1] - t[k];
            if h <= 0.0 {
                y[k + 1]
            } else {
                y[k] + (y[k + 1] - y[k]) * (tt - t[k]) / h
            }
        };
        let mut acc = 0.0;
        for (k, a, b) in self.pieces(t0, t1) {
            let (ya, yb) = (at(k, a), at(k, b));
            let ym = at(k, 0.5 * (a + b));
            acc += (b - a) / 6.0 * (g(ya) + 4.0 * g(ym) + g(yb));
        }
        Ok(acc)
    }

    /// RMS of a column over [t0, t1] (the piecewise-linear interpolant's RMS).
    pub fn rms(&self, name: &str, t0: f64, t1: f64) -> Result<f64, SpiceError> {
        Ok((self.integrate(name, t0, t1, |y| y * y)? / (t1 - t0)).sqrt())
    }

    /// Largest |y| of a column at the time points inside [t0, t1].
    pub fn max_abs(&self, name: &str, t0: f64, t1: f64) -> Result<f64, SpiceError> {
        self.check_window(t0, t1)?;
        let y = self.column(name)?;
        Ok(self
            .time
            .iter()
            .zip(y)
            .filter(|(t, _)| **t >= t0 && **t <= t1)
            .fold(0.0, |m, (_, v)| m.max(v.abs())))
    }

    /// Fraction of [t0, t1] during which |y| > `level` (piecewise-linear interpolant, crossing
    /// times interpolated).
    pub fn fraction_above(
        &self,
        name: &str,
        level: f64,
        t0: f64,
        t1: f64,
    ) -> Result<f64, SpiceError> {
        self.check_window(t0, t1)?;
        let y = self.column(name)?;
        let t = &self.time;
        let mut above = 0.0;
        for (k, a, b) in self.pieces(t0, t1) {
            // Subdivide at the crossings of +level and -level of the linear piece.
            let h = t[k + 1] - t[k];
            let lin = |tt: f64| y[k] + (y[k + 1] - y[k]) * (tt - t[k]) / h;
            let mut cuts = vec![a, b];
            for lv in [level, -level] {
                let dy = y[k + 1] - y[k];
                if dy != 0.0 {
                    let tc = t[k] + (lv - y[k]) / dy * h;
                    if tc > a && tc < b {
                        cuts.push(tc);
                    }
                }
            }
            cuts.sort_by(f64::total_cmp);
            for w in cuts.windows(2) {
                if lin(0.5 * (w[0] + w[1])).abs() > level {
                    above += w[1] - w[0];
                }
            }
        }
        Ok(above / (t1 - t0))
    }
}
