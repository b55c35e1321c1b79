//! The ngspice cross-check's verdicts (`endstop::paper::crosscheck`) on stored ngspice output,
//! without ngspice: `tests/fixtures/ngspice/` holds, for two cases under ngspice's default
//! settings, the netlist the library writes and the waveforms ngspice 39 wrote from it (the
//! command and version are in its README). The tests check that the stored netlists are still
//! the library's (so the stored output answers the current model), and judge the stored
//! output: prototype 1 without impacts stays within 0.1 % of ours even with ngspice's
//! defaults, and prototype 1 on its impacting upper branch falls to the lower branch with
//! them (no impacts left in the window), 14 % below ours. With ngspice installed, an ignored
//! test runs ngspice on the stored netlists and compares its output with the stored files.

use std::path::PathBuf;

use endstop::paper::crosscheck::{
    cases, prepare, Difference, Ours, Prepared, Setting, SpiceRun, Verdict,
};
use endstop::paper::setups::endstop;

use crate::common;

/// The stored runs: (case key, setting).
const FIXTURES: [(&str, Setting); 2] = [
    ("p1_free", Setting::Defaults),
    ("p1_impacting", Setting::Defaults),
];

fn fixture_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/ngspice")
}

/// The file stem of a stored run.
fn stem(case: &str, setting: Setting) -> String {
    format!("{case}_{}", setting.key())
}

/// A case prepared and our side of it run.
fn ours(case: &str) -> (Prepared, Ours) {
    let case = cases(&common::prototype1(), &common::prototype2())
        .into_iter()
        .find(|c| c.key == case)
        .expect("a case of the cross-check");
    let prepared = prepare(&case).unwrap();
    let ours = prepared.ours().unwrap();
    (prepared, ours)
}

fn read(name: &str) -> String {
    let path = fixture_dir().join(name);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[test]
fn the_stored_netlists_are_the_ones_the_library_writes() {
    for (case, setting) in FIXTURES {
        let (prepared, ours) = ours(case);
        let s = stem(case, setting);
        let text = prepared.netlist(&ours, setting, format!("{s}.dat"));
        assert!(
            text == read(&format!("{s}.cir")),
            "{s}.cir is not the netlist the library writes now: regenerate the fixture as \
             tests/fixtures/ngspice/README.md says"
        );
    }
}

#[test]
fn stored_ngspice_output_is_judged_by_the_case_tolerance() {
    // Without impacts ngspice's defaults stay within the 0.1 % of the acceptance tolerance.
    let (prepared, free) = ours("p1_free");
    let spice = SpiceRun::of_wrdata(
        &read("p1_free_defaults.dat"),
        endstop(&prepared.case.device).gap_m,
        free.window_s,
    )
    .unwrap();
    let d = Difference::of(&free.measurement, &spice);
    assert_eq!(
        d.verdict(prepared.case.tolerance()),
        Verdict::Reproduced,
        "{d:?}"
    );
    assert!(d.rel > 0.0 && spice.contact_fraction == 0.0, "{d:?}");
    // On the impacting upper branch they lose it: ngspice ends on the lower branch, without
    // impacts, far outside the 1 % tolerance.
    let (prepared, upper) = ours("p1_impacting");
    let spice = SpiceRun::of_wrdata(
        &read("p1_impacting_defaults.dat"),
        endstop(&prepared.case.device).gap_m,
        upper.window_s,
    )
    .unwrap();
    let d = Difference::of(&upper.measurement, &spice);
    assert_eq!(
        d.verdict(prepared.case.tolerance()),
        Verdict::Deviates,
        "{d:?}"
    );
    assert!(upper.measurement.contact_fraction > 0.0);
    assert_eq!(spice.contact_fraction, 0.0);
    assert!(d.rel_v1 < -0.1, "{d:?}");
}

#[test]
fn a_window_the_output_does_not_cover_is_an_error() {
    let (prepared, free) = ours("p1_free");
    let late = (free.window_s.0 + 1.0, free.window_s.1 + 1.0);
    let r = SpiceRun::of_wrdata(
        &read("p1_free_defaults.dat"),
        endstop(&prepared.case.device).gap_m,
        late,
    );
    assert!(r.is_err());
}

/// Needs ngspice: runs it on the stored netlists and compares its waveforms with the stored
/// ones, byte for byte (`cargo test --release --test all -- crosscheck:: --ignored`).
#[test]
#[ignore]
fn ngspice_writes_the_stored_output() {
    let tmp = std::env::temp_dir().join(format!("endstop-fixture-{}", std::process::id()));
    std::fs::create_dir_all(&tmp).unwrap();
    for (case, setting) in FIXTURES {
        let s = stem(case, setting);
        std::fs::write(tmp.join(format!("{s}.cir")), read(&format!("{s}.cir"))).unwrap();
        let status = std::process::Command::new("ngspice")
            .arg("-b")
            .arg(format!("{s}.cir"))
            .current_dir(&tmp)
            .output()
            .expect("ngspice is installed")
            .status;
        assert!(status.success(), "{s}: ngspice {status}");
        let out = std::fs::read_to_string(tmp.join(format!("{s}.dat"))).unwrap();
        assert!(out == read(&format!("{s}.dat")), "{s}.dat differs");
    }
    std::fs::remove_dir_all(&tmp).ok();
}
