//! Band-limited white-noise acceleration (the paper's section 4 and Figure 10).
//!
//! The paper drives its random-vibration experiments with low-pass filtered white noise:
//! bandwidth 10 kHz, 10 s, sampled at 100 kHz, characterised by its **two-sided** power spectral
//! density `Sa` (g²/Hz) in the flat band. [`generate`] synthesises such a record directly in the
//! frequency domain, so the band is exactly flat in expectation and exactly empty outside it.
//!
//! # Conventions
//!
//! * **Level.** `Sa` is the two-sided PSD: the density per Hz over `-B..B`. The variance of the
//!   output is therefore `E[x²] = 2 B Sa_SI`, with `Sa_SI = Sa · G²` (m²/s⁴/Hz) and
//!   [`crate::G`] = 9.81 m/s². A one-sided estimate (e.g. [`crate::signal::welch()`]) reads
//!   `2 Sa` in the band.
//! * **Grid.** `N = round(duration_s · sample_rate_hz)` samples, read off one period of `M`
//!   samples of a periodic band-limited signal: `M` is the least even number `>= N` whose half
//!   factors into 2, 3, 5 and 7 and that is a multiple of `fs / B` when that ratio is an
//!   integer, so that its FFT has small radices only and the band edge falls on a bin. The
//!   paper's 10 s record has `M = N = 10^6`; a record with a pre-roll (e.g. 1 000 800 samples)
//!   is the first `N` samples of a slightly longer period (1 003 520). The bin spacing is
//!   `df = fs / M`, bin `k` at `f_k = k df`. Any `N` consecutive samples of the periodic
//!   signal are a stationary Gaussian sequence with the same spectrum, so the truncation
//!   changes no statistic.
//! * **Band.** Bins `1 <= k <= K` with `K = floor(B / df)` are filled; the band edge is
//!   *inclusive* (a bin exactly at `B` is filled; a relative slack of 1e-9 absorbs rounding in
//!   `B / df`). DC (`k = 0`) is zero, so a period has zero mean (up to rounding). Every other
//!   bin, including Nyquist, is zero. Since `B < fs/2` is required, `K < M/2`.
//! * **Coefficients.** `X_k = σ (g₁ + i g₂) / √2` with independent standard normals `g₁, g₂`
//!   and `σ² = E|X_k|² = M · fs · Sa_SI`; `X_{M-k} = conj(X_k)` (Hermitian), so the output is
//!   real. Each bin pair contributes `2 E|X_k|² / M² = 2 Sa_SI df` to the variance, i.e. `Sa_SI`
//!   per Hz on each side. The realised variance is `2 K df Sa_SI` in expectation, which equals
//!   `2 B Sa_SI` whenever `B / df` is an integer (the choice of `M` makes it one whenever
//!   `fs / B` is an integer, as for the paper's values: `K = 100 000` at `M = 10^6`).
//! * **Normalisation.** The inverse transform (`inverse.rs`, a complex-to-real transform over
//!   RustFFT's scalar planner) does not normalise: it computes `Σ_k X_k e^{+2πikn/M}` over the
//!   full Hermitian spectrum from the half `X_0..=X_{M/2}`, with one complex FFT of length
//!   `M/2`; we divide by `M` once, when copying the samples out (`x[n] = (...) / M`), which
//!   makes it the inverse of the un-normalised forward DFT.
//! * **Random numbers.** `ChaCha8Rng::seed_from_u64(seed)` then `set_stream(stream)`; one
//!   stream is one realisation, so parallel realisations do not depend on thread scheduling.
//!   Gaussians come from Box-Muller on `rng.random::<f64>()` (53-bit uniforms in `[0, 1)`):
//!   `u₁ = 1 - U` in `(0, 1]`, `r = √(-2 ln u₁)`, `θ = 2π U'`, `(g₁, g₂) = (r cos θ, r sin θ)`,
//!   one pair per bin, bins drawn in increasing `k`.
//! * **Determinism.** The transform runs on RustFFT's scalar planner by name, not on the
//!   planner that picks the CPU's SIMD instructions, so the result does not depend on which of
//!   them the CPU offers. Bit-identical output across machines still assumes the same
//!   `ln`/`sin`/`cos` (the platform libm) for Box-Muller and for RustFFT's twiddle factors; on
//!   one platform the bytes are fixed by `(spec, seed, stream)`.
//!
//! Memory: the half-spectrum and the transform's output (`M/2 + 1` complex and `M` real values,
//! plus RustFFT's scratch), kept per thread with the transform's plan for the next record of
//! the same length, and the output vector.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::cell::RefCell;
use std::sync::Arc;

