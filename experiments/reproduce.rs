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

use std::path::PathBuf;
use std::process::Command;
use std::sync::Mutex;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use clap::Parser;
use endstop::paper::claims::score;
use endstop::paper::claims::Claims;
use endstop::paper::claims::Row;
use endstop::paper::claims::Value;
use endstop::paper::claims::Verdict;
use endstop::paper::setups::ParamSet;
use endstop_experiments::pipeline::freshness;
use endstop_experiments::pipeline::jobs::{experiment_dir, experiment_names, Job, Phase, JOBS};
use serde::Deserialize;

/// The wall and processor time of the last `reproduce` that ran experiments, in the results
/// directory.
const LAST_RUN: &str = "reproduce_timing.json";

/// Copies the own-device runs' numbers and plots into the book's generated directory, with
/// the curve drawn from several of them ([`common::pipeline::noise_curve`]).
fn publish_own_device() -> Result<()> {
    let dst = common::book_generated_root().join("own_device");
    for job in JOBS.iter().filter(|j| j.is_tool_run()) {
        let src = job.dir();
        let stem = job.name.trim_start_matches("own_device_");
        // The tool names its files after its study, the job's first argument.
        let tool = format!("endstop-{}", job.args.first().copied().unwrap_or(stem));
        for (from, to) in [
            ("numbers.md".to_string(), format!("{stem}.md")),
            (format!("{tool}.svg"), format!("{stem}.svg")),
            (format!("{tool}.png"), format!("{stem}.png")),
        ] {
            if let Ok(bytes) = std::fs::read(src.join(&from)) {
                common::write_atomic(&dst.join(to), &bytes)?;
            }
        }
        // The caption, with the image pointing at the copy above.
        if let Ok(md) = std::fs::read_to_string(src.join(format!("{tool}.figure.md"))) {
            let md = match (md.find("]("), md.find(".svg)")) {
                (Some(a), Some(b)) if a < b => {
                    format!("{}](generated/own_device/{stem}{}", &md[..a], &md[b..])
                }
                _ => md,
            };
            common::write_atomic(&dst.join(format!("{stem}.figure.md")), md.as_bytes())?;
        }
    }
    // The bistable example's power and transition rate against the noise level, from its
    // random jobs' summaries.
    common::pipeline::noise_curve::publish(&common::results_root(), &dst)
}

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
    let mut failures = Vec::new();
    let mut timings: Vec<(String, f64)> = Vec::new();
    if !args.book_only {
        if !args.no_build {
            build_binaries()?;
        }
        // The experiments' wall and processor time (ngspice's included), for the provenance
        // table; the build above is not counted.
        let (started, cpu_before) = (Instant::now(), common::children_cpu_time_s());
        // Phase by phase: a job's key is computed when its phase starts, after the artefacts
        // of earlier phases (the calibration) are written.
        for (phase, parallel) in [
            (Phase::First, 1),
            (Phase::Parallel, args.jobs.max(1)),
            (Phase::Last, 1),
        ] {
            let mut to_run = Vec::new();
            for job in selected.iter().filter(|j| j.phase == phase) {
                let key = freshness::key(job)?;
                if !args.force && freshness::is_fresh(job, &key) {
                    eprintln!(
                        "[{}] skipped: inputs unchanged since its last run (use --force to rerun)",
                        job.name
                    );
                } else {
                    to_run.push((*job, key));
                }
            }
            // Longest first, so that no long job starts last and runs alone at the end (the
            // greedy schedule of Graham's LPT rule, within 4/3 of the shortest makespan).
            longest_first(&mut to_run);
            let out = run_jobs(&to_run, parallel)?;
            timings.extend(out.timings);
            failures.extend(out.failures);
        }
        if !timings.is_empty() {
            let cpu = common::children_cpu_time_s()
                .zip(cpu_before)
                .map(|(after, before)| after - before);
            let total = serde_json::json!({
                "wall_time_s": started.elapsed().as_secs_f64(),
                "cpu_time_s": cpu,
                "experiments": timings.iter().map(|(n, _)| n.as_str()).collect::<Vec<_>>(),
                "force": args.force,
            });
            common::write_atomic(
                &common::results_root().join(LAST_RUN),
                serde_json::to_string_pretty(&total)?.as_bytes(),
            )?;
        }
    }
    publish_own_device()?;
    let rows = write_scorecard()?;
    common::pipeline::answers::write(&rows)?;
    write_provenance()?;
    deviations_placeholder()?;
    eprintln!("[reproduce] building the book");
    common::pipeline::book::build(&root.join("book"))?;

    let count = |v: Verdict| rows.iter().filter(|r| r.verdict == v).count();
    if !timings.is_empty() {
        eprintln!("\n experiment   wall time");
        for (n, t) in &timings {
            eprintln!(" {n:<10} {t:>8.2} s");
        }
    }
    eprintln!(
        "\nscorecard: {} reproduced, {} deviates, {} not yet ({} rows) -> data/results/scorecard.json",
        count(Verdict::Reproduced),
        count(Verdict::Deviates),
        count(Verdict::NotYet),
        rows.len()
    );
    eprintln!("book: {}", root.join("book/build/index.html").display());
    if !failures.is_empty() {
        bail!("experiments failed: {}", failures.join(", "));
    }
    Ok(())
}

