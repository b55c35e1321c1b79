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
use serde::Deserialize;

/// Every experiment, in the order of the paper.
const EXPERIMENTS: [&str; 10] = [
    "fig05", "table3", "fig08", "fig09", "fig10", "fig11", "fig12", "fig13", "fig14", "fig15",
];

/// Runs of the `endstop` tool on the example device of the "Model your own harvester"
/// chapter: (job name, arguments before `--out`).
const OWN_DEVICE: [(&str, &[&str]); 2] = [
    (
        "own_device_sweep",
        &[
            "sweep",
            "--device",
            "data/examples/my_harvester.toml",
            "--from",
            "500",
            "--to",
            "800",
            "--step",
            "2",
            "--accel-rms-g",
            "0.3",
        ],
    ),
    (
        "own_device_random",
        &[
            "random",
            "--device",
            "data/examples/my_harvester.toml",
            "--psd",
            "1e-4",
            "--records",
            "4",
        ],
    ),
];

/// The calibration of prototype 1 runs first and alone: every experiment of the calibrated set
/// (fig08, fig09, fig11, fig12, bench) reads its artefact, in `data/results/calibration/`.
const CALIBRATE: &str = "calibrate";

/// The benchmark runs last and alone, so that nothing else competes for the cores it times.
const BENCH: &str = "bench";

/// The ngspice cross-check: run when `ngspice` is on PATH, otherwise the book says it was not.
const CROSSCHECK: &str = "crosscheck";

/// Every job `reproduce` knows: the calibration, the experiments, the own-device runs, the
/// ngspice cross-check, then the benchmark.
fn all_jobs() -> Vec<&'static str> {
    std::iter::once(CALIBRATE)
        .chain(EXPERIMENTS.iter().copied())
        .chain(OWN_DEVICE.iter().map(|(n, _)| *n))
        .chain([CROSSCHECK, BENCH])
        .collect()
}

fn ngspice_available() -> bool {
    Command::new("ngspice")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success())
}

/// The results directory of a job (the calibration's is its artefact's directory).
fn job_dir(name: &str) -> PathBuf {
    if name == CALIBRATE {
        common::calibration_io::calibration_dir()
    } else {
        common::results_root().join(name)
    }
}

/// The program and arguments of a job.
fn job_command(name: &str) -> (String, Vec<String>) {
    match OWN_DEVICE.iter().find(|(n, _)| *n == name) {
        Some((_, args)) => {
            let mut a: Vec<String> = args.iter().map(|s| s.to_string()).collect();
            a.push("--out".into());
            a.push(common::results_root().join(name).display().to_string());
            ("endstop".into(), a)
        }
        None => (name.to_string(), Vec::new()),
    }
}

/// Copies the own-device runs' numbers and plots into the book's generated directory.
fn publish_own_device() -> Result<()> {
    let dst = common::book_generated_root().join("own_device");
    for (name, _) in OWN_DEVICE {
        let src = common::results_root().join(name);
        let stem = name.trim_start_matches("own_device_");
        let tool = format!("endstop-{stem}");
        for (from, to) in [
            ("numbers.md".to_string(), format!("{stem}.md")),
            (format!("{tool}.svg"), format!("{stem}.svg")),
            (format!("{tool}.png"), format!("{stem}.png")),
        ] {
            if let Ok(bytes) = std::fs::read(src.join(&from)) {
                common::write_atomic(&dst.join(to), &bytes)?;
            }
        }
    }
    Ok(())
}

