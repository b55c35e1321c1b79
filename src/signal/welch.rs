//! Welch power spectral density, matching `scipy.signal.welch`.
//!
//! # Conventions
//!
//! [`welch`] follows `scipy.signal.welch` with its defaults except the segment length
//! (`window='hann', detrend='constant', return_onesided=True, scaling='density',
//! average='mean'`), so `welch(x, fs, &WelchOptions { nperseg, noverlap })` equals
//! `scipy.signal.welch(x, fs=fs, nperseg=nperseg, noverlap=noverlap)` to rounding.
//!
//! * **Segments.** Segment `j` is `x[j·step .. j·step + nperseg]` with
//!   `step = nperseg - noverlap`; only full segments are used (a tail shorter than `nperseg`
//!   is dropped, no padding), so there are `(len - nperseg) / step + 1` of them.
//! * **Detrend.** Each segment's own mean is subtracted before windowing (`'constant'`),
//!   summed as numpy sums, pairwise (blocks of at most 128 values in eight partial sums).
//! * **Window.** Periodic Hann, `w[n] = 0.5 - 0.5 cos(2πn / nperseg)` for
//!   `n = 0..nperseg` (scipy's `get_window('hann', nperseg)`, which is periodic: `fftbins=True`).
//! * **Transform.** An un-normalised forward DFT of length `nperseg` (no zero padding),
//!   `X_k = Σ_n w[n] (x[n] - mean) e^{-2πikn/nperseg}`, computed for `k = 0..=nperseg/2` by a
//!   real-input FFT (`realfft` over RustFFT's default planner, which uses the CPU's SIMD
//!   instructions where it finds them: AVX, SSE or NEON). The SIMD butterflies round
//!   differently from the scalar ones, so the last bits of a density depend on the CPU: on
//!   band-limited noise every bin moves by under 1e-15 of the spectrum's peak between the two
//!   (a bin within 1e-3 of the peak by under 1e-14 of itself; a bin of the empty stop band,
//!   1e-8 of the peak, by up to 1e-7 of itself), far below the estimate's own scatter
//!   (`1/sqrt(segments)`, a few per cent) and below every tolerance a spectrum is read to.
//! * **Scaling.** Density: `|X_k|² / (fs Σ w²)`, in *units²/Hz* where *units* are those of `x`
//!   (m²/s⁴/Hz for an acceleration in m/s²). With this scaling the integral of the PSD is the
//!   variance (Parseval), for any window.
//! * **One-sided.** Bins `k = 0..=nperseg/2` at `f_k = k fs / nperseg` Hz (`0..=fs/2`); every
//!   bin except DC and, for even `nperseg`, Nyquist is doubled, so the one-sided density of
//!   white noise is twice its two-sided level.
//! * **Averaging.** Arithmetic mean of the segment periodograms (`average='mean'`).
//!
//! Bandwidths ([`crate::signal::width_at_fraction`]) are read from the density as given: no smoothing is

use realfft::RealFftPlanner;
use thiserror::Error;

/// Segmenting of a Welch estimate: segment length and overlap, in samples.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct WelchOptions {
    /// Segment (and DFT) length, samples. Bin spacing is `fs / nperseg`.
    pub nperseg: usize,
    /// Samples shared by consecutive segments; must be below `nperseg`.
    pub noverlap: usize,
}

impl WelchOptions {
    /// Segments of `nperseg` samples with 50 % overlap (`noverlap = nperseg / 2`), the paper's
    /// choice and scipy's default overlap.
    pub fn half_overlap(nperseg: usize) -> Self {
        Self {
            nperseg,
            noverlap: nperseg / 2,
        }
    }
}

/// Errors from [`welch`].
#[derive(Debug, Clone, PartialEq, Error)]
pub enum SpectralError {
    /// `nperseg` is zero.
    #[error("welch: nperseg = 0 is invalid; expected 1 <= nperseg <= signal length")]
    NpersegZero,
    /// `nperseg` exceeds the number of samples.
    #[error(
        "welch: nperseg = {nperseg} is invalid; expected 1 <= nperseg <= signal length = {len}"
    )]
    NpersegTooLong {
        /// Requested segment length.
        nperseg: usize,
        /// Number of samples in the signal.
        len: usize,
    },
    /// `noverlap` is not below `nperseg`.
    #[error(
        "welch: noverlap = {noverlap} is invalid; expected 0 <= noverlap < nperseg = {nperseg}"
    )]
    NoverlapTooLarge {
        /// Requested overlap.
        noverlap: usize,
        /// Segment length.
        nperseg: usize,
    },
    /// The sample rate is zero, negative, NaN or infinite.
    #[error("welch: fs = {fs} is invalid; expected a positive finite sample rate in Hz")]
    InvalidSampleRate {
        /// Requested sample rate, Hz.
        fs: f64,
    },
}

