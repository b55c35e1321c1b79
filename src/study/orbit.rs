//! Periodic orbits of the harvester under a sinusoidal drive, by shooting on the period map,
//! with their Floquet multipliers.
//!
//! # The period map and its section
//! For a drive a(t) = sqrt(2) a_rms sin(2 pi f t + phi), the period map P takes the state at
//! drive phase phi to the state one drive period T = 1/f later, integrated by the
//! event-locating [`Dopri5`] (through its public API: a new integrator per evaluation, so that
//! an evaluation never depends on the ones before). A periodic orbit is a fixed point
//! P(y) = y, found by Newton's method.
//!
//! The section (the drive phase phi at which the orbit is cut) must lie in free flight: the
//! end-stop force switches on at the stop, so a section that cuts the orbit in contact would
//! make P non-differentiable there and Newton would stall. Each [`Orbit`] therefore carries its
//! own section phase, and [`Shooter::reanchor`] moves it to the drive phase where x crosses
//! zero upwards (the orbit's fastest point, as far from both stops as it gets).
//!
//! Newton works in scaled coordinates z = y / s with s = [`Harvester::scales`] (x ~ xmax,
//! v ~ w0 xmax, charges ~ C0 Vb xmax / x0), so that every component is of order one.
//!
//! # The monodromy matrix
//! The monodromy matrix M = dP/dy is computed by the **variational equations** integrated
//! alongside the state: Phi' = J(y) Phi with Phi(0) = I, J the Jacobian of the mode's
//! right-hand side ([`Harvester::jacobian`]), and at every contact entry and exit the
//! saltation matrix
//!
//! S = I + (f+ - f-) n^T / (n . f-),
//!
//! with f- and f+ the vector fields before and after the switch and n the gradient of the guard
//! that fired (the end-stop damper switches on at the stop, so the acceleration jumps by
//! b_im v / m there and S is not the identity). The sensitivity to the continuation parameter,
//! dP/dp, rides along as a fifth column (with the end-time term f(y(T)) dT/dp for the
//! frequency). Why this choice rather than finite differences through the event-located
//! integration: one integration of the 24-dimensional system gives M and dP/dp to the
//! integrator's tolerance, whereas central differences need eight integrations and are accurate
//! only to about rtol/eps. Finite differences are kept as the check
//! ([`Shooter::monodromy_fd`]); the tests compare the two on impacting orbits.
//!
//! The Floquet multipliers are the eigenvalues of M; an orbit is stable when every multiplier
//! lies inside the unit circle.

use nalgebra::{Complex, Matrix4, SVector, Vector4};
use thiserror::Error;

use crate::drive::Sine;
use crate::num::roots::{illinois, RootOptions, Sample};
use crate::ode::{Dopri5, HybridSystem, Observer, SolverError, Stats, Step};
use crate::physics::contact::{Mode, Side, StopModel};
use crate::physics::harvester::{reset_jacobian, Harvester, State, SwitchKind};

/// Dimension of the state with its variational equations: 4 + 16 (monodromy) + 4 (dP/dp).
pub const VARIATIONAL_DIM: usize = 24;

/// The parameter a continuation varies.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Parameter {
    /// Drive frequency (Hz).
    Frequency,
    /// RMS acceleration (g).
    Amplitude,
}

impl Parameter {
    /// Label with unit, for messages.
    pub fn label(self) -> &'static str {
        match self {
            Parameter::Frequency => "frequency (Hz)",
            Parameter::Amplitude => "RMS acceleration (g)",
        }
    }
}

/// A sinusoidal drive: frequency and RMS acceleration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Forcing {
    /// Frequency (Hz).
    pub freq_hz: f64,
    /// RMS acceleration (g).
    pub accel_rms_g: f64,
}

impl Forcing {
    /// The value of a parameter.
    pub fn get(&self, p: Parameter) -> f64 {
        match p {
            Parameter::Frequency => self.freq_hz,
            Parameter::Amplitude => self.accel_rms_g,
        }
    }

    /// The same drive with one parameter changed.
    pub fn with(&self, p: Parameter, value: f64) -> Self {
        let mut f = *self;
        match p {
            Parameter::Frequency => f.freq_hz = value,
            Parameter::Amplitude => f.accel_rms_g = value,
        }
        f
    }

    /// Drive period (s).
    pub fn period_s(&self) -> f64 {
        1.0 / self.freq_hz
    }

