//! The random-vibration claims of the study (Figures 12, 14 and 15) by ensembles of 10 s
//! records: the figures' own protocol with the drive scaled by the variant's acceleration
//! scale, on the streams of the stated level at every point (common random numbers).

use super::quantity::{ratio, Estimate, Outcome};
use super::ranges::Variant;
use crate::device::Device;
use crate::num::stats::Jackknife;
use crate::paper::ensembles::{
    protocol_spec, WidthReading, P1_BAND_HZ, P1_NPERSEG, P2_BAND_HZ, P2_NPERSEG,
};
use crate::paper::figures::fig12::{self, FIG12_LEVELS};
use crate::paper::figures::fig15::{self, FIG15_LEVELS};
use crate::paper::setups::{P1_BIAS_V, P2_BIAS_V};
use crate::physics::two_port::efficiency;
use crate::progress::Silent;
use crate::study::ensemble::{run_ensembles, Ensemble, EnsembleCase, EnsembleSpec};

/// An ensemble of the study at the stated level `psd_g2_per_hz`: the figure's protocol
/// ([`protocol_spec`], without the second segmenting) with `records` records, the streams of
/// the stated level (the same at every point of the study: common random numbers) and the
/// drive scaled by `accel_scale` (the PSD by its square). With the figures' 32 records and
/// the published set it is the figure's ensemble.
pub fn study_ensemble_spec(
    device: &Device,
    psd_g2_per_hz: f64,
    (nperseg, band_hz): (usize, (f64, f64)),
    records: usize,
    accel_scale: f64,
) -> EnsembleSpec {
    let mut spec = protocol_spec(device, psd_g2_per_hz, nperseg, band_hz, records, false);
    spec.record.noise.psd_g2_per_hz *= accel_scale * accel_scale;
    spec
}

/// The half-power width of an ensemble-mean PSD (Hz) with its jackknife interval, or failed
/// where undetermined.
fn mean_width(e: &Ensemble) -> Estimate {
    let w = WidthReading::HalfPower.mean_width(e);
    if w.estimate.is_finite() {
        (Outcome::Value(w.estimate), Some(w.ci95))
    } else {
        (Outcome::Failed, None)
    }
}

/// The ratio of two estimates from independent ensembles, its interval by propagating the
/// relative half-widths (first order).
fn ratio_estimate(a: Estimate, b: Estimate) -> Estimate {
    let r = ratio(a.0, b.0);
    let ci = match (r.value(), a.0.value(), a.1, b.0.value(), b.1) {
        (Some(r), Some(x), Some(cx), Some(y), Some(cy)) => {
            Some(r.abs() * ((cx / x).powi(2) + (cy / y).powi(2)).sqrt())
        }
        _ => None,
    };
    (r, ci)
}

/// The peak frequency of an ensemble-mean PSD (Hz) with its delete-one jackknife interval over
/// the records, at least one bin wide: the estimate lives on the Welch grid.
fn mean_peak(e: &Ensemble) -> Estimate {
    let sum = &e.mean_spectrum.total;
    let n = e.records.len();
    let mut p = sum.clone();
    let jack = Jackknife::of(n, sum.peak().0, |i| {
        let x = &e.records[i].spectrum.total.density;
        for ((d, m), x) in p.density.iter_mut().zip(&sum.density).zip(x) {
            *d = (n as f64 * m - x) / (n - 1) as f64;
        }
        p.peak().0
    });
    let ci = jack.ci95.max(sum.df());
    (Outcome::Value(jack.estimate), ci.is_finite().then_some(ci))
}

/// The study's ensembles of `device` at the stated `levels` ([`study_ensemble_spec`]), in
/// order; `None` if any failed.
fn study_ensembles(
    device: &Device,
    levels: &[f64],
    welch: (usize, (f64, f64)),
    records: usize,
    accel_scale: f64,
) -> Option<Vec<Ensemble>> {
    let cases: Vec<EnsembleCase> = levels
        .iter()
        .map(|&sa| EnsembleCase {
            device: device.clone(),
            spec: study_ensemble_spec(device, sa, welch, records, accel_scale),
        })
        .collect();
    run_ensembles(&cases, &Silent).ok()
}

/// Figure 12 by `records` records at 7.4e-3 and 2.85e-2 g²/Hz: the two half-power widths and
/// their ratio, with their intervals.
pub(super) fn p1_fig12(variant: &Variant, records: usize) -> [Estimate; 3] {
    let levels = [FIG12_LEVELS[fig12::LOW], FIG12_LEVELS[fig12::HIGH]];
    let device = variant.device.with_bias(P1_BIAS_V);
    let welch = (P1_NPERSEG, P1_BAND_HZ);
    let Some(ens) = study_ensembles(&device, &levels, welch, records, variant.accel_scale) else {
        return [(Outcome::Failed, None); 3];
    };
    let (lo, hi) = (mean_width(&ens[0]), mean_width(&ens[1]));
    [lo, hi, ratio_estimate(hi, lo)]
}

/// Figures 14 and 15 by `records` records at 0.34e-3, 0.55e-3 and 1.69e-3 g²/Hz
/// (15 V): the efficiency at 1.69e-3 (%, of the **stated** level, as the paper divides by its
/// Sa), the peak and width at 0.34e-3, the width ratio 0.55e-3 over 0.34e-3, and the widening
/// towards higher frequencies at 1.69e-3 ([`fig15::widens_up`]), with the intervals of the
/// first four.
pub(super) fn p2_ensembles(variant: &Variant, records: usize) -> [Estimate; 5] {
    let device = variant.device.with_bias(P2_BIAS_V);
    let welch = (P2_NPERSEG, P2_BAND_HZ);
    let Some(ens) = study_ensembles(&device, &FIG15_LEVELS, welch, records, variant.accel_scale)
    else {
        return [(Outcome::Failed, None); 5];
    };
    let (e34, e55, e169) = (&ens[fig15::L034], &ens[fig15::L055], &ens[fig15::L169]);
    let eff = efficiency(&device, e169.power_w.mean, FIG15_LEVELS[fig15::L169]) * 100.0;
    // The efficiency is proportional to the mean power.
    let eff_ci = eff * e169.power_w.ci95 / e169.power_w.mean;
    let w34 = mean_width(e34);
    let widening = fig15::widens_up(e34, e169).map_or(Outcome::Failed, Outcome::yes_no);
    [
        (Outcome::Value(eff), eff_ci.is_finite().then_some(eff_ci)),
        mean_peak(e34),
        w34,
        ratio_estimate(mean_width(e55), w34),
        (widening, None),
    ]
}