use rustfft::num_complex::Complex;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::num::gaussian::box_muller;
use crate::G;

mod inverse;

use inverse::InverseRealFft;

/// Relative slack when deciding whether the band edge `B` falls on a bin (`f_k <= B`).
const BAND_EDGE_SLACK: f64 = 1e-9;

/// Largest record length accepted, to refuse absurd allocations (2^31 samples, 32 GiB of FFT).
const MAX_SAMPLES: f64 = 2_147_483_648.0;

/// Parameters of a band-limited white-noise acceleration record.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct NoiseSpec {
    /// Two-sided acceleration PSD `Sa` in the flat band, g²/Hz.
    pub psd_g2_per_hz: f64,
    /// Upper band edge `B`, Hz (the paper: 10 kHz). Must be below `sample_rate_hz / 2`.
    pub bandwidth_hz: f64,
    /// Sample rate `fs`, Hz (the paper: 100 kHz).
    pub sample_rate_hz: f64,
    /// Record length, s (the paper: 10 s).
    pub duration_s: f64,
}

/// Errors from [`NoiseSpec::validate`] and [`generate`].
#[derive(Debug, Clone, PartialEq, Error)]
pub enum NoiseError {
    /// A field is zero, negative, NaN or infinite.
    #[error("noise spec: {field} = {value} is invalid; expected a positive finite number")]
    NotPositiveFinite {
        /// Name of the offending field.
        field: &'static str,
        /// Its value.
        value: f64,
    },
    /// The band reaches the Nyquist frequency.
    #[error(
        "noise spec: bandwidth_hz = {bandwidth_hz} is invalid; expected 0 < bandwidth_hz < \
         sample_rate_hz / 2 = {nyquist_hz}"
    )]
    BandwidthAboveNyquist {
        /// Requested band edge, Hz.
        bandwidth_hz: f64,
        /// Half the sample rate, Hz.
        nyquist_hz: f64,
    },
    /// The record is too short (or too long) to hold the band on its frequency grid.
    #[error(
        "noise spec: duration_s * sample_rate_hz = {samples} samples is invalid; expected \
         between 2 and 2^31 samples with at least one bin (spacing {df_hz} Hz) at or below \
         bandwidth_hz = {bandwidth_hz}"
    )]
    RecordLength {
        /// `duration_s * sample_rate_hz`, before rounding.
        samples: f64,
        /// Bin spacing `sample_rate_hz / M` (the synthesis period, see the module docs), Hz.
        df_hz: f64,
        /// Requested band edge, Hz.
        bandwidth_hz: f64,
    },
}

impl NoiseSpec {
    /// Check every field: positive and finite, and `bandwidth_hz < sample_rate_hz / 2`.
    pub fn validate(&self) -> Result<(), NoiseError> {
        for (field, value) in [
            ("psd_g2_per_hz", self.psd_g2_per_hz),
            ("bandwidth_hz", self.bandwidth_hz),
            ("sample_rate_hz", self.sample_rate_hz),
            ("duration_s", self.duration_s),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(NoiseError::NotPositiveFinite { field, value });
            }
        }
        let nyquist_hz = 0.5 * self.sample_rate_hz;
        if self.bandwidth_hz >= nyquist_hz {
            return Err(NoiseError::BandwidthAboveNyquist {
                bandwidth_hz: self.bandwidth_hz,
                nyquist_hz,
            });
        }
        Ok(())
    }

    /// Number of samples `N = round(duration_s * sample_rate_hz)` (no validation).
    pub fn n_samples(&self) -> usize {
        (self.duration_s * self.sample_rate_hz).round() as usize
    }

    /// Two-sided PSD in SI units, `Sa · G²` (m²/s⁴/Hz).
    pub fn psd_si(&self) -> f64 {
        self.psd_g2_per_hz * G * G
    }

    /// The ideal two-sided PSD at frequency `f_hz` (g²/Hz): `Sa` in the band `0 < f <= B`,
    /// zero outside it.
    pub fn ideal_psd_g2_per_hz(&self, f_hz: f64) -> f64 {
        if f_hz > 0.0 && f_hz <= self.bandwidth_hz {
            self.psd_g2_per_hz
        } else {
            0.0
        }
    }

    /// Mean square of the ideal band-limited acceleration, `2 B Sa` (g²).
    pub fn mean_square_g2(&self) -> f64 {
        2.0 * self.bandwidth_hz * self.psd_g2_per_hz
    }

    /// Validate, then return the record's grid: samples `N`, synthesis period `M` and the
    /// highest filled bin `K` (see the module docs).
    fn grid(&self) -> Result<Grid, NoiseError> {
        self.validate()?;
        let samples = self.duration_s * self.sample_rate_hz;
        let n = samples.round();
        let bad = |df_hz: f64| NoiseError::RecordLength {
            samples,
            df_hz,
            bandwidth_hz: self.bandwidth_hz,
        };
        if !(2.0..=MAX_SAMPLES).contains(&n) {
            return Err(bad(self.sample_rate_hz / n));
        }
        let n = n as usize;
        let period = synthesis_period(n, self.sample_rate_hz / self.bandwidth_hz);
        let df_hz = self.sample_rate_hz / period as f64;
        let k_max = (self.bandwidth_hz / df_hz * (1.0 + BAND_EDGE_SLACK)).floor();
        if k_max < 1.0 {
            return Err(bad(df_hz));
        }
        // B < fs/2 keeps K below M/2; the min only guards the slack at tiny M.
        let k_max = (k_max as usize).min((period - 1) / 2);
        Ok(Grid { n, period, k_max })
    }
}

