//! The calibrated prototype 1 is computed once (`calibrate`) and read by its consumers: the
//! artefact is a loadable device file with its provenance, a consumer reads it without
//! recalibrating, and recalibrates (saying so on stderr) only when the artefact is missing or
//! was fitted from another `prototype1.toml` text. Outputs go to a temporary directory
//! (ENDSTOP_OUTPUT_DIR), never to data/results/.

use endstop::paper::setups::endstop;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use endstop::device::Device;
use endstop::paper::setups::ParamSet;

fn run(bin: &str, out: &Path) -> Output {
    let o = Command::new(bin)
        .env("ENDSTOP_OUTPUT_DIR", out)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "{bin} failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

fn recalibrated(o: &Output) -> bool {
    String::from_utf8_lossy(&o.stderr).contains("[calibration]")
}

fn artefact(out: &Path) -> PathBuf {
    out.join("calibration/prototype1_calibrated.toml")
}

#[test]
fn the_calibration_is_computed_once_and_recomputed_only_when_stale() {
    let out = std::env::temp_dir().join(format!("endstop-calibration-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    run(env!("CARGO_BIN_EXE_calibrate"), &out);

    // A device file with its provenance, loadable as any parameter file.
    let text = std::fs::read_to_string(artefact(&out)).unwrap();
    let published = include_str!("../../data/prototype1.toml");
    let sha = endstop_experiments::reports::calibration_io::sha256_hex(published);
    assert!(
        text.contains(&format!("# fitted_from_sha256: {sha}\n")),
        "{text}"
    );
    for key in ["# commit: ", "# target_onset_hz: ", "# achieved_onset_hz: "] {
        assert!(text.contains(key), "{key} missing:\n{text}");
    }
    let device = Device::from_toml_str(&text, "artefact").unwrap();
    assert_eq!(device.params, ParamSet::Calibrated.label());
    let summary: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out.join("calibration/summary.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(
        summary["fitted_gap_m"].as_f64(),
        Some(endstop(&device).gap_m)
    );
    assert!(summary["onset_bracket"]["before"].is_f64() && summary["evaluations"].is_u64());

    // A consumer reads it as it is.
    let fig09 = env!("CARGO_BIN_EXE_fig09");
    assert!(!recalibrated(&run(fig09, &out)));
    assert_eq!(std::fs::read_to_string(artefact(&out)).unwrap(), text);

    // Fitted from another text: recomputed, said on stderr, and rewritten as before.
    let other = text.replace(&sha, &"0".repeat(sha.len()));
    std::fs::write(artefact(&out), other).unwrap();
    assert!(recalibrated(&run(fig09, &out)));
    assert_eq!(std::fs::read_to_string(artefact(&out)).unwrap(), text);

    // Missing: recomputed.
    std::fs::remove_file(artefact(&out)).unwrap();
    assert!(recalibrated(&run(fig09, &out)));
    assert_eq!(std::fs::read_to_string(artefact(&out)).unwrap(), text);
    let _ = std::fs::remove_dir_all(&out);
}
