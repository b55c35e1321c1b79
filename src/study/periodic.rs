//! The periodic steady state of any model under a sine, found by shooting on the period map,
//! with its outputs' means and ranges, the loads' power, its stability and its energy ledger
//! ([`steady_state`]).
//!
//! # Why shooting
//! A storage capacitor and its load have a time constant `R_L C_s` that can be hundreds of the
//! drive's periods. Integrating until two successive periods differ by little stops far from
//! the steady state when the approach is that slow; Newton's method on the period map
//! `P(y) - y = 0` does not care how slow the approach is. The map's Jacobian is the monodromy
//! through saltation matrices ([`crate::model::tangent`]; forward differences of the period map
//! are the alternative, [`JacobianKind`]), and the converged orbit's Floquet multipliers are
//! its eigenvalues. The section is at the drive's phase zero.
//!
//! Far from the orbit the residual `P(y) - y` is a poor measure of the distance to it: along a
//! mode with multiplier `mu` it is `(1 - mu)` times the distance, so with multipliers near 1 a
//! Newton step towards the orbit can raise it. Damping that asks the residual to fall at each
//! step creeps and stalls near 1e-2 on the example cantilever with SSHI at large loads
//! (parallel SSHI from 41.7 kohm, series SSHI from 100 kohm at 0.3 g and 120 Hz, multipliers
//! of modulus 0.92 to 0.98), where the period map is smooth (its differences match the
//! monodromy) and undamped Newton converges in 7 steps. The steps are damped instead by the
//! natural monotonicity test, which measures the distance by the Newton correction (Deuflhard,
//! *Newton Methods for Nonlinear Problems*, 2004, section 3.3).
//!
//! Where Newton's method still does not converge, the period map is iterated from the
//! transient's end until the change per period, divided by `1 - |mu|` for the slowest
//! multiplier estimated from the contraction of the changes, is below the tolerance: the
//! estimate of the distance to the orbit that accounts for the slow approach. The fallback
//! reaches only orbits the map contracts to from the start (stable ones). Each steady state
//! says which method found it ([`SteadyMethod`]).

use nalgebra::{DVector, SMatrix, SVector};
use thiserror::Error;

use crate::drive::{Parameter, Sine};
use crate::model::{Books, Ledger, Mode, Model, MAX_OUTPUTS};
use crate::ode::{Observer, SolverError, Stats, Step};
use crate::study::flow::SineFlow;
use crate::study::orbit::{multipliers, Forcing, Shooter, ShootingOptions};

/// A failed steady state.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum PeriodicError {
    /// The integrator failed.
    #[error("integration failed: {0}")]
    Solver(#[from] SolverError),
    /// The device's parts do not assemble into a model.
    #[error(transparent)]
    Device(#[from] crate::physics::harvester::AssemblyError),
    /// A storage with no load only charges: there is no periodic steady state.
    #[error(
        "the storage has an open load (interface.load.kind = \"open\"), so it charges towards \
         the open-circuit limit and has no periodic steady state; use the charging study"
    )]
    OpenLoad,
    /// Newton's method and the iterated period map did not converge.
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
    /// By the variational equations with saltation matrices: exact to the integrator's
    /// tolerance, one augmented integration.
    #[default]
    Saltation,
    /// By forward differences of the period map: one more period per state component,
    /// accurate to about `rtol / 1e-6` relative.
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

/// One output's mean and range over a period.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct OutputRange {
    /// Mean.
    pub mean: f64,
    /// Smallest value.
    pub min: f64,
    /// Largest value.
    pub max: f64,
}

/// The periodic steady state of a model, measured over one period.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct PeriodicState {
    /// Drive frequency (Hz).
    pub freq_hz: f64,
    /// State at the section (phase zero; the model's components).
    pub state: Vec<f64>,
    /// Each output's mean and range over the period ([`crate::model::Layout::outputs`]).
    pub outputs: Vec<OutputRange>,
    /// Mean of the first output over the period: behind a circuit, the storage voltage (V).
    pub vdc_v: f64,
    /// Mean power into the loads the outputs are across (W): behind a circuit, the DC load.
    pub p_dc_w: f64,
    /// Peak-to-peak of the first output (V): behind a circuit, the storage's ripple.
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
    pub ledger: Ledger,
    /// How the steady state was found.
    pub method: SteadyMethod,
}

