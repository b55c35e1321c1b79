//! The calibrated prototype 1 as an artefact, computed once and read by every experiment that
//! uses the calibrated set (Figures 8, 9, 11 and 12, the benchmark):
//!
//! * `<results>/calibration/prototype1_calibrated.toml`: a device file
//!   (`Device::from_toml_str` loads it) whose leading `#` comments give its provenance (the
//!   commit, the SHA-256 of the published `prototype1.toml` text it was fitted from, the target
//!   and the achieved onset);
//! * `<results>/calibration/summary.json`: the calibration's record
//!   ([`CalibrationRecord`]) with the same provenance.
//!
//! The `calibrate` experiment writes both (and `reproduce` runs it before every other job);
//! [`calibrated_prototype1`] reads them, and recomputes and rewrites them only when they are
//! missing, unreadable, or were fitted from another `prototype1.toml` text.

use std::path::PathBuf;

use anyhow::{Context, Result};
use endstop::paper::calibration::{
    calibrate_prototype1, calibrated_device, Calibration, CalibrationRecord,
};
use endstop::paper::setups::{ParamSet, Prototype1Sets};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use crate::{git_commit, results_root, write_atomic, Experiment, LoadedDevice};

/// The directory of the artefact under the results root.
pub const CALIBRATION_DIR: &str = "calibration";

/// The calibrated device file in [`CALIBRATION_DIR`].
pub const DEVICE_FILE: &str = "prototype1_calibrated.toml";

/// The comment line of the device file that names the text it was fitted from.
const SHA_PREFIX: &str = "# fitted_from_sha256: ";

/// `<results>/calibration/` (`data/results/calibration/` unless `ENDSTOP_OUTPUT_DIR` is set).
pub fn calibration_dir() -> PathBuf {
    results_root().join(CALIBRATION_DIR)
}

/// How the device file is named in provenance records: its path relative to the project root,
/// or under `$ENDSTOP_OUTPUT_DIR` when that is set (never a temporary directory's name, so
/// that outputs stay byte-identical between runs).
fn device_label() -> String {
    match std::env::var_os("ENDSTOP_OUTPUT_DIR") {
        Some(_) => format!("$ENDSTOP_OUTPUT_DIR/{CALIBRATION_DIR}/{DEVICE_FILE}"),
        None => format!("data/results/{CALIBRATION_DIR}/{DEVICE_FILE}"),
    }
}

/// SHA-256 of a text, in hex.
pub fn sha256_hex(text: &str) -> String {
    format!("{:x}", Sha256::digest(text.as_bytes()))
}

/// `summary.json` of the calibration.
#[derive(Debug, Serialize, Deserialize)]
struct Summary {
    experiment: String,
    commit: String,
    crate_version: String,
    /// (file, set) of the parameter files used, as in every experiment's summary.
    params: Vec<(String, String)>,
    fitted_from: String,
    fitted_from_sha256: String,
    #[serde(flatten)]
    record: CalibrationRecord,
}

/// The device file's text: provenance comments, then the calibrated device.
fn device_text(published: &LoadedDevice, cal: &Calibration, sha: &str) -> String {
    format!(
        "# Prototype 1 with its end-stop gap calibrated to the measured impact onset of Figure 8\n\
         # (endstop::paper::calibration::calibrate_prototype1), written by the `calibrate`\n\
         # experiment and read by every experiment of the calibrated set. Do not edit: it is\n\
         # rewritten whenever it is missing or was fitted from another prototype1.toml text.\n\
         # commit: {}\n\
         # fitted_from: {}\n\
         {SHA_PREFIX}{sha}\n\
         # target_onset_hz: {}\n\
         # achieved_onset_hz: {}\n\
         # fitted_gap_m: {:e} (published: {:e})\n\n{}",
        git_commit(),
        published.file,
        cal.record.target_onset_hz,
        cal.record.achieved_onset_hz,
        cal.record.fitted_gap_m,
        cal.record.published_gap_m,
        cal.device.to_toml_string()
    )
}

