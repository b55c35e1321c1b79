//! Table 3: electromechanical coupling k^2, quality factor Qm and figure of merit k^2 Qm of
//! both prototypes (eqs 15-18), with the broadband efficiency of eq 21 (claims T3-a, T3-b,
//! F14-a's linear-theory value). The table is stated in `endstop::paper::figures::table3`; this binary
//! writes its outputs.

use endstop_experiments as common;

use anyhow::Result;
use common::reports::table3_io;
use common::Experiment;
use endstop::paper::claims::Claims;
use endstop::paper::figures::table3::Table3;
use endstop::paper::setups::Prototypes;
use endstop::paper::Figure;

fn main() {
    common::run_main(Table3::NAME, run);
}

fn run() -> Result<()> {
    let mut exp = Experiment::start(Table3::NAME);
    let claims = Claims::bundled()?;
    let setup = Prototypes {
        prototype1: exp.load_published("prototype1")?.device,
        prototype2: exp.load_published("prototype2")?.device,
    };
    let (run, _) = exp.run_figure::<Table3>(&setup, &claims)?;
    table3_io::write(exp, &run)
}
