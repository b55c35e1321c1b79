//! Figure 15: prototype 2 at 15 V (linear k_im of eq 19, b_im = 0.4 N s/m), output power
//! spectra at three levels (claims F15-a to F15-c), and the sampling distribution of the
//! bandwidths and of their ratio when each is read from one 10 s record, as the paper did.

use crate::device::Device;
use crate::num::stats::{pair_fraction, ratio_spread, Jackknife, MeanCi, Spread};
use crate::paper::claims::{Claims, Value};
use crate::paper::ensembles::{
    protocol_spec, run_levels, Level, LevelCase, WidthReading, P2_BAND_HZ, P2_NPERSEG,
};
use crate::paper::setups::prototype2_setup;
use crate::physics::two_port::linear_widths;
use crate::signal::Widths;
use crate::study::ensemble::Ensemble;
use crate::study::record::BroadbandError;

/// Figure 15's levels (g²/Hz).
pub const FIG15_LEVELS: [f64; 3] = [0.34e-3, 0.55e-3, 1.69e-3];

/// Records per level in Figure 15: enough for 5-95 % quantiles of single-record widths and
/// 1024 record pairs per ratio. The same as Figure 14's, whose ensembles at the three levels
/// are the same records (same seed, streams and settings; [`from_fig14`] takes them).
pub const FIG15_REALISATIONS: usize = crate::paper::fig14::FIG14_REALISATIONS;

/// Index in [`FIG15_LEVELS`] of 0.34e-3 g²/Hz (claim F15-a, and the base of every ratio).
pub const L034: usize = 0;

/// Index in [`FIG15_LEVELS`] of 0.55e-3 g²/Hz (claim F15-b).
pub const L055: usize = 1;

/// Index in [`FIG15_LEVELS`] of 1.69e-3 g²/Hz (claim F15-c).
pub const L169: usize = 2;

/// The claim whose paper value and tolerance the single-record pairs are counted against.
pub const RATIO_CLAIM: (&str, &str) = ("F15-b", "bw_ratio_0p55e-3_over_0p34e-3");

/// The simulations of Figure 15.
#[derive(Debug, Clone, PartialEq)]
pub struct Run {
    /// Prototype 2 as simulated ([`prototype2_setup`]).
    pub device: Device,
    /// One ensemble per level of [`FIG15_LEVELS`], in order, with MATLAB's default
    /// segmenting beside.
    pub levels: Vec<Level>,
    /// Widths of the linearised output PSD (no end-stops; the same at every level).
    pub linear: Widths,
}

/// Runs Figure 15 for prototype 2 (the parameter file's device), calling `progress` after each
/// record.
pub fn run(prototype2: &Device, progress: &(dyn Fn() + Sync)) -> Result<Run, BroadbandError> {
    run_records(prototype2, FIG15_REALISATIONS, progress)
}

/// [`run`] with `records` records per level (the first of the figure's streams).
pub fn run_records(
    prototype2: &Device,
    records: usize,
    progress: &(dyn Fn() + Sync),
) -> Result<Run, BroadbandError> {
    let dev = prototype2_setup(prototype2);
    let cases = FIG15_LEVELS
        .iter()
        .enumerate()
        .map(|(index, &sa)| LevelCase {
            set: "published".to_string(),
            index,
            device: dev.clone(),
            spec: level_spec(&dev, sa, records),
        })
        .collect();
    Ok(Run {
        levels: run_levels(cases, progress)?,
        linear: linear_widths(&dev, P2_BAND_HZ.0, P2_BAND_HZ.1),
        device: dev,
    })
}

/// Index in Figure 14's levels ([`crate::paper::fig14::FIG14_LEVELS`]) of each of
/// [`FIG15_LEVELS`] (a test checks that the levels agree).
pub const IN_FIG14: [usize; 3] = [5, 6, 8];

/// The ensemble of one of Figure 15's levels with `records` records.
fn level_spec(dev: &Device, sa: f64, records: usize) -> crate::study::ensemble::EnsembleSpec {
    protocol_spec(dev, sa, P2_NPERSEG, P2_BAND_HZ, records, true)
}

/// Figure 15 from Figure 14's run, whose published ensembles at [`IN_FIG14`] are Figure 15's
/// records (the same device, seed, streams, record and Welch settings: [`run`] would simulate
/// the same records again).
///
/// # Panics
/// If an ensemble of `fig14` is not the one [`run`] would simulate (a protocol constant of
/// one figure changed without the other).
pub fn from_fig14(fig14: &crate::paper::fig14::Run) -> Run {
    // Figure 14's device is already the device as simulated.
    from_levels_as_simulated(fig14.device.clone(), levels_in_fig14(fig14))
        .unwrap_or_else(|| panic!("Figure 14's ensembles {IN_FIG14:?} are not Figure 15's levels"))
}

