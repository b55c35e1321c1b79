//! Figure 11: output power PSDs of prototype 1 at 30 V at the low levels 4.42e-6, 1.12e-4 and
//! 3.49e-4 g²/Hz under the published and the calibrated parameter sets (claim F11). The
//! figure is stated in `endstop::paper::figures::fig11`; this binary writes its outputs.

use endstop_experiments as common;

use anyhow::Result;
use common::reports::{fig11_io, record_io};
use common::Experiment;
use endstop::paper::claims::Claims;
use endstop::paper::figures::fig11::Fig11;
use endstop::paper::Figure;
use endstop::study::ensemble::DEFAULT_SEED;

fn main() {
    common::run_main(Fig11::NAME, run);
}

fn run() -> Result<()> {
    let mut exp = Experiment::start(Fig11::NAME);
    exp.seed = Some(DEFAULT_SEED);
    let claims = Claims::bundled()?;
    let sets = record_io::prototype1_sets(&mut exp)?;
    let (run, _) = exp.run_figure::<Fig11>(&sets, &claims)?;
    fig11_io::write(exp, &run)
}
