//! Figure 14: output power and efficiency 2P/(m Sa) of prototype 2 at 15 V against the
//! acceleration PSD, with the linear theory of eq 21 (claims F14-a, F14-b). The figure is
//! stated in `endstop::paper::figures::fig14`; this binary writes its outputs, and Figure 15's,
//! whose records are among its ensembles (`endstop::paper::prototype2_records`).

use endstop_experiments as common;

use anyhow::{Context, Result};
use common::reports::fig14_io;
use common::Experiment;
use endstop::paper::claims::Claims;
use endstop::paper::figures::fig14::{Fig14, Setup};
use endstop::paper::figures::fig15::{self, Fig15};
use endstop::paper::prototype2_records::Extras;
use endstop::paper::Figure;
use endstop::study::ensemble::DEFAULT_SEED;

fn main() {
    common::run_main(Fig14::NAME, run);
}

fn run() -> Result<()> {
    let mut exp = Experiment::start(Fig14::NAME);
    exp.seed = Some(DEFAULT_SEED);
    let claims = Claims::bundled()?;
    let p2 = exp.load_published("prototype2")?;
    let setup = Setup {
        prototype2: p2.device.clone(),
        extras: Extras::FULL,
    };
    let (run, _) = exp.run_figure::<Fig14>(&setup, &claims)?;
    fig14_io::write(exp, &run, &claims)?;
    // Figure 15's records are among these ensembles: its outputs come from the same run.
    let fig15 = fig15::Run::of(&run).context("Figure 14's run lacks a level of Figure 15")?;
    common::reports::fig15_io::write(Experiment::start(Fig15::NAME), &p2, &fig15, &claims)
}
