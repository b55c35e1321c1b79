//! One of our numbers against a reference value: how the difference is measured, the largest
//! difference accepted, and the verdict. The scorecard's claims, the cross-check with ngspice
//! and the validation against references all judge with [`Comparison`] and report a
//! [`Verdict`].
//!
//! ```
//! use endstop::num::compare::{Comparison, Measure, Verdict};
//! let c = Comparison { ours: 10.2, reference: 10.0, measure: Measure::Relative, tolerance: 0.05 };
//! assert!((c.difference() - 0.02).abs() < 1e-12);
//! assert_eq!(c.verdict(), Verdict::Reproduced);
//! // A value that is not a number is never within a tolerance.
//! assert_eq!(Comparison { ours: f64::NAN, ..c }.verdict(), Verdict::Deviates);
//! ```

use serde::{Deserialize, Serialize};

/// How a comparison measures the difference between ours and the reference.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Measure {
    /// `|ours - reference| / |reference|`.
    Relative,
    /// `|ours - reference| / |ours|`: a peer tool's number measured against ours (the
    /// cross-check's ngspice runs, whose differences are stated relative to our model).
    RelativeToOurs,
    /// `|ours - reference|`, in the quantity's unit.
    Absolute,
    /// `ours - reference`: ours must not exceed the reference (a bound) by more than the
    /// tolerance.
    NotAbove,
}

/// One of our numbers against a reference value, with the largest difference accepted.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Comparison {
    /// Our value.
    pub ours: f64,
    /// The reference value (the paper's, a closed form's, a peer tool's).
    pub reference: f64,
    /// How the difference is measured.
    pub measure: Measure,
    /// The largest difference accepted, in the measure's unit.
    pub tolerance: f64,
}

impl Comparison {
    /// The difference, as [`Comparison::measure`] says (NaN when either value is NaN).
    pub fn difference(&self) -> f64 {
        let d = (self.ours - self.reference).abs();
        match self.measure {
            Measure::Relative => d / self.reference.abs(),
            Measure::RelativeToOurs => d / self.ours.abs(),
            Measure::Absolute => d,
            Measure::NotAbove => self.ours - self.reference,
        }
    }

    /// True when the difference is within the tolerance; a NaN on either side is not.
    pub fn within(&self) -> bool {
        self.difference() <= self.tolerance
    }

    /// [`Verdict::Reproduced`] within the tolerance, [`Verdict::Deviates`] outside it.
    pub fn verdict(&self) -> Verdict {
        Verdict::of(self.within())
    }
}

/// The outcome of a comparison.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Verdict {
    /// Within tolerance.
    #[serde(rename = "reproduced")]
    Reproduced,
    /// Outside tolerance: our value is reported.
    #[serde(rename = "deviates")]
    Deviates,
    /// No value of ours to compare (not computed yet, or its computation failed).
    #[serde(rename = "not yet")]
    NotYet,
    /// Our value and its difference are reported but not judged: the reference is a
    /// hypothesis that a study did not confirm.
    #[serde(rename = "open question")]
    Open,
}

impl Verdict {
    /// [`Verdict::Reproduced`] when `within`, [`Verdict::Deviates`] otherwise.
    pub fn of(within: bool) -> Verdict {
        if within {
            Verdict::Reproduced
        } else {
            Verdict::Deviates
        }
    }

    /// The label used in the scorecard and the book.
    pub fn label(self) -> &'static str {
        match self {
            Verdict::Reproduced => "reproduced",
            Verdict::Deviates => "deviates",
            Verdict::NotYet => "not yet",
            Verdict::Open => "open question",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_measure_is_its_formula() {
        let c = |measure| Comparison {
            ours: 3.0,
            reference: 2.0,
            measure,
            tolerance: 0.0,
        };
        assert_eq!(c(Measure::Relative).difference(), 0.5);
        assert_eq!(c(Measure::RelativeToOurs).difference(), 1.0 / 3.0);
        assert_eq!(c(Measure::Absolute).difference(), 1.0);
        assert_eq!(c(Measure::NotAbove).difference(), 1.0);
        let below = Comparison {
            ours: 1.0,
            ..c(Measure::NotAbove)
        };
        assert_eq!(below.verdict(), Verdict::Reproduced);
    }
}