    /// The sine with drive phase `phase_rad` at t = 0.
    pub fn sine(&self, phase_rad: f64) -> Sine {
        Sine {
            phase_rad,
            ..Sine::from_rms_g(self.accel_rms_g, self.freq_hz)
        }
    }
}

/// Settings of the shooting method.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShootingConfig {
    /// Integrator relative tolerance (absolute tolerances are `rtol` times the state scales).
    pub rtol: f64,
    /// An orbit is accepted when |P(y) - y| / |y| (scaled, plain period map) is below this.
    pub residual_tol: f64,
    /// Largest number of Newton iterations.
    pub max_newton: usize,
}

impl Default for ShootingConfig {
    /// rtol 1e-10: the orbit is then accurate to about 1e-9 (the global error of the
    /// integration is some 15 rtol relative), and Newton drives the residual of the period map
    /// itself below 5e-10 (on smooth stretches of a branch it reaches 1e-14; near grazing,
    /// where the event times make the map less smooth, the noise of the map is near 1e-10).
    fn default() -> Self {
        Self {
            rtol: 1e-10,
            residual_tol: 5e-10,
            max_newton: 12,
        }
    }
}

impl ShootingConfig {
    /// Half the integrator tolerance (for convergence checks).
    pub fn halved(&self) -> Self {
        Self {
            rtol: 0.5 * self.rtol,
            ..*self
        }
    }
}

/// Failures of shooting and continuation, each with the parameter value last reached.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum OrbitError {
    /// The integrator failed.
    #[error("integration failed at {what} = {param}: {source}")]
    Solver {
        /// What the parameter is.
        what: &'static str,
        /// Parameter value.
        param: f64,
        /// The integrator's error.
        source: SolverError,
    },
    /// Newton's method did not reach the residual tolerance.
    #[error("Newton did not converge at {what} = {param} after {iterations} iterations (residual {residual:e})")]
    NoConvergence {
        /// What the parameter is.
        what: &'static str,
        /// Parameter value.
        param: f64,
        /// Iterations made.
        iterations: usize,
        /// Last scaled residual |P(y) - y| / |y|.
        residual: f64,
    },
    /// The Floquet multipliers could not be computed (the Schur iteration failed).
    #[error("no eigenvalues of the monodromy matrix at {what} = {param}")]
    Eigenvalues {
        /// What the parameter is.
        what: &'static str,
        /// Parameter value.
        param: f64,
    },
    /// The continuation's step fell below its minimum: the branch cannot be followed further.
    #[error("the branch cannot be continued past {what} = {last_param} (step below {ds_min:e})")]
    Stalled {
        /// What the parameter is.
        what: &'static str,
        /// The last parameter value reached on the branch.
        last_param: f64,
        /// The smallest step allowed.
        ds_min: f64,
    },
    /// The continuation used its whole budget of points inside the range.
    #[error("the continuation used all {points} points and stopped at {what} = {last_param}")]
    TooManyPoints {
        /// What the parameter is.
        what: &'static str,
        /// The last parameter value reached.
        last_param: f64,
        /// The budget.
        points: usize,
    },
    /// Bad input.
    #[error("invalid input: {0}")]
    Invalid(String),
}

/// Whole-period measures of an orbit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OrbitSummary {
    /// RMS voltage of load 1 (V).
    pub v1_rms_v: f64,
    /// RMS voltage of load 2 (V).
    pub v2_rms_v: f64,
    /// Mean power of both loads (W).
    pub p_total_w: f64,
    /// Largest |x| over the period (m), at a zero of v located on the dense output.
    pub x_max_m: f64,
    /// Largest x (m).
    pub x_upper_m: f64,
    /// Smallest x (m).
    pub x_lower_m: f64,
    /// Fraction of the period past a stop.
    pub contact_fraction: f64,
    /// Impacts per period: contact entries and rebounds off rigid stops.
    pub impacts: u32,
    /// The largest speed at which the mass strikes each side's rigid stop (upper, lower; m/s),
    /// zero where it does not: a rigid stop is never penetrated, so this, not the largest
    /// displacement, says how deep an orbit is past grazing.
    pub impact_speed_m_s: [f64; 2],
    /// Time after the section at which x first crosses zero upwards (s), if it does.
    pub upcrossing_s: Option<f64>,
}