impl PeriodicState {
    /// True when every Floquet multiplier is inside the unit circle (to 1e-6).
    pub fn is_stable(&self) -> bool {
        self.max_multiplier < 1.0 + 1e-6
    }
}

/// The period map `P(y)` of `model` under `sine` from phase zero at relative tolerance `rtol`.
pub fn period_map<M: Model<N>, const N: usize>(
    model: &M,
    sine: Sine,
    y: &SVector<f64, N>,
    rtol: f64,
) -> Result<SVector<f64, N>, SolverError> {
    let mut flow = SineFlow::new(model, sine, 0.0, *y, model.mode_of(y), rtol);
    flow.advance(sine.period_s())?;
    Ok(flow.y())
}

/// The Jacobian of the period map by forward differences, scaled (one period per state
/// component, steps of 1e-6 of each scale): the check of the saltation monodromy, and the
/// alternative [`JacobianKind::Differences`].
pub fn monodromy_differences<M: Model<N>, const N: usize>(
    model: &M,
    sine: Sine,
    y: &SVector<f64, N>,
    p: &SVector<f64, N>,
    rtol: f64,
) -> Result<SMatrix<f64, N, N>, SolverError> {
    let sc = model.scales();
    let mut jac = SMatrix::<f64, N, N>::zeros();
    for c in 0..N {
        let e = 1e-6 * sc[c];
        let mut yp = *y;
        yp[c] += e;
        let pp = period_map(model, sine, &yp, rtol)?;
        jac.set_column(c, &((pp - p).component_div(&sc) / 1e-6));
    }
    Ok(jac)
}

/// The period map at `y` and its Jacobian in scaled coordinates.
fn map_and_jacobian<M: Model<N>, const N: usize>(
    model: &M,
    sine: Sine,
    y: &SVector<f64, N>,
    settings: &SteadySettings,
) -> Result<(SVector<f64, N>, SMatrix<f64, N, N>), SolverError> {
    match settings.jacobian {
        JacobianKind::Saltation => {
            let shooter = Shooter::new(
                model,
                ShootingOptions {
                    rtol: settings.rtol,
                    ..ShootingOptions::default()
                },
            );
            let mut stats = Stats::default();
            let lin = shooter.linearise_sine(
                sine,
                Parameter::Frequency,
                *y,
                sine.period_s(),
                &mut stats,
            )?;
            Ok((lin.end, shooter.scaled_monodromy(&lin.monodromy)))
        }
        JacobianKind::Differences => {
            let p = period_map(model, sine, y, settings.rtol)?;
            Ok((p, monodromy_differences(model, sine, y, &p, settings.rtol)?))
        }
    }
}

