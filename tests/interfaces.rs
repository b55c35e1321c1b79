//! The interface circuits: their checks against the closed forms (the validation chapter's
//! rows), the energy ledger of every interface, and bad input. Release build, 2-core machine:
//! about 2 s in all.

use crate::common::validation::assert_all;
use endstop::device::{Device, ParamError};
use endstop::drive::Sine;
use endstop::model::{Books, Driven, Ledger, Model};
use endstop::ode::Dopri5;
use endstop::study::periodic::PeriodicError;
use endstop::validation::interfaces::{coupling_checks, coupling_rows, weak_coupling_checks};

fn root() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).to_path_buf()
}

fn load(rel: &str) -> Device {
    let text = std::fs::read_to_string(root().join(rel)).unwrap();
    Device::from_toml_str(&text, rel).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// Standard bridge, parallel and series SSHI and SECE against their closed forms.
#[test]
fn closed_forms_in_the_weakly_coupled_limit() {
    let d = load("data/validation/piezo_bridge.toml");
    assert_all(&weak_coupling_checks(&d).unwrap());
}

/// The uncoupled closed form, given the simulated excursion, holds at every coupling; its
/// residual at the fundamental shrinks with the coupling; the first-harmonic balance holds at
/// every coupling, each within a bound derived from what it leaves out.
#[test]
fn coupling_shrinks_the_difference_and_the_balance_holds() {
    let d = load("data/validation/piezo_bridge.toml");
    let rows = coupling_rows(&d).unwrap();
    for r in &rows {
        eprintln!("{r:?}");
    }
    assert_all(&coupling_checks(&rows));
}

/// A device text: the example cantilever's mechanics with a stop, and the given transducer and
/// interface tables.
fn text(transducer: &str, interface: &str) -> String {
    format!(
        r#"
name = "t"
params = "test"
description = "test"
[mechanics]
mass_kg = 5e-3
stiffness_n_per_m = 2842.0
damping_n_s_per_m = 0.0754
[stops.upper]
gap_m = 0.1e-3
law = "linear"
stiffness_n_per_m = 28420.0
damping_n_s_per_m = 0.5
{transducer}
{interface}
"#
    )
}

const PIEZO: &str = r#"[transducer]
kind = "piezoelectric"
coupling_n_per_v = 2.67e-3
capacitance_f = 50e-9"#;

const COIL: &str = r#"[transducer]
kind = "electromagnetic"
transduction_n_per_a = 5.0
coil_resistance_ohm = 400.0
coil_inductance_h = 1e-3"#;

fn bridge(kind: &str, extra: &str, diode: &str, load: &str) -> String {
    format!(
        "[interface]\nkind = \"{kind}\"\nstorage_capacitance_f = 1e-6\n{extra}\n{diode}\n{load}\n"
    )
}

const PWL: &str =
    "[interface.diode]\nlaw = \"piecewise_linear\"\nforward_drop_v = 0.2\non_resistance_ohm = 0.0";
const PWL_RON: &str = "[interface.diode]\nlaw = \"piecewise_linear\"\nforward_drop_v = 0.2\non_resistance_ohm = 500.0";
const SHOCKLEY: &str =
    "[interface.diode]\nlaw = \"shockley\"\nsaturation_current_a = 1e-9\nideality = 1.5";
const RES: &str = "[interface.load]\nkind = \"resistor\"\nresistance_ohm = 50e3";
const BAT: &str =
    "[interface.load]\nkind = \"battery\"\nvoltage_v = 3.0\nseries_resistance_ohm = 1e3";

/// Over 20 periods from rest, at a drive that strikes the stop, the ledger of every interface
/// closes to the integrator's tolerance: drive = damping + contact + coil + diodes + switch +
/// DC load + stored.
#[test]
fn the_energy_ledger_closes_for_every_interface() {
    let cases = [
        (
            "full bridge",
            text(PIEZO, &bridge("full_bridge", "", PWL, RES)),
        ),
        (
            "full bridge, R_on",
            text(PIEZO, &bridge("full_bridge", "", PWL_RON, RES)),
        ),
        (
            "full bridge, Shockley",
            text(PIEZO, &bridge("full_bridge", "", SHOCKLEY, RES)),
        ),
        (
            "full bridge, battery",
            text(PIEZO, &bridge("full_bridge", "", PWL, BAT)),
        ),
        (
            "parallel SSHI",
            text(
                PIEZO,
                &bridge("parallel_sshi", "quality_factor = 3.0", PWL, RES),
            ),
        ),
        (
            "series SSHI",
            text(
                PIEZO,
                &bridge("series_sshi", "inversion_factor = 0.6", PWL, RES),
            ),
        ),
        (
            "SECE",
            text(PIEZO, &bridge("sece", "efficiency = 0.8", "", RES)),
        ),
        (
            "coil, full bridge",
            text(COIL, &bridge("full_bridge", "", PWL, RES)),
        ),
        (
            "coil without inductance, full bridge",
            text(
                &COIL.replace("1e-3", "0.0"),
                &bridge("full_bridge", "", PWL, RES),
            ),
        ),
    ];
    for (name, t) in cases {
        let d = Device::from_toml_str(&t, name).unwrap_or_else(|e| panic!("{name}: {e}"));
        let f = d.suspension_omega_rad_s() / (2.0 * std::f64::consts::PI);
        let sine = Sine::from_rms_g(1.0, f);
        let l: Result<Ledger, PeriodicError> =
            endstop::with_harvester!(&d, |h| from_rest_ledger(&h, sine, 20.0 / f));
        let l = l.unwrap_or_else(|e| panic!("{name}: {e}"));
        eprintln!(
            "{name}: {l:?} relative residual {:e}",
            l.relative_residual()
        );
        // The contact's share: the end-stop damper, clip losses net of re-engagement gains,
        // impact losses.
        let contact = l.stop_absorbed() + l.impact_losses();
        assert!(contact > 0.0, "{name}: the drive must strike the stop");
        assert!(
            l.get("dc_load").abs() > 0.0,
            "{name}: nothing reached the load"
        );
        // rtol 1e-9 over 20 periods with events: 1e-6 leaves room for the error's growth.
        assert!(l.relative_residual().abs() < 1e-6, "{name}: {l:?}");
    }
}

/// A storage capacitor so small that it discharges through its load within a fraction of the
/// period (1e-30 F into 50 kOhm: 5e-26 s) ends in a named error at once, naming the storage,
/// where it otherwise ran to a storage voltage of hundreds of megavolts; the file's own 1 uF
/// assembles.
#[test]
fn a_storage_that_empties_within_a_step_is_a_named_error() {
    use endstop::physics::harvester::{AssemblyError, Harvester};
    let tiny = text(
        PIEZO,
        &bridge("full_bridge", "", PWL, RES).replace("1e-6", "1e-30"),
    );
    let d = Device::from_toml_str(&tiny, "tiny.toml").unwrap();
    let e = Harvester::<4>::new(&d).unwrap_err();
    assert!(matches!(e, AssemblyError::StiffStorage { .. }), "{e}");
    assert!(e.to_string().contains("storage_capacitance_f"), "{e}");
    let ok = text(PIEZO, &bridge("full_bridge", "", PWL, RES));
    let d = Device::from_toml_str(&ok, "ok.toml").unwrap();
    assert!(Harvester::<4>::new(&d).is_ok());
}

/// The paper's prototype 2 behind an ideal bridge (`data/examples/prototype2_bridge.toml`: the
/// electrostatic pair's two node charges, each drained by its load, and the storage) balances
/// its energy as every other interface does, striking its stops at 1 g near resonance.
#[test]
fn the_energy_ledger_closes_for_a_pair_behind_a_bridge() {
    let d = load("data/examples/prototype2_bridge.toml");
    let f = d.suspension_omega_rad_s() / (2.0 * std::f64::consts::PI);
    let sine = Sine::from_rms_g(1.0, f);
    let l: Result<Ledger, PeriodicError> =
        endstop::with_harvester!(&d, |h| from_rest_ledger(&h, sine, 20.0 / f));
    let l = l.unwrap();
    eprintln!("{l:?} relative residual {:e}", l.relative_residual());
    assert!(l.stop_absorbed() + l.impact_losses() > 0.0, "no contact");
    assert!(l.get("dc_load") > 0.0, "nothing reached the load");
    assert!(l.get("diodes") > 0.0, "the bridge never conducted");
    // As for the other interfaces: rtol 1e-9 over 20 periods with events.
    assert!(l.relative_residual().abs() < 1e-6, "{l:?}");
}

/// The ledger of `model` driven by `sine` from the zero state over `t_end_s` (Dormand-Prince
/// at rtol 1e-9, the model's own mode at the start).
fn from_rest_ledger<M: Model<N>, const N: usize>(
    model: &M,
    sine: Sine,
    t_end_s: f64,
) -> Result<Ledger, PeriodicError> {
    let y0 = nalgebra::SVector::<f64, N>::zeros();
    let mode0 = model.mode_of(&y0);
    let mut books = Books::new(model, sine);
    let mut ode = Dopri5::new(0.0, y0, mode0, model.solver_options(1e-9));
    ode.integrate_observed(&Driven::new(model, sine), t_end_s, &mut books)?;
    Ok(books.ledger())
}

fn bad(t: &str) -> ParamError {
    Device::from_toml_str(t, "bad.toml").unwrap_err()
}

/// Bad interfaces end in errors naming the file, the field and the valid range.
#[test]
fn bad_interfaces_are_named_errors() {
    let cases: [(String, &str); 7] = [
        (
            text(
                PIEZO,
                &bridge("full_bridge", "", &PWL.replace("0.2", "-0.2"), RES),
            ),
            "interface.diode.forward_drop_v",
        ),
        (
            text(
                PIEZO,
                &bridge("parallel_sshi", "inversion_factor = 1.0", PWL, RES),
            ),
            "interface.inversion_factor",
        ),
        (
            text(
                PIEZO,
                &bridge("full_bridge", "", PWL, RES).replace("1e-6", "0.0"),
            ),
            "interface.storage_capacitance_f",
        ),
        (
            text(
                PIEZO,
                &bridge("full_bridge", "", PWL, &BAT.replace("3.0", "-1.0")),
            ),
            "interface.load.voltage_v",
        ),
        (
            text(
                COIL,
                &bridge("parallel_sshi", "quality_factor = 3.0", PWL, RES),
            ),
            "interface.kind",
        ),
        (
            text(
                &format!("{PIEZO}\nload_resistance_ohm = 1e3"),
                &bridge("full_bridge", "", PWL, RES),
            ),
            "transducer.load_resistance_ohm",
        ),
        (text(PIEZO, ""), "transducer.load_resistance_ohm"),
    ];
    for (t, field) in cases {
        let e = bad(&t);
        eprintln!("{e}");
        assert_eq!(e.field(), Some(field), "{e}");
        assert!(e.to_string().starts_with("bad.toml"), "{e}");
    }
    // A capacitor pair behind a bridge is a device: its model carries the pair's two
    // electrical states and the storage (dimension 5).
    let pair = Device::from_toml_str(
        &text(
            "[transducer]\nkind = \"gap_closing_pair\"\nc0_f = 1e-12\nelectrode_gap_m = 1e-3\ncp_f = 0.0\nload_resistance_ohm = 1e6\nload_capacitance_f = 0.0\nbias_v = 1.0",
            &bridge("full_bridge", "", PWL, RES),
        ),
        "pair.toml",
    )
    .unwrap();
    assert_eq!(endstop::physics::harvester::dimension(&pair), Ok(5));
}

/// A device with an interface writes itself back to an equal device.
#[test]
fn interfaces_round_trip_through_toml() {
    for t in [
        text(
            PIEZO,
            &bridge("parallel_sshi", "quality_factor = 3.0", SHOCKLEY, BAT),
        ),
        text(PIEZO, &bridge("sece", "efficiency = 0.8", "", RES)),
    ] {
        let d = Device::from_toml_str(&t, "a.toml").unwrap();
        let back = Device::from_toml_str(&d.to_toml_string(), "b.toml").unwrap();
        assert_eq!(d, back);
    }
}

/// An on-resistance that makes conduction far faster than the period ends in a named error at
/// once (the explicit integrator would otherwise grind through millions of steps).
#[test]
fn a_stiff_conduction_mode_is_a_named_error() {
    let t = text(
        PIEZO,
        &bridge("full_bridge", "", &PWL_RON.replace("500.0", "1e-3"), RES),
    );
    let d = Device::from_toml_str(&t, "stiff.toml").unwrap();
    let f = d.suspension_omega_rad_s() / (2.0 * std::f64::consts::PI);
    let e = endstop::study::periodic::steady_state_from_rest(
        &d,
        Sine::from_rms_g(0.1, f),
        &endstop::study::periodic::SteadySettings::default(),
    )
    .unwrap_err();
    assert!(
        matches!(
            e,
            endstop::study::periodic::PeriodicError::Device(
                endstop::physics::harvester::AssemblyError::Stiff { .. }
            )
        ),
        "{e}"
    );
}

/// The paper's prototype 2 behind an ideal bridge (`data/examples/prototype2_bridge.toml`)
/// against an outside integration of the same circuit written from the paper's equations 7-10
/// and Kirchhoff's laws, not from this library (`data/references/pair_bridge/`: scipy's DOP853
/// at rtol 1e-12 by brute force from rest, conduction located as events, averages over whole
/// periods after 2 s). The drives keep the mass off the stops, so their law does not enter.
#[test]
fn the_pair_bridge_agrees_with_an_independent_integration() {
    use endstop::device::interface::DcLoad;
    use endstop::study::periodic::{steady_state_from_rest, SteadySettings};
    let rel = "data/examples/prototype2_bridge.toml";
    let d = load(rel);
    let settings = SteadySettings::default();
    // The storage voltage's scale in the shooting's residual (the model's own scales).
    let scales: Result<(Vec<f64>, Vec<String>), PeriodicError> =
        endstop::with_harvester!(&d, |h| {
            let names = h.layout().components.iter().map(|s| s.name.clone());
            Ok((h.scales().as_slice().to_vec(), names.collect()))
        });
    let (scales, names) = scales.unwrap();
    let vs_scale_v = scales[names
        .iter()
        .position(|n| n == "vs")
        .expect("a vs component")];
    let cs_f = d
        .interface
        .storage_capacitance_f()
        .expect("a storage capacitor");
    let Some(DcLoad::Resistor {
        resistance_ohm: r_ohm,
    }) = d.interface.load().cloned()
    else {
        panic!("{rel}: the DC load is not a resistor")
    };
    let csv = |name: &str| -> Vec<Vec<f64>> {
        let path = root().join("data/references/pair_bridge").join(name);
        let text = std::fs::read_to_string(&path).unwrap();
        let mut lines = text.lines().filter(|l| !l.trim().is_empty());
        let header = lines.next().unwrap_or_default().to_string();
        let rows: Vec<Vec<f64>> = lines
            .map(|l| l.split(',').map(|c| c.parse().unwrap()).collect())
            .collect();
        assert!(
            !rows.is_empty(),
            "{}: no rows under {header}",
            path.display()
        );
        rows
    };
    // The reference's own integration error: its rtol 1e-11 run's relative difference from the
    // reported rtol 1e-12 run (columns freq_hz, accel_rms_g, rtol, p_dc_w, vdc_v, p_rel_diff,
    // v_rel_diff, ...).
    let checks = csv("integration_check.csv");
    let mut rows = 0;
    let mut conducting = 0;
    for v in csv("reference.csv") {
        let (f, g, p_ref, v_ref, settle_ref) = (v[0], v[1], v[2], v[3], v[4]);
        let check = checks
            .iter()
            .find(|c| c[0] == f && c[1] == g && c[2] == 1e-11)
            .unwrap_or_else(|| panic!("{g} g, {f} Hz: no rtol 1e-11 check row"));
        let s = steady_state_from_rest(&d, Sine::from_rms_g(g, f), &settings).unwrap();
        assert!(!s.contact, "{g} g, {f} Hz: the mass reached a stop");
        // Tolerance, from both computations' stated accuracies (not from their difference):
        // - ours, shooting: Newton ends at the scaled residual |P(y) - y| / scale it reports;
        //   the distance to the orbit is about the residual over 1 - |mu|, mu the slowest
        //   Floquet multiplier. The slowest modes are the storage through its load (R Cs) and
        //   the mass's free ring-down (2 m / b); the bridge and the transducer only add loss, so
        //   |mu| <= exp(-T / tau), tau = max(R Cs, 2 m / b) = 0.1 s. That bounds the storage
        //   voltage's error absolutely: dv = residual * scale(vs) / (1 - exp(-T / tau)).
        // - ours, integration: Dormand-Prince at rtol 1e-9 with events; an adaptive method's
        //   global error is not bounded by its rtol, and the reference measured DOP853's on
        //   this circuit at rtol 1e-9 as up to about 400 rtol in <Vs> (`integration_check.csv`,
        //   0.2 g 650 Hz, where short conductions make event location matter): budget 1000
        //   rtol, relative, in the storage voltage.
        // - the reference: its rtol 1e-11 run's difference from its rtol 1e-12 run (an upper
        //   estimate of the reported run's error) and its settling, the relative change
        //   between its last two 50-period windows (`settle_rel_change`).
        // The mean power is <Vs^2> / R: an absolute voltage error dv moves it by at most
        // (2 Vrms dv + dv^2) / R, Vrms = sqrt(P R), and a relative error e by 2 e.
        let tau_s = f64::max(
            r_ohm * cs_f,
            2.0 * d.mechanics.mass_kg / d.mechanics.damping_n_s_per_m,
        );
        let dv = s.residual * vs_scale_v / (1.0 - (-1.0 / (f * tau_s)).exp());
        let e = 1000.0 * settings.rtol + f64::max(check[5], check[6]) + settle_ref;
        let v_rms = (p_ref * r_ohm).sqrt();
        let tol_v = dv + e * v_ref.abs();
        let tol_p = (2.0 * v_rms * dv + dv * dv) / r_ohm + 2.0 * e * p_ref;
        eprintln!(
            "{g} g, {f} Hz: P_DC ours {:.10e} ref {p_ref:.10e} (diff {:.2e}, tol {tol_p:.2e}); \
             Vdc ours {:.10e} ref {v_ref:.10e} (diff {:.2e}, tol {tol_v:.2e}); residual {:.1e}",
            s.p_dc_w,
            (s.p_dc_w - p_ref).abs(),
            s.vdc_v,
            (s.vdc_v - v_ref).abs(),
            s.residual,
        );
        assert!(
            (s.p_dc_w - p_ref).abs() <= tol_p,
            "{g} g, {f} Hz: P_DC {} W against the reference's {p_ref} W (tolerance {tol_p:e})",
            s.p_dc_w
        );
        assert!(
            (s.vdc_v - v_ref).abs() <= tol_v,
            "{g} g, {f} Hz: Vdc {} V against the reference's {v_ref} V (tolerance {tol_v:e})",
            s.vdc_v
        );
        rows += 1;
        conducting += usize::from(p_ref > 0.0);
    }
    // The brief's three points (two of them below the bridge's threshold) and three more where
    // the bridge conducts.
    assert!(
        rows >= 3 && conducting >= 2,
        "{rows} rows, {conducting} conducting"
    );
}
