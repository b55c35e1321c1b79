//! The predictor-corrector: Newton on the bordered system from the predictor `u_k + ds t_k`,
//! the tangent from the kernel, the acceptance of a corrected step ([`Rejection`]), and the
//! hop over a corner of the branch at grazing where no arclength step converges.

use nalgebra::{DMatrix, DVector, SMatrix, SVector};

use crate::model::Model;
use crate::ode::Stats;
use crate::study::orbit::{Forcing, Linearised, Orbit, OrbitError, Shooter, CHORD_STEPS};

use super::test_functions::{test_grazing, test_plus_one, Gaps, GRAZING_NEAR};
use super::{BranchPoint, ContinuationSettings, Rejection};

/// Largest distance of a corrected point from its predictor, in arclength steps: beyond it
/// the step is rejected as having jumped to another branch.
const MAX_CORRECTION: f64 = 0.5;

/// Largest parameter step across a grazing, as a fraction of the largest step.
const GRAZING_STEP: f64 = 0.01;

/// Largest factor by which the largest Floquet multiplier's modulus may change in one step.
const MAX_MULTIPLIER_RATIO: f64 = 2.0;

/// A corrected point with the matrix whose kernel is the tangent.
struct Corrected {
    orbit: Orbit,
    /// [M - I | dP/dq] in scaled coordinates.
    jac: DMatrix<f64>,
    iterations: usize,
}

/// The continuation's working state: the shooter, the settings, the drive periods of the map
/// whose fixed points the branch follows (1: the period map; k: the map over k periods, for a
/// branch of orbits of k periods), and the integrator counters of every integration so far.
pub(super) struct Continuer<'s, 'a, M, const N: usize> {
    pub(super) shooter: &'s Shooter<'a, M, N>,
    pub(super) settings: ContinuationSettings,
    pub(super) periods: usize,
    pub(super) stats: Stats,
}

/// The vector `(z, q)` of the bordered system: the scaled state and the scaled parameter.
fn join<const N: usize>(z: &SVector<f64, N>, q: f64) -> DVector<f64> {
    DVector::from_fn(N + 1, |i, _| if i < N { z[i] } else { q })
}

/// The scaled state of `(z, q)`.
fn state_part<const N: usize>(u: &DVector<f64>) -> SVector<f64, N> {
    SVector::<f64, N>::from_fn(|i, _| u[i])
}

/// The bordered matrix `[jac; t^T]`.
fn bordered(jac: &DMatrix<f64>, t: &DVector<f64>) -> DMatrix<f64> {
    let n = jac.nrows();
    let mut big = DMatrix::zeros(n + 1, n + 1);
    big.view_mut((0, 0), (n, n + 1)).copy_from(jac);
    big.set_row(n, &t.transpose());
    big
}

/// The unit tangent spanning the kernel of `jac`, oriented along `prev`.
pub(super) fn tangent(jac: &DMatrix<f64>, prev: &DVector<f64>) -> Option<DVector<f64>> {
    let big = bordered(jac, prev);
    let mut e = DVector::zeros(prev.len());
    e[prev.len() - 1] = 1.0;
    let t = big.lu().solve(&e)?;
    let n = t.norm();
    if !(n.is_finite() && n > 0.0) {
        return None;
    }
    let t = t / n;
    Some(if t.dot(prev) < 0.0 { -t } else { t })
}

impl<M: Model<N>, const N: usize> Continuer<'_, '_, M, N> {
    fn p_of(&self, q: f64) -> f64 {
        q * self.settings.param_scale
    }

    /// The branch's map (over [`Continuer::periods`] drive periods) at `y`, linearised.
    pub(super) fn linearise(
        &mut self,
        forcing: &Forcing,
        phase_rad: f64,
        y: SVector<f64, N>,
    ) -> Result<Linearised<N>, OrbitError> {
        let param = self.settings.parameter;
        let duration_s = self.periods as f64 * forcing.period_s();
        self.shooter
            .linearise_over(forcing, param, phase_rad, y, duration_s, &mut self.stats)
            .map_err(|e| OrbitError::Solver {
                what: param.label(),
                param: forcing.get(param),
                source: e,
            })
    }

