//! The SECE through its buck-boost inductor (`circuits::sece_inductor`,
//! `data/examples/piezo_sece_inductor.toml`): its limit of a fast inductor against the
//! instantaneous SECE, its Jacobian and monodromy, its energy ledger, and its description's
//! named errors.
//!
//! # The limit, derived before running
//! With `R_L = 0` and `V_F = 0` the transfer loses nothing: the charge phase moves all of
//! `Cp Vp^2 / 2` into the inductor and the flyback all of `L I^2 / 2` into the storage, so the
//! limit is the instantaneous SECE with efficiency 1. At a finite transfer time
//! `tau = (pi/2) sqrt(L Cp)` (drive period `T`) the leading difference is of first order in
//! `tau / T`: the element's force `theta Vp` outlives the extremum by a quarter LC cycle, an
//! extra impulse `J = (2/pi) theta V0 tau` (with `V0 = 2 theta X / Cp`, the voltage at the
//! extremum) of alternating sign at each extremum, whose fundamental is in phase with `x`: a
//! stiffness `dk = 4 J / (T X) = (16/pi) (theta^2 / Cp) tau / T`. Everything else is of second
//! order (the charge the motion adds during the transfer, the velocity's `O(tau^2)` away from
//! zero; the storage's ramp instead of its jump does not move the DC power, which in steady
//! state is what the transfers deliver). The amplitude then moves by
//! `d ln X = -(k_eff - m w^2) dk / |Z|^2` with the SECE's first-harmonic stiffness
//! `k_eff = k + theta^2 / Cp`, damping `c_eff = b + (4/pi) theta^2 / (Cp w)` and
//! `|Z|^2 = (k_eff - m w^2)^2 + (w c_eff)^2`, and the power (`~ X^2`) by twice that:
//! `|dP / P| = K tau / T` with `K = 2 (16/pi) (theta^2/Cp) |k_eff - m w^2| / |Z|^2`, about 2.7
//! at the example's resonance. The test asserts `|dP / P| <= 2 K tau / T` for every
//! `tau / T <= 1e-2` (the factor 2 for what the first-order estimate leaves out), and that the
//! difference shrinks with `L`.

use crate::common;
use endstop::circuits::{Bridge, CircuitMode, Heading};
use endstop::device::{DcLoad, Device, Interface, SeceInductor};
use endstop::drive::{Excitation, Sine};
use endstop::model::{Contact, Mode, Model};
use endstop::physics::contact::Side;
use endstop::physics::harvester::stops::contact_of;
use endstop::physics::harvester::AssemblyError;
use endstop::study::periodic::{
    steady_state, steady_state_from_rest, PeriodicError, PeriodicState, SteadySettings,
};
use nalgebra::SVector;
use std::f64::consts::PI;

fn example() -> Device {
    common::device("examples/piezo_sece_inductor")
}

/// The example's inductor description.
fn inductor(d: &Device) -> SeceInductor {
    let Interface::SeceInductor(s) = &d.interface else {
        unreachable!("the example has a SECE through its inductor")
    };
    s.clone()
}

/// The example's theta (N/V) and Cp (F).
fn piezo(d: &Device) -> (f64, f64) {
    let endstop::device::Transducer::Piezoelectric(p) = &d.transducer else {
        unreachable!("the example is piezoelectric")
    };
    (p.coupling_n_per_v, p.capacitance_f)
}

/// The example with a lossless inductor (`R_L = 0`, `V_F = 0`) whose transfer lasts `ratio`
/// of the period `period_s`: `(pi/2) sqrt(L Cp) = ratio T`.
fn lossless(d: &Device, ratio: f64, period_s: f64) -> (Device, f64) {
    let (_, cp) = piezo(d);
    let l = (2.0 * ratio * period_s / PI).powi(2) / cp;
    let mut out = d.clone();
    out.interface = Interface::SeceInductor(SeceInductor {
        inductance_h: l,
        inductor_resistance_ohm: 0.0,
        flyback_drop_v: 0.0,
        ..inductor(d)
    });
    (out, l)
}

/// The example with the instantaneous SECE of efficiency `eta`.
fn instantaneous(d: &Device, eta: f64) -> Device {
    let s = inductor(d);
    let mut out = d.clone();
    out.interface = Interface::Sece {
        storage_capacitance_f: s.storage_capacitance_f,
        load: s.load,
        efficiency: eta,
    };
    out
}

