//! What the study evaluates: the claim quantities of each prototype ([`Quantity`]), the value
//! or named absence of one at a point ([`Outcome`]), and that value normalised by its claim
//! ([`Evaluation`]).

use super::DeviationsError;
use crate::paper::claims::{Answer, Claim, Claims, Kind, Verdict};
use crate::paper::figures::fig09::FIG9_EXTEND_G;

/// Upper end of prototype 1's frequency continuations (Hz): Figure 8's range extended to
/// 2000 Hz, as the response study's fold claims (without end-stop damping the impacting
/// branch reaches 1600 Hz).
pub const P1_STOP_HZ: f64 = 2000.0;

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

    /// Every quantity the study can evaluate, in output order.
    pub fn all_quantities(self) -> &'static [Quantity] {
        match self {
            Prototype::P1 => &P1_QUANTITIES,
            Prototype::P2 => &P2_QUANTITIES,
        }
    }

    /// The quantity of claim `claim` keyed `quantity`, if the study evaluates it.
    pub fn quantity(self, claim: &str, quantity: &str) -> Option<Quantity> {
        self.all_quantities()
            .iter()
            .find(|q| q.claim == claim && q.quantity == quantity)
            .copied()
    }

    /// The quantities an evaluation in `scope` computes, in output order.
    pub fn quantities(self, scope: Scope) -> Vec<Quantity> {
        self.all_quantities()
            .iter()
            .filter(|q| scope.ensemble_records.is_some() || !q.ensemble)
            .copied()
            .collect()
    }
}

/// What an evaluation computes: the sine-sweep and analytic claims by their fast paths
/// always; the ensemble claims (Figures 12, 14 and 15) only when given a number of records
/// per level (each costs tens of records of 10 s).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Scope {
    /// Records per level of the ensemble claims (the first of the figures' own streams);
    /// `None` leaves the ensemble claims out.
    pub ensemble_records: Option<usize>,
}

/// One claim quantity of the study: its key in the claims file and what stands in for it when
/// it does not exist at a point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Quantity {
    /// Claim id.
    pub claim: &'static str,
    /// Quantity key.
    pub quantity: &'static str,
    /// The value used where the quantity does not exist or its computation failed: for a
    /// frequency or an onset, the end of the continuation's range (a censored value: the event
    /// lies beyond it); for a yes/no claim, 0 (not shown); for a power, a width or a ratio, 0
    /// (only where its computation failed); `None` for an analytic quantity, which always
    /// exists.
    pub substitute: Option<f64>,
    /// Computed from ensembles of random-vibration records ([`Scope::ensemble_records`]).
    pub ensemble: bool,
}

const fn q(claim: &'static str, quantity: &'static str, substitute: Option<f64>) -> Quantity {
    Quantity {
        claim,
        quantity,
        substitute,
        ensemble: false,
    }
}

/// An ensemble quantity (substitute 0, used only where the ensemble failed or a width is
/// undetermined).
const fn qe(claim: &'static str, quantity: &'static str) -> Quantity {
    Quantity {
        claim,
        quantity,
        substitute: Some(0.0),
        ensemble: true,
    }
}

/// Prototype 1's quantities: Figure 8's kink and jumps and their order, Figure 9's onsets
/// and saturated powers, Figure 12's widths, Table 3's first column.
pub const P1_QUANTITIES: [Quantity; 19] = [
    q("F8-b", "impact_onset_5p5g_hz", Some(P1_STOP_HZ)),
    q("F8-c", "jump_hertz_bim1p5_hz", Some(P1_STOP_HZ)),
    q("F8-d", "jump_hertz_bim0_hz", Some(P1_STOP_HZ)),
    q("F8-e", "jump_hertz_bim10_hz", Some(P1_STOP_HZ)),
    q("F8-e", "jump_order_by_bim", Some(0.0)),
    q("F8-f", "jump_linear_bim2_hz", Some(P1_STOP_HZ)),
    q("F9-a", "onset_g_20v", Some(FIG9_EXTEND_G)),
    q("F9-a", "onset_g_30v", Some(FIG9_EXTEND_G)),
    q("F9-a", "onset_g_40v", Some(FIG9_EXTEND_G)),
    q("F9-a", "onset_same_all_vb", Some(0.0)),
    q("F9-b", "p_sat_20v_nw", Some(0.0)),
    q("F9-b", "p_sat_40v_nw", Some(0.0)),
    q("F9-b", "p_sat_ratio_40v_20v", Some(0.0)),
    qe("F12", "bw_7p4e-3_hz"),
    qe("F12", "bw_2p85e-2_hz"),
    qe("F12", "bw_ratio_2p85e-2_over_7p4e-3"),
    q("T3-a", "k2_pct_p1", None),
    q("T3-a", "qm_p1", None),
    q("T3-a", "k2qm_p1", None),
];

