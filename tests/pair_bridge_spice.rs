//! ngspice on the paper's prototype 2 behind a full bridge into storage: the electrostatic pair
//! behind a bridge of Shockley diodes into a storage capacitor and a resistor
//! (`data/validation/prototype2_bridge_spice.toml`, the example `prototype2_bridge` with
//! Shockley diodes), its netlist `endstop::spice::pair_bridge`. Both sides start from rest and
//! run to their own steady state, so that no part of a disagreement is inherited: ours by
//! shooting from rest, ngspice by a transient run until what is left of its start has decayed
//! below a tenth of the tolerance. The storage's mean voltage and the load's mean power over
//! ngspice's last period must agree with ours at drives around the resonance, one of them
//! hard enough that the mass strikes its stops. ngspice is needed: without it the test fails,
//! naming the install (CI installs it). About a minute and a half with ngspice (one run of about 20 s
//! a case, two at a time), hence `#[ignore]`: `cargo test --release --test all -- pair_bridge_spice:: --ignored`.

use std::process::Command;

use endstop::device::{DcLoad, Device};
use endstop::drive::Sine;
use endstop::model::Model;
use endstop::spice::bridge::storage_means;
use endstop::spice::pair_bridge::{pair_bridge_netlist, STORAGE_VECTOR};
use endstop::spice::{
    parse_wrdata, InitialCondition, SolverSettings, SpiceDrive, SpiceOptions, Transient,
    HERTZ_NEWTON_STEPS,
};
use endstop::study::periodic::{steady_state_from_rest, PeriodicError, SteadySettings};

const FILE: &str = "data/validation/prototype2_bridge_spice.toml";

/// The drives (Hz, g RMS): the bridge conducting at the resonance and on both sides of it, and
/// a drive that puts the mass on its stops.
const CASES: [(f64, f64, bool); 4] = [
    (670.0, 0.1, false),
    (650.0, 0.2, false),
    (690.0, 0.2, false),
    (670.0, 0.4, true),
];

/// ngspice's default `gmin` (S), across every junction of the bridge.
const NGSPICE_GMIN_S: f64 = 1e-12;

/// One case's numbers.
struct Compared {
    ours_v: f64,
    ours_p: f64,
    spice_v: f64,
    spice_p: f64,
    tol_v: f64,
    tol_p: f64,
    contact: bool,
}

/// The storage voltage's scale in the shooting's residual (the model's own scales).
fn vs_scale_v(d: &Device) -> f64 {
    let scales: Result<(Vec<f64>, Vec<String>), PeriodicError> = endstop::with_harvester!(d, |h| {
        let names = h.layout().components.iter().map(|s| s.name.clone());
        Ok((h.scales().as_slice().to_vec(), names.collect()))
    });
    let (scales, names) = scales.unwrap();
    scales[names
        .iter()
        .position(|n| n == "vs")
        .expect("a vs component")]
}

