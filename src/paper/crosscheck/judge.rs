//! ngspice's side and the judgement: its `wrdata` output read and measured over the
//! comparison window, its RMS voltages against ours under a case's tolerance, and the
//! acceptance over the whole cross-check.

use super::{CrosscheckError, Setting, Verdict};
use crate::num::compare::{Comparison, Measure};
use crate::spice::{parse_wrdata, Waveforms};
use crate::study::steady::Measurement;

/// ngspice's run of a case, measured over the comparison window.
#[derive(Debug, Clone, PartialEq)]
pub struct SpiceRun {
    /// RMS voltage of load 1 (V).
    pub v1_rms_v: f64,
    /// RMS voltage of load 2 (V).
    pub v2_rms_v: f64,
    /// Largest |x| (m).
    pub x_peak_m: f64,
    /// Fraction of the window in contact.
    pub contact_fraction: f64,
    /// Time points in the window.
    pub points: usize,
}

impl SpiceRun {
    /// Reads ngspice's `wrdata` text (vectors `v(n1)`, `v(n2)`, `v(xpos)` in um) and measures
    /// it over `window_s`; `gap_m` is the end-stop gap (contact is |x| beyond it).
    pub fn of_wrdata(
        text: &str,
        gap_m: f64,
        window_s: (f64, f64),
    ) -> Result<Self, CrosscheckError> {
        Self::read_wrdata(text, gap_m, window_s).map(|(run, _)| run)
    }

    /// [`SpiceRun::of_wrdata`], with the waveforms as read (for a caller that plots them).
    pub fn read_wrdata(
        text: &str,
        gap_m: f64,
        window_s: (f64, f64),
    ) -> Result<(Self, Waveforms), CrosscheckError> {
        let (t0, t1) = window_s;
        let w = parse_wrdata(text)?;
        let run = Self {
            v1_rms_v: w.rms("v(n1)", t0, t1)?,
            v2_rms_v: w.rms("v(n2)", t0, t1)?,
            x_peak_m: w.max_abs("v(xpos)", t0, t1)? * 1e-6,
            contact_fraction: w.fraction_above("v(xpos)", gap_m * 1e6, t0, t1)?,
            points: w.time.iter().filter(|&&t| t >= t0 && t <= t1).count(),
        };
        if !(run.v1_rms_v.is_finite() && run.v2_rms_v.is_finite()) {
            return Err(CrosscheckError::NonFinite);
        }
        Ok((run, w))
    }
}

/// The verdict on one ngspice run as the tables write it: within or outside the case's
/// tolerance, or, with [`Verdict::NotYet`], why ngspice gave no result (`failure`).
pub fn verdict_label(verdict: Verdict, failure: Option<&str>) -> String {
    match verdict {
        Verdict::Reproduced => "within tolerance".into(),
        Verdict::Deviates => "outside tolerance".into(),
        Verdict::NotYet => format!("ngspice failed: {}", failure.unwrap_or("no result")),
        Verdict::Open => "open question".into(),
    }
}

/// ngspice against ours on one case and setting.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Difference {
    /// (ngspice - ours) / ours of the RMS voltage of load 1.
    pub rel_v1: f64,
    /// The same for load 2.
    pub rel_v2: f64,
    /// The larger magnitude of the two, what the tolerance applies to.
    pub rel: f64,
    /// Our RMS voltages of loads 1 and 2 (V).
    pub ours_v: [f64; 2],
    /// ngspice's (V).
    pub spice_v: [f64; 2],
}

impl Difference {
    /// ngspice's run against our measurement.
    pub fn of(ours: &Measurement, spice: &SpiceRun) -> Self {
        let rel_v1 = (spice.v1_rms_v - ours.v1_rms_v) / ours.v1_rms_v;
        let rel_v2 = (spice.v2_rms_v - ours.v2_rms_v) / ours.v2_rms_v;
        Self {
            rel_v1,
            rel_v2,
            rel: rel_v1.abs().max(rel_v2.abs()),
            ours_v: [ours.v1_rms_v, ours.v2_rms_v],
            spice_v: [spice.v1_rms_v, spice.v2_rms_v],
        }
    }

    /// Each load's RMS voltage, ngspice's against ours relative to ours, under `tolerance`.
    pub fn comparisons(&self, tolerance: f64) -> [Comparison; 2] {
        [0, 1].map(|k| Comparison {
            ours: self.ours_v[k],
            reference: self.spice_v[k],
            measure: Measure::RelativeToOurs,
            tolerance,
        })
    }

    /// The verdict under `tolerance`: reproduced if both loads' relative differences are at
    /// most `tolerance` (a NaN deviates).
    pub fn verdict(&self, tolerance: f64) -> Verdict {
        Verdict::of(self.comparisons(tolerance).iter().all(Comparison::within))
    }
}

/// The acceptance over the whole cross-check: every case of `case_keys` must have exactly one
/// verdict under the documented settings ([`Setting::documented`]), and each must be
/// [`Verdict::Reproduced`]. `verdicts` holds (case key, setting, verdict) of every run. Returns
/// the failures, one line each: a case without a documented verdict (or with two), and a
/// documented verdict outside the tolerance or failed; a set with no case fails.
pub fn acceptance_failures(
    case_keys: &[&str],
    verdicts: &[(&str, Setting, Verdict)],
) -> Vec<String> {
    if case_keys.is_empty() {
        return vec!["no case was compared".into()];
    }
    let mut failures = Vec::new();
    for key in case_keys {
        let documented: Vec<Verdict> = verdicts
            .iter()
            .filter(|(k, s, _)| k == key && s.documented())
            .map(|(_, _, v)| *v)
            .collect();
        match documented.as_slice() {
            [Verdict::Reproduced] => {}
            [v] => failures.push(format!("{key} [documented]: {}", verdict_label(*v, None))),
            vs => failures.push(format!(
                "{key}: {} verdicts under the documented settings, expected one",
                vs.len()
            )),
        }
    }
    failures
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_acceptance_fails_on_a_missing_case_an_outside_verdict_or_no_case() {
        let within = Verdict::Reproduced;
        let outside = Verdict::Deviates;
        let all = [
            ("a", Setting::Defaults, outside),
            ("a", Setting::Documented, within),
            ("b", Setting::Documented, within),
        ];
        assert!(acceptance_failures(&["a", "b"], &all).is_empty());
        // Case b was not run under the documented settings: a failure, not a pass.
        let f = acceptance_failures(&["a", "b"], &all[..2]);
        assert_eq!(f.len(), 1, "{f:?}");
        assert!(f[0].starts_with("b: 0 verdicts"), "{f:?}");
        // Nothing compared at all.
        assert_eq!(acceptance_failures(&[], &[]).len(), 1);
        assert_eq!(acceptance_failures(&["a"], &[]).len(), 1);
        // A documented verdict outside the tolerance.
        let f = acceptance_failures(&["a"], &[("a", Setting::Documented, outside)]);
        assert_eq!(f, ["a [documented]: outside tolerance"]);
    }

    #[test]
    fn a_difference_that_is_not_a_number_is_outside() {
        let d = Difference {
            rel_v1: f64::NAN,
            rel_v2: f64::NAN,
            rel: f64::NAN,
            ours_v: [1.0, 1.0],
            spice_v: [f64::NAN, f64::NAN],
        };
        assert_eq!(d.verdict(1e-3), Verdict::Deviates);
        // One load's NaN is enough.
        let d = Difference {
            spice_v: [1.0, f64::NAN],
            ..d
        };
        assert_eq!(d.verdict(1e-3), Verdict::Deviates);
    }
}