/// Writes the artefact of `cal`, fitted from `published` (summary first, the device file
/// last, each atomically), and returns the calibrated device as loaded from it.
pub fn write_calibration(published: &LoadedDevice, cal: &Calibration) -> Result<LoadedDevice> {
    let dir = calibration_dir();
    let sha = sha256_hex(&published.text);
    let summary = Summary {
        experiment: "calibrate".into(),
        commit: git_commit(),
        crate_version: env!("CARGO_PKG_VERSION").into(),
        params: vec![(published.file.clone(), ParamSet::Published.label().into())],
        fitted_from: published.file.clone(),
        fitted_from_sha256: sha.clone(),
        record: cal.record,
    };
    write_atomic(
        &dir.join("summary.json"),
        serde_json::to_string_pretty(&summary)?.as_bytes(),
    )?;
    let text = device_text(published, cal, &sha);
    write_atomic(&dir.join(DEVICE_FILE), text.as_bytes())?;
    Ok(LoadedDevice {
        device: cal.device.clone(),
        file: device_label(),
        text,
    })
}

/// Reads the artefact if it holds the calibration of exactly this published text; the error
/// says why not.
fn read_calibration(published: &LoadedDevice) -> Result<(LoadedDevice, Calibration)> {
    let dir = calibration_dir();
    let path = dir.join(DEVICE_FILE);
    let text =
        std::fs::read_to_string(&path).with_context(|| format!("{} is missing", path.display()))?;
    let sha = sha256_hex(&published.text);
    let fitted_from = text
        .lines()
        .find_map(|l| l.strip_prefix(SHA_PREFIX))
        .with_context(|| format!("{} does not say what it was fitted from", path.display()))?;
    anyhow::ensure!(
        fitted_from.trim() == sha,
        "{} was fitted from another {} text",
        path.display(),
        published.file
    );
    let summary_path = dir.join("summary.json");
    let summary: Summary = serde_json::from_str(
        &std::fs::read_to_string(&summary_path)
            .with_context(|| format!("{} is missing", summary_path.display()))?,
    )
    .with_context(|| format!("{} is unreadable", summary_path.display()))?;
    anyhow::ensure!(
        summary.fitted_from_sha256 == sha,
        "{} was fitted from another {} text",
        summary_path.display(),
        published.file
    );
    let label = device_label();
    let device = endstop::device::Device::from_toml_str(&text, &label)?;
    anyhow::ensure!(
        device == calibrated_device(&published.device, summary.record.fitted_gap_m),
        "{} is not the published device with the gap of {}",
        path.display(),
        summary_path.display()
    );
    let cal = Calibration {
        device: device.clone(),
        record: summary.record,
    };
    Ok((
        LoadedDevice {
            device,
            file: label,
            text,
        },
        cal,
    ))
}

/// The calibrated prototype 1 for the published set `published`: the device as a loaded
/// parameter set (for provenance: its file is the artefact) and the calibration's record. Read
/// from the artefact written by the `calibrate` experiment; recomputed and rewritten (with a
/// message on stderr) only when the artefact is missing, unreadable, or was fitted from another
/// text of `published`.
pub fn calibrated_prototype1(published: &LoadedDevice) -> Result<(LoadedDevice, Calibration)> {
    match read_calibration(published) {
        Ok(found) => Ok(found),
        Err(why) => {
            eprintln!(
                "[calibration] {why:#}: calibrating prototype 1 and writing {}",
                calibration_dir().display()
            );
            let cal = calibrate_prototype1(&published.device)?;
            let loaded = write_calibration(published, &cal)?;
            Ok((loaded, cal))
        }
    }
}

/// Prototype 1 under both parameter sets, for an experiment that runs both: the published
/// `prototype1.toml` as loaded and its calibration ([`calibrated_prototype1`]), with both
/// parameter files recorded on `exp` (published, then calibrated: the artefact's device file
/// with its own text).
pub fn prototype1_both_sets(exp: &mut Experiment) -> Result<(Prototype1Sets, Calibration)> {
    let published = exp.load_published("prototype1")?;
    let (calibrated, cal) = calibrated_prototype1(&published)?;
    exp.uses(&calibrated, ParamSet::Calibrated.label());
    let sets = Prototype1Sets {
        published: published.device,
        calibrated: cal.device.clone(),
    };
    Ok((sets, cal))
}
