//! ngspice on the same circuit: a piezoelectric harvester behind a bridge of Shockley diodes
//! into a storage capacitor and a resistor, without stops and with a linear stop
//! (`endstop::spice::bridge::BRIDGE_CASES`). ngspice finds its own steady state: it starts from
//! rest, as our shooting does, and runs until its transient has decayed to a tenth of the
//! case's tolerance, so that no part of a disagreement is inherited from our state. The
//! storage's mean voltage and the load's mean power over its last period must agree with ours,
//! and ngspice must show that it has settled (its last period against the period one decay
//! time earlier). ngspice is needed: without it the tests fail, naming the install (CI installs
//! it). A few seconds each with ngspice.

use std::process::Command;

use endstop::device::{DcLoad, Device};
use endstop::drive::Sine;
use endstop::physics::transducer::State;
use endstop::spice::bridge::{bridge_netlist, bridge_solver, dc_means, BridgeCase, BRIDGE_CASES};
use endstop::spice::parse_wrdata;
use endstop::study::periodic::{steady_state_from_rest, SteadySettings};

/// The periods ngspice runs from rest, and the periods in one decay time: the slowest decay of
/// the transient is bounded by the mechanical ring-up time `2 m / c` (the bridge only adds
/// damping) and the storage's `R Cs` (the bridge only adds current that pulls its voltage to
/// the steady state); a transient of relative size 1 at rest has fallen to `tolerance / 10`
/// after `ln(10 / tolerance)` of them.
fn periods(d: &Device, f: f64, r: f64, tolerance: f64) -> (f64, f64) {
    let m = &d.mechanics;
    let storage = d.interface.storage_capacitance_f().unwrap_or(0.0);
    let tau = (2.0 * m.mass_kg / m.damping_n_s_per_m).max(r * storage);
    let per_tau = (tau * f).ceil();
    ((f * tau * (10.0 / tolerance).ln()).ceil() + 1.0, per_tau)
}

fn run(case: &BridgeCase) {
    assert!(
        Command::new("ngspice").arg("-v").output().is_ok(),
        "ngspice is not on PATH: install it (apt-get install ngspice) to run this test"
    );
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(root.join(case.file)).unwrap();
    let d = Device::from_toml_str(&text, case.file).unwrap();
    let f = d.suspension_omega_rad_s() / (2.0 * std::f64::consts::PI);
    let sine = Sine::from_rms_g(case.accel_rms_g, f);
    let ours = steady_state_from_rest(&d, sine, &SteadySettings::default()).unwrap();
    let Some(DcLoad::Resistor { resistance_ohm }) = d.interface.load() else {
        unreachable!("the bridge netlist takes a resistor")
    };
    let (n, per_tau) = periods(&d, f, *resistance_ohm, case.tolerance);
    let t_end = n / f;
    let earlier = (n - 1.0 - per_tau) / f;
    let dir =
        std::env::temp_dir().join(format!("endstop-bridge-{}-{}", std::process::id(), d.name));
    std::fs::create_dir_all(&dir).unwrap();
    let net = bridge_netlist(
        &d,
        sine.amplitude_m_s2,
        f,
        &State::zeros(),
        t_end,
        earlier,
        &bridge_solver(f),
        "out.dat",
    )
    .unwrap();
    std::fs::write(dir.join("bridge.cir"), &net).unwrap();
    let out = Command::new("ngspice")
        .arg("-b")
        .arg("bridge.cir")
        .current_dir(&dir)
        .output()
        .unwrap();
    let log = String::from_utf8_lossy(&out.stdout).into_owned();
    let dat = std::fs::read_to_string(dir.join("out.dat"))
        .unwrap_or_else(|e| panic!("ngspice wrote no output ({e}):\n{net}\n{log}"));
    std::fs::remove_dir_all(&dir).ok();
    let w = parse_wrdata(&dat).unwrap();
    let (v, p) = dc_means(&w, *resistance_ohm, (n - 1.0) / f, t_end).unwrap();
    let (v0, p0) = dc_means(&w, *resistance_ohm, earlier, earlier + 1.0 / f).unwrap();
    eprintln!(
        "{}: ngspice from rest for {n} periods ({per_tau} a decay time): V_DC {v} V, P {p} W \
         (one decay time earlier {v0} V, {p0} W); ours V_DC {} V, P {} W; contact {}",
        case.file, ours.vdc_v, ours.p_dc_w, ours.contact
    );
    // Settled: a transient e^(-t/tau) of size r at the end was e r one decay time earlier, so
    // a change below 0.2 tolerance puts r below 0.12 tolerance.
    for (now, before) in [(v, v0), (p, p0)] {
        let change = (now - before).abs() / now.abs();
        assert!(
            change <= 0.2 * case.tolerance,
            "{}: ngspice has not settled: {change:e} over its last decay time",
            case.file
        );
    }
    for (o, s) in [(ours.vdc_v, v), (ours.p_dc_w, p)] {
        let rel = (o - s).abs() / o.abs();
        assert!(
            rel < case.tolerance,
            "ours {o} vs ngspice {s}: {rel:e} ({})",
            case.reason
        );
    }
}

#[test]
fn ngspice_agrees_on_a_bridge_without_stops() {
    run(&BRIDGE_CASES[0]);
}

#[test]
fn ngspice_agrees_on_a_bridge_with_a_linear_stop() {
    run(&BRIDGE_CASES[1]);
}
