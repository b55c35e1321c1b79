//! Sample statistics: the mean with a Student-t confidence interval ([`MeanCi`]), the sampling
//! distribution of an estimate ([`Spread`]), the delete-one jackknife ([`Jackknife`]), the
//! ratios of two samples taken pairwise ([`pairwise_ratios`], [`ratio_spread`],
//! [`pair_fraction`]) and the empirical distribution function ([`ecdf`]).

use statrs::distribution::{ContinuousCDF, StudentsT};

/// Mean of a sample with a 95 % confidence interval (Student's t, `n - 1` degrees of freedom).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MeanCi {
    /// Sample mean.
    pub mean: f64,
    /// Sample standard deviation (n - 1 in the denominator); NaN for n < 2.
    pub std: f64,
    /// Half-width of the 95 % confidence interval of the mean, `t_{0.975, n-1} std / sqrt(n)`;
    /// NaN for n < 2.
    pub ci95: f64,
    /// Sample size.
    pub n: usize,
}

impl MeanCi {
    /// Statistics of the finite values of `xs`.
    pub fn of(xs: &[f64]) -> Self {
        let v: Vec<f64> = xs.iter().copied().filter(|x| x.is_finite()).collect();
        let n = v.len();
        if n == 0 {
            return Self {
                mean: f64::NAN,
                std: f64::NAN,
                ci95: f64::NAN,
                n,
            };
        }
        let mean = v.iter().sum::<f64>() / n as f64;
        if n < 2 {
            return Self {
                mean,
                std: f64::NAN,
                ci95: f64::NAN,
                n,
            };
        }
        let var = v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1) as f64;
        let std = var.sqrt();
        Self {
            mean,
            std,
            ci95: student_t_975(n - 1) * std / (n as f64).sqrt(),
            n,
        }
    }
}

/// The 97.5 % quantile of Student's t with `dof` degrees of freedom (two-sided 95 %), from
/// statrs's inverse CDF. NaN for `dof = 0`.
pub fn student_t_975(dof: usize) -> f64 {
    if dof == 0 {
        return f64::NAN;
    }
    StudentsT::new(0.0, 1.0, dof as f64).map_or(f64::NAN, |t| t.inverse_cdf(0.975))
}

/// Sampling distribution of a single-record estimate: mean, standard deviation and the 5 % and
/// 95 % empirical quantiles (linear interpolation between order statistics), over the finite
/// values; `undetermined` counts the records where the estimate did not exist.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spread {
    /// Mean of the finite values.
    pub mean: f64,
    /// Standard deviation (n - 1).
    pub std: f64,
    /// 5 % quantile.
    pub p05: f64,
    /// 95 % quantile.
    pub p95: f64,
    /// Median.
    pub median: f64,
    /// Number of finite values.
    pub n: usize,
    /// Number of non-finite values (e.g. an undetermined band edge).
    pub undetermined: usize,
}

impl Spread {
    /// The distribution of `xs`.
    pub fn of(xs: &[f64]) -> Self {
        let mut v: Vec<f64> = xs.iter().copied().filter(|x| x.is_finite()).collect();
        v.sort_by(|a, b| a.total_cmp(b));
        let m = MeanCi::of(&v);
        Self {
            mean: m.mean,
            std: m.std,
            p05: quantile(&v, 0.05),
            p95: quantile(&v, 0.95),
            median: quantile(&v, 0.5),
            n: v.len(),
            undetermined: xs.len() - v.len(),
        }
    }
}

/// Quantile of sorted data by linear interpolation between order statistics (the default of
/// numpy.quantile); NaN for empty data.
pub fn quantile(sorted: &[f64], q: f64) -> f64 {
    match sorted.len() {
        0 => f64::NAN,
        1 => sorted[0],
        n => {
            let pos = q * (n - 1) as f64;
            let i = pos.floor() as usize;
            let j = (i + 1).min(n - 1);
            sorted[i] + (pos - i as f64) * (sorted[j] - sorted[i])
        }
    }
}

/// A delete-one jackknife estimate: the statistic of the whole sample with the standard error
/// `se = sqrt((n-1)/n sum (t_(i) - mean t_(.))^2)` over the statistics `t_(i)` of the sample
/// without item `i`, and `ci95 = t_{0.975, n-1} se`. A NaN `se` means a delete-one statistic
/// was undetermined (or n < 2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Jackknife {
    /// The statistic of the whole sample.
    pub estimate: f64,
    /// Jackknife standard error.
    pub se: f64,
    /// Half-width of the 95 % confidence interval.
    pub ci95: f64,
    /// Sample size.
    pub n: usize,
}

impl Jackknife {
    /// The jackknife of a statistic over `n` items: `estimate` is its value on the whole
    /// sample, `without(i)` its value without item `i`.
    pub fn of(n: usize, estimate: f64, mut without: impl FnMut(usize) -> f64) -> Self {
        if n < 2 {
            return Self {
                estimate,
                se: f64::NAN,
                ci95: f64::NAN,
                n,
            };
        }
        let loo: Vec<f64> = (0..n).map(&mut without).collect();
        let mean = loo.iter().sum::<f64>() / n as f64;
        let ss: f64 = loo.iter().map(|w| (w - mean).powi(2)).sum();
        let se = ((n - 1) as f64 / n as f64 * ss).sqrt();
        Self {
            estimate,
            se,
            ci95: student_t_975(n - 1) * se,
            n,
        }
    }

