//! The benchmark's run (`bench` and `bench --quick`): the main table of timed cases
//! (`bench/cases.rs`), the comparison with RK4 and the accuracy tables (`bench/rk4.rs`), the
//! records behind an interface (`bench/interfaces.rs`), the two-mass record against a one-mass
//! record (`bench/masses.rs`) and the example devices
//! (`bench/examples.rs`), written to `data/results/bench/` and the book's Performance page.

use anyhow::Result;
use endstop_experiments as common;
use polars::prelude::*;

use common::{fmt_sig, Experiment};

use crate::timing::sig_or_dash;
use crate::{cases, examples, interfaces, masses, rk4, REPEATS, SEED};

/// The whole benchmark's recorded tables (`data/recorded/bench/`): the whole run rewrites
/// them, the short run shows them.
pub const RECORDED_DIR: &str = "data/recorded/bench";

fn recorded(file: &str) -> std::path::PathBuf {
    common::root().join(RECORDED_DIR).join(file)
}

/// Writes to `dst` the recorded table `file` of the whole benchmark, labelled as recorded
/// (the short run does not measure `what`); where there is no recording, says so and why.
fn show_recorded(dst: &std::path::Path, file: &str, what: &str) -> Result<()> {
    let md = match std::fs::read_to_string(recorded(file)) {
        Ok(table) => format!(
            "*Recorded, not measured in this build: `reproduce` runs the short benchmark \
             (`bench --quick`), which leaves out {what}; below is the whole benchmark's \
             recorded output (`{RECORDED_DIR}/{file}`, with the commit it measured). `just \
             bench` measures it again on your machine.*\n\n{table}"
        ),
        Err(_) => format!(
            "*Not measured in this build, and not recorded: `reproduce` runs the short \
             benchmark (`bench --quick`), which leaves out {what}; `just bench` (the whole \
             benchmark, about a minute on 2 cores) measures it and writes it here.*\n"
        ),
    };
    common::write_atomic(dst, md.as_bytes())
}

/// A table only the whole benchmark measures (`quick` false): `measure` makes it, and it is
/// written into the book and recorded as `file`. `--quick` keeps the last whole run's table
/// (it names its commit), or else shows the recording (`show_recorded`).
fn whole_only(
    quick: bool,
    file: &str,
    what: &str,
    measure: impl FnOnce() -> Result<String>,
) -> Result<()> {
    let dst = common::book_generated_root().join("bench").join(file);
    if !quick {
        let md = measure()?;
        common::write_atomic(&dst, md.as_bytes())?;
        common::write_atomic(&recorded(file), md.as_bytes())?;
        print!("{md}");
    } else if !dst.exists() {
        show_recorded(&dst, file, what)?;
    }
    Ok(())
}

