//! The `endstop` tool on a device of several masses (the up-converter example): each study's
//! Parquet and numbers carry every mass's peak displacement and speed under the mass's name,
//! beside the one-mass columns of the output contract.

use std::path::{Path, PathBuf};
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_endstop");

/// The per-mass columns of the up-converter (its masses are `driver` and `generator`).
const MASS_COLUMNS: [&str; 4] = [
    "x_generator_peak_m",
    "v_generator_peak_m_per_s",
    "x_driver_peak_m",
    "v_driver_peak_m_per_s",
];

fn upconverter() -> String {
    format!(
        "{}/../data/examples/upconverter.toml",
        env!("CARGO_MANIFEST_DIR")
    )
}

fn tmp(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("endstop-climass-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn read_parquet(path: &Path) -> polars::prelude::DataFrame {
    use polars::prelude::*;
    ParquetReader::new(std::fs::File::open(path).unwrap())
        .finish()
        .unwrap()
}

fn run(args: &[&str]) -> std::process::Output {
    Command::new(BIN).args(args).output().unwrap()
}

/// Every per-mass column of `df` is there and positive, and the transducer mass's peak is the
/// one-mass `x_peak_m` (`x_col`) of the same row: the first mass of the state is the
/// transducer's, measured at the same samples.
fn assert_mass_columns(df: &polars::prelude::DataFrame, x_col: Option<&str>) {
    for c in MASS_COLUMNS {
        let col = df.column(c).unwrap_or_else(|_| panic!("no column {c}"));
        let v = col.f64().unwrap().clone();
        assert!(v.into_iter().all(|v| v.unwrap() > 0.0), "{c}");
    }
    if let Some(x) = x_col {
        let a = df.column(x).unwrap().f64().unwrap().clone();
        let b = df.column(MASS_COLUMNS[0]).unwrap().f64().unwrap().clone();
        for (a, b) in a.into_iter().zip(&b) {
            assert_eq!(a, b);
        }
    }
}

#[test]
fn a_two_mass_sweep_and_record_carry_each_mass_peaks() {
    let out = tmp("sweep");
    let o = run(&[
        "sweep",
        "--device",
        &upconverter(),
        "--from",
        "16",
        "--to",
        "20",
        "--step",
        "2",
        "--accel-rms-g",
        "0.5",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let df = read_parquet(&out.join("sweep.parquet"));
    // The one-mass contract's columns stay.
    for c in [
        "freq_hz",
        "v1_rms_v",
        "p1_w",
        "x_peak_m",
        "contact_fraction",
    ] {
        assert!(df.column(c).is_ok(), "{c}");
    }
    assert_mass_columns(&df, Some("x_peak_m"));
    let md = std::fs::read_to_string(out.join("numbers.md")).unwrap();
    assert!(
        md.contains("largest displacement and speed of each mass over the sweep")
            && md.contains("`driver`")
            && md.contains("`generator`"),
        "{md}"
    );
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
    for c in MASS_COLUMNS {
        assert!(summary.contains(c), "{c} not in summary.json");
    }

    let rec = tmp("record");
    let o = run(&[
        "random",
        "--device",
        &upconverter(),
        "--sine-g",
        "0.7",
        "--freq-hz",
        "18",
        "--duration-s",
        "3",
        "--sample-rate-hz",
        "5000",
        "--out",
        rec.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let df = read_parquet(&rec.join("records.parquet"));
    assert_mass_columns(&df, None);
    let md = std::fs::read_to_string(rec.join("numbers.md")).unwrap();
    assert!(
        md.contains("largest displacement and speed of each mass over the analysed record"),
        "{md}"
    );
    // The one-mass linear theory does not describe two masses: no number is given for it.
    assert!(
        md.contains("linear theory without stops under the same spectrum: not computed for a device of several masses"),
        "{md}"
    );
    let summary = std::fs::read_to_string(rec.join("summary.json")).unwrap();
    assert!(!summary.contains("linear_power_w"), "{summary}");
    let psd = read_parquet(&rec.join("output_psd.parquet"));
    let linear = psd
        .column("linear_psd_uw_per_hz")
        .unwrap()
        .f64()
        .unwrap()
        .clone();
    assert!(
        !linear.is_empty() && linear.into_iter().all(|v| v.is_none_or(f64::is_nan)),
        "linear theory written for two masses"
    );
    let _ = std::fs::remove_dir_all(out);
    let _ = std::fs::remove_dir_all(rec);
}
