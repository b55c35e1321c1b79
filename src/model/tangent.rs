//! A model with its variational equations: the state, its tangent map and one parameter
//! column integrated together ([`Tangent`]), with the saltation matrix applied at every
//! switch.
//!
//! Between switches `phi' = J phi` and `dp' = J dp + c da/dp`, with `J` the Jacobian of the
//! mode ([`Model::jacobian`]), `c` the drive's column and `da/dp` the drive's sensitivity to
//! the parameter ([`Parametric`]). At a switch through a guard `g` with gradient `n` and
//! explicit rate `g_t` (through the drive, for a mass resting on a stop), from the field `f-`
//! to `f+` with the reset Jacobian `D` (the identity without a reset),
//!
//! `S = D + (f+ - D f-) n^T / (n . f- + g_t)`
//!
//! is applied to every column (di Bernardo et al., *Piecewise-smooth Dynamical Systems*, 2008,
//! section 2.5; for a contact without reset, `D = I`, the damper's switch-on makes `f+ != f-`).
//! The gradient is taken by central differences in the scaled coordinates (the guards are
//! affine or smooth in the state, so this is exact to rounding for the affine ones), and the
//! explicit rate likewise in time.

use std::cell::Cell;

use nalgebra::{SMatrix, SVector};

use crate::drive::{Excitation, Parameter, Sine};
use crate::ode::{HybridSystem, Options, Step, Tangent};

use super::{Mode, Model};

/// A drive whose acceleration depends on a parameter: `da/dp` at time `t`.
pub trait Parametric: Excitation {
    /// `d a(t) / d p` (m/s^2 per unit of the parameter).
    fn sensitivity(&self, param: Parameter, t: f64) -> f64;
}

impl Parametric for Sine {
    #[inline]
    fn sensitivity(&self, param: Parameter, t: f64) -> f64 {
        let w = 2.0 * std::f64::consts::PI * self.freq_hz;
        let arg = w * t + self.phase_rad;
        match param {
            Parameter::Frequency => {
                self.amplitude_m_s2 * arg.cos() * 2.0 * std::f64::consts::PI * t
            }
            Parameter::Amplitude => std::f64::consts::SQRT_2 * crate::G * arg.sin(),
        }
    }
}

/// A model of dimension `N` under a parametric drive with its variational equations (see the
/// module docs).
pub struct Tangents<'m, M, E, const N: usize> {
    /// The model.
    pub model: &'m M,
    /// The drive.
    pub drive: E,
    /// The parameter of the parameter column.
    pub param: Parameter,
    /// Switches passed (their count).
    events: Cell<usize>,
    /// The smallest `|n . f- + g_t|` met at a switch, relative to the guard's scale rate (its
    /// gradient times the state scales, times [`Model::omega_rad_s`]): near zero the crossing
    /// is nearly tangential and the flow nearly not differentiable there.
    min_transversality: Cell<f64>,
    dim: std::marker::PhantomData<[(); N]>,
}

impl<'m, M: Model<N>, E, const N: usize> Tangents<'m, M, E, N> {
    /// `model` under `drive` with the parameter column of `param`.
    pub fn new(model: &'m M, drive: E, param: Parameter) -> Self {
        Self {
            model,
            drive,
            param,
            events: Cell::new(0),
            min_transversality: Cell::new(f64::INFINITY),
            dim: std::marker::PhantomData,
        }
    }

    /// Switches passed so far.
    pub fn events(&self) -> usize {
        self.events.get()
    }

    /// The smallest relative transversality met so far (infinite without a switch).
    pub fn min_transversality(&self) -> f64 {
        self.min_transversality.get()
    }
}

/// Integrator options for the tangent system at relative tolerance `rtol`: the model's for the
/// state, `rtol s_i / s_j` for `phi_ij` (of order `s_i / s_j`), `rtol s_i / p_ref` for the
/// parameter column.
pub fn tangent_options<M: Model<N>, const N: usize>(
    model: &M,
    scales: &SVector<f64, N>,
    rtol: f64,
    p_ref: f64,
) -> Options<Tangent<N>> {
    let base = model.solver_options(rtol);
    let mut atol = Tangent::<N>::start(base.atol);
    for i in 0..N {
        for j in 0..N {
            atol.phi[(i, j)] = rtol * scales[i] / scales[j];
        }
        atol.dp[i] = rtol * scales[i] / p_ref;
    }
    base.with_atol(atol)
}

