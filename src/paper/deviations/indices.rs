//! The global sensitivity study: Sobol first-order and total indices of every claim quantity
//! over a Saltelli design of the unit cube of [`super::ranges`], and the pair of claims that
//! pulls hardest against each other over the design's points, with its Pareto front.

use rayon::prelude::*;

use super::evaluation::evaluate_at;
use super::quantity::{Evaluation, Outcome, Prototype, Quantity, Scope};
use super::ranges::Ranges;
use super::DeviationsError;
use crate::device::Device;
use crate::num::pareto::pareto_front;
use crate::num::sensitivity::{Bootstrap, Indices, Saltelli, SensitivityError};
use crate::paper::claims::{Claims, Kind};
use crate::progress::Progress;

/// The Sobol indices of one quantity.
#[derive(Debug, Clone, PartialEq)]
pub struct QuantityIndices {
    /// The quantity.
    pub quantity: Quantity,
    /// First-order and total indices with their bootstrap intervals, in the factors' order;
    /// `None` when the quantity does not vary over the design (every index is 0/0).
    pub indices: Option<Indices>,
    /// Share of the design's points where the quantity does not exist (its substitute is used):
    /// the sum of the three shares below.
    pub absent_share: f64,
    /// Share of points whose branch has no upper fold in the range (no jump down).
    pub no_fold_share: f64,
    /// Share of points whose branch never grazes in the range (no impacts).
    pub no_grazing_share: f64,
    /// Share of points whose continuation failed.
    pub failed_share: f64,
}

/// A Sobol study of one prototype.
#[derive(Debug, Clone, PartialEq)]
pub struct SobolRun {
    /// The prototype.
    pub prototype: Prototype,
    /// The design.
    pub design: Saltelli,
    /// The evaluations at every design point, in design order.
    pub evaluations: Vec<Vec<Evaluation>>,
    /// One entry per quantity of [`Prototype::quantities`].
    pub quantities: Vec<QuantityIndices>,
}

/// The design of a Sobol study.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SobolDesign {
    /// How many factors: the dimension of the unit cube ([`Ranges::len`]).
    pub factors: usize,
    /// Base rows of the Saltelli design (a power of two).
    pub base_rows: usize,
    /// Scramble of the design.
    pub seed: u32,
    /// The bootstrap of the intervals.
    pub bootstrap: Bootstrap,
    /// What each point evaluates.
    pub scope: Scope,
}

/// Sobol first-order and total indices of every quantity of `prototype` over `ranges`, from
/// the Saltelli design of `d`; `on_point.tick()` after every design point (points run in
/// parallel, results in design order). The same as evaluating every point of
/// [`SobolDesign::design`] with [`evaluate_at`] (e.g. as tasks of a cluster) and passing the
/// evaluations to [`sobol_indices`].
pub fn sobol(
    prototype: Prototype,
    ranges: &Ranges,
    base: &Device,
    d: SobolDesign,
    claims: &Claims,
    on_point: &dyn Progress,
) -> Result<SobolRun, DeviationsError> {
    if d.factors != ranges.len() {
        return Err(DeviationsError::Evaluations(format!(
            "a design over {} factors for ranges of {}",
            d.factors,
            ranges.len()
        )));
    }
    let design = d.design()?;
    let evaluations = design
        .points()
        .par_iter()
        .map(|p| {
            let e = evaluate_at(prototype, ranges, base, p, claims, d.scope);
            on_point.tick();
            e
        })
        .collect::<Result<Vec<_>, _>>()?;
    sobol_indices(prototype, d, evaluations)
}

impl SobolDesign {
    /// The Saltelli design over the unit cube of the factors.
    pub fn design(&self) -> Result<Saltelli, DeviationsError> {
        Ok(Saltelli::new(self.base_rows, self.factors, self.seed)?)
    }
}

