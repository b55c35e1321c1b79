//! Figure 15: prototype 2 at 15 V (linear k_im of eq 19, b_im = 0.4 N s/m), output power
//! spectra at three levels (claims F15-a to F15-c), and the sampling distribution of the
//! bandwidths and of their ratio when each is read from one 10 s record, as the paper did.

use crate::device::Device;
use crate::num::stats::{pair_fraction, ratio_spread, Jackknife, MeanCi, Spread};
use crate::paper::claims::{keys, ClaimKey, Claims, ClaimsError, Value};
use crate::paper::ensembles::{Level, WidthReading, P2_BAND_HZ};
use crate::paper::prototype2_records::{self, Extras, Fig15Level, Levels, Scope};
use crate::paper::setups::ParamSet;
use crate::paper::Figure;
use crate::physics::linear::linear_widths;
use crate::progress::Progress;
use crate::signal::Widths;
use crate::study::ensemble::Ensemble;
use crate::study::record::RecordError;

/// Figure 15's levels (g²/Hz), in the order of [`Fig15Level::ALL`].
pub const FIG15_LEVELS: [f64; 3] = [
    Fig15Level::L034.psd_g2_per_hz(),
    Fig15Level::L055.psd_g2_per_hz(),
    Fig15Level::L169.psd_g2_per_hz(),
];

/// Records per level in Figure 15 ([`prototype2_records::REALISATIONS`]): Figure 14's records
/// at the same levels.
pub const FIG15_REALISATIONS: usize = prototype2_records::REALISATIONS;

/// Index in [`FIG15_LEVELS`] of 0.34e-3 g²/Hz (claim F15-a, and the base of every ratio).
pub const L034: usize = Fig15Level::L034.index();

/// Index in [`FIG15_LEVELS`] of 0.55e-3 g²/Hz (claim F15-b).
pub const L055: usize = Fig15Level::L055.index();

/// Index in [`FIG15_LEVELS`] of 1.69e-3 g²/Hz (claim F15-c).
pub const L169: usize = Fig15Level::L169.index();

/// The claim number whose paper value and tolerance the single-record pairs are counted
/// against.
pub const RATIO_CLAIM: ClaimKey = keys::F15B_BW_RATIO;

/// The simulations of Figure 15.
#[derive(Debug, Clone, PartialEq)]
pub struct Run {
    /// Prototype 2 as simulated ([`crate::paper::setups::prototype2_setup`]).
    pub device: Device,
    /// One ensemble per level of [`FIG15_LEVELS`], in order (each level's `index` is its
    /// index there), with MATLAB's default segmenting beside.
    pub levels: Vec<Level>,
    /// Widths of the linearised output PSD (no end-stops; the same at every level).
    pub linear: Widths,
}

impl Run {
    /// Figure 15 read from a run of the shared protocol ([`prototype2_records::run`]), whose
    /// ensembles at Figure 15's levels are the figure's records: Figure 14's run gives it
    /// without another simulation. `None` if the run lacks one of the levels.
    pub fn of(protocol: &prototype2_records::Run) -> Option<Run> {
        let levels = Fig15Level::ALL
            .iter()
            .map(|&l| {
                protocol.fig15_level(l).map(|level| Level {
                    index: l.index(),
                    ..level.clone()
                })
            })
            .collect::<Option<Vec<_>>>()?;
        let device = protocol.device.clone();
        Some(Run {
            linear: linear_widths(&device, P2_BAND_HZ.0, P2_BAND_HZ.1),
            device,
            levels,
        })
    }
}

/// What Figure 15 runs on.
#[derive(Debug, Clone, PartialEq)]
pub struct Setup {
    /// Prototype 2 as published ([`crate::paper::setups::prototype2_setup`] is applied in the
    /// run).
    pub prototype2: Device,
    /// Records per level: [`FIG15_REALISATIONS`], or fewer (the first of every level's
    /// streams) for a quicker look.
    pub records: usize,
}

impl Setup {
    /// The figure's setup: prototype 2 with [`FIG15_REALISATIONS`] records per level.
    pub fn new(prototype2: Device) -> Self {
        Self {
            prototype2,
            records: FIG15_REALISATIONS,
        }
    }

    /// The protocol's scope of this setup.
    pub fn scope(&self) -> Scope {
        Scope {
            levels: Levels::Fig15,
            records: self.records,
            extras: Extras::NONE,
        }
    }
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
        .claim(RATIO_CLAIM)
        .map_or((f64::NAN, f64::NAN), |c| (c.paper.to_f64(), c.tol_rel));
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

/// Figure 15: prototype 2's output spectra at three levels and their widths.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Fig15;

impl Figure for Fig15 {
    const NAME: &'static str = "fig15";
    type Setup = Setup;
    type Run = Run;
    type Error = RecordError;

    fn work(setup: &Setup) -> usize {
        setup.scope().records_simulated()
    }

    /// Runs the protocol at Figure 15's levels for prototype 2, calling `progress` after each
    /// record.
    fn run(setup: &Setup, progress: &dyn Progress) -> Result<Run, RecordError> {
        let protocol = prototype2_records::run(&setup.prototype2, setup.scope(), progress)?;
        Ok(Run::of(&protocol).expect("a run of Figure 15's levels has them all"))
    }

    /// Claims F15-a (peak and 3 dB width at 0.34e-3), F15-b (width ratio 0.55e-3 over
    /// 0.34e-3) and F15-c (widening towards higher frequencies at 1.69e-3), published set.
    fn claims(run: &Run, claims: &Claims) -> Result<Vec<Value>, ClaimsError> {
        let f = findings(run, claims);
        let w34 = &f.widths[L034];
        let set = ParamSet::Published;
        claims.known(vec![
            Value::new(
                keys::F15A_PEAK,
                set,
                f.peak_hz,
                Some(f.peak_uncertainty_hz),
                "peak bin of the ensemble-mean PSD; uncertainty: half a bin with the CI of the \
                 single-record peaks",
            ),
            Value::new(
                keys::F15A_BW,
                set,
                w34.estimate,
                Some(w34.ci95),
                "half-power width of the ensemble-mean PSD; CI: delete-one jackknife",
            ),
            Value::new(
                RATIO_CLAIM,
                set,
                f.ratio.0,
                Some(f.ratio.1),
                "ratio of the half-power widths; CI: the two jackknife intervals propagated",
            ),
            Value::yes_no(
                keys::F15C_WIDENING_UP,
                set,
                f.widening_up,
                format!(
                    "upper half-power edge up by {:.1} Hz, lower edge down by {:.1} Hz",
                    f.upper_shift_hz, f.lower_shift_hz
                ),
            ),
        ])
    }
}
