//! The lumped electromechanical model with end-stops (eqs 1-2 and 7-10).
//!
//! Mechanics (eq 7): m x'' + b x' + km x + F_e + F_im = m a(t).
//!
//! Transducers (eq 10): C_1,2(x) = C0 (1 +- x/x0), each with Cp in parallel. The bias Vb is on
//! the proof mass; fixed electrode i is a node with voltage V_i that goes to ground through RL
//! in parallel with CL. With node charge Q_i = (C_i + Cp)(V_i - Vb) + CL V_i (eq 8 plus the
//! load capacitor), the explicit state is (x, v, s_1, s_2) where s_i = Q_i + (C0 + Cp) Vb is
//! the node charge measured from its rest value (so that the state has no large constant
//! offset, which would spoil the relative error control):
//!
//! * V_i = (s_i + (C_i - C0) Vb) / (C_i + Cp + CL),
//! * ds_i/dt = -V_i / RL,
//! * electrostatic force on the mass +1/2 sum_i (V_i - Vb)^2 dC_i/dx (eq 9, i.e. -F_e of eq 7).
//!
//! End-stop (eqs 1-2): for |x| > xmax, delta = |x| - xmax and
//! F_im = sign(x) (F_k(delta) + b_im d(delta)/dt) with F_k the Hertz law (eq 6) or the linear
//! law of eq 19. With `tension_free` the bracket is clipped at zero, so the stop never pulls.
//!
//! Modes for the integrator ([`crate::physics::contact::Mode`]): `Free`, `Contact(side)` and (tension-free only) `Clipped(side)`,
//! where the mass is past the stop but the contact force would be tensile.

use nalgebra::{Matrix4, SMatrix, SVector};

use crate::device::{Device, StiffnessModel};
use crate::drive::Excitation;
use crate::ode::{Guards, HybridSystem, Options};
use crate::physics::contact::{ContactLaw, Mode, Side};
use crate::physics::hertz::HertzLine;

/// State (x in m, v in m/s, s1 and s2 in C).
pub type State = SVector<f64, 4>;

/// The harvester driven by an excitation: a [`HybridSystem`] of dimension 4.
#[derive(Debug, Clone)]
pub struct Harvester<E: Excitation> {
    /// Proof mass m (kg).
    pub mass_kg: f64,
    /// Mechanical damping b (N s/m).
    pub damping: f64,
    /// Suspension stiffness km (N/m).
    pub km: f64,
    /// Finger overlap x0 (m).
    pub x0: f64,
    /// End-stop position xmax (m).
    pub xmax: f64,
    /// C0 (F).
    pub c0: f64,
    /// Cp (F).
    pub cp: f64,
    /// CL (F).
    pub cl: f64,
    /// RL (ohm).
    pub rl: f64,
    /// Vb (V).
    pub vb: f64,
    /// Spring law of the stop.
    pub law: ContactLaw,
    /// End-stop damping b_im (N s/m).
    pub bim: f64,
    /// Clip the contact force at zero.
    pub tension_free: bool,
    /// The base acceleration.
    pub excitation: E,
}

/// Derived electrical quantities at one state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Electrical {
    /// Node voltages V1, V2 (V).
    pub v: [f64; 2],
    /// Transducer capacitances C1, C2 (F).
    pub c: [f64; 2],
}

impl<E: Excitation> Harvester<E> {
    /// Builds the model of a device (at its bias voltage and end-stop options).
    pub fn new(device: &Device, excitation: E) -> Self {
        let law = match device.endstop.stiffness {
            StiffnessModel::Hertz => ContactLaw::Hertz(HertzLine::of(device)),
            StiffnessModel::Linear => ContactLaw::Linear(device.linear_endstop_stiffness_n_per_m()),
        };
        let e = &device.electrical;
        Self {
            mass_kg: device.mechanics.mass_kg,
            damping: device.mechanics.damping_n_s_per_m,
            km: device.mechanics.stiffness_n_per_m,
            x0: device.geometry.finger_overlap_m,
            xmax: device.geometry.endstop_gap_m,
            c0: e.c0_f,
            cp: e.cp_f,
            cl: e.load_capacitance_f,
            rl: e.load_resistance_ohm,
            vb: e.bias_v,
            law,
            bim: device.endstop.damping_n_s_per_m,
            tension_free: device.endstop.tension_free,
            excitation,
        }
    }

