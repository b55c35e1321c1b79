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
//!   (A = sqrt(2) a_rms g, phase 0 as in [`crate::excitation::Sine`]);
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
//! (as issue 6 reports), and a fixed capacitor plus
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
//! [`HertzLine::force_of_delta`] in `tests/spice.rs`; [`hertz_force_closed_form`] is the same
//! formula in Rust). The Newton steps are `.func` definitions that ngspice inlines, so ngspice
//! differentiates the closed form exactly for its Newton-Raphson.
//! The tension-free variant (`endstop.tension_free = true`) clips the bracket of eq 1 at zero
//! with `max`/`min`.
//!
//! # Initial condition
//! The transient always starts with `uic` from [`InitialCondition`] (set with `.ic` on every
//! state node), so ngspice starts from the same state as our integrator; the rest state of
//! [`crate::model::Harvester::rest_state`] has both node voltages zero. The sensing nodes
//! `s1`, `s2` are set to Vb as well: left out of `.ic`, they would start at 0 V, the fixed
//! capacitors would start uncharged, and the first time step would dump the bias charge into the
//! loads.
//!
//! # Units of the tolerances
//! ngspice's `abstol` (amperes) applies to the mechanical side in mN and `vntol` (volts) in um
//! and mm/s; `chgtol` (coulombs) applies to the capacitor charges, which on the mechanical side
//! are momenta (kg mm/s) and 1e-3 x (um). The `crosscheck` experiment documents the settings
//! that make ngspice agree with our integrator, and what ngspice's defaults do.

use std::fmt::Write as _;

use thiserror::Error;

use crate::excitation::Sine;
use crate::hertz::HertzLine;
use crate::model::{Harvester, State};
use crate::params::{Device, StiffnessModel};

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
    /// [`crate::model::Harvester::rest_state`].
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
        let model = Harvester::new(device, Sine::from_rms_g(0.0, 1.0));
        let el = model.electrical(y);
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

