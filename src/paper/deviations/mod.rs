//! Why the paper deviates: the claim quantities of a [`Variant`] (a device with every uncertain
//! factor set, and the drive's scale) by their fast paths, the global sensitivity study of
//! those quantities over the ranges of [`ranges`], and the multi-claim calibration.
//!
//! * [`ranges`]: the uncertain inputs, their ranges and the unit-cube point of a variant;
//! * [`quantity`]: what is evaluated (the [`Quantity`] of each claim, its [`Outcome`] and its
//!   normalised [`Evaluation`]);
//! * [`sweeps`] and [`ensembles`]: the fast paths, by continuation of the periodic orbits
//!   and by ensembles of random-vibration records;
//! * [`evaluation`]: every quantity of a prototype at a variant;
//! * [`indices`]: Sobol indices over a Saltelli design and the most conflicting pair of claims;
//! * [`calibration`]: the minimax search for a set that meets every quantitative claim;
//! * [`history`]: the history match of every quantitative claim with Gaussian-process
//!   emulators, in waves: which sets, if any, are consistent with all claims at once.
//!
//! The fast path of a sine-sweep claim is the pseudo-arclength continuation of the periodic
//! orbits ([`crate::study::continuation`]) instead of the stepped sweep: Figure 8's kink (the
//! up-sweep's impact onset) is the branch's first grazing point, a jump down is the upper
//! fold (where the up-sweep leaves the impacting branch when its steady-state blocks are long
//! enough; the response study's table). Table 3's quantities are analytic (eqs 15-18).
//!
//! Every quantity is keyed by the claims file's `(id, quantity)` and normalised by the claim's
//! own tolerance ([`crate::paper::claims::Claim::tolerance`]). A quantity that does not exist at
//! a point is a named [`Outcome`]: no fold (the branch does not jump inside the continuation's
//! range) or no grazing (the mass never reaches the stops there). Where a number is needed
//! (Sobol indices, the minimax objective) the missing one is replaced by the end of the
//! continuation's range, the censored value ([`Quantity::substitute`]), and the share of
//! points where the substitute was used is reported beside every index.

use thiserror::Error;

use crate::num::minimax::MinimaxError;
use crate::num::sensitivity::{Bootstrap, SensitivityError};
use crate::paper::claims::ClaimsError;
use crate::study::orbit::OrbitError;

pub mod calibration;
pub mod ensembles;
pub mod evaluation;
pub mod history;
pub mod indices;
pub mod quantity;
pub mod ranges;
pub mod sweeps;

pub use calibration::{
    calibrate, calibrate_start, calibration_of_fits, calibration_starts, quantitative_deviations,
    MultiClaimCalibration,
};
pub use evaluation::{evaluate, evaluate_at, evaluate_p1, evaluate_p2, evaluate_quantitative};
pub use history::{history_match, Answer, ClaimIndices, HistoryRun, TOLERANCE_SIGMAS};
pub use indices::{
    most_conflicting, sobol, sobol_indices, Pareto, QuantityIndices, SobolDesign, SobolRun,
};
pub use quantity::{
    best_value_key, normalise, Estimate, Evaluation, Outcome, Prototype, Quantity, Scope,
    P1_QUANTITIES, P2_QUANTITIES,
};
pub use ranges::{Factor, Ranges, RangesError, RangesFile, Variant};

/// Scramble of the study's Saltelli design and of its calibration's Sobol starts.
pub const STUDY_SEED: u32 = 13;

/// Bootstrap resamples of the indices' 95 % intervals.
pub const STUDY_RESAMPLES: usize = 1000;

/// The study's bootstrap: [`STUDY_RESAMPLES`] resamples, 95 %, seeded by [`STUDY_SEED`].
pub const STUDY_BOOTSTRAP: Bootstrap = Bootstrap {
    resamples: STUDY_RESAMPLES,
    level: 0.95,
    seed: STUDY_SEED as u64,
};

/// Failures of an evaluation, a Sobol study or a calibration.
#[derive(Debug, Error)]
pub enum DeviationsError {
    /// Shooting or continuation failed.
    #[error("{what}: {source}")]
    Orbit {
        /// Which continuation.
        what: &'static str,
        /// The error.
        source: OrbitError,
    },
    /// A quantity matches no claim of the claims file.
    #[error("no claim ({0}, {1}) in the claims file")]
    UnknownClaim(&'static str, &'static str),
    /// A point outside the unit cube or a device that fails validation.
    #[error(transparent)]
    Ranges(#[from] RangesError),
    /// The design or the indices failed.
    #[error(transparent)]
    Sensitivity(#[from] SensitivityError),
    /// The minimax search failed.
    #[error(transparent)]
    Minimax(#[from] MinimaxError),
    /// The claims file lacks a class the study needs.
    #[error(transparent)]
    Claims(#[from] ClaimsError),
    /// A quantity that always exists came out absent.
    #[error("({0}, {1}) has no value and no substitute")]
    NoSubstitute(&'static str, &'static str),
    /// Evaluations or a start that do not belong to the design or the calibration they are
    /// given to.
    #[error("study: {0}")]
    Evaluations(String),
}
