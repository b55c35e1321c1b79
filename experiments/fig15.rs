//! Figure 15: output power PSDs of prototype 2 at 15 V at 0.34e-3, 0.55e-3 and 1.69e-3 g²/Hz
//! (claims F15-a, F15-b, F15-c), and the sampling distribution of the bandwidths and of their
//! ratio when each is read from one 10 s record. The figure is stated in
//! `endstop::paper::figures::fig15`; its outputs are written by `src/reports/fig15_io.rs`, which
//! Figure 14's binary calls too (its run holds the same records).

use endstop_experiments as common;

use anyhow::Result;
use endstop::paper::claims::Claims;
use endstop::paper::figures::fig15::{Fig15, Setup};
use endstop::paper::Figure;
use endstop_experiments::Experiment;

fn main() {
    common::run_main(Fig15::NAME, run);
}

fn run() -> Result<()> {
    let exp = Experiment::start(Fig15::NAME);
    let claims = Claims::bundled()?;
    let p2 = common::load_device("prototype2")?;
    let setup = Setup::new(p2.device.clone());
    let run = common::with_progress(Fig15::work(&setup), Fig15::NAME, |tick| {
        Fig15::run(&setup, tick)
    })?;
    common::reports::fig15_io::write(exp, &p2, &run, &claims)
}