fn run(d: &Device, freq_hz: f64, accel_rms_g: f64) -> Compared {
    let settings = SteadySettings::default();
    let sine = Sine::from_rms_g(accel_rms_g, freq_hz);
    let ours = steady_state_from_rest(d, sine, &settings).unwrap();
    let Some(DcLoad::Resistor { resistance_ohm: r }) = d.interface.load().cloned() else {
        panic!("{FILE}: the DC load is not a resistor")
    };
    let cs = d.interface.storage_capacitance_f().expect("a storage");
    let m = &d.mechanics;
    let solver = SolverSettings::documented(1.0 / freq_hz);
    let steps_per_period = 1.0 / (solver.max_step_s.unwrap() * freq_hz);

    // The tolerance on the storage's mean voltage (relative), from what each side's numbers
    // carry, fixed before the comparison:
    // - ours, shooting: the distance to the orbit is about the residual over 1 - |mu|, and the
    //   slowest Floquet multiplier has |mu| <= exp(-T / tau), tau = max(R Cs, 2 m / b) (the
    //   bridge and the transducer only add loss); budget 1000 rtol for Dormand-Prince's global
    //   error (as the pair bridge's outside integration in `tests/interfaces.rs` measured);
    let tau_s = f64::max(r * cs, 2.0 * m.mass_kg / m.damping_n_s_per_m);
    let dv = ours.residual * vs_scale_v(d) / (1.0 - (-1.0 / (freq_hz * tau_s)).exp());
    let e_ours = dv / ours.vdc_v.abs() + 1000.0 * settings.rtol;
    // - ngspice's integration: the same budget against its reltol, 1000 reltol;
    let e_spice = 1000.0 * solver.reltol.unwrap();
    // - ngspice's gmin across the junctions: each storage node leaks through two of them to
    //   the electrodes, whose mean is near zero, an extra load of at most 2 gmin against 1 / R;
    let e_gmin = 2.0 * NGSPICE_GMIN_S * r;
    // - the window: one period ending at ngspice's last point; the trapezoid on the step that
    //   straddles its start misplaces at most one step of the ripple, ripple / steps a period;
    let e_window = ours.ripple_v / ours.vdc_v.abs() / steps_per_period;
    // - ngspice's leftover transient: it runs until a transient of relative size 1 at rest
    //   has fallen to a tenth of the rest, and the settling check below bounds it by 0.12 of
    //   the rest (so 1.2 times the sum).
    let tol_v = 1.2 * (e_ours + e_spice + e_gmin + e_window);
    // The mean power is <Vs^2> / R: twice the relative error of the voltage.
    let tol_p = 2.0 * tol_v;

    // ngspice from rest for n periods: a transient of relative size 1 has fallen to tol_v / 10
    // after ln(10 / tol_v) slowest decay times. Its output starts a period before the earlier
    // window: ngspice's first point after `tstart` lies up to a step later, and a window that
    // started there would miss that part of its period.
    let per_tau = (tau_s * freq_hz).ceil();
    let n = (freq_hz * tau_s * (10.0 / tol_v).ln()).ceil() + 1.0;
    let (t_end, earlier) = (n / freq_hz, (n - 1.0 - per_tau) / freq_hz);
    let dir = std::env::temp_dir().join(format!(
        "endstop-pair-bridge-{}-{freq_hz}-{accel_rms_g}",
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    let opts = SpiceOptions {
        title: format!("{FILE} at {accel_rms_g} g, {freq_hz} Hz, from rest"),
        initial: InitialCondition::rest(),
        solver,
        transient: Transient {
            stop_s: t_end,
            step_s: solver.max_step_s.unwrap(),
            save_from_s: earlier - 1.0 / freq_hz,
            wrdata_file: Some("out.dat".into()),
        },
        hertz_newton_steps: HERTZ_NEWTON_STEPS,
    };
    let drive = SpiceDrive {
        accel_rms_g,
        freq_hz,
    };
    let net = pair_bridge_netlist(d, &drive, &opts, 0.0).unwrap();
    std::fs::write(dir.join("pair_bridge.cir"), &net).unwrap();
    let out = Command::new("ngspice")
        .arg("-b")
        .arg("pair_bridge.cir")
        .current_dir(&dir)
        .output()
        .unwrap();
    let log = String::from_utf8_lossy(&out.stdout).into_owned();
    let dat = std::fs::read_to_string(dir.join("out.dat"))
        .unwrap_or_else(|e| panic!("ngspice wrote no output ({e}):\n{net}\n{log}"));
    std::fs::remove_dir_all(&dir).ok();
    let w = parse_wrdata(&dat).unwrap();
    let period = 1.0 / freq_hz;
    let (v, p) = storage_means(&w, STORAGE_VECTOR, r, t_end - period, t_end).unwrap();
    let (v0, p0) = storage_means(&w, STORAGE_VECTOR, r, earlier, earlier + period).unwrap();
    eprintln!(
        "{accel_rms_g} g, {freq_hz} Hz: ngspice from rest for {n} periods ({per_tau} a decay \
         time): V_DC {v:.9e} V, P {p:.9e} W (one decay time earlier {v0:.9e} V, {p0:.9e} W); \
         ours V_DC {:.9e} V, P {:.9e} W, residual {:.1e}, contact {}; tolerance V {tol_v:.2e}, \
         P {tol_p:.2e} (ours {e_ours:.1e}, ngspice {e_spice:.1e}, gmin {e_gmin:.1e}, window \
         {e_window:.1e})",
        ours.vdc_v, ours.p_dc_w, ours.residual, ours.contact
    );
    // Settled: a transient e^(-t/tau) of size r at the end was e r one decay time earlier, so
    // a change below 0.2 tol_v puts r below 0.12 tol_v.
    for (now, before) in [(v, v0), (p, p0)] {
        let change = (now - before).abs() / now.abs();
        assert!(
            change <= 0.2 * tol_v,
            "{accel_rms_g} g, {freq_hz} Hz: ngspice has not settled: {change:e} over its last \
             decay time"
        );
    }
    Compared {
        ours_v: ours.vdc_v,
        ours_p: ours.p_dc_w,
        spice_v: v,
        spice_p: p,
        tol_v,
        tol_p,
        contact: ours.contact,
    }
}

#[test]
#[ignore = "ngspice, about 90 s: run with --ignored (CI runs it)"]
fn ngspice_agrees_on_the_pair_behind_a_bridge() {
    assert!(
        Command::new("ngspice").arg("-v").output().is_ok(),
        "ngspice is not on PATH: install it (apt-get install ngspice) to run this test"
    );
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(root.join(FILE)).unwrap();
    let d = Device::from_toml_str(&text, FILE).unwrap();
    // Two cases at a time (ngspice is single-threaded).
    let results: Vec<Compared> = std::thread::scope(|s| {
        let handles: Vec<_> = CASES
            .chunks(2)
            .map(|chunk| {
                let d = &d;
                s.spawn(move || {
                    chunk
                        .iter()
                        .map(|&(f, g, _)| run(d, f, g))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().unwrap())
            .collect()
    });
    let mut failures = Vec::new();
    for (&(f, g, contact), c) in CASES.iter().zip(&results) {
        if c.contact != contact {
            failures.push(format!(
                "{g} g, {f} Hz: contact {} where the case expects {contact}",
                c.contact
            ));
        }
        for (q, o, s, tol) in [
            ("V_DC", c.ours_v, c.spice_v, c.tol_v),
            ("P_DC", c.ours_p, c.spice_p, c.tol_p),
        ] {
            let rel = (o - s).abs() / o.abs();
            eprintln!("| {f} | {g} | {q} | {o:.6e} | {s:.6e} | {rel:.2e} | {tol:.2e} |");
            if rel.is_nan() || rel > tol {
                failures.push(format!(
                    "{g} g, {f} Hz: {q} ours {o:e}, ngspice {s:e}: {rel:e} > {tol:e}"
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