    /// Newton's method for a fixed point of the branch's map at `forcing` from `guess`.
    pub(super) fn solve(
        &mut self,
        forcing: &Forcing,
        phase_rad: f64,
        guess: SVector<f64, N>,
    ) -> Result<Orbit, OrbitError> {
        let param = self.settings.parameter;
        self.shooter.solve_periods(
            forcing,
            param,
            phase_rad,
            guess,
            self.periods,
            &mut self.stats,
        )
    }

    pub(super) fn u_of(&self, o: &Orbit) -> DVector<f64> {
        let z = o.state_n::<N>().component_div(&self.shooter.scales());
        join(
            &z,
            o.param(self.settings.parameter) / self.settings.param_scale,
        )
    }

    /// `[M - I | dP/dq]` of a monodromy in scaled coordinates and a scaled parameter column.
    fn jac_of(m: &SMatrix<f64, N, N>, gq: &SVector<f64, N>) -> DMatrix<f64> {
        let d = m - SMatrix::<f64, N, N>::identity();
        let mut jac = DMatrix::zeros(N, N + 1);
        jac.view_mut((0, 0), (N, N)).copy_from(&d);
        jac.set_column(N, gq);
        jac
    }

    /// Newton on P(z, q) = z with t . (u - anchor) = s, from the predictor anchor + s t, at the
    /// section phase `phase` of the anchor's orbit.
    fn correct(
        &mut self,
        template: &Forcing,
        phase: f64,
        anchor: &DVector<f64>,
        t: &DVector<f64>,
        s: f64,
    ) -> Result<Corrected, OrbitError> {
        let param = self.settings.parameter;
        let sc = self.shooter.scales();
        let cfg = self.shooter.cfg;
        let mut u = anchor + t * s;
        let mut residual = f64::INFINITY;
        for it in 0..=cfg.max_newton {
            let q = u[N];
            let p = self.p_of(q);
            if !(p.is_finite() && p > 0.0) {
                break;
            }
            let forcing = template.with(param, p);
            let z: SVector<f64, N> = state_part(&u);
            let y = z.component_mul(&sc);
            let lin = self.linearise(&forcing, phase, y)?;
            let g = (lin.end - y).component_div(&sc);
            let m = self.shooter.scaled_monodromy(&lin.monodromy);
            let gq = lin.dp.component_div(&sc) * self.settings.param_scale;
            let arc = t.dot(&(&u - anchor)) - s;
            residual = g.norm() / z.norm().max(1e-300);
            let jac = Self::jac_of(&m, &gq);
            let lu = bordered(&jac, t).lu();
            if residual < cfg.residual_tol && arc.abs() <= 1e-9 * (1.0 + s.abs()) {
                // Polish on the plain period map by chord steps (see `Shooter::solve`).
                for _ in 0..CHORD_STEPS {
                    let p = self.p_of(u[N]);
                    let forcing = template.with(param, p);
                    let z: SVector<f64, N> = state_part(&u);
                    let y = z.component_mul(&sc);
                    let (end, summary) = self
                        .shooter
                        .measure_periods(&forcing, phase, y, self.periods, &mut self.stats)
                        .map_err(|e| OrbitError::Solver {
                            what: param.label(),
                            param: p,
                            source: e,
                        })?;
                    let gp = (end - y).component_div(&sc);
                    let plain = gp.norm() / z.norm().max(1e-300);
                    if plain < cfg.residual_tol {
                        let mut orbit = self
                            .shooter
                            .orbit(&forcing, param, phase, y, m, plain, it, summary)?;
                        orbit.periods = self.periods;
                        return Ok(Corrected {
                            orbit,
                            jac,
                            iterations: it,
                        });
                    }
                    residual = plain;
                    // The last row keeps the arclength condition.
                    let rhs = join(&(-gp), 0.0);
                    let Some(du) = lu.solve(&rhs) else { break };
                    u += du;
                }
                break;
            }
            if it == cfg.max_newton {
                break;
            }
            let rhs = join(&(-g), -arc);
            let Some(du) = lu.solve(&rhs) else {
                break;
            };
            u += du;
        }
        Err(OrbitError::NoConvergence {
            what: param.label(),
            param: self.p_of(u[N]),
            iterations: cfg.max_newton,
            residual,
        })
    }

