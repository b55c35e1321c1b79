//! The emulator of one output at one wave: a Gaussian process of its expected value with
//! each run's sampling variance as its nugget, a model of that sampling variance over the
//! inputs, and the implausibility of a prediction against the observation.

use super::Observation;
use crate::num::gp::{Gp, GpError, GpSettings, Loo};

/// Variance of the logarithm of a sampling variance estimated from about 30 records (the
/// nugget of the emulator of `ln Var_ensemble`): `Var[ln s^2] ~ 2 / (n - 1)` for a chi-square
/// estimate, 0.07 at 30, rounded up to 0.1 because the jackknife's is larger.
pub const LOG_VARIANCE_NUGGET: f64 = 0.1;

/// The emulator of one output's expected value, or the value where it is constant over the
/// runs.
#[derive(Debug, Clone)]
pub enum Mean {
    /// A Gaussian process.
    Gp(Box<Gp>),
    /// The same value at every run (no variance to emulate).
    Constant(f64),
}

/// The model of one output's sampling variance over the inputs.
#[derive(Debug, Clone)]
pub enum SamplingVariance {
    /// A deterministic output.
    None,
    /// The median of the runs' variances (too few runs with a variance to emulate it).
    Constant(f64),
    /// A Gaussian process of its logarithm (stochastic kriging, Ankenman et al. 2010).
    LogGp(Box<Gp>),
}

/// One output's emulator at one wave.
#[derive(Debug, Clone)]
pub struct Emulator {
    /// Its expected value.
    pub mean: Mean,
    /// Its sampling variance.
    pub sampling: SamplingVariance,
}

/// A prediction of one output.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Prediction {
    /// Expected value.
    pub mean: f64,
    /// The emulator's variance of it (the process's, the mean's and the fitted nugget).
    pub emulator_var: f64,
    /// The simulator's sampling variance there.
    pub sampling_var: f64,
}

impl Emulator {
    /// Fits the emulator of one output to its runs (inputs, values, sampling variances).
    pub fn fit(x: &[Vec<f64>], y: &[f64], var: &[f64], gp: GpSettings) -> Result<Self, GpError> {
        let mean = if y.iter().all(|v| *v == y[0]) {
            Mean::Constant(y[0])
        } else {
            Mean::Gp(Box::new(Gp::fit(x, y, var, gp)?))
        };
        let with_var: Vec<usize> = (0..y.len()).filter(|&i| var[i] > 0.0).collect();
        let sampling = if with_var.is_empty() {
            SamplingVariance::None
        } else if with_var.len() < x[0].len() + 3 {
            let mut v: Vec<f64> = with_var.iter().map(|&i| var[i]).collect();
            v.sort_by(f64::total_cmp);
            SamplingVariance::Constant(v[v.len() / 2])
        } else {
            let xs: Vec<Vec<f64>> = with_var.iter().map(|&i| x[i].clone()).collect();
            let ln: Vec<f64> = with_var.iter().map(|&i| var[i].ln()).collect();
            let nugget = vec![LOG_VARIANCE_NUGGET; ln.len()];
            SamplingVariance::LogGp(Box::new(Gp::fit(&xs, &ln, &nugget, gp)?))
        };
        Ok(Self { mean, sampling })
    }

    /// The prediction at `x`.
    pub fn predict(&self, x: &[f64]) -> Prediction {
        // The emulator's variance holds its fitted nugget: what the smooth process does not
        // follow (a step where a fold appears) is as unknown at a new input as at a run.
        let (mean, emulator_var) = match &self.mean {
            Mean::Gp(g) => {
                let (m, v) = g.predict(x);
                (m, v + g.nugget_var())
            }
            Mean::Constant(c) => (*c, 0.0),
        };
        let sampling_var = match &self.sampling {
            SamplingVariance::None => 0.0,
            SamplingVariance::Constant(v) => *v,
            SamplingVariance::LogGp(g) => g.mean(x).exp(),
        };
        Prediction {
            mean,
            emulator_var,
            sampling_var,
        }
    }

    /// The leave-one-out predictions of the expected value (empty for a constant).
    pub fn loo(&self) -> &[Loo] {
        match &self.mean {
            Mean::Gp(g) => g.loo(),
            Mean::Constant(_) => &[],
        }
    }
}

/// The implausibility of a prediction against an observation.
pub fn implausibility(p: &Prediction, obs: &Observation) -> f64 {
    (obs.value - p.mean).abs() / (p.emulator_var + p.sampling_var + obs.variance).sqrt()
}

/// The `rank`-th largest of `values` (1: the largest); 0 when there are fewer.
pub fn ranked(values: &[f64], rank: usize) -> f64 {
    let mut v = values.to_vec();
    v.sort_by(|a, b| b.total_cmp(a));
    v.get(rank.saturating_sub(1)).copied().unwrap_or(0.0)
}

/// One wave's emulators.
#[derive(Debug, Clone)]
pub struct Wave {
    /// One per output.
    pub emulators: Vec<Emulator>,
    /// Indices (into all runs) of the runs the emulators were fitted to.
    pub training: Vec<usize>,
}

impl Wave {
    /// The implausibility of every output at `x`, the input as the emulators see it
    /// ([`HistoryMatch::emulator_input`](super::HistoryMatch::emulator_input)).
    pub fn implausibilities(&self, obs: &[Observation], x: &[f64]) -> Vec<f64> {
        self.emulators
            .iter()
            .zip(obs)
            .map(|(e, o)| implausibility(&e.predict(x), o))
            .collect()
    }
}
