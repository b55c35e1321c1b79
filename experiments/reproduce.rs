//! `reproduce`: runs every experiment, joins the claims with our values into the scorecard,
//! writes the provenance table, and builds the book into `book/build/`.
//!
//! Usage: `cargo run --release --bin reproduce [-- --only fig08,fig09] [--book-only] [--jobs N]`.
//!
//! The experiments run as separate processes (the binaries next to this one, built first with
//! `cargo build --release --bins`), at most `--jobs` at a time; each one's log goes to
//! `data/results/<name>/log.txt`. A failed experiment makes `reproduce` exit non-zero after the
//! others have finished.

use endstop_experiments as common;

use anyhow::{bail, Result};
use clap::Parser;
use endstop_experiments::pipeline::jobs::{experiment_names, Job, JOBS};
use endstop_experiments::pipeline::{
    answers, book, provenance, publish, recorded_history, schedule, scorecard,
};

#[derive(Parser, Debug)]
#[command(about = "Run every experiment, write the scorecard and build the book")]
struct Args {
    /// Run only these experiments (comma separated), e.g. `--only fig08,fig13` (an experiment
    /// another job writes runs that job: `fig15` runs `fig14`).
    #[arg(long, value_delimiter = ',')]
    only: Vec<String>,
    /// Do not run experiments: rebuild the scorecard and the book from existing results.
    #[arg(long)]
    book_only: bool,
    /// How many experiments run at once (each also uses all cores internally).
    #[arg(long, default_value_t = 2)]
    jobs: usize,
    /// Do not call `cargo build` first (the binaries must already be built).
    #[arg(long)]
    no_build: bool,
    /// Rerun experiments even when their inputs are unchanged.
    #[arg(long)]
    force: bool,
}

fn main() {
    common::run_main("reproduce", run);
}

fn run() -> Result<()> {
    let args = Args::parse();
    let root = common::root();
    let names = experiment_names();
    for name in &args.only {
        if !names.contains(&name.as_str()) {
            bail!("unknown experiment `{name}`; known: {}", names.join(", "));
        }
    }
    let selected: Vec<&'static Job> = JOBS
        .iter()
        .filter(|j| {
            args.only.is_empty() || j.experiments().any(|e| args.only.iter().any(|o| o == e))
        })
        .collect();
    let ran = if args.book_only {
        schedule::Outcome::default()
    } else {
        schedule::run_selected(&selected, args.jobs, args.force, args.no_build)?
    };
    publish::publish_own_device()?;
    let rows = scorecard::write_scorecard()?;
    answers::write(&rows)?;
    provenance::write_provenance()?;
    publish::deviations_placeholder()?;
    recorded_history::publish(&root, &common::book_generated_root())?;
    eprintln!("[reproduce] building the book");
    book::build(&root.join("book"))?;

    ran.eprint_timings();
    scorecard::eprint_counts(&rows);
    eprintln!("book: {}", root.join("book/build/index.html").display());
    if !ran.failures.is_empty() {
        bail!("experiments failed: {}", ran.failures.join(", "));
    }
    Ok(())
}
