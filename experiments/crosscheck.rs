//! Cross-check with ngspice (the edge; the comparison itself is `endstop::paper::crosscheck`,
//! the run and its report `endstop_experiments::reports::crosscheck_io`): for every case and
//! ngspice setting, writes the netlist, takes ngspice's numbers for it (from the recording
//! `data/recorded/ngspice/crosscheck.json` where it holds that netlist, else from a run of
//! ngspice in batch mode; `--fresh-ngspice` runs ngspice for every netlist and checks the
//! recording, `--record-ngspice` rewrites it) and has the paper layer judge them against our
//! integrator; writes the table, the portable netlists, the plot and the book's numbers. The
//! run fails (non-zero exit) if a netlist has neither a recording nor ngspice to run it, if a
//! fresh run disagrees with the recording, or if the documented settings miss the acceptance
//! tolerances (0.1 % without impacts, 1 % with impacts).

use endstop_experiments as common;

fn main() {
    common::run_main("crosscheck", common::reports::crosscheck_io::run);
}
