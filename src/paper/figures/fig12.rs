//! Figure 12: prototype 1 at 30 V (Hertz contact, b_im = 1.5 N s/m) under high-level random
//! vibration, where the mass hits the stops, published and calibrated parameter sets: the
//! 3 dB bandwidth grows with the level (claim F12).

use crate::num::stats::{ratio_spread, Jackknife, Spread};
use crate::paper::claims::{keys, Claims, ClaimsError, Value};
use crate::paper::ensembles::{run_prototype1, Prototype1Run, WidthReading};
use crate::paper::setups::{ParamSet, Prototype1Sets};
use crate::paper::Figure;
use crate::progress::Progress;
use crate::study::record::RecordError;

/// Figure 12's levels (g²/Hz).
pub const FIG12_LEVELS: [f64; 3] = [7.4e-3, 1.31e-2, 2.85e-2];

/// Records per level in Figure 12 (as Figure 11, whose 32 records it shares the reasons for;
/// the contact statistics of the lowest level, a few impacts per second, need them too).
pub const FIG12_REALISATIONS: usize = 32;

/// Index in [`FIG12_LEVELS`] of the claim's lower level (7.4e-3).
pub const LOW: usize = 0;

/// Index in [`FIG12_LEVELS`] of the claim's upper level (2.85e-2).
pub const HIGH: usize = 2;

/// The ensembles of Figure 12: both parameter sets at every level.
pub type Run = Prototype1Run;

/// The widths of one reading of "3 dB" at the claim's two levels, for one parameter set.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Findings {
    /// The reading.
    pub reading: WidthReading,
    /// Width of the ensemble-mean PSD at [`LOW`] with its jackknife interval (Hz).
    pub low: Jackknife,
    /// Width of the ensemble-mean PSD at [`HIGH`] (Hz).
    pub high: Jackknife,
    /// `high / low` with the 95 % half-width propagated from the two intervals.
    pub ratio: (f64, f64),
    /// Ratio of single-record widths over every pair of records (one at each level).
    pub single_ratio: Spread,
}

/// Figure 12's findings for a parameter set under `reading`.
pub fn findings(run: &Run, set: ParamSet, reading: WidthReading) -> Findings {
    let (lo, hi) = (&run.level(set, LOW).ens, &run.level(set, HIGH).ens);
    let (low, high) = (reading.mean_width(lo), reading.mean_width(hi));
    Findings {
        reading,
        low,
        high,
        ratio: high.ratio(&low),
        single_ratio: ratio_spread(&reading.single(hi), &reading.single(lo)),
    }
}

/// Figure 12: prototype 1 under high-level random vibration, both parameter sets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Fig12;

impl Figure for Fig12 {
    const NAME: &'static str = "fig12";
    type Setup = Prototype1Sets;
    type Run = Run;
    type Error = RecordError;

    fn work(_: &Prototype1Sets) -> usize {
        ParamSet::BOTH.len() * FIG12_LEVELS.len() * FIG12_REALISATIONS
    }

    /// Runs Figure 12 for the published and the calibrated prototype 1 (the parameter files'
    /// devices; [`crate::paper::setups::prototype1_setup`] is applied here), calling
    /// `progress` after each record.
    fn run(setup: &Prototype1Sets, progress: &dyn Progress) -> Result<Run, RecordError> {
        run_prototype1(setup, &FIG12_LEVELS, FIG12_REALISATIONS, progress)
    }

    /// Claim F12 for both parameter sets: the half-power widths of the ensemble-mean PSDs at
    /// 7.4e-3 and 2.85e-2 g²/Hz and their ratio (the half-amplitude reading is reported
    /// beside, not scored).
    fn claims(run: &Run, claims: &Claims) -> Result<Vec<Value>, ClaimsError> {
        let mut out = Vec::new();
        for set in ParamSet::BOTH {
            let f = findings(run, set, WidthReading::HalfPower);
            let note = "half-power width of the ensemble-mean PSD; CI: delete-one jackknife";
            for (key, width) in [(keys::F12_BW_LOW, f.low), (keys::F12_BW_HIGH, f.high)] {
                out.push(Value::new(key, set, width.estimate, Some(width.ci95), note));
            }
            out.push(Value::new(
                keys::F12_BW_RATIO,
                set,
                f.ratio.0,
                Some(f.ratio.1),
                "ratio of the half-power widths; CI: the two jackknife intervals propagated",
            ));
        }
        claims.known(out)
    }
}
