//! `endstop response` and `endstop random` on a device with an interface circuit (the example
//! cantilever with a stop behind a full bridge, `data/examples/piezo_bridge.toml`): the
//! response writes the sweeps and the continued branch, which turns at two folds with an
//! unstable stretch between them; a noise ensemble writes each record's DC power, efficiency
//! and ledger, and an open DC load is refused with nothing written; bad charging and noise
//! options and an implausible drive are named; the switched interfaces behind a coil are
//! refused naming the parts.

use std::path::Path;
use std::process::Command;

use crate::cli_common::{read_parquet, BIN};

/// At 1 g rms the stop bends the response: between 125 and 180 Hz the continued steady state
/// turns at two folds, is unstable between them and stable on either side, and both sweeps
/// find a steady state at each of their 12 frequencies.
#[test]
fn response_with_an_interface_continues_through_two_folds() {
    let out = std::env::temp_dir().join(format!(
        "endstop-cli-{}-interface-response",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&out);
    let device = format!(
        "{}/../data/examples/piezo_bridge.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    let o = Command::new(BIN)
        .args(["response", "--device", &device])
        .args(["--from", "125", "--to", "180", "--step", "5"])
        .args(["--accel-rms-g", "1", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in [
        "sweeps.parquet",
        "continuation.parquet",
        "endstop-response.svg",
        "endstop-response.png",
        "summary.json",
        "numbers.md",
    ] {
        assert!(out.join(f).exists(), "missing {f}");
    }
    let sweeps = read_parquet(&out.join("sweeps.parquet"));
    assert_eq!(sweeps.height(), 2 * 12, "a steady state at every frequency");

    // The continued branch, in its order: one branch whose frequency turns back twice (its
    // folds), unstable between the turns and stable elsewhere.
    let df = read_parquet(&out.join("continuation.parquet"));
    let col_f64 = |name: &str| -> Vec<f64> {
        let c = df.column(name).unwrap().f64().unwrap();
        c.into_no_null_iter().collect()
    };
    let freq = col_f64("freq_hz");
    let stable: Vec<bool> = df
        .column("stable")
        .unwrap()
        .bool()
        .unwrap()
        .into_no_null_iter()
        .collect();
    let branches: Vec<u32> = df
        .column("branch")
        .unwrap()
        .u32()
        .unwrap()
        .into_no_null_iter()
        .collect();
    assert!(branches.iter().all(|b| *b == 0), "one branch: {branches:?}");
    let turns: Vec<f64> = freq
        .windows(3)
        .filter(|w| (w[1] - w[0]) * (w[2] - w[1]) < 0.0)
        .map(|w| w[1])
        .collect();
    assert_eq!(turns.len(), 2, "two folds: {turns:?}");
    let (lo, hi) = (turns[0].min(turns[1]), turns[0].max(turns[1]));
    let unstable: Vec<f64> = freq
        .iter()
        .zip(&stable)
        .filter(|(_, s)| !**s)
        .map(|(f, _)| *f)
        .collect();
    assert!(unstable.len() >= 3, "an unstable stretch: {unstable:?}");
    // The unstable stretch lies between the folds (the turning points are the branch's points
    // nearest each fold, whose multiplier is within a step of 1: either side).
    let step = freq
        .windows(2)
        .map(|w| (w[1] - w[0]).abs())
        .fold(0.0, f64::max);
    for f in &unstable {
        assert!(
            *f > lo - step && *f < hi + step,
            "{f} Hz outside {lo}-{hi} Hz"
        );
    }
    // Stable on either side: below the lower fold and above the upper one.
    for (f, s) in freq.iter().zip(&stable) {
        if *f < lo - step || *f > hi + step {
            assert!(*s, "unstable at {f} Hz, outside the folds {lo}-{hi} Hz");
        }
    }
    let _ = std::fs::remove_dir_all(out);
}

fn example(name: &str) -> String {
    format!("{}/../data/examples/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// A noise ensemble behind the bridge: one row per record, the summary's means are the rows'
/// means, every record's energy ledger closes and most sample intervals are propagated
/// exactly. The ledger bound, 1e-9 of the sum of its terms: the exact steps close it to
/// rounding (about 1e-13 seen), and the intervals handed to Dormand-Prince (about 1 %) at
/// rtol 1e-7 carry about 1 % of the energy, so about 1e-9 at most.
#[test]
fn random_with_an_interface_reports_each_records_dc_power_and_ledger() {
    let out = std::env::temp_dir().join(format!(
        "endstop-cli-{}-interface-random",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&out);
    let o = Command::new(BIN)
        .args(["random", "--device", &example("piezo_bridge.toml")])
        .args([
            "--psd",
            "1e-4",
            "--records",
            "3",
            "--duration-s",
            "2",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rec = read_parquet(&out.join("records.parquet"));
    assert_eq!(rec.height(), 3);
    let col = |name: &str| -> Vec<f64> {
        rec.column(name)
            .unwrap()
            .cast(&polars::prelude::DataType::Float64)
            .unwrap()
            .f64()
            .unwrap()
            .into_no_null_iter()
            .collect()
    };
    let (p_dc, p_drive) = (col("p_dc_w"), col("p_drive_w"));
    for (dc, drive) in p_dc.iter().zip(&p_drive) {
        assert!(*dc > 0.0 && dc < drive, "{dc} of {drive}");
    }
    for r in col("ledger_relative_residual") {
        assert!(r.abs() < 1e-9, "ledger residual {r}");
    }
    let (exact, steps) = (col("exact_steps"), col("steps"));
    for (e, s) in exact.iter().zip(&steps) {
        assert!(*e > 0.9 * s, "{e} exact of {s}");
    }
    let text = std::fs::read_to_string(out.join("summary.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let mean = p_dc.iter().sum::<f64>() / 3.0;
    let reported = v["numbers"]["p_dc_w"].as_f64().unwrap();
    assert!(
        (reported - mean).abs() <= 1e-12 * mean,
        "{reported} vs {mean}"
    );
}

/// A storage feeding nothing has no steady mean under noise: a named error, nothing written.
#[test]
fn random_with_an_open_dc_load_is_refused_and_writes_nothing() {
    let dir = std::env::temp_dir().join(format!("endstop-cli-{}-open-load", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(example("piezo_bridge.toml")).unwrap();
    let i = text.find("[interface.load]").unwrap();
    let device = dir.join("open.toml");
    std::fs::write(
        &device,
        format!("{}[interface.load]\nkind = \"open\"\n", &text[..i]),
    )
    .unwrap();
    let out = dir.join("out");
    let o = Command::new(BIN)
        .args(["random", "--device"])
        .arg(&device)
        .args([
            "--psd",
            "1e-4",
            "--records",
            "1",
            "--duration-s",
            "1",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("open load"), "{err}");
    assert!(!out.exists(), "nothing written");
}

/// Bad charging options are refused before anything runs, each naming its option: a target
/// that is no number or not above the start, a run of more than 1e7 drive periods, a negative
/// value read as a number (not as an unknown option); a negative noise level likewise.
#[test]
fn bad_charge_and_noise_options_are_named_before_running() {
    let out = std::env::temp_dir().join(format!("endstop-cli-{}-bad-charge", std::process::id()));
    let device = example("piezo_bridge.toml");
    let base = ["--freq-hz", "120", "--accel-rms-g", "0.3"];
    for (extra, names) in [
        (vec!["--target-v", "nan"], "--target-v"),
        (vec!["--target-v", "-1"], "--target-v"),
        (vec!["--start-v", "2", "--target-v", "1"], "--start-v"),
        (vec!["--target-v", "1", "--t-max-s", "1e9"], "--t-max-s"),
    ] {
        let o = Command::new(BIN)
            .args(["charge", "--device", &device])
            .args(base)
            .args(&extra)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{extra:?} accepted");
        assert!(err.contains(names), "{extra:?}: {err}");
        assert!(!out.exists(), "{extra:?}: something written");
    }
    let o = Command::new(BIN)
        .args(["random", "--device", &device, "--psd", "-1e-3", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("--psd"), "{err}");
}

/// A drive that presses the mass through its stops (1e6 g on the example cantilever, whose
/// linear stop is 0.1 mm away) is named, on stderr and in the run's numbers.
#[test]
fn an_implausible_drive_is_named() {
    let out = std::env::temp_dir().join(format!("endstop-cli-{}-implausible", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let o = Command::new(BIN)
        .args(["sweep", "--device", &example("piezo_cantilever.toml")])
        .args([
            "--from",
            "100",
            "--to",
            "101",
            "--step",
            "1",
            "--steps-at-once",
        ])
        .args(["--accel-rms-g", "1e6", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("times the largest stop gap"), "{err}");
    let md = std::fs::read_to_string(out.join("numbers.md")).unwrap();
    assert!(md.contains("**warning**"), "{md}");
    let _ = std::fs::remove_dir_all(out);
}

/// The switched interfaces behind the electromagnetic example (`em_bridge.toml`, its bridge
/// replaced): parallel and series SSHI and SECE, with and without its inductor, switch on a
/// piezoelectric element's clamped capacitance, which a coil does not have, so they are
/// refused, naming the interface and the transducer, by `sweep` on a device file and by
/// `design` among its `--interfaces`, and nothing is written.
#[test]
fn switched_interfaces_behind_a_coil_are_refused_naming_the_parts() {
    let dir = std::env::temp_dir().join(format!("endstop-cli-{}-em-switch", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(example("em_bridge.toml")).unwrap();
    let head = &text[..text.find("[interface]").unwrap()];
    let load = "[interface.load]\nkind = \"resistor\"\nresistance_ohm = 100e3\n";
    let diode =
        "[interface.diode]\nlaw = \"piecewise_linear\"\nforward_drop_v = 0.2\non_resistance_ohm = 0.0\n";
    let cases = [
        ("parallel_sshi", format!("inversion_factor = 0.8\n{diode}")),
        ("series_sshi", format!("inversion_factor = 0.8\n{diode}")),
        ("sece", "efficiency = 0.8\n".to_string()),
        (
            "sece",
            "inductance_h = 1e-3\ninductor_resistance_ohm = 10.0\nflyback_drop_v = 0.2\n"
                .to_string(),
        ),
    ];
    let refused = |args: &[&str], out: &Path, kind: &str| {
        let o = Command::new(BIN)
            .args(args)
            .arg("--out")
            .arg(out)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(1), "{kind} is refused");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.contains(&format!(
                "interface kind `{kind}` takes a piezoelectric transducer"
            )) && err.contains("an electromagnetic transducer takes `resistive` or `full_bridge`"),
            "{err}"
        );
        assert!(!out.exists(), "nothing written for {kind}");
    };
    for (n, (kind, keys)) in cases.iter().enumerate() {
        let table = format!("kind = \"{kind}\"\nstorage_capacitance_f = 10e-6\n{keys}{load}");
        let device = dir.join(format!("em_{n}.toml"));
        std::fs::write(&device, format!("{head}[interface]\n{table}")).unwrap();
        let device = device.to_str().unwrap();
        let sweep = [
            "sweep",
            "--device",
            device,
            "--from",
            "45",
            "--to",
            "55",
            "--step",
            "1",
            "--accel-rms-g",
            "0.2",
        ];
        refused(&sweep, &dir.join(format!("sweep_{n}")), kind);
        let interfaces = dir.join(format!("interfaces_{n}.toml"));
        std::fs::write(&interfaces, format!("[[interface]]\n{table}")).unwrap();
        let design = [
            "design",
            "--device",
            &example("em_bridge.toml"),
            "--range",
            "load.resistance_ohm=1e3..1e5",
            "--freq-hz",
            "50",
            "--accel-rms-g",
            "0.2",
            "--interfaces",
            interfaces.to_str().unwrap(),
        ];
        refused(&design, &dir.join(format!("design_{n}")), kind);
    }
    let _ = std::fs::remove_dir_all(&dir);
}
