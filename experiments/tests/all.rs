//! The experiments' integration tests (they run the programs end to end), compiled into ONE
//! test binary: every file of `experiments/tests/` is a module of this crate root, so that the
//! reproduction's dependencies (Polars, plotters, ...) are linked into one test binary instead
//! of one per file.
//!
//! A new test file goes in `experiments/tests/` beside the others and gets a `mod` line below
//! (in alphabetical order); `every_test_file_is_a_module_here` fails while a file has none.
//! Run one file's tests with a filter on its module: `cargo test --release -p
//! endstop-experiments --test all -- cli::`. Slow runs are `#[ignore]`d with their reason and
//! run by `cargo test --release -- --include-ignored` (CI runs that; see the README).

#[path = "../../tests/common/layout.rs"]
mod layout;

mod bad_input;
mod bad_input_props;
mod calibration_artefact;
mod cli;
mod cli_common;
mod cli_design;
mod cli_devices;
mod cli_interface;
mod cli_masses;
mod cli_merit;
mod crosscheck_recording;
mod determinism;
mod fit_cli;
mod fit_paper;
mod springs_bad_input_props;
mod springs_cli;

/// Every file of `experiments/tests/` is a module here.
#[test]
fn every_test_file_is_a_module_here() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests");
    layout::assert_every_test_file_is_a_module(&dir, "all.rs", include_str!("all.rs"));
}

/// No program marked `test = false` in Cargo.toml has unit tests (`cargo test` would not
/// compile them, so they would never run): a program that gains one drops its `test = false`.
#[test]
fn no_program_skipped_by_cargo_test_has_unit_tests() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let manifest: toml::Table = include_str!("../Cargo.toml").parse().expect("Cargo.toml");
    let bins = manifest["bin"].as_array().expect("[[bin]] entries");
    let mut skipped = 0;
    for bin in bins
        .iter()
        .filter(|b| b.get("test") == Some(&toml::Value::Boolean(false)))
    {
        skipped += 1;
        let main = dir.join(bin["path"].as_str().expect("a bin's path"));
        // A program in a directory of its own (`endstop/main.rs`) has its modules beside it.
        let files: Vec<std::path::PathBuf> = if main.ends_with("main.rs") {
            std::fs::read_dir(main.parent().unwrap())
                .unwrap()
                .map(|e| e.unwrap().path())
                .filter(|p| p.extension().is_some_and(|e| e == "rs"))
                .collect()
        } else {
            vec![main]
        };
        for file in files {
            let text = std::fs::read_to_string(&file).unwrap();
            assert!(
                !text.contains("#[test]") && !text.contains("#[cfg(test)]"),
                "{} has unit tests, but its program is `test = false` in Cargo.toml",
                file.display()
            );
        }
    }
    assert!(skipped > 0, "no program is `test = false`");
}