    /// Replaces the excitation, keeping the device.
    pub fn with_excitation<F: Excitation>(&self, excitation: F) -> Harvester<F> {
        Harvester {
            mass_kg: self.mass_kg,
            damping: self.damping,
            km: self.km,
            x0: self.x0,
            xmax: self.xmax,
            c0: self.c0,
            cp: self.cp,
            cl: self.cl,
            rl: self.rl,
            vb: self.vb,
            law: self.law,
            bim: self.bim,
            tension_free: self.tension_free,
            excitation,
        }
    }

    /// The rest state: x = v = 0 and both node voltages zero.
    pub fn rest_state(&self) -> State {
        State::zeros()
    }

    /// The state at position `x` and velocity `v` with the charges at their static
    /// equilibrium: both node voltages zero (s_i = -+ dC Vb, dC = C0 x / x0).
    pub fn static_state(&self, x: f64, v: f64) -> State {
        let dc = self.c0 * x / self.x0;
        State::new(x, v, -dc * self.vb, dc * self.vb)
    }

    /// Capacitances and node voltages at a state.
    #[inline]
    pub fn electrical(&self, y: &State) -> Electrical {
        let dc = self.c0 * y[0] / self.x0;
        let c1 = self.c0 + dc;
        let c2 = self.c0 - dc;
        let v1 = (y[2] + dc * self.vb) / (c1 + self.cp + self.cl);
        let v2 = (y[3] - dc * self.vb) / (c2 + self.cp + self.cl);
        Electrical {
            v: [v1, v2],
            c: [c1, c2],
        }
    }

    /// Penetration delta into the stop on `side` (m; negative when not touching).
    #[inline]
    pub fn penetration(&self, side: Side, x: f64) -> f64 {
        side.sign() * x - self.xmax
    }

    /// The bracket F_k(delta) + b_im d(delta)/dt of eq 1 for a side (N).
    #[inline]
    pub fn contact_bracket(&self, side: Side, y: &State) -> f64 {
        let delta = self.penetration(side, y[0]);
        self.law.force(delta) + self.bim * side.sign() * y[1]
    }

    /// End-stop force F_im of eq 1 in a mode (N, along +x, as in eq 7's left-hand side).
    #[inline]
    pub fn endstop_force(&self, mode: Mode, y: &State) -> f64 {
        match mode {
            Mode::Contact(side) => {
                let b = self.contact_bracket(side, y);
                let b = if self.tension_free { b.max(0.0) } else { b };
                side.sign() * b
            }
            _ => 0.0,
        }
    }

    /// Electrostatic force on the mass, +1/2 sum (V_i - Vb)^2 dC_i/dx (N).
    #[inline]
    pub fn electrostatic_force(&self, el: &Electrical) -> f64 {
        let dcdx = self.c0 / self.x0;
        let u1 = el.v[0] - self.vb;
        let u2 = el.v[1] - self.vb;
        0.5 * dcdx * (u1 * u1 - u2 * u2)
    }

