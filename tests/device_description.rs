//! The device description: the paper's devices in the general format equal their earlier
//! files, every file round-trips through its TOML form, parameters are reachable by path, and
//! bad input is a named error naming the file, the field, the value and the valid range.

use endstop::device::{Device, ParamError, StopLaw, Transducer};

fn root() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).to_path_buf()
}

fn load(rel: &str) -> Device {
    let text = std::fs::read_to_string(root().join(rel)).unwrap();
    Device::from_toml_str(&text, rel).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// Every device file the project ships.
fn shipped() -> Vec<String> {
    let mut out = vec![
        "data/prototype1.toml".to_string(),
        "data/prototype2.toml".to_string(),
    ];
    for entry in std::fs::read_dir(root().join("data/examples")).unwrap() {
        let p = entry.unwrap().path();
        if p.extension().is_some_and(|e| e == "toml") {
            out.push(format!(
                "data/examples/{}",
                p.file_name().unwrap().to_string_lossy()
            ));
        }
    }
    out
}

#[test]
fn the_earlier_format_loads_as_the_same_device() {
    for (old, new) in [
        (
            "tests/fixtures/legacy/prototype1_v1.toml",
            "data/prototype1.toml",
        ),
        (
            "tests/fixtures/legacy/prototype2_v1.toml",
            "data/prototype2.toml",
        ),
        (
            "tests/fixtures/legacy/my_harvester_v1.toml",
            "data/examples/my_harvester.toml",
        ),
    ] {
        // The earlier format has no `[size]`: the devices agree in everything else.
        let new = Device {
            size: None,
            ..load(new)
        };
        assert_eq!(load(old), new, "{old} vs {new:?}");
    }
}

#[test]
fn every_shipped_device_round_trips_through_its_toml() {
    for rel in shipped() {
        let d = load(&rel);
        let back = Device::from_toml_str(&d.to_toml_string(), "round trip").unwrap();
        assert_eq!(d, back, "{rel}");
    }
}

#[test]
fn the_paper_devices_are_symmetric_hertz_line_stops_on_a_comb_pair() {
    for rel in ["data/prototype1.toml", "data/prototype2.toml"] {
        let d = load(rel);
        let s = d.stops.symmetric().expect("one stop for both sides");
        assert!(matches!(s.law, StopLaw::HertzLine(_)));
        assert!(matches!(d.transducer, Transducer::AreaOverlapPair(_)));
    }
}

#[test]
fn parameters_are_read_and_set_by_path() {
    let d = load("data/prototype1.toml");
    assert_eq!(d.param("mechanics.mass_kg").unwrap(), 2.8e-6);
    assert_eq!(d.param("stops.both.gap_m").unwrap(), 7e-6);
    assert_eq!(d.param("stops.lower.damping_n_s_per_m").unwrap(), 1.5);
    assert_eq!(d.param("transducer.bias_v").unwrap(), 30.0);
    // The earlier format's names are aliases.
    assert_eq!(d.param("geometry.endstop_gap_m").unwrap(), 7e-6);
    assert_eq!(d.param("endstop.damping_n_s_per_m").unwrap(), 1.5);
    // Setting one side makes the stops asymmetric; `both` then refuses to read.
    let a = d.with_param("stops.upper.gap_m", 6e-6).unwrap();
    assert_eq!(a.param("stops.upper.gap_m").unwrap(), 6e-6);
    assert_eq!(a.param("stops.lower.gap_m").unwrap(), 7e-6);
    assert!(a.stops.symmetric().is_none());
    assert!(matches!(
        a.param("stops.both.gap_m"),
        Err(ParamError::Invalid { .. })
    ));
    // An integer field takes integral values only.
    let n = d
        .with_param("transducer.fingers_per_electrode", 400.0)
        .unwrap();
    assert_eq!(n.param("transducer.fingers_per_electrode").unwrap(), 400.0);
    assert!(d
        .with_param("transducer.fingers_per_electrode", 400.5)
        .is_err());
    // Every listed path reads back.
    for p in d.param_paths() {
        d.param(&p).unwrap_or_else(|e| panic!("{p}: {e}"));
    }
    // A set value is validated like a file.
    let err = d.with_param("stops.both.gap_m", 20e-6).unwrap_err();
    assert!(err.to_string().contains("finger_overlap_m"), "{err}");
    let err = d.with_param("mechanics.no_such", 1.0).unwrap_err();
    assert!(err.to_string().contains("mechanics.mass_kg"), "{err}");
}

/// A minimal device with one stop table `stop` and one transducer table `transducer`.
fn device_text(stop: &str, transducer: &str) -> String {
    format!(
        "name = \"t\"\nparams = \"test\"\ndescription = \"test\"\n\
         [mechanics]\nmass_kg = 1e-3\nstiffness_n_per_m = 100.0\ndamping_n_s_per_m = 1e-3\n\
         {stop}\n{transducer}\n"
    )
}

const NONE: &str = "[transducer]\nkind = \"none\"";
const PIEZO: &str = "[transducer]\nkind = \"piezoelectric\"\ncoupling_n_per_v = 1e-4\n\
                     capacitance_f = 1e-8\nload_resistance_ohm = 1e5";

fn error(stop: &str, transducer: &str) -> String {
    Device::from_toml_str(&device_text(stop, transducer), "bad.toml")
        .expect_err("invalid")
        .to_string()
}

#[test]
fn bad_stops_are_named_errors() {
    // A gap that is not positive names the field, the value and the range.
    let e = error(
        "[stops.upper]\ngap_m = 0.0\nlaw = \"restitution\"\ncoefficient = 0.5",
        NONE,
    );
    assert!(
        e.contains("bad.toml") && e.contains("stops.upper.gap_m") && e.contains("> 0"),
        "{e}"
    );
    // A coefficient of restitution outside [0, 1].
    let e = error(
        "[stops.lower]\ngap_m = 1e-3\nlaw = \"restitution\"\ncoefficient = 1.5",
        NONE,
    );
    assert!(
        e.contains("stops.lower.coefficient") && e.contains("1.5") && e.contains("between 0 and 1"),
        "{e}"
    );
    // A key that the law does not take.
    let e = error(
        "[stops.upper]\ngap_m = 1e-3\nlaw = \"restitution\"\ncoefficient = 0.5\n\
         damping_n_s_per_m = 1.0",
        NONE,
    );
    assert!(
        e.contains("stops.upper.damping_n_s_per_m") && e.contains("restitution"),
        "{e}"
    );
    // A key that the law needs.
    let e = error(
        "[stops.upper]\ngap_m = 1e-3\nlaw = \"hunt_crossley\"\nexponent = 1.5\n\
         damping_s_per_m = 0.1",
        NONE,
    );
    assert!(e.contains("stops.upper.stiffness_n_per_m_pow_n"), "{e}");
    // An unknown law and an unknown key.
    let e = error("[stops.upper]\ngap_m = 1e-3\nlaw = \"glue\"", NONE);
    assert!(e.contains("glue") && e.contains("restitution"), "{e}");
    let e = error(
        "[stops.upper]\ngap_m = 1e-3\nlaw = \"linear\"\nstiffness_n_per_m = 1e4\nstiff = 1",
        NONE,
    );
    assert!(e.contains("stiff"), "{e}");
    // `both` with a side.
    let e = error(
        "[stops.both]\ngap_m = 1e-3\nlaw = \"linear\"\nstiffness_n_per_m = 1e4\n\
         [stops.upper]\ngap_m = 1e-3\nlaw = \"linear\"\nstiffness_n_per_m = 1e4",
        NONE,
    );
    assert!(e.contains("stops.both"), "{e}");
    // Hertz point contact: exactly one of its two forms.
    let e = error(
        "[stops.upper]\ngap_m = 1e-3\nlaw = \"hertz_point\"\nstiffness_n_per_m1p5 = 1e9\n\
         sphere_radius_m = 1e-3",
        NONE,
    );
    assert!(e.contains("hertz_point"), "{e}");
}

#[test]
fn the_volume_is_optional_positive_and_finite() {
    use endstop::device::{ParamError, Size};
    let text = |size: &str| device_text(size, NONE);
    let d = Device::from_toml_str(&text("[size]\nvolume_m3 = 2.5e-9"), "ok.toml").unwrap();
    assert_eq!(d.size, Some(Size { volume_m3: 2.5e-9 }));
    assert_eq!(
        Device::from_toml_str(&text(""), "ok.toml").unwrap().size,
        None
    );
    for bad in ["0.0", "-1e-9", "inf", "nan"] {
        let e = Device::from_toml_str(&text(&format!("[size]\nvolume_m3 = {bad}")), "bad.toml")
            .expect_err(bad);
        assert!(
            matches!(&e, ParamError::OutOfRange { field, .. } if field == "size.volume_m3"),
            "{bad}: {e}"
        );
    }
    // An unknown key of the table.
    let e = error("[size]\nvolume_m3 = 1e-9\nvolume_cm3 = 1.0", NONE);
    assert!(e.contains("volume_cm3"), "{e}");
}

#[test]
fn bad_transducers_are_named_errors() {
    // A missing parameter.
    let e = error(
        "",
        "[transducer]\nkind = \"piezoelectric\"\ncapacitance_f = 1e-8\nload_resistance_ohm = 1e5",
    );
    assert!(
        e.contains("bad.toml") && e.contains("coupling_n_per_v"),
        "{e}"
    );
    // A value out of range.
    let e = error(
        "",
        "[transducer]\nkind = \"electromagnetic\"\ntransduction_n_per_a = 5.0\n\
         coil_resistance_ohm = 10.0\ncoil_inductance_h = -1e-3\nload_resistance_ohm = 100.0",
    );
    assert!(
        e.contains("transducer.coil_inductance_h") && e.contains(">= 0"),
        "{e}"
    );
    // An unknown kind.
    let e = error("", "[transducer]\nkind = \"thermal\"");
    assert!(e.contains("thermal"), "{e}");
    // A gap-closing pair beyond pull-in.
    let e = error(
        "[stops.both]\ngap_m = 1e-6\nlaw = \"linear\"\nstiffness_n_per_m = 1e4",
        "[transducer]\nkind = \"gap_closing_pair\"\nc0_f = 1e-12\nelectrode_gap_m = 2e-6\n\
         cp_f = 1e-12\nload_resistance_ohm = 1e6\nload_capacitance_f = 1e-12\nbias_v = 1e4",
    );
    assert!(
        e.contains("transducer.bias_v") && e.contains("pull-in"),
        "{e}"
    );
    // A stop beyond a gap-closing pair's electrodes.
    let e = error(
        "[stops.both]\ngap_m = 3e-6\nlaw = \"linear\"\nstiffness_n_per_m = 1e4",
        "[transducer]\nkind = \"gap_closing_pair\"\nc0_f = 1e-12\nelectrode_gap_m = 2e-6\n\
         cp_f = 1e-12\nload_resistance_ohm = 1e6\nload_capacitance_f = 1e-12\nbias_v = 1.0",
    );
    assert!(
        e.contains("stops.both.gap_m") && e.contains("electrode_gap_m"),
        "{e}"
    );
}

#[test]
fn a_broken_file_of_the_earlier_format_names_the_new_keys() {
    let text = std::fs::read_to_string(root().join("tests/fixtures/legacy/prototype1_v1.toml"))
        .unwrap()
        .replace("bump_radius_m", "bump_radius");
    let e = Device::from_toml_str(&text, "old.toml")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("old.toml") && e.contains("[stops.both]") && e.contains("area_overlap_pair"),
        "{e}"
    );
}

#[test]
fn one_sided_and_asymmetric_stops_are_ordinary() {
    let d = Device::from_toml_str(
        &device_text(
            "[stops.upper]\ngap_m = 1e-3\nlaw = \"linear\"\nstiffness_n_per_m = 1e5\n\
             [stops.lower]\ngap_m = 2e-3\nlaw = \"hertz_point\"\nsphere_radius_m = 1e-3\n\
             youngs_modulus_pa = 2e11\npoisson_ratio = 0.3",
            PIEZO,
        ),
        "asym.toml",
    )
    .unwrap();
    assert!(d.stops.symmetric().is_none());
    assert_eq!(d.stops.smallest_gap_m(), Some(1e-3));
    let one = Device::from_toml_str(
        &device_text(
            "[stops.lower]\ngap_m = 1e-3\nlaw = \"restitution\"\ncoefficient = 0.8",
            PIEZO,
        ),
        "one.toml",
    )
    .unwrap();
    assert!(one.stops.upper.is_none());
    let back = Device::from_toml_str(&one.to_toml_string(), "back").unwrap();
    assert_eq!(one, back);
}
