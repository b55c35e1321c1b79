//! Shooting: the period map of one device, its linearisation, Newton's method for a periodic
//! orbit, and the move of an orbit's section into free flight.

use nalgebra::{Matrix4, Vector4};

use crate::drive::Sine;
use crate::ode::{HybridSystem, SolverError, Stats, Step};
use crate::physics::contact::{Mode, Side, StopModel};
use crate::physics::harvester::{Harvester, State};
use crate::study::flow::{Engine, SineFlow};

use super::period_sums::{Accumulator, Sums};
use super::variational::{state_of, Aug, Variational};
use super::CHORD_STEPS;
use super::{multipliers, Forcing, Orbit, OrbitError, OrbitSummary, Parameter, ShootingConfig};

/// The mode a state is in when an integration starts from it: in contact past a compliant
/// stop, else free.
pub fn mode_of(model: &Harvester<Sine>, y: &State) -> Mode {
    for side in Side::BOTH {
        if model.penetration(side, y[0]) > 0.0
            && matches!(model.stop(side), Some(StopModel::Compliant { .. }))
        {
            return Mode::Contact(side);
        }
    }
    Mode::Free
}

/// The period map and its derivatives at one point: P(y), M = dP/dy and dP/dp (physical
/// units).
#[derive(Debug, Clone, Copy)]
pub struct Linearised {
    /// P(y).
    pub end: State,
    /// dP/dy.
    pub monodromy: Matrix4<f64>,
    /// dP/dp.
    pub dp: Vector4<f64>,
}

/// Shooting for periodic orbits of one device.
#[derive(Debug, Clone)]
pub struct Shooter<'a> {
    /// The device model (its excitation is replaced for every drive).
    pub base: &'a Harvester<Sine>,
    /// Settings.
    pub cfg: ShootingConfig,
    scales: State,
}

impl<'a> Shooter<'a> {
    /// Shooting on `base` (its excitation is ignored) with settings `cfg`.
    pub fn new(base: &'a Harvester<Sine>, cfg: ShootingConfig) -> Self {
        Self::with_scales(base, cfg, base.scales())
    }

    /// Shooting with given state scales (e.g. those of another model of the same device).
    pub fn with_scales(base: &'a Harvester<Sine>, cfg: ShootingConfig, scales: State) -> Self {
        Self { base, cfg, scales }
    }

    /// The state scales of the scaled coordinates.
    pub fn scales(&self) -> State {
        self.scales
    }

    /// The model under a drive with drive phase `phase_rad` at t = 0.
    pub fn model(&self, forcing: &Forcing, phase_rad: f64) -> Harvester<Sine> {
        self.base.with_excitation(forcing.sine(phase_rad))
    }

    /// The scaled Euclidean norm of a state.
    pub fn norm(&self, y: &State) -> f64 {
        y.component_div(&self.scales).norm()
    }

    fn solver_err(&self, p: Parameter, forcing: &Forcing, e: SolverError) -> OrbitError {
        OrbitError::Solver {
            what: p.label(),
            param: forcing.get(p),
            source: e,
        }
    }

    /// Integrates from `y` at drive phase `phase_rad` for `duration_s`, calling `observer`
    /// with every accepted step; returns the final state and mode and the counters.
    pub fn flow<O: FnMut(&Step<State>, Mode)>(
        &self,
        forcing: &Forcing,
        phase_rad: f64,
        y: State,
        duration_s: f64,
        observer: O,
    ) -> Result<(State, Mode, Stats), SolverError> {
        let model = self.model(forcing, phase_rad);
        let mut ode = SineFlow::new(&model, 0.0, y, mode_of(&model, &y), self.cfg.rtol);
        ode.integrate(duration_s, observer)?;
        Ok((ode.y(), ode.mode(), ode.stats()))
    }

    /// The plain period map P(y) (4-dimensional integration).
    pub fn period_map(
        &self,
        forcing: &Forcing,
        phase_rad: f64,
        y: State,
    ) -> Result<State, SolverError> {
        self.flow(forcing, phase_rad, y, forcing.period_s(), |_, _| {})
            .map(|r| r.0)
    }

    /// P(y), dP/dy and dP/dp by the variational equations (see the module docs); `stats`
    /// accumulates the integrator's counters.
    pub fn linearise(
        &self,
        forcing: &Forcing,
        param: Parameter,
        phase_rad: f64,
        y: State,
        stats: &mut Stats,
    ) -> Result<Linearised, SolverError> {
        self.linearise_over(forcing, param, phase_rad, y, forcing.period_s(), stats)
    }

