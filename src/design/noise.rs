//! The noise objective of a design: the mean DC power over an ensemble of band-limited
//! white-noise records, compared across candidates on common random numbers.
//!
//! * **Records**: `records` realisations (streams `0..records` of one `seed`) of the base
//!   acceleration, flat at the two-sided level `psd_g2_per_hz` up to `bandwidth_hz`, sampled
//!   at ten times the band, each analysed for `duration_s` after a pre-roll from rest
//!   ([`crate::study::record`]). The power is the storage's DC load's behind a circuit, the
//!   loads' otherwise.
//! * **Common random numbers**: every candidate of a search sees the same realisations: the same
//!   seed and streams, and the same number of samples, since the synthesis depends on the
//!   record's length. The pre-roll is therefore one for the whole problem
//!   ([`NoiseObjective::transient_s`]), set by [`super::Problem::with_noise`] to the longest
//!   pre-roll ([`crate::study::record::transient_s`]) over the corners of the ranges and the
//!   interfaces (the ring-up time `2 m / b` and a storage's `R C_s` are monotone in each
//!   parameter). Two candidates' powers then differ by their design, with the realisations'
//!   share of the noise common to both, which is what lets a search rank them.
//! * **Confirmation**: the answer's power measured again on a fresh seed (independent
//!   realisations) with its 95 % interval over the records ([`super::Problem::confirm`]): the
//!   search's best is biased up by its selection among noisy values, the fresh estimate is not.
//! * **Limits**: a record measures the largest displacement (the integrator's step ends, which
//!   include every contact event) and the impacts; the impact speed and the contact force are
//!   not measured under noise, so a noise problem refuses their limits
//!   ([`super::Problem::with_noise`]) and its performance holds NaN for them.

use rayon::prelude::*;

use crate::device::{Device, Interface, ParamRange};
use crate::drive::noise::NoiseSpec;
use crate::num::stats::MeanCi;
use crate::study::periodic::SteadySettings;
use crate::study::record::{
    simulate_record, transient_s, RecordError, RecordSpec, RecordSummary, Scheme, DEFAULT_RTOL,
};

use super::{DesignError, Evaluated, Limits, Performance, Problem, Vibration};

/// The noise a design is judged under, and the ensemble that measures its mean power.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct NoiseObjective {
    /// Two-sided acceleration density (g^2/Hz).
    pub psd_g2_per_hz: f64,
    /// Upper edge of the flat band (Hz); sampled at ten times this.
    pub bandwidth_hz: f64,
    /// Records per evaluation.
    pub records: u64,
    /// Analysed length of each record (s).
    pub duration_s: f64,
    /// The search's seed (common to every candidate).
    pub seed: u64,
    /// The pre-roll from rest before each record (s), one for the whole problem (module
    /// docs); [`super::Problem::with_noise`] sets it.
    pub transient_s: f64,
}

impl NoiseObjective {
    /// The record of the objective on any candidate (the same samples for every one).
    pub fn record(&self) -> RecordSpec {
        RecordSpec {
            noise: NoiseSpec {
                psd_g2_per_hz: self.psd_g2_per_hz,
                bandwidth_hz: self.bandwidth_hz,
                sample_rate_hz: 10.0 * self.bandwidth_hz,
                duration_s: self.duration_s,
            },
            transient_s: self.transient_s,
            rtol: DEFAULT_RTOL,
            scheme: Scheme::Exponential,
        }
    }

    /// Checks the objective: a positive level, band, length and pre-roll, records to
    /// average, and a seed that leaves room for the fresh one; the message names the field.
    pub fn check(&self) -> Result<(), String> {
        for (name, v) in [
            ("the noise's density", self.psd_g2_per_hz),
            ("the noise's band", self.bandwidth_hz),
            ("the record's length", self.duration_s),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("{name} must be finite and positive, got {v}"));
            }
        }
        if !(self.transient_s.is_finite() && self.transient_s >= 0.0) {
            return Err(format!(
                "the pre-roll must be finite and >= 0, got {}",
                self.transient_s
            ));
        }
        if self.records < 2 {
            return Err(format!(
                "at least 2 records are needed for an interval, got {}",
                self.records
            ));
        }
        if self.fresh_seed().is_none() {
            return Err("the search's seed must leave room for the fresh seed (seed + 1)".into());
        }
        Ok(())
    }

    /// The seed of the confirmation's fresh records, `seed + 1` (independent of the search's:
    /// a record's samples are those of its seed and stream); none for the largest seed.
    pub fn fresh_seed(&self) -> Option<u64> {
        self.seed.checked_add(1)
    }
}

