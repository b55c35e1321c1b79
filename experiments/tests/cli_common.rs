//! Helpers the command-line tests share: the `endstop` program run with arguments, and a
//! Parquet output read back.

use std::path::Path;
use std::process::Command;

/// The `endstop` program built for these tests.
pub const BIN: &str = env!("CARGO_BIN_EXE_endstop");

/// Runs `endstop` with `args` and returns its output (status, stdout, stderr).
pub fn run(args: &[&str]) -> std::process::Output {
    Command::new(BIN).args(args).output().unwrap()
}

/// The Parquet file at `path` as a data frame.
pub fn read_parquet(path: &Path) -> polars::prelude::DataFrame {
    use polars::prelude::*;
    ParquetReader::new(std::fs::File::open(path).unwrap())
        .finish()
        .unwrap()
}
