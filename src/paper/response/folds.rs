//! The upper folds beside the scorecard's jump claims of Figure 8 that the response's cases do
//! not cover: prototype 1 at 5.5 g with each claim's end-stop model under both parameter
//! sets, by continuation alone; and the summary key of each fold, which the scorecard reads
//! ([`fold_key`]).

use rayon::prelude::*;

use crate::device::{Device, StiffnessModel};
use crate::paper::claims::{keys, ClaimKey};
use crate::paper::setups::{prototype1_setup, with_endstop, ParamSet, Prototype1Sets};
use crate::paper::sweeps::{self, P1_HIGH_ACCEL_RMS_G, P1_SWEEP_START_HZ, P1_SWEEP_STEP_HZ};
use crate::study::continuation::ContinuationSettings;

use super::{continuation, upper_fold_hz, Case, ResponseError, Setup};

/// The continuation-only cases behind the scorecard's jump claims of Figure 8 that the
/// sweep cases above do not cover: prototype 1 at 5.5 g with another end-stop model, under
/// both parameter sets. Each is `(claim number, stiffness, b_im)`.
pub const FOLD_CLAIMS: [(ClaimKey, StiffnessModel, f64); 4] = [
    (keys::F8C_JUMP_HERTZ_BIM1P5, StiffnessModel::Hertz, 1.5),
    (keys::F8D_JUMP_HERTZ_BIM0, StiffnessModel::Hertz, 0.0),
    (keys::F8E_JUMP_HERTZ_BIM10, StiffnessModel::Hertz, 10.0),
    (keys::F8F_JUMP_LINEAR_BIM2, StiffnessModel::Linear, 2.0),
];

/// The claim of Figure 13's jump (prototype 2, published set), whose fold is
/// [`Case::Fig13P2`]'s.
pub const FIG13_JUMP_CLAIM: ClaimKey = keys::F13_JUMP;

/// Summary key of the fold beside a jump claim (its id and quantity, as a scorecard row holds
/// them) under a parameter set (`None`: the row is not a jump claim).
pub fn fold_key(claim: &str, quantity: &str, set: ParamSet) -> Option<String> {
    let is = |k: ClaimKey| k.id == claim && k.quantity == quantity;
    if is(FIG13_JUMP_CLAIM) && set == ParamSet::Published {
        return Some(format!("{}_fold_hz", Case::Fig13P2.key()));
    }
    FOLD_CLAIMS
        .iter()
        .find(|c| is(c.0))
        .map(|c| fold_summary_key(c.0, set))
}

/// Summary key of the fold of a continuation-only case ([`FOLD_CLAIMS`]).
fn fold_summary_key(key: ClaimKey, set: ParamSet) -> String {
    format!(
        "claim_{}_{set}_fold_hz",
        key.id.to_lowercase().replace('-', "")
    )
}

/// The upper fold of prototype 1 at 5.5 g for every jump claim of [`FOLD_CLAIMS`] under both
/// parameter sets, by continuation alone over Figure 8's range (extended to 2000 Hz: without
/// end-stop damping the branch reaches 1600 Hz). Returns `(summary key, fold)`; a case
/// without a fold gives no entry.
pub fn claim_folds(p1: &Prototype1Sets) -> Result<Vec<(String, f64)>, ResponseError> {
    let jobs: Vec<(String, Device)> = FOLD_CLAIMS
        .iter()
        .flat_map(|&(key, law, bim)| {
            p1.each().into_iter().map(move |(set, d)| {
                (
                    fold_summary_key(key, set),
                    with_endstop(&prototype1_setup(d), law, bim),
                )
            })
        })
        .collect();
    jobs.par_iter()
        .map(|(key, device)| {
            let setup = Setup {
                case: Case::Fig08P1Published,
                device: device.clone(),
                accel_rms_g: P1_HIGH_ACCEL_RMS_G,
                sweep: sweeps::sweep_settings(device),
                continuation: ContinuationSettings::frequency(
                    P1_SWEEP_START_HZ,
                    2000.0,
                    P1_SWEEP_STEP_HZ,
                ),
                transient_periods: 200,
            };
            let branch = continuation(&setup).map_err(|source| ResponseError::Orbit {
                case: "claim folds",
                source,
            })?;
            Ok(upper_fold_hz(&branch).map(|f| (key.clone(), f)))
        })
        .collect::<Result<Vec<_>, _>>()
        .map(|v| v.into_iter().flatten().collect())
}
