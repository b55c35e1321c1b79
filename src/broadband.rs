//! Broadband (random-vibration) studies: records, output power spectra, ensembles and
//! bandwidths (SPEC 5; the paper's Figures 10, 11, 12, 14 and 15, and eq 21).
//!
//! # One record
//! [`simulate_record`] drives the lumped model of eq 7 with one realisation of band-limited
//! white noise from [`crate::noise::generate`] (two-sided level `Sa`, 10 kHz band, 100 kHz,
//! SPEC 5), read between samples by linear interpolation ([`crate::excitation::Sampled`]), and
//! integrates it with [`crate::integrator::Dopri5`] from rest. Every sample instant is a
//! breakpoint of the integrator, so the steps end on the sample instants and the node voltages
//! V1, V2 are collected there without interpolation.
//!
//! **Transient.** The model starts at rest, so its response needs a few mechanical ring-up
//! times `2m/b` (the amplitude decay time of the unloaded resonator, an upper bound on that of
//! the loaded one) to become stationary. The record is therefore preceded by a pre-roll of
//! [`TRANSIENT_RING_TIMES`] ring-up times (rounded up to a whole millisecond) drawn from the
//! same noise realisation and discarded: 0.48 s for prototype 2 (`2m/b` = 96 ms), 8 ms for
//! prototype 1 (1.5 ms). The *analysed* record that follows has the paper's length (10 s), so a
//! single-record estimate has the same statistics as the paper's. After five ring-up times the
//! remaining amplitude deficit is below e^-5 = 0.7 %.
//!
//! # Output power spectral density
//! [`output_psd`] is the one-sided Welch estimate ([`crate::spectral::welch`], periodic Hann,
//! 50 % overlap, density scaling) of both load voltages, divided by the load:
//! `S_P(f) = (S_V1(f) + S_V2(f)) / RL` in W/Hz, so that its integral over `f >= 0` is the mean
//! power of **both loads** (the power of eq 21). The per-load densities are kept beside it.
//!
//! # Efficiency
//! `2P/(m Sa)` with `P` the mean power of both loads and `Sa` the **two-sided** acceleration PSD
//! in SI units (`Sa_g2 * 9.81^2`), the input power being `m Sa / 2` (eq 21 and its reference).
//! [`eq21_power_w`] gives the linear theory with `Qm = sqrt(K m)/b`
//! ([`crate::linear::QmReading::OpenCircuit`]), the reading eq 21 is derived with.
//!
//! # Ensembles
//! Every excitation level is an ensemble of independent records: realisation `i` uses ChaCha8
//! stream `first_stream + i` of a fixed seed (so results do not depend on thread scheduling),
//! and [`run_ensembles`] runs all records of all levels in parallel with rayon. Means carry a
//! 95 % confidence interval from Student's t with `n - 1` degrees of freedom ([`MeanCi`]).
//!
//! # Bandwidths
//! [`Widths`] holds the width of the output power PSD at half its peak (3 dB, half power; the
//! default reading of "3 dB bandwidth") and at a quarter of its peak (half amplitude, -6 dB of
//! power), both from [`crate::spectral::width_at_fraction`] searched inside the ensemble's
//! analysis band. They are computed on the ensemble-averaged PSD and on every single record;
//! [`Spread`] summarises the sampling distribution of a single-record estimate (the paper
//! used one 10 s record per level), and [`ratio_spread`] that of a ratio of two of them. The
//! width of the ensemble-mean PSD carries a delete-one jackknife interval
//! ([`Ensemble::mean_width`], [`JackknifeWidth`]).
//!
//! # Linear theory
//! [`linear_output_psd_w_per_hz`] is the small-signal output PSD of the same model (eqs 7-17
//! in the frequency domain, no end-stops); it integrates to eq 21 and gives the bandwidth the
//! device has without impacts ([`linear_widths`]).
//!
//! # Protocols
//! The levels, record counts, Welch settings and the rules behind the claims of Figures 11-15
//! ([`FIG15_LEVELS`], [`protocol_spec`], [`pooled_efficiency`], [`sublinear_growth`],
//! [`edge_shifts`], ...) live here, so the experiments and the tests compute the same numbers
//! from the same records.

use std::sync::Arc;

use rayon::prelude::*;
use thiserror::Error;

use crate::excitation::Sampled;
use crate::integrator::{Dopri5, SolverError, Stats};
use crate::linear::{QmReading, TwoPort};
use crate::model::{Harvester, Mode};
use crate::noise::{self, NoiseError, NoiseSpec};
use crate::params::Device;
use crate::spectral::{self, Bandwidth, Psd, SpectralError, WelchConfig};
use crate::G;

/// Length of the discarded pre-roll in mechanical ring-up times `2m/b` (see the module docs).
pub const TRANSIENT_RING_TIMES: f64 = 5.0;

/// Default relative tolerance of the integrator for random records. In free flight the step
/// is bounded by the 10 us sample interval, not by this tolerance; the tests show that the
/// mean power changes by far less than the ensemble error when it is tightened.
pub const DEFAULT_RTOL: f64 = 1e-7;