/// The grid of a record: `n` samples, read off one period of `period` samples of a
/// band-limited periodic signal whose bins `1..=k_max` are filled.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Grid {
    n: usize,
    period: usize,
    k_max: usize,
}

/// The synthesis period `M` of a record of `n` samples: the least even `M >= n` whose half
/// factors into 2, 3, 5 and 7 (so that its FFT has only small radices) and which is a
/// multiple of `fs / B` when that ratio is an integer (so that the band edge falls on a bin,
/// as it does for the paper's 10 s record, whose `M` is its `N`).
fn synthesis_period(n: usize, fs_over_b: f64) -> usize {
    let ratio = fs_over_b.round();
    let step = if (fs_over_b - ratio).abs() <= BAND_EDGE_SLACK * fs_over_b && ratio >= 1.0 {
        ratio as usize
    } else {
        1
    };
    let smooth = |mut m: usize| {
        for p in [2, 3, 5, 7] {
            while m.is_multiple_of(p) {
                m /= p;
            }
        }
        m == 1
    };
    let mut m = n.next_multiple_of(2);
    while !(m.is_multiple_of(step) && smooth(m / 2)) {
        m += 2;
    }
    m
}

/// RMS acceleration of the ideal band-limited record, `sqrt(2 B Sa) · G`, m/s².
///
/// This is the continuous-band value; a record from [`generate`] has variance `2 K df Sa_SI`
/// in expectation (equal when `B` falls on a bin, see the module docs).
pub fn rms_si(spec: &NoiseSpec) -> f64 {
    (2.0 * spec.bandwidth_hz * spec.psd_g2_per_hz).sqrt() * G
}

/// Generate one realisation of band-limited white-noise acceleration, m/s².
///
/// `seed` fixes the ChaCha8 key and `stream` selects an independent realisation; the result is
/// a pure function of `(spec, seed, stream)`. See the module docs for every convention.
pub fn generate(spec: &NoiseSpec, seed: u64, stream: u64) -> Result<Vec<f64>, NoiseError> {
    synthesize(spec, seed, stream, |n, sample| (0..n).map(sample).collect())
}

/// [`generate`] into a shared slice (for [`crate::drive::Sampled`]), written in place.
///
/// ```
/// use endstop::drive::noise::{generate, generate_shared, NoiseSpec};
/// use endstop::drive::Sampled;
///
/// let spec = NoiseSpec { psd_g2_per_hz: 1e-4, bandwidth_hz: 500.0, sample_rate_hz: 5e3, duration_s: 0.2 };
/// let shared = generate_shared(&spec, 2012, 3)?;
/// // The same realisation as `generate`, bit for bit; another stream is another realisation.
/// assert_eq!(&shared[..], &generate(&spec, 2012, 3)?[..]);
/// assert_ne!(&shared[..], &generate(&spec, 2012, 4)?[..]);
/// assert_eq!(shared.len(), spec.n_samples());
/// let drive = Sampled::new(shared, spec.sample_rate_hz);
/// assert!(drive.duration_s() < spec.duration_s);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn generate_shared(spec: &NoiseSpec, seed: u64, stream: u64) -> Result<Arc<[f64]>, NoiseError> {
    // A `Range` mapped is an exact-size iterator: `collect` allocates the slice once and
    // writes into it.
    synthesize(spec, seed, stream, |n, sample| (0..n).map(sample).collect())
}

