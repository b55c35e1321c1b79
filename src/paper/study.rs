//! The claim quantities of a [`Variant`] (a device with every uncertain factor set, and the
//! drive's scale) by the fast paths, for the global sensitivity study and the multi-claim
//! calibration ("Why the paper deviates").
//!
//! The fast path of a narrowband claim is the pseudo-arclength continuation of the periodic
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

use rayon::prelude::*;
use thiserror::Error;

use crate::device::{Device, StiffnessModel};
use crate::num::minimax::{minimise_worst, Fit, MinimaxError, MinimaxSettings};
use crate::num::sensitivity::{Bootstrap, Indices, Saltelli, SensitivityError};
use crate::paper::claims::{Claim, Claims, Kind};
use crate::paper::fig08;
use crate::paper::sensitivity::{Factor, Ranges, RangesError, Variant};
use crate::paper::setups::{FIG13_BIAS_V, P1_BIAS_V, P2_BIAS_V};
use crate::physics::two_port::{TwoPort, TABLE3_QM};
use crate::study::continuation::{self, Branch, EventKind};
use crate::study::orbit::OrbitError;

/// Upper end of prototype 1's frequency continuations (Hz): Figure 8's range extended to
/// 2000 Hz, as the response study's fold claims (without end-stop damping the impacting
/// branch reaches 1600 Hz).
pub const P1_STOP_HZ: f64 = 2000.0;

/// Figure 13's range (Hz) and largest continuation step (Hz): the figure's sweep grid.
pub const P2_RANGE_HZ: (f64, f64) = (600.0, 850.0);

/// Largest continuation step of prototype 2 (Hz): the sweep's 2 Hz grid.
pub const P2_STEP_HZ: f64 = 2.0;

/// Figure 13's drive levels (g rms): below and above the impact onset.
pub const P2_LEVELS_G: (f64, f64) = (0.12, 0.31);

/// Figure 13's alternative Hertz fit of b_im (N s/m), a claim-defined setting.
pub const P2_HERTZ_BIM: f64 = 0.34;

/// The prototypes of the study.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Prototype {
    /// Prototype 1 (Figures 8-12, Table 3's first column).
    P1,
    /// Prototype 2 (Figures 13-15, Table 3's second column).
    P2,
}

impl Prototype {
    /// Both, in order.
    pub const BOTH: [Prototype; 2] = [Prototype::P1, Prototype::P2];

    /// Key in files (`p1`, `p2`).
    pub fn key(self) -> &'static str {
        match self {
            Prototype::P1 => "p1",
            Prototype::P2 => "p2",
        }
    }

    /// The quantities the fast paths evaluate, in output order.
    pub fn quantities(self) -> &'static [Quantity] {
        match self {
            Prototype::P1 => &P1_QUANTITIES,
            Prototype::P2 => &P2_QUANTITIES,
        }
    }
}

/// One claim quantity of the study: its key in the claims file and what stands in for it when
/// it does not exist at a point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Quantity {
    /// Claim id.
    pub claim: &'static str,
    /// Quantity key.
    pub quantity: &'static str,
    /// The value used where the quantity does not exist or its continuation failed: for a
    /// frequency, the end of the continuation's range (a censored value: the event lies beyond
    /// it); for a yes/no claim, 0 (not shown); `None` for an analytic quantity, which always
    /// exists.
    pub substitute: Option<f64>,
}

const fn q(claim: &'static str, quantity: &'static str, substitute: Option<f64>) -> Quantity {
    Quantity {
        claim,
        quantity,
        substitute,
    }
}

/// Prototype 1's quantities: Figure 8's kink and jumps, their order, Table 3's first column.
pub const P1_QUANTITIES: [Quantity; 9] = [
    q("F8-b", "impact_onset_5p5g_hz", Some(P1_STOP_HZ)),
    q("F8-c", "jump_hertz_bim1p5_hz", Some(P1_STOP_HZ)),
    q("F8-d", "jump_hertz_bim0_hz", Some(P1_STOP_HZ)),
    q("F8-e", "jump_hertz_bim10_hz", Some(P1_STOP_HZ)),
    q("F8-e", "jump_order_by_bim", Some(0.0)),
    q("F8-f", "jump_linear_bim2_hz", Some(P1_STOP_HZ)),
    q("T3-a", "k2_pct_p1", None),
    q("T3-a", "qm_p1", None),
    q("T3-a", "k2qm_p1", None),
];