/// The steady state of `model` under `sine` from `start` at phase zero (rest, with a storage
/// at some voltage, or a neighbouring steady state); see the module docs for the method.
pub fn steady_state<M: Model<N>, const N: usize>(
    model: &M,
    sine: Sine,
    start: &SVector<f64, N>,
    settings: &SteadySettings,
) -> Result<PeriodicState, PeriodicError> {
    let layout = model.layout();
    if layout
        .output("vs")
        .is_some_and(|i| layout.outputs[i].load.is_none())
    {
        return Err(PeriodicError::OpenLoad);
    }
    let period = sine.period_s();
    let sc = model.scales();
    let mut flow = SineFlow::new(
        model,
        sine,
        0.0,
        *start,
        model.mode_of(start),
        settings.rtol,
    );
    flow.advance(settings.transient_periods as f64 * period)?;
    let mut y = flow.y();
    let after_transient = y;
    let scaled = |d: &SVector<f64, N>| d.component_div(&sc);
    let mut newton_steps = 0;
    let (mut residual, mut jac);
    loop {
        let p;
        (p, jac) = map_and_jacobian(model, sine, &y, settings)?;
        let f = scaled(&(p - y));
        residual = f.amax();
        if residual < settings.tol {
            break;
        }
        if newton_steps >= settings.max_newton {
            return iterate_map(
                model,
                sine,
                &after_transient,
                settings,
                newton_steps,
                residual,
            );
        }
        let lu = crate::num::dense::Lu::of(&(jac - SMatrix::<f64, N, N>::identity()));
        let newton = |f: &SVector<f64, N>| -> SVector<f64, N> { lu.solve(&(-f)).unwrap_or(-f) };
        let dy = newton(&f);
        // A damped step by the natural monotonicity test (module docs): a trial is accepted
        // when the Newton correction there, taken with the same Jacobian, is shorter than
        // (1 - lambda / 4) |dy|; otherwise lambda halves (at most 6 times). A trial the
        // integrator cannot carry through a period (a wild step near a fold) is rejected.
        // When every halving is rejected the step is one period of the map, y -> P(y),
        // defined everywhere and moving towards a stable orbit.
        let size = dy.norm();
        let mut lambda = 1.0;
        let mut next = None;
        for _ in 0..=6 {
            let trial = y + dy.component_mul(&sc) * lambda;
            if let Ok(pn) = period_map(model, sine, &trial, settings.rtol) {
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
    let mut s = measure(model, sine, &y, settings.rtol)?;
    s.max_multiplier = max_multiplier;
    s.newton_steps = newton_steps;
    s.residual = residual;
    Ok(s)
}

/// The fallback of [`steady_state`] when Newton's method stalls after `newton_steps` at
/// `newton_residual`: the period map iterated from `y` ([`SteadyMethod::PeriodMap`]), its
/// multipliers from the exact monodromy at the end.
fn iterate_map<M: Model<N>, const N: usize>(
    model: &M,
    sine: Sine,
    y: &SVector<f64, N>,
    settings: &SteadySettings,
    newton_steps: usize,
    newton_residual: f64,
) -> Result<PeriodicState, PeriodicError> {
    let sc = model.scales();
    let mut y = *y;
    let mut changes = Vec::with_capacity(settings.max_map_periods);
    for k in 1..=settings.max_map_periods {
        let p = period_map(model, sine, &y, settings.rtol)?;
        let change = (p - y).component_div(&sc).amax();
        y = p;
        changes.push(change);
        if k <= MAP_WINDOW {
            continue;
        }
        let mu = (change / changes[k - 1 - MAP_WINDOW]).powf(1.0 / MAP_WINDOW as f64);
        if mu < 1.0 && change / (1.0 - mu) < settings.tol {
            let salted = SteadySettings {
                jacobian: JacobianKind::Saltation,
                ..*settings
            };
            let (end, m) = map_and_jacobian(model, sine, &y, &salted)?;
            let mut s = measure(model, sine, &y, settings.rtol)?;
            s.max_multiplier = multipliers(&m).map(|m| m[0].norm()).unwrap_or(f64::NAN);
            s.newton_steps = newton_steps;
            s.residual = (end - y).component_div(&sc).amax();
            s.method = SteadyMethod::PeriodMap { periods: k };
            return Ok(s);
        }
    }
    Err(PeriodicError::NoConvergence {
        iterations: newton_steps,
        residual: newton_residual,
        tol: settings.tol,
    })
}

/// Observes a measured period: the outputs' integrals and ranges, the displacement's
/// fundamental, its peak and whether the mass touched a stop, and the ledger.
struct Meter<'m, M, const N: usize> {
    model: &'m M,
    w: f64,
    squares: Vec<f64>,
    integrals: Vec<f64>,
    range: Vec<(f64, f64)>,
    c1: f64,
    s1: f64,
    x0: f64,
    x2: f64,
    x_peak: f64,
    contact: bool,
    books: Books<'m, M, Sine, N>,
}

impl<M: Model<N>, const N: usize> Observer<SVector<f64, N>, Mode> for Meter<'_, M, N> {
    fn step(&mut self, st: &Step<SVector<f64, N>>, m: Mode) {
        let k = self.squares.len();
        let mut out = [0.0; MAX_OUTPUTS];
        for (th, wt) in crate::ode::GAUSS_LEGENDRE_3 {
            let t = st.t0 + th * st.h;
            let y = st.at_theta(th);
            self.model.outputs(m, &y, &mut out[..k]);
            for (i, o) in out.iter().take(k).enumerate() {
                self.squares[i] += wt * st.h * o * o;
                self.integrals[i] += wt * st.h * o;
            }
            let x = y[0];
            self.x0 += wt * st.h * x;
            self.x2 += wt * st.h * x * x;
            // The fundamental, the drive's phase at the nodes.
            self.c1 += wt * st.h * x * (self.w * t).cos();
            self.s1 += wt * st.h * x * (self.w * t).sin();
        }
        for y in [st.y1, st.at_theta(0.5)] {
            self.x_peak = self.x_peak.max(y[0].abs());
            self.model.outputs(m, &y, &mut out[..k]);
            for (r, v) in self.range.iter_mut().zip(&out[..k]) {
                *r = (r.0.min(*v), r.1.max(*v));
            }
        }
        self.contact |= m.in_contact();
        self.books.step(st, m);
    }
}

/// The measures of the period from `y` at phase zero (an orbit's section state), with the
/// energy ledger; its multiplier, Newton steps and residual are left NaN, 0 and NaN.
pub fn measure<M: Model<N>, const N: usize>(
    model: &M,
    sine: Sine,
    y: &SVector<f64, N>,
    rtol: f64,
) -> Result<PeriodicState, SolverError> {
    let period = sine.period_s();
    let k = model.layout().outputs.len();
    let mode0 = model.mode_of(y);
    let mut m = Meter {
        model,
        w: 2.0 * std::f64::consts::PI / period,
        squares: vec![0.0; k],
        integrals: vec![0.0; k],
        range: vec![(f64::INFINITY, f64::NEG_INFINITY); k],
        c1: 0.0,
        s1: 0.0,
        x0: 0.0,
        x2: 0.0,
        x_peak: y[0].abs(),
        contact: mode0.in_contact(),
        books: Books::new(model, sine),
    };
    let mut flow = SineFlow::new(model, sine, 0.0, *y, mode0, rtol);
    flow.integrate_observed(period, &mut m)?;
    let ledger = m.books.ledger();
    let x1 = 2.0 / period * m.c1.hypot(m.s1);
    let x_rms2 = m.x2 / period - (m.x0 / period).powi(2);
    let harmonics = (x_rms2 - 0.5 * x1 * x1).max(0.0);
    let outputs: Vec<OutputRange> = (0..k)
        .map(|i| OutputRange {
            mean: m.integrals[i] / period,
            min: m.range[i].0,
            max: m.range[i].1,
        })
        .collect();
    let first = outputs.first().copied().unwrap_or(OutputRange {
        mean: 0.0,
        min: 0.0,
        max: 0.0,
    });
    Ok(PeriodicState {
        freq_hz: sine.freq_hz,
        state: y.iter().copied().collect(),
        vdc_v: first.mean,
        p_dc_w: model.layout().load_power(&m.squares, &m.integrals, period),
        ripple_v: first.max - first.min,
        outputs,
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

/// The state of a steady state as a model's state of dimension `N`.
pub fn state_of<const N: usize>(s: &PeriodicState) -> SVector<f64, N> {
    SVector::<f64, N>::from_column_slice(&s.state)
}

/// A state of dimension `N` as a list (for a caller that keeps it across devices).
pub fn as_list<const N: usize>(y: &SVector<f64, N>) -> DVector<f64> {
    DVector::from_column_slice(y.as_slice())
}

impl Forcing {
    /// The forcing of a sine (its frequency and RMS acceleration in g).
    pub fn of(sine: &Sine) -> Self {
        Forcing {
            freq_hz: sine.freq_hz,
            accel_rms_g: sine.amplitude_m_s2 / (std::f64::consts::SQRT_2 * crate::G),
        }
    }
}

/// The steady state of `device` under `sine` from rest ([`steady_state`] on its model).
///
/// ```
/// use endstop::device::Device;
/// use endstop::drive::Sine;
/// use endstop::study::periodic::{steady_state_from_rest, SteadySettings};
///
/// let text = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/examples/piezo_bridge.toml"));
/// let device = Device::from_toml_str(text, "piezo_bridge.toml")?;
/// let s = steady_state_from_rest(&device, Sine::from_rms_g(0.05, 120.0), &SteadySettings::default())?;
/// assert!(s.is_stable() && s.vdc_v > 0.0);
/// // The DC load (41.7 kOhm) takes <V^2> / R, which lies between <V>^2 / R and the square of
/// // the storage's highest voltage over R (the ripple bounds how far V leaves its mean).
/// let r = 41.7e3;
/// assert!(s.p_dc_w >= s.vdc_v * s.vdc_v / r * (1.0 - 1e-12));
/// assert!(s.p_dc_w <= (s.vdc_v + s.ripple_v).powi(2) / r);
/// // Over the measured period the energy books balance: the residual is of the order of the
/// // integrator's tolerance (1e-9) times the energies turned over; 1e-6 leaves room for it.
/// assert!(s.ledger.relative_residual().abs() < 1e-6);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn steady_state_from_rest(
    device: &crate::device::Device,
    sine: Sine,
    settings: &SteadySettings,
) -> Result<PeriodicState, PeriodicError> {
    crate::with_harvester!(device, |h| steady_state(
        &h,
        sine,
        &h.rest_state(),
        settings
    ))
}

/// The steady states of `device` at each frequency (Hz) in order, at `accel_rms_g`, from rest
/// for the first and from the previous point's section state for the others (so that the
/// sweep follows one branch, as a stepped-sine measurement does). A point where shooting finds
/// no period-one orbit (the response may be of a longer period, or not periodic) is kept as its
/// error, and the sweep goes on from the last point found; `progress` is told of each point.
///
/// ```
/// use endstop::device::Device;
/// use endstop::progress::Silent;
/// use endstop::study::periodic::{frequency_sweep, SteadySettings};
///
/// let text = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/examples/piezo_bridge.toml"));
/// let device = Device::from_toml_str(text, "piezo_bridge.toml")?;
/// // 0.05 g rms at 100 Hz and at the 120 Hz resonance (quality factor about 50, so 100 Hz
/// // lies many half-power widths below it): the storage charges higher at resonance.
/// let points = frequency_sweep(&device, &[100.0, 120.0], 0.05, &SteadySettings::default(), &Silent)?;
/// let vdc: Vec<f64> = points.into_iter().map(|p| p.map(|s| s.vdc_v)).collect::<Result<_, _>>()?;
/// assert!(vdc[1] > vdc[0]);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn frequency_sweep(
    device: &crate::device::Device,
    freqs_hz: &[f64],
    accel_rms_g: f64,
    settings: &SteadySettings,
    progress: &dyn crate::progress::Progress,
) -> Result<Vec<Result<PeriodicState, PeriodicError>>, PeriodicError> {
    crate::with_harvester!(device, |h| Ok(frequency_sweep_on(
        &h,
        freqs_hz,
        accel_rms_g,
        settings,
        progress
    )))
}

/// [`frequency_sweep`] on a model.
pub fn frequency_sweep_on<M: Model<N>, const N: usize>(
    model: &M,
    freqs_hz: &[f64],
    accel_rms_g: f64,
    settings: &SteadySettings,
    progress: &dyn crate::progress::Progress,
) -> Vec<Result<PeriodicState, PeriodicError>> {
    let mut out = Vec::with_capacity(freqs_hz.len());
    let mut start = model.rest_state();
    for &f in freqs_hz {
        let s = steady_state(model, Sine::from_rms_g(accel_rms_g, f), &start, settings);
        if let Ok(s) = &s {
            start = state_of(s);
        }
        progress.tick();
        out.push(s);
    }
    out
}

/// The steady states of `device` at each DC load resistance (ohm) in order, at one drive;
/// every point starts from rest (a different load moves the DC voltage far, so a neighbour's
/// state is no better a start); `progress` is told of each point.
pub fn load_sweep(
    device: &crate::device::Device,
    loads_ohm: &[f64],
    sine: Sine,
    settings: &SteadySettings,
    progress: &dyn crate::progress::Progress,
) -> Vec<Result<PeriodicState, PeriodicError>> {
    let mut out = Vec::with_capacity(loads_ohm.len());
    for &r in loads_ohm {
        let mut d = device.clone();
        d.interface = d.interface.with_load_resistance(r);
        let s = crate::with_harvester!(&d, |h| steady_state(&h, sine, &h.rest_state(), settings));
        progress.tick();
        out.push(s);
    }
    out
}