    /// The Jacobian of the right-hand side with respect to the state, in a mode (the drive
    /// enters additively and does not appear). Used by the variational equations of periodic
    /// orbits ([`crate::study::orbit`]).
    ///
    /// With a = C0/x0, D_i = C_i + Cp + CL and u_i = V_i - Vb: dV1/dx = a (Vb - V1)/D1,
    /// dV2/dx = -a (Vb - V2)/D2, dV_i/ds_i = 1/D_i; the electrostatic force 1/2 a (u1^2 - u2^2)
    /// then differentiates by the chain rule, and in contact the end-stop force adds the
    /// spring's stiffness to d/dx and b_im to d/dv (a tension-free contact whose force is
    /// clipped adds nothing).
    pub fn jacobian(&self, mode: Mode, y: &State) -> Matrix4<f64> {
        let el = self.electrical(y);
        let a = self.c0 / self.x0;
        let d1 = el.c[0] + self.cp + self.cl;
        let d2 = el.c[1] + self.cp + self.cl;
        let (u1, u2) = (el.v[0] - self.vb, el.v[1] - self.vb);
        let dv1_dx = -a * u1 / d1;
        let dv2_dx = a * u2 / d2;
        let dfe_dx = a * (u1 * dv1_dx - u2 * dv2_dx);
        let dfe_ds1 = a * u1 / d1;
        let dfe_ds2 = -a * u2 / d2;
        let (mut dfim_dx, mut dfim_dv) = (0.0, 0.0);
        if let Mode::Contact(side) = mode {
            if !self.tension_free || self.contact_bracket(side, y) > 0.0 {
                dfim_dx = self.law.stiffness(self.penetration(side, y[0]));
                dfim_dv = self.bim;
            }
        }
        let m = self.mass_kg;
        let g = 1.0 / self.rl;
        Matrix4::new(
            0.0,
            1.0,
            0.0,
            0.0,
            (-self.km + dfe_dx - dfim_dx) / m,
            (-self.damping - dfim_dv) / m,
            dfe_ds1 / m,
            dfe_ds2 / m,
            -g * dv1_dx,
            0.0,
            -g / d1,
            0.0,
            -g * dv2_dx,
            0.0,
            0.0,
            -g / d2,
        )
    }

    /// Characteristic scales of (x, v, s1, s2), used for absolute tolerances.
    pub fn scales(&self) -> State {
        let w0 = ((self.km) / self.mass_kg).sqrt();
        let x = self.xmax;
        let q = self.c0 * self.vb.max(1.0) * x / self.x0;
        State::new(x, w0 * x, q, q)
    }

    /// The free-flight model split into its linearisation about rest and a small remainder,
    /// for [`crate::ode::exponential`] (see [`FreeFlight`]).
    pub fn free_flight(&self) -> FreeFlight {
        let ct = self.c0 + self.cp + self.cl;
        FreeFlight {
            dcdx: self.c0 / self.x0,
            vb: self.vb,
            ct,
            gamma: self.c0 * self.vb / self.x0,
            inv_ct: 1.0 / ct,
            inv_mass: 1.0 / self.mass_kg,
            inv_rl: 1.0 / self.rl,
            inv_ct_rl: 1.0 / (ct * self.rl),
            mass_kg: self.mass_kg,
            damping: self.damping,
            km: self.km,
        }
    }

    /// Integrator options with relative tolerance `rtol` and absolute tolerances
    /// `rtol` times [`Harvester::scales`].
    pub fn solver_options(&self, rtol: f64) -> Options<4> {
        let w0 = (self.km / self.mass_kg).sqrt();
        Options {
            rtol,
            atol: self.scales() * rtol,
            h_max: 0.02 * 2.0 * std::f64::consts::PI / w0,
            // Absolute floor; the smallest step grows with |t| (`Options::min_step`).
            h_min: 1e-16,
            h_init: 1e-7,
            max_steps: 50_000_000,
            event_time_tol: 1e-14,
        }
    }
}

