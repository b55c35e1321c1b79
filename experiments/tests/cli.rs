//! The `endstop` command-line tool end to end on a device that is not one of the paper's
//! (`data/examples/my_harvester.toml`): both studies run, write readable Parquet with
//! provenance metadata, a plot and a summary; bad input is refused with a clear message.

use std::path::Path;
use std::process::Command;

use crate::cli_common::{read_parquet, BIN};

fn example() -> String {
    format!(
        "{}/../data/examples/my_harvester.toml",
        env!("CARGO_MANIFEST_DIR")
    )
}

fn tmp(tag: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("endstop-cli-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn summary_number(dir: &Path, key: &str) -> Option<f64> {
    let text = std::fs::read_to_string(dir.join("summary.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v["numbers"][key].as_f64()
}

/// Runs the tool on the example device (`args` follow `<study> --device <example>`) writing
/// into `out`, and asserts that it succeeded and wrote every one of `files`.
fn run_ok(study: &str, args: &[&str], out: &Path, files: &[&str]) {
    let o = Command::new(BIN)
        .args([study, "--device", &example()])
        .args(args)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in files {
        assert!(out.join(f).exists(), "missing {f}");
    }
}

/// Runs the tool with `args`, asserts that it exits with status 1, and returns its stderr.
fn run_refused(args: &[&str]) -> String {
    let o = Command::new(BIN).args(args).output().unwrap();
    assert_eq!(o.status.code(), Some(1));
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn sweep_on_a_user_device_writes_data_plot_and_summary() {
    let out = tmp("sweep");
    let args = [
        "--from",
        "500",
        "--to",
        "700",
        "--step",
        "4",
        "--accel-rms-g",
        "0.3",
    ];
    let files = [
        "sweep.parquet",
        "endstop-sweep.svg",
        "endstop-sweep.png",
        "summary.json",
        "numbers.md",
    ];
    run_ok("sweep", &args, &out, &files);
    let df = read_parquet(&out.join("sweep.parquet"));
    assert_eq!(df.height(), 51);
    let v = df.column("v1_rms_v").unwrap().f64().unwrap();
    assert!(v.into_no_null_iter().all(|x| x.is_finite() && x > 0.0));
    // This device at 0.3 g reaches its 8 um stops near its 616 Hz resonance.
    let onset = summary_number(&out, "impact_onset_hz").expect("an impact onset");
    assert!(onset > 500.0 && onset < 700.0, "onset {onset}");
    let _ = std::fs::remove_dir_all(out);
}

#[test]
fn random_on_a_user_device_writes_data_plot_and_summary() {
    let out = tmp("random");
    let args = ["--psd", "1e-5", "--records", "2", "--duration-s", "2"];
    let files = [
        "output_psd.parquet",
        "records.parquet",
        "endstop-random.svg",
        "summary.json",
    ];
    run_ok("random", &args, &out, &files);
    let p = summary_number(&out, "power_w").unwrap();
    let p21 = summary_number(&out, "eq21_power_w").unwrap();
    // At 1e-5 g^2/Hz this device stays clear of its stops, so the simulated power must agree
    // with eq 21 within the statistical error of 2 x 2 s records (~10 % for Qm ~ 150; we allow
    // 30 %, about 3 sigma, since this test checks the tool, not the physics).
    assert!(
        p > 0.0 && ((p - p21) / p21).abs() < 0.3,
        "power {p} vs eq 21 {p21}"
    );
    let md = std::fs::read_to_string(out.join("summary.json")).unwrap();
    assert!(md.contains("my_harvester.toml"));
    let _ = std::fs::remove_dir_all(out);
}

#[test]
fn bad_input_is_refused_with_a_message() {
    let ex = example();
    let err = run_refused(&[
        "sweep",
        "--device",
        &ex,
        "--from",
        "900",
        "--to",
        "500",
        "--accel-rms-g",
        "0.3",
    ]);
    assert!(err.contains("--to"), "{err}");
    let err = run_refused(&["random", "--device", "/nonexistent.toml", "--psd", "1e-3"]);
    assert!(err.contains("/nonexistent.toml"), "{err}");
}

#[test]
fn response_on_a_user_device_writes_branch_sweeps_plot_and_summary() {
    let out = tmp("response");
    let args = [
        "--from",
        "560",
        "--to",
        "700",
        "--step",
        "4",
        "--accel-rms-g",
        "0.3",
    ];
    let files = [
        "continuation.parquet",
        "sweeps.parquet",
        "endstop-response.svg",
        "summary.json",
        "numbers.md",
    ];
    run_ok("response", &args, &out, &files);
    let df = read_parquet(&out.join("continuation.parquet"));
    assert!(df.height() > 10);
    let f = df.column("freq_hz").unwrap().f64().unwrap();
    assert!(f.into_no_null_iter().all(|x| (559.0..=710.0).contains(&x)));
    let sweeps = read_parquet(&out.join("sweeps.parquet"));
    // Both directions over the same 36-step grid (the up-sweep may extend while in contact).
    assert!(sweeps.height() >= 72);
    // This device at 0.3 g reaches its 8 um stops near its 616 Hz resonance: the branch has
    // a grazing point in the range and the down-sweep leaves the lower branch inside it.
    let graze = summary_number(&out, "event_0_hz").expect("a grazing point");
    assert!(graze > 560.0 && graze < 700.0, "grazing {graze}");
    let down = summary_number(&out, "down_branch_end_hz").expect("a down-sweep transition");
    assert!(down > 560.0 && down < 700.0, "down-sweep {down}");
    let ex = example();
    let err = run_refused(&[
        "response",
        "--device",
        &ex,
        "--from",
        "600",
        "--to",
        "700",
        "--accel-rms-g",
        "0",
    ]);
    assert!(err.contains("--accel-rms-g"), "{err}");
    let _ = std::fs::remove_dir_all(out);
}
