//! A fold of a branch of periodic orbits found directly from a fold of a nearby system,
//! without following the branch up to it.
//!
//! Along a branch u(s) = (z(s), q(s)) of fixed points of the period map (scaled state z,
//! scaled parameter q), a fold is where the tangent's parameter component t_q vanishes: there
//! M - I is singular and its kernel is the tangent. When the system moves a little (the
//! device's parameters in a fit), the fold moves a little too, and its old location is a good
//! start: the branch is parametrised by the arclength s along the old fold's direction
//! t0 = (v, 0), v the eigenvector of the old monodromy for its multiplier nearest 1, which is
//! transversal to the branch near the fold (the bordered system below stays regular there,
//! unlike one with the parameter held fixed). Each u(s) is a Newton solution of
//!
//!   P(z, q) - z = 0,   t0 . (u - u0) = s,
//!
//! its tangent is the kernel of [M - I | dP/dq] normalised by t0 . t = 1, and a secant
//! iteration on t_q(s) = 0 finds the fold (Keller's pseudo-arclength bordering, and the fold
//! as the zero of the tangent's parameter component: Kuznetsov, "Elements of Applied
//! Bifurcation Theory", 3rd ed., chapter 10). The fold's parameter is stationary in s, so its
//! error is of the order of the square of the error in s.

use nalgebra::{DMatrix, DVector, SMatrix, SVector};

use crate::model::Model;
use crate::ode::Stats;

use super::doubling::eigenvector_near;
use super::{Forcing, Orbit, OrbitError, Parameter, Shooter, CHORD_STEPS};

/// Secant steps before the search for a fold is given up.
const FOLD_SECANT_STEPS: usize = 12;

/// Lengths tried for the secant's first step, each a tenth of the one before, before the
/// search for a fold is given up: the first is a tenth of [`FoldSearch::max_step`], the last
/// a thousandth.
const FIRST_STEP_TRIES: usize = 3;

/// How a fold is sought by [`Shooter::fold_near`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FoldSearch {
    /// The parameter along which the branch folds.
    pub param: Parameter,
    /// Scale of the parameter in the arclength (its unit per scaled state unit).
    pub param_scale: f64,
    /// The fold is located when a secant step in arclength is below this: its parameter is
    /// then off by about the square of it times the branch's curvature.
    pub tol: f64,
    /// Largest secant step in arclength: a step beyond it would leave the neighbourhood in
    /// which the fold's old direction parametrises the branch.
    pub max_step: f64,
}

/// A fold found by [`Shooter::fold_near`].
#[derive(Debug, Clone, PartialEq)]
pub struct FoldOrbit {
    /// The orbit at the fold.
    pub orbit: Orbit,
    /// d^2 q / ds^2 there (scaled parameter per squared arclength, along the old fold's
    /// direction): negative where the parameter is largest at the fold (the branch before it
    /// lies below it in the parameter), positive where it is smallest.
    pub curvature: f64,
}

/// A point of the branch at one arclength: the scaled state and parameter, the tangent
/// (normalised by t0 . t = 1) and the converged orbit.
struct Point {
    u: DVector<f64>,
    tangent: DVector<f64>,
    orbit: Orbit,
}

impl Point {
    /// The tangent's parameter component: zero at the fold.
    fn t_q<const N: usize>(&self) -> f64 {
        self.tangent[N]
    }
}

/// What every corrected point of one search shares.
struct Ctx<'c> {
    template: Forcing,
    phase: f64,
    anchor: &'c DVector<f64>,
    t0: &'c DVector<f64>,
    search: &'c FoldSearch,
}

