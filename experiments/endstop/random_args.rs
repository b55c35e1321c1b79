//! The arguments of `endstop random` and its measured drive: a record read from a file,
//! checked against the band the device needs and resampled before anything is written.

use std::path::PathBuf;
use std::sync::Arc;

use anyhow::{bail, Result};
use clap::Parser;
use endstop::device::Device;
use endstop::drive::measured::MeasuredRecord;
use endstop::drive::swept_sine_samples;
use endstop::study::record::transient_s;
use endstop::G;
use endstop_experiments::fmt_sig;
use endstop_experiments::reports::measured_io;
use endstop_experiments::time_split::TimeSplit;

/// The arguments of `endstop random`.
#[derive(Parser, Debug)]
pub struct RandomArgs {
    /// Device file (TOML), e.g. a copy of data/prototype2.toml or of a file in data/examples/.
    #[arg(long)]
    pub(crate) device: PathBuf,
    /// Two-sided acceleration PSD of the white noise in its flat band (g^2/Hz); or give
    /// --accel-file instead.
    #[arg(
        long,
        required_unless_present_any = ["accel_file", "sine_g"],
        conflicts_with_all = ["accel_file", "sine_g"],
        allow_hyphen_values = true
    )]
    pub(crate) psd: Option<f64>,
    /// A sine drive instead of noise: its peak acceleration (g), `a(t) = A g sin(2 pi f t)`
    /// from rest, with --freq-hz, sampled at --sample-rate-hz for the pre-roll (as for
    /// --accel-file) and then --duration-s analysed; its outputs are --accel-file's.
    #[arg(
        long,
        requires = "freq_hz",
        conflicts_with = "accel_file",
        allow_hyphen_values = true
    )]
    pub(crate) sine_g: Option<f64>,
    /// The sine drive's frequency (Hz), with --sine-g.
    #[arg(long, requires = "sine_g", allow_hyphen_values = true)]
    pub(crate) freq_hz: Option<f64>,
    /// A linear chirp instead of a steady sine, with --sine-g: the sine holds --freq-hz through
    /// the pre-roll and then sweeps linearly to this frequency (Hz) over --duration-s, at a
    /// continuous phase.
    #[arg(long, requires = "sine_g", allow_hyphen_values = true)]
    pub(crate) chirp_to_hz: Option<f64>,
    /// A measured acceleration record to drive the device with instead of noise: a CSV file
    /// whose header names a time column (`time_s` or `time_ms`) and an acceleration column
    /// (`accel_m_per_s2` or `accel_g`), or a mono WAV file with --accel-scale. It is checked
    /// (uniform time, finite values, long enough for the band), resampled to
    /// --sample-rate-hz, and its first pre-roll (five ring-up times 2m/b; behind an interface
    /// circuit at least five storage time constants R C_s) is discarded.
    #[arg(long)]
    pub(crate) accel_file: Option<PathBuf>,
    /// The acceleration of a WAV file's full scale (m/s^2); a WAV file carries no unit.
    #[arg(long, allow_hyphen_values = true)]
    pub(crate) accel_scale: Option<f64>,
    /// The integrator's sample rate for a measured record (Hz).
    #[arg(long, default_value_t = 100e3, allow_hyphen_values = true)]
    pub(crate) sample_rate_hz: f64,
    /// The band a measured record must carry, `LO,HI` in Hz (default: the analysis band, a
    /// quarter to four times the device's open-circuit resonance).
    #[arg(long, value_delimiter = ',', num_args = 2, allow_hyphen_values = true)]
    pub(crate) band_hz: Option<Vec<f64>>,
    /// Number of independent noise records (their mean and 95 % interval are reported).
    #[arg(long, default_value_t = 4)]
    pub(crate) records: usize,
    /// Length of each noise record, or of a sine drive's analysed record (s).
    #[arg(long, default_value_t = 10.0, allow_hyphen_values = true)]
    pub(crate) duration_s: f64,
    /// Seed of the random streams (record i uses stream i).
    #[arg(long, default_value_t = 2012)]
    pub(crate) seed: u64,
    /// Bias voltage (V) of an electrostatic transducer; default: the device file's.
    #[arg(long, allow_hyphen_values = true)]
    pub(crate) bias_v: Option<f64>,
    /// Output directory; default: data/results/endstop-random.
    #[arg(long)]
    pub(crate) out: Option<PathBuf>,
}

impl RandomArgs {
    /// Checks the noise ensemble's arguments (`--psd`, `--records`, `--duration-s`).
    pub(crate) fn check_noise(&self, psd: f64) -> Result<()> {
        if !(psd.is_finite() && psd > 0.0) {
            bail!("--psd = {psd}: must be a finite positive two-sided PSD in g^2/Hz");
        }
        if self.records == 0 {
            bail!("--records = 0: must be at least 1");
        }
        if !(self.duration_s.is_finite() && self.duration_s > 0.0) {
            bail!("--duration-s = {}: must be finite and > 0", self.duration_s);
        }
        Ok(())
    }
}

/// The most samples a resampled measured record may have.
const MAX_RESAMPLED: usize = 1 << 27;

