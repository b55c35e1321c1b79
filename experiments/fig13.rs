//! Figure 13 (the edge; the figure itself is `endstop::paper::figures::fig13`): prototype 2 at 10 V,
//! up-sweeps at 0.12 and 0.31 g rms with the linear and the Hertz end-stop law, published
//! parameters, with the convergence repetition and the cost of the sweeps. Writes the
//! per-step sweeps as Parquet, the plot and the book's tables.

use endstop_experiments as common;

use anyhow::Result;
use common::reports::fig13_io;
use common::Experiment;
use endstop::paper::claims::Claims;
use endstop::paper::figures::fig13::Fig13;
use endstop::paper::Figure;

fn main() {
    common::run_main(Fig13::NAME, run);
}

fn run() -> Result<()> {
    let mut exp = Experiment::start(Fig13::NAME);
    let p2 = exp.load_published("prototype2")?;
    let claims = Claims::bundled()?;
    let (run, values) = exp.run_figure::<Fig13>(&p2.device, &claims)?;
    fig13_io::write(exp, &run, &values, &claims)
}
