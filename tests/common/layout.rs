//! The check that keeps a one-binary test layout whole: with `autotests = false`, a test file
//! that its crate root does not name as a module is never compiled, so its tests never run.

use std::path::Path;

/// Asserts that every `*.rs` file directly in `dir` (the crate root `root_file` aside) is a
/// module of that root, i.e. that `root_source` has the line `mod <stem>;`.
pub fn assert_every_test_file_is_a_module(dir: &Path, root_file: &str, root_source: &str) {
    let mut files = 0;
    for entry in std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display())) {
        let path = entry.expect("a directory entry").path();
        let Some(name) = path.file_name().and_then(|s| s.to_str()) else {
            continue;
        };
        let Some(stem) = name.strip_suffix(".rs") else {
            continue;
        };
        if name == root_file {
            continue;
        }
        files += 1;
        assert!(
            root_source.lines().any(|l| l == format!("mod {stem};")),
            "{} is not compiled: add `mod {stem};` to {root_file} beside it",
            path.display()
        );
    }
    assert!(files > 0, "no test files in {}", dir.display());
}
