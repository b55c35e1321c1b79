//! Variance-based global sensitivity: Sobol first-order and total indices from a Saltelli design
//! on an Owen-scrambled Sobol sequence, with percentile-bootstrap confidence intervals.
//!
//! The design (Saltelli 2002, 2010) draws two independent `N x d` matrices `A` and `B` on the
//! unit cube (the first and the last `d` coordinates of one `2d`-dimensional scrambled Sobol
//! sequence, from the `sobol_burley` crate) and, for each input `i`, the matrix `AB_i`: `A` with
//! its column `i` taken from `B`. The model is evaluated on `A`, `B` and every `AB_i`, `N (d + 2)`
//! runs in all, in the order of [`Saltelli::point`]. With `V` the variance of the outputs on `A`
//! and `B` together, the estimators are
//!
//! - first order (Saltelli et al. 2010): `S_i = mean(f(B) (f(AB_i) - f(A))) / V`,
//! - total (Jansen 1999): `ST_i = mean((f(A) - f(AB_i))^2) / (2 V)`.
//!
//! Written here rather than taken from a crate: the estimators are a few sums, tested on the
//! Ishigami function against its analytic indices, while the one Rust crate that estimates
//! Sobol indices (`salib`) is a family of sub-crates with one maintainer and a short record. The sequence itself comes from `sobol_burley`.
//! Confidence intervals resample the `N` rows (each row carries `f(A)`, `f(B)` and every
//! `f(AB_i)` together) with a seeded ChaCha8 stream, so they are the same on every machine.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::stats::quantile;

/// Why a design or an estimate could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SensitivityError {
    /// The base sample size is not a power of two in `2..=2^15` (the scrambled sequence keeps
    /// its balance only on powers of two and holds `2^16` points).
    #[error("base sample size {0} must be a power of two between 2 and 32768")]
    BaseSize(usize),
    /// The number of inputs is not in `1..=128` (the sequence has 256 dimensions, the design
    /// uses two per input).
    #[error("number of inputs {0} must be between 1 and 128")]
    Inputs(usize),
    /// The outputs do not match the design's `N (d + 2)` points.
    #[error("{got} outputs given for a design of {expected} points")]
    Outputs {
        /// Points in the design.
        expected: usize,
        /// Outputs given.
        got: usize,
    },
    /// An output is NaN or infinite.
    #[error("output {index} (design point {index}) is not finite: {value}")]
    NotFinite {
        /// Index of the design point.
        index: usize,
        /// The value.
        value: f64,
    },
    /// The outputs on `A` and `B` have no variance: every index is 0/0.
    #[error("the outputs have zero variance; the indices are undefined")]
    NoVariance,
}

/// A Saltelli design of `N` base samples over `d` inputs on the unit cube.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Saltelli {
    base: usize,
    inputs: usize,
    seed: u32,
}

/// A sensitivity index with its bootstrap confidence interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Index {
    /// The estimate from all `N` rows.
    pub value: f64,
    /// Lower end of the percentile-bootstrap interval.
    pub lo: f64,
    /// Upper end of the percentile-bootstrap interval.
    pub hi: f64,
}

/// First-order and total indices of every input, in input order.
#[derive(Debug, Clone, PartialEq)]
pub struct Indices {
    /// First-order index `S_i` of each input.
    pub first: Vec<Index>,
    /// Total index `ST_i` of each input.
    pub total: Vec<Index>,
    /// Variance of the outputs on `A` and `B`.
    pub variance: f64,
}

/// How the confidence intervals are drawn.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bootstrap {
    /// Number of resamples.
    pub resamples: usize,
    /// Coverage of the interval, e.g. 0.95.
    pub level: f64,
    /// Seed of the resampling stream.
    pub seed: u64,
}

impl Default for Bootstrap {
    fn default() -> Self {
        Self {
            resamples: 1000,
            level: 0.95,
            seed: 0,
        }
    }
}

impl Saltelli {
    /// A design of `base` rows (a power of two) over `inputs` inputs; `seed` selects the Owen
    /// scramble.
    pub fn new(base: usize, inputs: usize, seed: u32) -> Result<Self, SensitivityError> {
        if !(2..=1 << 15).contains(&base) || !base.is_power_of_two() {
            return Err(SensitivityError::BaseSize(base));
        }
        if !(1..=128).contains(&inputs) {
            return Err(SensitivityError::Inputs(inputs));
        }
        Ok(Self { base, inputs, seed })
    }

    /// Number of base rows `N`.
    pub fn base(&self) -> usize {
        self.base
    }

    /// Number of inputs `d`.
    pub fn inputs(&self) -> usize {
        self.inputs
    }

    /// Number of model runs, `N (d + 2)`.
    pub fn len(&self) -> usize {
        self.base * (self.inputs + 2)
    }