/// Errors of a broadband simulation.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum BroadbandError {
    /// The excitation could not be generated.
    #[error("excitation: {0}")]
    Noise(#[from] NoiseError),
    /// The integrator failed.
    #[error("integration: {0}")]
    Solver(#[from] SolverError),
    /// The spectral estimate could not be formed.
    #[error("spectrum: {0}")]
    Spectral(#[from] SpectralError),
    /// A setting is out of range.
    #[error("broadband spec: {field} = {value} is invalid; expected {expected}")]
    InvalidSpec {
        /// Name of the setting.
        field: &'static str,
        /// Its value.
        value: f64,
        /// The valid range.
        expected: &'static str,
    },
}

/// Mechanical ring-up time `2m/b` of a device (s): the amplitude decay time of the unloaded
/// resonator (SPEC 8: about 0.1 s for prototype 2).
pub fn ring_up_time_s(device: &Device) -> f64 {
    2.0 * device.mechanics.mass_kg / device.mechanics.damping_n_s_per_m
}

/// The discarded pre-roll of a device: [`TRANSIENT_RING_TIMES`] ring-up times, rounded up to a
/// whole millisecond (s).
pub fn transient_s(device: &Device) -> f64 {
    (TRANSIENT_RING_TIMES * ring_up_time_s(device) * 1e3 - 1e-9).ceil() / 1e3
}

/// Settings of one random-vibration record.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RecordSpec {
    /// The analysed excitation: two-sided level `Sa` (g²/Hz), band, sample rate and the
    /// **analysed** duration (the paper: 10 s).
    pub noise: NoiseSpec,
    /// Pre-roll simulated from rest before the analysed record and discarded (s); it is
    /// rounded to a whole number of samples.
    pub transient_s: f64,
    /// Relative tolerance of the integrator.
    pub rtol: f64,
}

impl RecordSpec {
    /// The paper's record (SPEC 5: 10 kHz band, 100 kHz, 10 s analysed) at level
    /// `psd_g2_per_hz`, with the device's pre-roll ([`transient_s`]) and [`DEFAULT_RTOL`].
    pub fn paper(device: &Device, psd_g2_per_hz: f64) -> Self {
        Self {
            noise: NoiseSpec::paper(psd_g2_per_hz),
            transient_s: transient_s(device),
            rtol: DEFAULT_RTOL,
        }
    }

    /// Samples of the pre-roll, `round(transient_s * fs)`.
    pub fn transient_samples(&self) -> usize {
        (self.transient_s * self.noise.sample_rate_hz).round() as usize
    }

    /// Samples of the analysed record, `round(duration_s * fs)`.
    pub fn analysed_samples(&self) -> usize {
        self.noise.n_samples()
    }

    /// The generated excitation: pre-roll plus analysed record, one noise realisation.
    pub fn generated_noise(&self) -> NoiseSpec {
        let n = self.transient_samples() + self.analysed_samples();
        NoiseSpec {
            duration_s: n as f64 / self.noise.sample_rate_hz,
            ..self.noise
        }
    }

    fn validate(&self) -> Result<(), BroadbandError> {
        self.noise.validate()?;
        if !(self.transient_s.is_finite() && self.transient_s >= 0.0) {
            return Err(BroadbandError::InvalidSpec {
                field: "transient_s",
                value: self.transient_s,
                expected: "a finite number >= 0",
            });
        }
        if !(self.rtol.is_finite() && self.rtol > 0.0 && self.rtol < 1.0) {
            return Err(BroadbandError::InvalidSpec {
                field: "rtol",
                value: self.rtol,
                expected: "0 < rtol < 1",
            });
        }
        Ok(())
    }
}

/// Scalar results of one record, over the analysed window (after the pre-roll).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RecordSummary {
    /// Mean power in load 1, `<V1²>/RL` over the samples (W).
    pub p1_w: f64,
    /// Mean power in load 2 (W).
    pub p2_w: f64,
    /// RMS displacement over the samples (m).
    pub x_rms_m: f64,
    /// Largest |x| at the ends of the integrator's steps (which include every contact event) (m).
    pub x_peak_m: f64,
    /// Fraction of the analysed time spent past a stop (eq 2: delta > 0).
    pub contact_fraction: f64,
    /// Contact entries (impacts) in the analysed window.
    pub impacts: u64,
    /// Mean square of the applied acceleration over the analysed samples (m²/s⁴); its
    /// expectation is `2 B Sa` (SPEC 5).
    pub accel_mean_square_si: f64,
    /// Integrator counters for the whole record (pre-roll included).
    pub stats: Stats,
}

impl RecordSummary {
    /// Mean power of both loads (W), the `P` of eq 21.
    pub fn p_total_w(&self) -> f64 {
        self.p1_w + self.p2_w
    }
}

/// One simulated record: the node voltages at the analysed sample instants and its summary.
#[derive(Debug, Clone, PartialEq)]
pub struct Record {
    /// Sample rate of `v1_v`, `v2_v` (Hz).
    pub sample_rate_hz: f64,
    /// V1 at `t = transient + k / fs`, `k = 0 .. N` (V).
    pub v1_v: Vec<f64>,
    /// V2 at the same instants (V).
    pub v2_v: Vec<f64>,
    /// Scalar results.
    pub summary: RecordSummary,
}

/// Simulates one record: realisation `stream` of seed `seed` of the excitation `spec` drives
/// `device` (eq 7 with the end-stop of eq 1) from rest; see the module docs.
///
/// The only allocations are the excitation and the two output vectors; the per-sample loop
/// calls the integrator up to the next sample instant (a breakpoint) and stores V1, V2 there.
pub fn simulate_record(
    device: &Device,
    spec: &RecordSpec,
    seed: u64,
    stream: u64,
) -> Result<Record, BroadbandError> {
    spec.validate()?;
    let gen = spec.generated_noise();
    let accel: Arc<[f64]> = noise::generate(&gen, seed, stream)?.into();
    let fs = gen.sample_rate_hz;
    let n_tr = spec.transient_samples();
    let n = spec.analysed_samples();
    let excitation = Sampled::new(accel.clone(), fs);
    let model = Harvester::new(device, excitation);
    let dt = model.excitation.dt_s;
    let t_start = model.excitation.time_of(n_tr);

    let mut ode = Dopri5::new(
        0.0,
        model.rest_state(),
        Mode::Free,
        model.solver_options(spec.rtol),
    );
    let mut v1 = Vec::with_capacity(n);
    let mut v2 = Vec::with_capacity(n);
    let (mut contact_time, mut impacts, mut x_peak) = (0.0f64, 0u64, 0.0f64);
    let mut in_contact = false;
    let (mut sx2, mut sa2) = (0.0f64, 0.0f64);

    for k in 0..n_tr + n {
        let t_k = model.excitation.time_of(k);
        if k > 0 {
            ode.integrate(&model, t_k, |step, mode| {
                let now = mode.in_contact();
                if step.t0 >= t_start - 0.5 * dt {
                    if now {
                        contact_time += step.h;
                        if !in_contact {
                            impacts += 1;
                        }
                    }
                    x_peak = x_peak.max(step.y1[0].abs());
                }
                in_contact = now;
            })?;
        }
        if k >= n_tr {
            let el = model.electrical(&ode.y);
            v1.push(el.v[0]);
            v2.push(el.v[1]);
            sx2 += ode.y[0] * ode.y[0];
            sa2 += accel[k] * accel[k];
        }
    }

    let nf = n as f64;
    let rl = model.rl;
    let p1_w = v1.iter().map(|v| v * v).sum::<f64>() / nf / rl;
    let p2_w = v2.iter().map(|v| v * v).sum::<f64>() / nf / rl;
    let duration = (n.saturating_sub(1)) as f64 * dt;
    let summary = RecordSummary {
        p1_w,
        p2_w,
        x_rms_m: (sx2 / nf).sqrt(),
        x_peak_m: x_peak,
        contact_fraction: if duration > 0.0 {
            contact_time / duration
        } else {
            0.0
        },
        impacts,
        accel_mean_square_si: sa2 / nf,
        stats: ode.stats,
    };
    Ok(Record {
        sample_rate_hz: fs,
        v1_v: v1,
        v2_v: v2,
        summary,
    })
}

