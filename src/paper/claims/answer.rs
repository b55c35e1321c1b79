//! The value of a claim, the paper's or ours ([`Answer`]): a number or a yes/no by type, and
//! a number in files (the scorecard's contract).

use serde::{Deserialize, Serialize};

use super::Kind;

/// The value of a claim, the paper's or ours: a number or a yes/no.
///
/// In files it is a number, as the scorecard's rows have always carried it: the number itself,
/// or 1 for yes and 0 for no ([`Answer::to_f64`]). A number read back is an
/// [`Answer::Number`] until [`super::Claim::read`] types it by its claim.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Answer {
    /// A quantity, in its claim's unit.
    Number(f64),
    /// A yes/no statement.
    YesNo(bool),
}

impl Answer {
    /// The number the files carry: the number, or 1 for yes and 0 for no.
    pub fn to_f64(self) -> f64 {
        match self {
            Answer::Number(v) => v,
            Answer::YesNo(yes) => f64::from(u8::from(yes)),
        }
    }

    /// The number of a quantitative answer; `None` for a yes/no.
    pub fn number(self) -> Option<f64> {
        match self {
            Answer::Number(v) => Some(v),
            Answer::YesNo(_) => None,
        }
    }

    /// The yes/no of a qualitative answer; `None` for a number.
    pub fn yes_no(self) -> Option<bool> {
        match self {
            Answer::Number(_) => None,
            Answer::YesNo(yes) => Some(yes),
        }
    }

    /// The kind of claim this answers.
    pub fn kind(self) -> Kind {
        match self {
            Answer::Number(_) => Kind::Quantitative,
            Answer::YesNo(_) => Kind::Qualitative,
        }
    }

    /// True for a number that is finite, and for every yes/no.
    pub fn is_finite(self) -> bool {
        self.to_f64().is_finite()
    }
}

impl From<f64> for Answer {
    fn from(v: f64) -> Self {
        Answer::Number(v)
    }
}

impl From<bool> for Answer {
    fn from(yes: bool) -> Self {
        Answer::YesNo(yes)
    }
}

impl Serialize for Answer {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_f64(self.to_f64())
    }
}

impl<'de> Deserialize<'de> for Answer {
    /// A number, or a JSON `true`/`false`; a number stays [`Answer::Number`] (see the type's
    /// docs).
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Wire {
            Number(f64),
            YesNo(bool),
        }
        Ok(match Wire::deserialize(d)? {
            Wire::Number(v) => Answer::Number(v),
            Wire::YesNo(yes) => Answer::YesNo(yes),
        })
    }
}

#[cfg(test)]
mod tests {
    use serde::de::IntoDeserializer;

    use super::*;
    use crate::paper::claims::{keys, score, Claims, ClaimsError, Value, Verdict};
    use crate::paper::setups::ParamSet;

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

    /// A yes/no is typed from the claim's creation to the scorecard's row, which writes it as
    /// the number the files have always carried; a number read back becomes a yes/no only by
    /// its claim, and only when it is exactly 1 or 0.
    #[test]
    fn yes_no_values_are_typed_and_written_as_one_or_zero() {
        let c = Claims::bundled().unwrap();
        let key = keys::F8E_JUMP_ORDER;
        let yes = Value::yes_no(key, ParamSet::Published, true, "");
        assert_eq!(yes.ours, Answer::YesNo(true));
        // Serialised (here by toml; the scorecard by serde_json, the same serde) as 1.0.
        let text = toml::to_string(&yes).unwrap();
        assert!(text.contains("ours = 1.0"), "{text}");
        // Read back: a number, typed by the claim when scored.
        let wire: serde::de::value::F64Deserializer<serde::de::value::Error> =
            1.0f64.into_deserializer();
        let back = Value {
            ours: Answer::deserialize(wire).unwrap(),
            ..yes.clone()
        };
        assert_eq!(back.ours, Answer::Number(1.0));
        let rows = score(&c, &[back]).unwrap();
        let row = rows.iter().find(|r| r.quantity == key.quantity).unwrap();
        assert_eq!(row.ours, Some(Answer::YesNo(true)));
        assert_eq!(row.paper, Answer::YesNo(true));
        assert_eq!(row.verdict, Verdict::Reproduced);
        let text = toml::to_string(row).unwrap();
        assert!(
            text.contains("ours = 1.0") && text.contains("paper = 1.0"),
            "{text}"
        );
        let no = score(&c, &[Value::yes_no(key, ParamSet::Published, false, "")]).unwrap();
        let row = no.iter().find(|r| r.quantity == key.quantity).unwrap();
        assert_eq!(row.verdict, Verdict::Deviates);
        // Neither 1 nor 0: an error, not a yes by one reading and a no by another.
        let half = value(key.id, key.quantity, 0.7);
        assert!(matches!(score(&c, &[half]), Err(ClaimsError::Kind { .. })));
        // A yes/no for a number is an error too.
        let num = keys::F8C_JUMP_HERTZ_BIM1P5;
        let wrong = Value::yes_no(num, ParamSet::Published, true, "");
        assert!(matches!(score(&c, &[wrong]), Err(ClaimsError::Kind { .. })));
    }
}
