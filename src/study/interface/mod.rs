//! Studies of a harvester with an interface circuit ([`crate::physics::interface`]): the
//! periodic steady state under a sine, found by shooting on the period map, with its DC voltage
//! and power, its stability and its energy ledger ([`steady_state`]); sweeps of it over
//! frequency or load ([`sweep`]); the charging of the storage ([`charging`]); and random or
//! measured records and their ensembles ([`record`]).
//!
//! # Why shooting
//! The storage capacitor and its load have a time constant `R_L C_s` that can be hundreds of
//! the drive's periods. Integrating until two successive periods differ by little stops far
//! from the steady state when the approach is that slow; Newton's method on the period map
//! `P(y) - y = 0` does not care how slow the approach is. The map's Jacobian is the monodromy
//! through saltation matrices ([`monodromy`]; forward differences of the period map are the
//! alternative, [`JacobianKind`]), and the converged orbit's Floquet multipliers are its
//! eigenvalues. The section is at the drive's phase zero.
//!
//! Far from the orbit the residual `P(y) - y` is a poor measure of the distance to it: along a
//! mode with multiplier `mu` it is `(1 - mu)` times the distance, so with multipliers near 1 a
//! Newton step towards the orbit can raise it. Damping that asks the residual to fall at each
//! step creeps and stalls near 1e-2 on the example cantilever with SSHI at large loads
//! (parallel SSHI from 41.7 kohm, series SSHI from 100 kohm at 0.3 g and 120 Hz, multipliers
//! of modulus 0.92 to 0.98), where the period map is smooth (its differences match the
//! monodromy) and undamped Newton converges in 7 steps. The steps are damped instead by the
//! natural monotonicity test, which measures the distance by the Newton correction (see
//! [`steady_state`]).
//!
//! Where Newton's method still does not converge, the period map is iterated from the
//! transient's end until the change per period, divided by `1 - |mu|` for the slowest
//! multiplier estimated from the contraction of the changes, is below the tolerance: the
//! estimate of the distance to the orbit that accounts for the slow approach. On the example
//! cantilever at 1 g this finds the first point of an up-sweep past the upper fold, where the
//! start (the orbit on the upper branch) is far from the orbit, and points far above resonance
//! where the bridge no longer conducts and the largest multiplier is 1 to six digits (a
//! neutral direction along which `M - I` is singular; why the multiplier is 1 there is not
//! analysed). The fallback reaches only orbits the map contracts to from the start (stable
//! ones). Each steady state says which method found it ([`SteadyMethod`]).

pub mod charging;
pub mod continuation;
mod linear_modes;
pub mod monodromy;
pub mod record;
pub mod sweep;

use nalgebra::{Matrix4, Vector4};
use thiserror::Error;

use crate::device::Device;
use crate::drive::Sine;
use crate::ode::{Dopri5, Observer, SolverError, Stats, Step};
use crate::physics::harvester::State;
use crate::physics::interface::{
    audit_start, IfAuditState, IfMode, InterfaceAudit, InterfaceLedger, Interfaced,
};
use crate::study::orbit::multipliers;

/// A failed study of a device with an interface.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum InterfaceError {
    /// The device's interface is resistive: the resistive studies apply.
    #[error("device `{0}` has a resistive load, not an interface circuit")]
    Resistive(String),
    /// The storage has no load: it only charges, and there is no periodic steady state.
    #[error(
        "device `{0}`: the storage has an open load (interface.load.kind = \"open\"), so it \
         charges towards the open-circuit limit and has no periodic steady state; use the \
         charging study"
    )]
    OpenLoad(String),
    /// The integrator failed.
    #[error("integration failed: {0}")]
    Solver(#[from] SolverError),
    /// A conduction mode is too stiff for the explicit integrator: its time constant is below
    /// [`STIFF_LIMIT`] of the suspension's period.
    #[error(
        "device `{name}`: a conduction mode's time constant {tau_s:e} s is below {STIFF_LIMIT:e} \
         of the suspension's period {period_s:e} s: the integrator would take more than \
         1e5 steps a period; use interface.diode.on_resistance_ohm = 0 (ideal with a drop) or \
         a larger one"
    )]
    Stiff {
        /// The device.
        name: String,
        /// The time constant (s).
        tau_s: f64,
        /// The suspension's period (s).
        period_s: f64,
    },
    /// The drive could not be made.
    #[error("drive: {0}")]
    Drive(String),
    /// Newton's method did not converge.
    #[error(
        "shooting did not converge in {iterations} Newton steps (scaled residual {residual:e}, \
         tolerance {tol:e})"
    )]
    NoConvergence {
        /// Newton steps taken.
        iterations: usize,
        /// Last scaled residual.
        residual: f64,
        /// Tolerance.
        tol: f64,
    },
}