/// The levels of Figure 14's run that are Figure 15's ([`IN_FIG14`], in order), for a caller
/// that keeps them to build Figure 15 later ([`from_levels`]).
pub fn levels_in_fig14(fig14: &crate::paper::fig14::Run) -> Vec<Level> {
    IN_FIG14.iter().map(|&j| fig14.levels[j].clone()).collect()
}

/// Figure 15 from ensembles simulated elsewhere (Figure 14's levels at [`IN_FIG14`], possibly
/// read back from a file): `None` unless they are, in order, exactly the ensembles [`run`]
/// would simulate for `prototype2` (the same device as simulated, parameter set, records and
/// settings).
pub fn from_levels(prototype2: &Device, levels: Vec<Level>) -> Option<Run> {
    from_levels_as_simulated(prototype2_setup(prototype2), levels)
}

/// [`from_levels`] for the device as simulated (`prototype2_setup` applied).
fn from_levels_as_simulated(dev: Device, levels: Vec<Level>) -> Option<Run> {
    let same = levels.len() == FIG15_LEVELS.len()
        && levels.iter().enumerate().all(|(index, l)| {
            l.set == "published"
                && l.device == dev
                && l.ens.spec == level_spec(&dev, FIG15_LEVELS[index], FIG15_REALISATIONS)
                && l.ens.records.len() == FIG15_REALISATIONS
        });
    same.then(|| Run {
        levels: levels
            .into_iter()
            .enumerate()
            .map(|(index, l)| Level { index, ..l })
            .collect(),
        linear: linear_widths(&dev, P2_BAND_HZ.0, P2_BAND_HZ.1),
        device: dev,
    })
}

/// Shifts of the half-power band edges of the ensemble-mean PSD from `low` to `high` (Hz):
/// `(up, down)` = (upper edge of `high` minus that of `low`, lower edge of `low` minus that of
/// `high`); `None` if either band is undetermined. The widening is "towards higher
/// frequencies" (claim F15-c) when `up > down` and `up > 0`.
pub fn edge_shifts(low: &Ensemble, high: &Ensemble) -> Option<(f64, f64)> {
    let a = low.mean_widths.half_power?;
    let b = high.mean_widths.half_power?;
    Some((b.f_hi_hz - a.f_hi_hz, a.f_lo_hz - b.f_lo_hz))
}

/// Whether the response widens towards higher frequencies from `low` to `high` (claim
/// F15-c): the upper half-power edge moves up, and by more than the lower edge moves down
/// ([`edge_shifts`]); `None` if either band is undetermined.
pub fn widens_up(low: &Ensemble, high: &Ensemble) -> Option<bool> {
    edge_shifts(low, high).map(|(up, down)| up > down && up > 0.0)
}

/// What Figure 15 shows.
#[derive(Debug, Clone, PartialEq)]
pub struct Findings {
    /// Peak of the ensemble-mean PSD at 0.34e-3 (Hz).
    pub peak_hz: f64,
    /// Its uncertainty: half a bin with the 95 % CI of the single-record peaks (Hz).
    pub peak_uncertainty_hz: f64,
    /// Peaks of the single records at 0.34e-3 (Hz).
    pub peak_single: MeanCi,
    /// Half-power width of the ensemble-mean PSD at every level (Hz).
    pub widths: Vec<Jackknife>,
    /// Half-power width ratio 0.55e-3 over 0.34e-3, with its propagated 95 % half-width.
    pub ratio: (f64, f64),
    /// The same ratio of the half-amplitude widths.
    pub ratio_half_amplitude: (f64, f64),
    /// Half-power width ratio 1.69e-3 over 0.34e-3, with its propagated 95 % half-width.
    pub ratio_169: (f64, f64),
    /// Shift of the upper half-power edge from 0.34e-3 to 1.69e-3 (Hz, up is positive).
    pub upper_shift_hz: f64,
    /// Shift of the lower half-power edge (Hz, down is positive).
    pub lower_shift_hz: f64,
    /// The widening is towards higher frequencies ([`edge_shifts`]).
    pub widening_up: bool,
    /// Single-record 3 dB ratio 0.55e-3 over 0.34e-3, over every pair of records.
    pub single_ratio: Spread,
    /// The same, 1.69e-3 over 0.34e-3.
    pub single_ratio_169: Spread,
    /// The same, half-amplitude widths, 0.55e-3 over 0.34e-3.
    pub single_ratio_half_amplitude: Spread,
    /// The same with MATLAB's default segmenting, 0.55e-3 over 0.34e-3.
    pub single_ratio_matlab: Spread,
    /// Fraction of single-record pairs whose 3 dB ratio reaches the paper's (F15-b).
    pub pairs_at_least_paper: f64,
    /// Fraction of pairs within the claims file's tolerance of the paper's ratio.
    pub pairs_within_tolerance: f64,
    /// Fraction of pairs reaching the paper's ratio with MATLAB's default segmenting.
    pub pairs_at_least_paper_matlab: f64,
}

