//! What `endstop design` tells the designer: on a problem no design can meet, infeasible and
//! the least violating design, never an optimum; an answer at the end of a range, said to be.

use std::path::PathBuf;

use polars::prelude::*;

use crate::cli_common::{read_parquet, run};

fn example(name: &str) -> String {
    format!("{}/../data/examples/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// Runs `endstop design` on the example `device` with `args` into a fresh directory named by
/// `tag`; returns the directory and its `numbers.md`.
fn design(tag: &str, device: &str, args: &[&str]) -> (PathBuf, String) {
    let out = std::env::temp_dir().join(format!("endstop-design-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let device = example(device);
    let mut all = vec!["design", "--device", &device, "--map-points", "0"];
    all.extend_from_slice(args);
    let out_arg = out.to_str().unwrap().to_string();
    all.extend_from_slice(&["--out", &out_arg]);
    let o = run(&all);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let md = std::fs::read_to_string(out.join("numbers.md")).unwrap();
    (out, md)
}

/// The piezoelectric cantilever at 0.5 g with its stopper's gap kept between 20 and 50 um,
/// far inside the tip's free stroke (the example's gap of 0.1 mm is reached from about
/// 0.3 g), under a limit of 1 um/s on the impact speed, which no impacting design meets:
/// `numbers.md` says infeasible and gives the least violating design with its violation,
/// `summary.json` records it as not feasible, and the design it gives is the least violating
/// of every design in `designs.parquet`.
#[test]
fn an_unmeetable_limit_is_reported_infeasible_with_the_least_violating_design() {
    let (out, md) = design(
        "infeasible",
        "piezo_cantilever.toml",
        &[
            "--range",
            "stops.upper.gap_m=2e-5..5e-5",
            "--range",
            "load.resistance_ohm=1e4..1e5",
            "--freq-hz",
            "120",
            "--accel-rms-g",
            "0.5",
            "--max-impact-speed-m-s",
            "1e-6",
            "--samples",
            "8",
        ],
    );
    assert!(
        md.contains("**infeasible**: no design tried meets every limit; the least violating is"),
        "{md}"
    );
    assert!(!md.contains("**optimum**"), "an optimum is claimed: {md}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["numbers"]["feasible"].as_f64(), Some(0.0));

    let designs = read_parquet(&out.join("designs.parquet"));
    let feasible = designs.column("feasible").unwrap().bool().unwrap();
    assert_eq!(feasible.sum(), Some(0), "a design in the table is feasible");
    let violation = designs.column("violation").unwrap().f64().unwrap();
    let least = violation.min().unwrap();
    assert!(least > 0.0 && least.is_finite(), "least violation {least}");
    // The answer's violation, as numbers.md prints it, is the table's least: 3 significant
    // digits hold it to half a unit of the third, at most 5e-3 of the value.
    let printed = md
        .split("(violation ")
        .nth(1)
        .and_then(|s| s.split(')').next())
        .and_then(|s| s.parse::<f64>().ok())
        .expect("the answer's violation in numbers.md");
    assert!(
        (printed / least - 1.0).abs() <= 5e-3 * (1.0 + 1e-9),
        "printed {printed} vs least {least} (3 significant digits)"
    );
    // Its power is that design's.
    let k = violation
        .into_iter()
        .position(|v| v == Some(least))
        .unwrap();
    let power = designs.column("power_w").unwrap().f64().unwrap().get(k);
    assert_eq!(summary["numbers"]["power_w"].as_f64(), power);
    let _ = std::fs::remove_dir_all(&out);
}

/// The cantilever behind its diode bridge at 120 Hz and 0.3 g with its stopper's gap between
/// 40 and 80 um, well inside the stroke the tip takes without it (it still strikes a stopper
/// 0.16 mm away: the Design chapter's map of this device): the stopper caps the stroke, so
/// the power grows with the gap and the best design lies at the gap's upper end, where
/// `numbers.md` must say so, while the load's best lies inside its two decades (about
/// 31 kohm in that map).
#[test]
fn an_answer_at_the_end_of_a_range_is_said_to_be() {
    let (out, md) = design(
        "end",
        "piezo_bridge.toml",
        &[
            "--range",
            "stops.upper.gap_m=4e-5..8e-5",
            "--range",
            "load.resistance_ohm=3e3..3e5",
            "--freq-hz",
            "120",
            "--accel-rms-g",
            "0.3",
        ],
    );
    let answer = md
        .lines()
        .find(|l| l.starts_with("- **optimum**"))
        .unwrap_or_else(|| panic!("no optimum: {md}"));
    assert!(
        answer.contains("`stops.upper.gap_m` = 0.00008000 (the upper end of its range)"),
        "{answer}"
    );
    assert_eq!(
        answer.matches("end of its range").count(),
        1,
        "only the gap is at an end: {answer}"
    );
    assert!(
        md.contains("- the answer lies at an end of a range"),
        "{md}"
    );
    let _ = std::fs::remove_dir_all(&out);
}

/// A measured record in place of the sines: a CSV record of the cantilever's 120 Hz drive at
/// 0.3 g rms. `numbers.md` says the objective is the mean power over the record after the
/// pre-roll and that it needs no confirmation on fresh seeds; `summary.json` records the
/// file, the rate and the pre-roll, and holds no confirmed power.
#[test]
fn a_measured_record_is_designed_over_without_confirmation() {
    let dir = std::env::temp_dir().join(format!("endstop-design-rec-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let csv = dir.join("sine.csv");
    let (fs, peak) = (10e3, 0.3 * std::f64::consts::SQRT_2 * 9.80665);
    let mut text = String::from("time_s,accel_m_per_s2\n");
    for k in 0..12_000 {
        let t = k as f64 / fs;
        let a = peak * (2.0 * std::f64::consts::PI * 120.0 * t).sin();
        text.push_str(&format!("{t:.6},{a:.9e}\n"));
    }
    std::fs::write(&csv, text).unwrap();
    let (out, md) = design(
        "record",
        "piezo_cantilever.toml",
        &[
            "--range",
            "load.resistance_ohm=1e4..1e5",
            "--accel-file",
            csv.to_str().unwrap(),
            "--sample-rate-hz",
            "20000",
            "--samples",
            "4",
        ],
    );
    assert!(md.contains("over the measured record"), "{md}");
    assert!(md.contains("no confirmation on fresh seeds"), "{md}");
    assert!(md.contains("(mean over the record)"), "{md}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert!(summary["numbers"]["power_w"].as_f64().unwrap() > 0.0);
    assert!(summary["numbers"].get("power_confirmed_w").is_none());
    let settings = &summary["settings"];
    assert_eq!(settings["record_sample_rate_hz"].as_f64(), Some(20e3));
    assert!(settings["record_transient_s"].as_f64().unwrap() > 0.0);
    assert!(settings["accel_file"]
        .as_str()
        .unwrap()
        .ends_with("sine.csv"));
    let _ = std::fs::remove_dir_all(&dir);
}
