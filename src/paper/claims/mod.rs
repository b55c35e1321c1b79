//! Claims of the paper, our values, tolerances and verdicts.
//!
//! `data/claims.toml` lists every number the paper claims, each in a tolerance class fixed
//! before any of our results existed ([`ToleranceClass`]). It is compiled into the crate
//! ([`Claims::bundled`]) so that the figures' `claims` functions, the tests and the scorecard
//! read the same file. Every number of a claim has its key in [`keys`] ([`ClaimKey`]), which a
//! test holds to the file. Experiments emit [`Value`] rows keyed by (claim key, parameter set);
//! [`score`] joins them into [`Row`]s with a [`Verdict`]:
//!
//! * quantitative: `reproduced` iff |ours - paper| <= max(tol_rel |paper|, tol_abs);
//! * qualitative: `reproduced` iff ours and the paper say the same, yes or no;
//! * no value from us yet: `not yet`.
//!
//! A claim's value, the paper's and ours, is an [`Answer`]: a number, or yes/no by type. Files
//! carry it as a number (the scorecard's contract: yes is 1, no is 0); [`Claim::read`] is the
//! one place that turns such a number back into a yes/no, strictly, by the claim's kind.
//!
//! A value whose (claim, quantity) matches no claim is an error ([`ClaimsError::Unknown`]): a
//! typo in a key must not drop a number from the scorecard silently.

mod answer;
pub mod keys;

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};
use thiserror::Error;

pub use answer::Answer;
pub use keys::ClaimKey;

use crate::num::compare::{Comparison, Measure};
use crate::paper::setups::ParamSet;

/// The claims file as compiled into the crate.
pub const CLAIMS_TOML: &str = include_str!("../../../data/claims.toml");

/// Errors of the claims file and of scoring.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ClaimsError {
    /// The file is not valid TOML for the claims schema.
    #[error("data/claims.toml: {0}")]
    Parse(String),
    /// A claim names a tolerance class that the file does not define.
    #[error("data/claims.toml: claim ({id}, {quantity}) has class `{class}`, which is not defined under [class]")]
    UnknownClass {
        /// Claim id.
        id: String,
        /// Quantity key.
        quantity: String,
        /// The class named.
        class: String,
    },
    /// Two claims share an (id, quantity) key.
    #[error("data/claims.toml: claim ({id}, {quantity}) appears twice")]
    Duplicate {
        /// Claim id.
        id: String,
        /// Quantity key.
        quantity: String,
    },
    /// A rule needs a tolerance class that the file does not define.
    #[error("data/claims.toml: no tolerance class `{class}` (a rule of the paper layer needs it)")]
    MissingClass {
        /// The class needed.
        class: String,
    },
    /// A value is not of its claim's kind (a number for a yes/no claim other than 0 or 1, a
    /// yes/no for a quantitative claim).
    #[error("claim ({claim}, {quantity}) is {kind}: {value} is not such a value")]
    Kind {
        /// Claim id.
        claim: String,
        /// Quantity key.
        quantity: String,
        /// What the claim takes (`a number` or `yes/no`).
        kind: &'static str,
        /// The value given, as the files write it.
        value: f64,
    },
    /// A value matches no claim.
    #[error(
        "value ({claim}, {quantity}) for set `{set}` = {ours} matches no claim in data/claims.toml"
    )]
    Unknown {
        /// Claim id of the value.
        claim: String,
        /// Quantity key of the value.
        quantity: String,
        /// Parameter set of the value.
        set: ParamSet,
        /// The value.
        ours: f64,
    },
}

/// A tolerance class: how close our value must be to the paper's for `reproduced`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ToleranceClass {
    /// Relative tolerance.
    #[serde(default)]
    pub tol_rel: f64,
    /// Absolute tolerance, in the claim's unit.
    #[serde(default)]
    pub tol_abs: f64,
    /// What the class covers and why.
    pub why: String,
}

impl ToleranceClass {
    /// The class's absolute tolerance about a reference value: max(tol_rel |reference|,
    /// tol_abs), the rule of the verdicts applied to a comparison of two of our own values.
    pub fn tolerance(&self, reference: f64) -> f64 {
        (self.tol_rel * reference.abs()).max(self.tol_abs)
    }
}

/// Whether a claim is a number or a yes/no statement.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Kind {
    /// A number with a tolerance.
    Quantitative,
    /// A yes/no statement.
    Qualitative,
}

impl Kind {
    /// What a value of this kind is, for messages.
    pub fn label(self) -> &'static str {
        match self {
            Kind::Quantitative => "a number",
            Kind::Qualitative => "yes/no",
        }
    }
}

