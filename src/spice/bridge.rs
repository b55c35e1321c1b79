//! The ngspice netlist of a piezoelectric harvester behind a full-wave diode bridge into a
//! storage capacitor and a resistor, for the cross-check of the interface circuits
//! ([`crate::circuits`]).
//!
//! The mechanical side is the mobility analogue of the paper's netlist (see [`crate::spice`]:
//! 1 V of `vel` = 1 mm/s, 1 V of `xpos` = 1 um, 1 A = 1 mN). The element is its clamped
//! capacitance `Cp` between nodes `p` and `n` with the controlled source `Gp p n vel 0`, which
//! draws `theta v` out of `p` (so that `Cp Vp' = -theta v` open), and it pushes the mass with
//! `Gf 0 vel p n`, `+theta Vp`. Four diodes `D1 p a`, `D2 n a`, `D3 0 p`, `D4 0 n` rectify into
//! `Cs` and `RL` between `a` and ground. The diodes are ngspice's junction diode with only the
//! Shockley law left (`IS`, `N`; no series resistance, no junction capacitance, no breakdown):
//! the law the model uses ([`crate::device::Diode::Shockley`]), at ngspice's default temperature
//! 27 degrees C, the default thermal voltage of the device description. A stop with the linear
//! law is a behavioural current source on `vel`, as in the paper's netlist. Every node has a
//! 1 GOhm resistor to ground (`rshunt`), without which ngspice cannot start from a blocking
//! bridge.

use std::fmt::Write as _;

use crate::device::{DcLoad, Device, Diode, Interface, Side, StopLaw, Transducer};
use crate::physics::transducer::State;
use crate::spice::{units, SolverSettings};

/// Why a device has no bridge netlist.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("the bridge netlist takes {0}")]
pub struct Unsupported(pub(super) &'static str);

/// A full bridge of Shockley diodes into a storage capacitor and a resistor: what the bridge
/// netlists take of a device's interface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct ShockleyBridge {
    /// The diodes' saturation current I_s (A).
    saturation_current_a: f64,
    /// Their ideality n.
    ideality: f64,
    /// Cs (F).
    storage_capacitance_f: f64,
    /// The DC load (ohm).
    resistance_ohm: f64,
}

impl ShockleyBridge {
    /// The bridge of `device`, or why the netlists do not take it: a full bridge of Shockley
    /// diodes at the default thermal voltage (ngspice's 27 degrees C) into a resistor.
    pub(super) fn of(device: &Device) -> Result<Self, Unsupported> {
        let Interface::FullBridge(rect) = &device.interface else {
            return Err(Unsupported("a full bridge"));
        };
        let Diode::Shockley {
            saturation_current_a,
            ideality,
            thermal_voltage_v,
        } = rect.diode
        else {
            return Err(Unsupported("Shockley diodes"));
        };
        if (thermal_voltage_v - crate::device::interface::THERMAL_VOLTAGE_V).abs() > 1e-12 {
            return Err(Unsupported(
                "the default thermal voltage (ngspice's 27 degrees C)",
            ));
        }
        let DcLoad::Resistor { resistance_ohm } = rect.load else {
            return Err(Unsupported("a resistor load"));
        };
        Ok(Self {
            saturation_current_a,
            ideality,
            storage_capacitance_f: rect.storage_capacitance_f,
            resistance_ohm,
        })
    }

    /// The four diodes from the AC nodes `ac` to the DC nodes `dc` (positive, negative), their
    /// model, and `Cs` and `RL` across the DC nodes.
    pub(super) fn write(&self, s: &mut String, ac: [&str; 2], dc: [&str; 2]) {
        let ([p, n], [a, b]) = (ac, dc);
        for (name, anode, cathode) in [("D1", p, a), ("D2", n, a), ("D3", b, p), ("D4", b, n)] {
            let _ = writeln!(s, "{name} {anode} {cathode} dbridge");
        }
        let _ = writeln!(
            s,
            ".model dbridge D(IS={:e} N={} RS=0 CJO=0)",
            self.saturation_current_a, self.ideality
        );
        let _ = writeln!(s, "Cs {a} {b} {:e}", self.storage_capacitance_f);
        let _ = writeln!(s, "RL {a} {b} {:e}", self.resistance_ohm);
    }
}