/// Formats a number for the netlist: the shortest text that reads back as the same `f64`, in
/// plain decimal between 1e-3 and 1e6 and in scientific notation otherwise.
fn num(x: f64) -> String {
    let a = x.abs();
    if x == 0.0 || (1e-3..1e6).contains(&a) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// The closed-form Hertz inverse written into the netlist, evaluated in Rust: the force (N) at
/// penetration `delta_m` (m), zero for delta <= 0. Starting value d / (1 - ln d), then
/// `newton_steps` steps f <- (f - d) / ln f on d = f (1 - ln f).
pub fn hertz_force_closed_form(h: &HertzLine, delta_m: f64, newton_steps: usize) -> f64 {
    if delta_m <= 0.0 {
        return 0.0;
    }
    let d = delta_m / h.delta_scale_m();
    let mut f = d / (1.0 - d.ln());
    for _ in 0..newton_steps {
        f = (f - d) / f.ln();
    }
    h.force_scale_n() * f
}

/// The ngspice netlist of `device` driven by `drive` (see the module documentation for the
/// analogue and its units).
pub fn netlist(device: &Device, drive: &SpiceDrive, opts: &SpiceOptions) -> String {
    let g = &device.geometry;
    let mech = &device.mechanics;
    let e = &device.electrical;
    let es = &device.endstop;
    let mut s = String::new();
    let title = opts.title.replace(['\n', '\r'], " ");
    let _ = writeln!(s, "* {title}");
    let _ = writeln!(
        s,
        "* Generated by endstop {} (src/spice.rs): device `{}`, parameter set `{}`.",
        env!("CARGO_PKG_VERSION"),
        device.name,
        device.params
    );
    s.push_str(
        "* Le & Halvorsen 2012, eqs 1, 6-10, 19, as a force-current analogue (Figure 6).\n\
         * Units: V(xpos) = x in um, V(vel) = dx/dt in mm/s, branch currents of the\n\
         * mechanical side = forces in mN; electrical nodes n1, n2, bias in volts.\n",
    );
    let _ = writeln!(
        s,
        "* Drive: a(t) = sqrt(2) * {} g * sin(2 pi {} Hz t), g = {} m/s^2.",
        num(drive.accel_rms_g),
        num(drive.freq_hz),
        num(crate::G)
    );

    // Parameters, in netlist units (the comment gives the SI value).
    s.push_str("\n* --- parameters (netlist units) ---\n");
    fn param(s: &mut String, name: &str, value: f64, comment: &str) {
        let _ = writeln!(s, ".param {name} = {}  $ {comment}", num(value));
    }
    param(
        &mut s,
        "mass",
        mech.mass_kg,
        "proof mass (kg) = mass capacitor (F)",
    );
    param(&mut s, "bdamp", mech.damping_n_s_per_m, "damping b (N s/m)");
    param(&mut s, "km", mech.stiffness_n_per_m, "suspension km (N/m)");
    param(
        &mut s,
        "x0",
        g.finger_overlap_m * units::X_PER_M,
        "finger overlap x0 (um)",
    );
    param(
        &mut s,
        "xmax",
        g.endstop_gap_m * units::X_PER_M,
        "end-stop position xmax (um)",
    );
    param(
        &mut s,
        "c0",
        e.c0_f,
        "nominal transducer capacitance C0 (F)",
    );
    param(&mut s, "cp", e.cp_f, "parasitic capacitance Cp (F)");
    param(
        &mut s,
        "rl",
        e.load_resistance_ohm,
        "load resistance RL (ohm)",
    );
    param(
        &mut s,
        "cl",
        e.load_capacitance_f,
        "load capacitance CL (F)",
    );
    param(&mut s, "vb", e.bias_v, "bias Vb (V)");
    param(
        &mut s,
        "bim",
        es.damping_n_s_per_m,
        "end-stop damping b_im (N s/m)",
    );
    param(
        &mut s,
        "famp",
        mech.mass_kg * drive.amplitude_m_s2() * units::F_PER_N,
        "peak inertial force m A (mN)",
    );
    param(&mut s, "freq", drive.freq_hz, "drive frequency (Hz)");
    let hertz = HertzLine::of(device);
    match es.stiffness {
        StiffnessModel::Linear => {
            let k = device.linear_endstop_stiffness_n_per_m();
            let _ = writeln!(s, "* linear end-stop law, eq 19: k_im = {} N/m", num(k));
            param(
                &mut s,
                "kim",
                k * units::F_PER_N / units::X_PER_M,
                "k_im (mN/um) = 1e-3 k_im (N/m)",
            );
        }
        StiffnessModel::Hertz => {
            let _ = writeln!(
                s,
                "* Hertz line contact, eq 6: F0 = t^3/(2 lambda R), delta0 = t^2/R"
            );
            param(
                &mut s,
                "hf0",
                hertz.force_scale_n() * units::F_PER_N,
                "force scale F0 (mN)",
            );
            param(
                &mut s,
                "hd0",
                hertz.delta_scale_m() * units::X_PER_M,
                "penetration scale delta0 (um)",
            );
        }
    }

    // The spring law F_k(delta) in mN for delta in um, as a .func.
    s.push_str("\n* --- end-stop spring law F_k(delta): delta in um, force in mN ---\n");
    match es.stiffness {
        StiffnessModel::Linear => {
            s.push_str(".func fk(dl) {kim*dl}\n");
        }
        StiffnessModel::Hertz => {
            let n = opts.hertz_newton_steps;
            let _ = writeln!(
                s,
                "* Inverse of d = f (1 - ln f) (Figure 5): f0 = d/(1 - ln d), then {n} Newton\n\
                 * steps f <- (f - d)/ln f (closed form; ngspice has no Lambert W)."
            );
            s.push_str(".func hzs(d) {d/(1-ln(d))}\n");
            s.push_str(".func hzn(f,d) {(f-d)/ln(f)}\n");
            let mut expr = "hzs(d)".to_string();
            for _ in 0..n {
                expr = format!("hzn({expr},d)");
            }
            let _ = writeln!(s, ".func hzf(d) {{{expr}}}");
            s.push_str(".func fk(dl) {hf0*hzf(max(dl,1e-30)/hd0)}\n");
        }
    }

    // Mechanical side.
    s.push_str(
        "\n* --- mechanical domain (force-current analogue), eq 7 ---\n\
         Cm vel 0 {mass}\n\
         Rb vel 0 {1/bdamp}\n\
         Gk vel 0 xpos 0 {km*1e-3}\n\
         * integrator: 1e-3 d V(xpos)/dt = V(vel), i.e. dx[um]/dt = 1e3 v[mm/s]\n\
         Cx xpos 0 1e-3\n\
         Gx 0 xpos vel 0 1\n\
         * inertial force m a(t), into node vel\n\
         Ia 0 vel SIN(0 {famp} {freq} 0 0 0)\n\
         * electrostatic force +1/2 sum (V_i - Vb)^2 dC_i/dx (eq 9), in mN\n\
         Bfe 0 vel I = {0.5e9*c0/x0} * ((V(n1)-V(bias))*(V(n1)-V(bias)) - (V(n2)-V(bias))*(V(n2)-V(bias)))\n",
    );
    s.push_str("* end-stop force F_im of eq 1 (along +x, leaving node vel), in mN\n");
    let (upper, lower) = if es.tension_free {
        (
            "max(fk(V(xpos)-xmax) + bim*V(vel), 0)",
            "min(-fk(-V(xpos)-xmax) + bim*V(vel), 0)",
        )
    } else {
        (
            "fk(V(xpos)-xmax) + bim*V(vel)",
            "-fk(-V(xpos)-xmax) + bim*V(vel)",
        )
    };
    let _ = writeln!(
        s,
        "Bim vel 0 I = (V(xpos) > xmax) ? ({upper}) : ((V(xpos) < -xmax) ? ({lower}) : 0)"
    );

    // Electrical side.
    s.push_str(
        "\n* --- electrical domain, eqs 8 and 10 ---\n\
         Vbias bias 0 DC {vb}\n\
         * transducer 1: C1(x) + Cp = (C0 + Cp) + C0 x/x0; fixed part plus motional current.\n\
         * Vs1 senses the fixed capacitor's current (C0 + Cp) d(V1 - Vb)/dt.\n\
         C1 n1 s1 {c0+cp}\n\
         Vs1 s1 bias DC 0\n\
         B1 n1 bias I = {c0/x0} * (1e3*V(vel)*(V(n1)-V(bias)) + V(xpos)*I(Vs1)/(c0+cp))\n\
         RL1 n1 0 {rl}\n\
         CL1 n1 0 {cl}\n\
         * transducer 2: C2(x) + Cp = (C0 + Cp) - C0 x/x0\n\
         C2 n2 s2 {c0+cp}\n\
         Vs2 s2 bias DC 0\n\
         B2 n2 bias I = {-c0/x0} * (1e3*V(vel)*(V(n2)-V(bias)) + V(xpos)*I(Vs2)/(c0+cp))\n\
         RL2 n2 0 {rl}\n\
         CL2 n2 0 {cl}\n",
    );

    // Initial condition, options, analysis.
    let ic = &opts.initial;
    s.push_str("\n* --- initial state (applied with uic) ---\n");
    let _ = writeln!(
        s,
        ".ic V(xpos)={} V(vel)={} V(n1)={} V(n2)={} V(bias)={vb} V(s1)={vb} V(s2)={vb}",
        num(ic.x_m * units::X_PER_M),
        num(ic.v_m_per_s * units::V_PER_M_PER_S),
        num(ic.v1_v),
        num(ic.v2_v),
        vb = num(e.bias_v)
    );
    s.push_str("\n* --- solver settings ---\n");
    let sv = &opts.solver;
    let mut o: Vec<String> = Vec::new();
    for (name, val) in [
        ("reltol", sv.reltol),
        ("abstol", sv.abstol),
        ("vntol", sv.vntol),
        ("chgtol", sv.chgtol),
        ("trtol", sv.trtol),
    ] {
        if let Some(v) = val {
            o.push(format!("{name}={}", num(v)));
        }
    }
    match sv.method {
        Method::Trapezoidal => o.push("method=trap".into()),
        Method::Gear { maxord } => {
            o.push("method=gear".into());
            o.push(format!("maxord={maxord}"));
        }
    }
    let _ = writeln!(s, ".options {}", o.join(" "));
    let tr = &opts.transient;
    match sv.max_step_s {
        Some(h) => {
            let _ = writeln!(
                s,
                ".tran {} {} {} {} uic",
                num(tr.step_s),
                num(tr.stop_s),
                num(tr.save_from_s),
                num(h)
            );
        }
        None => {
            let _ = writeln!(
                s,
                ".tran {} {} {} uic",
                num(tr.step_s),
                num(tr.stop_s),
                num(tr.save_from_s)
            );
        }
    }
    if let Some(file) = &tr.wrdata_file {
        s.push_str("\n.control\nset wr_singlescale\nset wr_vecnames\noption numdgt=15\nrun\n");
        let _ = writeln!(s, "wrdata {file} {}", WRDATA_VECTORS.join(" "));
        // Without `quit`, `ngspice -b` goes on to look for .print lines and exits with status 1.
        s.push_str("quit\n.endc\n");
    }
    s.push_str(".end\n");
    s
}

/// Failure to read ngspice output.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum SpiceError {
    /// The output is empty or has no header line.
    #[error("wrdata output is empty")]
    Empty,
    /// A line does not have the expected number of numeric columns.
    #[error("wrdata line {line}: expected {expected} numeric columns, found `{text}`")]
    BadLine {
        /// 1-based line number.
        line: usize,
        /// Columns expected from the header.
        expected: usize,
        /// The offending line (truncated).
        text: String,
    },
    /// A requested column is not in the header.
    #[error("wrdata output has no column `{0}`")]
    NoColumn(String),
    /// The data do not cover a requested time window.
    #[error("time window {t0:e} .. {t1:e} s not covered by the data ({first:e} .. {last:e} s)")]
    Window {
        /// Requested start (s).
        t0: f64,
        /// Requested end (s).
        t1: f64,
        /// First time in the data (s).
        first: f64,
        /// Last time in the data (s).
        last: f64,
    },
}