/// Figure 15's findings; the paper's ratio and its tolerance are read from `claims`
/// ([`RATIO_CLAIM`]); without that claim the pair fractions are NaN.
pub fn findings(run: &Run, claims: &Claims) -> Findings {
    let e = |i: usize| &run.levels[i].ens;
    let (e34, e55, e169) = (e(L034), e(L055), e(L169));
    let hp = WidthReading::HalfPower;
    let ha = WidthReading::HalfAmplitude;
    let peak_single = MeanCi::of(&e34.single_peak_hz());
    let half_bin = 0.5 * e34.mean_spectrum.total.df();
    let widths: Vec<Jackknife> = run.levels.iter().map(|l| hp.mean_width(&l.ens)).collect();
    let (up, down) = edge_shifts(e34, e169).unwrap_or((f64::NAN, f64::NAN));
    let (paper, tol_rel) = claims
        .get(RATIO_CLAIM.0, RATIO_CLAIM.1)
        .map_or((f64::NAN, f64::NAN), |c| (c.paper, c.tol_rel));
    let (w55, w34) = (e55.single_bw3db_hz(), e34.single_bw3db_hz());
    let (m55, m34) = (e55.single_alt_bw3db_hz(), e34.single_alt_bw3db_hz());
    Findings {
        peak_hz: e34.mean_spectrum.total.peak().0,
        peak_uncertainty_hz: half_bin.hypot(peak_single.ci95),
        peak_single,
        ratio: widths[L055].ratio(&widths[L034]),
        ratio_169: widths[L169].ratio(&widths[L034]),
        ratio_half_amplitude: ha.mean_width(e55).ratio(&ha.mean_width(e34)),
        widths,
        upper_shift_hz: up,
        lower_shift_hz: down,
        widening_up: widens_up(e34, e169).unwrap_or(false),
        single_ratio: ratio_spread(&w55, &w34),
        single_ratio_169: ratio_spread(&e169.single_bw3db_hz(), &w34),
        single_ratio_half_amplitude: ratio_spread(&ha.single(e55), &ha.single(e34)),
        single_ratio_matlab: ratio_spread(&m55, &m34),
        pairs_at_least_paper: pair_fraction(&w55, &w34, |r| r >= paper),
        pairs_within_tolerance: pair_fraction(&w55, &w34, |r| (r / paper - 1.0).abs() <= tol_rel),
        pairs_at_least_paper_matlab: pair_fraction(&m55, &m34, |r| r >= paper),
    }
}

/// Claims F15-a (peak and 3 dB width at 0.34e-3), F15-b (width ratio 0.55e-3 over 0.34e-3)
/// and F15-c (widening towards higher frequencies at 1.69e-3), published set.
pub fn claims(run: &Run, claims: &Claims) -> Vec<Value> {
    let f = findings(run, claims);
    let w34 = &f.widths[L034];
    vec![
        Value::new(
            "F15-a",
            "peak_0p34e-3_hz",
            "published",
            f.peak_hz,
            Some(f.peak_uncertainty_hz),
            "peak bin of the ensemble-mean PSD; uncertainty: half a bin with the CI of the \
             single-record peaks",
        ),
        Value::new(
            "F15-a",
            "bw_0p34e-3_hz",
            "published",
            w34.estimate,
            Some(w34.ci95),
            "half-power width of the ensemble-mean PSD; CI: delete-one jackknife",
        ),
        Value::new(
            "F15-b",
            "bw_ratio_0p55e-3_over_0p34e-3",
            "published",
            f.ratio.0,
            Some(f.ratio.1),
            "ratio of the half-power widths; CI: the two jackknife intervals propagated",
        ),
        Value::yes_no(
            "F15-c",
            "widening_up_1p69e-3",
            "published",
            f.widening_up,
            format!(
                "upper half-power edge up by {:.1} Hz, lower edge down by {:.1} Hz",
                f.upper_shift_hz, f.lower_shift_hz
            ),
        ),
    ]
}