    /// As [`Shooter::linearise`] for the flow over `duration_s` instead of one period (the
    /// half-period map of a symmetric orbit): the end state, its derivative with respect to
    /// the start state, and with respect to the parameter (for the frequency at a fixed
    /// fraction of the period, `duration_s * f` fixed).
    pub fn linearise_over(
        &self,
        forcing: &Forcing,
        param: Parameter,
        phase_rad: f64,
        y: State,
        duration_s: f64,
        stats: &mut Stats,
    ) -> Result<Linearised, SolverError> {
        let model = self.model(forcing, phase_rad);
        let sys = Variational {
            model: &model,
            param,
        };
        let base = model.solver_options(self.cfg.rtol);
        let p_ref = forcing.get(param).abs().max(1e-300);
        let mut atol = Aug::zeros();
        let mut z0 = Aug::zeros();
        for i in 0..4 {
            z0[i] = y[i];
            for j in 0..4 {
                // Phi_ij is of order s_i / s_j.
                atol[4 + i + 4 * j] = self.cfg.rtol * self.scales[i] / self.scales[j];
            }
            z0[4 + 5 * i] = 1.0;
            atol[20 + i] = self.cfg.rtol * self.scales[i] / p_ref;
        }
        let opts = base.augmented(atol);
        let mut ode = Engine::new(&sys, 0.0, z0, mode_of(&model, &y), opts, true);
        let period = forcing.period_s();
        ode.integrate_observed(duration_s, &mut crate::ode::Steps(|_: &Step<Aug>, _| {}))?;
        *stats += ode.stats();
        let z = ode.z();
        let end = state_of(&z);
        let mut monodromy = Matrix4::from_column_slice(&z.as_slice()[4..20]);
        self.drop_unused(&mut monodromy);
        let mut dp = Vector4::new(z[20], z[21], z[22], z[23]);
        if param == Parameter::Frequency {
            // The end time t = c/f moves with the frequency: + f(y(t)) dt/df, dt/df = -t T.
            let f_end = model.rhs(ode.mode(), duration_s, &end);
            dp -= f_end * (duration_s * period);
        }
        Ok(Linearised { end, monodromy, dp })
    }

    /// The monodromy matrix in scaled coordinates by central differences of the plain period
    /// map, with steps of `eps` in each scaled coordinate (the check of the variational one).
    pub fn monodromy_fd(
        &self,
        forcing: &Forcing,
        phase_rad: f64,
        y: State,
        eps: f64,
    ) -> Result<Matrix4<f64>, SolverError> {
        let mut m = Matrix4::zeros();
        for c in 0..4 {
            let h = eps * self.scales[c];
            let (mut yp, mut ym) = (y, y);
            yp[c] += h;
            ym[c] -= h;
            let pp = self.period_map(forcing, phase_rad, yp)?;
            let pm = self.period_map(forcing, phase_rad, ym)?;
            let col = (pp - pm).component_div(&self.scales) / (2.0 * eps);
            m.set_column(c, &col);
        }
        self.drop_unused(&mut m);
        Ok(m)
    }

    /// Replaces the trivial multiplier 1 of each state component the transducer leaves unused
    /// (held at zero; its row and column of the monodromy are those of the identity) by 0, so
    /// that Newton's matrix M - I is regular and the Floquet tests see only the device's
    /// multipliers.
    fn drop_unused(&self, m: &mut Matrix4<f64>) {
        for i in self.base.active_states()..4 {
            m[(i, i)] = 0.0;
        }
    }

    /// Scales a physical monodromy to the scaled coordinates: D^-1 M D.
    pub fn scaled_monodromy(&self, m: &Matrix4<f64>) -> Matrix4<f64> {
        let mut out = *m;
        for i in 0..4 {
            for j in 0..4 {
                out[(i, j)] *= self.scales[j] / self.scales[i];
            }
        }
        out
    }

    /// One period of the plain map from `y` with the orbit's whole-period measures; returns
    /// (P(y), summary).
    pub fn measure(
        &self,
        forcing: &Forcing,
        phase_rad: f64,
        y: State,
        stats: &mut Stats,
    ) -> Result<(State, OrbitSummary), SolverError> {
        let model = self.model(forcing, phase_rad);
        let mut acc = Accumulator {
            model: &model,
            sums: Sums::default(),
        };
        let mut ode = SineFlow::new(&model, 0.0, y, mode_of(&model, &y), self.cfg.rtol);
        ode.integrate_observed(forcing.period_s(), &mut acc)?;
        let (end, st) = (ode.y(), ode.stats());
        let acc = acc.sums;
        *stats += st;
        let period = forcing.period_s();
        Ok((
            end,
            OrbitSummary {
                v1_rms_v: (acc.v1sq / period).sqrt(),
                v2_rms_v: (acc.v2sq / period).sqrt(),
                p_total_w: (acc.v1sq + acc.v2sq) / period / model.load_resistance(),
                x_max_m: acc.x_upper.max(-acc.x_lower),
                x_upper_m: acc.x_upper,
                x_lower_m: acc.x_lower,
                contact_fraction: acc.contact_time / period,
                impacts: acc.impacts,
                impact_speed_m_s: acc.impact_speed,
                upcrossing_s: acc.upcrossing,
            },
        ))
    }

