//! The noise synthesis's inverse transform: a complex-to-real inverse DFT of even length `M`
//! from the half-spectrum `X_0..=X_{M/2}`, on RustFFT's **scalar** planner.
//!
//! The planner is named rather than chosen at run time so that a record's bits do not depend
//! on the SIMD instructions of the CPU (RustFFT's default planner picks AVX, SSE or NEON where
//! it finds them, and their butterflies round differently): the noise records are inputs to
//! every random-vibration result, whereas a spectrum is an estimate read to a tolerance.
//!
//! # The transform
//!
//! `x[n] = Σ_{k=0}^{M-1} X_k e^{+2πikn/M}`, un-normalised, over the Hermitian spectrum
//! `X_{M-k} = conj(X_k)`, with one complex inverse FFT of length `h = M/2` (the standard
//! even-length packing, Sorensen, Jones, Heideman & Burrus, "Real-valued fast Fourier
//! transform algorithms", IEEE Trans. ASSP 35 (1987) 849-863): with `W_k = e^{+2πik/M}`,
//! `Z_k = (X_k + conj(X_{h-k})) + i W_k (X_k - conj(X_{h-k}))` for `k = 0..h`, and
//! `z = IFFT_h(Z)` gives `x[2j] = Re z_j`, `x[2j+1] = Im z_j`.
//!
//! The packing step is written in the order of operations of the `realfft` crate's
//! `ComplexToRealEven` (version 3.5), which the synthesis used over the same scalar FFT, so
//! that the records keep their bits: the pairs `(X_k, X_{h-k})` are combined from both ends
//! with `k < h/2`, `X_0` with `X_h`, and the centre bin of an even `h` on its own.

use std::sync::Arc;

use rustfft::num_complex::Complex;
use rustfft::{Fft, FftPlannerScalar};

/// A planned inverse real transform of one even length, with its buffers.
pub(super) struct InverseRealFft {
    /// The real length `M`.
    len: usize,
    /// `conj(e^{-2πik/M})` for `k = 1..ceil(M/4)`.
    twiddles: Vec<Complex<f64>>,
    /// The complex inverse FFT of length `M/2`.
    fft: Arc<dyn Fft<f64>>,
    scratch: Vec<Complex<f64>>,
    /// The complex output `z`, `M/2` values: the real samples in pairs.
    packed: Vec<Complex<f64>>,
}

impl InverseRealFft {
    /// Plans the transform of real length `len`, which the caller makes even and positive.
    pub(super) fn new(len: usize) -> Self {
        debug_assert!(
            len >= 2 && len.is_multiple_of(2),
            "an even length >= 2: {len}"
        );
        let half = len / 2;
        let twiddle_count = len / 4 + usize::from(!len.is_multiple_of(4));
        let step = -2.0 * std::f64::consts::PI / len as f64;
        let twiddles = (1..twiddle_count)
            .map(|k| {
                let angle = step * k as f64;
                Complex::new(angle.cos(), -angle.sin())
            })
            .collect();
        let fft = FftPlannerScalar::<f64>::new().plan_fft_inverse(half);
        Self {
            len,
            twiddles,
            scratch: vec![Complex::new(0.0, 0.0); fft.get_outofplace_scratch_len()],
            packed: vec![Complex::new(0.0, 0.0); half],
            fft,
        }
    }

    /// The real length `M`.
    pub(super) fn len(&self) -> usize {
        self.len
    }

    /// Transforms the half-spectrum `spectrum` (`M/2 + 1` values, `Im X_0 = Im X_{M/2} = 0`;
    /// overwritten) and returns the samples in pairs: `x[2j] = Re z_j`, `x[2j+1] = Im z_j`.
    pub(super) fn process(&mut self, spectrum: &mut [Complex<f64>]) -> &[Complex<f64>] {
        let half = self.len / 2;
        debug_assert_eq!(spectrum.len(), half + 1);
        let (left, right) = spectrum.split_at_mut(spectrum.len() / 2);
        let (Some((first, left)), Some((last, right))) =
            (left.split_first_mut(), right.split_last_mut())
        else {
            unreachable!("an even length >= 2 has at least two bins")
        };
        let (sum, diff) = (*first + *last, *first - *last);
        *first = Complex::new(sum.re - sum.im, diff.re - diff.im);
        for ((w, a), b) in self.twiddles.iter().zip(left).zip(right.iter_mut().rev()) {
            let (sum, diff) = (*a + *b, *a - *b);
            let re = sum.im * w.re + diff.re * w.im;
            let im = sum.im * w.im - diff.re * w.re;
            *a = Complex::new(sum.re - re, diff.im - im);
            *b = Complex::new(sum.re + re, -im - diff.im);
        }
        if spectrum.len() % 2 == 1 {
            let centre = spectrum.len() / 2;
            let doubled = spectrum[centre] + spectrum[centre];
            spectrum[centre] = doubled.conj();
        }
        self.fft.process_outofplace_with_scratch(
            &mut spectrum[..half],
            &mut self.packed,
            &mut self.scratch,
        );
        &self.packed
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The direct sum `Σ_k X_k e^{+2πikn/M}` over the Hermitian spectrum.
    fn direct(half_spectrum: &[Complex<f64>], m: usize) -> Vec<f64> {
        (0..m)
            .map(|n| {
                (0..m)
                    .map(|k| {
                        let x = if k <= m / 2 {
                            half_spectrum[k]
                        } else {
                            half_spectrum[m - k].conj()
                        };
                        let angle = 2.0 * std::f64::consts::PI * ((k * n) % m) as f64 / m as f64;
                        (x * Complex::new(angle.cos(), angle.sin())).re
                    })
                    .sum()
            })
            .collect()
    }

    #[test]
    fn matches_the_direct_sum_for_even_and_odd_halves() {
        // Lengths whose half is odd (M % 4 = 2: no centre bin), even (a centre bin), a power of
        // two and a smooth composite. Tolerance 1e-12 of the sum of |X_k|: the rounding of a
        // few dozen operations per output on values of that size.
        for m in [2usize, 6, 10, 12, 16, 30, 64, 210] {
            let spectrum: Vec<Complex<f64>> = (0..=m / 2)
                .map(|k| {
                    let t = k as f64;
                    let im = if k == 0 || k == m / 2 {
                        0.0
                    } else {
                        (1.3 * t).cos()
                    };
                    Complex::new((0.7 * t + 0.2).sin(), im)
                })
                .collect();
            let want = direct(&spectrum, m);
            let scale: f64 = spectrum.iter().map(|c| c.norm()).sum();
            let mut fft = InverseRealFft::new(m);
            assert_eq!(fft.len(), m);
            let mut buf = spectrum.clone();
            let got: Vec<f64> = fft
                .process(&mut buf)
                .iter()
                .flat_map(|z| [z.re, z.im])
                .collect();
            assert_eq!(got.len(), m);
            for (n, (g, w)) in got.iter().zip(&want).enumerate() {
                assert!(
                    (g - w).abs() <= 1e-12 * scale,
                    "M = {m}, n = {n}: {g} vs {w}"
                );
            }
        }
    }
}
