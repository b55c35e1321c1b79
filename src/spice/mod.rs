//! SPICE netlist export of the harvester model (the paper's Figure 6), for cross-validation with
//! ngspice, and the pure helpers that read ngspice's `wrdata` output back.
//!
//! The paper's authors simulated eqs 7-10 in SPICE with the end-stop force as a behavioural
//! source (section 2.3, Figure 6). [`netlist`] writes the same model as an ngspice netlist for any
//! [`Device`], with its end-stop law (Hertz or linear, with or without tension) and a sinusoidal
//! drive. This module only builds and parses text: running ngspice is the caller's job (the
//! `crosscheck` experiment does it).
//!
//! # The analogue circuit
//! The mechanical domain uses the **force-current** (mobility) analogy: a node voltage is a
//! velocity and a current is a force, so Kirchhoff's current law at the velocity node is
//! Newton's law (eq 7). Units are scaled so that every node voltage is of order one to a hundred
//! and ngspice's absolute tolerances (`vntol`, in volts) are small against it:
//!
//! | quantity | SPICE unknown | unit |
//! |---|---|---|
//! | velocity \\(\dot x\\) | voltage of node `vel` | 1 V = 1 mm/s |
//! | displacement \\(x\\) | voltage of node `xpos` | 1 V = 1 um |
//! | force | current | 1 A = 1 mN |
//! | electrical nodes | voltages of `n1`, `n2`, `bias` | volts (unscaled) |
//!
//! With these units the elements of the mechanical side are
//!
//! * `Cm vel 0 {mass}`: the mass, a capacitor of m (kg) farads, since
//!   `F[mN] = m[kg] dv[mm/s]/dt`;
//! * `Rb vel 0 {1/bdamp}`: the damper b (N s/m), a conductance of b siemens;
//! * `Gk vel 0 xpos 0 {km*1e-3}`: the suspension, a linear transconductance
//!   (`F[mN] = 1e-3 km[N/m] x[um]`);
//! * `Cx xpos 0 1e-3` and `Gx 0 xpos vel 0 1`: the integrator dx/dt = v
//!   (`1e-3 dV(xpos)/dt = V(vel)`, i.e. `dx[um]/dt = 1e3 v[mm/s]`);
//! * `Ia 0 vel SIN(0 {1e3 m A} f)`: the inertial force m a(t), a = A sin(2 pi f t)
//!   (A = sqrt(2) a_rms g, phase 0 as in [`crate::drive::Sine`]);
//! * `Bfe 0 vel I=...`: the electrostatic force +1/2 sum_i (V_i - Vb)^2 dC_i/dx of eq 9;
//! * `Bim vel 0 I=...`: the end-stop force F_im of eq 1 (see below).
//!
//! # The transducers
//! Each transducer i is the capacitor C_i(x) + Cp = C0 (1 +- x/x0) + Cp between the proof mass
//! (node `bias`, held at Vb by `Vbias`) and the fixed electrode `n_i`, whose load RL || CL goes to
//! ground. The current leaving n_i into the transducer is dq_i/dt with q_i = (C_i(x) + Cp) u_i,
//! u_i = V_i - Vb (eq 8), i.e.
//!
//! dq_i/dt = (C0 + Cp) du_i/dt +- (C0/x0) (dx/dt u_i + x du_i/dt).
//!
//! The netlist splits it into a **fixed capacitor** `C_i n_i s_i {c0+cp}`, in series with a zero
//! volt source `Vs_i s_i bias` that senses its current (C0 + Cp) du_i/dt, and a **behavioural
//! current source** for the motional terms, with du_i/dt read from that current:
//!
//! `B_i n_i bias I = +-(C0/x0) (1e3 V(vel) u_i + V(xpos) I(Vs_i)/(C0 + Cp))`
//!
//! (x/x0 is dimensionless with both in um; 1e3 V(vel) is dx/dt in um/s). This is exact, and it
//! contains no `ddt`. Two other writings fail in ngspice 39: the whole charge inside one
//! `B_i n_i bias I = ddt((C_i(x)+Cp)(V(n_i)-V(bias)))` stops at once with "Timestep too small"
//! (we tried it), and a fixed capacitor plus
//! `+-(C0/x0) ddt(V(xpos) (V(n_i) - V(bias)))` runs but is wrong: in a case symmetric in V1 and
//! V2 (no impacts) it gave unequal V1 and V2 and RMS errors from 1e-4 to above 1e-1 depending on
//! the max step, which points at the `ddt` of a B source not being under ngspice's
//! truncation-error control. With the sensing source every derivative in the circuit is that of
//! a plain capacitor, which ngspice's step control sees.
//!
//! # The end-stop force (eq 1)
//! With delta = |x| - xmax, F_im = sign(x) (F_k(delta) + b_im d(delta)/dt) for |x| > xmax and
//! zero otherwise, written with ngspice's ternary operator on V(xpos). For the linear law of
//! eq 19, F_k = k_im delta. ngspice has no Lambert W function, so the Hertz law (the inverse of
//! eq 6, f = -d / W_{-1}(-d/e)) is written in closed form: a starting value
//! f_0 = d / (1 - ln d) followed by [`SpiceOptions::hertz_newton_steps`] Newton steps on
//! d = f (1 - ln f), each of which simplifies to f <- (f - d) / ln f. The starting value
//! overestimates f by a relative 10 % to 60 % on 1e-12 < d < 0.5 and the convergence is
//! quadratic, so 4 steps bring the relative error below 1e-11 on that range (measured against
//! [`HertzLine::force_of_delta`](crate::laws::hertz::HertzLine::force_of_delta) in
//! `tests/spice.rs`; [`hertz_force_closed_form`] is the same
//! formula in Rust). The Newton steps are `.func` definitions that ngspice inlines, so ngspice
//! differentiates the closed form exactly for its Newton-Raphson.
//! The tension-free variant (`endstop.tension_free = true`) clips the bracket of eq 1 at zero
//! with `max`/`min`.
//!
//! # Initial condition
//! The transient always starts with `uic` from [`InitialCondition`] (set with `.ic` on every
//! state node), so ngspice starts from the same state as our integrator; the rest state of
//! [`crate::model::Model::rest_state`] has both node voltages zero. The sensing nodes
//! `s1`, `s2` are set to Vb as well: left out of `.ic`, they would start at 0 V, the fixed
//! capacitors would start uncharged, and the first time step would dump the bias charge into the
//! loads.
//!
//! # Units of the tolerances
//! ngspice's `abstol` (amperes) applies to the mechanical side in mN and `vntol` (volts) in um
//! and mm/s; `chgtol` (coulombs) applies to the capacitor charges, which on the mechanical side
//! are momenta (kg mm/s) and 1e-3 x (um). The `crosscheck` experiment documents the settings
//! that make ngspice agree with our integrator, and what ngspice's defaults do.
//!
//! # Behind a bridge
//! [`bridge`] writes a piezoelectric element behind a full bridge of Shockley diodes into a
//! storage capacitor and a resistor; [`pair_bridge`] writes the paper's pair behind the same
//! bridge, from this netlist's steps and the bridge's.