/// Output power spectral density of both loads and of each, one-sided, W/Hz.
#[derive(Debug, Clone, PartialEq)]
pub struct OutputSpectrum {
    /// `(S_V1 + S_V2) / RL`: its integral is the mean power of both loads.
    pub total: Psd,
    /// `S_V1 / RL`.
    pub load1: Psd,
    /// `S_V2 / RL`.
    pub load2: Psd,
}

impl OutputSpectrum {
    /// The bins with `f_lo <= f <= f_hi` of each density.
    pub fn restrict(&self, f_lo: f64, f_hi: f64) -> Self {
        Self {
            total: restrict(&self.total, f_lo, f_hi),
            load1: restrict(&self.load1, f_lo, f_hi),
            load2: restrict(&self.load2, f_lo, f_hi),
        }
    }
}

/// One-sided Welch estimate of the output power PSD of both loads, `(S_V1 + S_V2)/RL` (W/Hz),
/// and of each load (see the module docs).
pub fn output_psd(
    v1_v: &[f64],
    v2_v: &[f64],
    sample_rate_hz: f64,
    load_resistance_ohm: f64,
    cfg: &WelchConfig,
) -> Result<OutputSpectrum, SpectralError> {
    let scale = |mut p: Psd| {
        p.density.iter_mut().for_each(|d| *d /= load_resistance_ohm);
        p
    };
    let load1 = scale(spectral::welch(v1_v, sample_rate_hz, cfg)?);
    let load2 = scale(spectral::welch(v2_v, sample_rate_hz, cfg)?);
    let total = Psd {
        freq_hz: load1.freq_hz.clone(),
        density: load1
            .density
            .iter()
            .zip(&load2.density)
            .map(|(a, b)| a + b)
            .collect(),
        segments: load1.segments,
    };
    Ok(OutputSpectrum {
        total,
        load1,
        load2,
    })
}

/// The bins of `psd` with `f_lo <= f <= f_hi`.
pub fn restrict(psd: &Psd, f_lo: f64, f_hi: f64) -> Psd {
    let (freq_hz, density) = psd
        .freq_hz
        .iter()
        .zip(&psd.density)
        .filter(|(f, _)| (f_lo..=f_hi).contains(*f))
        .map(|(f, d)| (*f, *d))
        .unzip();
    Psd {
        freq_hz,
        density,
        segments: psd.segments,
    }
}

/// Welch segment length for MATLAB's `pwelch` default: eight segments with 50 % overlap,
/// `floor(N / 4.5)` samples each (MATLAB also zero-pads to a power of two and uses a Hamming
/// window; we keep our Hann window and no padding, so only the segmenting is MATLAB's).
pub fn matlab_default_nperseg(len: usize) -> usize {
    (len as f64 / 4.5).floor() as usize
}

/// Widths of an output power PSD around its peak (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Widths {
    /// Band where the PSD is at least half its peak: the 3 dB (half-power) bandwidth.
    pub half_power: Option<Bandwidth>,
    /// Band where the PSD is at least a quarter of its peak: the half-amplitude (-6 dB) width.
    pub half_amplitude: Option<Bandwidth>,
}

impl Widths {
    /// Widths of `psd` (searched over all its bins; restrict it first to the analysis band).
    pub fn of(psd: &Psd) -> Self {
        Self {
            half_power: spectral::width_at_fraction(psd, 0.5),
            half_amplitude: spectral::width_at_fraction(psd, 0.25),
        }
    }

    /// 3 dB width (Hz), NaN if undetermined.
    pub fn bw3db_hz(&self) -> f64 {
        self.half_power.map_or(f64::NAN, |b| b.width_hz)
    }

    /// Half-amplitude width (Hz), NaN if undetermined.
    pub fn bw6db_hz(&self) -> f64 {
        self.half_amplitude.map_or(f64::NAN, |b| b.width_hz)
    }
}

/// Settings of an ensemble at one excitation level.
#[derive(Debug, Clone, PartialEq)]
pub struct EnsembleSpec {
    /// The record.
    pub record: RecordSpec,
    /// Welch segmenting of the output PSD.
    pub welch: WelchConfig,
    /// A second segmenting whose single-record widths are reported beside (e.g. MATLAB's
    /// default of eight segments, [`matlab_default_nperseg`]).
    pub alt_welch: Option<WelchConfig>,
    /// Band (Hz) in which spectra are kept and bandwidths are searched.
    pub analysis_band_hz: (f64, f64),
    /// ChaCha8 seed of the excitation.
    pub seed: u64,
    /// Stream of realisation 0; realisation `i` uses `first_stream + i`.
    pub first_stream: u64,
    /// Number of independent records.
    pub realisations: usize,
}

/// One record of an ensemble, analysed (the voltages themselves are not kept).
#[derive(Debug, Clone, PartialEq)]
pub struct RecordResult {
    /// Its ChaCha8 stream.
    pub stream: u64,
    /// Scalar results.
    pub summary: RecordSummary,
    /// Output power PSD restricted to the analysis band (W/Hz).
    pub spectrum: OutputSpectrum,
    /// Widths of `spectrum.total`.
    pub widths: Widths,
    /// Output power PSD of both loads with the alternative segmenting, restricted to the
    /// analysis band, and its widths.
    pub alt: Option<(Psd, Widths)>,
}

/// Mean of a sample with a 95 % confidence interval (Student's t, `n - 1` degrees of freedom).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeanCi {
    /// Sample mean.
    pub mean: f64,
    /// Sample standard deviation (n - 1 in the denominator); NaN for n < 2.
    pub std: f64,
    /// Half-width of the 95 % confidence interval of the mean, `t_{0.975, n-1} std / sqrt(n)`;
    /// NaN for n < 2.
    pub ci95: f64,
    /// Sample size.
    pub n: usize,
}

