//! A stop's gap the best refined fit leaves beyond every orbit's reach (`fit::untouched`):
//! its Jacobian column is exactly zero, so the search cannot move it, and where the fit is
//! improbable the gap is tried just inside the orbits' reach and refined from there.
//!
//! The rule was written after the recovery family's case 13 (the electromagnetic example's
//! two gaps, up-sweep) stopped on that plateau, so it is a hypothesis, tested here on
//! realisations it was not derived from: case 13 with new noise seeds fixed before the first
//! run (its seed plus 2000 + k, k = 0..SEEDS). Each fit's chi-square must not be improbable
//! (probability of a larger one at least 1e-3 each), and at least one realisation must have
//! been rescued by the rule (its reported start is the moved gap's), or the test tests
//! nothing. Ignored by `cargo test --release` (about a minute); CI runs it with
//! `--include-ignored`.

use endstop::fit::family::recovery_family;
use endstop::fit::{fit, FitSettings, StartOrigin};

/// New seeds.
const SEEDS: u64 = 4;

/// Smallest probability of a larger chi-square accepted for one fit.
const ALPHA: f64 = 1e-3;

#[test]
#[ignore = "fits of new realisations: about a minute; CI runs it with --include-ignored"]
fn a_gap_beyond_every_orbit_is_tried_inside_their_reach() {
    let family = recovery_family();
    let c = family
        .iter()
        .find(|c| c.name.starts_with("13 "))
        .expect("case 13");
    let mut rescued = 0;
    for k in 0..SEEDS {
        let mut case = c.clone();
        case.seed = c.seed + 2000 + k;
        let data = case.data().unwrap();
        let r = fit(
            &case.start_device().unwrap(),
            &data,
            &case.free,
            &FitSettings::default(),
        )
        .unwrap_or_else(|e| panic!("seed {}: {e}", case.seed));
        let p = r.chi2_p.unwrap_or(0.0);
        let origin = &r.starts[r.best_start].origin;
        rescued += usize::from(matches!(origin, StartOrigin::Untouched { .. }));
        let covered: Vec<bool> = r
            .params
            .iter()
            .zip(&case.truth)
            .map(|(q, &t)| q.interval.0 <= t && t <= q.interval.1)
            .collect();
        eprintln!(
            "seed {}: chi2/dof {:.3}, P(larger) {p:.3}, covered {covered:?}, from {origin}",
            case.seed, r.reduced_chi2
        );
        assert!(
            p >= ALPHA,
            "seed {}: P(larger chi-square) {p:.2e}",
            case.seed
        );
    }
    assert!(
        rescued > 0,
        "no realisation needed the rule: nothing tested"
    );
}