    /// [M - I | dP/dq] in scaled coordinates at a linearised orbit: the matrix whose kernel
    /// is the branch's tangent.
    pub(super) fn kernel_jacobian(&self, lin: &Linearised<N>) -> DMatrix<f64> {
        let sc = self.shooter.scales();
        let m = self.shooter.scaled_monodromy(&lin.monodromy);
        Self::jac_of(&m, &(lin.dp.component_div(&sc) * self.settings.param_scale))
    }

    /// The point at arclength `s` from `from` along its tangent, with its tangent.
    pub(super) fn point_at(
        &mut self,
        from: &BranchPoint,
        s: f64,
    ) -> Result<(BranchPoint, usize), OrbitError> {
        let anchor = self.u_of(&from.orbit);
        let c = self.correct(
            &from.orbit.forcing,
            from.orbit.phase_rad,
            &anchor,
            &from.tangent,
            s,
        )?;
        let tangent = tangent(&c.jac, &from.tangent).ok_or(OrbitError::NoConvergence {
            what: self.settings.parameter.label(),
            param: c.orbit.param(self.settings.parameter),
            iterations: c.iterations,
            residual: c.orbit.residual,
        })?;
        Ok((
            BranchPoint {
                orbit: c.orbit,
                tangent,
            },
            c.iterations,
        ))
    }

    /// Moves the section of a point into free flight (when its tangent's parameter component
    /// is large enough to orient the new tangent by it; near a fold the section waits).
    pub(super) fn reanchor(&mut self, p: BranchPoint) -> Result<BranchPoint, OrbitError> {
        if self.shooter.section_is_free(&p.orbit) || p.param_tangent().abs() < 0.05 {
            return Ok(p);
        }
        let param = self.settings.parameter;
        let o = self.shooter.reanchor(&p.orbit, param, &mut self.stats)?;
        // The kernel at the new section, oriented so that the parameter moves the same way.
        let lin = self.linearise(&o.forcing, o.phase_rad, o.state_n())?;
        let jac = self.kernel_jacobian(&lin);
        let sign = p.param_tangent().signum();
        let e = join(&SVector::<f64, N>::zeros(), sign);
        let tangent = tangent(&jac, &e).ok_or(OrbitError::NoConvergence {
            what: param.label(),
            param: o.param(param),
            iterations: 0,
            residual: o.residual,
        })?;
        Ok(BranchPoint { orbit: o, tangent })
    }

    /// Whether the corrected point `p`, at arclength `ds` along the tangent of `last`, goes
    /// onto the branch: the first reason it does not, in the order of [`Rejection`]'s
    /// variants after [`Rejection::Corrector`].
    pub(super) fn judge(
        &self,
        last: &BranchPoint,
        p: &BranchPoint,
        ds: f64,
    ) -> Result<(), Rejection> {
        let settings = &self.settings;
        let param = settings.parameter;
        let dp = (p.orbit.param(param) - last.orbit.param(param)).abs();
        if p.tangent.dot(&last.tangent) < settings.max_turn_rad.cos() {
            return Err(Rejection::Turn);
        }
        if dp > settings.max_param_step {
            return Err(Rejection::ParamStep);
        }
        // The corrector must stay near its predictor: a correction much longer than the step
        // has left the branch (near a grazing corner it can land on another branch that passes
        // close by).
        let predicted = self.u_of(&last.orbit) + &last.tangent * ds;
        if (self.u_of(&p.orbit) - predicted).norm() > MAX_CORRECTION * ds {
            return Err(Rejection::LeftPredictor);
        }
        // The largest multiplier moves continuously along a branch: a step that changes it by
        // more than a factor MAX_MULTIPLIER_RATIO is refined (near a grazing corner the
        // corrector can land on a neighbouring branch that is close in state but differs in
        // stability).
        let (ma, mb) = (
            last.orbit.max_multiplier_abs(),
            p.orbit.max_multiplier_abs(),
        );
        if (mb / ma).max(ma / mb) > MAX_MULTIPLIER_RATIO {
            return Err(Rejection::MultiplierJump);
        }
        // A step that starts or stops touching the stops is kept short: a long one can leave an
        // impacting branch for the non-impacting one across a narrow loop of the branch (a fold
        // just past the grazing) without passing the fold.
        let crossed = p.orbit.is_impacting() != last.orbit.is_impacting();
        if crossed && dp > GRAZING_STEP * settings.max_param_step {
            return Err(Rejection::LongCrossing);
        }
        // A free-flight branch that turns back at grazing with no change of stability has not
        // folded (a smooth fold moves a multiplier through +1): the corrector has slid back
        // along the branch it came on, unable to step across a corner (an impacting branch
        // that leaves at an angle, as with a large impact damping). Refined, and hopped over
        // when the step is exhausted ([`Continuer::corner_hop`]).
        let gaps = Gaps::of(self.shooter.base);
        let graze_tol = GRAZING_NEAR * gaps.smallest();
        let slid_back = !crossed
            && !last.orbit.is_impacting()
            && test_grazing(last, gaps).abs() <= graze_tol
            && (p.param_tangent() > 0.0) != (last.param_tangent() > 0.0)
            && p.orbit.is_stable() == last.orbit.is_stable()
            && (test_plus_one(p, gaps) > 0.0) == (test_plus_one(last, gaps) > 0.0);
        if slid_back {
            return Err(Rejection::SlidBack);
        }
        Ok(())
    }