/// The harvester in free flight (no contact force) as `y' = L y + c a(t) + N(y)`: `L` is the
/// model of eqs 7-10 linearised about rest, `c = (0, 1, 0, 0)` takes the base acceleration,
/// and `N` is the remainder, which comes only from the capacitances' dependence on x (eq 10):
/// with `Ct = C0 + Cp + CL`, `Gamma = C0 Vb / x0` and `dC = C0 x / x0`,
///
/// * `L`: `x' = v`, `m v' = -(km + 2 Gamma²/Ct) x - b v - Gamma (s1 - s2)/Ct`,
///   `RL s1' = -(s1 + Gamma x)/Ct`, `RL s2' = -(s2 - Gamma x)/Ct`
///   (the differential two-port of eqs 11-17, with the common mode beside it);
/// * `N`: `m N_v = (C0/x0) [ (V1² - V2²)/2 + Vb (dC/Ct) (V1 + V2) ]`,
///   `RL N_s1 = V1 dC/Ct`, `RL N_s2 = -V2 dC/Ct`, with the exact node voltages of
///   [`Harvester::electrical`].
///
/// `N` is written in closed form (not as the right-hand side minus `L y`) so that it keeps
/// its relative precision: it is of relative size `dC/Ct`, a few per cent at the stops.
/// [`FreeFlight::linear`] + [`FreeFlight::remainder`] equals the free-flight right-hand side
/// to rounding (tested).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FreeFlight {
    dcdx: f64,
    vb: f64,
    ct: f64,
    gamma: f64,
    inv_ct: f64,
    inv_mass: f64,
    inv_rl: f64,
    inv_ct_rl: f64,
    mass_kg: f64,
    damping: f64,
    km: f64,
}

impl FreeFlight {
    /// `(L, c)`: the linearised free-flight model and the column of the base acceleration.
    pub fn linear(&self) -> (SMatrix<f64, 4, 4>, State) {
        let (m, g, ct) = (self.mass_kg, self.gamma, self.ct);
        let k_oc = self.km + 2.0 * g * g / ct;
        let rc = self.inv_ct_rl;
        #[rustfmt::skip]
        let l = SMatrix::<f64, 4, 4>::new(
            0.0, 1.0, 0.0, 0.0,
            -k_oc / m, -self.damping / m, -g / (m * ct), g / (m * ct),
            -g * rc, 0.0, -rc, 0.0,
            g * rc, 0.0, 0.0, -rc,
        );
        (l, State::new(0.0, 1.0, 0.0, 0.0))
    }

    /// The node voltages V1, V2 at a state (V), as [`Harvester::electrical`] computes them.
    #[inline]
    pub fn voltages(&self, y: &State) -> [f64; 2] {
        let dc = self.dcdx * y[0];
        [
            (y[2] + dc * self.vb) / (self.ct + dc),
            (y[3] - dc * self.vb) / (self.ct - dc),
        ]
    }

    /// The remainder `N(y)` (see the type's docs).
    #[inline]
    pub fn remainder(&self, y: &State) -> State {
        self.remainder_and_voltages(y).0
    }

    /// The remainder `N(y)` and the node voltages it is computed from.
    #[inline]
    pub fn remainder_and_voltages(&self, y: &State) -> (State, [f64; 2]) {
        let dc = self.dcdx * y[0];
        let [v1, v2] = self.voltages(y);
        let r = dc * self.inv_ct;
        let n = State::new(
            0.0,
            self.dcdx * (0.5 * (v1 * v1 - v2 * v2) + self.vb * r * (v1 + v2)) * self.inv_mass,
            v1 * r * self.inv_rl,
            -v2 * r * self.inv_rl,
        );
        (n, [v1, v2])
    }
}

impl<E: Excitation> HybridSystem<4> for Harvester<E> {
    type Mode = Mode;

    #[inline]
    fn rhs(&self, mode: Mode, t: f64, y: &State) -> State {
        let el = self.electrical(y);
        let f = self.mass_kg * self.excitation.accel(t) - self.damping * y[1] - self.km * y[0]
            + self.electrostatic_force(&el)
            - self.endstop_force(mode, y);
        State::new(
            y[1],
            f / self.mass_kg,
            -el.v[0] / self.rl,
            -el.v[1] / self.rl,
        )
    }