/// A one-sided power spectral density on a uniform frequency grid.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Psd {
    /// Bin frequencies, Hz, uniformly spaced and increasing (from 0 for [`welch`]).
    pub freq_hz: Vec<f64>,
    /// One-sided density, units²/Hz (twice the two-sided level except at DC and Nyquist).
    pub density: Vec<f64>,
    /// Number of segments averaged (0 for a density not produced by [`welch`]).
    pub segments: usize,
}

impl Psd {
    /// Bin spacing, Hz: `(f_last - f_first) / (bins - 1)`; NaN with fewer than two bins.
    pub fn df(&self) -> f64 {
        match self.freq_hz.len() {
            0 | 1 => f64::NAN,
            n => (self.freq_hz[n - 1] - self.freq_hz[0]) / (n - 1) as f64,
        }
    }

    /// Rectangle-rule integral `Σ density · df`, units². For [`welch`] this is the mean
    /// variance of the detrended segments (Parseval).
    pub fn integral(&self) -> f64 {
        self.density.iter().sum::<f64>() * self.df()
    }

    /// Frequency and value of the largest density (first one on ties); NaN values are
    /// skipped; `(NaN, NaN)` if there is none.
    pub fn peak(&self) -> (f64, f64) {
        match peak_index(&self.density) {
            Some(i) => (self.freq_hz[i], self.density[i]),
            None => (f64::NAN, f64::NAN),
        }
    }

    /// Mean two-sided level over the bins with `f_lo <= f <= f_hi`: the mean of
    /// `density / 2`, units²/Hz. NaN if no bin lies in the band. Keep DC and Nyquist out of
    /// the band (they are not doubled in a one-sided density).
    pub fn two_sided_level_in_band(&self, f_lo: f64, f_hi: f64) -> f64 {
        let (sum, count) = self
            .freq_hz
            .iter()
            .zip(&self.density)
            .filter(|(f, _)| (f_lo..=f_hi).contains(*f))
            .fold((0.0, 0usize), |(s, c), (_, d)| (s + d, c + 1));
        if count == 0 {
            f64::NAN
        } else {
            0.5 * sum / count as f64
        }
    }

    /// The densities of the bins with `f_lo <= f <= f_hi`, in frequency order.
    pub fn densities_in_band(&self, f_lo: f64, f_hi: f64) -> Vec<f64> {
        self.freq_hz
            .iter()
            .zip(&self.density)
            .filter(|(f, _)| (f_lo..=f_hi).contains(*f))
            .map(|(_, d)| *d)
            .collect()
    }

    /// The largest density at or above `f_lo` (0 if no bin lies there).
    pub fn max_density_from(&self, f_lo: f64) -> f64 {
        self.freq_hz
            .iter()
            .zip(&self.density)
            .filter(|(f, _)| **f >= f_lo)
            .map(|(_, d)| *d)
            .fold(0.0, f64::max)
    }

    /// The same grid with every density multiplied by `factor` (for example 0.5 for the
    /// two-sided level of a one-sided density away from DC and Nyquist).
    pub fn scaled(&self, factor: f64) -> Psd {
        Psd {
            freq_hz: self.freq_hz.clone(),
            density: self.density.iter().map(|d| d * factor).collect(),
            segments: self.segments,
        }
    }
}