    /// Newton's method for the periodic orbit of `forcing` with section at `phase_rad`, from
    /// `guess`; `param` names the parameter in errors (and is the one whose sensitivity is
    /// computed alongside). The orbit is accepted when the plain period map's residual is
    /// below [`ShootingConfig::residual_tol`].
    pub fn solve(
        &self,
        forcing: &Forcing,
        param: Parameter,
        phase_rad: f64,
        guess: State,
        stats: &mut Stats,
    ) -> Result<Orbit, OrbitError> {
        let err = |e| self.solver_err(param, forcing, e);
        let mut y = guess;
        let mut residual = f64::INFINITY;
        for it in 0..=self.cfg.max_newton {
            let lin = self
                .linearise(forcing, param, phase_rad, y, stats)
                .map_err(err)?;
            let g = (lin.end - y).component_div(&self.scales);
            residual = g.norm() / self.norm(&y).max(1e-300);
            let m = self.scaled_monodromy(&lin.monodromy);
            let lu = (m - Matrix4::identity()).lu();
            if residual < self.cfg.residual_tol {
                // The fixed point of the variational integration; polish it on the plain
                // period map (the one every reported residual refers to) by chord steps
                // with the same matrix: the two integrations differ by their global error,
                // a few rtol.
                for _ in 0..CHORD_STEPS {
                    let (end, summary) = self.measure(forcing, phase_rad, y, stats).map_err(err)?;
                    let gp = (end - y).component_div(&self.scales);
                    let plain = gp.norm() / self.norm(&y).max(1e-300);
                    if plain < self.cfg.residual_tol {
                        return self.orbit(forcing, param, phase_rad, y, m, plain, it, summary);
                    }
                    residual = plain;
                    let Some(dz) = lu.solve(&(-gp)) else { break };
                    y += dz.component_mul(&self.scales);
                }
                break;
            }
            if it == self.cfg.max_newton {
                break;
            }
            let Some(dz) = lu.solve(&(-g)) else {
                break;
            };
            y += dz.component_mul(&self.scales);
        }
        Err(OrbitError::NoConvergence {
            what: param.label(),
            param: forcing.get(param),
            iterations: self.cfg.max_newton,
            residual,
        })
    }

    /// Builds an orbit from a converged state.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn orbit(
        &self,
        forcing: &Forcing,
        param: Parameter,
        phase_rad: f64,
        y: State,
        monodromy: Matrix4<f64>,
        residual: f64,
        iterations: usize,
        summary: OrbitSummary,
    ) -> Result<Orbit, OrbitError> {
        let multipliers = multipliers(&monodromy).ok_or(OrbitError::Eigenvalues {
            what: param.label(),
            param: forcing.get(param),
        })?;
        Ok(Orbit {
            forcing: *forcing,
            phase_rad,
            state: y,
            monodromy,
            multipliers,
            residual,
            iterations,
            summary,
        })
    }

    /// True when the orbit's section lies well inside free flight (at most half the gap from
    /// rest towards either stop).
    pub fn section_is_free(&self, orbit: &Orbit) -> bool {
        let x = orbit.state[0];
        x <= 0.5 * self.base.gap(Side::Upper) && -x <= 0.5 * self.base.gap(Side::Lower)
    }

    /// The same orbit cut at the drive phase where x crosses zero upwards (see the module
    /// docs), polished by Newton at the new section. Returns the orbit unchanged when it has
    /// no upward zero crossing.
    pub fn reanchor(
        &self,
        orbit: &Orbit,
        param: Parameter,
        stats: &mut Stats,
    ) -> Result<Orbit, OrbitError> {
        let Some(t) = orbit.summary.upcrossing_s else {
            return Ok(orbit.clone());
        };
        let f = &orbit.forcing;
        let (y, _, st) = self
            .flow(f, orbit.phase_rad, orbit.state, t, |_, _| {})
            .map_err(|e| self.solver_err(param, f, e))?;
        *stats += st;
        let w = 2.0 * std::f64::consts::PI * f.freq_hz;
        let phase = (orbit.phase_rad + w * t).rem_euclid(2.0 * std::f64::consts::PI);
        self.solve(f, param, phase, y, stats)
    }

    /// The state of an orbit at drive phase `phase_rad` (integrated from its section).
    pub fn state_at_phase(&self, orbit: &Orbit, phase_rad: f64) -> Result<State, SolverError> {
        let f = &orbit.forcing;
        let w = 2.0 * std::f64::consts::PI * f.freq_hz;
        let dphi = (phase_rad - orbit.phase_rad).rem_euclid(2.0 * std::f64::consts::PI);
        let t = dphi / w;
        if t == 0.0 {
            return Ok(orbit.state);
        }
        self.flow(f, orbit.phase_rad, orbit.state, t, |_, _| {})
            .map(|r| r.0)
    }
}
