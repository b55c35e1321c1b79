//! A measured base-acceleration record (a recorded vibration, read from a file by the caller):
//! its samples checked one by one, checked against the band a study asks of it, and resampled
//! to the integrator's sample rate.
//!
//! # Checks
//! A record given by its sample times ([`MeasuredRecord::from_times`], a CSV file's rows) must
//! have finite times and accelerations, strictly increasing times and a uniform step: every
//! step within [`UNIFORM_TOL`] of the record's median step (a record with a dropped sample has
//! one step twice as long, and is refused; times printed with a few digits jitter by far less).
//! A record given at a sample rate ([`MeasuredRecord::from_uniform`], a WAV file) must have
//! finite samples. Either needs at least [`MIN_SAMPLES`] samples. Every refusal is a
//! [`MeasuredError`] naming the source, the line or sample, the value and the valid range.
//!
//! [`MeasuredRecord::check_band`] refuses a record that cannot carry the band `[lo, hi]` a
//! study analyses: its sample rate must be at least [`RATE_PER_BAND`] times `hi` (the
//! resampler's pass band ends at 0.4 of the record's rate), and after the discarded pre-roll it
//! must last at least [`MIN_CYCLES`] periods of `lo` (so that a Welch estimate of several
//! segments resolves the band's lowest frequency).
//!
//! # Resampling
//! [`MeasuredRecord::resampled`] evaluates the band-limited interpolant of the samples at the
//! integrator's sample instants `t_j = j / fs` (time zero is the first sample): a sum of
//! windowed sincs, `y(t) = sum_k x_k r sinc(r (t fs_in - k)) w((t fs_in - k) / W)`, with the
//! cut-off `r = 0.9 min(1, fs / fs_in)` in units of the record's Nyquist frequency (the lower
//! of the two rates' Nyquist frequencies, so that downsampling does not alias), a Kaiser
//! window `w` with beta [`KAISER_BETA`] (stop band about 90 dB down) and half-width `W` of
//! [`HALF_TAPS`] zero crossings. Past the record's ends the samples are zero. At equal rates
//! (within the rounding of a CSV's mean step) the record is used as it is: the interpolant at
//! the sample instants is the samples up to the kernel's pass-band ripple.
//!
//! The weights are computed once per record (the `resample` submodule): at a rational ratio
//! `p / q` (up to 16384 phases) one exact table per phase, and at any other ratio a table of
//! the kernel at `P` phases per sample, interpolated linearly between phases, with `P` chosen
//! so that the worst-case interpolation error is 1e-6 of the record's largest sample (30 dB
//! under the kernel's stop band). Each output is then one dot product (two for the
//! interpolated table) over a zero-padded copy of the record; a 10 s record at 50 kHz
//! resampled 2x up takes tens of milliseconds where evaluating the window and the sinc at each
//! of its 71 million taps took seconds.
//!
//! Why by hand: the record is in memory whole and resampled once, at any real ratio (a CSV's
//! step need not divide the integrator's), and a polyphase table over a padded slice is a few
//! tens of lines with no delay or chunk bookkeeping. Considered: `rubato` (streaming audio) is
//! built around fixed chunks, an output delay to compensate and, in its current major version,
//! an adapter API that a single slice does not need; its sinc resamplers tabulate the filter
//! at a chosen oversampling factor and interpolate between the tabulated points, as the table
//! plan here does, but with its own windows and cut-off and no error bound tied to a tolerance.
//! `dasp` (`interpolate::sinc::Sinc`) evaluates a `sin` and a `cos` at every tap of every
//! output over a ring buffer, with a raised-cosine window: the cost this module removes.
//! `samplerate` binds the C libsamplerate (a C build dependency) and converts `f32` samples
//! between integer rates with its own fixed filters.

use std::sync::Arc;

use thiserror::Error;

mod resample;

/// Largest relative deviation of one time step from the record's median step.
pub const UNIFORM_TOL: f64 = 0.01;

/// Fewest samples a record may have.
pub const MIN_SAMPLES: usize = 16;

/// The record's sample rate must be at least this many times the band's upper edge.
pub const RATE_PER_BAND: f64 = 2.5;

/// The analysed part of a record must last at least this many periods of the band's lower
/// edge.
pub const MIN_CYCLES: f64 = 32.0;

