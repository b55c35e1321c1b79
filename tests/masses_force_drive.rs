//! A device of several masses driven by a force on one mass (`drive_mass`): its named errors,
//! its file form, and the drive's column, right-hand side and power in the model. (Its orbits
//! against an outside reference: `nlvib_unilateral.rs`, whose points off the stop are the
//! linear chain's exact forced response.)

use endstop::device::{Device, ParamError};
use endstop::model::{Mode, Model};
use endstop::physics::harvester::masses::MassChain;
use nalgebra::SVector;

/// Two masses on springs to the frame and to each other, no transducer, `extra` at the top.
fn pair(extra: &str) -> String {
    format!(
        r#"{extra}
name = "pair"
params = "test"
description = "two masses"
[[masses]]
name = "a"
mass_kg = 1e-3
[[masses]]
name = "b"
mass_kg = 2e-4
[[springs]]
masses = [0]
stiffness_n_per_m = 10.0
[[springs]]
masses = [0, 1]
stiffness_n_per_m = 4.0
[[dampers]]
masses = [1]
damping_n_s_per_m = 1e-3
[transducer]
kind = "none"
"#
    )
}

fn field(text: &str) -> Option<String> {
    Device::from_toml_str(text, "pair.toml")
        .unwrap_err()
        .field()
        .map(str::to_string)
}

#[test]
fn a_bad_drive_mass_gets_a_named_error() {
    let e = Device::from_toml_str(&pair("drive_mass = 2"), "pair.toml").unwrap_err();
    assert!(matches!(e, ParamError::OutOfRange { ref field, .. } if field == "drive_mass"));
    assert_eq!(
        field(&pair("drive_mass = -1")).as_deref(),
        Some("drive_mass")
    );
    assert_eq!(
        field(&pair("drive_mass = \"b\"")).as_deref(),
        Some("drive_mass")
    );
    // A one-mass file has no masses to choose from: the key is unknown there.
    let one = "drive_mass = 0\nname = \"one\"\nparams = \"test\"\ndescription = \"one\"\n\
               [mechanics]\nmass_kg = 1.0\nstiffness_n_per_m = 1.0\ndamping_n_s_per_m = 0.1\n\
               [transducer]\nkind = \"none\"\n";
    assert!(Device::from_toml_str(one, "one.toml").is_err());
}

#[test]
fn the_drive_mass_reads_back_equal() {
    let d = Device::from_toml_str(&pair("drive_mass = 1"), "pair.toml").unwrap();
    assert_eq!(d.masses.as_ref().unwrap().drive_mass, Some(1));
    let back = Device::from_toml_str(&d.to_toml_string(), "back.toml").unwrap();
    assert_eq!(back, d);
    let base = Device::from_toml_str(&pair(""), "pair.toml").unwrap();
    assert_eq!(base.masses.as_ref().unwrap().drive_mass, None);
    assert!(!base.to_toml_string().contains("drive_mass"));
}

/// The drive enters linearly: `rhs(y, a) - rhs(y, 0) = a c` with `c` the drive's column, which
/// is 1 on every mass's velocity under the frame's acceleration and on the driven mass's
/// alone under a force; the drive's power is `m_j a v_j` of the driven mass alone.
#[test]
fn a_force_drive_acts_on_its_mass_alone() {
    let base = MassChain::<6>::new(&Device::from_toml_str(&pair(""), "p.toml").unwrap()).unwrap();
    let force =
        MassChain::<6>::new(&Device::from_toml_str(&pair("drive_mass = 1"), "p.toml").unwrap())
            .unwrap();
    let m = base.layout().masses.clone();
    let mut y = SVector::<f64, 6>::zeros();
    for (&(x, v), (p, s)) in m.iter().zip([(1e-4, -2e-3), (3e-4, 5e-3)]) {
        y[x] = p;
        y[v] = s;
    }
    let a = 2.5;
    for (model, driven) in [(&base, [1.0, 1.0]), (&force, [0.0, 1.0])] {
        let c = model.drive_column(Mode::FREE);
        let d = model.rhs(Mode::FREE, &y, a) - model.rhs(Mode::FREE, &y, 0.0);
        for (k, &(x, v)) in m.iter().enumerate() {
            assert_eq!(c[x], 0.0);
            assert_eq!(c[v], driven[k]);
            // The difference of two right-hand sides: exact to a few ulps of the forces.
            assert!((d[v] - a * c[v]).abs() < 1e-12 * a, "{d} vs {c}");
        }
        let mut p = vec![0.0; model.ledger_terms().len()];
        model.powers(Mode::FREE, &y, a, &mut p);
        let expected: f64 = m
            .iter()
            .zip(&model.bodies)
            .enumerate()
            .map(|(k, (&(_, v), b))| driven[k] * b.mass_kg * a * y[v])
            .sum();
        assert!(
            (p[0] - expected).abs() <= 1e-15 * expected.abs(),
            "{} vs {expected}",
            p[0]
        );
    }
}