impl MeanCi {
    /// Statistics of the finite values of `xs`.
    pub fn of(xs: &[f64]) -> Self {
        let v: Vec<f64> = xs.iter().copied().filter(|x| x.is_finite()).collect();
        let n = v.len();
        if n == 0 {
            return Self {
                mean: f64::NAN,
                std: f64::NAN,
                ci95: f64::NAN,
                n,
            };
        }
        let mean = v.iter().sum::<f64>() / n as f64;
        if n < 2 {
            return Self {
                mean,
                std: f64::NAN,
                ci95: f64::NAN,
                n,
            };
        }
        let var = v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1) as f64;
        let std = var.sqrt();
        Self {
            mean,
            std,
            ci95: student_t_975(n - 1) * std / (n as f64).sqrt(),
            n,
        }
    }
}

/// The 97.5 % quantile of Student's t with `dof` degrees of freedom (two-sided 95 %).
///
/// Tabulated to 4 digits for `dof <= 30`; above, the Cornish-Fisher expansion in `1/dof`
/// about the normal quantile 1.959964 (error below 1e-5 there). NaN for `dof = 0`.
pub fn student_t_975(dof: usize) -> f64 {
    const TABLE: [f64; 30] = [
        12.7062, 4.3027, 3.1824, 2.7764, 2.5706, 2.4469, 2.3646, 2.3060, 2.2622, 2.2281, 2.2010,
        2.1788, 2.1604, 2.1448, 2.1314, 2.1199, 2.1098, 2.1009, 2.0930, 2.0860, 2.0796, 2.0739,
        2.0687, 2.0639, 2.0595, 2.0555, 2.0518, 2.0484, 2.0452, 2.0423,
    ];
    match dof {
        0 => f64::NAN,
        1..=30 => TABLE[dof - 1],
        _ => {
            let z: f64 = 1.959_963_984_540_054;
            let v = dof as f64;
            let (z3, z5, z7, z9) = (z.powi(3), z.powi(5), z.powi(7), z.powi(9));
            z + (z3 + z) / (4.0 * v)
                + (5.0 * z5 + 16.0 * z3 + 3.0 * z) / (96.0 * v * v)
                + (3.0 * z7 + 19.0 * z5 + 17.0 * z3 - 15.0 * z) / (384.0 * v.powi(3))
                + (79.0 * z9 + 776.0 * z7 + 1482.0 * z5 - 1920.0 * z3 - 945.0 * z)
                    / (92160.0 * v.powi(4))
        }
    }
}

/// Sampling distribution of a single-record estimate: mean, standard deviation and the 5 % and
/// 95 % empirical quantiles (linear interpolation between order statistics), over the finite
/// values; `undetermined` counts the records where the estimate did not exist.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spread {
    /// Mean of the finite values.
    pub mean: f64,
    /// Standard deviation (n - 1).
    pub std: f64,
    /// 5 % quantile.
    pub p05: f64,
    /// 95 % quantile.
    pub p95: f64,
    /// Median.
    pub median: f64,
    /// Number of finite values.
    pub n: usize,
    /// Number of non-finite values (e.g. an undetermined band edge).
    pub undetermined: usize,
}

impl Spread {
    /// The distribution of `xs`.
    pub fn of(xs: &[f64]) -> Self {
        let mut v: Vec<f64> = xs.iter().copied().filter(|x| x.is_finite()).collect();
        v.sort_by(|a, b| a.total_cmp(b));
        let m = MeanCi::of(&v);
        Self {
            mean: m.mean,
            std: m.std,
            p05: quantile(&v, 0.05),
            p95: quantile(&v, 0.95),
            median: quantile(&v, 0.5),
            n: v.len(),
            undetermined: xs.len() - v.len(),
        }
    }
}

/// Quantile of sorted data by linear interpolation between order statistics (the default of
/// numpy.quantile); NaN for empty data.
fn quantile(sorted: &[f64], q: f64) -> f64 {
    match sorted.len() {
        0 => f64::NAN,
        1 => sorted[0],
        n => {
            let pos = q * (n - 1) as f64;
            let i = pos.floor() as usize;
            let j = (i + 1).min(n - 1);
            sorted[i] + (pos - i as f64) * (sorted[j] - sorted[i])
        }
    }
}

/// An ensemble at one excitation level, analysed.
#[derive(Debug, Clone, PartialEq)]
pub struct Ensemble {
    /// The settings.
    pub spec: EnsembleSpec,
    /// Every record, in stream order.
    pub records: Vec<RecordResult>,
    /// Ensemble average of the records' Welch estimates (analysis band, W/Hz).
    pub mean_spectrum: OutputSpectrum,
    /// Widths of the ensemble-averaged PSD of both loads.
    pub mean_widths: Widths,
    /// Mean power of both loads (W).
    pub power_w: MeanCi,
    /// Mean power of load 1 (W).
    pub p1_w: MeanCi,
    /// Mean power of load 2 (W).
    pub p2_w: MeanCi,
    /// Efficiency `2P/(m Sa)` per record (fraction).
    pub efficiency: MeanCi,
    /// RMS displacement (m).
    pub x_rms_m: MeanCi,
    /// Fraction of time in contact.
    pub contact_fraction: MeanCi,
    /// Largest |x| over all records (m).
    pub x_peak_m: f64,
    /// Impacts over all records.
    pub impacts: u64,
    /// Integrator counters summed over the records.
    pub stats: Stats,
}

impl Ensemble {
    /// Two-sided acceleration PSD of the level (g²/Hz).
    pub fn psd_g2_per_hz(&self) -> f64 {
        self.spec.record.noise.psd_g2_per_hz
    }

    /// Single-record 3 dB widths (Hz; NaN where undetermined), in stream order.
    pub fn single_bw3db_hz(&self) -> Vec<f64> {
        self.records.iter().map(|r| r.widths.bw3db_hz()).collect()
    }

    /// Single-record half-amplitude widths (Hz).
    pub fn single_bw6db_hz(&self) -> Vec<f64> {
        self.records.iter().map(|r| r.widths.bw6db_hz()).collect()
    }

