//! Every quantity of a prototype at a variant: the fast paths of [`super::sweeps`] and
//! [`super::ensembles`] in the order of [`Prototype::quantities`], normalised by the claims.

use super::ensembles::{p1_fig12, p2_ensembles};
use super::quantity::{normalise, Estimate, Evaluation, Outcome, Prototype, Quantity, Scope};
use super::quantity::{P1_QUANTITIES, P2_QUANTITIES};
use super::ranges::{Ranges, Variant};
use super::sweeps::{p1_fig8, p1_fig9, p1_table3, p2_fig13, p2_table3};
use super::DeviationsError;
use crate::device::Device;
use crate::paper::claims::{Claims, Kind};

/// The raw quantities (with the intervals of the ensemble ones) of prototype 1 at a variant (`variant.device` is prototype 1 with the
/// factors applied), in the order of [`Prototype::quantities`] in `scope`. The variant's own b_im and tension-free
/// setting enter the fitted cases (F8-b, F8-c, Figures 9 and 12); the other jump claims set b_im
/// and the law as the claims state them. Figures 8, 9 and 12 run in parallel.
pub fn evaluate_p1(
    variant: &Variant,
    claims: &Claims,
    scope: Scope,
) -> Result<Vec<Estimate>, DeviationsError> {
    let class = claims.require_class("amplitude_threshold")?;
    let ((fig8, fig9), fig12) = rayon::join(
        || rayon::join(|| p1_fig8(variant), || p1_fig9(variant, class)),
        || scope.ensemble_records.map(|r| p1_fig12(variant, r)),
    );
    let mut out = Vec::with_capacity(P1_QUANTITIES.len());
    out.extend(fig8.map(exact));
    out.extend(fig9.map(exact));
    out.extend(fig12.into_iter().flatten());
    out.extend(p1_table3(variant).map(exact));
    Ok(out)
}

/// The raw quantities (with the intervals of the ensemble ones) of prototype 2 at a variant, in the order of [`Prototype::quantities`]
/// in `scope`: Figure 13 at 10 V with the linear law and the variant's b_im (the paper's fit),
/// the Hertz alternative with its claim-defined b_im; Figures 14 and 15 at 15 V
/// (`p2_ensembles`); Table 3 at 15 V.
pub fn evaluate_p2(
    variant: &Variant,
    claims: &Claims,
    scope: Scope,
) -> Result<Vec<Estimate>, DeviationsError> {
    let (fig13, ensembles) = rayon::join(
        || p2_fig13(variant, claims),
        || scope.ensemble_records.map(|r| p2_ensembles(variant, r)),
    );
    let mut out = Vec::with_capacity(P2_QUANTITIES.len());
    out.extend(fig13.map(exact));
    out.extend(ensembles.into_iter().flatten());
    out.extend(p2_table3(variant).map(exact));
    Ok(out)
}

/// The quantitative claims of a prototype at a variant (the calibration's objective): every
/// quantitative claim of [`evaluate`], computed without the continuations none of them needs
/// (prototype 2's come from the ensembles and Table 3).
pub fn evaluate_quantitative(
    prototype: Prototype,
    variant: &Variant,
    claims: &Claims,
    scope: Scope,
) -> Result<Vec<Evaluation>, DeviationsError> {
    match prototype {
        Prototype::P1 => Ok(evaluate(prototype, variant, claims, scope)?
            .into_iter()
            .filter(|e| e.kind == Kind::Quantitative)
            .collect()),
        // Everything but Figure 13 (whose claims are yes/no), in order: the ensembles and
        // Table 3, without the continuations.
        Prototype::P2 => prototype
            .quantities(scope)
            .iter()
            .filter(|q| q.claim != "F13")
            .zip(
                scope
                    .ensemble_records
                    .map(|r| p2_ensembles(variant, r))
                    .into_iter()
                    .flatten()
                    .chain(p2_table3(variant).map(exact)),
            )
            .map(|(qty, estimate)| normalised(qty, estimate, claims))
            .filter(|e| !matches!(e, Ok(e) if e.kind != Kind::Quantitative))
            .collect(),
    }
}

/// Every quantity of a prototype at a variant, normalised by the claims file.
pub fn evaluate(
    prototype: Prototype,
    variant: &Variant,
    claims: &Claims,
    scope: Scope,
) -> Result<Vec<Evaluation>, DeviationsError> {
    let raw = match prototype {
        Prototype::P1 => evaluate_p1(variant, claims, scope)?,
        Prototype::P2 => evaluate_p2(variant, claims, scope)?,
    };
    prototype
        .quantities(scope)
        .iter()
        .zip(raw)
        .map(|(qty, estimate)| normalised(qty, estimate, claims))
        .collect()
}

/// An outcome without sampling error.
fn exact(outcome: Outcome) -> Estimate {
    (outcome, None)
}

/// An estimate normalised by its claim ([`normalise`]), with its interval.
fn normalised(
    qty: &Quantity,
    (outcome, ci95): Estimate,
    claims: &Claims,
) -> Result<Evaluation, DeviationsError> {
    Ok(normalise(qty, outcome, claims)?.with_ci95(ci95))
}

/// The unit-cube model of a prototype: the variant of `base` at a point, evaluated.
pub fn evaluate_at(
    prototype: Prototype,
    ranges: &Ranges,
    base: &Device,
    point: &[f64],
    claims: &Claims,
    scope: Scope,
) -> Result<Vec<Evaluation>, DeviationsError> {
    let variant = ranges.variant(base, point)?;
    evaluate(prototype, &variant, claims, scope)
}
