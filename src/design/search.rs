//! The search over the unit cube of a design's ranges: a global sample, then a local polish.
//!
//! 1. `samples` points of an Owen-scrambled Sobol sequence (deterministic, spread over the
//!    cube), evaluated in parallel.
//! 2. From the `polish_starts` best of them (by [`score`]), argmin's Nelder-Mead on the score,
//!    the simplex's edge `simplex_size`, at most `max_iters` iterations each, the starts in
//!    parallel. The box is kept as in [`crate::num::minimax`]: the design is evaluated at the
//!    point clamped to the cube, and the distance outside is added to the score.
//!
//! The score ranks feasible designs by power and puts every infeasible one behind them, by its
//! violation: `-P / P_ref` when feasible (`P_ref` the largest power of the sample, so the
//! score is of order one), `1 + violation` otherwise, infinite where the design could not be
//! evaluated. Every design evaluated is returned, in the order of evaluation (the sample's in
//! sample order, then each polish's); the caller picks its answer from them
//! ([`super::answer`]).
//!
//! Why this optimiser: the objective is a steady state found by shooting (tens of
//! milliseconds to seconds a design), its ranges few (one to four), and it is not smooth
//! where the orbit starts to touch a stop or jumps between branches; a space-filling sample
//! finds the basin, and Nelder-Mead, which needs no gradient, polishes it in a few dozen
//! evaluations. The checks of `tests/design.rs` print the sample's best beside the polished
//! answer and a brute-force grid's best; the example `design_optimisers` measures the search
//! against CMA-ES on the same problems (the evaluations to within 1 % of the grid's best).

use std::sync::Mutex;

use argmin::core::{CostFunction, Error as ArgminError, Executor};
use argmin::solver::neldermead::NelderMead;
use rayon::prelude::*;

use super::{DesignError, Evaluated};

/// How the search runs.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct SearchSettings {
    /// Points of the global sample.
    pub samples: usize,
    /// Nelder-Mead polishes, from the best points of the sample.
    pub polish_starts: usize,
    /// Iteration cap of each polish.
    pub max_iters: u64,
    /// Edge of the initial simplex, in unit-cube coordinates.
    pub simplex_size: f64,
    /// Stop a polish when the standard deviation of its simplex's scores is below this.
    pub sd_tolerance: f64,
    /// Scramble of the sample.
    pub seed: u32,
}

impl Default for SearchSettings {
    fn default() -> Self {
        Self {
            samples: 32,
            polish_starts: 2,
            max_iters: 40,
            simplex_size: 0.1,
            sd_tolerance: 1e-4,
            seed: 0,
        }
    }
}

impl SearchSettings {
    /// The most designs a search of `interfaces` interfaces over `dims` ranges evaluates: per
    /// interface the sample, then per polish its simplex's `dims + 1` vertices and at most
    /// `dims + 2` designs an iteration (a reflection, an expansion or contraction, and a shrink
    /// of the `dims` other vertices).
    pub fn budget(&self, interfaces: usize, dims: usize) -> usize {
        let polish = dims + 1 + self.max_iters as usize * (dims + 2);
        interfaces * (self.samples + self.polish_starts * polish)
    }

    fn check(&self, dims: usize) -> Result<(), DesignError> {
        let bad = |m: String| Err(DesignError::Search(m));
        if dims == 0 || dims > 64 {
            return bad(format!("need 1..=64 ranges, got {dims}"));
        }
        if self.samples == 0 || self.samples > 1 << 16 {
            return bad(format!("samples = {} must be in 1..=65536", self.samples));
        }
        if self.polish_starts > self.samples {
            return bad(format!(
                "polish_starts = {} exceeds the samples ({})",
                self.polish_starts, self.samples
            ));
        }
        if !(self.simplex_size > 0.0 && self.simplex_size <= 0.5) {
            return bad(format!(
                "simplex_size = {} must be in (0, 0.5]",
                self.simplex_size
            ));
        }
        if self.sd_tolerance.is_nan() || self.sd_tolerance < 0.0 {
            return bad(format!("sd_tolerance = {} must be >= 0", self.sd_tolerance));
        }
        Ok(())
    }
}