/// The netlist of `device` driven by `a = amplitude sin(2 pi f t)` (m/s^2), starting from the
/// model state `y0` (the bridge's nodes put where the symmetric bridge has them: `a` at `Vs`,
/// `p` and `n` at `(Vs +- Vp) / 2`), integrated to `stop_s` with output from `save_from_s`.
#[allow(clippy::too_many_arguments)]
pub fn bridge_netlist(
    device: &Device,
    amplitude_m_s2: f64,
    freq_hz: f64,
    y0: &State,
    stop_s: f64,
    save_from_s: f64,
    solver: &SolverSettings,
    wrdata_file: &str,
) -> Result<String, Unsupported> {
    let Transducer::Piezoelectric(pz) = &device.transducer else {
        return Err(Unsupported("a piezoelectric transducer"));
    };
    let rect = ShockleyBridge::of(device)?;
    let m = &device.mechanics;
    let (xu, vu, fu) = (units::X_PER_M, units::V_PER_M_PER_S, units::F_PER_N);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "* {}: piezoelectric harvester, diode bridge, Cs, RL",
        device.name
    );
    let _ = writeln!(s, "Cm vel 0 {:e}", m.mass_kg * fu / vu);
    let _ = writeln!(s, "Rb vel 0 {:e}", vu / (m.damping_n_s_per_m * fu));
    let _ = writeln!(s, "Gk vel 0 xpos 0 {:e}", m.stiffness_n_per_m * fu / xu);
    let _ = writeln!(s, "Cx xpos 0 1e-3");
    let _ = writeln!(s, "Gx 0 xpos vel 0 {:e}", 1e-3 * xu / vu);
    let _ = writeln!(
        s,
        "Ia 0 vel SIN(0 {:e} {:e})",
        m.mass_kg * amplitude_m_s2 * fu,
        freq_hz
    );
    let theta = pz.coupling_n_per_v;
    let _ = writeln!(s, "Cpz p n {:e}", pz.capacitance_f);
    let _ = writeln!(s, "Gp p n vel 0 {:e}", theta / vu);
    let _ = writeln!(s, "Gf 0 vel p n {:e}", theta * fu);
    for (side, stop) in device.stops.present() {
        let StopLaw::Linear { stiffness_n_per_m } = stop.law else {
            return Err(Unsupported("stops with the linear law"));
        };
        let sign = match side {
            Side::Upper => 1.0,
            Side::Lower => -1.0,
        };
        let gap = stop.gap_m * xu;
        // delta (um) = sign x - gap; F (mN) = sign (k delta + b d(delta)/dt) while delta > 0.
        let _ = writeln!(
            s,
            "Bim{} vel 0 I = ({sign} * V(xpos) > {gap:e}) ? {sign} * ({:e} * ({sign} * V(xpos) - {gap:e}) + {:e} * {sign} * V(vel)) : 0",
            if sign > 0.0 { "u" } else { "l" },
            stiffness_n_per_m * fu / xu,
            stop.damping_n_s_per_m * fu / vu,
        );
    }
    rect.write(&mut s, ["p", "n"], ["a", "0"]);
    let (vp, vs) = (y0[2], y0[3]);
    let _ = writeln!(
        s,
        ".ic V(xpos)={:e} V(vel)={:e} V(a)={vs:e} V(p)={:e} V(n)={:e}",
        y0[0] * xu,
        y0[1] * vu,
        0.5 * (vs + vp),
        0.5 * (vs - vp)
    );
    // A 1 GOhm resistor from every node to ground: a blocking bridge leaves `p` and `n`
    // floating but for the diodes' reverse currents, and ngspice then stops with "timestep
    // too small" at the first step. Its currents are below 1e-5 of the element's here.
    let mut o = vec!["rshunt=1e9".to_string()];
    for (name, val) in [
        ("reltol", solver.reltol),
        ("abstol", solver.abstol),
        ("vntol", solver.vntol),
        ("chgtol", solver.chgtol),
        ("trtol", solver.trtol),
    ] {
        if let Some(v) = val {
            o.push(format!("{name}={v:e}"));
        }
    }
    if let crate::spice::Method::Gear { maxord } = solver.method {
        o.push(format!("method=gear maxord={maxord}"));
    }
    let _ = writeln!(s, ".options {}", o.join(" "));
    let h = solver.max_step_s.unwrap_or(1e-3 / freq_hz);
    let _ = writeln!(
        s,
        ".tran {:e} {stop_s:e} {save_from_s:e} {h:e} uic",
        h.min(1e-2 / freq_hz)
    );
    s.push_str("\n.control\nset wr_singlescale\nset wr_vecnames\noption numdgt=15\nrun\n");
    let _ = writeln!(s, "wrdata {wrdata_file} v(a) v(p) v(n) v(xpos) v(vel)");
    s.push_str("quit\n.endc\n.end\n");
    Ok(s)
}