/// The indices of every quantity of `prototype` from its `evaluations` at the points of the
/// design of `d`, in design order (each one [`evaluate_at`]'s output in `d.scope`).
pub fn sobol_indices(
    prototype: Prototype,
    d: SobolDesign,
    evaluations: Vec<Vec<Evaluation>>,
) -> Result<SobolRun, DeviationsError> {
    let design = d.design()?;
    let wanted = prototype.quantities(d.scope);
    if evaluations.len() != design.len() {
        return Err(DeviationsError::Evaluations(format!(
            "{} evaluations for a design of {} points",
            evaluations.len(),
            design.len()
        )));
    }
    if let Some((k, _)) = evaluations.iter().enumerate().find(|(_, e)| {
        e.len() != wanted.len() || e.iter().zip(&wanted).any(|(e, q)| e.quantity != *q)
    }) {
        return Err(DeviationsError::Evaluations(format!(
            "the evaluation of point {k} does not hold the quantities of {} in this scope, in order",
            prototype.key()
        )));
    }
    let quantities = wanted
        .iter()
        .enumerate()
        .map(|(j, qty)| {
            let outputs: Vec<f64> = evaluations.iter().map(|e| e[j].deviation).collect();
            let share = |keep: &dyn Fn(Outcome) -> bool| {
                let n = evaluations.iter().filter(|e| keep(e[j].outcome)).count();
                n as f64 / evaluations.len() as f64
            };
            let indices = match design.indices(&outputs, d.bootstrap) {
                Ok(i) => Some(i),
                Err(SensitivityError::NoVariance) => None,
                Err(e) => return Err(DeviationsError::Sensitivity(e)),
            };
            Ok(QuantityIndices {
                quantity: *qty,
                indices,
                absent_share: share(&|o| o.value().is_none()),
                no_fold_share: share(&|o| o == Outcome::NoFold),
                no_grazing_share: share(&|o| o == Outcome::NoGrazing),
                failed_share: share(&|o| o == Outcome::Failed),
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(SobolRun {
        prototype,
        design,
        evaluations,
        quantities,
    })
}

/// The Pareto front between two claims of a prototype over the points of a Sobol design:
/// the points no other point beats on both |normalised deviations|.
#[derive(Debug, Clone, PartialEq)]
pub struct Pareto {
    /// The prototype.
    pub prototype: Prototype,
    /// The two quantities (indices into the run's quantities).
    pub pair: (Quantity, Quantity),
    /// How much the pair conflicts: the least worst-of-two |deviation| over the points, less
    /// the larger of the two least single |deviations| (0: one point is best for both).
    pub conflict: f64,
    /// Every point's (|deviation a|, |deviation b|), in design order.
    pub points: Vec<(f64, f64)>,
    /// Indices of the front's points, by increasing |deviation a|.
    pub front: Vec<usize>,
}

/// The most conflicting pair of quantitative claims of a Sobol run ([`Pareto::conflict`],
/// the largest) with its front; `None` with fewer than two quantitative claims.
pub fn most_conflicting(run: &SobolRun) -> Option<Pareto> {
    let quant: Vec<usize> = (0..run.quantities.len())
        .filter(|&j| {
            run.evaluations
                .first()
                .is_some_and(|e| e[j].kind == Kind::Quantitative)
        })
        .collect();
    let abs = |j: usize| -> Vec<f64> {
        run.evaluations
            .iter()
            .map(|e| e[j].deviation.abs())
            .collect()
    };
    let mut best: Option<Pareto> = None;
    for (k, &a) in quant.iter().enumerate() {
        for &b in &quant[k + 1..] {
            let points: Vec<(f64, f64)> = abs(a).into_iter().zip(abs(b)).collect();
            let least =
                |f: &dyn Fn(&(f64, f64)) -> f64| points.iter().map(f).fold(f64::INFINITY, f64::min);
            let conflict = least(&|p| p.0.max(p.1)) - least(&|p| p.0).max(least(&|p| p.1));
            if best.as_ref().is_none_or(|p| conflict > p.conflict) {
                best = Some(Pareto {
                    prototype: run.prototype,
                    pair: (run.quantities[a].quantity, run.quantities[b].quantity),
                    conflict,
                    front: pareto_front(&points),
                    points,
                });
            }
        }
    }
    best
}
