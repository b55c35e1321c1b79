//! One free flight between two impacts: the flow of the model without its stops over a given
//! time, with its derivatives with respect to the start state, the continuation parameter and
//! the drive phase at the start (the variational equations), the interior extrema of the
//! displacement (where a new contact would begin), and the sums of the orbit's measures over
//! the flight.

use nalgebra::{Matrix4, SVector, Vector4};

use crate::drive::Sine;
use crate::num::roots::{illinois, RootOptions, Sample};
use crate::ode::{Dopri5, HybridSystem, SolverError, Stats, Step};
use crate::physics::contact::Mode;
use crate::physics::harvester::{head, Harvester, State};
use crate::study::orbit::Parameter;

/// The state, its 16 derivatives with respect to the start state, and the derivatives with
/// respect to the parameter and to the start phase of the drive.
const DIM: usize = 28;
type Aug = SVector<f64, DIM>;

/// The free flow of a model with its variational equations. The stops play no part: a
/// flight's ends are imposed by the boundary-value problem, and a flight that would cross a
/// stop shows as an interior extremum past it.
struct FreeFlow<'a> {
    model: &'a Harvester<Sine>,
    param: Parameter,
}

impl FreeFlow<'_> {
    /// d a / dp and d a / d(phase) of the drive at time `t` (m/s^2 per Hz or per g, per rad).
    fn drive_sensitivities(&self, t: f64) -> (f64, f64) {
        let s = &self.model.excitation;
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

impl HybridSystem for FreeFlow<'_> {
    type State = Aug;
    type Mode = Mode;

    fn guard_count(&self) -> usize {
        0
    }

    #[inline]
    fn rhs(&self, _mode: Mode, t: f64, z: &Aug) -> Aug {
        let y = head(z);
        let f = self.model.rhs(Mode::Free, t, &y);
        let j = self.model.jacobian(Mode::Free, &y);
        let mut out = Aug::zeros();
        out.fixed_rows_mut::<4>(0).copy_from(&f);
        for c in 0..6 {
            let b = 4 + 4 * c;
            let col = Vector4::new(z[b], z[b + 1], z[b + 2], z[b + 3]);
            out.fixed_rows_mut::<4>(b).copy_from(&(j * col));
        }
        let (dp, dphase) = self.drive_sensitivities(t);
        out[21] += dp;
        out[25] += dphase;
        out
    }

    fn guards(&self, _mode: Mode, _t: f64, _z: &Aug, _g: &mut [f64]) {}

    fn switch(&self, mode: Mode, _index: usize, _t: f64, _z: &mut Aug) -> Mode {
        mode
    }

    fn next_breakpoint(&self, t: f64) -> f64 {
        self.model.next_breakpoint(t)
    }
}

/// An interior extremum of the displacement over a flight.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Extremum {
    /// Time from the flight's start (s).
    pub t: f64,
    /// The state there (its velocity is zero to the root finder's tolerance).
    pub state: State,
    /// True for a maximum of x.
    pub maximum: bool,
}

/// One flight: where it ends, its derivatives, and what happened on the way.
#[derive(Debug, Clone)]
pub(super) struct Flight {
    /// The state at the end.
    pub end: State,
    /// d end / d start.
    pub phi: Matrix4<f64>,
    /// d end / d p at a fixed duration.
    pub dp: Vector4<f64>,
    /// d end / d(drive phase at the start) at a fixed duration.
    pub dphase: Vector4<f64>,
    /// The vector field at the end.
    pub f_end: State,
    /// Interior extrema of x, in time order.
    pub extrema: Vec<Extremum>,
    /// Integral of V1^2 and V2^2 over the flight (V^2 s).
    pub v_sq: [f64; 2],
    /// The first upward zero crossing of x: time from the start (s) and state.
    pub upcrossing: Option<(f64, State)>,
    /// The state at each of the requested times (`None` for a time outside the flight).
    pub marked: Vec<Option<State>>,
}