/// A table read from ngspice's `wrdata` with `wr_singlescale` and `wr_vecnames`: a header of
/// vector names (the first is `time`) and one row per time point.
#[derive(Debug, Clone, PartialEq)]
pub struct Waveforms {
    /// Column names (lower case), `time` first.
    pub names: Vec<String>,
    /// Time points (s).
    pub time: Vec<f64>,
    /// One vector per column after `time`.
    pub columns: Vec<Vec<f64>>,
}

/// Parses the text of a `wrdata` file (see [`Transient::wrdata_file`]).
pub fn parse_wrdata(text: &str) -> Result<Waveforms, SpiceError> {
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let (_, header) = lines.next().ok_or(SpiceError::Empty)?;
    let names: Vec<String> = header
        .split_whitespace()
        .map(|n| n.to_ascii_lowercase())
        .collect();
    if names.is_empty() {
        return Err(SpiceError::Empty);
    }
    let ncol = names.len();
    let mut time = Vec::new();
    let mut columns = vec![Vec::new(); ncol - 1];
    for (i, line) in lines {
        let vals: Result<Vec<f64>, _> = line.split_whitespace().map(str::parse::<f64>).collect();
        match vals {
            Ok(v) if v.len() == ncol => {
                time.push(v[0]);
                for (c, x) in columns.iter_mut().zip(&v[1..]) {
                    c.push(*x);
                }
            }
            _ => {
                return Err(SpiceError::BadLine {
                    line: i + 1,
                    expected: ncol,
                    text: line.chars().take(120).collect(),
                })
            }
        }
    }
    Ok(Waveforms {
        names,
        time,
        columns,
    })
}

