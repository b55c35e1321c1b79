//! Levenberg-Marquardt for small, expensive least-squares problems in unbounded coordinates,
//! with a forward-difference Jacobian whose columns are evaluated in parallel.
//!
//! Written here because argmin (the crate's optimiser library) offers Gauss-Newton with and
//! without a line search but no Levenberg-Marquardt, and the fit needs the damping: far from
//! the optimum a stepped sweep's residuals change abruptly (a jump moves past a measured
//! point) and an undamped Gauss-Newton step overshoots. The method is Marquardt's (the damping
//! scales the diagonal of J^T J), with the damping divided by 10 after an accepted step and
//! multiplied by 10 after a rejected one (Nocedal and Wright, Numerical Optimization, 2nd ed.,
//! section 10.3). Each residual evaluation here is a whole sweep, so the solver counts them.

use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

/// Settings of [`levenberg_marquardt`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LmSettings {
    /// Forward-difference step in the unbounded coordinates.
    pub fd_step: f64,
    /// Largest number of Jacobians (outer iterations).
    pub max_iter: usize,
    /// Stop when an accepted step lowers the cost by less than this fraction.
    pub cost_rel_tol: f64,
    /// Stop when a step is shorter than this (unbounded coordinates, Euclidean norm).
    pub step_tol: f64,
    /// Initial damping.
    pub lambda0: f64,
    /// Give up on an iteration (and stop) when the damping exceeds this.
    pub lambda_max: f64,
    /// A stop without descent counts as converged ([`LmStop::Stalled`]) when the undamped
    /// Gauss-Newton step promises a relative decrease of the cost below this: the cost of a
    /// stepped sweep is smooth only down to its steady-state criterion.
    pub noise_rel_tol: f64,
    /// Absolute counterpart of `cost_rel_tol` and `noise_rel_tol` (0: none): a fit whose
    /// residuals are weighted by stated standard deviations converges when the weighted SSR
    /// changes by less than this, however small the SSR.
    pub cost_abs_tol: f64,
    /// Longest step (unbounded coordinates, Euclidean norm): a direction the data hardly
    /// constrain would otherwise be thrown to the edge of its range by a tiny gradient.
    pub max_step: f64,
}

/// The damping scales each diagonal element of J^T J, but at least this fraction of the
/// largest one, so that a parameter the residuals do not depend on is still damped.
const DIAG_FLOOR: f64 = 1e-6;

impl Default for LmSettings {
    fn default() -> Self {
        Self {
            fd_step: 1e-2,
            max_iter: 40,
            cost_rel_tol: 1e-6,
            step_tol: 1e-4,
            lambda0: 1e-2,
            lambda_max: 1e8,
            max_step: 2.0,
            noise_rel_tol: 1e-3,
            cost_abs_tol: 0.0,
        }
    }
}

/// Why the solver stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LmStop {
    /// The cost no longer fell by [`LmSettings::cost_rel_tol`].
    CostConverged,
    /// The step became shorter than [`LmSettings::step_tol`].
    StepConverged,
    /// No damping up to [`LmSettings::lambda_max`] lowered the cost, and the undamped
    /// Gauss-Newton step promised a relative decrease below [`LmSettings::noise_rel_tol`]:
    /// the optimum within the model's own numerical noise.
    Stalled,
    /// No damping up to [`LmSettings::lambda_max`] lowered the cost although the Gauss-Newton
    /// step promised more than [`LmSettings::noise_rel_tol`].
    NoDescent,
    /// [`LmSettings::max_iter`] Jacobians were computed.
    MaxIter,
}

impl LmStop {
    /// True when the stop is a convergence criterion.
    pub fn converged(self) -> bool {
        matches!(
            self,
            LmStop::CostConverged | LmStop::StepConverged | LmStop::Stalled
        )
    }
}

/// Result of [`levenberg_marquardt`].
#[derive(Debug, Clone, PartialEq)]
pub struct LmResult {
    /// The best point (unbounded coordinates).
    pub u: Vec<f64>,
    /// Residuals there.
    pub residuals: Vec<f64>,
    /// Jacobian of the residuals there (rows: residuals, columns: coordinates).
    pub jacobian: DMatrix<f64>,
    /// Outer iterations.
    pub iterations: usize,
    /// Residual evaluations, the Jacobians' included.
    pub evaluations: usize,
    /// Why it stopped.
    pub stop: LmStop,
}

fn cost(r: &[f64]) -> f64 {
    r.iter().map(|x| x * x).sum()
}