    /// Hops over a corner of the branch at an orbit `last` that (nearly) grazes a stop.
    /// From an impacting `last`: shoots at fixed parameter values stepping away from `last` in
    /// the direction opposite to its tangent's parameter component (the non-impacting branch
    /// leaves the corner that way), then the other way, and returns the first non-impacting
    /// orbit found. From a non-impacting `last` (the free-flight branch arriving at grazing,
    /// where a large impact damping makes the impacting branch leave at an angle that no
    /// arclength step converges across): steps on along its tangent and returns the first
    /// impacting orbit. The tangent is oriented along the direction stepped. `None` when
    /// `last` is not near grazing or nothing is found within `max_step`.
    pub(super) fn corner_hop(&mut self, last: &BranchPoint, max_step: f64) -> Option<BranchPoint> {
        let gaps = Gaps::of(self.shooter.base);
        let near = test_grazing(last, gaps).abs() <= GRAZING_NEAR * gaps.smallest();
        if !near {
            return None;
        }
        let leaving_contact = last.orbit.is_impacting();
        let ahead = last.param_tangent().signum();
        let dirs: &[f64] = if leaving_contact {
            &[-ahead, ahead]
        } else {
            &[ahead]
        };
        dirs.iter().find_map(|&dir| {
            self.shoot_away(last, dir, max_step, |o| o.is_impacting() != leaving_contact)
        })
    }

    /// The first orbit that `accept` takes, shot at fixed parameter values stepping from
    /// `last` in the direction `dir` (+1 or -1) by 1e-4 `max_step`, four times that, ... up to
    /// `max_step`, each from `last`'s state; with its tangent, oriented along `dir`.
    pub(super) fn shoot_away(
        &mut self,
        last: &BranchPoint,
        dir: f64,
        max_step: f64,
        accept: impl Fn(&Orbit) -> bool,
    ) -> Option<BranchPoint> {
        let param = self.settings.parameter;
        let p0 = last.orbit.param(param);
        let mut step = 1e-4 * max_step;
        while step <= max_step {
            let f = last.orbit.forcing.with(param, p0 + dir * step);
            let solved = self.solve(&f, last.orbit.phase_rad, last.orbit.state_n());
            if let Ok(o) = solved {
                if accept(&o) {
                    return self.with_tangent(o, dir);
                }
            }
            step *= 4.0;
        }
        None
    }

    /// A point of the branch at the orbit `o`, its tangent oriented so that the parameter
    /// moves in the direction `dir`.
    pub(super) fn with_tangent(&mut self, o: Orbit, dir: f64) -> Option<BranchPoint> {
        let lin = self.linearise(&o.forcing, o.phase_rad, o.state_n()).ok()?;
        let jac = self.kernel_jacobian(&lin);
        let e = join(&SVector::<f64, N>::zeros(), dir);
        let tangent = tangent(&jac, &e)?;
        Some(BranchPoint { orbit: o, tangent })
    }
}
