//! The random-vibration protocol shared by Figures 11 to 15: record, Welch segmenting and
//! analysis band of each prototype, and the ensemble of one level.

use crate::device::Device;
use crate::signal::welch::matlab_default_nperseg;
use crate::signal::WelchConfig;
use crate::study::ensemble::{first_stream_for_level, EnsembleSpec, DEFAULT_SEED};
use crate::study::record::RecordSpec;

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