    /// Always false: a design has at least two rows.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Design point `k` (`0 <= k < len()`) on the unit cube, written into `out` (length `d`):
    /// rows `0..N` are `A`, `N..2N` are `B`, then `AB_1`, ..., `AB_d`.
    ///
    /// # Panics
    /// If `k >= len()` or `out.len() != inputs()` (a caller's indexing error).
    pub fn point(&self, k: usize, out: &mut [f64]) {
        assert!(k < self.len() && out.len() == self.inputs);
        let (block, row) = (k / self.base, k % self.base);
        for (i, o) in out.iter_mut().enumerate() {
            let from_b = block == 1 || (block >= 2 && block - 2 == i);
            let dim = if from_b { self.inputs + i } else { i };
            *o = self.coordinate(row, dim);
        }
    }

    /// Every design point, in run order.
    pub fn points(&self) -> Vec<Vec<f64>> {
        (0..self.len())
            .map(|k| {
                let mut p = vec![0.0; self.inputs];
                self.point(k, &mut p);
                p
            })
            .collect()
    }

    fn coordinate(&self, row: usize, dim: usize) -> f64 {
        // Both are below the crate's limits (2^16 points, 256 dimensions) by `new`.
        f64::from(sobol_burley::sample(row as u32, dim as u32, self.seed))
    }

    /// Sobol indices from the outputs at the design points (in [`Saltelli::point`] order).
    pub fn indices(&self, outputs: &[f64], boot: Bootstrap) -> Result<Indices, SensitivityError> {
        if outputs.len() != self.len() {
            return Err(SensitivityError::Outputs {
                expected: self.len(),
                got: outputs.len(),
            });
        }
        if let Some((index, &value)) = outputs.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(SensitivityError::NotFinite { index, value });
        }
        let n = self.base;
        let all: Vec<usize> = (0..n).collect();
        let point = |rows: &[usize]| self.estimate(outputs, rows);
        let (first, total, variance) = point(&all).ok_or(SensitivityError::NoVariance)?;