    /// Single-record 3 dB widths with the alternative segmenting (Hz).
    pub fn single_alt_bw3db_hz(&self) -> Vec<f64> {
        self.records
            .iter()
            .map(|r| r.alt.as_ref().map_or(f64::NAN, |a| a.1.bw3db_hz()))
            .collect()
    }

    /// Sampling distribution of the single-record 3 dB width.
    pub fn single_bw3db_spread(&self) -> Spread {
        Spread::of(&self.single_bw3db_hz())
    }

    /// Sampling distribution of the single-record half-amplitude width.
    pub fn single_bw6db_spread(&self) -> Spread {
        Spread::of(&self.single_bw6db_hz())
    }

    /// Single-record peak frequencies of the output PSD of both loads (Hz).
    pub fn single_peak_hz(&self) -> Vec<f64> {
        self.records
            .iter()
            .map(|r| r.spectrum.total.peak().0)
            .collect()
    }

    /// Width of the ensemble-averaged PSD of both loads at `fraction` of its peak (0.5: 3 dB),
    /// with its delete-one jackknife uncertainty over the records (see [`JackknifeWidth`]).
    pub fn mean_width(&self, fraction: f64) -> JackknifeWidth {
        let est = spectral::width_at_fraction(&self.mean_spectrum.total, fraction)
            .map_or(f64::NAN, |b| b.width_hz);
        let n = self.records.len();
        if n < 2 {
            return JackknifeWidth {
                width_hz: est,
                se_hz: f64::NAN,
                ci95_hz: f64::NAN,
                n,
            };
        }
        let sum = &self.mean_spectrum.total;
        let mut loo = Vec::with_capacity(n);
        let mut p = sum.clone();
        for r in &self.records {
            for ((d, m), x) in p
                .density
                .iter_mut()
                .zip(&sum.density)
                .zip(&r.spectrum.total.density)
            {
                *d = (n as f64 * m - x) / (n - 1) as f64;
            }
            loo.push(spectral::width_at_fraction(&p, fraction).map_or(f64::NAN, |b| b.width_hz));
        }
        let mean = loo.iter().sum::<f64>() / n as f64;
        let se = ((n - 1) as f64 / n as f64 * loo.iter().map(|w| (w - mean).powi(2)).sum::<f64>())
            .sqrt();
        JackknifeWidth {
            width_hz: est,
            se_hz: se,
            ci95_hz: student_t_975(n - 1) * se,
            n,
        }
    }

    /// True if no record of the ensemble touched a stop.
    pub fn no_impact(&self) -> bool {
        self.impacts == 0
    }
}

/// The width of an ensemble-averaged PSD with a delete-one jackknife standard error: the
/// width is recomputed from the mean of the records without record `i`, for each `i`, and
/// `se = sqrt((n-1)/n sum (w_(i) - mean w_(.))²)`; `ci95 = t_{0.975, n-1} se`. A NaN `se`
/// means a delete-one width was undetermined.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JackknifeWidth {
    /// Width of the full ensemble's mean PSD (Hz).
    pub width_hz: f64,
    /// Jackknife standard error (Hz).
    pub se_hz: f64,
    /// Half-width of the 95 % confidence interval (Hz).
    pub ci95_hz: f64,
    /// Records.
    pub n: usize,
}

impl JackknifeWidth {
    /// The ratio `self / other` of two widths from independent ensembles, with the 95 %
    /// half-width propagated in relative terms:
    /// `ci(r)/r = sqrt((ci_a/a)² + (ci_b/b)²)`.
    pub fn ratio(&self, other: &JackknifeWidth) -> (f64, f64) {
        let r = self.width_hz / other.width_hz;
        let rel = ((self.ci95_hz / self.width_hz).powi(2)
            + (other.ci95_hz / other.width_hz).powi(2))
        .sqrt();
        (r, r * rel)
    }
}

/// Sampling distribution of the ratio `w_a / w_b` of two single-record widths, one record from
/// each ensemble, over **all** pairs `(i, j)` (the records are independent, so every pair is a
/// draw of what one record per level, as in the paper, would give). Non-finite widths are
/// counted as undetermined.
pub fn ratio_spread(w_a: &[f64], w_b: &[f64]) -> Spread {
    let mut r = Vec::with_capacity(w_a.len() * w_b.len());
    for a in w_a {
        for b in w_b {
            r.push(a / b);
        }
    }
    Spread::of(&r)
}

/// One level of one device, for [`run_ensembles`].
#[derive(Debug, Clone, PartialEq)]
pub struct EnsembleCase {
    /// The device (bias voltage and end-stop options included).
    pub device: Device,
    /// The ensemble.
    pub spec: EnsembleSpec,
}

/// Simulates and analyses one record of an ensemble (realisation `i`).
pub fn run_record(
    device: &Device,
    spec: &EnsembleSpec,
    i: usize,
) -> Result<RecordResult, BroadbandError> {
    let stream = spec.first_stream + i as u64;
    let rec = simulate_record(device, &spec.record, spec.seed, stream)?;
    let rl = device.electrical.load_resistance_ohm;
    let (lo, hi) = spec.analysis_band_hz;
    let spectrum =
        output_psd(&rec.v1_v, &rec.v2_v, rec.sample_rate_hz, rl, &spec.welch)?.restrict(lo, hi);
    let widths = Widths::of(&spectrum.total);
    let alt = match &spec.alt_welch {
        Some(cfg) => {
            let s = output_psd(&rec.v1_v, &rec.v2_v, rec.sample_rate_hz, rl, cfg)?;
            let t = restrict(&s.total, lo, hi);
            let w = Widths::of(&t);
            Some((t, w))
        }
        None => None,
    };
    Ok(RecordResult {
        stream,
        summary: rec.summary,
        spectrum,
        widths,
        alt,
    })
}

