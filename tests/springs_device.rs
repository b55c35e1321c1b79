//! Nonlinear suspensions in device files: each bad input is refused with an error naming the
//! file, the field, the value and the valid range; good files load, report their equilibria
//! and read back equal.

use endstop::device::{Device, ParamError};
use endstop::physics::statics::{equilibria, reference_well};
use endstop::physics::suspension::Place;

const HEAD: &str = r#"
name = "s"
params = "test"
description = "suspension test"
[transducer]
kind = "none"
"#;

fn load(mech: &str, stops: &str) -> Result<Device, ParamError> {
    Device::from_toml_str(&format!("{HEAD}\n{mech}\n{stops}"), "springs.toml")
}

fn mech(suspension: &str) -> String {
    format!("[mechanics]\nmass_kg = 1e-3\ndamping_n_s_per_m = 0.02\n[mechanics.suspension]\n{suspension}")
}

/// The error names the file and the field; an out-of-range error also the value and range.
fn refused(r: Result<Device, ParamError>, field: &str) -> ParamError {
    let e = r.expect_err("must be refused");
    let text = e.to_string();
    assert!(text.contains("springs.toml"), "{text}");
    assert_eq!(e.field(), Some(field), "{text}");
    e
}

#[test]
fn bistable_loads_with_its_wells_barrier_and_derived_stiffness() {
    let d = load(
        &mech("form = \"bistable\"\nwell_m = 1e-4\nbarrier_j = 1e-6"),
        "",
    )
    .unwrap();
    let eq = equilibria(&d);
    assert_eq!(eq.len(), 3);
    assert!(eq[0].stable && !eq[1].stable && eq[2].stable);
    assert!((eq[2].x_m - 1e-4).abs() < 1e-16);
    // Barrier above the wells as given (relative 1e-12: polished roots).
    assert!(((eq[1].energy_j - eq[2].energy_j) - 1e-6).abs() < 1e-18);
    // k = 4 barrier / well^2 = 400 N/m; the well's stiffness is 2 k.
    assert!((d.mechanics.stiffness_n_per_m - 800.0).abs() < 1e-9);
    // The file form reads back to an equal device.
    let back = Device::from_toml_str(&d.to_toml_string(), "back.toml").unwrap();
    assert_eq!(back, d);
}

#[test]
fn a_polynomial_held_on_rigid_stops_rests_on_them() {
    let d = load(
        &mech("form = \"polynomial\"\nk1_n_per_m = -100.0\nk2_n_per_m2 = 1e3"),
        "[stops.both]\ngap_m = 1e-3\nlaw = \"restitution\"\ncoefficient = 0.5",
    )
    .unwrap();
    let eq = equilibria(&d);
    assert!(eq.iter().any(|e| e.place == Place::UpperStop && e.stable));
    assert!(eq.iter().any(|e| e.place == Place::LowerStop && e.stable));
    assert!(eq
        .iter()
        .any(|e| e.place == Place::Free && !e.stable && e.x_m == 0.0));
}

