//! The same experiment gives byte-identical Parquet and summary files on every run and for
//! any thread count (RAYON_NUM_THREADS = 1 versus 2): one narrowband and one broadband
//! experiment. Outputs go to temporary directories (ENDSTOP_OUTPUT_DIR), never to
//! data/results/.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

fn run(bin: &str, threads: &str, tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "endstop-det-{}-{}-{tag}",
        std::process::id(),
        Path::new(bin).file_name().unwrap().to_string_lossy()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    let out = Command::new(bin)
        .env("RAYON_NUM_THREADS", threads)
        .env("ENDSTOP_OUTPUT_DIR", &dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{bin} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    dir
}

/// Every .parquet and summary.json under `dir`, by relative path.
fn outputs(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut map = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let name = p.file_name().unwrap().to_string_lossy().to_string();
                if name.ends_with(".parquet") || name == "summary.json" {
                    let rel = p.strip_prefix(dir).unwrap().to_string_lossy().to_string();
                    map.insert(rel, std::fs::read(&p).unwrap());
                }
            }
        }
    }
    map
}

fn assert_identical(bin: &str) {
    let a = run(bin, "1", "a");
    let b = run(bin, "2", "b");
    let (oa, ob) = (outputs(&a), outputs(&b));
    assert!(!oa.is_empty(), "{bin} wrote no Parquet or summary");
    assert_eq!(
        oa.keys().collect::<Vec<_>>(),
        ob.keys().collect::<Vec<_>>(),
        "{bin}: different file sets"
    );
    for (k, va) in &oa {
        assert!(va == &ob[k], "{bin}: {k} differs between 1 and 2 threads");
    }
    let _ = std::fs::remove_dir_all(a);
    let _ = std::fs::remove_dir_all(b);
}

#[test]
fn narrowband_fig08_is_byte_identical_for_1_and_2_threads() {
    assert_identical(env!("CARGO_BIN_EXE_fig08"));
}

#[test]
fn broadband_fig11_is_byte_identical_for_1_and_2_threads() {
    assert_identical(env!("CARGO_BIN_EXE_fig11"));
}
