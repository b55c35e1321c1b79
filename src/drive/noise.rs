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
//! * **Grid.** `N = round(duration_s · sample_rate_hz)` samples, bin spacing `df = fs / N`,
//!   bin `k` at `f_k = k df`.
//! * **Band.** Bins `1 <= k <= K` with `K = floor(B / df)` are filled; the band edge is
//!   *inclusive* (a bin exactly at `B` is filled; a relative slack of 1e-9 absorbs rounding in
//!   `B / df`). DC (`k = 0`) is zero, so the record has zero mean (up to rounding). Every other
//!   bin, including Nyquist, is zero. Since `B < fs/2` is required, `K < N/2`.
//! * **Coefficients.** `X_k = σ (g₁ + i g₂) / √2` with independent standard normals `g₁, g₂`
//!   and `σ² = E|X_k|² = N · fs · Sa_SI`; `X_{N-k} = conj(X_k)` (Hermitian), so the output is
//!   real. Each bin pair contributes `2 E|X_k|² / N² = 2 Sa_SI df` to the variance, i.e. `Sa_SI`
//!   per Hz on each side. The realised variance is `2 K df Sa_SI` in expectation, which equals
//!   `2 B Sa_SI` whenever `B / df` is an integer (it is for the paper's values: `K = 100 000`).
//! * **Normalisation.** RustFFT does not normalise. The inverse transform computes
//!   `Σ_k X_k e^{+2πikn/N}`; we divide by `N` once, when copying the real part out
//!   (`x[n] = Re(...) / N`), which makes it the inverse of the un-normalised forward DFT.
//! * **Random numbers.** `ChaCha8Rng::seed_from_u64(seed)` then `set_stream(stream)`; one
//!   stream is one realisation, so parallel realisations do not depend on thread scheduling.
//!   Gaussians come from Box-Muller on `rng.random::<f64>()` (53-bit uniforms in `[0, 1)`):
//!   `u₁ = 1 - U` in `(0, 1]`, `r = √(-2 ln u₁)`, `θ = 2π U'`, `(g₁, g₂) = (r cos θ, r sin θ)`,
//!   one pair per bin, bins drawn in increasing `k`.
//! * **Determinism.** The FFT uses RustFFT's scalar planner, so the result does not depend on
//!   which SIMD instructions the CPU offers. Bit-identical output across machines still
//!   assumes the same `ln`/`sin`/`cos` (the platform libm) for Box-Muller and for RustFFT's
//!   twiddle factors; on one platform the bytes are fixed by `(spec, seed, stream)`.
//!
//! Memory: one complex FFT buffer of `N` values (plus RustFFT's scratch) and the output vector.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rustfft::num_complex::Complex;
use rustfft::FftPlannerScalar;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::G;

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
        /// Bin spacing `sample_rate_hz / N`, Hz.
        df_hz: f64,
        /// Requested band edge, Hz.
        bandwidth_hz: f64,
    },
}

impl NoiseSpec {
    /// The paper's excitation: level `psd_g2_per_hz`, 10 kHz band, 100 kHz, 10 s.
    pub fn paper(psd_g2_per_hz: f64) -> Self {
        Self {
            psd_g2_per_hz,
            bandwidth_hz: 10e3,
            sample_rate_hz: 100e3,
            duration_s: 10.0,
        }
    }

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

    /// Validate, then return `(N, K)`: samples and the highest filled bin.
    fn grid(&self) -> Result<(usize, usize), NoiseError> {
        self.validate()?;
        let samples = self.duration_s * self.sample_rate_hz;
        let n = samples.round();
        let df_hz = self.sample_rate_hz / n;
        let k_max = (self.bandwidth_hz / df_hz * (1.0 + BAND_EDGE_SLACK)).floor();
        if !(2.0..=MAX_SAMPLES).contains(&n) || k_max < 1.0 {
            return Err(NoiseError::RecordLength {
                samples,
                df_hz,
                bandwidth_hz: self.bandwidth_hz,
            });
        }
        let n = n as usize;
        // B < fs/2 keeps K below N/2; the min only guards the slack at tiny N.
        let k_max = (k_max as usize).min((n - 1) / 2);
        Ok((n, k_max))
    }
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
    let (n, k_max) = spec.grid()?;

    let mut buf = vec![Complex::new(0.0, 0.0); n];
    let mut rng = stream_rng(seed, stream);
    let amp = coefficient_scale(spec, n);
    for k in 1..=k_max {
        let x = draw_coefficient(&mut rng, amp);
        buf[k] = x;
        buf[n - k] = x.conj();
    }

