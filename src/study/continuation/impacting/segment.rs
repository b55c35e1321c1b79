//! One free flight between two impacts: the flow of the model without its stops over a given
//! time, with its derivatives with respect to the start state, the continuation parameter and
//! the drive phase at the start (the variational equations), the interior extrema of the
//! displacement (where a new contact would begin), and the sums of the orbit's measures over
//! the flight.

use nalgebra::{SMatrix, SVector};

use crate::drive::{Excitation, Sine};
use crate::model::{Mode, Model};
use crate::num::roots::{illinois, RootOptions, Sample};
use crate::ode::{Dopri5, HybridSystem, SolverError, Stats, Step, Tangent};
use crate::study::mass_peaks::MassPeaks;
use crate::study::orbit::Parameter;

/// The state, its derivatives with respect to the start state, and the derivatives with
/// respect to the parameter and to the start phase of the drive.
type Aug<const N: usize> = Tangent<N, 2>;

/// The free flow of a model with its variational equations. The stops play no part: a
/// flight's ends are imposed by the boundary-value problem, and a flight that would cross a
/// stop shows as an interior extremum past it.
struct FreeFlow<'a, M, const N: usize> {
    model: &'a M,
    sine: Sine,
    param: Parameter,
}

impl<M: Model<N>, const N: usize> FreeFlow<'_, M, N> {
    /// d a / dp and d a / d(phase) of the drive at time `t` (m/s^2 per Hz or per g, per rad).
    fn drive_sensitivities(&self, t: f64) -> (f64, f64) {
        let s = &self.sine;
        let w = 2.0 * std::f64::consts::PI * s.freq_hz;
        let arg = w * t + s.phase_rad;
        let d_phase = s.amplitude_m_s2 * arg.cos();
        let d_param = match self.param {
            Parameter::Frequency => d_phase * 2.0 * std::f64::consts::PI * t,
            Parameter::Amplitude => std::f64::consts::SQRT_2 * crate::G * arg.sin(),
        };
        (d_param, d_phase)
    }
}

impl<M: Model<N>, const N: usize> HybridSystem for FreeFlow<'_, M, N> {
    type State = Aug<N>;
    type Mode = Mode;

    fn guard_count(&self) -> usize {
        0
    }

    #[inline]
    fn rhs(&self, _mode: Mode, t: f64, z: &Aug<N>) -> Aug<N> {
        let y = z.y;
        let f = self.model.rhs(Mode::FREE, &y, self.sine.accel(t));
        let j = self.model.jacobian(Mode::FREE, &y);
        let mut phi = SMatrix::<f64, N, N>::zeros();
        for c in 0..N {
            phi.set_column(c, &(j * z.phi.column(c)));
        }
        let mut dp = SMatrix::<f64, N, 2>::zeros();
        for c in 0..2 {
            dp.set_column(c, &(j * z.dp.column(c)));
        }
        let (d_param, d_phase) = self.drive_sensitivities(t);
        let col = self.model.drive_column(Mode::FREE);
        for i in 0..N {
            if col[i] != 0.0 {
                dp[(i, 0)] += col[i] * d_param;
                dp[(i, 1)] += col[i] * d_phase;
            }
        }
        Tangent { y: f, phi, dp }
    }

    fn guards(&self, _mode: Mode, _t: f64, _z: &Aug<N>, _g: &mut [f64]) {}

    fn switch(&self, mode: Mode, _index: usize, _t: f64, _z: &mut Aug<N>) -> Mode {
        mode
    }
}

/// An interior extremum of the displacement over a flight.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Extremum<const N: usize> {
    /// Time from the flight's start (s).
    pub t: f64,
    /// The state there (its velocity is zero to the root finder's tolerance).
    pub state: SVector<f64, N>,
    /// True for a maximum of x.
    pub maximum: bool,
}

/// One flight: where it ends, its derivatives, and what happened on the way.
#[derive(Debug, Clone)]
pub(super) struct Flight<const N: usize> {
    /// The state at the end.
    pub end: SVector<f64, N>,
    /// d end / d start.
    pub phi: SMatrix<f64, N, N>,
    /// d end / d p at a fixed duration.
    pub dp: SVector<f64, N>,
    /// d end / d(drive phase at the start) at a fixed duration.
    pub dphase: SVector<f64, N>,
    /// The vector field at the end.
    pub f_end: SVector<f64, N>,
    /// Interior extrema of x, in time order.
    pub extrema: Vec<Extremum<N>>,
    /// Each mass's largest |x| and |v| at the ends and midpoints of the steps (a model of
    /// several masses; none for one).
    pub mass_peaks: MassPeaks,
    /// Integrals of the squares of the model's outputs over the flight (V^2 s).
    pub out_sq: Vec<f64>,
    /// Integrals of the model's outputs over the flight (V s).
    pub out_int: Vec<f64>,
    /// The first upward zero crossing of x: time from the start (s) and state.
    pub upcrossing: Option<(f64, SVector<f64, N>)>,
    /// The state at each of the requested times (`None` for a time outside the flight).
    pub marked: Vec<Option<SVector<f64, N>>>,
}