/// Prototype 2's quantities: Figure 13's yes/no claims, Figure 14's efficiency at 1.69e-3,
/// Figure 15's peak, width, width ratio and widening, Table 3's second column.
pub const P2_QUANTITIES: [Quantity; 11] = [
    q("F13", "no_impact_0p12g", Some(0.0)),
    q("F13", "jump_0p31g", Some(0.0)),
    q("F13", "hertz_linear_agree", Some(0.0)),
    qe("F14-b", "eff_1p69e-3_pct"),
    qe("F15-a", "peak_0p34e-3_hz"),
    qe("F15-a", "bw_0p34e-3_hz"),
    qe("F15-b", "bw_ratio_0p55e-3_over_0p34e-3"),
    qe("F15-c", "widening_up_1p69e-3"),
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

    /// A yes/no quantity: 1 for yes, 0 for no.
    pub fn yes_no(yes: bool) -> Self {
        Outcome::Value(if yes { 1.0 } else { 0.0 })
    }

    /// The outcome of a [`Outcome::label`] (and the value, for `"value"`); `None` for an
    /// unknown label.
    pub fn from_label(label: &str, value: f64) -> Option<Self> {
        Some(match label {
            "value" => Outcome::Value(value),
            "no fold" => Outcome::NoFold,
            "no grazing" => Outcome::NoGrazing,
            "continuation failed" => Outcome::Failed,
            _ => return None,
        })
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
    /// Half-width of the 95 % interval of the value from the sampling error of its records,
    /// in the value's unit (an ensemble quantity); `None` for a quantity without sampling
    /// error (a continuation, eqs 15-18) and for a yes/no claim.
    pub ci95: Option<f64>,
}

impl Evaluation {
    /// The same evaluation with the half-width `ci95` of its value's 95 % interval.
    pub fn with_ci95(self, ci95: Option<f64>) -> Self {
        Self { ci95, ..self }
    }
}

/// A quantity's outcome normalised by its claim.
pub fn normalise(
    qty: &Quantity,
    outcome: Outcome,
    claims: &Claims,
) -> Result<Evaluation, DeviationsError> {
    let claim: &Claim = claims
        .get(qty.claim, qty.quantity)
        .ok_or(DeviationsError::UnknownClaim(qty.claim, qty.quantity))?;
    let value = match (outcome.value(), qty.substitute) {
        (Some(v), _) => v,
        (None, Some(s)) => s,
        (None, None) => return Err(DeviationsError::NoSubstitute(qty.claim, qty.quantity)),
    };
    let paper = claim.paper.to_f64();
    let deviation = match claim.kind {
        Kind::Quantitative => (value - paper) / claim.tolerance(),
        Kind::Qualitative => value - paper,
    };
    let meets = outcome.value().is_some()
        && claim
            .read(Answer::Number(value))
            .is_ok_and(|v| claim.verdict(Some(v)) == Verdict::Reproduced);
    Ok(Evaluation {
        quantity: *qty,
        outcome,
        value,
        deviation,
        meets,
        kind: claim.kind,
        ci95: None,
    })
}

/// Summary key of a quantity's value at the best set of the calibration of its prototype
/// (`None`: the study does not evaluate the claim).
pub fn best_value_key(claim: &str, quantity: &str) -> Option<String> {
    Prototype::BOTH.iter().find_map(|p| {
        p.all_quantities()
            .iter()
            .any(|q| q.claim == claim && q.quantity == quantity)
            .then(|| format!("calibration_{}_{claim}_{quantity}_value", p.key()))
    })
}

/// The ratio of two outcomes, failed unless both exist.
pub(crate) fn ratio(a: Outcome, b: Outcome) -> Outcome {
    match (a.value(), b.value()) {
        (Some(a), Some(b)) => Outcome::Value(a / b),
        _ => Outcome::Failed,
    }
}

/// An outcome with the half-width of its 95 % interval where it has sampling error (see
/// [`Evaluation::ci95`]).
pub type Estimate = (Outcome, Option<f64>);
