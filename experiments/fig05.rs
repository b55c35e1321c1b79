//! Figure 5: the Hertz line-contact law (eq 6) in normalised form, delta0 for both prototypes
//! (claim F5-a), and the linear end-stop stiffness of eq 19 (claim F5-b). The figure is
//! stated in `endstop::paper::figures::fig05`; this binary writes its outputs.

use endstop_experiments as common;

use anyhow::Result;
use common::reports::fig05_io;
use common::Experiment;
use endstop::paper::claims::Claims;
use endstop::paper::figures::fig05::Fig05;
use endstop::paper::setups::Prototypes;
use endstop::paper::Figure;

fn main() {
    common::run_main(Fig05::NAME, run);
}

fn run() -> Result<()> {
    let mut exp = Experiment::start(Fig05::NAME);
    let claims = Claims::bundled()?;
    let setup = Prototypes {
        prototype1: exp.load_published("prototype1")?.device,
        prototype2: exp.load_published("prototype2")?.device,
    };
    let (run, _) = exp.run_figure::<Fig05>(&setup, &claims)?;
    fig05_io::write(exp, &run, &claims)
}
