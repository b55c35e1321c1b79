//! Which branch a measured point lies on, where the data state a branch end and their points
//! show the jump: the points decide. A stated end has an uncertainty of its own (0.5 Hz in the
//! recovery family, against grid steps of 1 to 4 Hz), so it can lie past a measured frequency
//! at which the points have already jumped; a point assigned by the stated end is then
//! compared with the wrong branch, and the fit, even from the truth, cannot describe it.
//!
//! The rule was written after the recovery family's case 3 missed this way (a hypothesis, so
//! tested here on cases it was not derived from): the family's three cases that state a
//! branch end (3, 15 and 20), each with new noise seeds fixed before the first run (the case's
//! seed plus 1000 + k, k = 0..SEEDS). Every realisation whose stated end and points' jump
//! disagree is fitted with the default settings, and its chi-square must not be improbable:
//! probability of a larger one at least 1e-3 each, so that right fits fail the test with
//! probability about 1e-3 times the number fitted. The test fails too when no realisation
//! disagrees (it would then test nothing). Ignored by `cargo test --release` (about a minute);
//! CI runs it with `--include-ignored`.

use endstop::fit::data::FeatureKind;
use endstop::fit::family::recovery_family;
use endstop::fit::{fit, FitSettings};

/// New seeds per case.
const SEEDS: u64 = 6;

/// Smallest probability of a larger chi-square accepted for one fit.
const ALPHA: f64 = 1e-3;

#[test]
#[ignore = "fits of new realisations: about a minute; CI runs it with --include-ignored"]
fn the_points_not_the_stated_end_decide_the_branch() {
    let family = recovery_family();
    let stating: Vec<_> = family
        .iter()
        .filter(|c| {
            c.sweeps
                .iter()
                .any(|s| s.features.contains(&FeatureKind::BranchEnd))
        })
        .collect();
    assert_eq!(
        stating.len(),
        3,
        "the family's cases that state a branch end"
    );
    let mut fitted = Vec::new();
    for c in stating {
        for k in 0..SEEDS {
            let mut case = c.clone();
            case.seed = c.seed + 1000 + k;
            let data = case.data().unwrap();
            let disagree = data.iter().any(|d| {
                let end = d.features.iter().find(|f| f.kind == FeatureKind::BranchEnd);
                match (d.points_jump(), end) {
                    (Some(j), Some(e)) => {
                        let (lo, hi) = (j.from_hz.min(j.to_hz), j.from_hz.max(j.to_hz));
                        !(lo < e.freq_hz && e.freq_hz < hi)
                    }
                    _ => false,
                }
            });
            if !disagree {
                continue;
            }
            let r = fit(
                &case.start_device().unwrap(),
                &data,
                &case.free,
                &FitSettings::default(),
            )
            .unwrap_or_else(|e| panic!("{} seed {}: {e}", case.name, case.seed));
            let p = r.chi2_p.unwrap_or(0.0);
            let covered: Vec<bool> = r
                .params
                .iter()
                .zip(&case.truth)
                .map(|(q, &t)| q.interval.0 <= t && t <= q.interval.1)
                .collect();
            eprintln!(
                "{} seed {}: chi2/dof {:.3}, P(larger) {p:.3}, covered {covered:?}",
                case.name, case.seed, r.reduced_chi2
            );
            fitted.push((case.name, case.seed, p));
        }
    }
    assert!(
        !fitted.is_empty(),
        "no realisation disagrees: nothing tested"
    );
    for (name, seed, p) in &fitted {
        assert!(
            *p >= ALPHA,
            "{name} seed {seed}: P(larger chi-square) {p:.2e}"
        );
    }
}
