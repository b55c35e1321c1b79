//! The check that keeps a one-binary test layout whole: with `autotests = false`, a test file
//! that no module of the crate root declares is never compiled, so its tests never run. That
//! holds for the files in subfolders too (`tests/record_figures/regression.rs` is compiled only
//! because `tests/record_figures.rs` declares it), so the check walks the whole tree.

use std::path::{Path, PathBuf};

/// Every `*.rs` file under `dir`, at any depth, sorted.
fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let entries = std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    for entry in entries {
        let path = entry.expect("a directory entry").path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
    out.sort();
}

/// True when `text` declares the module `stem` (`mod stem;`, with any visibility) or names the
/// file `rel` in a `#[path = "..."]` attribute.
fn declares(text: &str, stem: &str, rel: &str) -> bool {
    let decl = format!("mod {stem};");
    text.lines().any(|l| {
        let l = l.trim();
        l == decl
            || l.strip_prefix("pub ").is_some_and(|r| r == decl)
            || l.strip_prefix("pub(crate) ").is_some_and(|r| r == decl)
            || l == format!("#[path = \"{rel}\"]")
    })
}

/// The files under `dir` (the crate root `root_file`, whose text is `root_source`, aside) that
/// no module declares, each with the file that should declare it; and how many files were
/// looked at. A file `dir/a.rs` or `dir/a/mod.rs` is declared by the root; a file
/// `dir/.../d/x.rs` by `dir/.../d.rs` or `dir/.../d/mod.rs` (a `mod x;` line, or a `#[path]`
/// attribute naming it relative to the declaring file's folder).
pub fn undeclared_test_files(
    dir: &Path,
    root_file: &str,
    root_source: &str,
) -> (Vec<String>, usize) {
    let mut files = Vec::new();
    rust_files(dir, &mut files);
    let read = |p: &Path| std::fs::read_to_string(p).unwrap_or_default();
    let mut missing = Vec::new();
    let mut seen = 0;
    for path in &files {
        let rel = path.strip_prefix(dir).expect("under dir");
        if rel == Path::new(root_file) {
            continue;
        }
        seen += 1;
        let name = path.file_name().and_then(|s| s.to_str()).unwrap_or("");
        // The module this file is, and the folder its declaring file sits in or beside.
        let (stem, folder) = if name == "mod.rs" {
            let d = rel.parent().expect("mod.rs in a folder");
            let stem = d.file_name().and_then(|s| s.to_str()).unwrap_or("");
            (
                stem.to_string(),
                d.parent().unwrap_or(Path::new("")).to_path_buf(),
            )
        } else {
            let stem = name.trim_end_matches(".rs").to_string();
            (stem, rel.parent().unwrap_or(Path::new("")).to_path_buf())
        };
        let ok = if folder.as_os_str().is_empty() {
            let r = rel.to_string_lossy().replace('\\', "/");
            declares(root_source, &stem, &r)
        } else {
            // Declared by `folder.rs` (beside the folder) or `folder/mod.rs`.
            let beside = dir.join(folder.with_extension("rs"));
            let inside = dir.join(&folder).join("mod.rs");
            let from_beside = folder
                .parent()
                .map(|p| rel.strip_prefix(p).unwrap_or(rel))
                .unwrap_or(rel)
                .to_string_lossy()
                .replace('\\', "/");
            let from_inside = rel
                .strip_prefix(&folder)
                .unwrap_or(rel)
                .to_string_lossy()
                .replace('\\', "/");
            (beside.is_file() && declares(&read(&beside), &stem, &from_beside))
                || (inside.is_file()
                    && inside != *path
                    && declares(&read(&inside), &stem, &from_inside))
        };
        if !ok {
            missing.push(rel.display().to_string());
        }
    }
    (missing, seen)
}

/// Asserts that every `*.rs` file under `dir`, at any depth (the crate root `root_file` aside),
/// is a module of that root (see [`undeclared_test_files`]).
pub fn assert_every_test_file_is_a_module(dir: &Path, root_file: &str, root_source: &str) {
    let (missing, seen) = undeclared_test_files(dir, root_file, root_source);
    assert!(seen > 0, "no test files in {}", dir.display());
    assert!(
        missing.is_empty(),
        "not compiled (no module declares them; add `mod <name>;` beside them, in {root_file} \
         for a file directly in {}): {missing:?}",
        dir.display()
    );
}
