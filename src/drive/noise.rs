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
//!   For an even `N` (the paper's records) the real output is computed with one complex
//!   transform of length `N/2` (the even and odd samples as real and imaginary parts, see
//!   `synthesize`), which equals the full-length transform to rounding and costs half.
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
//! Memory: one complex FFT buffer of `N/2` values (plus RustFFT's scratch), kept per thread
//! with the transform's plan for the next record of the same length, and the output vector.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::cell::RefCell;
use std::sync::Arc;

use rustfft::num_complex::Complex;
use rustfft::{Fft, FftPlannerScalar};
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
    synthesize(spec, seed, stream, |n, sample| (0..n).map(sample).collect())
}

/// [`generate`] into a shared slice (for [`crate::drive::Sampled`]), written in place.
pub fn generate_shared(spec: &NoiseSpec, seed: u64, stream: u64) -> Result<Arc<[f64]>, NoiseError> {
    // A `Range` mapped is an exact-size iterator: `collect` allocates the slice once and
    // writes into it.
    synthesize(spec, seed, stream, |n, sample| (0..n).map(sample).collect())
}

/// The inverse transform of one record length, kept per thread: an ensemble's records all
/// have the same length, so each thread plans (and computes the twiddle factors) once.
struct Synthesis {
    n: usize,
    k_max: usize,
    /// Inverse FFT of length `n / 2` (`n` even) or `n`.
    fft: Arc<dyn Fft<f64>>,
    /// `e^{2πik/n}` for `k = 0..=K` (`n` even only).
    twiddle: Vec<Complex<f64>>,
    /// The transform's buffer and scratch.
    buf: Vec<Complex<f64>>,
    scratch: Vec<Complex<f64>>,
    /// The drawn coefficients `X_1..=X_K`.
    coeffs: Vec<Complex<f64>>,
}

thread_local! {
    static SYNTHESIS: RefCell<Option<Synthesis>> = const { RefCell::new(None) };
}

impl Synthesis {
    fn new(n: usize, k_max: usize) -> Self {
        let half = n.is_multiple_of(2);
        let len = if half { n / 2 } else { n };
        let fft = FftPlannerScalar::new().plan_fft_inverse(len);
        let twiddle = if half {
            (0..=k_max)
                .map(|k| {
                    let (s, c) = (std::f64::consts::TAU * k as f64 / n as f64).sin_cos();
                    Complex::new(c, s)
                })
                .collect()
        } else {
            Vec::new()
        };
        let scratch = vec![Complex::new(0.0, 0.0); fft.get_inplace_scratch_len()];
        Self {
            n,
            k_max,
            fft,
            twiddle,
            buf: vec![Complex::new(0.0, 0.0); len],
            scratch,
            coeffs: Vec::with_capacity(k_max),
        }
    }
}

/// Draws the coefficients of `(spec, seed, stream)`, transforms them, and hands `out` the
/// record length and the function that reads sample `j` off the transform.
///
/// For an even length `n` the real record is obtained from one complex transform of half the
/// length: with `X_k` the Hermitian spectrum and `w = e^{2πi/n}`, the sequence
/// `z_m = x_{2m} + i x_{2m+1}` is the (un-normalised, divided by `n`) inverse transform of
/// length `n/2` of `Y_k = (X_k + X_{k+n/2}) + i (X_k - X_{k+n/2}) w^k`, where
/// `X_{k+n/2} = conj(X_{n/2-k})` (split the sum over `k` that defines `x_j` into `k < n/2`
/// and `k + n/2`, for even and for odd `j`). Only `Y_k` with `1 <= k <= K` or `n/2 - K <= k < n/2` are
/// non-zero, and `w^{n/2-j} = -conj(w^j)`, so the twiddles of `k <= K` suffice. The result
/// equals the full-length transform to rounding.
fn synthesize<T>(
    spec: &NoiseSpec,
    seed: u64,
    stream: u64,
    out: impl FnOnce(usize, &dyn Fn(usize) -> f64) -> T,
) -> Result<T, NoiseError> {
    let (n, k_max) = spec.grid()?;
    SYNTHESIS.with(|cell| {
        let mut cache = cell.borrow_mut();
        if cache.as_ref().is_none_or(|c| c.n != n || c.k_max != k_max) {
            *cache = Some(Synthesis::new(n, k_max));
        }
        let Some(syn) = cache.as_mut() else {
            unreachable!("the cache was just filled")
        };
        let mut rng = stream_rng(seed, stream);
        let amp = coefficient_scale(spec, n);
        syn.coeffs.clear();
        syn.coeffs
            .extend((1..=k_max).map(|_| draw_coefficient(&mut rng, amp)));
        let zero = Complex::new(0.0, 0.0);
        syn.buf.iter_mut().for_each(|b| *b = zero);
        // RustFFT's inverse is un-normalised: divide by N when reading the samples, once.
        let inv_n = 1.0 / n as f64;
        if n.is_multiple_of(2) {
            let half = n / 2;
            // X_j for 1 <= j <= K, zero elsewhere on 0..=n/2.
            let x = |j: usize| {
                if (1..=k_max).contains(&j) {
                    syn.coeffs[j - 1]
                } else {
                    zero
                }
            };
            let i = Complex::new(0.0, 1.0);
            let mut fill = |k: usize, w: Complex<f64>| {
                let a = x(k);
                let b = x(half - k).conj();
                syn.buf[k] = (a + b) + i * (a - b) * w;
            };
            for k in 1..=k_max.min(half - 1) {
                fill(k, syn.twiddle[k]);
            }
            for j in 1..=k_max.min(half - 1) {
                let k = half - j;
                if k > k_max {
                    fill(k, -syn.twiddle[j].conj());
                }
            }
            syn.fft.process_with_scratch(&mut syn.buf, &mut syn.scratch);
            let buf = &syn.buf;
            Ok(out(n, &|j| {
                let z = buf[j / 2];
                (if j % 2 == 0 { z.re } else { z.im }) * inv_n
            }))
        } else {
            for (k, &c) in syn.coeffs.iter().enumerate() {
                syn.buf[k + 1] = c;
                syn.buf[n - k - 1] = c.conj();
            }
            syn.fft.process_with_scratch(&mut syn.buf, &mut syn.scratch);
            let buf = &syn.buf;
            Ok(out(n, &|j| buf[j].re * inv_n))
        }
    })
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