    #[inline]
    fn guards(&self, mode: Mode, _t: f64, y: &State) -> Guards {
        const OFF: f64 = f64::NEG_INFINITY;
        match mode {
            Mode::Free => [
                self.penetration(Side::Upper, y[0]),
                self.penetration(Side::Lower, y[0]),
                OFF,
            ],
            Mode::Contact(side) => [
                -self.penetration(side, y[0]),
                if self.tension_free {
                    -self.contact_bracket(side, y)
                } else {
                    OFF
                },
                OFF,
            ],
            Mode::Clipped(side) => [
                -self.penetration(side, y[0]),
                self.contact_bracket(side, y),
                OFF,
            ],
        }
    }

    fn switch(&self, mode: Mode, index: usize, _t: f64, y: &mut State) -> Mode {
        match (mode, index) {
            (Mode::Free, 0) => {
                y[0] = self.xmax;
                Mode::Contact(Side::Upper)
            }
            (Mode::Free, _) => {
                y[0] = -self.xmax;
                Mode::Contact(Side::Lower)
            }
            (Mode::Contact(side), 0) | (Mode::Clipped(side), 0) => {
                y[0] = side.sign() * self.xmax;
                Mode::Free
            }
            (Mode::Contact(side), _) => Mode::Clipped(side),
            (Mode::Clipped(side), _) => Mode::Contact(side),
        }
    }

    fn next_breakpoint(&self, t: f64) -> f64 {
        self.excitation.next_breakpoint(t)
    }

    fn check_state(&self, _mode: Mode, t: f64, y: &State) -> Result<(), String> {
        let el = self.electrical(y);
        if el.c[0] + self.cp <= 0.0 || el.c[1] + self.cp <= 0.0 {
            return Err(format!(
                "a transducer capacitance plus Cp is not positive at t = {t:e} s \
                 (x = {:e} m): C1+Cp = {:e} F, C2+Cp = {:e} F",
                y[0],
                el.c[0] + self.cp,
                el.c[1] + self.cp
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::device::StiffnessModel;
    use crate::drive::Sine;
    use crate::physics::contact::Side;

    /// The analytic Jacobian equals central differences of the right-hand side, in free
    /// flight and in contact under both spring laws.
    #[test]
    fn jacobian_matches_central_differences_of_the_rhs() {
        let text = include_str!("../../data/prototype1.toml");
        let base = Device::from_toml_str(text, "prototype1.toml").unwrap();
        for law in [StiffnessModel::Hertz, StiffnessModel::Linear] {
            let h = Harvester::new(&base.with_endstop(law, 1.5), Sine::from_rms_g(5.5, 1300.0));
            let sc = h.scales();
            // A state 0.2 um into the upper stop, moving, with charged nodes.
            let y = State::new(h.xmax + 0.2e-6, 0.3, 0.4 * sc[2], -0.3 * sc[3]);
            for mode in [Mode::Free, Mode::Contact(Side::Upper)] {
                let j = h.jacobian(mode, &y);
                // Columns scaled by the state scales, so that every entry is the change of a
                // derivative over a typical change of the state; compared per row against the
                // row's largest entry.
                let mut fd = Matrix4::zeros();
                for c in 0..4 {
                    // Steps of 1e-5 of each scale: truncation ~1e-10 of the row, rounding
                    // ~1e-11 of it.
                    let e = 1e-5 * sc[c];
                    let (mut yp, mut ym) = (y, y);
                    yp[c] += e;
                    ym[c] -= e;
                    let col = (h.rhs(mode, 0.1, &yp) - h.rhs(mode, 0.1, &ym)) * (sc[c] / (2.0 * e));
                    fd.set_column(c, &col);
                }
                for r in 0..4 {
                    let row_max = (0..4).map(|c| fd[(r, c)].abs()).fold(0.0, f64::max);
                    for c in 0..4 {
                        let an = j[(r, c)] * sc[c];
                        assert!(
                            (fd[(r, c)] - an).abs() <= 1e-6 * row_max,
                            "{law:?} {mode:?} d f{r}/d y{c}: {an} vs {}",
                            fd[(r, c)]
                        );
                    }
                }
            }
        }
    }
}