/// One number claimed by the paper, with its tolerance resolved from its class.
#[derive(Debug, Clone, PartialEq)]
pub struct Claim {
    /// Claim id, e.g. `F8-c`.
    pub id: String,
    /// Figure or table.
    pub figure: String,
    /// Quantity key within the claim.
    pub quantity: String,
    /// What is compared.
    pub text: String,
    /// Experiment that produces our value.
    pub experiment: String,
    /// Unit of `paper` and our value (`bool` for a yes/no claim).
    pub unit: String,
    /// The paper's value.
    pub paper: Answer,
    /// Quantitative, or qualitative (the class `qualitative`).
    pub kind: Kind,
    /// Name of the tolerance class.
    pub class: String,
    /// Relative tolerance (from the class).
    pub tol_rel: f64,
    /// Absolute tolerance in `unit`: the class's, or half a unit of the paper's last printed
    /// digit for analytic quantities.
    pub tol_abs: f64,
    /// Why this tolerance (the class's reason).
    pub why: String,
    /// A remark on how the claim is judged.
    pub note: String,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ClaimEntry {
    id: String,
    figure: String,
    quantity: String,
    text: String,
    experiment: String,
    unit: String,
    paper: f64,
    class: String,
    #[serde(default)]
    printed_half_unit: Option<f64>,
    #[serde(default)]
    note: String,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ClaimsFile {
    class: BTreeMap<String, ToleranceClass>,
    claim: Vec<ClaimEntry>,
}

/// The claims file: tolerance classes and claims.
#[derive(Debug, Clone, PartialEq)]
pub struct Claims {
    /// Tolerance classes by name.
    pub classes: BTreeMap<String, ToleranceClass>,
    /// Every claim, in file order.
    pub claims: Vec<Claim>,
}

impl Claims {
    /// Parses and checks the text of a claims file: every class named exists, every
    /// (id, quantity) is unique.
    pub fn parse(text: &str) -> Result<Self, ClaimsError> {
        let f: ClaimsFile = toml::from_str(text).map_err(|e| ClaimsError::Parse(e.to_string()))?;
        let mut claims: Vec<Claim> = Vec::with_capacity(f.claim.len());
        for e in f.claim {
            let class = f
                .class
                .get(&e.class)
                .ok_or_else(|| ClaimsError::UnknownClass {
                    id: e.id.clone(),
                    quantity: e.quantity.clone(),
                    class: e.class.clone(),
                })?;
            if claims
                .iter()
                .any(|c| c.id == e.id && c.quantity == e.quantity)
            {
                return Err(ClaimsError::Duplicate {
                    id: e.id,
                    quantity: e.quantity,
                });
            }
            let kind = if e.class == "qualitative" {
                Kind::Qualitative
            } else {
                Kind::Quantitative
            };
            let paper = read(kind, &e.id, &e.quantity, e.paper)?;
            claims.push(Claim {
                kind,
                tol_rel: class.tol_rel,
                tol_abs: e.printed_half_unit.unwrap_or(class.tol_abs),
                why: class.why.clone(),
                id: e.id,
                figure: e.figure,
                quantity: e.quantity,
                text: e.text,
                experiment: e.experiment,
                unit: e.unit,
                paper,
                class: e.class,
                note: e.note,
            });
        }
        Ok(Self {
            classes: f.class,
            claims,
        })
    }

    /// The claims file compiled into the crate ([`CLAIMS_TOML`]).
    pub fn bundled() -> Result<Self, ClaimsError> {
        Self::parse(CLAIMS_TOML)
    }

    /// The claim with this id and quantity.
    pub fn get(&self, id: &str, quantity: &str) -> Option<&Claim> {
        self.claims
            .iter()
            .find(|c| c.id == id && c.quantity == quantity)
    }

    /// The claim of a key.
    pub fn claim(&self, key: ClaimKey) -> Option<&Claim> {
        self.get(key.id, key.quantity)
    }

    /// A tolerance class by name.
    pub fn class(&self, name: &str) -> Option<&ToleranceClass> {
        self.classes.get(name)
    }

    /// A tolerance class by name, or an error naming it (for the rules of the paper layer,
    /// which take their tolerances from the file rather than from literals in code).
    pub fn require_class(&self, name: &str) -> Result<&ToleranceClass, ClaimsError> {
        self.class(name).ok_or_else(|| ClaimsError::MissingClass {
            class: name.to_string(),
        })
    }

    /// `values`, each typed by its claim ([`Claim::read`]), if every one matches a claim of
    /// this file and is of its kind; else the error naming the first that does not (a typo in
    /// a key must not drop a number silently).
    pub fn known(&self, values: Vec<Value>) -> Result<Vec<Value>, ClaimsError> {
        values
            .into_iter()
            .map(|v| match self.get(&v.claim, &v.quantity) {
                None => Err(ClaimsError::Unknown {
                    claim: v.claim.clone(),
                    quantity: v.quantity.clone(),
                    set: v.set,
                    ours: v.ours.to_f64(),
                }),
                Some(c) => Ok(Value {
                    ours: c.read(v.ours)?,
                    ..v
                }),
            })
            .collect()
    }

    /// The claims an experiment produces, in file order.
    pub fn of_experiment<'a>(&'a self, experiment: &'a str) -> impl Iterator<Item = &'a Claim> {
        self.claims
            .iter()
            .filter(move |c| c.experiment == experiment)
    }
}

/// Our value for a claim's quantity under one parameter set.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Value {
    /// Claim id.
    pub claim: String,
    /// Quantity key.
    pub quantity: String,
    /// Parameter set.
    pub set: ParamSet,
    /// Our value.
    pub ours: Answer,
    /// Optional uncertainty of our value (same unit), e.g. a bracket half-width or a 95 % CI.
    #[serde(default)]
    pub uncertainty: Option<f64>,
    /// What the value is, for the book (e.g. "loss of contact, no jump").
    #[serde(default)]
    pub note: String,
}

impl Value {
    /// Our value `ours` of the claim number `key` under parameter set `set`, with its
    /// uncertainty (same unit) and a note for the book.
    pub fn new(
        key: ClaimKey,
        set: ParamSet,
        ours: f64,
        uncertainty: Option<f64>,
        note: impl Into<String>,
    ) -> Self {
        Self {
            claim: key.id.to_string(),
            quantity: key.quantity.to_string(),
            set,
            ours: Answer::Number(ours),
            uncertainty,
            note: note.into(),
        }
    }