/// The smallest conduction time constant accepted, relative to the suspension's period.
pub const STIFF_LIMIT: f64 = 1e-5;

/// Refuses a device whose conduction modes are too stiff (see [`InterfaceError::Stiff`]).
pub fn check_stiffness<E: crate::drive::Excitation>(
    device: &Device,
    model: &Interfaced<E>,
) -> Result<(), InterfaceError> {
    let period_s = 2.0 * std::f64::consts::PI / device.suspension_omega_rad_s();
    let tau_s = model.circuit.conduction_time_constant_s();
    if tau_s < STIFF_LIMIT * period_s {
        return Err(InterfaceError::Stiff {
            name: device.name.clone(),
            tau_s,
            period_s,
        });
    }
    Ok(())
}

/// Settings of the steady-state search.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SteadySettings {
    /// Integrator relative tolerance.
    pub rtol: f64,
    /// Periods integrated from the start before Newton's method.
    pub transient_periods: usize,
    /// Most Newton steps.
    pub max_newton: usize,
    /// Convergence: the largest scaled component of `P(y) - y`.
    pub tol: f64,
    /// How Newton's method takes the period map's Jacobian.
    pub jacobian: JacobianKind,
    /// Most periods of the period map iterated when Newton's method does not converge
    /// ([`SteadyMethod::PeriodMap`]).
    pub max_map_periods: usize,
}

/// How the period map's Jacobian is taken.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum JacobianKind {
    /// By the variational equations with saltation matrices ([`monodromy::linearise`]):
    /// exact to the integrator's tolerance, one augmented integration.
    #[default]
    Saltation,
    /// By forward differences of the period map ([`monodromy_differences`]): four more
    /// periods, accurate to about `rtol / 1e-6` relative.
    Differences,
}

impl Default for SteadySettings {
    fn default() -> Self {
        Self {
            rtol: 1e-9,
            transient_periods: 30,
            max_newton: 12,
            tol: 1e-7,
            jacobian: JacobianKind::Saltation,
            max_map_periods: 20_000,
        }
    }
}

/// The periodic steady state of a device with an interface, measured over one period.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct IfSteady {
    /// Drive frequency (Hz).
    pub freq_hz: f64,
    /// State at the section (phase zero).
    pub state: [f64; 4],
    /// Mean storage voltage over the period (V).
    pub vdc_v: f64,
    /// Mean power into the DC load or battery (W).
    pub p_dc_w: f64,
    /// Peak-to-peak storage voltage ripple (V).
    pub ripple_v: f64,
    /// Amplitude of the displacement's fundamental (m).
    pub x1_m: f64,
    /// Largest |x| (m).
    pub x_peak_m: f64,
    /// Relative RMS of the displacement's harmonics beyond the fundamental: its distortion.
    pub x_distortion: f64,
    /// True when the mass touched a stop.
    pub contact: bool,
    /// Largest Floquet multiplier modulus.
    pub max_multiplier: f64,
    /// Newton steps taken.
    pub newton_steps: usize,
    /// Final scaled residual of `P(y) - y`.
    pub residual: f64,
    /// The energy ledger over the measured period (J).
    pub ledger: InterfaceLedger,
    /// How the steady state was found.
    pub method: SteadyMethod,
}

