//! Figure 9 (the edge; the figure itself is `endstop::paper::figures::fig09`): prototype 1 at 1220 Hz,
//! output power against RMS acceleration for 20, 30 and 40 V, under the published and the
//! calibrated parameter set (read from the calibration artefact), with both readings of
//! "output power" and the convergence repetition. Writes the continuations as Parquet, the
//! plot and the book's tables.

use endstop_experiments as common;

use anyhow::Result;
use common::reports::fig09_io;
use common::Experiment;
use endstop::paper::claims::Claims;
use endstop::paper::figures::fig09::{self, Fig09, PowerReading};
use endstop::paper::Figure;

fn main() {
    common::run_main(Fig09::NAME, run);
}

fn run() -> Result<()> {
    let mut exp = Experiment::start(Fig09::NAME);
    let (p1, cal) = common::prototype1_both_sets(&mut exp)?;
    let claims = Claims::bundled()?;
    let (run, values) = exp.run_figure::<Fig09>(&p1, &claims)?;
    let both_loads = fig09::claims_under(&run, PowerReading::BothLoads, &claims)?;

    fig09_io::write(exp, &cal.record, &run, &values, &both_loads, &claims)
}