/// Prototype 2's quantities: Figure 13's yes/no claims, Table 3's second column.
pub const P2_QUANTITIES: [Quantity; 6] = [
    q("F13", "no_impact_0p12g", Some(0.0)),
    q("F13", "jump_0p31g", Some(0.0)),
    q("F13", "hertz_linear_agree", Some(0.0)),
    q("T3-b", "k2_pct_p2", None),
    q("T3-b", "qm_p2", None),
    q("T3-b", "k2qm_p2", None),
];

/// The value of a quantity at a point, or why it has none.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Outcome {
    /// The quantity exists.
    Value(f64),
    /// The branch has no upper fold inside the range: no jump down.
    NoFold,
    /// The branch never grazes inside the range: no impacts.
    NoGrazing,
    /// The continuation failed at this point (Newton or the integrator; counted and reported).
    Failed,
}

impl Outcome {
    /// The value, if the quantity exists.
    pub fn value(self) -> Option<f64> {
        match self {
            Outcome::Value(v) => Some(v),
            _ => None,
        }
    }

    /// Label for tables.
    pub fn label(self) -> &'static str {
        match self {
            Outcome::Value(_) => "value",
            Outcome::NoFold => "no fold",
            Outcome::NoGrazing => "no grazing",
            Outcome::Failed => "continuation failed",
        }
    }
}

/// One quantity evaluated at a point, normalised by its claim.
#[derive(Debug, Clone, PartialEq)]
pub struct Evaluation {
    /// The quantity.
    pub quantity: Quantity,
    /// Its value or absence.
    pub outcome: Outcome,
    /// The value, or the substitute where it does not exist.
    pub value: f64,
    /// (value - paper) / the claim's tolerance for a quantitative claim; for a yes/no claim
    /// ours - paper (0 when met, +-1 otherwise).
    pub deviation: f64,
    /// The claim's verdict on the value is `reproduced` (an absent quantity never is).
    pub meets: bool,
    /// Quantitative (normalised by a tolerance) or yes/no.
    pub kind: Kind,
}

/// Failures of an evaluation.
#[derive(Debug, Error)]
pub enum StudyError {
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
    /// A quantity that always exists came out absent.
    #[error("({0}, {1}) has no value and no substitute")]
    NoSubstitute(&'static str, &'static str),
}

/// The frequency branch of `device` at `accel_rms_g` from `start` to `stop` (Hz), steps of at
/// most `step` (Hz) ([`continuation::frequency_branch`]), its failure named by `what`.
pub fn frequency_branch(
    device: &Device,
    accel_rms_g: f64,
    (start, stop): (f64, f64),
    step: f64,
    what: &'static str,
) -> Result<Branch, StudyError> {
    continuation::frequency_branch(device, accel_rms_g, start, stop, step, |_| {})
        .map_err(|source| StudyError::Orbit { what, source })
}

/// The upper branch's fold: the highest fold (away from grazing) at which the branch loses
/// stability (the rule of [`crate::paper::response::CaseRun::fold_hz`]).
pub fn upper_fold(branch: &Result<Branch, StudyError>) -> Outcome {
    let Ok(branch) = branch else {
        return Outcome::Failed;
    };
    branch
        .events_of(EventKind::Fold)
        .filter(|e| !e.at_grazing && e.stable_before && !e.stable_after)
        .map(|e| e.param)
        .fold(None, |m: Option<f64>, p| Some(m.map_or(p, |m| m.max(p))))
        .map_or(Outcome::NoFold, Outcome::Value)
}

/// The first grazing point along the branch (a corner at grazing counts): where the
/// up-sweep's mass first reaches a stop, the branch starting in free flight below it.
pub fn first_grazing(branch: &Result<Branch, StudyError>) -> Outcome {
    let Ok(branch) = branch else {
        return Outcome::Failed;
    };
    branch
        .events
        .iter()
        .find(|e| e.kind == EventKind::Grazing || e.at_grazing)
        .map_or(Outcome::NoGrazing, |e| Outcome::Value(e.param))
}