/// Runs every record of every case in parallel (rayon; one task per record, so that the
/// cores stay busy across levels of very different cost), calling `on_record` after each,
/// and analyses each case into an [`Ensemble`] (in the order of `cases`).
pub fn run_ensembles<F: Fn() + Sync>(
    cases: &[EnsembleCase],
    on_record: F,
) -> Result<Vec<Ensemble>, BroadbandError> {
    for c in cases {
        if c.spec.realisations == 0 {
            return Err(BroadbandError::InvalidSpec {
                field: "realisations",
                value: 0.0,
                expected: "at least 1",
            });
        }
        c.spec.record.validate()?;
    }
    let jobs: Vec<(usize, usize)> = cases
        .iter()
        .enumerate()
        .flat_map(|(c, case)| (0..case.spec.realisations).map(move |i| (c, i)))
        .collect();
    let results: Vec<RecordResult> = jobs
        .par_iter()
        .map(|&(c, i)| {
            let r = run_record(&cases[c].device, &cases[c].spec, i);
            on_record();
            r
        })
        .collect::<Result<_, _>>()?;
    let mut it = results.into_iter();
    Ok(cases
        .iter()
        .map(|case| {
            let recs: Vec<RecordResult> = it.by_ref().take(case.spec.realisations).collect();
            analyse(case, recs)
        })
        .collect())
}

/// Runs one ensemble (see [`run_ensembles`]).
pub fn run_ensemble<F: Fn() + Sync>(
    device: &Device,
    spec: &EnsembleSpec,
    on_record: F,
) -> Result<Ensemble, BroadbandError> {
    let case = EnsembleCase {
        device: device.clone(),
        spec: spec.clone(),
    };
    Ok(run_ensembles(std::slice::from_ref(&case), on_record)?.remove(0))
}

/// Element-wise mean of densities on a common grid.
fn mean_psd<'a>(psds: impl Iterator<Item = &'a Psd>) -> Psd {
    let mut out: Option<Psd> = None;
    let mut n = 0usize;
    for p in psds {
        n += 1;
        match &mut out {
            None => out = Some(p.clone()),
            Some(o) => o
                .density
                .iter_mut()
                .zip(&p.density)
                .for_each(|(a, b)| *a += b),
        }
    }
    let mut o = out.unwrap_or(Psd {
        freq_hz: Vec::new(),
        density: Vec::new(),
        segments: 0,
    });
    o.density.iter_mut().for_each(|d| *d /= n.max(1) as f64);
    o.segments *= n;
    o
}

fn analyse(case: &EnsembleCase, records: Vec<RecordResult>) -> Ensemble {
    let mean_spectrum = OutputSpectrum {
        total: mean_psd(records.iter().map(|r| &r.spectrum.total)),
        load1: mean_psd(records.iter().map(|r| &r.spectrum.load1)),
        load2: mean_psd(records.iter().map(|r| &r.spectrum.load2)),
    };
    let mean_widths = Widths::of(&mean_spectrum.total);
    let col = |f: &dyn Fn(&RecordSummary) -> f64| -> Vec<f64> {
        records.iter().map(|r| f(&r.summary)).collect()
    };
    let m = case.device.mechanics.mass_kg;
    let sa_si = case.spec.record.noise.psd_si();
    let mut stats = Stats::default();
    for r in &records {
        stats.accepted += r.summary.stats.accepted;
        stats.rejected += r.summary.stats.rejected;
        stats.rhs_evals += r.summary.stats.rhs_evals;
        stats.events += r.summary.stats.events;
    }
    Ensemble {
        spec: case.spec.clone(),
        mean_widths,
        power_w: MeanCi::of(&col(&|s| s.p_total_w())),
        p1_w: MeanCi::of(&col(&|s| s.p1_w)),
        p2_w: MeanCi::of(&col(&|s| s.p2_w)),
        efficiency: MeanCi::of(&col(&|s| 2.0 * s.p_total_w() / (m * sa_si))),
        x_rms_m: MeanCi::of(&col(&|s| s.x_rms_m)),
        contact_fraction: MeanCi::of(&col(&|s| s.contact_fraction)),
        x_peak_m: records
            .iter()
            .map(|r| r.summary.x_peak_m)
            .fold(0.0, f64::max),
        impacts: records.iter().map(|r| r.summary.impacts).sum(),
        stats,
        mean_spectrum,
        records,
    }
}

// ------------------------------------------------------------------------------------------
// Protocols of Figures 11-15: shared by the experiments and the tests, so both compute the
// same numbers from the same records. (The book includes this section between the anchors.)
// ANCHOR: protocols

/// Welch segment of prototype 1: 2^12 samples, 24.4 Hz bins at 100 kHz. Its responses are
/// broad (a linear half-power width of about 220 Hz, 9 bins, growing to some 600 Hz with
/// impacts), so short segments cost no resolution and buy 487 segments per 10 s record, which
/// keeps the flat top of the high-level spectra from being read off a noisy maximum.
pub const P1_NPERSEG: usize = 1 << 12;
/// Welch segment of prototype 2: 2^16 samples, 1.53 Hz bins at 100 kHz (its linear half-power
/// width of about 12 Hz spans some 8 bins), 29 segments per 10 s record.
pub const P2_NPERSEG: usize = 1 << 16;
/// Band in which prototype 1's spectra are kept and its bandwidths searched (Hz).
pub const P1_BAND_HZ: (f64, f64) = (200.0, 5000.0);
/// Band in which prototype 2's spectra are kept and its bandwidths searched (Hz).
pub const P2_BAND_HZ: (f64, f64) = (100.0, 3000.0);

/// Figure 11's levels (g²/Hz).
pub const FIG11_LEVELS: [f64; 3] = [4.42e-6, 1.12e-4, 3.49e-4];
/// Figure 12's levels (g²/Hz).
pub const FIG12_LEVELS: [f64; 3] = [7.4e-3, 1.31e-2, 2.85e-2];
/// Figure 14's levels (g²/Hz): a logarithmic grid from 1e-5 to 2e-3 that includes the paper's
/// 0.34e-3, 0.55e-3 and 1.69e-3.
pub const FIG14_LEVELS: [f64; 10] = [
    1e-5, 2e-5, 5e-5, 1e-4, 2e-4, 0.34e-3, 0.55e-3, 1e-3, 1.69e-3, 2e-3,
];
/// Figure 15's levels (g²/Hz).
pub const FIG15_LEVELS: [f64; 3] = [0.34e-3, 0.55e-3, 1.69e-3];
/// Records per level in Figure 11 (prototype 1 is broad-band, Qm = 5.7: a 10 s record spans
/// thousands of correlation times, so a few records give width CIs of a few per cent).
pub const FIG11_REALISATIONS: usize = 6;
/// Records per level in Figure 12 (as Figure 11; the contact statistics need a few more).
pub const FIG12_REALISATIONS: usize = 8;
/// Records per level in Figure 14. A record's efficiency scatters by about 6 % (relative) in
/// the linear regime (10 s span only some 150 correlation times of a 12 Hz wide response), so
/// eight give a 95 % CI of about 5 % per level, and the linear levels pooled about 2 %.
pub const FIG14_REALISATIONS: usize = 8;
/// Records per level in Figure 15: enough for 5-95 % quantiles of single-record widths and
/// 256 record pairs per ratio.
pub const FIG15_REALISATIONS: usize = 16;
/// "Impacts are frequent" (the paper's wording for the sublinear regime of Figure 14): the
/// mass spends at least this fraction of the time in contact.
pub const FREQUENT_CONTACT: f64 = 1e-5;