    let ifft = FftPlannerScalar::new().plan_fft_inverse(n);
    ifft.process(&mut buf);

    // RustFFT's inverse is un-normalised: divide by N here, once.
    let inv_n = 1.0 / n as f64;
    Ok(buf.iter().map(|c| c.re * inv_n).collect())
}

/// The Fourier coefficients `X_0..=X_K` that [`generate`] transforms for `(spec, seed, stream)`.
///
/// `X_0 = 0`; bins `K < k <= N/2` are zero and `X_{N-k} = conj(X_k)`, so
/// `x[n] = (1/N) Σ_k X_k e^{2πikn/N}` is the output of [`generate`], and its mean square is
/// `(2/N²) Σ_{k=1..K} |X_k|²` (Parseval). Intended for tests and diagnostics.
pub fn spectrum(spec: &NoiseSpec, seed: u64, stream: u64) -> Result<Vec<Complex<f64>>, NoiseError> {
    let (n, k_max) = spec.grid()?;
    let mut rng = stream_rng(seed, stream);
    let amp = coefficient_scale(spec, n);
    let mut out = Vec::with_capacity(k_max + 1);
    out.push(Complex::new(0.0, 0.0));
    out.extend((1..=k_max).map(|_| draw_coefficient(&mut rng, amp)));
    Ok(out)
}

/// The generator of realisation `stream`.
fn stream_rng(seed: u64, stream: u64) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(stream);
    rng
}

/// `σ / √2` with `σ² = E|X_k|² = N fs Sa_SI`: each of Re, Im carries half the power.
fn coefficient_scale(spec: &NoiseSpec, n: usize) -> f64 {
    (0.5 * n as f64 * spec.sample_rate_hz * spec.psd_si()).sqrt()
}

/// One in-band coefficient `amp (g₁ + i g₂)`.
fn draw_coefficient(rng: &mut ChaCha8Rng, amp: f64) -> Complex<f64> {
    let (g1, g2) = box_muller(rng);
    Complex::new(amp * g1, amp * g2)
}

/// Two independent standard normals from two uniforms (Box-Muller, basic form).
fn box_muller(rng: &mut ChaCha8Rng) -> (f64, f64) {
    // random::<f64>() is in [0, 1); 1 - u is in (0, 1], so ln never sees 0.
    let u1 = 1.0 - rng.random::<f64>();
    let u2 = rng.random::<f64>();
    let r = (-2.0 * u1.ln()).sqrt();
    let (s, c) = (std::f64::consts::TAU * u2).sin_cos();
    (r * c, r * s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn validate_names_field_and_range() {
        let mut spec = NoiseSpec::paper(1e-2);
        assert!(spec.validate().is_ok());
        spec.duration_s = -1.0;
        let msg = spec.validate().unwrap_err().to_string();
        assert!(msg.contains("duration_s = -1"), "{msg}");
        assert!(msg.contains("positive finite"), "{msg}");

        let mut spec = NoiseSpec::paper(1e-2);
        spec.bandwidth_hz = 50e3;
        let msg = spec.validate().unwrap_err().to_string();
        assert!(msg.contains("bandwidth_hz = 50000"), "{msg}");
        assert!(msg.contains("sample_rate_hz / 2 = 50000"), "{msg}");

        let mut spec = NoiseSpec::paper(f64::NAN);
        assert!(spec.validate().is_err());
        spec.psd_g2_per_hz = 1.0;
        spec.duration_s = 1e-6;
        let msg = generate(&spec, 1, 0).unwrap_err().to_string();
        assert!(msg.contains("samples"), "{msg}");
    }

    #[test]
    fn ideal_level_and_mean_square() {
        let spec = NoiseSpec::paper(1e-2);
        assert_eq!(spec.ideal_psd_g2_per_hz(0.0), 0.0);
        assert_eq!(spec.ideal_psd_g2_per_hz(10e3), 1e-2);
        assert_eq!(spec.ideal_psd_g2_per_hz(10.001e3), 0.0);
        // 2 B Sa = 2 x 10 kHz x 1e-2 g²/Hz = 200 g².
        assert!((spec.mean_square_g2() - 200.0).abs() < 1e-12);
    }

    #[test]
    fn paper_grid() {
        let spec = NoiseSpec::paper(1e-2);
        assert_eq!(spec.grid().unwrap(), (1_000_000, 100_000));
        let rms = rms_si(&spec);
        assert!((rms - (2.0 * 10e3 * 1e-2f64).sqrt() * 9.81).abs() < 1e-12);
    }
}
