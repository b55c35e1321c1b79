//! Figure 15: prototype 2 at 15 V, output power spectra at three levels (claims F15-a to
//! F15-c).

use crate::study::ensemble::Ensemble;

/// Figure 15's levels (g²/Hz).
pub const FIG15_LEVELS: [f64; 3] = [0.34e-3, 0.55e-3, 1.69e-3];

/// Records per level in Figure 15: enough for 5-95 % quantiles of single-record widths and
/// 256 record pairs per ratio.
pub const FIG15_REALISATIONS: usize = 16;

/// Shifts of the half-power band edges of the ensemble-mean PSD from `low` to `high` (Hz):
/// `(up, down)` = (upper edge of `high` minus that of `low`, lower edge of `low` minus that of
/// `high`); `None` if either band is undetermined. The widening is "towards higher
/// frequencies" (claim F15-c) when `up > down` and `up > 0`.
pub fn edge_shifts(low: &Ensemble, high: &Ensemble) -> Option<(f64, f64)> {
    let a = low.mean_widths.half_power?;
    let b = high.mean_widths.half_power?;
    Some((b.f_hi_hz - a.f_hi_hz, a.f_lo_hz - b.f_lo_hz))
}