/// Welch PSD of `x` sampled at `fs` Hz, with scipy's conventions (see the module docs).
///
/// ```
/// use endstop::signal::{welch, WelchOptions};
///
/// // A sine of amplitude 2 at 125 Hz sampled at 1 kHz: 125 Hz falls on a bin of 1000-sample
/// // segments, and each segment holds whole periods.
/// let fs = 1000.0;
/// let x: Vec<f64> = (0..10_000)
///     .map(|k| 2.0 * (2.0 * std::f64::consts::PI * 125.0 * k as f64 / fs).sin())
///     .collect();
/// let psd = welch(&x, fs, &WelchOptions::half_overlap(1000))?;
/// assert_eq!(psd.peak().0, 125.0);
/// // The one-sided density integrates to the mean square, A^2 / 2 = 2 (Parseval with the
/// // window's normalisation; the Hann window's leakage stays in the sum): to rounding.
/// assert!((psd.integral() - 2.0).abs() < 1e-9);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn welch(x: &[f64], fs: f64, cfg: &WelchOptions) -> Result<Psd, SpectralError> {
    // A signal of zeros (the outputs of a device without a transducer) has the density zero
    // in every bin, as the transform below gives it, bit for bit: no transform is needed.
    if all_zero(x) {
        return welch_of_zeros(x.len(), fs, cfg);
    }
    let (freq_hz, segments) = grid(x.len(), fs, cfg)?;
    let WelchOptions { nperseg, noverlap } = *cfg;
    let step = nperseg - noverlap;
    let n_bins = freq_hz.len();

    let window = hann_periodic(nperseg);
    let win_sq_sum: f64 = window.iter().map(|w| w * w).sum();

    // A real-input FFT (`realfft`'s real-to-complex transform over RustFFT, one complex FFT
    // of half the length for an even `nperseg`) gives the bins `0..=nperseg/2` directly.
    let fft = RealFftPlanner::<f64>::new().plan_fft_forward(nperseg);
    let mut buf = fft.make_input_vec();
    let mut bins = fft.make_output_vec();
    let mut scratch = fft.make_scratch_vec();
    let mut acc = vec![0.0; n_bins];

    for seg in x.windows(nperseg).step_by(step).take(segments) {
        let mean = pairwise_sum(seg) / nperseg as f64;
        for ((b, &v), &w) in buf.iter_mut().zip(seg).zip(&window) {
            *b = w * (v - mean);
        }
        if let Err(e) = fft.process_with_scratch(&mut buf, &mut bins, &mut scratch) {
            unreachable!("the real FFT refused its own buffers: {e}")
        }
        for (a, c) in acc.iter_mut().zip(&bins) {
            *a += c.norm_sqr();
        }
    }

    // Density scaling, one-sided doubling (not DC, not an even-length Nyquist), mean.
    let scale = 1.0 / (fs * win_sq_sum) / segments as f64;
    let last_doubled = if nperseg % 2 == 0 { n_bins - 1 } else { n_bins };
    let density = acc
        .iter()
        .enumerate()
        .map(|(k, &p)| {
            let one_sided = if k >= 1 && k < last_doubled { 2.0 } else { 1.0 };
            p * scale * one_sided
        })
        .collect();
    Ok(Psd {
        freq_hz,
        density,
        segments,
    })
}

/// The Welch PSD of `len` zeros sampled at `fs` Hz: [`welch`]'s bins and segment count, the
/// density zero in each bin (as [`welch`] gives it for a signal of zeros), without the signal.
pub fn welch_of_zeros(len: usize, fs: f64, cfg: &WelchOptions) -> Result<Psd, SpectralError> {
    let (freq_hz, segments) = grid(len, fs, cfg)?;
    let n_bins = freq_hz.len();
    Ok(Psd {
        freq_hz,
        density: vec![0.0; n_bins],
        segments,
    })
}

/// The bin frequencies (Hz) and the number of segments of a Welch estimate of `len` samples
/// at `fs` Hz, or why `cfg` does not apply to them.
fn grid(len: usize, fs: f64, cfg: &WelchOptions) -> Result<(Vec<f64>, usize), SpectralError> {
    let WelchOptions { nperseg, noverlap } = *cfg;
    if !(fs.is_finite() && fs > 0.0) {
        return Err(SpectralError::InvalidSampleRate { fs });
    }
    if nperseg == 0 {
        return Err(SpectralError::NpersegZero);
    }
    if nperseg > len {
        return Err(SpectralError::NpersegTooLong { nperseg, len });
    }
    if noverlap >= nperseg {
        return Err(SpectralError::NoverlapTooLarge { noverlap, nperseg });
    }
    let step = nperseg - noverlap;
    let segments = (len - nperseg) / step + 1;
    let freq_hz = (0..nperseg / 2 + 1)
        .map(|k| k as f64 * fs / nperseg as f64)
        .collect();
    Ok((freq_hz, segments))
}

