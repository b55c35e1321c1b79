//! The multi-claim calibration: the point of the ranges that minimises the worst normalised
//! deviation over a prototype's quantitative claims, by the multi-start minimax search of
//! [`crate::num::minimax`] from the published set and points of a scrambled Sobol sequence.

use rayon::prelude::*;

use super::evaluation::{evaluate, evaluate_quantitative};
use super::quantity::{Evaluation, Prototype, Scope};
use super::ranges::{Ranges, Variant};
use super::DeviationsError;
use crate::device::Device;
use crate::num::minimax::{Fit, MinimaxSettings};
use crate::paper::claims::{Claims, Kind};
use crate::progress::Progress;

/// The multi-claim calibration of a prototype: the point of the ranges that minimises the
/// worst normalised deviation over its quantitative claims (the yes/no claims are reported,
/// not fitted: a step function gives the simplex no slope), by the minimax search of
/// [`crate::num::minimax`] from each of [`calibration_starts`].
#[derive(Debug, Clone, PartialEq)]
pub struct MultiClaimCalibration {
    /// The prototype.
    pub prototype: Prototype,
    /// Every start's fit, best first.
    pub fits: Vec<Fit>,
    /// The evaluations at the best point.
    pub best: Vec<Evaluation>,
    /// The best variant.
    pub variant: Variant,
    /// The evaluations at the published set (the first start).
    pub published: Vec<Evaluation>,
}

impl MultiClaimCalibration {
    /// The best fit's worst |normalised deviation| over the quantitative claims.
    pub fn worst(&self) -> f64 {
        self.fits[0].worst
    }

    /// The published set's worst |normalised deviation| over the quantitative claims.
    pub fn published_worst(&self) -> f64 {
        quantitative_deviations(&self.published)
            .iter()
            .fold(0.0, |m: f64, d| m.max(d.abs()))
    }

    /// True when the best set meets every claim of the prototype the study evaluates.
    pub fn meets_all(&self) -> bool {
        self.best.iter().all(|e| e.meets)
    }
}

/// The quantitative deviations of an evaluation (the minimax objective's components).
pub fn quantitative_deviations(e: &[Evaluation]) -> Vec<f64> {
    e.iter()
        .filter(|e| e.kind == Kind::Quantitative)
        .map(|e| e.deviation)
        .collect()
}

/// The calibration's objective at a unit-cube point: the quantitative deviations.
fn calibration_objective(
    prototype: Prototype,
    ranges: &Ranges,
    base: &Device,
    claims: &Claims,
    scope: Scope,
    u: &[f64],
) -> Result<Vec<f64>, DeviationsError> {
    let v = ranges.variant(base, u)?;
    Ok(quantitative_deviations(&evaluate_quantitative(
        prototype, &v, claims, scope,
    )?))
}

/// The starts of the calibration, in start order: the published set (start 0: the search can
/// only improve on it), then `settings.starts` points of the scrambled Sobol sequence.
pub fn calibration_starts(
    ranges: &Ranges,
    base: &Device,
    settings: MinimaxSettings,
) -> Result<Vec<Vec<f64>>, DeviationsError> {
    let published = ranges.published_point(base)?;
    Ok(crate::num::minimax::starts(
        ranges.len(),
        settings,
        std::slice::from_ref(&published),
    )?)
}

/// One start of [`calibrate`]: the search from start `start` of [`calibration_starts`]
/// (e.g. as one task of a cluster).
pub fn calibrate_start(
    prototype: Prototype,
    ranges: &Ranges,
    base: &Device,
    settings: MinimaxSettings,
    claims: &Claims,
    scope: Scope,
    start: usize,
) -> Result<Fit, DeviationsError> {
    let x0 = calibration_starts(ranges, base, settings)?
        .into_iter()
        .nth(start)
        .ok_or_else(|| {
            DeviationsError::Evaluations(format!(
                "start {start} is not one of the {} starts",
                settings.starts + 1
            ))
        })?;
    let model = |u: &[f64]| calibration_objective(prototype, ranges, base, claims, scope, u);
    Ok(crate::num::minimax::minimise_from(
        model, settings, start, x0,
    )?)
}

/// Runs the multi-claim calibration of `prototype` over `ranges` with `settings`: every
/// start of [`calibration_starts`] in parallel, then [`calibration_of_fits`].
pub fn calibrate(
    prototype: Prototype,
    ranges: &Ranges,
    base: &Device,
    settings: MinimaxSettings,
    claims: &Claims,
    scope: Scope,
    on_eval: &dyn Progress,
) -> Result<MultiClaimCalibration, DeviationsError> {
    let model = |u: &[f64]| {
        let d = calibration_objective(prototype, ranges, base, claims, scope, u);
        on_eval.tick();
        d
    };
    let fits = calibration_starts(ranges, base, settings)?
        .into_par_iter()
        .enumerate()
        .map(|(start, x0)| crate::num::minimax::minimise_from(model, settings, start, x0))
        .collect::<Result<Vec<_>, _>>()?;
    calibration_of_fits(prototype, ranges, base, claims, scope, fits)
}

/// The calibration from its starts' fits (in any order): the best set, evaluated, beside the
/// published set.
pub fn calibration_of_fits(
    prototype: Prototype,
    ranges: &Ranges,
    base: &Device,
    claims: &Claims,
    scope: Scope,
    fits: Vec<Fit>,
) -> Result<MultiClaimCalibration, DeviationsError> {
    let fits = crate::num::minimax::best_first(fits)?;
    let variant = ranges.variant(base, &fits[0].point)?;
    let best = evaluate(prototype, &variant, claims, scope)?;
    let published = ranges.published_point(base)?;
    let published = evaluate(prototype, &ranges.variant(base, &published)?, claims, scope)?;
    Ok(MultiClaimCalibration {
        prototype,
        fits,
        best,
        variant,
        published,
    })
}
