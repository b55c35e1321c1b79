//! `bench`: how fast the model runs, on fixed cases. Speed is measured here, never
//! asserted by a test.
//!
//! Usage: `cargo run --release --bin bench [-- --quick | --interfaces | --masses | --fits |
//! --floor]`
//! (`--floor` times the record engine against its floor kernel, `bench/floor.rs`; `--fits`
//! times every fit of the recovery family and Figure 8's on one thread and prints their
//! table, writing nothing, `--fit-only 13,20,fig8` some of them; `just bench` runs the
//! whole benchmark; `reproduce` runs `--quick`, which keeps its last phase short;
//! `--interfaces` measures the records behind an interface circuit alone and prints their
//! table, writing nothing; `--masses` measures the two-mass record against a one-mass record
//! of as many impacts alone and prints its table, writing nothing).
//!
//! * a 10 s prototype-1 record at Sa = 2.85e-2 g^2/Hz (heavy impacts; calibrated set, whose
//!   stops are closer, and published set), and a 10 s prototype-2 record at 1.69e-3;
//! * a steady impacting sine of prototype 1 (calibrated, 5.5 g at 1300 Hz): the share of
//!   integrator steps spent in contact;
//! * every example device of `data/examples/` (`bench/examples.rs`): its 10 s record, one
//!   periodic orbit and (not with `--quick`) its whole response over its file's range, with
//!   the ratio to a fixed-step RK4 at equal accuracy and to ngspice where it exports;
//! * the bistable example's 10 s record beside its linear twin's, paired;
//! * not with `--quick`: the up-converter's two-mass 10 s record against a one-mass record of
//!   as many impacts, paired (`bench/masses.rs`);
//! * not with `--quick`: a full Figure 8 sweep (every curve of the published set, one thread
//!   and all threads), Figure 13's whole curve by continuation and by sweeps, the paper
//!   records against RK4, and the untimed accuracy tables (`bench/accuracy.rs`;
//!   `tests/record_accuracy.rs` asserts what they show).
//!
//! Each timed case runs [`REPEATS`] times (once with `--quick`); the tables give the median
//! processor time (user and system, of every thread) beside the median and fastest wall time:
//! on a machine shared with other work the processor time is the steadier of the two. Results
//! go to `data/results/bench/` and the book's Performance page.

use endstop_experiments as common;

use anyhow::Result;
use clap::Parser;

#[path = "bench/accuracy.rs"]
mod accuracy;
#[path = "bench/cases.rs"]
mod cases;
#[path = "bench/examples.rs"]
mod examples;
#[path = "bench/fits.rs"]
mod fits;
#[path = "bench/floor.rs"]
mod floor;
#[path = "bench/floor_kernel.rs"]
mod floor_kernel;
#[path = "bench/interfaces.rs"]
mod interfaces;
#[path = "bench/masses.rs"]
mod masses;
#[path = "bench/report.rs"]
mod report;
#[path = "bench/rk4.rs"]
mod rk4;
#[path = "bench/timing.rs"]
mod timing;

/// Runs of each timed case (one with `--quick`).
pub const REPEATS: usize = 5;
/// Seed of every record.
pub const SEED: u64 = 2012;

#[derive(Parser, Debug)]
#[command(about = "How fast the model runs, on fixed cases")]
struct Args {
    /// Run each case once and leave out the sweeps, the continuation, the comparisons with
    /// RK4 and ngspice and the accuracy tables (as `reproduce` runs it).
    #[arg(long)]
    quick: bool,
    /// Measure the records behind an interface circuit alone and print their table, writing
    /// nothing.
    #[arg(long)]
    interfaces: bool,
    /// Measure a two-mass record against a one-mass record with as many impacts and print
    /// their table, writing nothing.
    #[arg(long)]
    masses: bool,
    /// Time the fits of the recovery family and of Figure 8, each on one thread, and print
    /// their table, writing nothing.
    #[arg(long)]
    fits: bool,
    /// Time the record engine against its floor kernel (a sine-driven oscillator between
    /// restitution stops, and prototype 2's noise record) and print their table, writing nothing.
    #[arg(long)]
    floor: bool,
    /// Runs of each fit with `--fits`.
    #[arg(long, default_value_t = 3)]
    fit_repeats: usize,
    /// With `--fits`, time only these fits: a family case by its number, Figure 8 as `fig8`
    /// (comma-separated; all when not given).
    #[arg(long, value_delimiter = ',')]
    fit_only: Vec<String>,
}

fn main() {
    common::run_main("bench", run);
}

fn run() -> Result<()> {
    let args = Args::parse();
    if args.fits {
        print!(
            "{}",
            fits::table(
                &fits::measure(args.fit_repeats, &args.fit_only)?,
                args.fit_repeats
            )
        );
        return Ok(());
    }
    if args.floor {
        print!("{}", floor::table(&floor::measure(REPEATS)?, REPEATS));
        return Ok(());
    }
    if args.masses {
        print!("{}", masses::table(&masses::measure(REPEATS)?, REPEATS));
        return Ok(());
    }
    if args.interfaces {
        print!(
            "{}",
            interfaces::table(&interfaces::measure(REPEATS)?, REPEATS)
        );
        return Ok(());
    }
    report::run(args.quick)
}