pub mod bridge;
mod netlist;
pub mod pair_bridge;
mod wrdata;

use crate::device::Device;
use crate::drive::Sine;
use crate::physics::transducer::{State, TransducerModel};

pub use netlist::{hertz_force_closed_form, netlist, supports};
pub use wrdata::{parse_wrdata, SpiceError, Waveforms};

/// Default number of Newton steps of the closed-form Hertz inverse (relative error < 1e-11 on
/// 1e-12 < delta/delta0 < 0.5).
pub const HERTZ_NEWTON_STEPS: usize = 4;

/// Names of the netlist's nodes, in the order [`netlist`] writes them with `wrdata`.
pub const WRDATA_VECTORS: [&str; 4] = ["v(n1)", "v(n2)", "v(xpos)", "v(vel)"];

/// The sinusoidal base acceleration a(t) = sqrt(2) a_rms g sin(2 pi f t).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpiceDrive {
    /// RMS acceleration (g).
    pub accel_rms_g: f64,
    /// Frequency (Hz).
    pub freq_hz: f64,
}

impl SpiceDrive {
    /// Peak acceleration (m/s^2).
    pub fn amplitude_m_s2(&self) -> f64 {
        Sine::from_rms_g(self.accel_rms_g, self.freq_hz).amplitude_m_s2
    }

    /// Period (s).
    pub fn period_s(&self) -> f64 {
        1.0 / self.freq_hz
    }
}

/// Initial state of the transient in physical units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InitialCondition {
    /// Displacement x (m).
    pub x_m: f64,
    /// Velocity (m/s).
    pub v_m_per_s: f64,
    /// Node voltage V1 (V).
    pub v1_v: f64,
    /// Node voltage V2 (V).
    pub v2_v: f64,
}

impl InitialCondition {
    /// The rest state (x = v = 0, both node voltages zero), as in
    /// [`crate::model::Model::rest_state`].
    pub fn rest() -> Self {
        Self {
            x_m: 0.0,
            v_m_per_s: 0.0,
            v1_v: 0.0,
            v2_v: 0.0,
        }
    }

