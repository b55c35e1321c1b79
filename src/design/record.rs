//! The measured-record objective of a design: the mean DC power a design delivers over one
//! acceleration record (a measurement of the designer's own vibration, resampled to the
//! integrator's rate).
//!
//! * **Record**: the samples at `t = k / fs` (m/s^2), read between samples by linear
//!   interpolation ([`crate::study::record::SampledDrive`]); the first
//!   [`RecordObjective::transient_s`] of them are a pre-roll from rest, simulated and
//!   discarded, and the power is the mean over the rest (the storage's DC load's behind a
//!   circuit, the loads' otherwise).
//! * **One pre-roll for every design**: as under noise ([`super::noise`]), the pre-roll is one
//!   for the whole problem, the longest ([`crate::study::record::transient_s`]) over the
//!   corners of the ranges and the interfaces, set by [`super::Problem::with_record`]; every
//!   design is then judged over the same analysed stretch of the record.
//! * **Deterministic**: the record is the vibration itself, not a realisation of it, so the
//!   objective has no sampling noise: no common random numbers are needed and there is no
//!   confirmation on fresh records ([`super::Problem::confirm`] gives none).
//! * **Limits**: as under noise, a record measures the largest displacement (at the
//!   integrator's step ends, which include every contact event) and the impacts, not the
//!   impact speed or the contact force; a record problem refuses their limits and its
//!   performance holds NaN for them.

use std::sync::Arc;

use crate::device::{Device, Interface, ParamRange};
use crate::study::record::{simulate_drive, RecordError, SampledDrive, Scheme, DEFAULT_RTOL};

use super::{DesignError, Limits, Performance, Problem};

/// A measured acceleration record a design is judged over (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct RecordObjective {
    /// The base acceleration at `t = k / fs` (m/s^2).
    pub accel_m_s2: Arc<[f64]>,
    /// The sample rate fs (Hz), the integrator's.
    pub sample_rate_hz: f64,
    /// The pre-roll from rest discarded at the record's start (s), one for the whole problem
    /// (module docs); [`super::Problem::with_record`] sets it.
    pub transient_s: f64,
}

impl RecordObjective {
    /// The record `accel_m_s2` sampled at `sample_rate_hz`, its pre-roll left to the problem.
    pub fn new(accel_m_s2: Arc<[f64]>, sample_rate_hz: f64) -> Self {
        Self {
            accel_m_s2,
            sample_rate_hz,
            transient_s: 0.0,
        }
    }

    /// Samples of the pre-roll, `round(transient_s * fs)`.
    pub fn transient_samples(&self) -> usize {
        (self.transient_s * self.sample_rate_hz).round() as usize
    }

    /// Length of the analysed stretch, after the pre-roll (s).
    pub fn analysed_s(&self) -> f64 {
        self.accel_m_s2
            .len()
            .saturating_sub(self.transient_samples()) as f64
            / self.sample_rate_hz
    }

    /// Checks the objective: a positive sample rate, finite samples, a finite non-negative
    /// pre-roll and at least two samples after it; the message names what is wrong.
    pub fn check(&self) -> Result<(), String> {
        let fs = self.sample_rate_hz;
        if !(fs.is_finite() && fs > 0.0) {
            return Err(format!(
                "the record's sample rate must be finite and positive, got {fs}"
            ));
        }
        if let Some(k) = self.accel_m_s2.iter().position(|a| !a.is_finite()) {
            return Err(format!("the record's sample {k} is not finite"));
        }
        if !(self.transient_s.is_finite() && self.transient_s >= 0.0) {
            return Err(format!(
                "the pre-roll must be finite and >= 0, got {}",
                self.transient_s
            ));
        }
        let n = self.accel_m_s2.len();
        if n < self.transient_samples() + 2 {
            return Err(format!(
                "the record holds {n} samples ({} s) at {fs} Hz: the pre-roll the ranges need \
                 is {} s, and the power is averaged after it; give a longer record",
                n as f64 / fs,
                self.transient_s
            ));
        }
        Ok(())
    }

    /// The sampled drive of the record, its pre-roll discarded.
    pub fn drive(&self) -> SampledDrive {
        SampledDrive {
            accel: self.accel_m_s2.clone(),
            sample_rate_hz: self.sample_rate_hz,
            transient_samples: self.transient_samples(),
        }
    }
}

/// The performance of `device` over the record of `objective` (module docs).
pub fn record_power(
    device: &Device,
    objective: &RecordObjective,
) -> Result<Performance, RecordError> {
    let r = simulate_drive(
        device,
        &objective.drive(),
        DEFAULT_RTOL,
        Scheme::Exponential,
    )?;
    let s = &r.summary;
    let power_w = s.p_dc_w.unwrap_or_else(|| s.p_total_w());
    Ok(Performance {
        power_w,
        worst_freq_hz: f64::NAN,
        best_power_w: power_w,
        impact_speed_m_s: f64::NAN,
        contact_force_n: f64::NAN,
        displacement_m: s.x_peak_m,
        impacts_per_s: s.impacts as f64 / objective.analysed_s(),
    })
}

impl Problem {
    /// The problem of `device` over the measured record `record` alone
    /// ([`Problem::with_record`]): its [`Problem::vibration`] holds no sine.
    pub fn under_record(
        device: Device,
        interfaces: Vec<Interface>,
        ranges: Vec<ParamRange>,
        record: RecordObjective,
        limits: Limits,
    ) -> Result<Problem, DesignError> {
        Problem::without_sines(device, interfaces, ranges, limits).with_record(record)
    }

    /// The problem with the measured record `record` in place of the sines or the noise (its
    /// pre-roll set to the longest over the corners of the ranges and the interfaces, module
    /// docs); refused with limits on the impact speed or the contact force, which a record
    /// does not measure.
    pub fn with_record(mut self, mut record: RecordObjective) -> Result<Problem, DesignError> {
        record.transient_s = self.longest_transient_s("a measured record")?;
        self.noise = None;
        self.record = Some(record);
        self.check()?;
        Ok(self)
    }
}