impl Waveforms {
    /// The samples of a column by name (`v(n1)`, case-insensitive).
    pub fn column(&self, name: &str) -> Result<&[f64], SpiceError> {
        let key = name.to_ascii_lowercase();
        self.names
            .iter()
            .skip(1)
            .position(|n| *n == key)
            .map(|i| self.columns[i].as_slice())
            .ok_or(SpiceError::NoColumn(name.to_string()))
    }

    /// Number of time points.
    pub fn len(&self) -> usize {
        self.time.len()
    }

    /// True if there are no time points.
    pub fn is_empty(&self) -> bool {
        self.time.is_empty()
    }

    fn check_window(&self, t0: f64, t1: f64) -> Result<(), SpiceError> {
        let first = self.time.first().copied().unwrap_or(f64::NAN);
        let last = self.time.last().copied().unwrap_or(f64::NAN);
        // Allow a relative slack of 1e-9 of the window for the float time stamps.
        let slack = 1e-9 * (t1 - t0).abs();
        let ordered = t0.partial_cmp(&t1) == Some(std::cmp::Ordering::Less);
        if self.time.len() < 2 || !ordered || first > t0 + slack || last < t1 - slack {
            return Err(SpiceError::Window {
                t0,
                t1,
                first,
                last,
            });
        }
        Ok(())
    }

