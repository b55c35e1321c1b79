//! The library's integration tests, compiled into ONE test binary: every file of `tests/` is a
//! module of this crate root. One binary links the library and its dependencies once, where a
//! binary per file linked them some twenty times over (most of `cargo test`'s compile time
//! after a release build); it also computes each shared value of `common` (the calibration of
//! prototype 1, the claims file) once for all the tests.
//!
//! A new test file goes in `tests/` beside the others, gets a `mod` line below (in alphabetical
//! order), and reaches the shared helpers with `use crate::common;` (not `mod common;`, which
//! would look for `tests/<file>/common.rs`). `every_test_file_is_a_module_here` fails while a
//! file of `tests/` has no `mod` line, so that no test file is silently left out.
//!
//! Run one file's tests with a filter on its module: `cargo test --release --test all --
//! record_figures::`. Slow characterisation runs are `#[ignore]`d with their reason and run by
//! `cargo test --release -- --include-ignored` (CI runs that; see the README).

mod common;

mod calibration_recovery;
mod continuation_corners;
mod crosscheck;
mod design;
mod design_noise;
mod design_record;
mod device_description;
mod fit_family;
mod fit_held_out;
mod fit_recovery;
mod foundation;
mod general_model;
mod history_matching;
mod history_study;
mod impacting_orbits;
mod integrator;
mod integrator_stepping;
mod interface_orbits;
mod interface_records;
mod interface_sece_inductor;
mod interface_sshi_inductor;
mod interfaces;
mod interfaces_spice;
mod masses;
mod masses_exact;
mod masses_force_drive;
mod masses_impact_damper;
mod masses_studies;
mod nlvib_unilateral;
mod pair_bridge_spice;
mod period_two;
mod pwsdde_impduff;
mod record_accuracy;
mod record_figures;
mod record_ledger;
mod record_rebounds;
mod record_simulation;
mod regression_analytic;
mod regression_response;
mod response_orbits;
mod response_sweeps;
mod restitution;
mod restitution_orbits;
mod robustness;
mod spectral_noise;
mod spectrum_fit;
mod spice;
mod springs_basins;
mod springs_device;
mod springs_validation;
mod study_claims;
mod study_determinism;
mod sweep_figures;
mod sweep_steps;
mod swept_sine;
mod upconverter_response;
mod validation;

/// Every file of `tests/` is a module here.
#[test]
fn every_test_file_is_a_module_here() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests");
    common::layout::assert_every_test_file_is_a_module(&dir, "all.rs", include_str!("all.rs"));
}

/// The guard sees a file in a subfolder that no module declares (the defect it exists for,
/// planted in a temporary tree), at any depth and beside a `mod.rs`, and passes the same tree
/// once each file is declared.
#[test]
fn the_layout_guard_finds_undeclared_files_in_subfolders() {
    use common::layout::undeclared_test_files;
    let dir = std::env::temp_dir().join(format!("endstop-layout-guard-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    for sub in ["a/deep", "m"] {
        std::fs::create_dir_all(dir.join(sub)).unwrap();
    }
    let write = |rel: &str, text: &str| std::fs::write(dir.join(rel), text).unwrap();
    let root = "mod a;\nmod m;\n";
    write("root.rs", root);
    write("a.rs", "mod deep;\n");
    write("a/deep.rs", "");
    write("a/deep/x.rs", "");
    write("a/y.rs", "");
    write("m/mod.rs", "");
    write("m/z.rs", "");
    let (missing, seen) = undeclared_test_files(&dir, "root.rs", root);
    assert_eq!(seen, 6);
    assert_eq!(missing, ["a/deep/x.rs", "a/y.rs", "m/z.rs"]);
    write("a.rs", "mod deep;\n#[path = \"a/y.rs\"]\nmod y;\n");
    write("a/deep.rs", "pub mod x;\n");
    write("m/mod.rs", "pub(crate) mod z;\n");
    let (missing, _) = undeclared_test_files(&dir, "root.rs", root);
    assert!(missing.is_empty(), "{missing:?}");
    // A folder module the root leaves out: its `mod.rs` is reported (its children follow it).
    let (missing, _) = undeclared_test_files(&dir, "root.rs", "mod a;\n");
    assert_eq!(missing, ["m/mod.rs"]);
    std::fs::remove_dir_all(&dir).unwrap();
}