/// The sum of `x` by numpy's pairwise summation scheme (its `pairwise_sum`, which `np.mean`
/// of contiguous data uses): a stretch of more than 128 values is split in two at a multiple
/// of 8 near its middle and the halves summed apart; a shorter one goes in eight interleaved
/// partial sums,
/// combined as `((s0 + s1) + (s2 + s3)) + ((s4 + s5) + (s6 + s7))`, then its tail of under
/// eight one by one; under eight values are summed in order. Written out because a plain
/// sequential sum is one chain of dependent additions: it took most of the estimate's time
/// outside the FFT (measured with `perf` on Figure 12's records), and the eight partial sums
/// run side by side.
fn pairwise_sum(x: &[f64]) -> f64 {
    const BLOCK: usize = 128;
    let n = x.len();
    if n < 8 {
        return x.iter().fold(0.0, |s, v| s + v);
    }
    if n > BLOCK {
        let half = n / 2;
        let half = half - half % 8;
        return pairwise_sum(&x[..half]) + pairwise_sum(&x[half..]);
    }
    let mut r = [0.0; 8];
    r.copy_from_slice(&x[..8]);
    let body = n - n % 8;
    for chunk in x[8..body].chunks_exact(8) {
        for (acc, v) in r.iter_mut().zip(chunk) {
            *acc += v;
        }
    }
    let mut s = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]));
    for v in &x[body..] {
        s += v;
    }
    s
}

/// Whether every value of `x` is zero (of either sign), as `x.iter().all(|&v| v == 0.0)`.
/// Written as an OR of the values' bits over blocks, without the sign bit, because the
/// one-value-at-a-time test with its early exit does not vectorise: it took about seven
/// instructions a sample (measured with callgrind on a record of a device without a
/// transducer, whose two output signals are all zeros), the blocks about one. A block with a
/// nonzero value still ends the test.
fn all_zero(x: &[f64]) -> bool {
    const BLOCK: usize = 256;
    const NOT_SIGN: u64 = !(1 << 63);
    x.chunks(BLOCK)
        .all(|b| b.iter().fold(0u64, |acc, v| acc | v.to_bits()) & NOT_SIGN == 0)
}

/// Periodic Hann window of length `n`: `0.5 - 0.5 cos(2πi/n)` (scipy `get_window('hann', n)`).
pub fn hann_periodic(n: usize) -> Vec<f64> {
    let nf = n as f64;
    (0..n)
        .map(|i| 0.5 - 0.5 * (std::f64::consts::TAU * i as f64 / nf).cos())
        .collect()
}

/// Welch segment length for MATLAB's `pwelch` default: eight segments with 50 % overlap,
/// `floor(N / 4.5)` samples each (MATLAB also zero-pads to a power of two and uses a Hamming
/// window; we keep our Hann window and no padding, so only the segmenting is MATLAB's).
pub fn matlab_default_nperseg(len: usize) -> usize {
    (len as f64 / 4.5).floor() as usize
}