/// Half-width of the resampling kernel, in zero crossings of its sinc.
pub const HALF_TAPS: f64 = 32.0;

/// Shape parameter of the resampling kernel's Kaiser window.
pub const KAISER_BETA: f64 = 8.6;

/// Where in a source a value sits: a line of a text file or a sample of a sampled one.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Position {
    /// Line number (from 1) of a text file.
    Line(usize),
    /// Sample index (from 0) of a sampled file.
    Sample(usize),
}

impl std::fmt::Display for Position {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Position::Line(l) => write!(f, "line {l}"),
            Position::Sample(k) => write!(f, "sample {k}"),
        }
    }
}

/// A measured record that cannot be used.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum MeasuredError {
    /// A time or an acceleration is NaN or infinite.
    #[error("{source_name}: {at}: {field} = {value} is not a finite number")]
    NotFinite {
        /// The source (a file name).
        source_name: String,
        /// Where.
        at: Position,
        /// Which column (`time_s`, `accel`).
        field: String,
        /// The value.
        value: f64,
    },
    /// The times do not increase.
    #[error(
        "{source_name}: {at}: time_s = {time_s:e} does not increase: must be > {previous_s:e} \
         (the time of the row before)"
    )]
    NotIncreasing {
        /// The source.
        source_name: String,
        /// Where.
        at: Position,
        /// This time (s).
        time_s: f64,
        /// The time before it (s).
        previous_s: f64,
    },
    /// A time step differs from the mean step (a gap, or jittered sampling).
    #[error(
        "{source_name}: {at}: time step {step_s:.4e} s is not uniform: must be between \
         {lo_s:.4e} and {hi_s:.4e} s (the record's median step {median_step_s:.4e} s within \
         {tol_pct} %)"
    )]
    NonUniform {
        /// The source.
        source_name: String,
        /// Where (the later sample of the step).
        at: Position,
        /// The step (s).
        step_s: f64,
        /// The record's median step (s).
        median_step_s: f64,
        /// Smallest valid step (s).
        lo_s: f64,
        /// Largest valid step (s).
        hi_s: f64,
        /// The tolerance in per cent.
        tol_pct: f64,
    },
    /// A record's time and acceleration columns differ in length.
    #[error("{source_name}: {times} times but {accels} accelerations: must be as many")]
    ColumnLengths {
        /// The source.
        source_name: String,
        /// How many times.
        times: usize,
        /// How many accelerations.
        accels: usize,
    },
    /// Too few samples to be a record.
    #[error("{source_name}: {samples} samples: must be at least {min}")]
    TooFewSamples {
        /// The source.
        source_name: String,
        /// How many there are.
        samples: usize,
        /// How many are needed.
        min: usize,
    },
    /// The sample rate (or the scale) is not a finite positive number.
    #[error("{source_name}: {field} = {value:e} is out of range: must be finite and > 0")]
    NotPositive {
        /// The source.
        source_name: String,
        /// The field.
        field: String,
        /// The value.
        value: f64,
    },
    /// The record is sampled too slowly for the band asked.
    #[error(
        "{source_name}: sample rate {sample_rate_hz:e} Hz is too low for the band asked (up to \
         {band_hi_hz:e} Hz): must be at least {needed_hz:e} Hz ({RATE_PER_BAND} times the band's \
         upper edge)"
    )]
    Undersampled {
        /// The source.
        source_name: String,
        /// The record's sample rate (Hz).
        sample_rate_hz: f64,
        /// The band's upper edge (Hz).
        band_hi_hz: f64,
        /// The lowest valid sample rate (Hz).
        needed_hz: f64,
    },
    /// The record is too short for the band asked.
    #[error(
        "{source_name}: duration {duration_s:e} s is too short for the band asked (from \
         {band_lo_hz:e} Hz): must be at least {needed_s:e} s (a pre-roll of {preroll_s:e} s, \
         then {MIN_CYCLES} periods of the band's lower edge)"
    )]
    TooShort {
        /// The source.
        source_name: String,
        /// The record's duration (s).
        duration_s: f64,
        /// The band's lower edge (Hz).
        band_lo_hz: f64,
        /// The discarded pre-roll (s).
        preroll_s: f64,
        /// The shortest valid duration (s).
        needed_s: f64,
    },
    /// The band asked is not a band.
    #[error(
        "{source_name}: band {lo_hz:e} to {hi_hz:e} Hz is not a band: must have 0 < lower < \
         upper, both finite"
    )]
    BadBand {
        /// The source.
        source_name: String,
        /// Lower edge (Hz).
        lo_hz: f64,
        /// Upper edge (Hz).
        hi_hz: f64,
    },
}

