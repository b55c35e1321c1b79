//! The harvester with its variational equations: the state, the monodromy's sixteen columns
//! and the parameter sensitivity integrated together, with the saltation matrix applied at
//! every switch of mode (see the parent module).

use nalgebra::{Matrix4, SVector, Vector4};

use crate::drive::Sine;
use crate::ode::HybridSystem;
use crate::physics::contact::Mode;
use crate::physics::harvester::{reset_jacobian, Harvester, State, SwitchKind};
use crate::study::flow::{AffineMode, Carrier};

use super::{Parameter, VARIATIONAL_DIM};

/// The harvester with its variational equations (state, monodromy, parameter sensitivity).
pub(super) struct Variational<'a> {
    pub(super) model: &'a Harvester<Sine>,
    pub(super) param: Parameter,
}

pub(super) type Aug = SVector<f64, VARIATIONAL_DIM>;

pub(super) fn state_of(z: &Aug) -> State {
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

impl HybridSystem for Variational<'_> {
    type State = Aug;
    type Mode = Mode;

    fn guard_count(&self) -> usize {
        self.model.guard_count()
    }

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

    fn guards(&self, mode: Mode, t: f64, z: &Aug, g: &mut [f64]) {
        self.model.guards(mode, t, &state_of(z), g)
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

/// In an affine mode the variational equations are solved exactly too: the monodromy's
/// columns by `e^{sL}`, the parameter column by `e^{sL}` and the particular solution of its
/// forcing ([`AffineMode::sensitivity`]); the saltation at every switch is the one above.
impl Carrier for Variational<'_> {
    fn harvester(&self) -> &Harvester<Sine> {
        self.model
    }

    const DENSE: bool = false;

    fn carry(&self, am: &AffineMode, e: &Matrix4<f64>, t: f64, s: f64, z: &Aug, y1: &State) -> Aug {
        let mut out = *z;
        out.fixed_rows_mut::<4>(0).copy_from(y1);
        for c in 0..4 {
            let base = 4 + 4 * c;
            let col = e * Vector4::new(z[base], z[base + 1], z[base + 2], z[base + 3]);
            out.fixed_rows_mut::<4>(base).copy_from(&col);
        }
        let w = Vector4::new(z[20], z[21], z[22], z[23]);
        let w1 = e * (w - am.sensitivity(self.param, t)) + am.sensitivity(self.param, t + s);
        out.fixed_rows_mut::<4>(20).copy_from(&w1);
        out
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
        n[c] = (model.guard_values(mode, t, &yp)[index] - model.guard_values(mode, t, &ym)[index])
            / (2.0 * h);
    }
    let g_t = if let Mode::Stuck(_) = mode {
        let ht = 1e-6 / model.well_omega_rad_s();
        (model.guard_values(mode, t + ht, y)[index] - model.guard_values(mode, t - ht, y)[index])
            / (2.0 * ht)
    } else {
        0.0
    };
    (n, g_t)
}