    /// Integral of g(y) over [t0, t1] for the column `name`, with y linearly interpolated
    /// between time points and each piece integrated by Simpson's rule (exact for g(y) = y^2).
    fn integrate(
        &self,
        name: &str,
        t0: f64,
        t1: f64,
        g: impl Fn(f64) -> f64,
    ) -> Result<f64, SpiceError> {
        self.check_window(t0, t1)?;
        let y = self.column(name)?;
        let t = &self.time;
        let at = |k: usize, tt: f64| {
            let h = t[k + 1] - t[k];
            if h <= 0.0 {
                y[k + 1]
            } else {
                y[k] + (y[k + 1] - y[k]) * (tt - t[k]) / h
            }
        };
        let mut acc = 0.0;
        for k in 0..t.len() - 1 {
            let a = t[k].max(t0);
            let b = t[k + 1].min(t1);
            if b <= a {
                continue;
            }
            let (ya, yb) = (at(k, a), at(k, b));
            let ym = at(k, 0.5 * (a + b));
            acc += (b - a) / 6.0 * (g(ya) + 4.0 * g(ym) + g(yb));
        }
        Ok(acc)
    }

    /// RMS of a column over [t0, t1] (the piecewise-linear interpolant's RMS).
    pub fn rms(&self, name: &str, t0: f64, t1: f64) -> Result<f64, SpiceError> {
        Ok((self.integrate(name, t0, t1, |y| y * y)? / (t1 - t0)).sqrt())
    }

    /// Largest |y| of a column at the time points inside [t0, t1].
    pub fn max_abs(&self, name: &str, t0: f64, t1: f64) -> Result<f64, SpiceError> {
        self.check_window(t0, t1)?;
        let y = self.column(name)?;
        Ok(self
            .time
            .iter()
            .zip(y)
            .filter(|(t, _)| **t >= t0 && **t <= t1)
            .fold(0.0, |m, (_, v)| m.max(v.abs())))
    }

    /// Fraction of [t0, t1] during which |y| > `level` (piecewise-linear interpolant, crossing
    /// times interpolated).
    pub fn fraction_above(
        &self,
        name: &str,
        level: f64,
        t0: f64,
        t1: f64,
    ) -> Result<f64, SpiceError> {
        self.check_window(t0, t1)?;
        let y = self.column(name)?;
        let t = &self.time;
        let mut above = 0.0;
        for k in 0..t.len() - 1 {
            let a = t[k].max(t0);
            let b = t[k + 1].min(t1);
            if b <= a {
                continue;
            }
            // Subdivide at the crossings of +level and -level of the linear piece.
            let h = t[k + 1] - t[k];
            let lin = |tt: f64| y[k] + (y[k + 1] - y[k]) * (tt - t[k]) / h;
            let mut cuts = vec![a, b];
            for lv in [level, -level] {
                let dy = y[k + 1] - y[k];
                if dy != 0.0 {
                    let tc = t[k] + (lv - y[k]) / dy * h;
                    if tc > a && tc < b {
                        cuts.push(tc);
                    }
                }
            }
            cuts.sort_by(f64::total_cmp);
            for w in cuts.windows(2) {
                if lin(0.5 * (w[0] + w[1])).abs() > level {
                    above += w[1] - w[0];
                }
            }
        }
        Ok(above / (t1 - t0))
    }
}