/// A checked, uniformly sampled acceleration record.
#[derive(Debug, Clone, PartialEq)]
pub struct MeasuredRecord {
    /// Where it came from (a file name), quoted in errors.
    pub source_name: String,
    /// Its sample rate (Hz).
    pub sample_rate_hz: f64,
    /// Accelerations (m/s^2), sample k at `t = k / sample_rate_hz`; shared, so that the drive
    /// at the record's own rate is these samples, not a copy ([`MeasuredRecord::resampled`]).
    pub accel_si: Arc<[f64]>,
}

impl MeasuredRecord {
    /// A record from rows `(position, time_s, accel_si)` (see the module docs for the checks);
    /// its sample rate is the inverse of the mean step, and its time origin is the first row.
    pub fn from_times(
        source_name: &str,
        rows: &[(Position, f64, f64)],
    ) -> Result<Self, MeasuredError> {
        let times: Vec<f64> = rows.iter().map(|r| r.1).collect();
        let accel: Arc<[f64]> = rows.iter().map(|r| r.2).collect();
        Self::from_columns(source_name, &times, accel, |k| rows[k].0)
    }

    /// A record from its times and accelerations as columns, `position(k)` naming where row
    /// `k` came from (asked only to name a refused row): the checks and the record of
    /// [`MeasuredRecord::from_times`], without a vector of rows (a reader of a long file
    /// keeps two columns instead).
    pub fn from_columns(
        source_name: &str,
        times_s: &[f64],
        accel_si: impl Into<Arc<[f64]>>,
        position: impl Fn(usize) -> Position,
    ) -> Result<Self, MeasuredError> {
        let accel_si = accel_si.into();
        let src = || source_name.to_string();
        let n = times_s.len();
        if accel_si.len() != n {
            return Err(MeasuredError::ColumnLengths {
                source_name: src(),
                times: n,
                accels: accel_si.len(),
            });
        }
        if n < MIN_SAMPLES {
            return Err(MeasuredError::TooFewSamples {
                source_name: src(),
                samples: n,
                min: MIN_SAMPLES,
            });
        }
        let bad = |k: usize, field: &str, value: f64| MeasuredError::NotFinite {
            source_name: src(),
            at: position(k),
            field: field.into(),
            value,
        };
        for (k, (&t, &a)) in times_s.iter().zip(accel_si.iter()).enumerate() {
            if !t.is_finite() {
                return Err(bad(k, "time_s", t));
            }
            if !a.is_finite() {
                return Err(bad(k, "accel", a));
            }
        }
        let t = times_s;
        if let Some(k) = (1..n).find(|&k| t[k] <= t[k - 1]) {
            return Err(MeasuredError::NotIncreasing {
                source_name: src(),
                at: position(k),
                time_s: t[k],
                previous_s: t[k - 1],
            });
        }
        // The reference step is the median (a gap does not move it); the rate is the mean
        // step's inverse, which averages the times' rounding.
        let steps = || t.windows(2).map(|w| w[1] - w[0]);
        let (min, max) = steps().fold((f64::INFINITY, 0.0f64), |(lo, hi), s| {
            (lo.min(s), hi.max(s))
        });
        // The median lies in [min, max], and a rounded product with a positive factor is
        // monotone in its operand: where every step is within the tolerance of both the
        // smallest and the largest step, it is within the tolerance of the median, and the
        // record is uniform without the median being found.
        if min >= max * (1.0 - UNIFORM_TOL) && max <= min * (1.0 + UNIFORM_TOL) {
            return Ok(Self::at_mean_step(source_name, t, accel_si));
        }
        let mut steps: Vec<f64> = steps().collect();
        let mid = steps.len() / 2;
        let median = *steps.select_nth_unstable_by(mid, f64::total_cmp).1;
        let (lo, hi) = (median * (1.0 - UNIFORM_TOL), median * (1.0 + UNIFORM_TOL));
        if let Some(k) = (1..n).find(|&k| !(lo..=hi).contains(&(t[k] - t[k - 1]))) {
            return Err(MeasuredError::NonUniform {
                source_name: src(),
                at: position(k),
                step_s: t[k] - t[k - 1],
                median_step_s: median,
                lo_s: lo,
                hi_s: hi,
                tol_pct: UNIFORM_TOL * 100.0,
            });
        }
        Ok(Self::at_mean_step(source_name, t, accel_si))
    }