/// Runs every case ([`REPEATS`] times, once with `quick`) and writes the tables.
pub fn run(quick: bool) -> Result<()> {
    let repeats = if quick { 1 } else { REPEATS };
    let mut exp = Experiment::start("bench");
    exp.seed = Some(SEED);
    let p1 = exp.load_published("prototype1")?;
    let p2 = exp.load_published("prototype2")?;
    let cal = common::calibrated_prototype1(&p1)?.0.device;
    let records = cases::records(&cal, &p1.device, &p2.device);
    let rows = cases::rows(
        &mut exp, &records, &cal, &p1.device, &p2.device, repeats, quick,
    )?;

    let mut md = format!(
        "Machine: {} logical cores (RAYON_NUM_THREADS unset unless stated). Each case ran \
         {repeats} time(s){}. Processor time is user plus system time of every thread.\n\n\
         | case | median processor time (s) | median wall (s) | fastest wall (s) | simulated s per processor s | steps per simulated s | rejected steps (after an event) | RHS evals per simulated s | events | notes |\n|---|---|---|---|---|---|---|---|---|---|\n",
        std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1),
        if quick {
            " (`bench --quick`, as `reproduce` runs it; `just bench` adds the sweeps, the \
             continuation, the comparisons with RK4 and ngspice and the accuracy tables)"
        } else {
            ""
        }
    );
    for r in &rows {
        md.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} ({}) | {} | {} | {} |\n",
            r.case,
            sig_or_dash(r.times.median_cpu()),
            fmt_sig(r.times.median_wall(), 3),
            fmt_sig(r.times.fastest_wall(), 3),
            sig_or_dash(r.simulated_s / r.times.median_cpu()),
            fmt_sig(r.stats.steps() as f64 / r.simulated_s, 3),
            r.stats.rejected,
            r.stats.rejected_after_event,
            fmt_sig(r.stats.rhs_evals as f64 / r.simulated_s, 3),
            r.stats.events,
            r.note
        ));
    }
    exp.write_numbers_md(&md)?;
    print!("{md}");
    // The comparison with RK4 and the accuracy tables.
    whole_only(
        quick,
        "full.md",
        "the comparison with RK4 and the accuracy tables",
        || {
            Ok(format!(
                "*Measured by the whole benchmark (`just bench`) at commit `{}`.*\n{}",
                common::git_commit(),
                rk4::paper_rk4_and_accuracy(&mut exp, &records, &p1, &p2)?
            ))
        },
    )?;
    // Records behind an interface circuit against the resistive load, in alternated rounds.
    whole_only(
        quick,
        "interfaces.md",
        "the paired cost of records behind an interface",
        || {
            let costs = interfaces::measure(repeats)?;
            for c in &costs.interfaces {
                let key = c.name.split(' ').next().unwrap_or(c.name);
                exp.number(
                    &format!("interface_record_cost_ratio_median_{key}"),
                    c.ratios.0,
                );
            }
            Ok(interfaces::table(&costs, repeats))
        },
    )?;
    // A two-mass record against a one-mass record of as many impacts, in alternated rounds.
    whole_only(
        quick,
        "masses.md",
        "the paired cost of a two-mass record",
        || {
            let costs = masses::measure(repeats)?;
            if let Some(two) = costs.get(1) {
                exp.number("two_mass_record_cost_ratio_median", two.ratios.0);
            }
            Ok(masses::table(&costs, repeats))
        },
    )?;

    // Every example device.
    let costs = examples::measure(&common::root(), repeats, quick)?;
    let examples_md = examples::table(&costs, repeats, quick);
    for c in &costs {
        exp.number(&format!("{}_record_s", c.name), c.record.0);
        exp.number(&format!("{}_orbit_s", c.name), c.orbit);
        if let Some(r) = c.response {
            exp.number(&format!("{}_response_s", c.name), r);
        }
    }
    common::write_atomic(
        &common::book_generated_root()
            .join("bench")
            .join("examples.md"),
        examples_md.as_bytes(),
    )?;
    print!("{examples_md}");

    let mut df = df!(
        "case" => rows.iter().map(|r| r.case.clone()).collect::<Vec<_>>(),
        "median_cpu_s" => rows.iter().map(|r| r.times.median_cpu()).collect::<Vec<_>>(),
        "median_wall_s" => rows.iter().map(|r| r.times.median_wall()).collect::<Vec<_>>(),
        "min_wall_s" => rows.iter().map(|r| r.times.fastest_wall()).collect::<Vec<_>>(),
        "simulated_s" => rows.iter().map(|r| r.simulated_s).collect::<Vec<_>>(),
        "steps" => rows.iter().map(|r| r.stats.steps()).collect::<Vec<_>>(),
        "rejected_steps" => rows.iter().map(|r| r.stats.rejected).collect::<Vec<_>>(),
        "rejected_after_event" => rows.iter().map(|r| r.stats.rejected_after_event).collect::<Vec<_>>(),
        "rhs_evals" => rows.iter().map(|r| r.stats.rhs_evals).collect::<Vec<_>>(),
        "events" => rows.iter().map(|r| r.stats.events).collect::<Vec<_>>(),
        "params" => vec!["published+calibrated"; rows.len()],
    )?;
    exp.write_parquet("bench", &mut df, "published+calibrated")?;
    let mut df = df!(
        "device" => costs.iter().map(|c| c.name.clone()).collect::<Vec<_>>(),
        "record_cpu_s" => costs.iter().map(|c| c.record.0).collect::<Vec<_>>(),
        "orbit_cpu_s" => costs.iter().map(|c| c.orbit).collect::<Vec<_>>(),
        "response_cpu_s" => costs.iter().map(|c| c.response).collect::<Vec<_>>(),
        "params" => vec!["example"; costs.len()],
    )?;
    exp.write_parquet("examples", &mut df, "example")?;
    exp.finish()
}
