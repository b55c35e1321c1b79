//! Levenberg-Marquardt for small, expensive least-squares problems in unbounded coordinates,
//! with a forward-difference Jacobian whose columns are evaluated in parallel, for problems
//! whose evaluations carry a state from the accepted point to the next ([`Tracked`]: the fit
//! follows orbits and bifurcations from where they were).
//!
//! Written here rather than taken from a crate: argmin (the crate's optimiser library) offers
//! Gauss-Newton with and without a line search but no Levenberg-Marquardt, and the
//! `levenberg-marquardt` crate (MINPACK's method on nalgebra) stops the whole search when an
//! evaluation fails, whereas here a trial point whose model cannot be evaluated (an orbit
//! that no longer exists, a fold that left the range) is a rejected step like one that raises
//! the cost, and the evaluations must start from the state of the accepted point. The method
//! is Marquardt's (the damping scales the diagonal of J^T J; Nocedal and Wright, Numerical
//! Optimization, 2nd ed., section 10.3) with Nielsen's update of the damping (Madsen, Nielsen
//! and Tingleff, Methods for Non-Linear Least Squares Problems, 2nd ed., IMM DTU 2004,
//! section 3.2): after an accepted step the damping is multiplied by
//! `max(1/3, 1 - (2 rho - 1)^3)`, where `rho` is the cost's actual decrease over the decrease
//! the Gauss-Newton model predicted for the step, and after a rejected one by `nu`, which
//! starts at 2 and doubles at each rejection in a row. A step the model predicts well thus
//! lowers the damping, one it predicts badly keeps it, where a fixed factor of 10 lowers it
//! either way and, in a curved valley, sends the next step across the valley. Each residual
//! evaluation here costs orbits or a whole sweep, so the solver counts them.
//!
//! The Jacobian is differenced at every accepted point the search goes on from. Broyden's
//! secant update after a step the model predicted well (Madsen, Nielsen and Tingleff,
//! section 3.5) was tried and not kept: it cut the evaluations counted but not the time, since
//! on the branches a column (a step of 1e-4 from converged orbits) costs far less than a
//! trial, and it took more iterations in some cases and moved the optimum of the stepped-sweep
//! case 21. Nor is a trial after a lost one shortened to a quarter of it, as a trust region
//! would: the searches then took more, shorter steps and were slower. The numbers are in this
//! file's history (`git log`); `cargo run --release --example fit_cost` measures them.

use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

/// Settings of [`levenberg_marquardt`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LmSettings {
    /// Forward-difference step in the unbounded coordinates (the fit's model on the branches
    /// is smooth to about 1e-9 relative, so a step of 1e-4 gives derivatives to about 1e-4;
    /// the stepped-sweep model needs [`STEPPED_FD_STEP`]).
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
    /// A stop without descent counts as converged ([`Termination::Stalled`]) when the undamped
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
    /// Difference the Jacobian at the point where the search converges (true), or leave the
    /// one of the point before the last step (false: for a search whose stop hands over to
    /// another model that may never need it; [`LmResult::jacobian_at_u`] says which).
    pub jacobian_at_stop: bool,
}

/// Forward-difference step of the stepped-sweep model: a steady state converged to a relative
/// change of 1e-6 changes by about that much for a step of 1e-2 in the transformed coordinates.
pub const STEPPED_FD_STEP: f64 = 1e-2;

/// The damping scales each diagonal element of J^T J, but at least this fraction of the
/// largest one, so that a parameter the residuals do not depend on is still damped.
const DIAG_FLOOR: f64 = 1e-6;

impl Default for LmSettings {
    fn default() -> Self {
        Self {
            fd_step: 1e-4,
            max_iter: 40,
            cost_rel_tol: 1e-6,
            step_tol: 1e-4,
            lambda0: 1e-2,
            lambda_max: 1e8,
            max_step: 2.0,
            noise_rel_tol: 1e-3,
            cost_abs_tol: 0.0,
            jacobian_at_stop: true,
        }
    }
}

/// Why the solver stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Termination {
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
    /// The problem asked to stop at an accepted point ([`Tracked::hand_over`]), to be
    /// searched on from there with another model.
    HandedOver,
}