/// How a steady state was found.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum SteadyMethod {
    /// Newton's method on the period map converged.
    Newton,
    /// Newton's method did not converge, and the period map iterated from the transient's end
    /// did, in this many periods: the change per period divided by `1 - |mu|`, for the slowest
    /// multiplier estimated by the mean contraction over the last [`MAP_WINDOW`] periods, fell
    /// below the tolerance (the distance to the orbit of a linear contraction by `|mu|`).
    PeriodMap {
        /// Periods iterated.
        periods: usize,
    },
}

impl SteadyMethod {
    /// A short name: `newton` or `period map`.
    pub fn label(&self) -> &'static str {
        match self {
            Self::Newton => "newton",
            Self::PeriodMap { .. } => "period map",
        }
    }
}

/// Periods over which [`SteadyMethod::PeriodMap`] estimates the slowest multiplier.
pub const MAP_WINDOW: usize = 20;

impl IfSteady {
    /// True when every Floquet multiplier is inside the unit circle (to 1e-6).
    pub fn is_stable(&self) -> bool {
        self.max_multiplier < 1.0 + 1e-6
    }
}

/// Integrates one period from (y, its start mode) at t0.
pub(crate) fn period_map(
    model: &Interfaced<Sine>,
    y: &State,
    t0: f64,
    period: f64,
    rtol: f64,
) -> Result<(State, IfMode, Stats), SolverError> {
    let mut ode = Dopri5::new(t0, *y, model.mode_of(y), model.solver_options(rtol));
    ode.integrate(model, t0 + period, |_, _| {})?;
    Ok((ode.y(), ode.mode(), ode.stats()))
}

/// The period map P(y) of `model` from phase zero at relative tolerance `rtol`.
pub fn period_map_of(model: &Interfaced<Sine>, y: &State, rtol: f64) -> Result<State, SolverError> {
    period_map(model, y, 0.0, model.h.excitation.period_s(), rtol).map(|r| r.0)
}

/// Observes a measured period.
struct Meter {
    t0: f64,
    w: f64,
    vs: f64,
    vs_min: f64,
    vs_max: f64,
    c1: f64,
    s1: f64,
    x0: f64,
    x2: f64,
    x_peak: f64,
    contact: bool,
}

impl Observer<IfAuditState, IfMode> for Meter {
    fn step(&mut self, st: &Step<IfAuditState>, m: IfMode) {
        let (t0, w) = (self.t0, self.w);
        self.vs += st.integrate(|z| z[3]);
        self.x0 += st.integrate(|z| z[0]);
        self.x2 += st.integrate(|z| z[0] * z[0]);
        // Fundamental by Gauss-Legendre on the dense output, the phase at the nodes.
        for (th, wt) in crate::ode::GAUSS_LEGENDRE_3 {
            let t = st.t0 + th * st.h;
            let x = st.at_theta(th)[0];
            self.c1 += wt * st.h * x * (w * (t - t0)).cos();
            self.s1 += wt * st.h * x * (w * (t - t0)).sin();
        }
        for z in [st.y1, st.at_theta(0.5)] {
            self.x_peak = self.x_peak.max(z[0].abs());
            self.vs_min = self.vs_min.min(z[3]);
            self.vs_max = self.vs_max.max(z[3]);
        }
        self.contact |= m.contact.in_contact();
    }
}

/// The model of `device` under `sine`, refused when it has no interface, a conduction mode too
/// stiff for the integrator, or no load (no steady state).
pub fn steady_model(device: &Device, sine: Sine) -> Result<Interfaced<Sine>, InterfaceError> {
    let model = Interfaced::new(device, sine)
        .ok_or_else(|| InterfaceError::Resistive(device.name.clone()))?;
    check_stiffness(device, &model)?;
    if matches!(model.circuit.sink, crate::physics::interface::Sink::Open) {
        return Err(InterfaceError::OpenLoad(device.name.clone()));
    }
    Ok(model)
}

