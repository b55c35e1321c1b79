//! The recovery family (`endstop::fit::family`): 22 synthetic sweeps of piezoelectric,
//! electromagnetic and electrostatic devices (up- and down-sweeps, jumps at folds and at a
//! rigid stop's grazing, 1 to 3 free parameters, noise from 0.5 to 5 %), each started up to
//! 50 % off inside its ranges, with seeds fixed in the family before any fit was run. Each
//! case is fitted with the default settings (the design, the best starts refined), and the
//! test asserts two things fixed before the first run:
//!
//! * **Coverage.** With exact 95 % intervals the number of intervals containing the truth is
//!   binomial(N, 0.95) over the family's N intervals; the test fails when the count is so low
//!   that a count at most as large has probability below 0.1 %. A fit that fails counts as
//!   missing every one of its intervals.
//! * **The chi-square law.** Each fit's chi-square (the standard deviations are stated) with
//!   n - p degrees of freedom has the probability of a larger one uniform on (0, 1) when the
//!   model and the noise are right; the test fails when the Kolmogorov-Smirnov distance of the
//!   family's probabilities from the uniform law exceeds its 0.1 % critical value (the
//!   asymptotic `sqrt(ln(2 / 0.001) / 2) / sqrt(n)`, a little conservative for 22 values).
//!   A fit that fails counts as probability 0.
//!
//! Each fit's time, the share recovered, the coverage and the probabilities are printed
//! (`--nocapture`); `bench --fits` times the fits. The run takes minutes, so the test is
//! ignored by `cargo test --release` and run by CI's `--include-ignored`.

use endstop::fit::family::recovery_family;
use endstop::fit::{fit, FitSettings};
use statrs::distribution::{Binomial, DiscreteCDF};

/// Level of both tests: a family whose fits are right fails either one with probability 0.1 %.
const ALPHA: f64 = 1e-3;

/// The Kolmogorov-Smirnov distance of `p` from the uniform law on (0, 1).
fn ks_uniform(p: &[f64]) -> f64 {
    let mut s = p.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len() as f64;
    s.iter()
        .enumerate()
        .map(|(i, &x)| f64::max((i + 1) as f64 / n - x, x - i as f64 / n))
        .fold(0.0, f64::max)
}

#[test]
#[ignore = "the recovery family: minutes; CI runs it with --include-ignored"]
fn the_recovery_family_covers_the_truth_and_follows_the_chi_square_law() {
    let family = recovery_family();
    assert!(family.len() >= 20);
    let (mut intervals, mut covering, mut recovered) = (0, 0, 0);
    let mut probabilities = Vec::new();
    for c in &family {
        intervals += c.free.len();
        let t = std::time::Instant::now();
        let outcome = c.data().and_then(|data| {
            let start = c.start_device()?;
            fit(&start, &data, &c.free, &FitSettings::default())
        });
        let secs = t.elapsed().as_secs_f64();
        let r = match outcome {
            Ok(r) => r,
            Err(e) => {
                eprintln!("{}: FAILED after {secs:.1} s: {e}", c.name);
                probabilities.push(0.0);
                continue;
            }
        };
        let cov: Vec<bool> = r
            .params
            .iter()
            .zip(&c.truth)
            .map(|(p, &t)| p.interval.0 <= t && t <= p.interval.1)
            .collect();
        let n_cov = cov.iter().filter(|&&b| b).count();
        covering += n_cov;
        recovered += usize::from(n_cov == cov.len());
        let p = r.chi2_p.unwrap_or(f64::NAN);
        probabilities.push(if p.is_nan() { 0.0 } else { p });
        eprintln!(
            "{}: {secs:.1} s, chi2/dof {:.3} (dof {}, P(larger) {p:.3}), covered {cov:?}, \
             {} of {} starts refined, reported from {}, model {}{}",
            c.name,
            r.reduced_chi2,
            r.dof,
            r.starts_refined(),
            r.starts.len(),
            r.starts[r.best_start].origin,
            r.model,
            r.headline().map_or(String::new(), |h| format!(", {h}")),
        );
        for (p, t) in r.params.iter().zip(&c.truth) {
            eprintln!(
                "  {}: fitted {:e}, 95 % {:e} .. {:e}, truth {t:e}, start {:e}",
                p.path, p.value, p.interval.0, p.interval.1, p.start
            );
        }
        for w in &r.warnings {
            eprintln!("  warning: {w}");
        }
    }
    let binomial = Binomial::new(0.95, intervals as u64).unwrap();
    let p_low = binomial.cdf(covering as u64);
    let d = ks_uniform(&probabilities);
    let n = probabilities.len() as f64;
    let d_crit = ((2.0 / ALPHA).ln() / 2.0).sqrt() / n.sqrt();
    eprintln!(
        "recovered (every interval containing the truth): {recovered} of {} cases; {covering} \
         of {intervals} intervals contain the truth ({:.1} %, nominal 95 %; P(at most as many) \
         {p_low:.3}); chi-square probabilities {probabilities:.3?}, Kolmogorov-Smirnov \
         distance from uniform {d:.3} (0.1 % critical value {d_crit:.3})",
        family.len(),
        100.0 * covering as f64 / intervals as f64,
    );
    assert!(
        p_low >= ALPHA,
        "coverage {covering} of {intervals}: P(at most as many) {p_low:.2e}"
    );
    assert!(
        d <= d_crit,
        "chi-square law: KS distance {d:.3} > {d_crit:.3}"
    );
}
