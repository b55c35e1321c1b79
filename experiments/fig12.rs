//! Figure 12: output power PSDs of prototype 1 at 30 V at 7.4e-3, 1.31e-2 and 2.85e-2 g²/Hz,
//! where the mass hits the stops, under the published and the calibrated parameter sets
//! (claim F12). The figure is stated in `endstop::paper::figures::fig12`; this binary writes its
//! outputs.

use endstop_experiments as common;

use anyhow::Result;
use common::reports::{fig12_io, record_io};
use common::Experiment;
use endstop::paper::claims::Claims;
use endstop::paper::figures::fig12::Fig12;
use endstop::paper::resolution::{self, LEVELS};
use endstop::paper::Figure;
use endstop::study::ensemble::DEFAULT_SEED;

fn main() {
    common::run_main(Fig12::NAME, run);
}

fn run() -> Result<()> {
    let mut exp = Experiment::start(Fig12::NAME);
    exp.seed = Some(DEFAULT_SEED);
    let claims = Claims::bundled()?;
    let sets = record_io::prototype1_sets(&mut exp)?;
    let (run, _) = exp.run_figure::<Fig12>(&sets, &claims)?;
    // The width against the Welch segment length, on the published set.
    let total = LEVELS.len() * resolution::RECORDS;
    let study = common::with_progress(total, "fig12 widths vs nperseg", |tick| {
        resolution::run(&sets.published, resolution::RECORDS, tick)
    })?;
    fig12_io::write(exp, &run, &study)
}