/// A periodic orbit with its stability.
#[derive(Debug, Clone, PartialEq)]
pub struct Orbit {
    /// The drive.
    pub forcing: Forcing,
    /// Drive phase at the section (rad).
    pub phase_rad: f64,
    /// State at the section.
    pub state: State,
    /// Monodromy matrix in scaled coordinates (z = y / scales).
    pub monodromy: Matrix4<f64>,
    /// Floquet multipliers, largest modulus first (a state component the transducer leaves
    /// unused contributes a multiplier 0).
    pub multipliers: [Complex<f64>; 4],
    /// |P(y) - y| / |y| of the plain period map (scaled coordinates).
    pub residual: f64,
    /// Newton iterations used.
    pub iterations: usize,
    /// Whole-period measures.
    pub summary: OrbitSummary,
}

impl Orbit {
    /// Largest modulus of the multipliers.
    pub fn max_multiplier_abs(&self) -> f64 {
        self.multipliers[0].norm()
    }

    /// True when every multiplier lies inside the unit circle.
    pub fn is_stable(&self) -> bool {
        self.max_multiplier_abs() < 1.0
    }

    /// True when the orbit touches a stop.
    pub fn is_impacting(&self) -> bool {
        self.summary.impacts > 0
    }

    /// The parameter's value.
    pub fn param(&self, p: Parameter) -> f64 {
        self.forcing.get(p)
    }

    /// prod (mu_i - 1), real: changes sign where a real multiplier crosses +1.
    pub fn det_minus_one(&self) -> f64 {
        self.multipliers
            .iter()
            .fold(Complex::new(1.0, 0.0), |acc, &m| acc * (m - 1.0))
            .re
    }

    /// prod (mu_i + 1), real: changes sign where a real multiplier crosses -1.
    pub fn det_plus_one(&self) -> f64 {
        self.multipliers
            .iter()
            .fold(Complex::new(1.0, 0.0), |acc, &m| acc * (m + 1.0))
            .re
    }

    /// Number of multipliers outside the unit circle.
    pub fn unstable_count(&self) -> usize {
        self.multipliers.iter().filter(|m| m.norm() > 1.0).count()
    }
}

/// Chord steps on the plain period map after Newton has converged on the variational one.
pub const CHORD_STEPS: usize = 4;

/// The harvester with its variational equations (state, monodromy, parameter sensitivity).
struct Variational<'a> {
    model: &'a Harvester<Sine>,
    param: Parameter,
}

type Aug = SVector<f64, VARIATIONAL_DIM>;

fn state_of(z: &Aug) -> State {
    State::new(z[0], z[1], z[2], z[3])
}

impl Variational<'_> {
    /// d a(t) / dp for the drive (m/s^2 per Hz or per g).
    fn drive_sensitivity(&self, t: f64) -> f64 {
        let s = &self.model.excitation;
        let w = 2.0 * std::f64::consts::PI * s.freq_hz;
        let arg = w * t + s.phase_rad;
        match self.param {
            Parameter::Frequency => s.amplitude_m_s2 * arg.cos() * 2.0 * std::f64::consts::PI * t,
            Parameter::Amplitude => std::f64::consts::SQRT_2 * crate::G * arg.sin(),
        }
    }
}