/// The power of `device` in each record of `noise` on `seed` (streams `0..noise.records`, in
/// parallel, in stream order), with the records' summaries.
pub fn record_powers(
    device: &Device,
    noise: &NoiseObjective,
    seed: u64,
) -> Result<(Vec<f64>, Vec<RecordSummary>), RecordError> {
    let spec = noise.record();
    let summaries = (0..noise.records)
        .into_par_iter()
        .map(|k| simulate_record(device, &spec, seed, k).map(|r| r.summary))
        .collect::<Result<Vec<_>, _>>()?;
    let powers = summaries
        .iter()
        .map(|s| s.p_dc_w.unwrap_or_else(|| s.p_total_w()))
        .collect();
    Ok((powers, summaries))
}

/// The mean power of `device` over the records of `noise` on `seed` ([`record_powers`]),
/// with its interval, and the performance a design is judged by (module docs).
pub fn noise_power(
    device: &Device,
    noise: &NoiseObjective,
    seed: u64,
) -> Result<(MeanCi, Performance), RecordError> {
    let (powers, summaries) = record_powers(device, noise, seed)?;
    let power = MeanCi::of(&powers);
    let impacts: u64 = summaries.iter().map(|s| s.impacts).sum();
    let perf = Performance {
        power_w: power.mean,
        worst_freq_hz: f64::NAN,
        best_power_w: power.mean,
        impact_speed_m_s: f64::NAN,
        contact_force_n: f64::NAN,
        displacement_m: summaries.iter().map(|s| s.x_peak_m).fold(0.0, f64::max),
        impacts_per_s: impacts as f64 / (noise.records as f64 * noise.duration_s),
    };
    Ok((power, perf))
}

impl Problem {
    /// The problem of `device` under the noise objective `noise` alone ([`Problem::with_noise`]):
    /// its [`Problem::vibration`] holds no sine (no frequency, a NaN acceleration).
    pub fn under_noise(
        device: Device,
        interfaces: Vec<Interface>,
        ranges: Vec<ParamRange>,
        noise: NoiseObjective,
        limits: Limits,
    ) -> Result<Problem, DesignError> {
        Problem::without_sines(device, interfaces, ranges, limits).with_noise(noise)
    }

    /// The problem of `device` without a vibration (no frequency, a NaN acceleration), for a
    /// sampled drive to take the sines' place; unchecked.
    pub(super) fn without_sines(
        device: Device,
        interfaces: Vec<Interface>,
        ranges: Vec<ParamRange>,
        limits: Limits,
    ) -> Problem {
        Problem {
            device,
            interfaces,
            ranges,
            vibration: Vibration {
                freqs_hz: Vec::new(),
                accel_rms_g: f64::NAN,
            },
            limits,
            steady: SteadySettings::default(),
            noise: None,
            record: None,
        }
    }

    /// The problem with the noise objective `noise` in place of the sines (its pre-roll set to
    /// the longest over the corners of the ranges and the interfaces, module docs); refused with
    /// limits on the impact speed or the contact force, which records do not measure.
    pub fn with_noise(mut self, mut noise: NoiseObjective) -> Result<Problem, DesignError> {
        noise.transient_s = self.longest_transient_s("noise")?;
        self.record = None;
        self.noise = Some(noise);
        self.check()?;
        Ok(self)
    }

    /// The longest pre-roll ([`transient_s`]) over the corners of the ranges and the
    /// interfaces, for a sampled drive (`drive` names it in errors); refused with limits on
    /// the impact speed or the contact force, which records do not measure.
    pub(super) fn longest_transient_s(&self, drive: &str) -> Result<f64, DesignError> {
        if self.limits.impact_speed_m_s.is_some() || self.limits.contact_force_n.is_some() {
            return Err(DesignError::Invalid(format!(
                "under {drive} the records measure the displacement and the impacts, not the \
                 impact speed or the contact force: limit only those two"
            )));
        }
        let dims = self.ranges.len();
        if dims > 12 {
            return Err(DesignError::Invalid(format!(
                "under {drive} the pre-roll is read at the 2^n corners of the ranges: at most \
                 12 ranges, got {dims}"
            )));
        }
        let mut longest: f64 = 0.0;
        for i in 0..self.interfaces.len() {
            for corner in 0..1usize << dims {
                let unit: Vec<f64> = (0..dims).map(|d| ((corner >> d) & 1) as f64).collect();
                let (dev, _) = self.device_at(i, &unit)?;
                longest = longest.max(transient_s(&dev));
            }
        }
        Ok(longest)
    }

    /// The power of `design` measured again under the noise objective on `seed`, with its 95 %
    /// interval over the records (none without a noise objective).
    pub fn confirm(&self, design: &Evaluated, seed: u64) -> Option<Result<MeanCi, DesignError>> {
        let noise = self.noise.as_ref()?;
        Some(
            self.device_at(design.interface, &design.unit)
                .and_then(|(dev, _)| {
                    noise_power(&dev, noise, seed)
                        .map(|(p, _)| p)
                        .map_err(|e| DesignError::NoEvaluation(e.to_string()))
                }),
        )
    }
}