/// Prototype 1 as Figures 8-12 simulate it: 30 V, Hertz contact (eq 6), b_im = 1.5 N s/m.
pub fn prototype1_setup(device: &Device) -> Device {
    device
        .with_bias(30.0)
        .with_endstop(crate::params::StiffnessModel::Hertz, 1.5)
}

/// Prototype 2 as Figures 14 and 15 simulate it: 15 V, linear k_im (eq 19), b_im = 0.4 N s/m.
pub fn prototype2_setup(device: &Device) -> Device {
    device
        .with_bias(15.0)
        .with_endstop(crate::params::StiffnessModel::Linear, 0.4)
}

/// The ensemble of one level: the paper's record ([`RecordSpec::paper`]), Welch segments of
/// `nperseg` with 50 % overlap, MATLAB's default segmenting beside when `matlab_alt`, seed
/// [`DEFAULT_SEED`] and streams keyed by the level ([`first_stream_for_level`]).
pub fn protocol_spec(
    device: &Device,
    psd_g2_per_hz: f64,
    nperseg: usize,
    analysis_band_hz: (f64, f64),
    realisations: usize,
    matlab_alt: bool,
) -> EnsembleSpec {
    let record = RecordSpec::paper(device, psd_g2_per_hz);
    let alt_welch = matlab_alt
        .then(|| WelchConfig::half_overlap(matlab_default_nperseg(record.analysed_samples())));
    EnsembleSpec {
        record,
        welch: WelchConfig::half_overlap(nperseg),
        alt_welch,
        analysis_band_hz,
        seed: DEFAULT_SEED,
        first_stream: first_stream_for_level(psd_g2_per_hz),
        realisations,
    }
}

/// Efficiency `2P/(m Sa)` of every record of the ensembles pooled (in the linear regime the
/// efficiency does not depend on the level): mean and 95 % CI over the records (claim F14-a).
pub fn pooled_efficiency(device: &Device, ensembles: &[&Ensemble]) -> MeanCi {
    let effs: Vec<f64> = ensembles
        .iter()
        .flat_map(|e| {
            let sa = e.psd_g2_per_hz();
            e.records
                .iter()
                .map(move |r| efficiency(device, r.summary.p_total_w(), sa))
        })
        .collect();
    MeanCi::of(&effs)
}

/// Sublinear growth of the power with `Sa` (claim F14-b): starting from the linear-regime
/// efficiency `linear`, the efficiency of every ensemble (in increasing `Sa`) whose mean time
/// in contact is at least [`FREQUENT_CONTACT`] is below that of the one before (`P/Sa`
/// falls), and the last is below the linear value by more than both 95 % CIs. False when no
/// ensemble has frequent impacts.
pub fn sublinear_growth(linear: &MeanCi, ensembles: &[&Ensemble]) -> bool {
    let frequent: Vec<&&Ensemble> = ensembles
        .iter()
        .filter(|e| e.contact_fraction.mean >= FREQUENT_CONTACT)
        .collect();
    let mut prev = linear.mean;
    let mut falling = !frequent.is_empty();
    for e in &frequent {
        falling &= e.efficiency.mean < prev;
        prev = e.efficiency.mean;
    }
    let last_drop = frequent
        .last()
        .is_some_and(|e| linear.mean - e.efficiency.mean > linear.ci95 + e.efficiency.ci95);
    falling && last_drop
}

/// Shifts of the half-power band edges of the ensemble-mean PSD from `low` to `high` (Hz):
/// `(up, down)` = (upper edge of `high` minus that of `low`, lower edge of `low` minus that of
/// `high`); `None` if either band is undetermined. The widening is "towards higher
/// frequencies" (claim F15-c) when `up > down` and `up > 0`.
pub fn edge_shifts(low: &Ensemble, high: &Ensemble) -> Option<(f64, f64)> {
    let a = low.mean_widths.half_power?;
    let b = high.mean_widths.half_power?;
    Some((b.f_hi_hz - a.f_hi_hz, a.f_lo_hz - b.f_lo_hz))
}
// ANCHOR_END: protocols

/// Seed of the ChaCha8 streams of every broadband experiment (a named constant, so that runs
/// are deterministic).
pub const DEFAULT_SEED: u64 = 20_120_704;

/// First ChaCha8 stream of the ensemble at level `psd_g2_per_hz`: `round(Sa * 1e9) * 1000`.
///
/// Keying the streams by the level makes ensembles at different levels independent, and makes
/// the same level in two experiments (Figures 14 and 15) reuse the same records.
pub fn first_stream_for_level(psd_g2_per_hz: f64) -> u64 {
    (psd_g2_per_hz * 1e9).round() as u64 * 1000
}