impl<M: Model<N>, const N: usize> Shooter<'_, M, N> {
    /// The fold of the branch through the fold `from` of a nearby system (an orbit at a
    /// fold of the same branch at slightly different model parameters, or at this model near
    /// its fold): the orbit where the branch's parameter is extremal, with its section at
    /// `from`'s phase, and the branch's curvature there (which way it turns). Errors when
    /// Newton's method or the secant iteration does not converge; the caller checks that the
    /// fold found is the one it follows (its parameter and its multiplier at 1).
    pub fn fold_near(
        &self,
        from: &Orbit,
        search: &FoldSearch,
        stats: &mut Stats,
    ) -> Result<FoldOrbit, OrbitError> {
        let param = search.param;
        let fail = |p: f64, residual: f64| OrbitError::NoConvergence {
            what: param.label(),
            param: p,
            iterations: FOLD_SECANT_STEPS,
            residual,
        };
        let p0 = from.param(param);
        let v =
            eigenvector_near::<N>(&from.monodromy_n(), 1.0).ok_or_else(|| fail(p0, f64::NAN))?;
        let z0 = from.state_n::<N>().component_div(&self.scales());
        let anchor = DVector::from_fn(N + 1, |i, _| {
            if i < N {
                z0[i]
            } else {
                p0 / search.param_scale
            }
        });
        let t0 = DVector::from_fn(N + 1, |i, _| if i < N { v[i] } else { 0.0 });
        let ctx = Ctx {
            template: from.forcing,
            phase: from.phase_rad,
            anchor: &anchor,
            t0: &t0,
            search,
        };
        let (mut sa, mut a) = (0.0, self.corrected(&ctx, &anchor, 0.0, stats)?);
        // A first step of a tenth of the largest: either side brackets a t_q that is nearly
        // linear in s near the fold. Where Newton's method does not converge there (the step
        // left the neighbourhood in which the old direction parametrises the branch) the step
        // is shortened tenfold, up to `FIRST_STEP_TRIES` lengths in all.
        let mut sb = 0.1 * search.max_step;
        let mut tries = 1;
        let mut b = loop {
            match self.corrected(&ctx, &(&a.u + &a.tangent * sb), sb, stats) {
                Ok(b) => break b,
                Err(e) if tries == FIRST_STEP_TRIES => return Err(e),
                Err(_) => {
                    sb *= 0.1;
                    tries += 1;
                }
            }
        };
        for _ in 0..FOLD_SECANT_STEPS {
            let slope = (b.t_q::<N>() - a.t_q::<N>()) / (sb - sa);
            if !(slope.is_finite() && slope != 0.0) {
                return Err(fail(b.orbit.param(param), b.t_q::<N>()));
            }
            let ds = (-b.t_q::<N>() / slope).clamp(-search.max_step, search.max_step);
            let s_next = sb + ds;
            // The predictor: the last point moved along its tangent (t0 . t = 1).
            let guess = &b.u + &b.tangent * ds;
            let c = self.corrected(&ctx, &guess, s_next, stats)?;
            (sa, a, sb, b) = (sb, b, s_next, c);
            if ds.abs() <= search.tol {
                // t_q = dq/ds (t0 . t = 1 and s = t0 . (u - u0)): its slope is the curvature.
                return Ok(FoldOrbit {
                    orbit: b.orbit,
                    curvature: slope,
                });
            }
        }
        Err(fail(b.orbit.param(param), b.t_q::<N>()))
    }

    /// Newton on P(z, q) = z with t0 . (u - anchor) = s from `guess`, polished on the plain
    /// period map by chord steps (as [`Shooter::solve`]), with the tangent there.
    fn corrected(
        &self,
        ctx: &Ctx<'_>,
        guess: &DVector<f64>,
        s: f64,
        stats: &mut Stats,
    ) -> Result<Point, OrbitError> {
        let param = ctx.search.param;
        let scale = ctx.search.param_scale;
        let sc = self.scales();
        let solver = |p: f64, e| OrbitError::Solver {
            what: param.label(),
            param: p,
            source: e,
        };
        let mut u = guess.clone();
        let mut residual = f64::INFINITY;
        for it in 0..=self.cfg.max_newton {
            let p = u[N] * scale;
            if !(p.is_finite() && p > 0.0) {
                break;
            }
            let forcing = ctx.template.with(param, p);
            let z = SVector::<f64, N>::from_fn(|i, _| u[i]);
            let y = z.component_mul(&sc);
            let lin = self
                .linearise(&forcing, param, ctx.phase, y, stats)
                .map_err(|e| solver(p, e))?;
            let g = (lin.end - y).component_div(&sc);
            let m = self.scaled_monodromy(&lin.monodromy);
            let gq = lin.dp.component_div(&sc) * scale;
            let arc = ctx.t0.dot(&(&u - ctx.anchor)) - s;
            residual = g.norm() / z.norm().max(1e-300);
            let lu = bordered(&m, &gq, ctx.t0).lu();
            let rhs = |g: &SVector<f64, N>, last: f64| {
                DVector::from_fn(N + 1, |i, _| if i < N { -g[i] } else { last })
            };
            if residual < self.cfg.residual_tol && arc.abs() <= 1e-9 * (1.0 + s.abs()) {
                for _ in 0..CHORD_STEPS {
                    let p = u[N] * scale;
                    let forcing = ctx.template.with(param, p);
                    let z = SVector::<f64, N>::from_fn(|i, _| u[i]);
                    let y = z.component_mul(&sc);
                    let (end, summary) = self
                        .measure(&forcing, ctx.phase, y, stats)
                        .map_err(|e| solver(p, e))?;
                    let gp = (end - y).component_div(&sc);
                    let plain = gp.norm() / z.norm().max(1e-300);
                    if plain < self.cfg.residual_tol {
                        let mut e = DVector::zeros(N + 1);
                        e[N] = 1.0;
                        let tangent = lu.solve(&e).ok_or(OrbitError::NoConvergence {
                            what: param.label(),
                            param: p,
                            iterations: it,
                            residual: plain,
                        })?;
                        let orbit =
                            self.orbit(&forcing, param, ctx.phase, y, m, plain, it, summary)?;
                        return Ok(Point { u, tangent, orbit });
                    }
                    residual = plain;
                    let Some(du) = lu.solve(&rhs(&gp, 0.0)) else {
                        break;
                    };
                    u += du;
                }
                break;
            }
            if it == self.cfg.max_newton {
                break;
            }
            let Some(du) = lu.solve(&rhs(&g, -arc)) else {
                break;
            };
            u += du;
        }
        Err(OrbitError::NoConvergence {
            what: param.label(),
            param: u[N] * scale,
            iterations: self.cfg.max_newton,
            residual,
        })
    }
}

/// The bordered matrix [M - I, dP/dq; t0^T] (scaled coordinates).
fn bordered<const N: usize>(
    m: &SMatrix<f64, N, N>,
    gq: &SVector<f64, N>,
    t0: &DVector<f64>,
) -> DMatrix<f64> {
    let mut big = DMatrix::zeros(N + 1, N + 1);
    for i in 0..N {
        for j in 0..N {
            big[(i, j)] = m[(i, j)] - if i == j { 1.0 } else { 0.0 };
        }
        big[(i, N)] = gq[i];
    }
    big.set_row(N, &t0.transpose());
    big
}
