//! Validation against references: runs every check of `endstop::validation` with the cases of
//! `endstop::validation::cases` (the ones `tests/validation.rs` asserts), and writes the checks
//! and their data as Parquet, two plots, and the book chapter's generated tables
//! (`book/src/generated/validation/`). A check outside its tolerance is reported as such in the
//! tables (the tests fail on it); the run itself fails only when a check cannot be computed.
//! It reads the recorded band-limit study; `--band-study` runs that study instead and records it
//! (`common::reports::band_limit_io`). The run and its outputs are
//! `src/reports/validation_io/`.

use endstop_experiments as common;

use common::reports::{band_limit_io, validation_io};

fn main() {
    if std::env::args().skip(1).any(|a| a == "--band-study") {
        common::run_main("validation --band-study", band_limit_io::record_study);
    } else {
        common::run_main("validation", validation_io::run);
    }
}