    /// A yes/no value with a note.
    pub fn yes_no(key: ClaimKey, set: ParamSet, yes: bool, note: impl Into<String>) -> Self {
        Self {
            ours: Answer::YesNo(yes),
            ..Self::new(key, set, f64::NAN, None, note)
        }
    }

    /// True if this is a value of the claim number `key`.
    pub fn is(&self, key: ClaimKey) -> bool {
        self.claim == key.id && self.quantity == key.quantity
    }
}

pub use crate::num::compare::Verdict;

/// `x` as a value of a claim of `kind` (see [`Claim::read`]).
fn read(kind: Kind, claim: &str, quantity: &str, x: f64) -> Result<Answer, ClaimsError> {
    match kind {
        Kind::Quantitative => Ok(Answer::Number(x)),
        Kind::Qualitative if x == 1.0 => Ok(Answer::YesNo(true)),
        Kind::Qualitative if x == 0.0 => Ok(Answer::YesNo(false)),
        Kind::Qualitative => Err(ClaimsError::Kind {
            claim: claim.to_string(),
            quantity: quantity.to_string(),
            kind: kind.label(),
            value: x,
        }),
    }
}

impl Claim {
    /// Effective absolute tolerance max(tol_rel |paper|, tol_abs) (a yes/no claim's is 0).
    pub fn tolerance(&self) -> f64 {
        (self.tol_rel * self.paper.to_f64().abs()).max(self.tol_abs)
    }

    /// The value `answer` typed by this claim's kind: a number as read from a file becomes
    /// a yes/no for a yes/no claim when it is exactly 1 (yes) or 0 (no); any other number, or
    /// a yes/no for a quantitative claim, is an error naming the claim.
    pub fn read(&self, answer: Answer) -> Result<Answer, ClaimsError> {
        match (self.kind, answer) {
            (Kind::Qualitative, Answer::YesNo(_)) => Ok(answer),
            (_, Answer::Number(x)) => read(self.kind, &self.id, &self.quantity, x),
            (Kind::Quantitative, Answer::YesNo(_)) => Err(ClaimsError::Kind {
                claim: self.id.clone(),
                quantity: self.quantity.clone(),
                kind: self.kind.label(),
                value: answer.to_f64(),
            }),
        }
    }

    /// Verdict for our value: a number within the tolerance, or the paper's yes/no; a value
    /// that is not a finite number of this claim's kind deviates.
    pub fn verdict(&self, ours: Option<Answer>) -> Verdict {
        match (ours, self.paper) {
            (None, _) => Verdict::NotYet,
            (Some(Answer::Number(v)), Answer::Number(p)) => Comparison {
                ours: v,
                reference: p,
                measure: Measure::Absolute,
                tolerance: self.tolerance(),
            }
            .verdict(),
            (Some(Answer::YesNo(v)), Answer::YesNo(p)) => Verdict::of(v == p),
            (Some(_), _) => Verdict::Deviates,
        }
    }
}

/// A scorecard row.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Row {
    /// Claim id.
    pub claim: String,
    /// Quantity key.
    pub quantity: String,
    /// Parameter set.
    pub set: ParamSet,
    /// The paper's value.
    pub paper: Answer,
    /// Our value (None: not yet).
    pub ours: Option<Answer>,
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
    /// For a jump claim: the upper fold of the continued periodic orbits (Hz), beside the
    /// sweep's jump (the verdict stays the sweep's); absent for every other row.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fold_hz: Option<f64>,
    /// Our value at the best set of the multi-claim calibration within the sensitivity ranges
    /// (the study's summary, when it has been run), on the `published` row of a claim the study
    /// evaluates; absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub best_calibrated: Option<f64>,
}