/// A measured record read, checked against the band the device needs, and resampled to the
/// integrator's rate, before anything is written.
pub(crate) struct MeasuredDrive {
    /// The record as read.
    pub(crate) rec: endstop::drive::measured::MeasuredRecord,
    /// The resampled acceleration (m/s^2).
    pub(crate) accel: Arc<[f64]>,
    /// The integrator's sample rate (Hz).
    pub(crate) fs: f64,
    /// Samples of the pre-roll.
    pub(crate) n_tr: usize,
    /// The pre-roll (s): the device's (`endstop::study::record::transient_s`).
    pub(crate) preroll_s: f64,
    /// The analysis band (Hz).
    pub(crate) band_hz: (f64, f64),
    /// The run's time so far: reading and resampling.
    pub(crate) times: TimeSplit,
}

/// The sine drive of `--sine-g` and `--freq-hz` for `device` (swept to `--chirp-to-hz` after
/// the pre-roll, if given): the device's pre-roll and then `--duration-s`, sampled at
/// `--sample-rate-hz`.
fn sine_record(a: &RandomArgs, device: &Device, amplitude_g: f64) -> Result<MeasuredRecord> {
    let freq_hz = a.freq_hz.unwrap_or(f64::NAN);
    if !(amplitude_g.is_finite() && freq_hz.is_finite() && freq_hz > 0.0) {
        bail!("--sine-g = {amplitude_g}, --freq-hz = {freq_hz}: must be finite, the frequency > 0");
    }
    let to_hz = a.chirp_to_hz.unwrap_or(freq_hz);
    if !(to_hz.is_finite() && to_hz > 0.0) {
        bail!("--chirp-to-hz = {to_hz}: must be finite and > 0");
    }
    if !(a.duration_s.is_finite() && a.duration_s > 0.0) {
        bail!("--duration-s = {}: must be finite and > 0", a.duration_s);
    }
    let fs = a.sample_rate_hz;
    let preroll_s = transient_s(device);
    let samples = ((preroll_s + a.duration_s) * fs).round();
    if samples >= MAX_RESAMPLED as f64 {
        bail!("--duration-s = {} at --sample-rate-hz = {fs}: must give at most {MAX_RESAMPLED} samples", a.duration_s);
    }
    let hold = (preroll_s * fs).round() as usize;
    let accel = swept_sine_samples(amplitude_g * G, freq_hz, to_hz, fs, hold, samples as usize);
    let name = match a.chirp_to_hz {
        Some(to) => format!(
            "sine {} g at {} Hz, swept linearly to {} Hz",
            fmt_sig(amplitude_g, 6),
            fmt_sig(freq_hz, 6),
            fmt_sig(to, 6)
        ),
        None => format!(
            "sine {} g at {} Hz",
            fmt_sig(amplitude_g, 6),
            fmt_sig(freq_hz, 6)
        ),
    };
    Ok(MeasuredRecord::from_uniform(&name, fs, accel)?)
}

/// Reads `path` as `--accel-file` for `device` (the file of `a`, as loaded), or without a path
/// makes the sine of `--sine-g`, checks it and resamples it.
pub(crate) fn read_measured(
    a: &RandomArgs,
    device: &Device,
    path: Option<&std::path::Path>,
) -> Result<MeasuredDrive> {
    let fs = a.sample_rate_hz;
    if !(fs.is_finite() && fs > 0.0) {
        bail!("--sample-rate-hz = {fs}: must be finite and > 0");
    }
    // Read and check everything before the experiment starts, so that nothing is written for
    // a bad record.
    let mut times = TimeSplit::start();
    let rec = match (path, a.sine_g) {
        (Some(path), _) => measured_io::read_record(path, a.accel_scale)?,
        (None, Some(g)) => sine_record(a, device, g)?,
        (None, None) => bail!("give --accel-file or --sine-g"),
    };
    let preroll_s = transient_s(device);
    let f0 = endstop::physics::linear::open_circuit_resonance_hz(device);
    let (lo, hi) = match a.band_hz.as_deref() {
        Some([lo, hi]) => (*lo, *hi),
        _ => (0.25 * f0, (4.0 * f0).min(0.45 * fs)),
    };
    if hi > 0.45 * fs {
        bail!(
            "--band-hz upper edge {hi} Hz: must be at most {} Hz (0.45 of --sample-rate-hz)",
            0.45 * fs
        );
    }
    rec.check_band(lo, hi, preroll_s)?;
    // The resampled record and the response are held in memory: at most 2^27 samples (1 GiB
    // per signal).
    let samples = rec.duration_s() * fs;
    if samples > MAX_RESAMPLED as f64 {
        bail!(
            "{}: --sample-rate-hz = {fs} gives {samples:.0} samples over the record's {} s: must \
             give at most {MAX_RESAMPLED}",
            rec.source_name,
            fmt_sig(rec.duration_s(), 6)
        );
    }
    times.lap("reading");
    let accel: Arc<[f64]> = rec.resampled(fs);
    times.lap("resampling");
    let n_tr = (preroll_s * fs).round() as usize;
    Ok(MeasuredDrive {
        rec,
        accel,
        fs,
        n_tr,
        preroll_s,
        band_hz: (lo, hi),
        times,
    })
}
