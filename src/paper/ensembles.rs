//! The random-vibration protocol shared by Figures 11 to 15: record, Welch segmenting and
//! analysis band of each prototype, the ensemble of one level ([`protocol_spec`]), the analysed
//! levels of a figure ([`Level`], [`run_levels`]), the two readings of "3 dB"
//! ([`WidthReading`]) and prototype 1 under both parameter sets ([`Prototype1Run`], Figures 11
//! and 12).

use crate::device::Device;
use crate::num::stats::Jackknife;
use crate::paper::setups::{paper_record, prototype1_setup, ParamSet, Prototype1Sets};
use crate::physics::linear::{linear_widths, LinearResponse};
use crate::physics::two_port::{eq21_efficiency, eq21_power_w};
use crate::progress::Progress;
use crate::signal::welch::matlab_default_nperseg;
use crate::signal::{Psd, WelchOptions, Widths};
use crate::study::ensemble::{
    first_stream_for_level, run_ensembles, Ensemble, EnsembleCase, EnsembleSpec, RecordResult,
    DEFAULT_SEED,
};
use crate::study::record::RecordError;

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

/// The ensemble of one level: the paper's record ([`paper_record`]), Welch segments of
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
    let record = paper_record(device, psd_g2_per_hz);
    let alt_welch = matlab_alt
        .then(|| WelchOptions::half_overlap(matlab_default_nperseg(record.analysed_samples())));
    EnsembleSpec {
        record,
        welch: WelchOptions::half_overlap(nperseg),
        alt_welch,
        analysis_band_hz,
        seed: DEFAULT_SEED,
        first_stream: first_stream_for_level(psd_g2_per_hz),
        realisations,
    }
}

/// A level as the paper writes it, e.g. `3.49e-4` (mantissa rounded to two decimals).
pub fn level_label(psd_g2_per_hz: f64) -> String {
    let e = psd_g2_per_hz.log10().floor() as i32;
    let m = psd_g2_per_hz / 10f64.powi(e);
    let m = format!("{}", (m * 100.0).round() / 100.0);
    format!("{m}e{e}")
}

/// A level as a claim's quantity key writes it, e.g. `3p49e-4`.
pub fn level_key(psd_g2_per_hz: f64) -> String {
    level_label(psd_g2_per_hz).replace('.', "p")
}

/// One ensemble to run: its parameter set (and the reading of the end-stop, when it is not
/// the set's own), the index of its level in the figure's list of levels, the device and the
/// ensemble's settings.
#[derive(Debug, Clone, PartialEq)]
pub struct LevelCase {
    /// The parameter set.
    pub set: ParamSet,
    /// Another reading of the end-stop than the figure's (its label), if any.
    pub variant: Option<String>,
    /// Index of the level in the figure's list.
    pub index: usize,
    /// The device as simulated.
    pub device: Device,
    /// The ensemble.
    pub spec: EnsembleSpec,
}

/// One analysed level of a figure: the parameter set (and reading), the level's index in the
/// figure's list (curves and claims find a level by it, never by comparing levels), the device
/// and its ensemble.
#[derive(Debug, Clone, PartialEq)]
pub struct Level {
    /// The parameter set.
    pub set: ParamSet,
    /// Another reading of the end-stop than the figure's (its label), if any.
    pub variant: Option<String>,
    /// Index of the level in the figure's list.
    pub index: usize,
    /// The device as simulated.
    pub device: Device,
    /// The ensemble.
    pub ens: Ensemble,
}

impl Level {
    /// Two-sided acceleration PSD (g²/Hz).
    pub fn sa(&self) -> f64 {
        self.ens.psd_g2_per_hz()
    }

    /// Power of both loads by eq 21 at this level (W).
    pub fn eq21_power_w(&self) -> f64 {
        eq21_power_w(&self.device, self.sa())
    }

    /// Efficiency `2P/(m Sa)` by eq 21 (fraction).
    pub fn eq21_efficiency(&self) -> f64 {
        eq21_efficiency(&self.device)
    }

    /// Efficiency `2P/(m Sa)` of one record (fraction), as the ensemble's mean efficiency
    /// counts it.
    pub fn record_efficiency(&self, r: &RecordResult) -> f64 {
        let m = self.device.mechanics.mass_kg;
        2.0 * r.summary.p_total_w() / (m * self.ens.spec.record.noise.psd_si())
    }

    /// Linearised output power PSD (eqs 11-17, no end-stops) at this level on `freq_hz` (W/Hz,
    /// one-sided).
    pub fn linear_psd(&self, freq_hz: &[f64]) -> Psd {
        LinearResponse::of(&self.device).output_psd(self.sa() * crate::G * crate::G, freq_hz)
    }

    /// Impacts per record.
    pub fn impacts_per_record(&self) -> f64 {
        self.ens.impacts as f64 / self.ens.records.len() as f64
    }
}