#[test]
fn bad_suspensions_are_refused_with_named_errors() {
    // A well or barrier not above zero.
    refused(
        load(
            &mech("form = \"bistable\"\nwell_m = 0.0\nbarrier_j = 1e-6"),
            "",
        ),
        "mechanics.suspension.well_m",
    );
    refused(
        load(
            &mech("form = \"bistable\"\nwell_m = 1e-4\nbarrier_j = -1.0"),
            "",
        ),
        "mechanics.suspension.barrier_j",
    );
    refused(
        load(
            &mech("form = \"bistable\"\nwell_m = 1e-4\nbarrier_j = nan"),
            "",
        ),
        "mechanics.suspension.barrier_j",
    );
    // A missing key and a key of another form.
    refused(
        load(&mech("form = \"bistable\"\nwell_m = 1e-4"), ""),
        "mechanics.suspension.barrier_j",
    );
    refused(
        load(
            &mech("form = \"bistable\"\nwell_m = 1e-4\nbarrier_j = 1e-6\nk3_n_per_m3 = 1.0"),
            "",
        ),
        "mechanics.suspension.k3_n_per_m3",
    );
    refused(
        load(&mech("well_m = 1e-4"), ""),
        "mechanics.suspension.form",
    );
    // A non-finite coefficient.
    refused(
        load(
            &mech("form = \"polynomial\"\nk1_n_per_m = 1.0\nk3_n_per_m3 = inf"),
            "",
        ),
        "mechanics.suspension.k3_n_per_m3",
    );
    // A suspension that does not confine the mass, without stops: a negative leading term,
    // and an even one (it confines on one side only).
    refused(
        load(
            &mech("form = \"polynomial\"\nk1_n_per_m = 1.0\nk3_n_per_m3 = -1.0"),
            "",
        ),
        "mechanics.suspension.k3_n_per_m3",
    );
    refused(
        load(
            &mech("form = \"polynomial\"\nk1_n_per_m = 1.0\nk2_n_per_m2 = 5.0"),
            "",
        ),
        "mechanics.suspension.k2_n_per_m2",
    );
    // ... nor with a stop on the wrong side only.
    refused(
        load(
            &mech("form = \"polynomial\"\nk1_n_per_m = 1.0\nk2_n_per_m2 = 5.0"),
            "[stops.upper]\ngap_m = 1e-3\nlaw = \"restitution\"\ncoefficient = 0.5",
        ),
        "mechanics.suspension.k2_n_per_m2",
    );
    // A stop at or inside a bistable's well.
    let e = refused(
        load(
            &mech("form = \"bistable\"\nwell_m = 1e-4\nbarrier_j = 1e-6"),
            "[stops.both]\ngap_m = 5e-5\nlaw = \"linear\"\nstiffness_n_per_m = 1e4",
        ),
        "stops.both.gap_m",
    );
    assert!(e.to_string().contains("5e-5"), "{e}");
    // The linear stiffness beside a nonlinear form.
    let text = format!(
        "{HEAD}\n[mechanics]\nmass_kg = 1e-3\nstiffness_n_per_m = 10.0\ndamping_n_s_per_m = 0.02\n\
         [mechanics.suspension]\nform = \"polynomial\"\nk1_n_per_m = 1.0\nk3_n_per_m3 = 1.0"
    );
    refused(
        Device::from_toml_str(&text, "springs.toml"),
        "mechanics.stiffness_n_per_m",
    );
}

#[test]
fn a_stop_confines_a_softening_suspension_only_when_its_force_grows_faster() {
    let with_stop = |stop: &str| {
        load(
            &mech("form = \"polynomial\"\nk1_n_per_m = 100.0\nk3_n_per_m3 = -1e3"),
            &format!("[stops.both]\ngap_m = 1e-3\n{stop}"),
        )
    };
    // -x^3 outgrows a linear or a Hertz point stop.
    refused(
        with_stop("law = \"linear\"\nstiffness_n_per_m = 1e9"),
        "mechanics.suspension.k3_n_per_m3",
    );
    refused(
        with_stop("law = \"hertz_point\"\nstiffness_n_per_m1p5 = 1e12"),
        "mechanics.suspension.k3_n_per_m3",
    );
    // A Hunt-Crossley stop of the same exponent but stiffer, and a rigid stop, confine it.
    let hc = with_stop(
        "law = \"hunt_crossley\"\nstiffness_n_per_m_pow_n = 1e12\nexponent = 3.0\ndamping_s_per_m = 0.1",
    )
    .unwrap();
    let rigid = with_stop("law = \"restitution\"\ncoefficient = 0.8").unwrap();
    for d in [hc, rigid] {
        let w = reference_well(&d).unwrap();
        assert_eq!(w.x_m, 0.0);
        assert!((d.mechanics.stiffness_n_per_m - 100.0).abs() < 1e-12);
    }
}