impl<M: Model<N>, E: Parametric, const N: usize> Tangents<'_, M, E, N> {
    /// The gradient of guard `index` of `mode` in the state, and its explicit rate in time,
    /// by central differences (see the module docs).
    pub fn guard_gradient(
        &self,
        mode: Mode,
        index: usize,
        t: f64,
        y: &SVector<f64, N>,
    ) -> (SVector<f64, N>, f64) {
        let m = self.model;
        let count = m.guard_count();
        let mut buf = vec![0.0; count];
        let mut guard = |y: &SVector<f64, N>, t: f64| {
            m.guards(mode, y, || self.drive.accel(t), &mut buf);
            buf[index]
        };
        let sc = m.scales();
        let mut n = SVector::<f64, N>::zeros();
        for c in 0..N {
            let h = 1e-6 * sc[c];
            let (mut yp, mut ym) = (*y, *y);
            yp[c] += h;
            ym[c] -= h;
            n[c] = (guard(&yp, t) - guard(&ym, t)) / (2.0 * h);
        }
        let ht = 1e-6 / m.omega_rad_s();
        let g_t = (guard(y, t + ht) - guard(y, t - ht)) / (2.0 * ht);
        (n, g_t)
    }
}

impl<M: Model<N>, E: Parametric, const N: usize> HybridSystem for Tangents<'_, M, E, N> {
    type State = Tangent<N>;
    type Mode = Mode;

    fn guard_count(&self) -> usize {
        self.model.guard_count()
    }

    #[inline]
    fn rhs(&self, mode: Mode, t: f64, z: &Tangent<N>) -> Tangent<N> {
        let a = self.drive.accel(t);
        let f = self.model.rhs(mode, &z.y, a);
        let j = self.model.jacobian(mode, &z.y);
        let mut phi = SMatrix::<f64, N, N>::zeros();
        for c in 0..N {
            phi.set_column(c, &(j * z.phi.column(c)));
        }
        let mut dp = j * z.dp;
        let s = self.drive.sensitivity(self.param, t);
        let col = self.model.drive_column(mode);
        for i in 0..N {
            if col[i] != 0.0 {
                dp[i] += col[i] * s;
            }
        }
        Tangent { y: f, phi, dp }
    }

    #[inline]
    fn guards(&self, mode: Mode, t: f64, z: &Tangent<N>, g: &mut [f64]) {
        self.model.guards(mode, &z.y, || self.drive.accel(t), g)
    }

    /// The guards read the state alone: only it is interpolated, not the tangent map.
    #[inline(always)]
    fn guards_on_step(
        &self,
        mode: Mode,
        t: f64,
        step: &Step<Tangent<N>>,
        theta: f64,
        g: &mut [f64],
    ) {
        let y = step.part_at_theta(theta, |z| &z.y);
        self.model.guards(mode, &y, || self.drive.accel(t), g)
    }

    // ANCHOR: saltation
    fn switch(&self, mode: Mode, index: usize, t: f64, z: &mut Tangent<N>) -> Mode {
        let m = self.model;
        let a = self.drive.accel(t);
        let y = z.y;
        let f_old = m.rhs(mode, &y, a);
        let (n, g_t) = self.guard_gradient(mode, index, t, &y);
        let mut y_new = y;
        let new_mode = m.switch(mode, index, &mut y_new, a);
        let f_new = m.rhs(new_mode, &y_new, a);
        let denom = n.dot(&f_old) + g_t;
        let rate_scale = n.component_mul(&m.scales()).abs().sum() * m.omega_rad_s();
        self.events.set(self.events.get() + 1);
        self.min_transversality
            .set(self.min_transversality.get().min(denom.abs() / rate_scale));
        z.y = y_new;
        if denom != 0.0 && denom.is_finite() {
            match m.reset_jacobian(mode, index, new_mode, &y) {
                // A reset y+ = R(y-) with Jacobian D: S = D + (f+ - D f-) n^T / (dg/dt).
                Some(d) => {
                    let df = (f_new - d * f_old) / denom;
                    for c in 0..N {
                        let col = z.phi.column(c).into_owned();
                        z.phi.set_column(c, &(d * col + df * n.dot(&col)));
                    }
                    z.dp = d * z.dp + df * n.dot(&z.dp);
                }
                // S = I + (f+ - f-) n^T / (dg/dt), applied to every column.
                None => {
                    let df = (f_new - f_old) / denom;
                    for c in 0..N {
                        let col = z.phi.column(c).into_owned();
                        z.phi.set_column(c, &(col + df * n.dot(&col)));
                    }
                    z.dp += df * n.dot(&z.dp);
                }
            }
        }
        new_mode
    }
    // ANCHOR_END: saltation

    fn next_breakpoint(&self, t: f64) -> f64 {
        self.drive.next_breakpoint(t)
    }

    fn check_state(&self, mode: Mode, t: f64, z: &Tangent<N>) -> Result<(), String> {
        self.model
            .check_state(mode, &z.y)
            .map_err(|msg| format!("at t = {t:e} s: {msg}"))
    }
}