/// Flies `y0` for `duration_s` under `model` (whose drive's phase at t = 0 is the phase at
/// the flight's start), with relative tolerance `rtol` and absolute tolerances `rtol` times
/// `scales` (their ratios for the derivatives); the states at the times `marks` (s from the
/// start) are kept.
#[allow(clippy::too_many_arguments)]
pub(super) fn fly(
    model: &Harvester<Sine>,
    param: Parameter,
    y0: State,
    duration_s: f64,
    rtol: f64,
    scales: &State,
    marks: &[f64],
    stats: &mut Stats,
) -> Result<Flight, SolverError> {
    let sys = FreeFlow { model, param };
    let p_ref = match param {
        Parameter::Frequency => model.excitation.freq_hz,
        Parameter::Amplitude => {
            model.excitation.amplitude_m_s2 / (std::f64::consts::SQRT_2 * crate::G)
        }
    }
    .abs()
    .max(1e-300);
    let mut atol = Aug::zeros();
    let mut z0 = Aug::zeros();
    for i in 0..4 {
        z0[i] = y0[i];
        for j in 0..4 {
            atol[4 + i + 4 * j] = rtol * scales[i] / scales[j];
        }
        z0[4 + 5 * i] = 1.0;
        atol[20 + i] = rtol * scales[i] / p_ref;
        atol[24 + i] = rtol * scales[i];
    }
    let opts = model.solver_options(rtol).augmented(atol);
    let mut ode = Dopri5::new(0.0, z0, Mode::Free, opts);
    let mut extrema = Vec::new();
    let mut v_sq = [0.0; 2];
    let mut upcrossing = None;
    let mut marked = vec![None; marks.len()];
    ode.integrate(&sys, duration_s, |st: &Step<Aug>, _| {
        for (m, &t) in marked.iter_mut().zip(marks) {
            if m.is_none() && t >= st.t0 && t <= st.t1() {
                *m = Some(head(&st.at(t)));
            }
        }
        v_sq[0] += st.integrate(|z| model.electrical(&head(z)).v[0].powi(2));
        v_sq[1] += st.integrate(|z| model.electrical(&head(z)).v[1].powi(2));
        let (v0, v1) = (st.y0[1], st.y1[1]);
        if (v0 > 0.0) != (v1 > 0.0) && v0 != 0.0 {
            if let Some(th) = root_on_step(st, 1) {
                extrema.push(Extremum {
                    t: st.t0 + th * st.h,
                    state: head(&st.at_theta(th)),
                    maximum: v0 > 0.0,
                });
            }
        }
        if upcrossing.is_none() && st.y0[0] <= 0.0 && st.y1[0] > 0.0 {
            if let Some(th) = root_on_step(st, 0) {
                upcrossing = Some((st.t0 + th * st.h, head(&st.at_theta(th))));
            }
        }
    })?;
    *stats += ode.stats();
    let z = ode.y();
    let end = head(&z);
    let phi = Matrix4::from_column_slice(&z.as_slice()[4..20]);
    let dp = Vector4::new(z[20], z[21], z[22], z[23]);
    let dphase = Vector4::new(z[24], z[25], z[26], z[27]);
    Ok(Flight {
        end,
        phi,
        dp,
        dphase,
        f_end: model.rhs(Mode::Free, duration_s, &end),
        extrema,
        v_sq,
        upcrossing,
        marked,
    })
}

/// theta in [0, 1] where component `c` of a step's dense output changes sign, to 1e-13 of
/// the step.
fn root_on_step(st: &Step<Aug>, c: usize) -> Option<f64> {
    let f =
        |th: f64| -> Result<(f64, ()), std::convert::Infallible> { Ok((st.at_theta(th)[c], ())) };
    let opts = RootOptions {
        f_tol: None,
        x_tol_abs: 1e-13,
        x_tol_rel: 0.0,
        max_iter: 100,
    };
    let (a, b) = (st.y0[c], st.y1[c]);
    illinois(f, Sample::new(0.0, a, ()), Sample::new(1.0, b, ()), &opts)
        .ok()
        .map(|r| 0.5 * (r.positive.x + r.non_positive.x))
}
