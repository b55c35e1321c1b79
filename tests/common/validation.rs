//! What the validation tests share: the validation devices and the assertion of a set of
//! checks.

use std::collections::HashMap;

use endstop::device::Device;
use endstop::validation::Check;

/// The repository's root.
pub fn root() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).to_path_buf()
}

/// The rows of the reference file `data/references/<folder>/<file>` (comma-separated, a
/// header line of column names), each by column name.
pub fn reference_rows(folder: &str, file: &str) -> Vec<HashMap<String, String>> {
    let path = root().join("data/references").join(folder).join(file);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path:?}: {e}"));
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .unwrap_or_default()
        .split(',')
        .map(str::to_string)
        .collect();
    lines
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            header
                .iter()
                .cloned()
                .zip(l.split(',').map(str::to_string))
                .collect()
        })
        .collect()
}

/// The validation device `data/validation/<name>.toml`.
pub fn device(name: &str) -> Device {
    let rel = format!("data/validation/{name}.toml");
    let text = std::fs::read_to_string(root().join(&rel)).unwrap();
    Device::from_toml_str(&text, &rel).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// Prints every check and asserts each one that is judged (an open question is printed, not
/// judged).
pub fn assert_all(checks: &[Check]) {
    assert!(!checks.is_empty(), "no checks");
    for c in checks {
        eprintln!(
            "{} | {} | {} | theirs {:e} | ours {:e} | difference {:e} (tolerance {:e}){}",
            c.group,
            c.source,
            c.quantity,
            c.compared.reference,
            c.compared.ours,
            c.difference(),
            c.compared.tolerance,
            if c.is_open() { " [open question]" } else { "" }
        );
    }
    for c in checks.iter().filter(|c| !c.is_open()) {
        assert!(
            c.passes(),
            "{}: {} against {}: difference {:e} above {:e} ({})",
            c.group,
            c.quantity,
            c.source,
            c.difference(),
            c.compared.tolerance,
            c.reason
        );
    }
}
