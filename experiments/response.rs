//! The whole response curve (the edge; the study itself is `endstop::paper::response`):
//! Figure 13's prototype 2 and Figure 8's prototype 1 (published and calibrated), with the
//! continued periodic orbits and their stability, the up- and down-sweeps, folds and grazing
//! points, the Floquet multipliers of the coexisting orbits in the hysteresis band and the
//! basins of attraction there. Writes `continuation.parquet`, `sweeps.parquet`,
//! `basins.parquet`, the plots and the book's tables.

use endstop_experiments as common;

use anyhow::Result;
use common::reports::response_io;
use common::Experiment;
use endstop::paper::response::{self, BASIN_CELLS};

fn main() {
    common::run_main("response", run);
}

fn run() -> Result<()> {
    let mut exp = Experiment::start("response");
    let p2 = exp.load_published("prototype2")?;
    let (p1, _) = common::prototype1_both_sets(&mut exp)?;
    let setups = response::setups(&p2.device, &p1.published, &p1.calibrated);
    let units = response::work_units(&setups, BASIN_CELLS);
    let run = common::with_progress(units, "response", |tick| {
        response::run(&setups, BASIN_CELLS, tick)
    })?;
    // The basins again on a grid twice as fine, for their convergence.
    let mut fine_shift = Vec::new();
    for c in &run.cases {
        if let Some(conv) = response::basin_convergence(c, BASIN_CELLS)? {
            fine_shift.push((c.setup.case, conv.largest_share_change));
        }
    }
    // The folds beside the scorecard's jump claims of Figure 8 (continuation only).
    let claim_folds = response::claim_folds(&p1)?;
    response_io::write(exp, &run, &fine_shift, &claim_folds)
}