/// Whether any orbit of the branch reaches the stops (`None`: the continuation failed).
pub fn branch_impacts(branch: &Result<Branch, StudyError>) -> Option<bool> {
    let branch = branch.as_ref().ok()?;
    Some(
        branch.events.iter().any(|e| e.kind == EventKind::Grazing)
            || branch.points.iter().any(|p| p.orbit.is_impacting()),
    )
}

/// The raw quantities of prototype 1 at a variant (`variant.device` is prototype 1 with the
/// factors applied), in [`P1_QUANTITIES`] order: the variant's own b_im and tension-free
/// setting enter the fitted case (F8-b, F8-c); the other jump claims set b_im and the law as
/// the claims state them.
pub fn evaluate_p1(variant: &Variant) -> Result<Vec<Outcome>, StudyError> {
    let base = variant.device.with_bias(P1_BIAS_V);
    let fitted = base.endstop.damping_n_s_per_m;
    let accel = fig08::P1_HIGH_ACCEL_RMS_G * variant.accel_scale;
    let cases: [(StiffnessModel, f64, &'static str); 4] = [
        (
            StiffnessModel::Hertz,
            fitted,
            "F8-c Hertz, the variant's b_im",
        ),
        (StiffnessModel::Hertz, 0.0, "F8-d Hertz, b_im 0"),
        (StiffnessModel::Hertz, 10.0, "F8-e Hertz, b_im 10"),
        (StiffnessModel::Linear, 2.0, "F8-f linear, b_im 2"),
    ];
    let branches = cases
        .par_iter()
        .map(|&(law, bim, what)| {
            frequency_branch(
                &base.with_endstop(law, bim),
                accel,
                (fig08::P1_SWEEP_START_HZ, P1_STOP_HZ),
                fig08::P1_SWEEP_STEP_HZ,
                what,
            )
        })
        .collect::<Vec<_>>();
    let folds: Vec<Outcome> = branches.iter().map(upper_fold).collect();
    let order = match (folds[1], folds[0], folds[2]) {
        (Outcome::Value(b0), Outcome::Value(b15), Outcome::Value(b10)) => {
            Outcome::Value(if b0 > b15 && b15 > b10 { 1.0 } else { 0.0 })
        }
        (Outcome::Failed, _, _) | (_, Outcome::Failed, _) | (_, _, Outcome::Failed) => {
            Outcome::Failed
        }
        _ => Outcome::Value(0.0),
    };
    let tp = TwoPort::of(&base);
    let qm = tp.qm(TABLE3_QM);
    // The grazing orbit is a free-flight orbit, the same for every contact law and b_im: the
    // first branch that reaches it gives the onset when the fitted case's continuation failed.
    let onset = branches
        .iter()
        .map(first_grazing)
        .find(|o| *o != Outcome::Failed)
        .unwrap_or(Outcome::Failed);
    Ok(vec![
        onset,
        folds[0],
        folds[1],
        folds[2],
        order,
        folds[3],
        Outcome::Value(tp.k2 * 100.0),
        Outcome::Value(qm),
        Outcome::Value(tp.k2 * qm),
    ])
}

/// The raw quantities of prototype 2 at a variant, in [`P2_QUANTITIES`] order: Figure 13 at
/// 10 V with the linear law and the variant's b_im (the paper's fit), the Hertz alternative with
/// its claim-defined b_im; Table 3 at 15 V.
pub fn evaluate_p2(variant: &Variant, claims: &Claims) -> Result<Vec<Outcome>, StudyError> {
    let base = variant.device.with_bias(FIG13_BIAS_V);
    let fitted = base.endstop.damping_n_s_per_m;
    let cases: [(StiffnessModel, f64, f64, &'static str); 3] = [
        (StiffnessModel::Linear, fitted, P2_LEVELS_G.0, "F13 0.12 g"),
        (
            StiffnessModel::Linear,
            fitted,
            P2_LEVELS_G.1,
            "F13 0.31 g, linear",
        ),
        (
            StiffnessModel::Hertz,
            P2_HERTZ_BIM,
            P2_LEVELS_G.1,
            "F13 0.31 g, Hertz",
        ),
    ];
    let branches = cases
        .par_iter()
        .map(|&(law, bim, g, what)| {
            frequency_branch(
                &base.with_endstop(law, bim),
                g * variant.accel_scale,
                P2_RANGE_HZ,
                P2_STEP_HZ,
                what,
            )
        })
        .collect::<Vec<_>>();
    let yes = |b: Option<bool>| {
        b.map_or(Outcome::Failed, |b| {
            Outcome::Value(if b { 1.0 } else { 0.0 })
        })
    };
    let failed = branches.iter().any(|b| b.is_err());
    let fold_linear = upper_fold(&branches[1]);
    let fold_hertz = upper_fold(&branches[2]);
    // Figure 13's rule: the two jumps agree within the frequency class.
    let agree = match (
        fold_linear.value(),
        fold_hertz.value(),
        claims.class("frequency"),
    ) {
        (Some(a), Some(b), Some(class)) => (a - b).abs() <= class.tolerance(a),
        _ => false,
    };
    let mut out = vec![
        yes(branch_impacts(&branches[0]).map(|b| !b)),
        yes(branch_impacts(&branches[1]).map(|b| b && fold_linear.value().is_some())),
        yes((!failed).then_some(agree)),
    ];
    out.extend(p2_table3(variant));
    Ok(out)
}

/// Table 3's second column at a variant (eqs 15-18 at 15 V), in [`P2_QUANTITIES`] order.
fn p2_table3(variant: &Variant) -> [Outcome; 3] {
    let tp = TwoPort::of(&variant.device.with_bias(P2_BIAS_V));
    let qm = tp.qm(TABLE3_QM);
    [
        Outcome::Value(tp.k2 * 100.0),
        Outcome::Value(qm),
        Outcome::Value(tp.k2 * qm),
    ]
}

/// The quantitative claims of a prototype at a variant (the calibration's objective): every
/// quantitative claim of [`evaluate`], computed without the continuations none of them needs
/// (prototype 2's are all analytic).
pub fn evaluate_quantitative(
    prototype: Prototype,
    variant: &Variant,
    claims: &Claims,
) -> Result<Vec<Evaluation>, StudyError> {
    match prototype {
        Prototype::P1 => Ok(evaluate(prototype, variant, claims)?
            .into_iter()
            .filter(|e| e.kind == Kind::Quantitative)
            .collect()),
        // The analytic quantities (no substitute: they always exist), in their order.
        Prototype::P2 => P2_QUANTITIES
            .iter()
            .filter(|q| q.substitute.is_none())
            .zip(p2_table3(variant))
            .map(|(qty, outcome)| normalise(qty, outcome, claims))
            .collect(),
    }
}

/// Every quantity of a prototype at a variant, normalised by the claims file.
pub fn evaluate(
    prototype: Prototype,
    variant: &Variant,
    claims: &Claims,
) -> Result<Vec<Evaluation>, StudyError> {
    let raw = match prototype {
        Prototype::P1 => evaluate_p1(variant)?,
        Prototype::P2 => evaluate_p2(variant, claims)?,
    };
    prototype
        .quantities()
        .iter()
        .zip(raw)
        .map(|(qty, outcome)| normalise(qty, outcome, claims))
        .collect()
}

/// A quantity's outcome normalised by its claim.
pub fn normalise(
    qty: &Quantity,
    outcome: Outcome,
    claims: &Claims,
) -> Result<Evaluation, StudyError> {
    let claim: &Claim = claims
        .get(qty.claim, qty.quantity)
        .ok_or(StudyError::UnknownClaim(qty.claim, qty.quantity))?;
    let value = match (outcome.value(), qty.substitute) {
        (Some(v), _) => v,
        (None, Some(s)) => s,
        (None, None) => return Err(StudyError::NoSubstitute(qty.claim, qty.quantity)),
    };
    let deviation = match claim.kind {
        Kind::Quantitative => (value - claim.paper) / claim.tolerance(),
        Kind::Qualitative => value - claim.paper,
    };
    let meets = outcome.value().is_some()
        && claim.verdict(Some(value)) == crate::paper::claims::Verdict::Reproduced;
    Ok(Evaluation {
        quantity: *qty,
        outcome,
        value,
        deviation,
        meets,
        kind: claim.kind,
    })
}

/// The unit-cube model of a prototype: the variant of `base` at a point, evaluated.
pub fn evaluate_at(
    prototype: Prototype,
    ranges: &Ranges,
    base: &Device,
    point: &[f64],
    claims: &Claims,
) -> Result<Vec<Evaluation>, StudyError> {
    let variant = ranges.variant(base, point)?;
    evaluate(prototype, &variant, claims)
}

/// The Sobol indices of one quantity.
#[derive(Debug, Clone, PartialEq)]
pub struct QuantityIndices {
    /// The quantity.
    pub quantity: Quantity,
    /// First-order and total indices with their bootstrap intervals, in [`Factor::ALL`] order;
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
    /// Base rows of the Saltelli design (a power of two).
    pub base_rows: usize,
    /// Scramble of the design.
    pub seed: u32,
    /// The bootstrap of the intervals.
    pub bootstrap: Bootstrap,
}

/// Sobol first-order and total indices of every quantity of `prototype` over `ranges`, from
/// the Saltelli design of `d`; `on_point()` after every design point (points run in
/// parallel, results in design order).
pub fn sobol(
    prototype: Prototype,
    ranges: &Ranges,
    base: &Device,
    d: SobolDesign,
    claims: &Claims,
    on_point: &(dyn Fn() + Sync),
) -> Result<SobolRun, StudyError> {
    let design = Saltelli::new(d.base_rows, Factor::ALL.len(), d.seed)?;
    let boot = d.bootstrap;
    let evaluations = design
        .points()
        .par_iter()
        .map(|p| {
            let e = evaluate_at(prototype, ranges, base, p, claims);
            on_point();
            e
        })
        .collect::<Result<Vec<_>, _>>()?;
    let quantities = prototype
        .quantities()
        .iter()
        .enumerate()
        .map(|(j, qty)| {
            let outputs: Vec<f64> = evaluations.iter().map(|e| e[j].deviation).collect();
            let share = |keep: &dyn Fn(Outcome) -> bool| {
                let n = evaluations.iter().filter(|e| keep(e[j].outcome)).count();
                n as f64 / evaluations.len() as f64
            };
            let indices = match design.indices(&outputs, boot) {
                Ok(i) => Some(i),
                Err(SensitivityError::NoVariance) => None,
                Err(e) => return Err(StudyError::Sensitivity(e)),
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

/// The multi-claim calibration of a prototype: the point of the ranges that minimises the
/// worst normalised deviation over its quantitative claims (the yes/no claims are reported,
/// not fitted: a step function gives the simplex no slope), by [`minimise_worst`].
#[derive(Debug, Clone, PartialEq)]
pub struct Calibration {
    /// The prototype.
    pub prototype: Prototype,
    /// Every start's fit, best first.
    pub fits: Vec<Fit>,
    /// The evaluations at the best point.
    pub best: Vec<Evaluation>,
    /// The best variant.
    pub variant: Variant,
}

impl Calibration {
    /// The best fit's worst |normalised deviation| over the quantitative claims.
    pub fn worst(&self) -> f64 {
        self.fits[0].worst
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

/// Runs the multi-claim calibration of `prototype` over `ranges` with `settings`.
pub fn calibrate(
    prototype: Prototype,
    ranges: &Ranges,
    base: &Device,
    settings: MinimaxSettings,
    claims: &Claims,
    on_eval: &(dyn Fn() + Sync),
) -> Result<Calibration, StudyError> {
    let model = |u: &[f64]| -> Result<Vec<f64>, StudyError> {
        let e = ranges
            .variant(base, u)
            .map_err(StudyError::from)
            .and_then(|v| evaluate_quantitative(prototype, &v, claims));
        on_eval();
        Ok(quantitative_deviations(&e?))
    };
    // The published set is the first start: the search can only improve on it.
    let published = ranges.published_point(base)?;
    let fits = minimise_worst(Factor::ALL.len(), model, settings, &[published])?;
    let variant = ranges.variant(base, &fits[0].point)?;
    let best = evaluate(prototype, &variant, claims)?;
    Ok(Calibration {
        prototype,
        fits,
        best,
        variant,
    })
}

/// Summary key of a quantity's value at the best set of the calibration of its prototype
/// (`None`: the study does not evaluate the claim).
pub fn best_value_key(claim: &str, quantity: &str) -> Option<String> {
    Prototype::BOTH.iter().find_map(|p| {
        p.quantities()
            .iter()
            .any(|q| q.claim == claim && q.quantity == quantity)
            .then(|| format!("calibration_{}_{claim}_{quantity}_value", p.key()))
    })
}
