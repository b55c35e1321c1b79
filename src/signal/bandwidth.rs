//! Widths and edges of a spectral density: the band around the peak where the density stays
//! above a fraction of its peak ([`width_at_fraction`]; 0.5 of a power density is the 3 dB
//! bandwidth, 0.25 the half-amplitude width), the upper edge of a low-pass band
//! ([`upper_band_edge_hz`]), and the restriction and averaging of densities. No smoothing is
//! applied: on a noisy estimate a width inherits the estimator's scatter.

use crate::signal::welch::{peak_index, Psd};

/// A band around a spectral peak, from [`width_at_fraction`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Bandwidth {
    /// Lower edge, Hz (interpolated).
    pub f_lo_hz: f64,
    /// Upper edge, Hz (interpolated).
    pub f_hi_hz: f64,
    /// `f_hi_hz - f_lo_hz`, Hz.
    pub width_hz: f64,
    /// Frequency of the peak bin, Hz.
    pub peak_hz: f64,
    /// Density at the peak bin.
    pub peak_value: f64,
}

/// Width of the contiguous band around the global peak where `density >= fraction · peak`.
///
/// Each edge lies between the last bin at or above the threshold and the first bin below it,
/// placed by linear interpolation of the density between those two bins. On a power PSD,
/// `fraction = 0.5` gives the 3 dB (half-power) bandwidth and `0.25` the half-amplitude
/// (-6 dB) width. No smoothing is applied.
///
/// Returns `None` if `fraction` is not in `(0, 1)`, the spectrum has fewer than two bins or
/// no positive finite peak, or the band runs into either end of the spectrum (the edge is then
/// not determined).
///
/// ```
/// use endstop::signal::{width_at_fraction, Psd};
///
/// // A Lorentzian 1 / (1 + ((f - 100) / 2)^2) on a 0.01 Hz grid: its half-power width is
/// // 2 x 2 = 4 Hz. The edges are interpolated linearly between bins; over 0.01 Hz the
/// // Lorentzian's curvature leaves an error far below 1e-3 Hz.
/// let freq_hz: Vec<f64> = (0..20_001).map(|k| k as f64 * 0.01).collect();
/// let density = freq_hz.iter().map(|f| 1.0 / (1.0 + ((f - 100.0) / 2.0).powi(2))).collect();
/// let psd = Psd { freq_hz, density, segments: 0 };
/// let bw = width_at_fraction(&psd, 0.5).unwrap();
/// assert!((bw.width_hz - 4.0).abs() < 1e-3);
/// assert!((bw.peak_hz - 100.0).abs() < 1e-9);
/// ```
pub fn width_at_fraction(psd: &Psd, fraction: f64) -> Option<Bandwidth> {
    if !(fraction > 0.0 && fraction < 1.0) || psd.density.len() < 2 {
        return None;
    }
    let d = &psd.density;
    let f = &psd.freq_hz;
    let ip = peak_index(d)?;
    let peak_value = d[ip];
    if !(peak_value.is_finite() && peak_value > 0.0) {
        return None;
    }
    let thr = fraction * peak_value;
    let above = |i: usize| d[i] >= thr;
    // Crossing between an inside bin `a` and an outside bin `b`.
    let cross = |a: usize, b: usize| f[a] + (thr - d[a]) * (f[b] - f[a]) / (d[b] - d[a]);

    let lo = (0..ip).rev().find(|&i| !above(i))?;
    let hi = (ip + 1..d.len()).find(|&i| !above(i))?;
    let f_lo_hz = cross(lo + 1, lo);
    let f_hi_hz = cross(hi - 1, hi);
    Some(Bandwidth {
        f_lo_hz,
        f_hi_hz,
        width_hz: f_hi_hz - f_lo_hz,
        peak_hz: f[ip],
        peak_value,
    })
}