    /// The record of checked times and accelerations: its rate the inverse of the mean step.
    fn at_mean_step(source_name: &str, times_s: &[f64], accel_si: Arc<[f64]>) -> Self {
        let n = times_s.len();
        let mean = (times_s[n - 1] - times_s[0]) / (n - 1) as f64;
        Self {
            source_name: source_name.to_string(),
            sample_rate_hz: 1.0 / mean,
            accel_si,
        }
    }

    /// A record of samples at `sample_rate_hz` (see the module docs for the checks); samples
    /// given as an `Arc` are kept as they are, without a copy.
    pub fn from_uniform(
        source_name: &str,
        sample_rate_hz: f64,
        accel_si: impl Into<Arc<[f64]>>,
    ) -> Result<Self, MeasuredError> {
        let accel_si = accel_si.into();
        let src = || source_name.to_string();
        if !(sample_rate_hz.is_finite() && sample_rate_hz > 0.0) {
            return Err(MeasuredError::NotPositive {
                source_name: src(),
                field: "sample_rate_hz".into(),
                value: sample_rate_hz,
            });
        }
        if accel_si.len() < MIN_SAMPLES {
            return Err(MeasuredError::TooFewSamples {
                source_name: src(),
                samples: accel_si.len(),
                min: MIN_SAMPLES,
            });
        }
        // A test over blocks first (it vectorises; the search for the first bad sample, with
        // its early exit, does not: about nine instructions a sample, measured with callgrind
        // on a 500 000-sample record), the search only in a record that has one.
        let all_finite = accel_si
            .chunks(256)
            .all(|b| b.iter().fold(true, |ok, a| ok & a.is_finite()));
        if let Some((k, &value)) = (!all_finite)
            .then(|| accel_si.iter().enumerate().find(|(_, a)| !a.is_finite()))
            .flatten()
        {
            return Err(MeasuredError::NotFinite {
                source_name: src(),
                at: Position::Sample(k),
                field: "accel".into(),
                value,
            });
        }
        Ok(Self {
            source_name: src(),
            sample_rate_hz,
            accel_si,
        })
    }

    /// Duration from the first to the last sample (s).
    pub fn duration_s(&self) -> f64 {
        (self.accel_si.len() - 1) as f64 / self.sample_rate_hz
    }

    /// Mean square of the samples ((m/s^2)^2).
    pub fn mean_square_si(&self) -> f64 {
        self.accel_si.iter().map(|a| a * a).sum::<f64>() / self.accel_si.len() as f64
    }

    /// Checks that the record can carry the band `[lo_hz, hi_hz]` after a discarded pre-roll
    /// of `preroll_s` (see the module docs).
    pub fn check_band(&self, lo_hz: f64, hi_hz: f64, preroll_s: f64) -> Result<(), MeasuredError> {
        let src = || self.source_name.clone();
        if !(lo_hz.is_finite() && hi_hz.is_finite() && lo_hz > 0.0 && hi_hz > lo_hz) {
            return Err(MeasuredError::BadBand {
                source_name: src(),
                lo_hz,
                hi_hz,
            });
        }
        let needed_hz = RATE_PER_BAND * hi_hz;
        if self.sample_rate_hz < needed_hz {
            return Err(MeasuredError::Undersampled {
                source_name: src(),
                sample_rate_hz: self.sample_rate_hz,
                band_hi_hz: hi_hz,
                needed_hz,
            });
        }
        let needed_s = preroll_s.max(0.0) + MIN_CYCLES / lo_hz;
        if self.duration_s() < needed_s {
            return Err(MeasuredError::TooShort {
                source_name: src(),
                duration_s: self.duration_s(),
                band_lo_hz: lo_hz,
                preroll_s,
                needed_s,
            });
        }
        Ok(())
    }