fn steady(d: &Device, sine: Sine) -> PeriodicState {
    steady_state_from_rest(d, sine, &SteadySettings::default())
        .unwrap_or_else(|e| panic!("{}: {e}", d.name))
}

/// The convergence table: the steady DC power and storage voltage at the resonance (0.1 g,
/// free of the stop) as the transfer time falls from 1e-1 to 1e-4 of the period, against the
/// instantaneous SECE with efficiency 1, within the first-order bound of the module docs.
#[test]
fn a_fast_lossless_inductor_approaches_the_instantaneous_sece() {
    let d = example();
    let f = d.suspension_omega_rad_s() / (2.0 * PI);
    let sine = Sine::from_rms_g(0.1, f);
    let period_s = 1.0 / f;
    let reference = steady(&instantaneous(&d, 1.0), sine);
    assert!(!reference.contact, "the drive must stay off the stop");
    // The first-order constant K of the module docs, from the device.
    let (theta, cp) = piezo(&d);
    let m = &d.mechanics;
    let w = 2.0 * PI * f;
    let kc = theta * theta / cp;
    let detune = m.stiffness_n_per_m + kc - m.mass_kg * w * w;
    let c_eff = m.damping_n_s_per_m + 4.0 / PI * kc / w;
    let z2 = detune * detune + (w * c_eff).powi(2);
    let k_first = 2.0 * 16.0 / PI * kc * detune.abs() / z2;
    eprintln!(
        "instantaneous SECE (eta = 1): P_dc = {:.6e} W, V_dc = {:.6e} V; K = {k_first:.3}",
        reference.p_dc_w, reference.vdc_v
    );
    eprintln!("L (H) | tau/T | P_dc (W) | V_dc (V) | dP/P | dV/V | bound 2 K tau/T");
    let mut last = f64::INFINITY;
    let mut rows = Vec::new();
    for ratio in [1e-1, 1e-2, 1e-3, 1e-4] {
        let (dl, l) = lossless(&d, ratio, period_s);
        let s = steady(&dl, sine);
        let dp = (s.p_dc_w - reference.p_dc_w) / reference.p_dc_w;
        let dv = (s.vdc_v - reference.vdc_v) / reference.vdc_v;
        let bound = 2.0 * k_first * ratio;
        eprintln!(
            "{l:.3e} | {ratio:.0e} | {:.6e} | {:.6e} | {dp:+.3e} | {dv:+.3e} | {bound:.2e}",
            s.p_dc_w, s.vdc_v
        );
        // Lossless: the ledger has nothing to book in the inductor's resistance or diode.
        assert_eq!(s.ledger.get("element"), 0.0);
        assert_eq!(s.ledger.get("diodes"), 0.0);
        // The extra stiffness lowers the amplitude above the SECE's resonance: P falls.
        assert!(dp < 0.0, "tau/T = {ratio:e}: {dp:e}");
        assert!(dp.abs() < last, "tau/T = {ratio:e}: {dp:e} after {last:e}");
        last = dp.abs();
        if ratio <= 1e-2 {
            assert!(
                dp.abs() <= bound,
                "tau/T = {ratio:e}: {dp:e} beyond {bound:e}"
            );
        }
        rows.push((ratio, dp));
    }
    let (a, b) = (rows[2], rows[3]);
    let order = (a.1.abs() / b.1.abs()).log10() / (a.0 / b.0).log10();
    eprintln!("observed order between tau/T = 1e-3 and 1e-4: {order:.2}");
}

/// At each phase, free and pressed on the stop, the analytic Jacobian equals central
/// differences of the vector field: each phase is affine in the state, so the differences
/// are exact but for rounding, about eps / h = 1e-10 of a column's scale; 1e-6 leaves room.
#[test]
fn jacobian_matches_differences_in_every_phase() {
    let d = example();
    let r: Result<(), AssemblyError> = endstop::with_harvester!(&d, |m| {
        jacobian_checks(&m);
        Ok(())
    });
    r.unwrap();
}