/// The Jacobian of the period map by forward differences, scaled (one period per state
/// component, steps of 1e-6 of each scale): the check of [`monodromy::linearise`], and the
/// alternative [`JacobianKind::Differences`].
pub fn monodromy_differences(
    model: &Interfaced<Sine>,
    y: &State,
    p: &State,
    rtol: f64,
) -> Result<Matrix4<f64>, SolverError> {
    let period = model.h.excitation.period_s();
    let sc = model.scales();
    let mut jac = Matrix4::<f64>::zeros();
    for c in 0..4 {
        let e = 1e-6 * sc[c];
        let mut yp = *y;
        yp[c] += e;
        let (pp, _, _) = period_map(model, &yp, 0.0, period, rtol)?;
        jac.set_column(c, &((pp - p).component_div(&sc) / 1e-6));
    }
    Ok(jac)
}

/// The steady state of `device` under `sine`, starting from `start` at phase zero (rest, with
/// the storage at some voltage, or a neighbouring steady state); see the module docs for the
/// method.
pub fn steady_state(
    device: &Device,
    sine: Sine,
    start: &State,
    settings: &SteadySettings,
) -> Result<IfSteady, InterfaceError> {
    let model = steady_model(device, sine)?;
    let period = sine.period_s();
    let sc = model.scales();
    let mut y = *start;
    let mut ode = Dopri5::new(
        0.0,
        y,
        model.mode_of(&y),
        model.solver_options(settings.rtol),
    );
    ode.integrate(
        &model,
        settings.transient_periods as f64 * period,
        |_, _| {},
    )?;
    y = ode.y();
    let after_transient = y;
    let scaled = |d: &State| d.component_div(&sc);
    let mut newton_steps = 0;
    let (mut residual, mut jac);
    loop {
        // P(y) and the Jacobian of the scaled map.
        let p;
        (p, jac) = match settings.jacobian {
            JacobianKind::Saltation => {
                let lin = monodromy::linearise(&model, &y, settings.rtol)?;
                let s = Matrix4::from_diagonal(&sc);
                let si = Matrix4::from_diagonal(&sc.map(|v| 1.0 / v));
                (lin.end, si * lin.monodromy * s)
            }
            JacobianKind::Differences => {
                let (p, _, _) = period_map(&model, &y, 0.0, period, settings.rtol)?;
                (p, monodromy_differences(&model, &y, &p, settings.rtol)?)
            }
        };
        let f = scaled(&(p - y));
        residual = f.amax();
        if residual < settings.tol {
            break;
        }
        if newton_steps >= settings.max_newton {
            return iterate_map(&model, &after_transient, settings, newton_steps, residual);
        }
        let lu = (jac - Matrix4::identity()).lu();
        let newton = |f: &Vector4<f64>| -> Vector4<f64> { lu.solve(&(-f)).unwrap_or(-f) };
        let dy = newton(&f);
        // A damped step by the natural monotonicity test (Deuflhard 2004, Newton Methods for
        // Nonlinear Problems, sec 3.3): a trial is accepted when the Newton correction there,
        // taken with the same Jacobian, is shorter than (1 - lambda / 4) |dy|; otherwise
        // lambda halves (at most 6 times). The correction measures the distance to the orbit,
        // which the residual does not when a multiplier is near 1 (module docs). A trial the
        // integrator cannot carry through a period (a wild step near a fold) is rejected.
        // When every halving is rejected the step is one period of the map, y -> P(y),
        // defined everywhere and moving towards a stable orbit.
        let size = dy.norm();
        let mut lambda = 1.0;
        let mut next = None;
        for _ in 0..=6 {
            let trial = y + dy.component_mul(&sc) * lambda;
            if let Ok((pn, _, _)) = period_map(&model, &trial, 0.0, period, settings.rtol) {
                let ft = scaled(&(pn - trial));
                if ft.iter().all(|v| v.is_finite())
                    && newton(&ft).norm() < (1.0 - 0.25 * lambda) * size
                {
                    next = Some(trial);
                    break;
                }
            }
            lambda *= 0.5;
        }
        y = next.unwrap_or(p);
        newton_steps += 1;
    }
    let max_multiplier = multipliers(&jac)
        .map(|m| m.iter().map(|c| c.norm()).fold(0.0, f64::max))
        .unwrap_or(f64::NAN);
    let mut s = measure(&model, &y, settings.rtol)?;
    s.max_multiplier = max_multiplier;
    s.newton_steps = newton_steps;
    s.residual = residual;
    Ok(s)
}