/// One case of the bridge cross-check: a device file (relative to the repository), its drive
/// at the suspension's resonance, and the tolerance on the storage's mean voltage and the
/// load's mean power.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BridgeCase {
    /// The device file.
    pub file: &'static str,
    /// RMS base acceleration (g).
    pub accel_rms_g: f64,
    /// Largest relative difference accepted.
    pub tolerance: f64,
    /// Why.
    pub reason: &'static str,
}

/// The cases: without stops, and with a linear stop struck every period.
pub const BRIDGE_CASES: [BridgeCase; 2] = [
    BridgeCase {
        file: "data/validation/piezo_bridge_spice.toml",
        accel_rms_g: 0.1,
        tolerance: 1e-3,
        reason: "ngspice's Gear-2 truncation error at 2000 steps a period with reltol 1e-6, and \
                 the drift of ten periods from our section",
    },
    BridgeCase {
        file: "data/validation/piezo_bridge_spice_stop.toml",
        accel_rms_g: 0.5,
        tolerance: 5e-3,
        reason: "as above, and ngspice steps over the switch of the behavioural stop force, \
                 which we locate",
    },
];

/// Periods ngspice runs from our steady state's section; the last one is compared.
pub const BRIDGE_PERIODS: f64 = 10.0;

/// The solver settings of the bridge cross-check at drive frequency `freq_hz`.
pub fn bridge_solver(freq_hz: f64) -> SolverSettings {
    SolverSettings {
        reltol: Some(1e-6),
        abstol: Some(1e-15),
        vntol: Some(1e-9),
        chgtol: None,
        trtol: Some(1.0),
        method: crate::spice::Method::Gear { maxord: 2 },
        max_step_s: Some(1.0 / (2000.0 * freq_hz)),
    }
}

/// The storage's mean voltage (V) and the load's mean power (W) over `[t0, t1]` from ngspice's
/// `v(a)` (trapezoidal means).
pub fn dc_means(
    w: &crate::spice::Waveforms,
    load_ohm: f64,
    t0: f64,
    t1: f64,
) -> Result<(f64, f64), crate::spice::SpiceError> {
    storage_means(w, "v(a)", load_ohm, t0, t1)
}

/// The mean (V) of the storage voltage in the column `column` and the load's mean power (W)
/// over `[t0, t1]` (trapezoidal means).
pub fn storage_means(
    w: &crate::spice::Waveforms,
    column: &str,
    load_ohm: f64,
    t0: f64,
    t1: f64,
) -> Result<(f64, f64), crate::spice::SpiceError> {
    let va = w.column(column)?;
    let (mut sv, mut sp) = (0.0, 0.0);
    for i in 1..w.time.len() {
        let (a, b) = (w.time[i - 1].max(t0), w.time[i].min(t1));
        if b > a {
            sv += 0.5 * (va[i] + va[i - 1]) * (b - a);
            sp += 0.5 * (va[i] * va[i] + va[i - 1] * va[i - 1]) / load_ohm * (b - a);
        }
    }
    Ok((sv / (t1 - t0), sp / (t1 - t0)))
}
