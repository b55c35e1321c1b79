use super::charging::{charge, ChargeError, ChargeSettings};
use super::*;
use crate::device::DcLoad;
use crate::progress::Silent;

fn device() -> Device {
    let text = include_str!("../../../data/validation/piezo_bridge.toml");
    Device::from_toml_str(text, "piezo_bridge.toml").unwrap()
}

fn resonance(d: &Device) -> f64 {
    d.suspension_omega_rad_s() / (2.0 * std::f64::consts::PI)
}

/// Each extremum inverts the element's voltage once: a parallel SSHI steady state at the
/// weak coupling delivers more than the plain bridge at the same load.
#[test]
fn parallel_sshi_beats_the_bridge() {
    let d = device();
    let sine = Sine::from_rms_g(0.1, resonance(&d));
    let set = SteadySettings::default();
    let bridge = steady_state(&d, sine, &State::zeros(), &set).unwrap();
    let mut s = d.clone();
    let crate::device::Interface::FullBridge(r) = &d.interface else {
        unreachable!()
    };
    s.interface =
        crate::device::Interface::ParallelSshi(r.clone(), crate::device::Inversion::Factor(0.5));
    let sshi = steady_state(&s, sine, &State::zeros(), &set).unwrap();
    assert!(
        sshi.p_dc_w > 1.5 * bridge.p_dc_w,
        "{} vs {}",
        sshi.p_dc_w,
        bridge.p_dc_w
    );
    assert!(bridge.is_stable() && sshi.is_stable());
}

/// An open load has no steady state: a named error.
#[test]
fn open_load_has_no_steady_state() {
    let mut d = device();
    if let crate::device::Interface::FullBridge(r) = &mut d.interface {
        r.load = DcLoad::Open;
    }
    let e = steady_state(
        &d,
        Sine::from_rms_g(0.1, resonance(&d)),
        &State::zeros(),
        &SteadySettings::default(),
    )
    .unwrap_err();
    assert!(matches!(e, InterfaceError::OpenLoad(_)), "{e}");
}

/// With an open load the storage charges towards the element's open-circuit peak; a target
/// below it is reached, one far above it ends in the named error (and does not hang).
#[test]
fn charging_reaches_a_target_or_says_out_of_reach() {
    let mut d = device();
    if let crate::device::Interface::FullBridge(r) = &mut d.interface {
        r.load = DcLoad::Open;
        r.storage_capacitance_f = 1e-6;
    }
    let f = resonance(&d);
    let settings = ChargeSettings {
        start_v: 0.0,
        target_v: 0.3,
        ramp_s: 0.0,
        t_max_s: 20.0,
        sample_s: 1e-3,
        block_s: 0.1,
        rtol: 1e-8,
    };
    let run = charge(&d, Sine::from_rms_g(0.1, f), &settings, &Silent).unwrap();
    assert!(run.time_to_target_s > 0.0 && run.time_to_target_s < 20.0);
    let far = ChargeSettings {
        target_v: 50.0,
        ..settings
    };
    let e = charge(&d, Sine::from_rms_g(0.1, f), &far, &Silent).unwrap_err();
    assert!(
        matches!(
            e,
            ChargeError::OutOfReach { .. } | ChargeError::NotReached { .. }
        ),
        "{e}"
    );
}