/// The inverse transform of one synthesis period, kept per thread: an ensemble's records all
/// have the same length, so each thread plans (and computes the twiddle factors) once.
struct Synthesis {
    k_max: usize,
    /// Inverse real FFT of length `period` (Hermitian half-spectrum in, real samples out).
    fft: InverseRealFft,
    /// The half-spectrum `X_0..=X_{period/2}`.
    spectrum: Vec<Complex<f64>>,
}

thread_local! {
    static SYNTHESIS: RefCell<Option<Synthesis>> = const { RefCell::new(None) };
}

impl Synthesis {
    fn new(period: usize, k_max: usize) -> Self {
        Self {
            k_max,
            fft: InverseRealFft::new(period),
            spectrum: vec![Complex::new(0.0, 0.0); period / 2 + 1],
        }
    }
}

/// Draws the coefficients of `(spec, seed, stream)`, transforms them over the synthesis
/// period, and hands `out` the record length and the function that reads sample `j`.
///
/// The transform is the complex-to-real inverse of `inverse.rs`: from the half-spectrum
/// `X_0..=X_{M/2}` of the Hermitian spectrum it computes `Σ_k X_k e^{2πijk/M}` over all `M`
/// bins, un-normalised, with one complex FFT of half the length for an even `M`.
fn synthesize<T>(
    spec: &NoiseSpec,
    seed: u64,
    stream: u64,
    out: impl FnOnce(usize, &dyn Fn(usize) -> f64) -> T,
) -> Result<T, NoiseError> {
    let grid = spec.grid()?;
    SYNTHESIS.with(|cell| {
        let mut cache = cell.borrow_mut();
        if cache
            .as_ref()
            .is_none_or(|c| c.fft.len() != grid.period || c.k_max != grid.k_max)
        {
            *cache = Some(Synthesis::new(grid.period, grid.k_max));
        }
        let Some(syn) = cache.as_mut() else {
            unreachable!("the cache was just filled")
        };
        let mut rng = stream_rng(seed, stream);
        let amp = coefficient_scale(spec, grid.period);
        let zero = Complex::new(0.0, 0.0);
        syn.spectrum[0] = zero;
        for c in &mut syn.spectrum[1..=grid.k_max] {
            *c = draw_coefficient(&mut rng, amp);
        }
        syn.spectrum[grid.k_max + 1..].fill(zero);
        // DC and Nyquist are zero, as the transform asks.
        let pairs = syn.fft.process(&mut syn.spectrum);
        // The inverse is un-normalised: divide by M when reading the samples, once. Sample `j`
        // is the real (even `j`) or imaginary (odd `j`) part of the pair `j / 2`.
        let inv_m = 1.0 / grid.period as f64;
        let sample = |j: usize| {
            let z = pairs[j / 2];
            (if j.is_multiple_of(2) { z.re } else { z.im }) * inv_m
        };
        Ok(out(grid.n, &sample))
    })
}

/// The Fourier coefficients `X_0..=X_K` that [`generate`] transforms for `(spec, seed, stream)`.
///
/// `X_0 = 0`; bins `K < k <= M/2` are zero and `X_{M-k} = conj(X_k)`, so
/// `x[n] = (1/M) Σ_k X_k e^{2πikn/M}` is the output of [`generate`] for `n < N`, and the mean
/// square of a period is `(2/M²) Σ_{k=1..K} |X_k|²` (Parseval; `M = N` for the paper's 10 s
/// record). Intended for tests and diagnostics.
pub fn spectrum(spec: &NoiseSpec, seed: u64, stream: u64) -> Result<Vec<Complex<f64>>, NoiseError> {
    let grid = spec.grid()?;
    let mut rng = stream_rng(seed, stream);
    let amp = coefficient_scale(spec, grid.period);
    let mut out = Vec::with_capacity(grid.k_max + 1);
    out.push(Complex::new(0.0, 0.0));
    out.extend((1..=grid.k_max).map(|_| draw_coefficient(&mut rng, amp)));
    Ok(out)
}

