//! The `endstop` tool on nonlinear suspensions (`data/examples/hardening_em.toml`,
//! `bistable_stops_em.toml`): `random` writes the displacement density with its interval and,
//! for two wells, the rate of bottom-to-bottom passages; `response` reports the static equilibria; `basins`
//! writes the grid and each cell's attractor (every cell, each attractor placed by well) with
//! the attractors' table; a bad suspension or a bad basin option is refused by name, and
//! nothing is written.

use std::path::PathBuf;
use std::process::Command;

use crate::cli_common::{read_parquet, BIN};

fn data(rel: &str) -> String {
    format!("{}/../data/{rel}", env!("CARGO_MANIFEST_DIR"))
}

fn tmp(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("endstop-springs-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
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
    assert!(md.contains("bottom-to-bottom passages"), "{md}");
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

fn strings(df: &polars::prelude::DataFrame, col: &str) -> Vec<String> {
    df.column(col)
        .unwrap()
        .str()
        .unwrap()
        .into_iter()
        .map(|s| s.unwrap().to_string())
        .collect()
}

#[test]
fn basins_of_a_bistable_device_label_every_cell_by_its_attractor_and_well() {
    let out = tmp("bistable");
    let o = Command::new(BIN)
        .args([
            "basins",
            "--device",
            &data("examples/bistable_stops_em.toml"),
            "--freq",
            "55",
            "--accel-rms-g",
            "0.5",
            "--cells",
            "5",
            "--seeds-per-side",
            "2",
            "--out",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let cells = read_parquet(&out.join("basins.parquet"));
    assert_eq!(cells.height(), 25, "every cell of the 5 x 5 grid is a row");
    let attractors = read_parquet(&out.join("attractors.parquet"));
    let labels = strings(&attractors, "attractor");
    let places = strings(&attractors, "place");
    for p in &places {
        assert!(
            ["left well", "right well", "inter-well"].contains(&p.as_str()),
            "{p}"
        );
    }
    // Each cell's attractor is one of the table's or `unsettled`, and its place is that
    // attractor's.
    for (a, p) in strings(&cells, "attractor")
        .iter()
        .zip(strings(&cells, "place"))
    {
        match labels.iter().position(|l| l == a) {
            Some(k) => assert_eq!(p, places[k]),
            None => assert_eq!((a.as_str(), p.as_str()), ("unsettled", "unsettled")),
        }
    }
    let share: f64 = attractors
        .column("share")
        .unwrap()
        .f64()
        .unwrap()
        .into_iter()
        .map(|s| s.unwrap())
        .sum();
    let unsettled = strings(&cells, "attractor")
        .iter()
        .filter(|a| *a == "unsettled")
        .count();
    assert!((share + unsettled as f64 / 25.0 - 1.0).abs() < 1e-12);
    let md = std::fs::read_to_string(out.join("numbers.md")).unwrap();
    assert!(md.contains("a grid of 5 by 5 initial states"), "{md}");
    assert!(out.join("endstop-basins.svg").exists());
    let _ = std::fs::remove_dir_all(out);
}

/// Runs `endstop basins` with `extra` options on `device` and returns its stderr after
/// checking that it failed and wrote nothing.
fn refused(device: &str, extra: &[&str]) -> String {
    let out = tmp("bad");
    let mut args = vec![
        "basins",
        "--device",
        device,
        "--freq",
        "55",
        "--accel-rms-g",
        "0.5",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let o = Command::new(BIN).args(&args).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(!out.exists(), "{extra:?} wrote {}", out.display());
    err
}

#[test]
fn bad_basin_options_are_refused_by_name_and_nothing_is_written() {
    let bistable = data("examples/bistable_stops_em.toml");
    for (extra, named) in [
        (&["--cells", "1"][..], "--cells = 1"),
        (&["--x-range", "1e-4,-1e-4"][..], "--x-range"),
        (&["--v-range", "0,NaN"][..], "--v-range"),
        (&["--settle-tol", "0"][..], "--settle-tol = 0"),
        (&["--max-periods", "0"][..], "--max-periods = 0"),
        (&["--seeds-per-side", "50"][..], "--seeds-per-side = 50"),
    ] {
        let err = refused(&bistable, extra);
        assert!(err.contains(named), "{extra:?}: {err}");
    }
    // A device without stops has nothing to bound the positions by default.
    let err = refused(&data("examples/hardening_em.toml"), &[]);
    assert!(
        err.contains("no lower stop") && err.contains("--x-range"),
        "{err}"
    );
}
