//! The `endstop` tool on nonlinear suspensions (`data/examples/hardening_em.toml`,
//! `bistable_stops_em.toml`): `random` writes the displacement density with its interval and,
//! for two wells, the well-to-well rate; `response` reports the static equilibria; a bad
//! suspension is refused naming the file, the field and the range, and nothing is written.

use std::path::{Path, PathBuf};
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_endstop");

fn data(rel: &str) -> String {
    format!("{}/../data/{rel}", env!("CARGO_MANIFEST_DIR"))
}

fn tmp(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("endstop-springs-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn read_parquet(path: &Path) -> polars::prelude::DataFrame {
    use polars::prelude::*;
    ParquetReader::new(std::fs::File::open(path).unwrap())
        .finish()
        .unwrap()
}

#[test]
fn random_on_a_bistable_device_writes_the_density_and_the_transition_rate() {
    let out = tmp("random");
    let o = Command::new(BIN)
        .args([
            "random",
            "--device",
            &data("examples/bistable_stops_em.toml"),
            "--psd",
            "1e-3",
            "--records",
            "2",
            "--duration-s",
            "2",
            "--out",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let df = read_parquet(&out.join("displacement_pdf.parquet"));
    let x = df.column("x_m").unwrap().f64().unwrap().clone();
    let p = df.column("density_per_m").unwrap().f64().unwrap().clone();
    let w = x.get(1).unwrap() - x.get(0).unwrap();
    let total: f64 = p.into_iter().map(|v| v.unwrap() * w).sum();
    // The bins span the largest |x| of the records, so every sample is in one.
    assert!((total - 1.0).abs() < 1e-9, "density integrates to {total}");
    let md = std::fs::read_to_string(out.join("numbers.md")).unwrap();
    assert!(md.contains("well-to-well transitions"), "{md}");
    assert!(
        md.contains("`bistable` suspension (static equilibria"),
        "{md}"
    );
    let _ = std::fs::remove_dir_all(out);
}

#[test]
fn a_bad_suspension_is_refused_and_nothing_is_written() {
    let dir = tmp("bad");
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(data("examples/bistable_stops_em.toml"))
        .unwrap()
        .replace("gap_m = 8e-4", "gap_m = 4e-4");
    std::fs::write(dir.join("my.toml"), text).unwrap();
    let out = dir.join("out");
    let o = Command::new(BIN)
        .current_dir(&dir)
        .args([
            "random",
            "--device",
            "my.toml",
            "--psd",
            "1e-3",
            "--out",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains(
            "my.toml: field `stops.both.gap_m` = 4e-4 is out of range: must be > \
                      mechanics.suspension.well_m = 5e-4"
        ),
        "{err}"
    );
    assert!(!out.exists());
    let _ = std::fs::remove_dir_all(dir);
}
