//! From the harvester to the battery: the example devices `data/examples/piezo_bridge.toml`
//! (a piezoelectric cantilever with a stop) and `data/examples/em_bridge.toml` (an
//! electromagnetic harvester with stops) behind each interface circuit. Writes the DC power
//! against the load for every interface, the DC power against frequency with each steady
//! state's stability, random ensembles, a charging curve and the energy ledger of each
//! interface, as Parquet, plots and the chapter's generated tables
//! (`book/src/generated/interfaces/`); the run and its report are
//! `endstop_experiments::reports::interfaces_io`. The cost of a record behind an interface
//! against the resistive load is measured by the benchmark (`bench`,
//! `experiments/bench/interfaces.rs`).

use endstop_experiments as common;

fn main() {
    common::run_main("interfaces", common::reports::interfaces_io::run);
}