/// The score of a design (see the module docs); `p_ref` > 0.
pub fn score(e: &Evaluated, p_ref: f64) -> f64 {
    match &e.result {
        Err(_) => f64::INFINITY,
        Ok(p) if e.violation == 0.0 => -p.power_w / p_ref,
        Ok(_) => 1.0 + e.violation,
    }
}

/// The scale of the powers of a sample: the largest feasible power, else the largest power,
/// floored at the smallest positive normal number.
fn reference_power(evals: &[Evaluated]) -> f64 {
    let best = |feasible_only: bool| {
        evals
            .iter()
            .filter(|e| !feasible_only || e.feasible())
            .map(Evaluated::power_w)
            .filter(|p| p.is_finite())
            .fold(0.0, f64::max)
    };
    let p = best(true);
    (if p > 0.0 { p } else { best(false) }).max(f64::MIN_POSITIVE)
}

/// The scrambled Sobol sample of `n` points of the `dims`-cube.
pub fn sobol_sample(dims: usize, n: usize, seed: u32) -> Vec<Vec<f64>> {
    (0..n)
        .map(|i| {
            (0..dims)
                .map(|d| f64::from(sobol_burley::sample(i as u32, d as u32, seed)))
                .collect()
        })
        .collect()
}

struct Polish<'a, F> {
    eval: &'a F,
    p_ref: f64,
    seen: &'a Mutex<Vec<Evaluated>>,
}

impl<F: Fn(&[f64]) -> Evaluated> CostFunction for Polish<'_, F> {
    type Param = Vec<f64>;
    type Output = f64;

    fn cost(&self, p: &Vec<f64>) -> Result<f64, ArgminError> {
        let clamped: Vec<f64> = p.iter().map(|u| u.clamp(0.0, 1.0)).collect();
        let outside: f64 = p.iter().zip(&clamped).map(|(u, c)| (u - c).abs()).sum();
        let e = (self.eval)(&clamped);
        let s = score(&e, self.p_ref) + outside;
        self.seen
            .lock()
            .map_err(|_| ArgminError::msg("a polish panicked"))?
            .push(e);
        Ok(s)
    }
}

/// The simplex of a polish from `x0`: `x0` and one vertex per axis, `size` along it, towards
/// the cube's inside.
fn simplex(x0: &[f64], size: f64) -> Vec<Vec<f64>> {
    let mut v = vec![x0.to_vec()];
    for d in 0..x0.len() {
        let mut p = x0.to_vec();
        p[d] += if p[d] + size <= 1.0 { size } else { -size };
        v.push(p);
    }
    v
}

/// Searches the `dims`-cube with `eval` (see the module docs); returns every evaluation.
pub fn search<F>(
    dims: usize,
    eval: F,
    settings: &SearchSettings,
) -> Result<Vec<Evaluated>, DesignError>
where
    F: Fn(&[f64]) -> Evaluated + Sync,
{
    settings.check(dims)?;
    let mut evals: Vec<Evaluated> = sobol_sample(dims, settings.samples, settings.seed)
        .par_iter()
        .map(|u| eval(u))
        .collect();
    let p_ref = reference_power(&evals);
    let mut order: Vec<usize> = (0..evals.len()).collect();
    order.sort_by(|&a, &b| {
        score(&evals[a], p_ref)
            .total_cmp(&score(&evals[b], p_ref))
            .then(a.cmp(&b))
    });
    let starts: Vec<Vec<f64>> = order
        .iter()
        .filter(|&&k| evals[k].result.is_ok())
        .take(settings.polish_starts)
        .map(|&k| evals[k].unit.clone())
        .collect();
    let polished = starts
        .into_par_iter()
        .map(|x0| {
            let seen = Mutex::new(Vec::new());
            let problem = Polish {
                eval: &eval,
                p_ref,
                seen: &seen,
            };
            let solver = NelderMead::new(simplex(&x0, settings.simplex_size))
                .with_sd_tolerance(settings.sd_tolerance)
                .map_err(|e| DesignError::Search(e.to_string()))?;
            Executor::new(problem, solver)
                .configure(|s| s.max_iters(settings.max_iters))
                .run()
                .map_err(|e| DesignError::Search(e.to_string()))?;
            seen.into_inner()
                .map_err(|_| DesignError::Search("a polish panicked".into()))
        })
        .collect::<Result<Vec<_>, _>>()?;
    for p in polished {
        evals.extend(p);
    }
    Ok(evals)
}
