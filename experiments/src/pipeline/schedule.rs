//! How `reproduce` runs its jobs: the binaries built first, then phase by phase each job whose
//! inputs changed, as separate processes at most `--jobs` at a time, longest first; each one's
//! log goes to `data/results/<name>/log.txt`, and the run's wall and processor time to
//! [`LAST_RUN`].

use std::path::PathBuf;
use std::process::Command;
use std::sync::Mutex;
use std::time::Instant;

use anyhow::{bail, Context, Result};

use crate::pipeline::freshness;
use crate::pipeline::jobs::{experiment_names, Job, Phase};
use crate::pipeline::scorecard::read_json;

/// The wall and processor time of the last `reproduce` that ran experiments, in the results
/// directory.
pub const LAST_RUN: &str = "reproduce_timing.json";

/// Wall time (s) of each job that ran, and the names of those that failed.
#[derive(Debug, Default)]
pub struct Outcome {
    /// Each job that ran and its wall time (s), in the order of the experiments.
    pub timings: Vec<(String, f64)>,
    /// The jobs that failed.
    pub failures: Vec<String>,
}

impl Outcome {
    /// Prints each job's wall time to standard error (nothing when no job ran).
    pub fn eprint_timings(&self) {
        if !self.timings.is_empty() {
            eprintln!("\n experiment   wall time");
            for (n, t) in &self.timings {
                eprintln!(" {n:<10} {t:>8.2} s");
            }
        }
    }
}

/// Runs the selected jobs whose inputs changed since their last run (all of them with
/// `force`), phase by phase, `parallel` at a time in the parallel phase; builds the binaries
/// first unless `no_build`. Writes [`LAST_RUN`] when a job ran.
pub fn run_selected(
    selected: &[&'static Job],
    parallel: usize,
    force: bool,
    no_build: bool,
) -> Result<Outcome> {
    let mut outcome = Outcome::default();
    if !no_build {
        build_binaries()?;
    }
    // The experiments' wall and processor time (ngspice's included), for the provenance
    // table; the build above is not counted.
    let (started, cpu_before) = (Instant::now(), crate::children_cpu_time_s());
    // Phase by phase: a job's key is computed when its phase starts, after the artefacts
    // of earlier phases (the calibration) are written.
    for (phase, parallel) in [
        (Phase::First, 1),
        (Phase::Parallel, parallel.max(1)),
        (Phase::Last, 1),
    ] {
        let mut to_run = Vec::new();
        for job in selected.iter().filter(|j| j.phase == phase) {
            let key = freshness::key(job)?;
            if !force && freshness::is_fresh(job, &key) {
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
        outcome.timings.extend(out.timings);
        outcome.failures.extend(out.failures);
    }
    if !outcome.timings.is_empty() {
        let cpu = crate::children_cpu_time_s()
            .zip(cpu_before)
            .map(|(after, before)| after - before);
        let total = serde_json::json!({
            "wall_time_s": started.elapsed().as_secs_f64(),
            "cpu_time_s": cpu,
            "experiments": outcome.timings.iter().map(|(n, _)| n.as_str()).collect::<Vec<_>>(),
            "force": force,
        });
        crate::write_atomic(
            &crate::results_root().join(LAST_RUN),
            serde_json::to_string_pretty(&total)?.as_bytes(),
        )?;
    }
    Ok(outcome)
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
    "fig14",
    "validation",
    "fig12",
    "response",
    "fig08",
    "fig11",
    "own_device_sweep",
];

fn build_binaries() -> Result<()> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".to_string());
    eprintln!("[reproduce] cargo build --release --bins");
    let status = Command::new(cargo)
        .args(["build", "--release", "--bins", "--quiet"])
        .current_dir(crate::root())
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

/// Runs the jobs (each with its freshness key), at most `parallel` at once.
fn run_jobs(jobs: &[(&'static Job, String)], parallel: usize) -> Result<Outcome> {
    let dir = binary_dir()?;
    // The jobs not started, taken in order by the workers.
    let queue = Mutex::new(jobs.iter());
    let results = Mutex::new(Vec::new());
    let pb = crate::progress(jobs.len() as u64, "reproduce");
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
                        .current_dir(crate::root())
                        .output();
                    let secs = t.elapsed().as_secs_f64();
                    let ok = match &out {
                        Ok(o) => {
                            let log = job.dir().join("log.txt");
                            let mut text = String::from_utf8_lossy(&o.stdout).to_string();
                            text.push_str(&String::from_utf8_lossy(&o.stderr));
                            let _ = crate::write_atomic(&log, text.as_bytes());
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