/// Joins claims with our values: one row per claim number and per parameter set that has a
/// value; a claim with no value at all gets one `not yet` row for the `published` set. A value
/// that matches no claim is an error naming it.
pub fn score(claims: &Claims, values: &[Value]) -> Result<Vec<Row>, ClaimsError> {
    let values = claims.known(values.to_vec())?;
    let mut rows = Vec::new();
    for c in &claims.claims {
        let mine: Vec<&Value> = values
            .iter()
            .filter(|v| v.claim == c.id && v.quantity == c.quantity)
            .collect();
        let mut push = |set: ParamSet, ours: Option<Answer>, unc: Option<f64>| {
            rows.push(Row {
                claim: c.id.clone(),
                quantity: c.quantity.clone(),
                set,
                paper: c.paper,
                ours,
                uncertainty: unc,
                unit: c.unit.clone(),
                tolerance: c.tolerance(),
                verdict: c.verdict(ours),
                text: c.text.clone(),
                note: String::new(),
                fold_hz: None,
                best_calibrated: None,
            })
        };
        if mine.is_empty() {
            push(ParamSet::Published, None, None);
        }
        for v in mine {
            push(v.set, Some(v.ours), v.uncertainty);
        }
    }
    Ok(rows)
}

/// Our value for one number of a claim (`data/claims.toml`), with a note for the book.
#[derive(Debug, Clone, PartialEq)]
pub struct ClaimValue {
    /// The claim number.
    pub key: ClaimKey,
    /// Our value.
    pub value: Answer,
    /// Uncertainty (bracket half-width), same unit.
    pub uncertainty: Option<f64>,
    /// What the value is (e.g. "loss of contact, no jump").
    pub note: String,
}

impl ClaimValue {
    /// The scorecard row input of this value under a parameter set.
    pub fn to_value(&self, set: ParamSet) -> Value {
        Value {
            ours: self.value,
            ..Value::new(self.key, set, f64::NAN, self.uncertainty, self.note.clone())
        }
    }
}

/// A yes/no value of a claim number with a note.
pub(crate) fn bool_value(key: ClaimKey, yes: bool, note: String) -> ClaimValue {
    ClaimValue {
        key,
        value: Answer::YesNo(yes),
        uncertainty: None,
        note,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn value(claim: &str, quantity: &str, ours: f64) -> Value {
        Value {
            claim: claim.into(),
            quantity: quantity.into(),
            set: ParamSet::Published,
            ours: Answer::Number(ours),
            uncertainty: None,
            note: String::new(),
        }
    }

    #[test]
    fn the_bundled_file_parses_with_resolved_tolerances() {
        let c = Claims::bundled().expect("data/claims.toml parses");
        let f = c.claim(keys::F8C_JUMP_HERTZ_BIM1P5).expect("F8-c");
        assert_eq!(f.tol_rel, c.class("frequency").unwrap().tol_rel);
        let d = c.claim(keys::F5A_DELTA0_P1).expect("F5-a");
        assert_eq!((d.tol_rel, d.tol_abs), (0.01, 0.5));
    }

    #[test]
    fn a_value_matching_no_claim_is_an_error_naming_it() {
        let c = Claims::bundled().unwrap();
        let ok = score(&c, &[value("F8-c", "jump_hertz_bim1p5_hz", 1425.0)]).unwrap();
        assert!(ok
            .iter()
            .any(|r| r.claim == "F8-c" && r.verdict == Verdict::Reproduced));
        let err = score(&c, &[value("F8-c", "jump_hertz_bim1p5", 1425.0)]).unwrap_err();
        let msg = err.to_string();
        assert!(
            msg.contains("(F8-c, jump_hertz_bim1p5)") && msg.contains("published"),
            "{msg}"
        );
    }

    #[test]
    fn an_unknown_class_or_a_duplicate_is_rejected() {
        let text = CLAIMS_TOML.replacen("class = \"frequency\"", "class = \"freq\"", 1);
        assert!(matches!(
            Claims::parse(&text),
            Err(ClaimsError::UnknownClass { .. })
        ));
        let first = CLAIMS_TOML.find("\n[[claim]]").unwrap() + 1;
        let second = CLAIMS_TOML[first..].find("\n[[claim]]").unwrap() + first + 1;
        let dup = format!("{}\n{}", CLAIMS_TOML, &CLAIMS_TOML[first..second]);
        let r = Claims::parse(&dup);
        assert!(matches!(r, Err(ClaimsError::Duplicate { .. })), "{r:?}");
    }
}