    /// The state (x, v, s1, s2) of our model for a device, converted to node voltages.
    pub fn from_state(device: &Device, y: &State) -> Self {
        let el = TransducerModel::of(&device.transducer).electrical(y);
        Self {
            x_m: y[0],
            v_m_per_s: y[1],
            v1_v: el.v[0],
            v2_v: el.v[1],
        }
    }
}

/// ngspice's integration method.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    /// Trapezoidal rule (ngspice's default).
    Trapezoidal,
    /// Gear (BDF) of order `maxord` (1 to 6).
    Gear {
        /// Maximum order.
        maxord: u8,
    },
}

/// Solver settings written as `.options` and into the `.tran` card. `None` leaves ngspice's
/// default (given in each field's documentation, for ngspice 39).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolverSettings {
    /// Relative tolerance `reltol` (default 1e-3).
    pub reltol: Option<f64>,
    /// Absolute current tolerance `abstol` in amperes, here mN on the mechanical side
    /// (default 1e-12).
    pub abstol: Option<f64>,
    /// Absolute voltage tolerance `vntol` in volts, here um and mm/s on the mechanical side
    /// (default 1e-6).
    pub vntol: Option<f64>,
    /// Charge tolerance `chgtol` in coulombs (default 1e-14).
    pub chgtol: Option<f64>,
    /// Truncation-error overestimation factor `trtol` (default 7).
    pub trtol: Option<f64>,
    /// Integration method (default trapezoidal).
    pub method: Method,
    /// Maximum time step, the `tmax` of `.tran` (s). `None`: ngspice's default, which is bounded
    /// by the output step and (tstop - tstart)/50.
    pub max_step_s: Option<f64>,
}

/// Maximum step of the documented settings, in steps per drive period.
pub const DOCUMENTED_STEPS_PER_PERIOD: f64 = 1000.0;

impl SolverSettings {
    /// The settings with which ngspice agrees with our integrator (see the cross-check
    /// chapter): reltol 1e-6; abstol 1e-15 A (= mN on the mechanical side); vntol 1e-9 V
    /// (= um and mm/s on the mechanical side); chgtol 1e-20 C; trapezoidal; maximum step of
    /// a thousandth of the drive period `period_s`.
    pub fn documented(period_s: f64) -> Self {
        Self {
            reltol: Some(1e-6),
            abstol: Some(1e-15),
            vntol: Some(1e-9),
            chgtol: Some(1e-20),
            trtol: None,
            method: Method::Trapezoidal,
            max_step_s: Some(period_s / DOCUMENTED_STEPS_PER_PERIOD),
        }
    }

    /// Every setting at ngspice's default.
    pub fn ngspice_defaults() -> Self {
        Self {
            reltol: None,
            abstol: None,
            vntol: None,
            chgtol: None,
            trtol: None,
            method: Method::Trapezoidal,
            max_step_s: None,
        }
    }
}

/// The transient analysis and what is written back.
#[derive(Debug, Clone, PartialEq)]
pub struct Transient {
    /// End time (s); the run starts at t = 0 from the initial condition.
    pub stop_s: f64,
    /// Output step `tstep` of `.tran` (s); also an upper bound of ngspice's default max step.
    pub step_s: f64,
    /// Results are kept from this time on (`tstart` of `.tran`, s).
    pub save_from_s: f64,
    /// If set, a `.control` block runs the analysis and writes time and
    /// [`WRDATA_VECTORS`] with `wrdata` to this file (one header line, then one row per time
    /// point); see [`parse_wrdata`].
    pub wrdata_file: Option<String>,
}

/// Everything about the netlist except the device and the drive.
#[derive(Debug, Clone, PartialEq)]
pub struct SpiceOptions {
    /// Title line (the first line of a SPICE deck).
    pub title: String,
    /// Initial state (always applied with `uic`).
    pub initial: InitialCondition,
    /// Solver settings.
    pub solver: SolverSettings,
    /// The transient analysis.
    pub transient: Transient,
    /// Newton steps of the closed-form Hertz inverse (ignored for the linear law).
    pub hertz_newton_steps: usize,
}

/// Scale factors of the analogue (SI value times factor = netlist value).
pub mod units {
    /// Displacement: m to um.
    pub const X_PER_M: f64 = 1e6;
    /// Velocity: m/s to mm/s.
    pub const V_PER_M_PER_S: f64 = 1e3;
    /// Force: N to mN.
    pub const F_PER_N: f64 = 1e3;
}
