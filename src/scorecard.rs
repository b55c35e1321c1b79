//! Claims of the paper, our values, tolerances and verdicts (SPEC 6 and 7).
//!
//! `data/claims.toml` lists every number the paper claims with its tolerance, fixed before any
//! of our results existed. Experiments emit [`Value`] rows keyed by (claim id, quantity,
//! parameter set); [`score`] joins them into [`Row`]s with a [`Verdict`]:
//!
//! * quantitative: `reproduced` iff |ours - paper| <= max(tol_rel |paper|, tol_abs);
//! * qualitative (paper = 1.0 for "yes"): `reproduced` iff ours == paper;
//! * no value from us yet: `not yet`.

use serde::{Deserialize, Serialize};

/// Whether a claim is a number or a yes/no statement.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Kind {
    /// A number with a tolerance.
    Quantitative,
    /// A yes/no statement (1.0 = yes).
    Qualitative,
}

/// One number claimed by the paper.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Claim {
    /// Claim id (SPEC 6), e.g. `F8-c`.
    pub id: String,
    /// Figure or table.
    pub figure: String,
    /// Quantity key within the claim.
    pub quantity: String,
    /// What is compared.
    pub text: String,
    /// Experiment that produces our value.
    pub experiment: String,
    /// Unit of `paper` and our value.
    pub unit: String,
    /// The paper's value.
    pub paper: f64,
    /// Quantitative or qualitative.
    pub kind: Kind,
    /// Relative tolerance.
    #[serde(default)]
    pub tol_rel: f64,
    /// Absolute tolerance in `unit`.
    #[serde(default)]
    pub tol_abs: f64,
    /// Why this tolerance.
    pub why: String,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ClaimsFile {
    claim: Vec<Claim>,
}

/// Parses the claims file text.
pub fn parse_claims(text: &str) -> Result<Vec<Claim>, String> {
    let f: ClaimsFile = toml::from_str(text).map_err(|e| e.to_string())?;
    Ok(f.claim)
}

/// Our value for a claim's quantity under one parameter set.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Value {
    /// Claim id.
    pub claim: String,
    /// Quantity key.
    pub quantity: String,
    /// Parameter set (`published`, `calibrated`).
    pub set: String,
    /// Our value (qualitative: 1.0 yes, 0.0 no).
    pub ours: f64,
    /// Optional uncertainty of our value (same unit), e.g. a bracket half-width or a 95 % CI.
    #[serde(default)]
    pub uncertainty: Option<f64>,
}

/// Outcome of a comparison.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Verdict {
    /// Within tolerance.
    #[serde(rename = "reproduced")]
    Reproduced,
    /// Outside tolerance: our value is reported.
    #[serde(rename = "deviates")]
    Deviates,
    /// No value from us yet.
    #[serde(rename = "not yet")]
    NotYet,
}

impl Verdict {
    /// The label used in files and the book.
    pub fn label(self) -> &'static str {
        match self {
            Verdict::Reproduced => "reproduced",
            Verdict::Deviates => "deviates",
            Verdict::NotYet => "not yet",
        }
    }
}

impl Claim {
    /// Effective absolute tolerance max(tol_rel |paper|, tol_abs).
    pub fn tolerance(&self) -> f64 {
        (self.tol_rel * self.paper.abs()).max(self.tol_abs)
    }

    /// Verdict for our value.
    pub fn verdict(&self, ours: Option<f64>) -> Verdict {
        match ours {
            None => Verdict::NotYet,
            Some(v) if !v.is_finite() => Verdict::Deviates,
            Some(v) => match self.kind {
                Kind::Qualitative => {
                    if (v - self.paper).abs() < 0.5 {
                        Verdict::Reproduced
                    } else {
                        Verdict::Deviates
                    }
                }
                Kind::Quantitative => {
                    if (v - self.paper).abs() <= self.tolerance() {
                        Verdict::Reproduced
                    } else {
                        Verdict::Deviates
                    }
                }
            },
        }
    }
}

/// A scorecard row (SPEC 7).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Row {
    /// Claim id.
    pub claim: String,
    /// Quantity key.
    pub quantity: String,
    /// Parameter set.
    pub set: String,
    /// The paper's value.
    pub paper: f64,
    /// Our value (None: not yet).
    pub ours: Option<f64>,
    /// Uncertainty of our value, if known.
    pub uncertainty: Option<f64>,
    /// Unit.
    pub unit: String,
    /// Effective absolute tolerance.
    pub tolerance: f64,
    /// Verdict.
    pub verdict: Verdict,
    /// What is compared.
    pub text: String,
    /// A remark on the row (e.g. that a value is a calibration target, not a prediction).
    #[serde(default)]
    pub note: String,
}

/// Joins claims with our values: one row per claim number and per parameter set that has a
/// value; a claim with no value at all gets one `not yet` row for the `published` set.
pub fn score(claims: &[Claim], values: &[Value]) -> Vec<Row> {
    let mut rows = Vec::new();
    for c in claims {
        let mine: Vec<&Value> = values
            .iter()
            .filter(|v| v.claim == c.id && v.quantity == c.quantity)
            .collect();
        let mut push = |set: &str, ours: Option<f64>, unc: Option<f64>| {
            rows.push(Row {
                claim: c.id.clone(),
                quantity: c.quantity.clone(),
                set: set.to_string(),
                paper: c.paper,
                ours,
                uncertainty: unc,
                unit: c.unit.clone(),
                tolerance: c.tolerance(),
                verdict: c.verdict(ours),
                text: c.text.clone(),
                note: String::new(),
            })
        };
        if mine.is_empty() {
            push("published", None, None);
        }
        for v in mine {
            push(&v.set, Some(v.ours), v.uncertainty);
        }
    }
    rows
}
