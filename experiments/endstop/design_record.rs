//! `endstop design --accel-file`: the measured record's options, read and resampled before
//! anything is written ([`endstop::design::record`]).

use std::path::PathBuf;

use anyhow::{bail, Result};
use endstop::design::{Problem, RecordObjective};
use endstop_experiments::fmt_sig;
use endstop_experiments::reports::measured_io;

/// The most samples a resampled record may have (as `endstop random`'s).
const MAX_RESAMPLED: usize = 1 << 27;

/// The measured record's options.
#[derive(clap::Args, Debug, Clone)]
pub struct RecordArgs {
    /// A measured acceleration record, in place of --freq-hz and --accel-rms-g: a CSV file
    /// whose header names a time column (`time_s` or `time_ms`) and an acceleration column
    /// (`accel_m_per_s2` or `accel_g`), or a mono WAV file with --accel-scale (as for `endstop
    /// random`). The objective is the mean DC power over the record after a pre-roll (the
    /// longest any design of the ranges needs), the same record for every design; it is
    /// deterministic, so there is nothing to confirm on fresh seeds.
    #[arg(long, conflicts_with_all = ["freqs_hz", "accel_rms_g", "psd"])]
    pub(crate) accel_file: Option<PathBuf>,
    /// The acceleration of a WAV file's full scale (m/s^2); a WAV file carries no unit.
    #[arg(long, requires = "accel_file", allow_hyphen_values = true)]
    pub(crate) accel_scale: Option<f64>,
    /// The integrator's sample rate for the record (Hz); the record is resampled to it.
    #[arg(
        long,
        default_value_t = 100e3,
        requires = "accel_file",
        allow_hyphen_values = true
    )]
    pub(crate) sample_rate_hz: f64,
}

/// A record read and resampled, with the words that describe it.
pub(crate) struct ReadRecord {
    /// The objective (its pre-roll is the problem's to set).
    pub(crate) objective: RecordObjective,
    /// The record's source, its length and rate as read.
    pub(crate) described: String,
    /// RMS of the resampled record (g).
    pub(crate) rms_g: f64,
}

impl RecordArgs {
    /// The record of --accel-file, read and resampled, if given.
    pub(crate) fn objective(&self) -> Result<Option<ReadRecord>> {
        let Some(path) = &self.accel_file else {
            return Ok(None);
        };
        let fs = self.sample_rate_hz;
        if !(fs.is_finite() && fs > 0.0) {
            bail!("--sample-rate-hz = {fs}: must be finite and > 0");
        }
        let rec = measured_io::read_record(path, self.accel_scale)?;
        let samples = rec.duration_s() * fs;
        if samples > MAX_RESAMPLED as f64 {
            bail!(
                "{}: --sample-rate-hz = {fs} gives {samples:.0} samples over the record's {} s: \
                 must give at most {MAX_RESAMPLED}",
                path.display(),
                fmt_sig(rec.duration_s(), 6)
            );
        }
        let accel = rec.resampled(fs);
        let ms = accel.iter().map(|a| a * a).sum::<f64>() / accel.len().max(1) as f64;
        let described = format!(
            "`{}` ({} s at {} Hz, resampled to {} Hz)",
            path.display(),
            fmt_sig(rec.duration_s(), 4),
            rec.sample_rate_hz,
            fs
        );
        Ok(Some(ReadRecord {
            objective: RecordObjective::new(accel, fs),
            described,
            rms_g: ms.sqrt() / endstop::G,
        }))
    }
}

/// The opening of `numbers.md` over a record: the question, with the pre-roll the problem set.
pub(crate) fn question(p: &Problem, described: &str, rms_g: f64) -> String {
    let Some(r) = &p.record else {
        return String::new();
    };
    format!(
        "over the measured record {described}, {} g rms (the objective is the mean DC power over \
         its last {} s, after a pre-roll of {} s, the longest any design of the ranges needs; \
         the same record for every design: the objective is deterministic, so the answer needs \
         no confirmation on fresh seeds)",
        fmt_sig(rms_g, 4),
        fmt_sig(r.analysed_s(), 4),
        fmt_sig(r.transient_s, 4)
    )
}
