//! ngspice on the same circuit: a piezoelectric harvester behind a bridge of Shockley diodes
//! into a storage capacitor and a resistor, without stops and with a linear stop
//! (`endstop::spice::bridge::BRIDGE_CASES`). ngspice starts from our steady state's section and
//! runs ten periods; the storage's mean voltage and the load's mean power over the last period
//! must agree with ours. Prints a skip message and returns when `ngspice` is not on PATH (CI
//! installs it). About a second with ngspice.

use std::process::Command;

use endstop::device::{DcLoad, Device};
use endstop::drive::Sine;
use endstop::physics::harvester::State;
use endstop::spice::bridge::{
    bridge_netlist, bridge_solver, dc_means, BridgeCase, BRIDGE_CASES, BRIDGE_PERIODS,
};
use endstop::spice::parse_wrdata;
use endstop::study::interface::{steady_state, SteadySettings};

fn run(case: &BridgeCase) {
    if Command::new("ngspice").arg("-v").output().is_err() {
        eprintln!("SKIPPED: ngspice is not on PATH");
        return;
    }
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(root.join(case.file)).unwrap();
    let d = Device::from_toml_str(&text, case.file).unwrap();
    let f = d.suspension_omega_rad_s() / (2.0 * std::f64::consts::PI);
    let sine = Sine::from_rms_g(case.accel_rms_g, f);
    let ours = steady_state(&d, sine, &State::zeros(), &SteadySettings::default()).unwrap();
    let t_end = BRIDGE_PERIODS / f;
    let t0 = (BRIDGE_PERIODS - 1.0) / f;
    let dir =
        std::env::temp_dir().join(format!("endstop-bridge-{}-{}", std::process::id(), d.name));
    std::fs::create_dir_all(&dir).unwrap();
    let net = bridge_netlist(
        &d,
        sine.amplitude_m_s2,
        f,
        &State::from(ours.state),
        t_end,
        t0,
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
    let Some(DcLoad::Resistor { resistance_ohm }) = d.interface.load() else {
        unreachable!("the bridge netlist takes a resistor")
    };
    let (v, p) = dc_means(&parse_wrdata(&dat).unwrap(), *resistance_ohm, t0, t_end).unwrap();
    eprintln!(
        "{}: ours V_DC {} V, P {} W; ngspice {v} V, {p} W; contact {}",
        case.file, ours.vdc_v, ours.p_dc_w, ours.contact
    );
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