/// The generator of realisation `stream`.
fn stream_rng(seed: u64, stream: u64) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(stream);
    rng
}

/// `σ / √2` with `σ² = E|X_k|² = M fs Sa_SI` over a period of `m` samples: each of Re, Im
/// carries half the power.
fn coefficient_scale(spec: &NoiseSpec, m: usize) -> f64 {
    (0.5 * m as f64 * spec.sample_rate_hz * spec.psd_si()).sqrt()
}

/// One in-band coefficient `amp (g₁ + i g₂)`.
fn draw_coefficient(rng: &mut ChaCha8Rng, amp: f64) -> Complex<f64> {
    let (g1, g2) = box_muller(rng);
    Complex::new(amp * g1, amp * g2)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The paper's excitation at level `psd`: 10 kHz band, 100 kHz, 10 s.
    fn ten_khz(psd: f64) -> NoiseSpec {
        NoiseSpec {
            psd_g2_per_hz: psd,
            bandwidth_hz: 10e3,
            sample_rate_hz: 100e3,
            duration_s: 10.0,
        }
    }

    #[test]
    fn validate_names_field_and_range() {
        let mut spec = ten_khz(1e-2);
        assert!(spec.validate().is_ok());
        spec.duration_s = -1.0;
        let msg = spec.validate().unwrap_err().to_string();
        assert!(msg.contains("duration_s = -1"), "{msg}");
        assert!(msg.contains("positive finite"), "{msg}");

        let mut spec = ten_khz(1e-2);
        spec.bandwidth_hz = 50e3;
        let msg = spec.validate().unwrap_err().to_string();
        assert!(msg.contains("bandwidth_hz = 50000"), "{msg}");
        assert!(msg.contains("sample_rate_hz / 2 = 50000"), "{msg}");

        let mut spec = ten_khz(f64::NAN);
        assert!(spec.validate().is_err());
        spec.psd_g2_per_hz = 1.0;
        spec.duration_s = 1e-6;
        let msg = generate(&spec, 1, 0).unwrap_err().to_string();
        assert!(msg.contains("samples"), "{msg}");
    }

    #[test]
    fn ideal_level_and_mean_square() {
        let spec = ten_khz(1e-2);
        assert_eq!(spec.ideal_psd_g2_per_hz(0.0), 0.0);
        assert_eq!(spec.ideal_psd_g2_per_hz(10e3), 1e-2);
        assert_eq!(spec.ideal_psd_g2_per_hz(10.001e3), 0.0);
        // 2 B Sa = 2 x 10 kHz x 1e-2 g²/Hz = 200 g².
        assert!((spec.mean_square_g2() - 200.0).abs() < 1e-12);
    }

    #[test]
    fn paper_grid() {
        let spec = ten_khz(1e-2);
        let grid = spec.grid().unwrap();
        assert_eq!(
            (grid.n, grid.period, grid.k_max),
            (1_000_000, 1_000_000, 100_000)
        );
        let rms = rms_si(&spec);
        assert!((rms - (2.0 * 10e3 * 1e-2f64).sqrt() * 9.81).abs() < 1e-12);
    }

    #[test]
    fn synthesis_periods_are_smooth_and_put_the_band_edge_on_a_bin() {
        // Prototype 1's record with its 8 ms pre-roll, prototype 2's with 0.48 s, and the
        // paper's bare 10 s record, at fs / B = 10.
        assert_eq!(synthesis_period(1_000_800, 10.0), 1_003_520); // 2^12 x 5 x 7^2
        assert_eq!(synthesis_period(1_048_000, 10.0), 1_049_760); // 2^5 x 3^8 x 5
        assert_eq!(synthesis_period(1_000_000, 10.0), 1_000_000);
        // An odd length rounds up; a ratio that is not an integer asks only for evenness.
        assert_eq!(synthesis_period(7, 10.0), 10);
        assert_eq!(synthesis_period(23, 2.5), 24);
        let mut spec = ten_khz(1e-2);
        spec.duration_s = 10.008;
        let grid = spec.grid().unwrap();
        assert_eq!(
            (grid.n, grid.period, grid.k_max),
            (1_000_800, 1_003_520, 100_352)
        );
        assert_eq!(generate(&spec, 1, 0).unwrap().len(), 1_000_800);
    }
}