impl HybridSystem<VARIATIONAL_DIM> for Variational<'_> {
    type Mode = Mode;

    #[inline]
    fn rhs(&self, mode: Mode, t: f64, z: &Aug) -> Aug {
        let y = state_of(z);
        let f = self.model.rhs(mode, t, &y);
        let j = self.model.jacobian(mode, &y);
        let mut out = Aug::zeros();
        out.fixed_rows_mut::<4>(0).copy_from(&f);
        for c in 0..5 {
            let col = Vector4::new(z[4 + 4 * c], z[5 + 4 * c], z[6 + 4 * c], z[7 + 4 * c]);
            let d = j * col;
            out.fixed_rows_mut::<4>(4 + 4 * c).copy_from(&d);
        }
        out[21] += self.drive_sensitivity(t);
        out
    }

    fn guards(&self, mode: Mode, t: f64, z: &Aug) -> crate::ode::Guards {
        self.model.guards(mode, t, &state_of(z))
    }

    // ANCHOR: saltation
    fn switch(&self, mode: Mode, index: usize, t: f64, z: &mut Aug) -> Mode {
        let y = state_of(z);
        let f_old = self.model.rhs(mode, t, &y);
        let (n, g_t) = guard_gradient(self.model, mode, index, t, &y);
        let mut y_new = y;
        let new_mode = self.model.switch(mode, index, t, &mut y_new);
        let f_new = self.model.rhs(new_mode, t, &y_new);
        let denom = n.dot(&f_old) + g_t;
        z.fixed_rows_mut::<4>(0).copy_from(&y_new);
        if denom != 0.0 && denom.is_finite() {
            let kind = SwitchKind::of(mode, new_mode);
            if matches!(kind, SwitchKind::Rebound | SwitchKind::Stick) {
                // A reset y+ = R(y-) with Jacobian D: S = D + (f+ - D f-) n^T / (dg/dt).
                let d = reset_jacobian(mode, new_mode, self.model.restitution(index));
                let df = (f_new - d * f_old) / denom;
                for c in 0..5 {
                    let base = 4 + 4 * c;
                    let col = Vector4::new(z[base], z[base + 1], z[base + 2], z[base + 3]);
                    let upd = d * col + df * n.dot(&col);
                    z.fixed_rows_mut::<4>(base).copy_from(&upd);
                }
            } else {
                // S = I + (f+ - f-) n^T / (dg/dt), applied to every sensitivity column.
                let df = (f_new - f_old) / denom;
                for c in 0..5 {
                    let base = 4 + 4 * c;
                    let col = Vector4::new(z[base], z[base + 1], z[base + 2], z[base + 3]);
                    let upd = col + df * n.dot(&col);
                    z.fixed_rows_mut::<4>(base).copy_from(&upd);
                }
            }
        }
        new_mode
    }
    // ANCHOR_END: saltation

    fn next_breakpoint(&self, t: f64) -> f64 {
        self.model.next_breakpoint(t)
    }

    fn check_state(&self, mode: Mode, t: f64, z: &Aug) -> Result<(), String> {
        self.model.check_state(mode, t, &state_of(z))
    }
}

/// Gradient of guard `index` of `mode` in the state and its explicit time derivative, by
/// central differences (the stops' guards are linear in the state or smooth and do not depend
/// on time, so this is exact to rounding there; a stuck mass's guard, the holding force,
/// follows the drive in time). The saltation's denominator is the guard's total rate,
/// `n . f + dg/dt`.
fn guard_gradient(
    model: &Harvester<Sine>,
    mode: Mode,
    index: usize,
    t: f64,
    y: &State,
) -> (Vector4<f64>, f64) {
    let sc = model.scales();
    let mut n = Vector4::zeros();
    for c in 0..4 {
        let h = 1e-6 * sc[c];
        let (mut yp, mut ym) = (*y, *y);
        yp[c] += h;
        ym[c] -= h;
        n[c] = (model.guards(mode, t, &yp)[index] - model.guards(mode, t, &ym)[index]) / (2.0 * h);
    }
    let g_t = if let Mode::Stuck(_) = mode {
        let ht = 1e-6 / (model.km / model.mass_kg).sqrt();
        (model.guards(mode, t + ht, y)[index] - model.guards(mode, t - ht, y)[index]) / (2.0 * ht)
    } else {
        0.0
    };
    (n, g_t)
}

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
    pub fn flow<O: FnMut(&Step<4>, Mode)>(
        &self,
        forcing: &Forcing,
        phase_rad: f64,
        y: State,
        duration_s: f64,
        observer: O,
    ) -> Result<(State, Mode, Stats), SolverError> {
        let model = self.model(forcing, phase_rad);
        let mut ode = Dopri5::new(
            0.0,
            y,
            mode_of(&model, &y),
            model.solver_options(self.cfg.rtol),
        );
        ode.integrate(&model, duration_s, observer)?;
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
        let mut ode = Dopri5::new(0.0, z0, mode_of(&model, &y), opts);
        let period = forcing.period_s();
        ode.integrate(&sys, period, |_, _| {})?;
        *stats += ode.stats();
        let z = ode.y();
        let end = state_of(&z);
        let mut monodromy = Matrix4::from_column_slice(&z.as_slice()[4..20]);
        self.drop_unused(&mut monodromy);
        let mut dp = Vector4::new(z[20], z[21], z[22], z[23]);
        if param == Parameter::Frequency {
            // The period T = 1/f moves with the frequency: + f(y(T)) dT/df.
            let f_end = model.rhs(ode.mode(), period, &end);
            dp -= f_end * (period * period);
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
        let mut ode = Dopri5::new(
            0.0,
            y,
            mode_of(&model, &y),
            model.solver_options(self.cfg.rtol),
        );
        ode.integrate_observed(&model, forcing.period_s(), &mut acc)?;
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

/// The eigenvalues of a monodromy matrix, largest modulus first (None if the Schur iteration
/// fails).
pub fn multipliers(m: &Matrix4<f64>) -> Option<[Complex<f64>; 4]> {
    let schur = nalgebra::Schur::try_new(*m, f64::EPSILON, 10_000)?;
    let ev = schur.complex_eigenvalues();
    let mut out = [ev[0], ev[1], ev[2], ev[3]];
    out.sort_by(|a, b| b.norm().total_cmp(&a.norm()));
    Some(out)
}

/// Whole-period sums over the accepted steps of one period.
#[derive(Debug, Default)]
struct Sums {
    v1sq: f64,
    v2sq: f64,
    x_upper: f64,
    x_lower: f64,
    contact_time: f64,
    impacts: u32,
    was_contact: Option<bool>,
    upcrossing: Option<f64>,
    /// The velocity at the end of the last step (before a switch, the impact velocity).
    last_v: f64,
    impact_speed: [f64; 2],
}

/// Observes one period: the sums over its steps, and the rebounds off rigid stops (impacts
/// without a contact phase, seen only as switches).
struct Accumulator<'m> {
    model: &'m Harvester<Sine>,
    sums: Sums,
}

impl Observer<4, Mode> for Accumulator<'_> {
    fn step(&mut self, st: &Step<4>, mode: Mode) {
        self.sums.add(self.model, st, mode);
    }

    fn switched(&mut self, _t: f64, from: Mode, to: Mode) {
        let kind = SwitchKind::of(from, to);
        if kind == SwitchKind::Rebound {
            self.sums.impacts += 1;
        }
        if matches!(kind, SwitchKind::Rebound | SwitchKind::Stick) {
            let v = self.sums.last_v;
            let side = usize::from(v < 0.0);
            self.sums.impact_speed[side] = self.sums.impact_speed[side].max(v.abs());
        }
    }
}

