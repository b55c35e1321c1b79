//! One random-vibration record: band-limited white noise drives the harvester from rest, and
//! the load voltages are sampled and turned into an output power spectral density.
//!
//! # One record
//! [`simulate_record`] drives the lumped model of eq 7 with one realisation of band-limited
//! white noise from [`crate::drive::noise::generate`] (two-sided level `Sa`, 10 kHz band, 100 kHz,
//! the paper's section 4), read between samples by linear interpolation ([`crate::drive::Sampled`]), and
//! integrates it with [`crate::ode::Dopri5`] from rest. Every sample instant is a
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
//! [`output_psd`] is the one-sided Welch estimate ([`crate::signal::welch()`], periodic Hann,
//! 50 % overlap, density scaling) of both load voltages, divided by the load:
//! `S_P(f) = (S_V1(f) + S_V2(f)) / RL` in W/Hz, so that its integral over `f >= 0` is the mean
//! power of **both loads** (the power of eq 21). The per-load densities are kept beside it.
//!
//! # Efficiency
//! `2P/(m Sa)` with `P` the mean power of both loads and `Sa` the **two-sided** acceleration PSD
//! in SI units (`Sa_g2 * 9.81^2`), the input power being `m Sa / 2` (eq 21 and its reference).
//! [`eq21_power_w`](crate::physics::two_port::eq21_power_w) gives the linear theory with
//! `Qm = sqrt(K m)/b` ([`crate::physics::two_port::QmReading::OpenCircuit`]), the reading
//! eq 21 is derived with.
//!

use std::sync::Arc;

use thiserror::Error;

use crate::device::Device;
use crate::drive::noise::{self, NoiseError, NoiseSpec};
use crate::drive::Sampled;
use crate::ode::{Dopri5, SolverError, Stats};
use crate::physics::contact::Mode;
use crate::physics::harvester::Harvester;
use crate::signal::bandwidth::restrict;
use crate::signal::{self, Psd, SpectralError, WelchConfig};

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
/// resonator (about 0.1 s for prototype 2).
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
    /// The paper's record (10 kHz band, 100 kHz, 10 s analysed) at level
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

    pub(crate) fn validate(&self) -> Result<(), BroadbandError> {
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
    /// expectation is `2 B Sa` for a two-sided level `Sa` over the band `B`.
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
            let el = model.electrical(&ode.y());
            v1.push(el.v[0]);
            v2.push(el.v[1]);
            sx2 += ode.y()[0] * ode.y()[0];
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
        stats: ode.stats(),
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
    let load1 = scale(signal::welch(v1_v, sample_rate_hz, cfg)?);
    let load2 = scale(signal::welch(v2_v, sample_rate_hz, cfg)?);
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