/// Flies `y0` for `duration_s` under `model` (whose drive's phase at t = 0 is the phase at
/// the flight's start), with relative tolerance `rtol` and absolute tolerances `rtol` times
/// `scales` (their ratios for the derivatives); the states at the times `marks` (s from the
/// start) are kept.
#[allow(clippy::too_many_arguments)]
pub(super) fn fly<M: Model<N>, const N: usize>(
    model: &M,
    sine: Sine,
    param: Parameter,
    y0: SVector<f64, N>,
    duration_s: f64,
    rtol: f64,
    scales: &SVector<f64, N>,
    marks: &[f64],
    stats: &mut Stats,
) -> Result<Flight<N>, SolverError> {
    let sys = FreeFlow { model, sine, param };
    let p_ref = match param {
        Parameter::Frequency => sine.freq_hz,
        Parameter::Amplitude => sine.amplitude_m_s2 / (std::f64::consts::SQRT_2 * crate::G),
    }
    .abs()
    .max(1e-300);
    let base = model.solver_options(rtol);
    let mut atol = Aug::<N>::start(base.atol);
    for i in 0..N {
        for j in 0..N {
            atol.phi[(i, j)] = rtol * scales[i] / scales[j];
        }
        atol.dp[(i, 0)] = rtol * scales[i] / p_ref;
        atol.dp[(i, 1)] = rtol * scales[i];
    }
    let opts = base.with_atol(atol);
    let mut ode = Dopri5::new(0.0, Aug::<N>::start(y0), Mode::FREE, opts);
    let mut extrema = Vec::new();
    let n_out = model.layout().outputs.len();
    let mut out_sq = vec![0.0; n_out];
    let mut out_int = vec![0.0; n_out];
    let mut upcrossing = None;
    let mut marked = vec![None; marks.len()];
    let mut buf = vec![0.0; n_out];
    let mut mass_peaks = MassPeaks::of(model.layout());
    let mut out_at = |z: &Aug<N>, i: usize| {
        model.outputs(Mode::FREE, &z.y, &mut buf);
        buf[i]
    };
    ode.integrate(&sys, duration_s, |st: &Step<Aug<N>>, _| {
        for (m, &t) in marked.iter_mut().zip(marks) {
            if m.is_none() && t >= st.t0 && t <= st.t1() {
                *m = Some(st.at(t).y);
            }
        }
        for i in 0..n_out {
            out_sq[i] += integrate(st, |z| out_at(z, i).powi(2));
            out_int[i] += integrate(st, |z| out_at(z, i));
        }
        if mass_peaks.len > 0 {
            mass_peaks.see(model.layout(), st.y1.y.as_slice());
            mass_peaks.see(model.layout(), st.at_theta(0.5).y.as_slice());
        }
        let (v0, v1) = (st.y0.y[1], st.y1.y[1]);
        if (v0 > 0.0) != (v1 > 0.0) && v0 != 0.0 {
            if let Some(th) = root_on_step(st, 1) {
                extrema.push(Extremum {
                    t: st.t0 + th * st.h,
                    state: st.at_theta(th).y,
                    maximum: v0 > 0.0,
                });
            }
        }
        if upcrossing.is_none() && st.y0.y[0] <= 0.0 && st.y1.y[0] > 0.0 {
            if let Some(th) = root_on_step(st, 0) {
                upcrossing = Some((st.t0 + th * st.h, st.at_theta(th).y));
            }
        }
    })?;
    *stats += ode.stats();
    let z = ode.y();
    let end = z.y;
    Ok(Flight {
        end,
        phi: z.phi,
        dp: z.dp.column(0).into_owned(),
        dphase: z.dp.column(1).into_owned(),
        f_end: model.rhs(Mode::FREE, &end, sine.accel(duration_s)),
        extrema,
        mass_peaks,
        out_sq,
        out_int,
        upcrossing,
        marked,
    })
}

/// The integral over a step of `f` on its dense output, by 3-point Gauss-Legendre (as
/// [`Step::integrate`], with a closure that may hold state).
fn integrate<V: crate::ode::Vector>(st: &Step<V>, mut f: impl FnMut(&V) -> f64) -> f64 {
    let mut s = 0.0;
    for (x, w) in crate::ode::GAUSS_LEGENDRE_3 {
        s += w * f(&st.at_theta(x));
    }
    s * st.h
}

/// theta in [0, 1] where component `c` of a step's dense output changes sign, to 1e-13 of
/// the step.
fn root_on_step<const N: usize>(st: &Step<Aug<N>>, c: usize) -> Option<f64> {
    let f =
        |th: f64| -> Result<(f64, ()), std::convert::Infallible> { Ok((st.at_theta(th).y[c], ())) };
    let opts = RootOptions {
        f_tol: None,
        x_tol_abs: 1e-13,
        x_tol_rel: 0.0,
        max_iter: 100,
    };
    let (a, b) = (st.y0.y[c], st.y1.y[c]);
    illinois(f, Sample::new(0.0, a, ()), Sample::new(1.0, b, ()), &opts)
        .ok()
        .map(|r| 0.5 * (r.positive.x + r.non_positive.x))
}
