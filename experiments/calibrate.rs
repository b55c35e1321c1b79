//! `calibrate`: fits the end-stop gap of prototype 1 to the measured impact onset of Figure 8
//! (`endstop::paper::calibration::calibrate_prototype1`) and saves the calibrated device and
//! the calibration's record as the artefact every experiment of the calibrated set reads
//! (`data/results/calibration/`, see `endstop_experiments::reports::calibration_io`). `reproduce` runs it
//! before every other job.

use endstop_experiments as common;

use std::time::Instant;

use anyhow::Result;
use common::reports::calibration_io::{calibration_dir, write_calibration};
use common::{fmt_sig, git_commit, load_device, write_atomic};
use endstop::paper::calibration::calibrate_prototype1;

fn main() {
    common::run_main("calibrate", run);
}

fn run() -> Result<()> {
    let started = Instant::now();
    eprintln!("[calibrate] running (commit {})", git_commit());
    let p1 = load_device("prototype1")?;
    let cal = calibrate_prototype1(&p1.device)?;
    write_calibration(&p1, &cal)?;
    let secs = started.elapsed().as_secs_f64();
    let timing = serde_json::json!({
        "experiment": "calibrate",
        "wall_time_s": secs,
        "cpu_time_s": common::cpu_time_s(),
    });
    write_atomic(
        &calibration_dir().join("timing.json"),
        serde_json::to_string_pretty(&timing)?.as_bytes(),
    )?;
    eprintln!(
        "[calibrate] end-stop gap {} um (published {} um), onset {} Hz (target {} Hz), {} \
         evaluations; wrote {} ({secs:.2} s)",
        fmt_sig(cal.record.fitted_gap_m * 1e6, 5),
        fmt_sig(cal.record.published_gap_m * 1e6, 4),
        fmt_sig(cal.record.achieved_onset_hz, 6),
        cal.record.target_onset_hz,
        cal.record.evaluations,
        calibration_dir().display()
    );
    Ok(())
}