/// Runs every record of every case in parallel, calling `progress` after each record; the
/// levels come back in the order of `cases`.
pub fn run_levels(
    cases: Vec<LevelCase>,
    progress: &dyn Progress,
) -> Result<Vec<Level>, RecordError> {
    let ec: Vec<EnsembleCase> = cases
        .iter()
        .map(|c| EnsembleCase {
            device: c.device.clone(),
            spec: c.spec.clone(),
        })
        .collect();
    let ens = run_ensembles(&ec, progress)?;
    Ok(cases
        .into_iter()
        .zip(ens)
        .map(|(c, ens)| Level {
            set: c.set,
            variant: c.variant,
            index: c.index,
            device: c.device,
            ens,
        })
        .collect())
}

/// The two readings of "3 dB bandwidth" (the paper does not say which it measured): half
/// power (scored) and half amplitude, a quarter of the power peak.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WidthReading {
    /// Width at half the peak of the power PSD (3 dB): the scored reading.
    HalfPower,
    /// Width at a quarter of the peak (half amplitude, -6 dB of power).
    HalfAmplitude,
}

impl WidthReading {
    /// Both readings, the scored one first.
    pub const ALL: [WidthReading; 2] = [WidthReading::HalfPower, WidthReading::HalfAmplitude];

    /// Fraction of the peak at which the width is read.
    pub fn fraction(self) -> f64 {
        match self {
            WidthReading::HalfPower => 0.5,
            WidthReading::HalfAmplitude => 0.25,
        }
    }

    /// Key of the reading in file and number names (`bw3db`, `bw6db`).
    pub fn tag(self) -> &'static str {
        match self {
            WidthReading::HalfPower => "bw3db",
            WidthReading::HalfAmplitude => "bw6db",
        }
    }

    /// Label for tables.
    pub fn label(self) -> &'static str {
        match self {
            WidthReading::HalfPower => "half power (3 dB, scored)",
            WidthReading::HalfAmplitude => "half amplitude",
        }
    }

    /// Width of the ensemble-mean PSD with its jackknife interval (Hz).
    pub fn mean_width(self, e: &Ensemble) -> Jackknife {
        e.mean_width(self.fraction())
    }

    /// Single-record widths (Hz; NaN where undetermined).
    pub fn single(self, e: &Ensemble) -> Vec<f64> {
        match self {
            WidthReading::HalfPower => e.single_bw3db_hz(),
            WidthReading::HalfAmplitude => e.single_bw6db_hz(),
        }
    }
}

/// Prototype 1 at 30 V (Hertz contact, b_im = 1.5 N s/m) under both parameter sets
/// ([`ParamSet::BOTH`]) at the levels of one figure (Figures 11 and 12).
#[derive(Debug, Clone, PartialEq)]
pub struct Prototype1Run {
    /// The figure's levels (g²/Hz).
    pub levels_g2_per_hz: Vec<f64>,
    /// The ensembles, set-major: level `i` of set `s` is `levels[s * n + i]`.
    pub levels: Vec<Level>,
    /// Widths of the linearised output PSD (no end-stops; the same for both sets, which
    /// differ only in the end-stop gap).
    pub linear: Widths,
}

impl Prototype1Run {
    /// Level `i` of set `set`.
    pub fn level(&self, set: ParamSet, i: usize) -> &Level {
        &self.levels[set.index() * self.levels_g2_per_hz.len() + i]
    }

    /// The levels of set `set`, in the figure's order.
    pub fn set(&self, set: ParamSet) -> &[Level] {
        let n = self.levels_g2_per_hz.len();
        &self.levels[set.index() * n..(set.index() + 1) * n]
    }
}

/// Runs prototype 1 ([`prototype1_setup`] of the published and of the calibrated device) at
/// `levels`, `realisations` records each, with [`P1_NPERSEG`] and [`P1_BAND_HZ`].
pub fn run_prototype1(
    sets: &Prototype1Sets,
    levels: &[f64],
    realisations: usize,
    progress: &dyn Progress,
) -> Result<Prototype1Run, RecordError> {
    let devices = sets.each().map(|(set, d)| (set, prototype1_setup(d)));
    let mut cases = Vec::new();
    for (set, dev) in &devices {
        for (index, &sa) in levels.iter().enumerate() {
            cases.push(LevelCase {
                set: *set,
                variant: None,
                index,
                device: dev.clone(),
                spec: protocol_spec(dev, sa, P1_NPERSEG, P1_BAND_HZ, realisations, false),
            });
        }
    }
    Ok(Prototype1Run {
        levels_g2_per_hz: levels.to_vec(),
        levels: run_levels(cases, progress)?,
        linear: linear_widths(&devices[0].1, P1_BAND_HZ.0, P1_BAND_HZ.1),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn level_labels_and_keys() {
        assert_eq!(level_label(3.49e-4), "3.49e-4");
        assert_eq!(level_label(4.42e-6), "4.42e-6");
        assert_eq!(level_label(1e-2), "1e-2");
        assert_eq!(level_key(2.85e-2), "2p85e-2");
        assert_eq!(level_key(1.69e-3), "1p69e-3");
    }
}