    /// The record at `rate_hz`, at `t_j = j / rate_hz` up to its last sample (see the module
    /// docs), shared as a sampled drive holds it. A non-positive or non-finite rate gives an
    /// empty record.
    pub fn resampled(&self, rate_hz: f64) -> Arc<[f64]> {
        if !(rate_hz.is_finite() && rate_hz > 0.0) || self.accel_si.is_empty() {
            return Arc::new([]);
        }
        let fs_in = self.sample_rate_hz;
        let m = (self.duration_s() * rate_hz + 1e-9).floor() as usize + 1;
        let plan = resample::Plan::choose(self.accel_si.len(), m, fs_in, rate_hz);
        // At the record's own rate the drive is the record's samples, shared.
        if plan == resample::Plan::Identity && m >= self.accel_si.len() {
            return Arc::clone(&self.accel_si);
        }
        resample::resample(&self.accel_si, fs_in, rate_hz, m, plan)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rows(times: &[f64]) -> Vec<(Position, f64, f64)> {
        times
            .iter()
            .enumerate()
            .map(|(i, &t)| (Position::Line(i + 2), t, (7.0 * t).sin()))
            .collect()
    }

    fn uniform(n: usize, dt: f64) -> Vec<f64> {
        (0..n).map(|i| i as f64 * dt).collect()
    }

    #[test]
    fn a_uniform_record_gives_its_rate() {
        let r = MeasuredRecord::from_times("a.csv", &rows(&uniform(100, 1e-3))).unwrap();
        assert!((r.sample_rate_hz - 1000.0).abs() < 1e-9);
        assert_eq!(r.accel_si.len(), 100);
    }

    /// At its own rate a record is its drive, shared: the same allocation, not a copy; at
    /// another rate the drive is a new one.
    #[test]
    fn the_drive_at_the_records_own_rate_is_its_samples() {
        let samples: Arc<[f64]> = (0..1000).map(|k| (0.01 * k as f64).sin()).collect();
        let r = MeasuredRecord::from_uniform("s.wav", 1000.0, Arc::clone(&samples)).unwrap();
        assert!(Arc::ptr_eq(&r.accel_si, &samples));
        assert!(Arc::ptr_eq(&r.resampled(1000.0), &samples));
        assert!(!Arc::ptr_eq(&r.resampled(2000.0), &samples));
    }

    #[test]
    fn a_gap_nan_or_backward_time_is_named_with_its_line() {
        let mut t = uniform(100, 1e-3);
        t.remove(50);
        match MeasuredRecord::from_times("a.csv", &rows(&t)) {
            Err(MeasuredError::NonUniform { at, step_s, .. }) => {
                assert_eq!(at, Position::Line(52));
                assert!((step_s - 2e-3).abs() < 1e-12);
            }
            other => panic!("{other:?}"),
        }
        let mut r = rows(&uniform(100, 1e-3));
        r[10].2 = f64::NAN;
        let e = MeasuredRecord::from_times("a.csv", &r).unwrap_err();
        assert!(matches!(
            e,
            MeasuredError::NotFinite {
                at: Position::Line(12),
                ..
            }
        ));
        assert!(e.to_string().contains("a.csv: line 12: accel = NaN"), "{e}");
        let mut t = uniform(100, 1e-3);
        t[30] = t[29];
        assert!(matches!(
            MeasuredRecord::from_times("a.csv", &rows(&t)),
            Err(MeasuredError::NotIncreasing {
                at: Position::Line(32),
                ..
            })
        ));
        let e = MeasuredRecord::from_uniform("b.wav", 1e3, vec![0.0; 3]).unwrap_err();
        assert!(matches!(e, MeasuredError::TooFewSamples { samples: 3, .. }));
        let mut s = vec![0.0; 100];
        s[40] = f64::INFINITY;
        let e = MeasuredRecord::from_uniform("b.wav", 1e3, s).unwrap_err();
        assert!(matches!(
            e,
            MeasuredError::NotFinite {
                at: Position::Sample(40),
                ..
            }
        ));
        // The first bad sample is named wherever it lies among the blocks of the test.
        let mut s = vec![0.0; 1000];
        (s[700], s[900]) = (f64::NAN, f64::NEG_INFINITY);
        let e = MeasuredRecord::from_uniform("b.wav", 1e3, s).unwrap_err();
        assert!(matches!(
            e,
            MeasuredError::NotFinite {
                at: Position::Sample(700),
                ..
            }
        ));
    }

    /// Steps within the tolerance of the median but not of each other (0.992 and 1.008 of it:
    /// 1.6 % apart) are uniform; one step 1.2 % short of the median is not, and is named.
    #[test]
    fn a_jittered_record_is_judged_by_its_median() {
        let times = |step: &dyn Fn(usize) -> f64| {
            let mut t = vec![0.0];
            for k in 1..100 {
                t.push(t[k - 1] + 1e-3 * step(k));
            }
            t
        };
        let jittered = |k: usize| [1.0, 0.992, 1.008][k % 3];
        let t = times(&jittered);
        let r = MeasuredRecord::from_times("a.csv", &rows(&t)).unwrap();
        assert_eq!(r.sample_rate_hz, 1.0 / ((t[99] - t[0]) / 99.0));
        let t = times(&|k| if k == 40 { 0.988 } else { jittered(k) });
        match MeasuredRecord::from_times("a.csv", &rows(&t)) {
            Err(MeasuredError::NonUniform {
                at, median_step_s, ..
            }) => {
                assert_eq!(at, Position::Line(42));
                // The median is the unjittered step, up to the times' rounding (1e-16 of 0.1 s).
                assert!((median_step_s - 1e-3).abs() < 1e-15, "{median_step_s:e}");
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn the_band_needs_rate_and_length() {
        let r = MeasuredRecord::from_uniform("b.wav", 1e3, vec![0.0; 1001]).unwrap();
        assert!(r.check_band(40.0, 400.0, 0.0).is_ok());
        assert!(matches!(
            r.check_band(40.0, 401.0, 0.0),
            Err(MeasuredError::Undersampled { .. })
        ));
        // 1 s lasts 32 periods of 32 Hz, not of 31 Hz; a pre-roll takes its share.
        assert!(r.check_band(32.0, 100.0, 0.0).is_ok());
        assert!(matches!(
            r.check_band(31.0, 100.0, 0.0),
            Err(MeasuredError::TooShort { .. })
        ));
        assert!(matches!(
            r.check_band(40.0, 100.0, 0.3),
            Err(MeasuredError::TooShort { .. })
        ));
        assert!(matches!(
            r.check_band(f64::NAN, 100.0, 0.0),
            Err(MeasuredError::BadBand { .. })
        ));
    }

    /// Upsampling a sine well inside the record's band reproduces it at the new instants
    /// (away from the ends, where the record's zero continuation is felt).
    #[test]
    fn upsampling_a_band_limited_sine_is_exact_inside_the_record() {
        let (fs_in, f) = (10e3, 1234.5);
        let x: Vec<f64> = (0..4000)
            .map(|k| (2.0 * std::f64::consts::PI * f * k as f64 / fs_in).sin())
            .collect();
        let rec = MeasuredRecord::from_uniform("s", fs_in, x).unwrap();
        let fs = 100e3;
        let y = rec.resampled(fs);
        assert_eq!(y.len(), 39991);
        let skip = (HALF_TAPS / 0.9 * fs / fs_in) as usize;
        let err = y[skip..y.len() - skip]
            .iter()
            .enumerate()
            .map(|(j, v)| {
                let t = (j + skip) as f64 / fs;
                (v - (2.0 * std::f64::consts::PI * f * t).sin()).abs()
            })
            .fold(0.0, f64::max);
        assert!(err < 1e-3, "largest error {err:e}");
    }

    /// Downsampling removes what lies above the new Nyquist frequency instead of folding it
    /// into the band.
    #[test]
    fn downsampling_does_not_alias() {
        let fs_in = 200e3;
        let x: Vec<f64> = (0..20000)
            .map(|k| (2.0 * std::f64::consts::PI * 80e3 * k as f64 / fs_in).sin())
            .collect();
        let rec = MeasuredRecord::from_uniform("s", fs_in, x).unwrap();
        let y = rec.resampled(100e3);
        let interior = &y[200..y.len() - 200];
        let rms = (interior.iter().map(|v| v * v).sum::<f64>() / interior.len() as f64).sqrt();
        assert!(rms < 1e-3, "rms {rms:e} of an 80 kHz tone at 100 kHz");
    }
}