/// Forward-difference Jacobian at `u` (residuals `r0` there), columns in parallel.
pub fn jacobian<E: Send>(
    residuals: &(impl Fn(&[f64]) -> Result<Vec<f64>, E> + Sync),
    u: &[f64],
    r0: &[f64],
    h: f64,
) -> Result<DMatrix<f64>, E> {
    let cols: Vec<Vec<f64>> = (0..u.len())
        .into_par_iter()
        .map(|j| {
            let mut v = u.to_vec();
            v[j] += h;
            let r = residuals(&v)?;
            Ok(r.iter().zip(r0).map(|(a, b)| (a - b) / h).collect())
        })
        .collect::<Result<_, E>>()?;
    Ok(DMatrix::from_fn(r0.len(), u.len(), |i, j| cols[j][i]))
}

/// Minimises the sum of squared `residuals(u)` from `u0`. Errors of the residual function
/// are returned as they are.
pub fn levenberg_marquardt<E: Send>(
    residuals: impl Fn(&[f64]) -> Result<Vec<f64>, E> + Sync,
    u0: &[f64],
    s: &LmSettings,
) -> Result<LmResult, E> {
    let p = u0.len();
    let mut u = u0.to_vec();
    let mut r = residuals(&u)?;
    let mut evaluations = 1;
    let mut c = cost(&r);
    let mut lambda = s.lambda0;
    let mut stop = LmStop::MaxIter;
    let mut iterations = 0;
    let mut jac = jacobian(&residuals, &u, &r, s.fd_step)?;
    evaluations += p;
    while iterations < s.max_iter {
        iterations += 1;
        let a = jac.transpose() * &jac;
        let g = jac.transpose() * DVector::from_column_slice(&r);
        let diag_max = (0..p).map(|k| a[(k, k)]).fold(f64::MIN_POSITIVE, f64::max);
        let mut accepted = None;
        while lambda <= s.lambda_max {
            let mut damped = a.clone();
            for k in 0..p {
                damped[(k, k)] += lambda * a[(k, k)].max(DIAG_FLOOR * diag_max);
            }
            let Some(mut step) = damped.lu().solve(&(-&g)) else {
                lambda *= 10.0;
                continue;
            };
            if step.norm() > s.max_step {
                step *= s.max_step / step.norm();
            }
            let trial: Vec<f64> = u.iter().zip(step.iter()).map(|(x, d)| x + d).collect();
            let rt = residuals(&trial)?;
            evaluations += 1;
            let ct = cost(&rt);
            if ct.is_finite() && ct < c {
                accepted = Some((trial, rt, ct, step.norm()));
                lambda = (lambda / 10.0).max(1e-12);
                break;
            }
            lambda *= 10.0;
        }
        let Some((trial, rt, ct, step_norm)) = accepted else {
            let promised = a
                .clone()
                .pseudo_inverse(1e-12 * diag_max)
                .map_or(f64::INFINITY, |ai| g.dot(&(ai * &g)));
            stop = if promised < (s.noise_rel_tol * c).max(s.cost_abs_tol) {
                LmStop::Stalled
            } else {
                LmStop::NoDescent
            };
            break;
        };
        let drop = (c - ct) / c.max(f64::MIN_POSITIVE);
        let c_before = c;
        u = trial;
        r = rt;
        c = ct;
        jac = jacobian(&residuals, &u, &r, s.fd_step)?;
        evaluations += p;
        if drop < s.cost_rel_tol || c_before - c < s.cost_abs_tol {
            stop = LmStop::CostConverged;
            break;
        }
        if step_norm < s.step_tol {
            stop = LmStop::StepConverged;
            break;
        }
    }
    Ok(LmResult {
        u,
        residuals: r,
        jacobian: jac,
        iterations,
        evaluations,
        stop,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fits_an_exponential_decay_to_its_generating_parameters() {
        // y = a exp(-k t) sampled without noise: the minimum is the generating (a, k).
        let t: Vec<f64> = (0..12).map(|i| 0.25 * i as f64).collect();
        let (a, k) = (3.0_f64, 0.7_f64);
        let y: Vec<f64> = t.iter().map(|t| a * (-k * t).exp()).collect();
        let res = |u: &[f64]| -> Result<Vec<f64>, ()> {
            Ok(t.iter()
                .zip(&y)
                .map(|(t, y)| u[0] * (-u[1] * t).exp() - y)
                .collect())
        };
        let settings = LmSettings {
            fd_step: 1e-7,
            cost_rel_tol: 1e-12,
            step_tol: 1e-10,
            ..LmSettings::default()
        };
        let r = levenberg_marquardt(res, &[1.0, 0.1], &settings).unwrap();
        assert!(r.stop.converged(), "{:?}", r.stop);
        assert!(
            (r.u[0] - a).abs() < 1e-5 && (r.u[1] - k).abs() < 1e-5,
            "{:?}",
            r.u
        );
    }
}