#[derive(Parser, Debug)]
#[command(about = "Run every experiment, write the scorecard and build the book")]
struct Args {
    /// Run only these experiments (comma separated), e.g. `--only fig08,fig13`.
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
    let jobs = all_jobs();
    for name in &args.only {
        if !jobs.contains(&name.as_str()) {
            bail!("unknown experiment `{name}`; known: {}", jobs.join(", "));
        }
    }
    let selected: Vec<&str> = jobs
        .iter()
        .copied()
        .filter(|n| args.only.is_empty() || args.only.iter().any(|o| o == n))
        .collect();
    let mut failures = Vec::new();
    let mut timings: Vec<(String, f64)> = Vec::new();
    if !args.book_only {
        if !args.no_build {
            build_binaries()?;
        }
        let key = inputs_key()?;
        let mut to_run = Vec::new();
        for &name in &selected {
            if !args.force && is_fresh(name, &key) {
                eprintln!(
                    "[{name}] skipped: inputs unchanged since its last run (use --force to rerun)"
                );
            } else {
                to_run.push(name);
            }
        }
        if to_run.contains(&CROSSCHECK) && !ngspice_available() {
            eprintln!("[{CROSSCHECK}] not run: ngspice is not installed (apt-get install ngspice)");
            to_run.retain(|n| *n != CROSSCHECK);
            let note = "*Not run in this build: `ngspice` was not installed. Install it \
                        (`apt-get install ngspice`) and rerun `reproduce`.*\n";
            let dir = common::book_generated_root().join(CROSSCHECK);
            common::write_atomic(&dir.join("numbers.md"), note.as_bytes())?;
            if !dir.join("p1_impacting.cir").exists() {
                common::write_atomic(&dir.join("p1_impacting.cir"), b"* not generated\n")?;
            }
        }
        let (calibrate, rest): (Vec<&str>, Vec<&str>) =
            to_run.iter().partition(|n| **n == CALIBRATE);
        let (parallel, alone): (Vec<&str>, Vec<&str>) = rest.iter().partition(|n| **n != BENCH);
        let before = run_experiments(&calibrate, 1, &key)?;
        let first = run_experiments(&parallel, args.jobs.max(1), &key)?;
        let last = run_experiments(&alone, 1, &key)?;
        timings = [before.timings, first.timings, last.timings].concat();
        failures = [before.failures, first.failures, last.failures].concat();
    }
    publish_own_device()?;
    let rows = write_scorecard()?;
    write_provenance()?;
    eprintln!("[reproduce] building the book");
    let book = mdbook_driver::MDBook::load(root.join("book"))
        .map_err(|e| anyhow::anyhow!("loading the book: {e:#}"))?;
    book.build()
        .map_err(|e| anyhow::anyhow!("building the book: {e:#}"))?;

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

/// Runs the experiments, at most `jobs` at once.
fn run_experiments(names: &[&str], jobs: usize, key: &str) -> Result<Outcome> {
    let dir = binary_dir()?;
    let queue = Mutex::new(names.iter().map(|s| s.to_string()).collect::<Vec<_>>());
    let results = Mutex::new(Vec::new());
    let pb = common::progress(names.len() as u64, "reproduce");
    std::thread::scope(|s| {
        for _ in 0..jobs.min(names.len()) {
            s.spawn(|| {
                let next = || {
                    let mut q = queue.lock().expect("queue lock");
                    (!q.is_empty()).then(|| q.remove(0))
                };
                while let Some(name) = next() {
                    pb.set_message(name.clone());
                    let t = Instant::now();
                    let (program, job_args) = job_command(&name);
                    let out = Command::new(dir.join(&program))
                        .args(&job_args)
                        .current_dir(common::root())
                        .output();
                    let secs = t.elapsed().as_secs_f64();
                    let ok = match &out {
                        Ok(o) => {
                            let log = job_dir(&name).join("log.txt");
                            let mut text = String::from_utf8_lossy(&o.stdout).to_string();
                            text.push_str(&String::from_utf8_lossy(&o.stderr));
                            let _ = common::write_atomic(&log, text.as_bytes());
                            if o.status.success() {
                                let _ = common::write_atomic(&key_path(&name), key.as_bytes());
                            } else {
                                let _ = std::fs::remove_file(key_path(&name));
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
                    results.lock().expect("results lock").push((name, secs, ok));
                }
            });
        }
    });
    pb.finish_and_clear();
    let mut results = results.into_inner().expect("results");
    let order = all_jobs();
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

/// Files whose content determines every experiment's output: the code, the parameter files,
/// the lock file and the bundled font. (Seeds are constants in the code.)
fn input_files() -> Result<Vec<PathBuf>> {
    fn walk(dir: &std::path::Path, out: &mut Vec<PathBuf>) -> Result<()> {
        for entry in std::fs::read_dir(dir).with_context(|| format!("reading {}", dir.display()))? {
            let p = entry?.path();
            if p.is_dir() {
                walk(&p, out)?;
            } else {
                out.push(p);
            }
        }
        Ok(())
    }
    let root = common::root();
    let mut files = vec![root.join("Cargo.toml"), root.join("Cargo.lock")];
    for d in ["src", "experiments", "assets"] {
        walk(&root.join(d), &mut files)?;
    }
    for entry in std::fs::read_dir(root.join("data"))? {
        let p = entry?.path();
        if p.extension().is_some_and(|e| e == "toml") && !p.ends_with("claims.toml") {
            files.push(p);
        }
    }
    files.sort();
    Ok(files)
}

/// Content hash (SHA-256) of every input file, with their paths.
fn inputs_key() -> Result<String> {
    use sha2::{Digest, Sha256};
    let root = common::root();
    let mut h = Sha256::new();
    for f in input_files()? {
        h.update(
            f.strip_prefix(&root)
                .unwrap_or(&f)
                .to_string_lossy()
                .as_bytes(),
        );
        h.update([0u8]);
        h.update(std::fs::read(&f).with_context(|| format!("reading {}", f.display()))?);
        h.update([0u8]);
    }
    Ok(format!("{:x}", h.finalize()))
}

fn key_path(name: &str) -> PathBuf {
    job_dir(name).join("inputs.sha256")
}

/// An experiment is fresh when its last successful run had the same inputs and its outputs
/// (summary and book snippet) are still there.
fn is_fresh(name: &str, key: &str) -> bool {
    let same = std::fs::read_to_string(key_path(name)).is_ok_and(|k| k.trim() == key);
    let snippet = if name == CALIBRATE {
        job_dir(name).join(common::calibration_io::DEVICE_FILE)
    } else if OWN_DEVICE.iter().any(|(n, _)| *n == name) {
        common::results_root().join(name).join("numbers.md")
    } else {
        common::book_generated_root().join(name).join("numbers.md")
    };
    same && job_dir(name).join("summary.json").exists() && snippet.exists()
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
}

fn read_summary(name: &str) -> Option<SummaryIn> {
    let path = job_dir(name).join("summary.json");
    let text = std::fs::read_to_string(path).ok()?;
    serde_json::from_str(&text).ok()
}

/// Joins `data/claims.toml` with every experiment's summary.
fn write_scorecard() -> Result<Vec<Row>> {
    let claims = Claims::bundled()?;
    let values: Vec<Value> = EXPERIMENTS
        .iter()
        .filter_map(|n| read_summary(n))
        .flat_map(|s| s.values)
        .collect();
    let mut rows = score(&claims, &values)?;
    let (target_id, target_q) = endstop::paper::calibration::CALIBRATION_TARGET;
    for r in &mut rows {
        if r.set == "calibrated" && r.claim == target_id && r.quantity == target_q {
            r.note = "calibration target: fitted, not a prediction".into();
        }
    }
    common::write_atomic(
        &common::results_root().join("scorecard.json"),
        serde_json::to_string_pretty(&rows)?.as_bytes(),
    )?;
    let mut md = String::from(
        "| claim | quantity | set | paper | ours | ± | unit | tolerance | verdict | note |\n|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in &rows {
        let ours = r
            .ours
            .map(|v| common::fmt_sig(v, 4))
            .unwrap_or_else(|| "-".into());
        let unc = r
            .uncertainty
            .map(|v| common::fmt_sig(v, 2))
            .unwrap_or_default();
        let verdict = match r.verdict {
            Verdict::Reproduced => "**reproduced**",
            Verdict::Deviates => "*deviates*",
            Verdict::NotYet => "not yet",
        };
        md.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            r.claim,
            r.quantity,
            r.set,
            r.paper,
            ours,
            unc,
            r.unit,
            common::fmt_sig(r.tolerance, 2),
            verdict,
            r.note
        ));
    }
    common::write_atomic(
        &common::book_generated_root().join("scorecard.md"),
        md.as_bytes(),
    )?;
    Ok(rows)
}

/// The provenance table: experiment, parameter files, seed, commit, wall time.
fn write_provenance() -> Result<()> {
    let mut md = String::from(
        "| experiment | parameter files (set) | seed | commit | wall time (s) |\n|---|---|---|---|---|\n",
    );
    for name in all_jobs() {
        let Some(s) = read_summary(name) else {
            md.push_str(&format!("| {name} | (no results) | | | |\n"));
            continue;
        };
        let wall = std::fs::read_to_string(job_dir(name).join("timing.json"))
            .ok()
            .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
            .and_then(|v| v["wall_time_s"].as_f64())
            .map(|t| format!("{t:.2}"))
            .unwrap_or_default();
        let params: Vec<String> = s
            .params
            .iter()
            .map(|(f, l)| format!("`{f}` ({l})"))
            .collect();
        md.push_str(&format!(
            "| {name} | {} | {} | `{}` | {wall} |\n",
            params.join(", "),
            s.seed.map(|x| x.to_string()).unwrap_or_else(|| "-".into()),
            s.commit,
        ));
    }
    common::write_atomic(
        &common::book_generated_root().join("provenance.md"),
        md.as_bytes(),
    )
}