impl Sums {
    fn add(&mut self, model: &Harvester<Sine>, st: &Step<4>, mode: Mode) {
        let el = |y: &State| model.electrical(y).v;
        self.v1sq += st.integrate(|y| el(y)[0].powi(2));
        self.v2sq += st.integrate(|y| el(y)[1].powi(2));
        for x in [st.y0[0], st.y1[0]] {
            self.x_upper = self.x_upper.max(x);
            self.x_lower = self.x_lower.min(x);
        }
        // An extremum of x inside the step: a zero of v on the dense output.
        if (st.y0[1] > 0.0) != (st.y1[1] > 0.0) {
            if let Some(th) = root_on_step(st, 1) {
                let x = st.at_theta(th)[0];
                self.x_upper = self.x_upper.max(x);
                self.x_lower = self.x_lower.min(x);
            }
        }
        if self.upcrossing.is_none() && st.y0[0] <= 0.0 && st.y1[0] > 0.0 {
            self.upcrossing = root_on_step(st, 0).map(|th| st.t0 + th * st.h);
        }
        self.last_v = st.y1[1];
        let contact = mode.in_contact();
        if contact {
            self.contact_time += st.h;
            if self.was_contact == Some(false) {
                self.impacts += 1;
            }
        }
        self.was_contact = Some(contact);
    }
}

/// theta in [0, 1] where component `c` of the dense output of `st` changes sign (the upper
/// end of the final bracket), located by the crate's root finder to 1e-12 of the step.
fn root_on_step(st: &Step<4>, c: usize) -> Option<f64> {
    let f =
        |th: f64| -> Result<(f64, ()), std::convert::Infallible> { Ok((st.at_theta(th)[c], ())) };
    let (a, b) = (
        Sample::new(0.0, st.y0[c], ()),
        Sample::new(1.0, st.y1[c], ()),
    );
    let opts = RootOptions {
        f_tol: None,
        x_tol_abs: 1e-12,
        x_tol_rel: 0.0,
        max_iter: 100,
    };
    illinois(f, a, b, &opts).ok().map(|r| r.positive.x)
}