/// The fallback of [`steady_state`] when Newton's method stalls after `newton_steps` at
/// `newton_residual`: the period map iterated from `y` ([`SteadyMethod::PeriodMap`]), its
/// multipliers from the exact monodromy at the end.
fn iterate_map(
    model: &Interfaced<Sine>,
    y: &State,
    settings: &SteadySettings,
    newton_steps: usize,
    newton_residual: f64,
) -> Result<IfSteady, InterfaceError> {
    let sc = model.scales();
    let mut y = *y;
    let mut changes = Vec::with_capacity(settings.max_map_periods);
    for k in 1..=settings.max_map_periods {
        let p = period_map_of(model, &y, settings.rtol)?;
        let change = (p - y).component_div(&sc).amax();
        y = p;
        changes.push(change);
        if k <= MAP_WINDOW {
            continue;
        }
        let mu = (change / changes[k - 1 - MAP_WINDOW]).powf(1.0 / MAP_WINDOW as f64);
        if mu < 1.0 && change / (1.0 - mu) < settings.tol {
            let lin = monodromy::linearise(model, &y, settings.rtol)?;
            let mut s = measure(model, &y, settings.rtol)?;
            s.max_multiplier = multipliers(&lin.monodromy)
                .map(|m| m[0].norm())
                .unwrap_or(f64::NAN);
            s.newton_steps = newton_steps;
            s.residual = (lin.end - y).component_div(&sc).amax();
            s.method = SteadyMethod::PeriodMap { periods: k };
            return Ok(s);
        }
    }
    Err(InterfaceError::NoConvergence {
        iterations: newton_steps,
        residual: newton_residual,
        tol: settings.tol,
    })
}

/// The measures of the period from `y` at phase zero (an orbit's section state), with the
/// energy ledger; its multiplier, Newton steps and residual are left NaN, 0 and NaN.
pub fn measure(model: &Interfaced<Sine>, y: &State, rtol: f64) -> Result<IfSteady, SolverError> {
    let period = model.h.excitation.period_s();
    let audit = InterfaceAudit(model.clone());
    let z0 = audit_start(y);
    let mode0 = model.mode_of(y);
    let mut ode = Dopri5::new(0.0, z0, mode0, audit.solver_options(rtol));
    let mut m = Meter {
        t0: 0.0,
        w: 2.0 * std::f64::consts::PI / period,
        vs: 0.0,
        vs_min: f64::INFINITY,
        vs_max: f64::NEG_INFINITY,
        c1: 0.0,
        s1: 0.0,
        x0: 0.0,
        x2: 0.0,
        x_peak: y[0].abs(),
        contact: mode0.contact.in_contact(),
    };
    ode.integrate_observed(&audit, period, &mut m)?;
    let ledger = audit.ledger(mode0, &z0, ode.mode(), &ode.y());
    let x1 = 2.0 / period * m.c1.hypot(m.s1);
    let x_rms2 = m.x2 / period - (m.x0 / period).powi(2);
    let harmonics = (x_rms2 - 0.5 * x1 * x1).max(0.0);
    Ok(IfSteady {
        freq_hz: model.h.excitation.freq_hz,
        state: [y[0], y[1], y[2], y[3]],
        vdc_v: m.vs / period,
        p_dc_w: ledger.dc_load / period,
        ripple_v: m.vs_max - m.vs_min,
        x1_m: x1,
        x_peak_m: m.x_peak,
        x_distortion: (harmonics / (0.5 * x1 * x1)).sqrt(),
        contact: m.contact,
        max_multiplier: f64::NAN,
        newton_steps: 0,
        residual: f64::NAN,
        ledger,
        method: SteadyMethod::Newton,
    })
}

#[cfg(test)]
mod tests;