/// Index of the largest non-NaN value (first on ties).
pub(crate) fn peak_index(d: &[f64]) -> Option<usize> {
    let mut best: Option<usize> = None;
    for (i, &v) in d.iter().enumerate() {
        if v.is_nan() {
            continue;
        }
        if best.is_none_or(|b| v > d[b]) {
            best = Some(i);
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_name_the_parameter() {
        let x = vec![0.0; 100];
        let e = |n, o, fs| {
            welch(
                &x,
                fs,
                &WelchOptions {
                    nperseg: n,
                    noverlap: o,
                },
            )
        };
        assert!(e(0, 0, 1.0)
            .unwrap_err()
            .to_string()
            .contains("nperseg = 0"));
        let msg = e(101, 0, 1.0).unwrap_err().to_string();
        assert!(
            msg.contains("nperseg = 101") && msg.contains("= 100"),
            "{msg}"
        );
        let msg = e(10, 10, 1.0).unwrap_err().to_string();
        assert!(msg.contains("noverlap = 10"), "{msg}");
        let msg = e(10, 5, f64::NAN).unwrap_err().to_string();
        assert!(msg.contains("fs = NaN"), "{msg}");
        assert_eq!(e(100, 50, 1.0).unwrap().segments, 1);
        assert_eq!(e(10, 5, 1.0).unwrap().segments, 19);
    }

    /// A signal of zeros (signed or not) has a density of positive zeros on the grid and
    /// with the segments of any signal of its length; one nonzero sample leaves that path.
    #[test]
    fn zeros_have_zero_density_on_the_same_grid() {
        let cfg = WelchOptions::half_overlap(256);
        let mut x = vec![0.0; 3000];
        x[7] = -0.0;
        let zero = welch(&x, 1e3, &cfg).unwrap();
        x[1500] = 1e-3;
        let one = welch(&x, 1e3, &cfg).unwrap();
        assert_eq!((&zero.freq_hz, zero.segments), (&one.freq_hz, one.segments));
        assert!(zero.density.iter().all(|d| d.to_bits() == 0));
        assert!(one.density.iter().any(|&d| d > 0.0));
    }

    /// The block test agrees with the value-by-value comparison with zero: signed zeros,
    /// subnormals, infinities and NaN, at a block's first and last place and in a tail.
    #[test]
    fn all_zero_is_the_comparison_with_zero() {
        let odd = [
            -0.0,
            f64::from_bits(1),
            -f64::from_bits(1),
            f64::MIN_POSITIVE,
            f64::INFINITY,
            f64::NAN,
            -f64::NAN,
            1.0,
        ];
        for len in [0, 1, 255, 256, 257, 1000] {
            let zeros = vec![0.0; len];
            assert!(all_zero(&zeros), "len {len}");
            for at in [0, len / 2, len.saturating_sub(1)]
                .into_iter()
                .filter(|&i| i < len)
            {
                for v in odd {
                    let mut x = zeros.clone();
                    x[at] = v;
                    let want = x.iter().all(|&v| v == 0.0);
                    assert_eq!(all_zero(&x), want, "len {len}, x[{at}] = {v:e}");
                }
            }
        }
    }

    #[test]
    fn band_selection_maximum_and_scaling() {
        let p = Psd {
            freq_hz: vec![0.0, 1.0, 2.0, 3.0],
            density: vec![4.0, 2.0, 6.0, 1.0],
            segments: 3,
        };
        assert_eq!(p.densities_in_band(1.0, 2.0), vec![2.0, 6.0]);
        assert_eq!(p.max_density_from(2.5), 1.0);
        assert_eq!(p.max_density_from(9.0), 0.0);
        let h = p.scaled(0.5);
        assert_eq!((h.density[2], h.segments), (3.0, 3));
    }

    #[test]
    fn pairwise_sum_is_the_sum() {
        // Integers below 2^53 add exactly in any order: every split and tail is exercised.
        for n in [0, 1, 7, 8, 9, 127, 128, 129, 1000, 4096] {
            let x: Vec<f64> = (0..n).map(|i| ((i * 7919) % 1013) as f64 - 500.0).collect();
            let want: f64 = x.iter().sum();
            assert_eq!(pairwise_sum(&x), want, "n = {n}");
        }
        // Rounded values: against a compensated (Neumaier) sum, within this scheme's error
        // bound k eps sum|x|, k the most additions a value passes through: one per level of
        // halving down to 128 values, 15 in its partial sum, 3 to combine the eight, 7 for the
        // tail (a sequential sum's k is n). The reference's own error is eps |sum| at most.
        let x: Vec<f64> = (0..5000).map(|i| (0.37 * i as f64).sin() * 1e3).collect();
        let (mut sum, mut carry) = (0.0f64, 0.0f64);
        for &v in &x {
            let t = sum + v;
            carry += if sum.abs() >= v.abs() {
                (sum - t) + v
            } else {
                (v - t) + sum
            };
            sum = t;
        }
        let levels = (x.len() as f64 / 128.0).log2().ceil();
        let k = levels + 15.0 + 3.0 + 7.0;
        let abs_sum: f64 = x.iter().map(|v| v.abs()).sum();
        let bound = k * f64::EPSILON * abs_sum + f64::EPSILON * (sum + carry).abs();
        assert!((pairwise_sum(&x) - (sum + carry)).abs() <= bound);
    }

    #[test]
    fn zeros_need_no_signal() {
        // The estimate of a signal of zeros without the signal: the same bins, segments and
        // (zero) densities bit for bit, and the same refusals, checked in the same order.
        let cfg = WelchOptions::half_overlap(256);
        for n in [256, 257, 1000, 4096] {
            let got = welch_of_zeros(n, 1e3, &cfg).unwrap();
            assert_eq!(got, welch(&vec![0.0; n], 1e3, &cfg).unwrap(), "n = {n}");
            assert!(got.density.iter().all(|d| d.to_bits() == 0), "n = {n}");
        }
        let bad = [
            (100, 0.0, cfg),
            (100, 1e3, WelchOptions::half_overlap(0)),
            (100, 1e3, cfg),
            (
                300,
                1e3,
                WelchOptions {
                    nperseg: 256,
                    noverlap: 256,
                },
            ),
        ];
        for (n, fs, c) in bad {
            assert_eq!(
                welch_of_zeros(n, fs, &c).unwrap_err(),
                welch(&vec![0.0; n], fs, &c).unwrap_err()
            );
        }
    }

    #[test]
    fn window_is_periodic_hann() {
        let w = hann_periodic(4);
        let expect = [0.0, 0.5, 1.0, 0.5];
        for (a, b) in w.iter().zip(expect) {
            assert!((a - b).abs() < 1e-15);
        }
    }
}