/// The jobs whose last run was longest, in that order, before the others: when a job has
/// no timing of its own yet (a fresh clone), its place in [`LONG_JOBS`] stands for it.
fn longest_first(jobs: &mut [(&'static Job, String)]) {
    let last_cpu = |job: &Job| -> Option<f64> {
        let t: serde_json::Value = read_json(&job.dir().join("timing.json"))?;
        t["cpu_time_s"].as_f64()
    };
    let known: Vec<Option<f64>> = jobs.iter().map(|(j, _)| last_cpu(j)).collect();
    if known.iter().all(Option::is_some) {
        let mut order: Vec<usize> = (0..jobs.len()).collect();
        order.sort_by(|&a, &b| {
            known[b]
                .partial_cmp(&known[a])
                .unwrap_or(std::cmp::Ordering::Equal)
        });
        let sorted: Vec<_> = order.iter().map(|&i| jobs[i].clone()).collect();
        jobs.clone_from_slice(&sorted);
    } else {
        jobs.sort_by_key(|(job, _)| {
            LONG_JOBS
                .iter()
                .position(|n| *n == job.name)
                .unwrap_or(LONG_JOBS.len())
        });
    }
}

/// The parallel phase's longest jobs, longest first, as measured by `reproduce --force` on
/// 2 cores (the Performance chapter's table of each job's time): the order of a run without
/// earlier timings.
const LONG_JOBS: [&str; 7] = [
    "response",
    "fig14",
    "fig12",
    "own_device_fit",
    "fig08",
    "fig11",
    "validation",
];

fn build_binaries() -> Result<()> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".to_string());
    eprintln!("[reproduce] cargo build --release --bins");
    let status = Command::new(cargo)
        .args(["build", "--release", "--bins", "--quiet"])
        .current_dir(common::root())
        .status()
        .context("running cargo build (pass --no-build if the binaries are already built)")?;
    if !status.success() {
        bail!("cargo build --release --bins failed");
    }
    Ok(())
}

fn binary_dir() -> Result<PathBuf> {
    let exe = std::env::current_exe().context("locating this executable")?;
    Ok(exe
        .parent()
        .context("executable has no directory")?
        .to_path_buf())
}

/// Wall time (s) of each job that ran, and the names of those that failed.
struct Outcome {
    timings: Vec<(String, f64)>,
    failures: Vec<String>,
}

/// Runs the jobs (each with its freshness key), at most `parallel` at once.
fn run_jobs(jobs: &[(&'static Job, String)], parallel: usize) -> Result<Outcome> {
    let dir = binary_dir()?;
    // The jobs not started, taken in order by the workers.
    let queue = Mutex::new(jobs.iter());
    let results = Mutex::new(Vec::new());
    let pb = common::progress(jobs.len() as u64, "reproduce");
    std::thread::scope(|s| {
        for _ in 0..parallel.min(jobs.len()) {
            s.spawn(|| {
                let next = || queue.lock().expect("queue lock").next();
                while let Some((job, key)) = next() {
                    let name = job.name;
                    pb.set_message(name);
                    let t = Instant::now();
                    let out = Command::new(dir.join(job.program))
                        .args(job.command_args())
                        .current_dir(common::root())
                        .output();
                    let secs = t.elapsed().as_secs_f64();
                    let ok = match &out {
                        Ok(o) => {
                            let log = job.dir().join("log.txt");
                            let mut text = String::from_utf8_lossy(&o.stdout).to_string();
                            text.push_str(&String::from_utf8_lossy(&o.stderr));
                            let _ = common::write_atomic(&log, text.as_bytes());
                            if o.status.success() {
                                let _ = freshness::mark_done(job, key);
                            } else {
                                freshness::forget(job);
                                pb.println(format!("[{name}] FAILED:\n{text}"));
                            }
                            o.status.success()
                        }
                        Err(e) => {
                            pb.println(format!("[{name}] could not start: {e}"));
                            false
                        }
                    };
                    pb.println(format!(
                        "[{name}] {} in {secs:.2} s",
                        if ok { "done" } else { "failed" }
                    ));
                    pb.inc(1);
                    results
                        .lock()
                        .expect("results lock")
                        .push((name.to_string(), secs, ok));
                }
            });
        }
    });
    pb.finish_and_clear();
    let mut results = results.into_inner().expect("results");
    let order = experiment_names();
    results.sort_by_key(|(n, _, _)| order.iter().position(|e| e == n));
    let failures = results
        .iter()
        .filter(|r| !r.2)
        .map(|r| r.0.clone())
        .collect();
    Ok(Outcome {
        timings: results.into_iter().map(|(n, t, _)| (n, t)).collect(),
        failures,
    })
}

#[derive(Deserialize)]
struct SummaryIn {
    #[serde(default)]
    values: Vec<Value>,
    #[serde(default)]
    commit: String,
    #[serde(default)]
    seed: Option<u64>,
    #[serde(default)]
    params: Vec<(String, String)>,
    /// A number that is not finite (a reduced chi-square without a noise level) is `null`.
    #[serde(default)]
    numbers: std::collections::BTreeMap<String, Option<f64>>,
}

fn read_summary(job: &Job) -> Option<SummaryIn> {
    read_json(&job.dir().join("summary.json"))
}

/// The summary of an experiment that a job writes besides its own.
fn read_experiment_summary(name: &str) -> Option<SummaryIn> {
    read_json(&experiment_dir(name).join("summary.json"))
}

/// A JSON file's contents; None when it is missing or does not parse (a job that has not run).
fn read_json<T: serde::de::DeserializeOwned>(path: &std::path::Path) -> Option<T> {
    serde_json::from_str(&std::fs::read_to_string(path).ok()?).ok()
}

/// Joins `data/claims.toml` with every experiment's summary.
fn write_scorecard() -> Result<Vec<Row>> {
    let claims = Claims::bundled()?;
    let values: Vec<Value> = JOBS
        .iter()
        .filter(|j| j.scored)
        .flat_map(Job::experiments)
        .filter_map(read_experiment_summary)
        .flat_map(|s| s.values)
        .collect();
    let mut rows = score(&claims, &values)?;
    let target = endstop::paper::calibration::CALIBRATION_TARGET;
    for r in &mut rows {
        if r.set == ParamSet::Calibrated && r.claim == target.id && r.quantity == target.quantity {
            r.note = "calibration target: fitted, not a prediction".into();
        }
    }
    // Beside each jump claim, the upper fold of the continued orbits (the response job).
    let folds = common::pipeline::jobs::job("response")
        .and_then(read_summary)
        .map(|s| s.numbers)
        .unwrap_or_default();
    for r in &mut rows {
        r.fold_hz = endstop::paper::response::fold_key(&r.claim, &r.quantity, r.set)
            .and_then(|k| folds.get(&k).copied().flatten());
    }
    // Beside each claim the study evaluates, its value at the best set of the multi-claim
    // calibration (the study's summary, if `just deviations` has been run).
    let best = read_summary(&common::pipeline::jobs::DEVIATIONS)
        .map(|s| s.numbers)
        .unwrap_or_default();
    for r in rows.iter_mut().filter(|r| r.set == ParamSet::Published) {
        r.best_calibrated = endstop::paper::deviations::best_value_key(&r.claim, &r.quantity)
            .and_then(|k| best.get(&k).copied().flatten());
    }
    common::write_atomic(
        &common::results_root().join("scorecard.json"),
        serde_json::to_string_pretty(&rows)?.as_bytes(),
    )?;
    let mut md = String::from(
        "| claim | quantity | set | paper | ours | ± | unit | tolerance | verdict | fold (Hz) | best under calibration | note |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in &rows {
        let ours = r
            .ours
            .map(|v| common::fmt_sig(v.to_f64(), 4))
            .unwrap_or_else(|| "-".into());
        let unc = r
            .uncertainty
            .map(|v| common::fmt_sig(v, 2))
            .unwrap_or_default();
        let verdict = match r.verdict {
            Verdict::Reproduced => "**reproduced**",
            Verdict::Deviates => "*deviates*",
            Verdict::NotYet => "not yet",
            Verdict::Open => "*open question*",
        };
        let fold = r.fold_hz.map(|v| format!("{v:.2}")).unwrap_or_default();
        let best = r
            .best_calibrated
            .map(|v| common::fmt_sig(v, 4))
            .unwrap_or_default();
        md.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            r.claim,
            r.quantity,
            r.set,
            r.paper.to_f64(),
            ours,
            unc,
            r.unit,
            common::fmt_sig(r.tolerance, 2),
            verdict,
            fold,
            best,
            r.note
        ));
    }
    common::write_atomic(
        &common::book_generated_root().join("scorecard.md"),
        md.as_bytes(),
    )?;
    Ok(rows)
}

/// The jobs that simulate the random-vibration ensembles (the provenance line compares their
/// processor time with a minute of the machine's cores).
const ENSEMBLE_JOBS: [&str; 4] = ["fig11", "fig12", "fig14", "fig15"];

/// The provenance table: experiment, parameter files, seed, commit, wall and CPU time; under
/// it, the CPU sum with the floor it puts on the wall time, and the last run's totals.
fn write_provenance() -> Result<()> {
    let mut md = String::from(
        "| experiment | parameter files (set) | seed | commit | wall time (s) | CPU time (s) |\n\
         |---|---|---|---|---|---|\n",
    );
    let (mut cpu_sum, mut cpu_jobs, mut cpu_ensembles) = (0.0, 0, 0.0);
    for (name, dir) in JOBS.iter().flat_map(Job::outputs) {
        let Some(s) = read_json::<SummaryIn>(&dir.join("summary.json")) else {
            md.push_str(&format!("| {name} | (no results) | | | | |\n"));
            continue;
        };
        let timing: Option<serde_json::Value> = read_json(&dir.join("timing.json"));
        let seconds = |key: &str| timing.as_ref().and_then(|v| v[key].as_f64());
        let wall = seconds("wall_time_s")
            .map(|t| format!("{t:.2}"))
            .unwrap_or_default();
        let cpu = seconds("cpu_time_s");
        if let Some(c) = cpu {
            cpu_sum += c;
            cpu_jobs += 1;
            if ENSEMBLE_JOBS.contains(&name) {
                cpu_ensembles += c;
            }
        }
        let params: Vec<String> = s
            .params
            .iter()
            .map(|(f, l)| format!("`{f}` ({l})"))
            .collect();
        md.push_str(&format!(
            "| {name} | {} | {} | `{}` | {wall} | {} |\n",
            params.join(", "),
            s.seed.map(|x| x.to_string()).unwrap_or_else(|| "-".into()),
            s.commit,
            cpu.map(|c| format!("{c:.1}")).unwrap_or_default(),
        ));
    }
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    if cpu_jobs > 0 {
        md.push_str(&format!(
            "\nThe CPU times (user and system, ngspice's included) add up to {cpu_sum:.0} s over \
             {cpu_jobs} experiments: on this machine's {cores} cores no schedule of them can take \
             less than {:.0} s of wall time.",
            cpu_sum / cores as f64
        ));
        // What a minute of wall time allows, against the random-vibration ensembles alone.
        let minute = 60.0 * cores as f64;
        md.push_str(&format!(
            " A minute on {cores} cores is {minute:.0} s of CPU time; the random-vibration \
             ensembles ({}) took {cpu_ensembles:.0} s of CPU time, {} of it.",
            ENSEMBLE_JOBS.join(", "),
            if cpu_ensembles > minute {
                "more than all".to_string()
            } else {
                format!("{:.0} %", 100.0 * cpu_ensembles / minute)
            }
        ));
    }
    if let Some(v) = read_json::<serde_json::Value>(&common::results_root().join(LAST_RUN)) {
        let (wall, cpu) = (v["wall_time_s"].as_f64(), v["cpu_time_s"].as_f64());
        let n = v["experiments"].as_array().map_or(0, |a| a.len());
        if let Some(wall) = wall {
            md.push_str(&format!(
                " The last `reproduce{}` ran {n} experiments in {wall:.0} s of wall time{}.",
                if v["force"].as_bool() == Some(true) {
                    " --force"
                } else {
                    ""
                },
                cpu.map(|c| format!(
                    " and {c:.0} s of CPU time ({:.2} cores busy on average)",
                    c / wall
                ))
                .unwrap_or_default()
            ));
        }
    }
    md.push('\n');
    common::write_atomic(
        &common::book_generated_root().join("provenance.md"),
        md.as_bytes(),
    )
}

/// The study is not one of `reproduce`'s jobs: until `just deviations` has run, its chapter
/// includes a note in place of its answer, numbers, recorded match and heat map.
fn deviations_placeholder() -> Result<()> {
    let dir = common::book_generated_root().join(common::pipeline::jobs::DEVIATIONS.name);
    if !dir.join("numbers.md").exists() {
        let note = "*Not run in this build: the study is not part of `reproduce`; run \
                    `just deviations` (or `cargo run --release --bin deviations`) and rebuild the book.*\n";
        common::write_atomic(&dir.join("numbers.md"), note.as_bytes())?;
    }
    for (file, note) in [
        ("answer.md", "*The study of why the paper deviates has not run in this build (`just deviations`).*\n"),
        ("recorded.md", "*(the study has not run in this build)*\n"),
    ] {
        if !dir.join(file).exists() {
            common::write_atomic(&dir.join(file), note.as_bytes())?;
        }
    }
    let path = dir.join("deviations.figure.md");
    if !path.exists() {
        common::write_atomic(&path, b"*(no plot: the study has not run)*\n")?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_ensemble_jobs_are_experiments() {
        for name in ENSEMBLE_JOBS {
            assert!(
                experiment_names().contains(&name),
                "{name} is not an experiment"
            );
        }
    }
}
