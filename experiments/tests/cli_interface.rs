//! `endstop response` on a device with an interface circuit (the example cantilever with a
//! stop behind a full bridge, `data/examples/piezo_bridge.toml`): it writes the sweeps and the
//! continued branch, and the branch turns at two folds with an unstable stretch between them.

use std::path::Path;
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_endstop");

fn read_parquet(path: &Path) -> polars::prelude::DataFrame {
    use polars::prelude::*;
    let f = std::fs::File::open(path).unwrap();
    ParquetReader::new(f).finish().unwrap()
}

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

    let text = std::fs::read_to_string(out.join("summary.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let fold = |i: usize| v["numbers"][format!("fold_{i}_hz")].as_f64();
    let (a, b) = (
        fold(0).expect("a first fold"),
        fold(1).expect("a second fold"),
    );
    assert!(fold(2).is_none(), "two folds only");
    let (lo, hi) = (a.min(b), a.max(b));

    let df = read_parquet(&out.join("continuation.parquet"));
    let freq: Vec<f64> = df
        .column("freq_hz")
        .unwrap()
        .f64()
        .unwrap()
        .into_no_null_iter()
        .collect();
    let stable: Vec<bool> = df
        .column("stable")
        .unwrap()
        .bool()
        .unwrap()
        .into_no_null_iter()
        .collect();
    let segment: Vec<u32> = df
        .column("branch")
        .unwrap()
        .u32()
        .unwrap()
        .into_no_null_iter()
        .collect();
    // Stable, unstable, stable: three stretches along the branch, the middle one unstable.
    assert_eq!(
        segment.last(),
        Some(&2),
        "three stretches of equal stability"
    );
    let unstable: Vec<f64> = freq
        .iter()
        .zip(&stable)
        .filter(|(_, s)| !**s)
        .map(|(f, _)| *f)
        .collect();
    assert!(unstable.len() >= 3, "an unstable stretch: {unstable:?}");
    for (f, (s, k)) in freq.iter().zip(stable.iter().zip(&segment)) {
        assert_eq!(*s, *k != 1, "stretch {k} at {f} Hz");
    }
    // The unstable stretch lies between the folds (a point within 1e-6 Hz of a fold, where its
    // multiplier is within its step of 1, may fall either side).
    for f in &unstable {
        assert!(
            *f > lo - 1e-6 && *f < hi + 1e-6,
            "{f} Hz outside {lo}-{hi} Hz"
        );
    }
    let _ = std::fs::remove_dir_all(out);
}