        let mut rng = ChaCha8Rng::seed_from_u64(boot.seed);
        let mut rows = vec![0; n];
        let d = self.inputs;
        let mut first_draws = vec![Vec::with_capacity(boot.resamples); d];
        let mut total_draws = vec![Vec::with_capacity(boot.resamples); d];
        for _ in 0..boot.resamples {
            rows.iter_mut().for_each(|r| *r = rng.random_range(0..n));
            // A resample with no variance (all rows equal) carries no information: skip it.
            if let Some((f, t, _)) = point(&rows) {
                for i in 0..d {
                    first_draws[i].push(f[i]);
                    total_draws[i].push(t[i]);
                }
            }
        }
        let tail = (1.0 - boot.level) / 2.0;
        let interval = |value: f64, draws: &mut Vec<f64>| {
            draws.sort_by(f64::total_cmp);
            Index {
                value,
                lo: quantile(draws, tail),
                hi: quantile(draws, 1.0 - tail),
            }
        };
        Ok(Indices {
            first: (0..d)
                .map(|i| interval(first[i], &mut first_draws[i]))
                .collect(),
            total: (0..d)
                .map(|i| interval(total[i], &mut total_draws[i]))
                .collect(),
            variance,
        })
    }

    /// Indices over the given rows (with repetition); `None` when the variance is zero.
    fn estimate(&self, y: &[f64], rows: &[usize]) -> Option<(Vec<f64>, Vec<f64>, f64)> {
        let n = self.base;
        let m = rows.len() as f64;
        let (fa, fb) = (&y[..n], &y[n..2 * n]);
        // Equal outputs have no variance, although rounding in the mean can leave a few ulps.
        let y0 = fa[rows[0]];
        if rows.iter().all(|&r| fa[r] == y0 && fb[r] == y0) {
            return None;
        }
        let mean = rows.iter().map(|&r| fa[r] + fb[r]).sum::<f64>() / (2.0 * m);
        let variance = rows
            .iter()
            .map(|&r| (fa[r] - mean).powi(2) + (fb[r] - mean).powi(2))
            .sum::<f64>()
            / (2.0 * m - 1.0);
        if variance <= 0.0 {
            return None;
        }
        let mut first = Vec::with_capacity(self.inputs);
        let mut total = Vec::with_capacity(self.inputs);
        for i in 0..self.inputs {
            let fab = &y[(2 + i) * n..(3 + i) * n];
            let (mut s, mut t) = (0.0, 0.0);
            for &r in rows {
                s += fb[r] * (fab[r] - fa[r]);
                t += (fa[r] - fab[r]).powi(2);
            }
            first.push(s / m / variance);
            total.push(t / (2.0 * m) / variance);
        }
        Some((first, total, variance))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// The Ishigami function with a = 7, b = 0.1 on [-pi, pi]^3, from unit-cube coordinates.
    fn ishigami(u: &[f64]) -> f64 {
        let x: Vec<f64> = u.iter().map(|u| -PI + 2.0 * PI * u).collect();
        x[0].sin() + 7.0 * x[1].sin().powi(2) + 0.1 * x[2].powi(4) * x[0].sin()
    }

    /// Analytic first-order and total indices of the Ishigami function (a = 7, b = 0.1):
    /// V1 = (1 + b pi^4 / 5)^2 / 2, V2 = a^2 / 8, V3 = 0, V13 = 8 b^2 pi^8 / 225.
    fn ishigami_exact() -> ([f64; 3], [f64; 3]) {
        let (a, b) = (7.0_f64, 0.1_f64);
        let v1 = 0.5 * (1.0 + b * PI.powi(4) / 5.0).powi(2);
        let v2 = a * a / 8.0;
        let v13 = 8.0 * b * b * PI.powi(8) / 225.0;
        let v = v1 + v2 + v13;
        ([v1 / v, v2 / v, 0.0], [(v1 + v13) / v, v2 / v, v13 / v])
    }

    fn run(design: &Saltelli) -> Vec<f64> {
        design.points().iter().map(|p| ishigami(p)).collect()
    }

    #[test]
    fn ishigami_indices_are_within_two_hundredths_of_the_analytic_ones() {
        // 2^13 base rows (40960 runs): the estimators' sampling error on Ishigami at this size
        // is a few thousandths, so 0.02 is a test of the estimators, not of luck.
        let design = Saltelli::new(1 << 13, 3, 7).unwrap();
        let got = design.indices(&run(&design), Bootstrap::default()).unwrap();
        let (s, st) = ishigami_exact();
        for i in 0..3 {
            assert!(
                (got.first[i].value - s[i]).abs() < 0.02,
                "S{} = {} vs {}",
                i + 1,
                got.first[i].value,
                s[i]
            );
            assert!(
                (got.total[i].value - st[i]).abs() < 0.02,
                "ST{} = {} vs {}",
                i + 1,
                got.total[i].value,
                st[i]
            );
        }
    }

    #[test]
    fn bootstrap_intervals_hold_their_estimate_and_shrink_with_more_rows() {
        let width = |base| {
            let design = Saltelli::new(base, 3, 7).unwrap();
            let got = design.indices(&run(&design), Bootstrap::default()).unwrap();
            for ix in got.first.iter().chain(&got.total) {
                assert!(ix.lo <= ix.value && ix.value <= ix.hi, "{ix:?}");
            }
            got.total[0].hi - got.total[0].lo
        };
        // The interval of a mean shrinks as 1/sqrt(N): 16x the rows, about a quarter the width;
        // asserting only "narrower than half" leaves room for the resampling noise.
        assert!(width(1 << 12) < 0.5 * width(1 << 8));
    }

    #[test]
    fn design_columns_swap_one_input_at_a_time() {
        let design = Saltelli::new(8, 3, 1).unwrap();
        let p = design.points();
        let n = design.base();
        for r in 0..n {
            let (a, b) = (&p[r], &p[n + r]);
            for i in 0..3 {
                let ab = &p[(2 + i) * n + r];
                for j in 0..3 {
                    assert_eq!(ab[j], if j == i { b[j] } else { a[j] });
                }
            }
            assert!(a.iter().chain(b).all(|u| (0.0..1.0).contains(u)));
        }
    }

    #[test]
    fn same_seed_same_indices_to_the_bit() {
        let design = Saltelli::new(1 << 8, 3, 3).unwrap();
        let y = run(&design);
        let one = design.indices(&y, Bootstrap::default()).unwrap();
        let two = design.indices(&y, Bootstrap::default()).unwrap();
        assert_eq!(format!("{one:?}"), format!("{two:?}"));
    }

    #[test]
    fn bad_designs_and_outputs_are_named_errors() {
        assert_eq!(
            Saltelli::new(100, 3, 0),
            Err(SensitivityError::BaseSize(100))
        );
        assert_eq!(
            Saltelli::new(1 << 16, 3, 0),
            Err(SensitivityError::BaseSize(1 << 16))
        );
        assert_eq!(Saltelli::new(8, 0, 0), Err(SensitivityError::Inputs(0)));
        assert_eq!(Saltelli::new(8, 129, 0), Err(SensitivityError::Inputs(129)));
        let design = Saltelli::new(8, 2, 0).unwrap();
        assert_eq!(
            design.indices(&[1.0; 3], Bootstrap::default()),
            Err(SensitivityError::Outputs {
                expected: 32,
                got: 3
            })
        );
        let mut y = vec![1.0; 32];
        assert_eq!(
            design.indices(&y, Bootstrap::default()),
            Err(SensitivityError::NoVariance)
        );
        // A constant whose mean rounds (0.1 summed 16 times is not 1.6): still no variance.
        assert_eq!(
            design.indices(&vec![0.1; 32], Bootstrap::default()),
            Err(SensitivityError::NoVariance)
        );
        y[5] = f64::NAN;
        assert!(matches!(
            design.indices(&y, Bootstrap::default()),
            Err(SensitivityError::NotFinite { index: 5, .. })
        ));
    }
}
