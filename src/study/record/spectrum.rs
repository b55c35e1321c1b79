//! The output power spectral density of a record's two loads (see the parent module).

use crate::signal::bandwidth::restrict;
use crate::signal::{self, Psd, SpectralError, WelchOptions};

use super::Record;

/// Output power spectral density of both loads and of each, one-sided, W/Hz.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
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

/// One-sided Welch estimate of the output power PSD of both loads of `record`,
/// `(S_V1 + S_V2)/RL` (W/Hz), and of each load (see the module docs). An output the model
/// holds at zero, whose samples the record does not keep, has the density zero.
pub fn output_psd(
    record: &Record,
    load_resistance_ohm: f64,
    cfg: &WelchOptions,
) -> Result<OutputSpectrum, SpectralError> {
    let fs = record.sample_rate_hz;
    let scale = |mut p: Psd| {
        p.density.iter_mut().for_each(|d| *d /= load_resistance_ohm);
        p
    };
    let density = |i: usize, v: &[f64]| {
        if record.keeps(i, v) {
            signal::welch(v, fs, cfg)
        } else {
            signal::welch_of_zeros(record.samples, fs, cfg)
        }
    };
    let load1 = scale(density(0, &record.v1_v)?);
    let load2 = scale(density(1, &record.v2_v)?);
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