    /// The ratio `self / other` of two estimates from independent samples, with the 95 %
    /// half-width propagated in relative terms: `ci(r)/r = sqrt((ci_a/a)^2 + (ci_b/b)^2)`.
    pub fn ratio(&self, other: &Jackknife) -> (f64, f64) {
        let r = self.estimate / other.estimate;
        let rel =
            ((self.ci95 / self.estimate).powi(2) + (other.ci95 / other.estimate).powi(2)).sqrt();
        (r, r * rel)
    }
}

/// Sampling distribution of the ratio `w_a / w_b` of two single-record widths, one record from
/// each ensemble, over **all** pairs `(i, j)` (the records are independent, so every pair is a
/// draw of what one record per level, as in the paper, would give). Non-finite widths are
/// counted as undetermined.
pub fn ratio_spread(w_a: &[f64], w_b: &[f64]) -> Spread {
    Spread::of(&pairwise_ratios(w_a, w_b))
}

/// Every ratio `a / b` with `a` from `w_a` and `b` from `w_b` (row-major in `w_a`).
pub fn pairwise_ratios(w_a: &[f64], w_b: &[f64]) -> Vec<f64> {
    w_a.iter()
        .flat_map(|a| w_b.iter().map(move |b| a / b))
        .collect()
}

/// Fraction of the finite pairwise ratios `a / b` ([`pairwise_ratios`]) that satisfy `pred`;
/// 0 when no ratio is finite.
pub fn pair_fraction(w_a: &[f64], w_b: &[f64], pred: impl Fn(f64) -> bool) -> f64 {
    let finite: Vec<f64> = pairwise_ratios(w_a, w_b)
        .into_iter()
        .filter(|r| r.is_finite())
        .collect();
    let hits = finite.iter().filter(|&&r| pred(r)).count();
    hits as f64 / finite.len().max(1) as f64
}

/// Empirical distribution function of the finite `values`: (sorted value, (rank + 1/2) / n).
pub fn ecdf(values: &[f64]) -> Vec<(f64, f64)> {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    v.sort_by(|a, b| a.total_cmp(b));
    let n = v.len() as f64;
    v.iter()
        .enumerate()
        .map(|(i, &x)| (x, (i as f64 + 0.5) / n))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn student_t_quantiles() {
        // Tabulated t_{0.975}: 1 dof 12.7062, 3 dof 3.1824, 30 dof 2.0423, 120 dof 1.9799.
        for (dof, t) in [(1, 12.7062), (3, 3.1824), (30, 2.0423), (120, 1.9799)] {
            assert!(
                (student_t_975(dof) - t).abs() < 1e-4,
                "{dof}: {}",
                student_t_975(dof)
            );
        }
        assert!(student_t_975(0).is_nan());
    }

    #[test]
    fn spread_quantiles() {
        let xs: Vec<f64> = (0..=100).map(|i| i as f64).chain([f64::NAN]).collect();
        let s = Spread::of(&xs);
        assert_eq!(s.n, 101);
        assert_eq!(s.undetermined, 1);
        assert!((s.p05 - 5.0).abs() < 1e-12 && (s.p95 - 95.0).abs() < 1e-12);
        assert!((s.median - 50.0).abs() < 1e-12);
    }

    #[test]
    fn mean_ci_of_known_sample() {
        let m = MeanCi::of(&[1.0, 2.0, 3.0, 4.0]);
        assert!((m.mean - 2.5).abs() < 1e-15);
        let std = (5.0f64 / 3.0).sqrt();
        assert!((m.std - std).abs() < 1e-15);
        assert!((m.ci95 - 3.182_446_305 * std / 2.0).abs() < 1e-8);
    }

    #[test]
    fn pairwise_ratios_fractions_and_ecdf() {
        let r = pairwise_ratios(&[2.0, 4.0], &[1.0, 2.0, 0.0]);
        assert_eq!(r[..2], [2.0, 1.0]);
        assert_eq!(r[3..5], [4.0, 2.0]);
        assert!(r[2].is_infinite() && r[5].is_infinite());
        // Four finite ratios 2, 1, 4, 2: three are at least 2.
        assert_eq!(
            pair_fraction(&[2.0, 4.0], &[1.0, 2.0, 0.0], |x| x >= 2.0),
            0.75
        );
        assert_eq!(pair_fraction(&[1.0], &[0.0], |_| true), 0.0);
        let e = ecdf(&[3.0, f64::NAN, 1.0]);
        assert_eq!(e, vec![(1.0, 0.25), (3.0, 0.75)]);
    }

    #[test]
    fn jackknife_of_the_mean_is_the_standard_error() {
        // For the sample mean the jackknife standard error equals std / sqrt(n) exactly.
        let x = [1.0, 4.0, 2.0, 8.0, 5.0];
        let n = x.len();
        let mean = x.iter().sum::<f64>() / n as f64;
        let j = Jackknife::of(n, mean, |i| (x.iter().sum::<f64>() - x[i]) / (n - 1) as f64);
        let m = MeanCi::of(&x);
        assert!((j.se - m.std / (n as f64).sqrt()).abs() < 1e-12);
        assert!((j.ci95 - m.ci95).abs() < 1e-12);
    }
}