/// Widths of an output power PSD around its peak (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Widths {
    /// Band where the PSD is at least half its peak: the 3 dB (half-power) bandwidth.
    pub half_power: Option<Bandwidth>,
    /// Band where the PSD is at least a quarter of its peak: the half-amplitude (-6 dB) width.
    pub half_amplitude: Option<Bandwidth>,
}

impl Widths {
    /// Widths of `psd` (searched over all its bins; restrict it first to the analysis band).
    pub fn of(psd: &Psd) -> Self {
        Self {
            half_power: width_at_fraction(psd, 0.5),
            half_amplitude: width_at_fraction(psd, 0.25),
        }
    }

    /// 3 dB width (Hz), NaN if undetermined.
    pub fn bw3db_hz(&self) -> f64 {
        self.half_power.map_or(f64::NAN, |b| b.width_hz)
    }

    /// Half-amplitude width (Hz), NaN if undetermined.
    pub fn bw6db_hz(&self) -> f64 {
        self.half_amplitude.map_or(f64::NAN, |b| b.width_hz)
    }
}

/// The band edge of a low-pass spectrum: the highest frequency at which `psd` is still at least
/// `fraction` of `level`, interpolated linearly to the next bin (Hz). Scanning down from the
/// top makes a single low bin inside the band irrelevant. NaN if no bin reaches the threshold
/// or the top bin does.
pub fn upper_band_edge_hz(psd: &Psd, level: f64, fraction: f64) -> f64 {
    let thr = fraction * level;
    let d = &psd.density;
    let f = &psd.freq_hz;
    match (0..d.len()).rev().find(|&i| d[i] >= thr) {
        Some(i) if i + 1 < d.len() => f[i] + (thr - d[i]) * (f[i + 1] - f[i]) / (d[i + 1] - d[i]),
        _ => f64::NAN,
    }
}

/// The bins of `psd` with `f_lo <= f <= f_hi`.
pub fn restrict(psd: &Psd, f_lo: f64, f_hi: f64) -> Psd {
    let (freq_hz, density) = psd
        .freq_hz
        .iter()
        .zip(&psd.density)
        .filter(|(f, _)| (f_lo..=f_hi).contains(*f))
        .map(|(f, d)| (*f, *d))
        .unzip();
    Psd {
        freq_hz,
        density,
        segments: psd.segments,
    }
}

/// Element-wise mean of densities on a common grid.
pub fn mean_psd<'a>(psds: impl Iterator<Item = &'a Psd>) -> Psd {
    let mut out: Option<Psd> = None;
    let mut n = 0usize;
    for p in psds {
        n += 1;
        match &mut out {
            None => out = Some(p.clone()),
            Some(o) => o
                .density
                .iter_mut()
                .zip(&p.density)
                .for_each(|(a, b)| *a += b),
        }
    }
    let mut o = out.unwrap_or(Psd {
        freq_hz: Vec::new(),
        density: Vec::new(),
        segments: 0,
    });
    o.density.iter_mut().for_each(|d| *d /= n.max(1) as f64);
    o.segments *= n;
    o
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn band_at_spectrum_edge_is_none() {
        let psd = Psd {
            freq_hz: vec![0.0, 1.0, 2.0],
            density: vec![1.0, 0.9, 0.1],
            segments: 0,
        };
        assert!(width_at_fraction(&psd, 0.5).is_none());
        let psd = Psd {
            freq_hz: vec![0.0, 1.0, 2.0],
            density: vec![0.0, 1.0, 0.0],
            segments: 0,
        };
        let bw = width_at_fraction(&psd, 0.5).unwrap();
        assert!((bw.width_hz - 1.0).abs() < 1e-15);
        assert!(width_at_fraction(&psd, 1.0).is_none());
    }

    #[test]
    fn band_edge_of_a_step() {
        let psd = Psd {
            freq_hz: (0..10).map(|i| i as f64).collect(),
            density: vec![1.0, 1.0, 0.1, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0],
            segments: 1,
        };
        assert!((upper_band_edge_hz(&psd, 1.0, 0.5) - 5.5).abs() < 1e-12);
    }
}