fn jacobian_checks<M: Model<N>, const N: usize>(m: &M) {
    let y = common::interface_checks::jacobian_state(m, 1.05e-4);
    let a = Sine::from_rms_g(0.3, 120.0).accel(1e-3);
    let upper = Mode::FREE.with_contact(contact_of(Side::Upper), Contact::Pressed);
    let mut checked = 0;
    for contact in [Mode::FREE, upper] {
        for bridge in [
            Bridge::Off,
            Bridge::Positive,
            Bridge::Negative,
            Bridge::Flyback,
        ] {
            let bits = CircuitMode {
                bridge,
                heading: Heading::Up,
            }
            .bits();
            let mode = contact.with_circuit(0, bits);
            checked += common::interface_checks::assert_jacobian_matches_differences(
                m,
                mode,
                &y,
                a,
                &format!("{bridge:?} {mode:?}"),
            );
        }
    }
    assert_eq!(checked, 2 * 4 * N * N);
}

/// The monodromy and dP/df through the saltation matrices against central differences of
/// the period map at the example's steady state (0.3 g at 120 Hz), as for the other
/// interfaces (`interface_orbits.rs`, whose tolerances this reuses: steps of 1e-5 of the
/// scales at rtol 1e-11, entries within 1e-4 of the largest). Each extremum starts a charge
/// and a flyback: at least six events a period.
#[test]
fn monodromy_matches_differences_of_the_period_map() {
    let d = example();
    let r: Result<(), PeriodicError> = endstop::with_harvester!(&d, |m| {
        monodromy_check(&m);
        Ok(())
    });
    r.unwrap();
}

fn monodromy_check<M: Model<N>, const N: usize>(model: &M) {
    let sine = Sine::from_rms_g(0.3, 120.0);
    let s = steady_state(model, sine, &model.rest_state(), &SteadySettings::default()).unwrap();
    let y = SVector::<f64, N>::from_column_slice(&s.state);
    let common::linearisation::Against {
        lin,
        stats,
        monodromy_rel: diff,
        dp_rel: diff_p,
    } = common::linearisation::against_differences(model, sine, y, 1e-11);
    let (monodromy, dp) = (lin.monodromy, lin.dp);
    eprintln!(
        "events {}; |M - M_fd| / |M| = {diff:.2e}, |dP/df - fd| / |dP/df| = {diff_p:.2e}, \
         max |mu| {:.6}, P_dc {:.4e} W",
        stats.events, s.max_multiplier, s.p_dc_w
    );
    assert!(stats.events >= 6, "{} events", stats.events);
    assert!(diff < 1e-4, "monodromy differs by {diff:e}\n{monodromy}");
    assert!(diff_p < 1e-4, "dP/df differs by {diff_p:e}\n{dp}");
}

/// Over 20 periods from rest at 1 g (the stop is struck), the ledger closes with the
/// inductor's energy stored, its resistance's loss in `element` and the flyback diode's in
/// `diodes`: to 1e-6 of the drive's work, as for every other interface (`interfaces.rs`: rtol
/// 1e-9 over 20 periods with events).
#[test]
fn the_energy_ledger_closes() {
    common::interface_checks::assert_ledger_closes_from_rest(&example());
}

/// The description: the example round-trips through TOML and needs five components; bad
/// values and keys are errors naming the field; a coil is refused.
#[test]
fn the_description_is_checked() {
    let d = example();
    common::interface_checks::assert_description_checked(
        &d,
        "examples/piezo_sece_inductor",
        5,
        &[
            (
                "inductance_h = 1e-3",
                "inductance_h = -1e-3",
                "interface.inductance_h",
            ),
            (
                "flyback_drop_v = 0.2",
                "efficiency = 0.8",
                "interface.efficiency",
            ),
            ("inductance_h = 1e-3", "", "interface.inductance_h"),
            (
                "inductor_resistance_ohm = 10.0",
                "inductor_resistance_ohm = 300.0",
                "interface.inductor_resistance_ohm",
            ),
            (
                "kind = \"sece\"",
                "kind = \"full_bridge\"",
                "interface.inductance_h",
            ),
        ],
    );
    // A coil behind the SECE through its inductor (built directly: the file form of a coil
    // takes other keys) is refused on load and by the assembly.
    let mut coil = common::device("examples/em_bridge");
    coil.interface = Interface::SeceInductor(SeceInductor {
        load: DcLoad::Open,
        ..inductor(&d)
    });
    assert!(coil.validate("coil.toml").is_err());
    let e = endstop::physics::harvester::dimension(&coil).unwrap_err();
    assert!(matches!(e, AssemblyError::Unsupported { .. }), "{e}");
}