/// Linearised small-signal response of the harvester (eqs 11-17 in the frequency domain): the
/// output power PSD of both loads under white acceleration, one-sided, W/Hz.
///
/// In the differential mode (V1 = -V2 = V, which the symmetric start from rest preserves to
/// first order) the linearised model of eqs 7-10 reads, with `Ct = C0 + Cp + CL` and
/// `Gamma = C0 Vb / x0`:
/// `V = Gamma x jw RL / (1 + jw RL Ct)`, and
/// `(km - w² m + jw b + 2 Gamma² jw RL / (1 + jw RL Ct)) x = m a`.
/// The power of both loads is `2|V|²/RL`, and the one-sided acceleration PSD is `2 Sa`, so
/// `S_P(f) = 4 Sa |V/a|² / RL`. Its integral over `f > 0` equals eq 21 (tested), and at high
/// frequency the electrical term tends to the stiffness `K - km` of eq 17.
pub fn linear_output_psd_w_per_hz(device: &Device, psd_g2_per_hz: f64, freq_hz: f64) -> f64 {
    let m = device.mechanics.mass_kg;
    let b = device.mechanics.damping_n_s_per_m;
    let km = device.mechanics.stiffness_n_per_m;
    let e = &device.electrical;
    let ct = e.c0_f + e.cp_f + e.load_capacitance_f;
    let gamma = e.c0_f * e.bias_v / device.geometry.finger_overlap_m;
    let rl = e.load_resistance_ohm;
    let w = 2.0 * std::f64::consts::PI * freq_hz;
    // z = jw RL / (1 + jw RL Ct) = (jw RL)(1 - jw RL Ct) / (1 + (w RL Ct)^2).
    let wrc = w * rl * ct;
    let den = 1.0 + wrc * wrc;
    let (z_re, z_im) = (w * rl * wrc / den, w * rl / den);
    // Mechanical impedance plus 2 Gamma^2 z.
    let d_re = km - w * w * m + 2.0 * gamma * gamma * z_re;
    let d_im = w * b + 2.0 * gamma * gamma * z_im;
    let x_over_a_sq = m * m / (d_re * d_re + d_im * d_im);
    let v_over_a_sq = gamma * gamma * (z_re * z_re + z_im * z_im) * x_over_a_sq;
    4.0 * psd_g2_per_hz * G * G * v_over_a_sq / rl
}

/// [`linear_output_psd_w_per_hz`] on a grid of frequencies, as a [`Psd`] (W/Hz).
pub fn linear_output_psd(device: &Device, psd_g2_per_hz: f64, freq_hz: &[f64]) -> Psd {
    Psd {
        freq_hz: freq_hz.to_vec(),
        density: freq_hz
            .iter()
            .map(|&f| linear_output_psd_w_per_hz(device, psd_g2_per_hz, f))
            .collect(),
        segments: 0,
    }
}

/// Widths of the linearised output PSD ([`linear_output_psd_w_per_hz`]), evaluated on a grid
/// of 0.01 Hz over `f_lo..f_hi` (the true widths, free of any estimator).
pub fn linear_widths(device: &Device, f_lo: f64, f_hi: f64) -> Widths {
    let n = ((f_hi - f_lo) / 0.01).ceil() as usize + 1;
    let f: Vec<f64> = (0..n).map(|i| f_lo + 0.01 * i as f64).collect();
    Widths::of(&linear_output_psd(device, 1.0, &f))
}

/// Linear theory of eq 21: mean power of both loads (W) at a two-sided acceleration PSD
/// `psd_g2_per_hz` (g²/Hz), with `Qm = sqrt(K m)/b` (the reading eq 21 is derived with).
pub fn eq21_power_w(device: &Device, psd_g2_per_hz: f64) -> f64 {
    let tp = TwoPort::of(device);
    tp.broadband_power_w(psd_g2_per_hz * G * G, tp.qm(QmReading::OpenCircuit))
}

/// Linear theory of eq 21: efficiency `2P/(m Sa)` (fraction), `Qm = sqrt(K m)/b`.
pub fn eq21_efficiency(device: &Device) -> f64 {
    let tp = TwoPort::of(device);
    tp.broadband_efficiency(tp.qm(QmReading::OpenCircuit))
}

/// Efficiency `2P/(m Sa)` (fraction) of a mean power `p_w` (both loads) at two-sided level
/// `psd_g2_per_hz` (g²/Hz) for `device`'s proof mass.
pub fn efficiency(device: &Device, p_w: f64, psd_g2_per_hz: f64) -> f64 {
    2.0 * p_w / (device.mechanics.mass_kg * psd_g2_per_hz * G * G)
}

/// The band edge of a low-pass spectrum: the highest frequency at which `psd` is still at least
/// `fraction` of `level`, interpolated linearly to the next bin (Hz). Scanning down from the
/// top makes a single low bin inside the band irrelevant. NaN if no bin reaches the threshold
/// or the top bin does.
pub fn upper_band_edge_hz(psd: &Psd, level: f64, fraction: f64) -> f64 {
    let thr = fraction * level;
    let d = &psd.density;
    let f = &psd.freq_hz;
    match (0..d.len()).rev().find(|&i| d[i] >= thr) {
        Some(i) if i + 1 < d.len() => f[i] + (thr - d[i]) * (f[i + 1] - f[i]) / (d[i + 1] - d[i]),
        _ => f64::NAN,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn student_t_expansion_joins_the_table() {
        // t_{0.975} for 30, 40, 60, 120 dof: 2.0423, 2.0211, 2.0003, 1.9799.
        assert!((student_t_975(31) - 2.0395).abs() < 2e-4);
        assert!((student_t_975(40) - 2.0211).abs() < 1e-4);
        assert!((student_t_975(60) - 2.0003).abs() < 1e-4);
        assert!((student_t_975(120) - 1.9799).abs() < 1e-4);
        assert!(student_t_975(0).is_nan());
    }

    #[test]
    fn spread_quantiles() {
        let xs: Vec<f64> = (0..=100).map(|i| i as f64).chain([f64::NAN]).collect();
        let s = Spread::of(&xs);
        assert_eq!(s.n, 101);
        assert_eq!(s.undetermined, 1);
        assert!((s.p05 - 5.0).abs() < 1e-12 && (s.p95 - 95.0).abs() < 1e-12);
        assert!((s.median - 50.0).abs() < 1e-12);
    }

    #[test]
    fn mean_ci_of_known_sample() {
        let m = MeanCi::of(&[1.0, 2.0, 3.0, 4.0]);
        assert!((m.mean - 2.5).abs() < 1e-15);
        let std = (5.0f64 / 3.0).sqrt();
        assert!((m.std - std).abs() < 1e-15);
        assert!((m.ci95 - 3.1824 * std / 2.0).abs() < 1e-12);
    }

    #[test]
    fn band_edge_of_a_step() {
        let psd = Psd {
            freq_hz: (0..10).map(|i| i as f64).collect(),
            density: vec![1.0, 1.0, 0.1, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0],
            segments: 1,
        };
        assert!((upper_band_edge_hz(&psd, 1.0, 0.5) - 5.5).abs() < 1e-12);
    }
}