impl Termination {
    /// True when the stop is a convergence criterion.
    pub fn converged(self) -> bool {
        matches!(
            self,
            Termination::CostConverged | Termination::StepConverged | Termination::Stalled
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
    /// Jacobian of the residuals there (rows: residuals, columns: coordinates), or at the
    /// point before the last step when [`LmResult::jacobian_at_u`] is false.
    pub jacobian: DMatrix<f64>,
    /// Whether [`LmResult::jacobian`] is the one at [`LmResult::u`] (false only after a
    /// convergence with [`LmSettings::jacobian_at_stop`] false).
    pub jacobian_at_u: bool,
    /// Outer iterations.
    pub iterations: usize,
    /// Residual evaluations, the Jacobians' included.
    pub evaluations: usize,
    /// Trial points whose residuals could not be evaluated (rejected steps).
    pub failed_trials: usize,
    /// Why it stopped.
    pub stop: Termination,
    /// The damping at the stop (where a search resumed from this point starts).
    pub lambda: f64,
}

fn cost(r: &[f64]) -> f64 {
    r.iter().map(|x| x * x).sum()
}

/// A least-squares problem whose evaluations start from the state of an earlier one (the
/// accepted point's, for trials and Jacobian columns alike).
pub trait Tracked: Sync {
    /// What an evaluation carries to the next.
    type State: Clone + Send + Sync;
    /// Why an evaluation failed.
    type Error: Send + std::fmt::Debug;
    /// The residuals at `u` and the state there, starting from `from`.
    fn residuals(
        &self,
        u: &[f64],
        from: &Self::State,
    ) -> Result<(Vec<f64>, Self::State), Self::Error>;

    /// True when the search is to stop at the accepted point `u` (with residuals `r` and state
    /// `state`), not yet converged, and hand over to another model there
    /// ([`Termination::HandedOver`]): asked after each accepted step, before its Jacobian is
    /// computed. Never, by default.
    fn hand_over(&self, _u: &[f64], _r: &[f64], _state: &Self::State) -> bool {
        false
    }
}

/// A residual function without state as a [`Tracked`] problem.
struct Plain<F>(F);

impl<E: Send + std::fmt::Debug, F: Fn(&[f64]) -> Result<Vec<f64>, E> + Sync> Tracked for Plain<F> {
    type State = ();
    type Error = E;
    fn residuals(&self, u: &[f64], _: &()) -> Result<(Vec<f64>, ()), E> {
        Ok(((self.0)(u)?, ()))
    }
}

/// Forward-difference Jacobian at `u` (residuals `r0` and state `state` there), columns in
/// parallel; a column whose forward point cannot be evaluated (a branch that ends just ahead)
/// is a backward difference.
pub fn jacobian<P: Tracked>(
    problem: &P,
    u: &[f64],
    r0: &[f64],
    state: &P::State,
    h: f64,
) -> Result<DMatrix<f64>, P::Error> {
    let cols: Vec<Vec<f64>> = (0..u.len())
        .into_par_iter()
        .map(|j| {
            let mut v = u.to_vec();
            v[j] += h;
            let (r, hj) = match problem.residuals(&v, state) {
                Ok((r, _)) => (r, h),
                Err(_) => {
                    v[j] = u[j] - h;
                    (problem.residuals(&v, state)?.0, -h)
                }
            };
            Ok(r.iter().zip(r0).map(|(a, b)| (a - b) / hj).collect())
        })
        .collect::<Result<_, P::Error>>()?;
    Ok(DMatrix::from_fn(r0.len(), u.len(), |i, j| cols[j][i]))
}

/// Minimises the sum of squared `residuals(u)` from `u0`. Errors of the residual function
/// at the start and in the Jacobian are returned as they are; at a trial point they reject
/// the step.
pub fn levenberg_marquardt<E: Send + std::fmt::Debug>(
    residuals: impl Fn(&[f64]) -> Result<Vec<f64>, E> + Sync,
    u0: &[f64],
    s: &LmSettings,
) -> Result<LmResult, E> {
    levenberg_marquardt_tracked(&Plain(residuals), u0, (), None, s).map(|(r, ())| r)
}

/// Minimises the sum of squared residuals of `problem` from `u0`, whose evaluation starts from
/// `state0` (with residuals `r0` there, if known; else they are evaluated); returns the result
/// and the state at the best point. Errors at the start and in the Jacobian are returned as
/// they are; at a trial point they reject the step.
pub fn levenberg_marquardt_tracked<P: Tracked>(
    problem: &P,
    u0: &[f64],
    state0: P::State,
    r0: Option<Vec<f64>>,
    s: &LmSettings,
) -> Result<(LmResult, P::State), P::Error> {
    let p = u0.len();
    let (r, state) = match r0 {
        Some(r) => (r, state0),
        None => problem.residuals(u0, &state0)?,
    };
    let jac = jacobian(problem, u0, &r, &state, s.fd_step)?;
    let (mut res, state) = levenberg_marquardt_resumed(problem, u0, state, r, jac, s)?;
    res.evaluations += p;
    Ok((res, state))
}

/// As [`levenberg_marquardt_tracked`] from a point whose residuals `r0` and Jacobian `jac0`
/// (with [`LmSettings::fd_step`]) are known, as at the end of an earlier search with looser
/// tolerances; the evaluations counted are the start's (one) and this search's own. Started
/// with the earlier search's damping ([`LmResult::lambda`]) as [`LmSettings::lambda0`] and its
/// remaining iterations as [`LmSettings::max_iter`], it takes the steps that search would have
/// taken with these tolerances.
pub fn levenberg_marquardt_resumed<P: Tracked>(
    problem: &P,
    u0: &[f64],
    state0: P::State,
    r0: Vec<f64>,
    jac0: DMatrix<f64>,
    s: &LmSettings,
) -> Result<(LmResult, P::State), P::Error> {
    let p = u0.len();
    let mut u = u0.to_vec();
    let (mut r, mut state) = (r0, state0);
    let mut evaluations = 1;
    let mut failed = 0;
    let mut c = cost(&r);
    let mut lambda = s.lambda0;
    let mut stop = Termination::MaxIter;
    let mut iterations = 0;
    let mut jac = jac0;
    let mut jacobian_at_u = true;
    while iterations < s.max_iter {
        iterations += 1;
        let a = jac.transpose() * &jac;
        let g = jac.transpose() * DVector::from_column_slice(&r);
        let diag_max = (0..p).map(|k| a[(k, k)]).fold(f64::MIN_POSITIVE, f64::max);
        let mut accepted = None;
        let mut nu = 2.0;
        while lambda <= s.lambda_max {
            let mut damped = a.clone();
            for k in 0..p {
                damped[(k, k)] += lambda * a[(k, k)].max(DIAG_FLOOR * diag_max);
            }
            let Some(mut step) = damped.lu().solve(&(-&g)) else {
                lambda *= nu;
                nu *= 2.0;
                continue;
            };
            if step.norm() > s.max_step {
                step *= s.max_step / step.norm();
            }
            let trial: Vec<f64> = u.iter().zip(step.iter()).map(|(x, d)| x + d).collect();
            evaluations += 1;
            match problem.residuals(&trial, &state) {
                Ok((rt, st)) if cost(&rt).is_finite() && cost(&rt) < c => {
                    let ct = cost(&rt);
                    // The Gauss-Newton model's decrease for this step: -(2 g.d + d^T A d).
                    let predicted = -(2.0 * g.dot(&step) + step.dot(&(&a * &step)));
                    let rho = (c - ct) / predicted;
                    let factor = if rho.is_finite() {
                        (1.0 - (2.0 * rho - 1.0).powi(3)).max(1.0 / 3.0)
                    } else {
                        1.0 / 3.0
                    };
                    accepted = Some((trial, rt, st, ct, step.norm()));
                    lambda = (lambda * factor).max(1e-12);
                    break;
                }
                Ok(_) => {}
                Err(_) => failed += 1,
            }
            lambda *= nu;
            nu *= 2.0;
        }
        let Some((trial, rt, st, ct, step_norm)) = accepted else {
            let promised = a
                .clone()
                .pseudo_inverse(1e-12 * diag_max)
                .map_or(f64::INFINITY, |ai| g.dot(&(ai * &g)));
            stop = if promised < (s.noise_rel_tol * c).max(s.cost_abs_tol) {
                Termination::Stalled
            } else {
                Termination::NoDescent
            };
            break;
        };
        let drop = (c - ct) / c.max(f64::MIN_POSITIVE);
        let c_before = c;
        u = trial;
        r = rt;
        state = st;
        c = ct;
        let converged = if drop < s.cost_rel_tol || c_before - c < s.cost_abs_tol {
            Some(Termination::CostConverged)
        } else if step_norm < s.step_tol {
            Some(Termination::StepConverged)
        } else {
            None
        };
        if converged.is_none() && problem.hand_over(&u, &r, &state) {
            stop = Termination::HandedOver;
            jacobian_at_u = false;
            break;
        }
        if converged.is_none() || s.jacobian_at_stop {
            jac = jacobian(problem, &u, &r, &state, s.fd_step)?;
            evaluations += p;
        } else {
            jacobian_at_u = false;
        }
        if let Some(t) = converged {
            stop = t;
            break;
        }
    }
    Ok((
        LmResult {
            u,
            residuals: r,
            jacobian: jac,
            jacobian_at_u,
            iterations,
            evaluations,
            failed_trials: failed,
            stop,
            lambda,
        },
        state,
    ))
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

    /// A search that hands over at an accepted point, carried on from there with its damping
    /// and remaining iterations, takes the steps of the search that never handed over: the
    /// same optimum to the last bit, with the same number of evaluations (the start counted
    /// once).
    #[test]
    fn a_search_carried_on_after_a_handover_takes_the_same_steps() {
        struct Decay {
            t: Vec<f64>,
            y: Vec<f64>,
            below: Option<f64>,
        }
        impl Tracked for Decay {
            type State = ();
            type Error = ();
            fn residuals(&self, u: &[f64], _: &()) -> Result<(Vec<f64>, ()), ()> {
                let r = self.t.iter().zip(&self.y);
                Ok((r.map(|(t, y)| u[0] * (-u[1] * t).exp() - y).collect(), ()))
            }
            fn hand_over(&self, _: &[f64], r: &[f64], _: &()) -> bool {
                self.below.is_some_and(|b| cost(r) < b)
            }
        }
        let t: Vec<f64> = (0..12).map(|i| 0.25 * i as f64).collect();
        let y: Vec<f64> = t
            .iter()
            .map(|t| 3.0 * (-0.7 * t).exp() + 0.01 * t.sin())
            .collect();
        let s = LmSettings {
            fd_step: 1e-7,
            cost_rel_tol: 1e-12,
            step_tol: 1e-10,
            ..LmSettings::default()
        };
        let plain = Decay {
            t: t.clone(),
            y: y.clone(),
            below: None,
        };
        let (whole, ()) = levenberg_marquardt_tracked(&plain, &[1.0, 0.1], (), None, &s).unwrap();
        let (r0, ()) = plain.residuals(&[1.0, 0.1], &()).unwrap();
        let watched = Decay {
            t,
            y,
            below: Some(0.5 * cost(&r0)),
        };
        let (near, ()) = levenberg_marquardt_tracked(&watched, &[1.0, 0.1], (), None, &s).unwrap();
        assert_eq!(near.stop, Termination::HandedOver);
        assert!(!near.jacobian_at_u);
        let rest = LmSettings {
            lambda0: near.lambda,
            max_iter: s.max_iter - near.iterations,
            ..s
        };
        let (more, ()) =
            levenberg_marquardt_tracked(&plain, &near.u, (), Some(near.residuals.clone()), &rest)
                .unwrap();
        assert_eq!(more.u, whole.u);
        assert_eq!(more.stop, whole.stop);
        assert_eq!(near.iterations + more.iterations, whole.iterations);
        assert_eq!(near.evaluations + more.evaluations - 1, whole.evaluations);
    }
}
