//! The same experiment gives byte-identical Parquet, summary and plot (SVG, PNG) files on every
//! run and for any thread count (RAYON_NUM_THREADS = 1 versus 2): one sine-sweep and one random-vibration
//! experiment. Outputs go to temporary directories (ENDSTOP_OUTPUT_DIR), never to
//! data/results/. The random-vibration run also serves the provenance check of its Parquet metadata
//! (each parameter set labelled with its own parameter file), so fig11 runs twice, not three
//! times.

use endstop::paper::setups::endstop;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

use endstop::device::Device;
use endstop::paper::setups::ParamSet;
use polars::prelude::{ParquetReader, SerReader};

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

/// Every .parquet, .svg, .png and summary.json under `dir`, by relative path.
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
                let kept = [".parquet", ".svg", ".png"];
                if kept.iter().any(|ext| name.ends_with(ext)) || name == "summary.json" {
                    let rel = p.strip_prefix(dir).unwrap().to_string_lossy().to_string();
                    map.insert(rel, std::fs::read(&p).unwrap());
                }
            }
        }
    }
    map
}

/// The Parquet, summary and plot files of `bin` run with 1 and with 2 threads.
fn outputs_1_and_2_threads(bin: &str) -> [BTreeMap<String, Vec<u8>>; 2] {
    let a = run(bin, "1", "a");
    let b = run(bin, "2", "b");
    let out = [outputs(&a), outputs(&b)];
    let _ = std::fs::remove_dir_all(a);
    let _ = std::fs::remove_dir_all(b);
    out
}

/// fig11's outputs, computed once for the tests of this file.
fn fig11_outputs() -> &'static [BTreeMap<String, Vec<u8>>; 2] {
    static OUT: OnceLock<[BTreeMap<String, Vec<u8>>; 2]> = OnceLock::new();
    OUT.get_or_init(|| outputs_1_and_2_threads(env!("CARGO_BIN_EXE_fig11")))
}

fn assert_identical(bin: &str, [oa, ob]: &[BTreeMap<String, Vec<u8>>; 2]) {
    assert!(!oa.is_empty(), "{bin} wrote no Parquet or summary");
    assert!(
        oa.keys().any(|k| k.ends_with(".svg")) && oa.keys().any(|k| k.ends_with(".png")),
        "{bin} wrote no plot"
    );
    assert_eq!(
        oa.keys().collect::<Vec<_>>(),
        ob.keys().collect::<Vec<_>>(),
        "{bin}: different file sets"
    );
    for (k, va) in oa {
        assert!(va == &ob[k], "{bin}: {k} differs between 1 and 2 threads");
    }
}

#[test]
fn sweep_fig08_is_byte_identical_for_1_and_2_threads() {
    let bin = env!("CARGO_BIN_EXE_fig08");
    assert_identical(bin, &outputs_1_and_2_threads(bin));
}

#[test]
fn record_fig11_is_byte_identical_for_1_and_2_threads() {
    assert_identical(env!("CARGO_BIN_EXE_fig11"), fig11_outputs());
}

/// The key-value metadata of a Parquet file.
fn parquet_metadata(bytes: &[u8]) -> BTreeMap<String, String> {
    let mut reader = ParquetReader::new(std::io::Cursor::new(bytes.to_vec()));
    let meta = reader.get_metadata().expect("Parquet footer");
    meta.key_value_metadata()
        .iter()
        .flatten()
        .map(|kv| (kv.key.clone(), kv.value.clone().unwrap_or_default()))
        .collect()
}

#[test]
fn fig11_parquet_metadata_holds_each_parameter_set_under_its_own_label() {
    // Figure 11 runs prototype 1 under two parameter sets. Every Parquet file must record the
    // published parameter file's text under `published` and the calibrated device (the
    // end-stop gap fitted to Figure 8's onset, computed here independently) under
    // `calibrated`, not the published text twice.
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let published_text = std::fs::read_to_string(root.join("data/prototype1.toml")).unwrap();
    let published = Device::from_toml_str(&published_text, "prototype1.toml").unwrap();
    let fitted = endstop(
        &endstop::paper::calibration::calibrate_prototype1(&published)
            .unwrap()
            .device,
    )
    .gap_m;
    let gap = endstop(&published).gap_m;
    assert!(
        (fitted / gap - 1.0).abs() > 1e-3,
        "the calibration moved the gap"
    );
    let files: Vec<(&String, &Vec<u8>)> = fig11_outputs()[0]
        .iter()
        .filter(|(k, _)| k.ends_with(".parquet"))
        .collect();
    assert_eq!(files.len(), 3, "fig11 writes summary, records and spectra");
    for (name, bytes) in files {
        let kv = parquet_metadata(bytes);
        let entry = |label: &str| -> &String {
            let found: Vec<&String> = kv
                .iter()
                .filter(|(k, _)| k.starts_with("param_file:") && k.ends_with(&format!(":{label}")))
                .map(|(_, v)| v)
                .collect();
            assert_eq!(
                found.len(),
                1,
                "{name}: one `{label}` parameter file in {kv:?}"
            );
            found[0]
        };
        assert_eq!(
            entry(ParamSet::Published.label()),
            &published_text,
            "{name}"
        );
        let calibrated = entry(ParamSet::Calibrated.label());
        assert_ne!(
            calibrated, &published_text,
            "{name}: calibrated holds the published text"
        );
        let d = Device::from_toml_str(calibrated, "calibrated").unwrap();
        let recorded = endstop(&d).gap_m;
        assert!(
            (recorded / fitted - 1.0).abs() < 1e-12,
            "{name}: calibrated gap {recorded} m, fitted {fitted} m"
        );
    }
}
