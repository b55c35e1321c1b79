//! Figure 8 (the edge; the figure itself is `endstop::paper::figures::fig08`): prototype 1 at 30 V,
//! up-sweeps at 4.1 and 5.5 g rms under the published and the calibrated parameter set (read
//! from the calibration artefact), the paper's fit of b_im and the convergence repetition.
//! Writes the per-step sweeps, the convergence and the b_im fits as Parquet, the two plots and
//! the book's tables.

use endstop_experiments as common;

use anyhow::Result;
use common::reports::fig08_io;
use common::Experiment;
use endstop::paper::claims::Claims;
use endstop::paper::figures::fig08::Fig08;
use endstop::paper::Figure;

fn main() {
    common::run_main(Fig08::NAME, run);
}

fn run() -> Result<()> {
    let mut exp = Experiment::start(Fig08::NAME);
    let (p1, cal) = common::prototype1_both_sets(&mut exp)?;
    let claims = Claims::bundled()?;
    let (run, values) = exp.run_figure::<Fig08>(&p1, &claims)?;
    fig08_io::write(exp, &cal.record, &run, &values, &claims)
}
