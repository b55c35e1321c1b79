//! Figure 10: the random excitation at the paper's example level Sa = 1e-2 g²/Hz and its
//! Welch PSD against the target (claim F10: level and band). The figure is stated in
//! `endstop::paper::figures::fig10`; this binary writes its outputs.

use endstop_experiments as common;

use anyhow::Result;
use common::reports::fig10_io;
use common::Experiment;
use endstop::paper::claims::Claims;
use endstop::paper::figures::fig10::Fig10;
use endstop::paper::Figure;

fn main() {
    common::run_main(Fig10::NAME, run);
}

fn run() -> Result<()> {
    let mut exp = Experiment::start(Fig10::NAME);
    let claims = Claims::bundled()?;
    let (run, _) = exp.run_figure::<Fig10>(&(), &claims)?;
    fig10_io::write(exp, &run, &claims)
}
