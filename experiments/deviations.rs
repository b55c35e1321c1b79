//! Why the paper deviates (the edge; the study itself is `endstop::paper::deviations`): the
//! history match of each prototype's claims over the ranges of `data/sensitivity.toml`, in
//! waves of runs with Gaussian-process emulators of every quantitative claim, and the Sobol
//! indices of every claim from the first wave's emulators with their uncertainty. Writes the
//! runs, waves, claims' diagnostics, projections and indices (Parquet), the projection plots,
//! the heat map of the indices, `summary.json`, and the book's numbers under
//! `data/results/deviations/`. Not part of `reproduce` (run `just deviations`); skipped when its
//! inputs are unchanged since its last run, unless `--force`.

use endstop_experiments as common;

use anyhow::Result;
use clap::Parser;
use common::reports::deviations_io::{self, Cost, RunSettings};
use common::Experiment;
use endstop::num::gp_sensitivity::EmulatedSobol;
use endstop::num::history::HistorySettings;
use endstop::paper::claims::Claims;
use endstop::paper::deviations::{self, Prototype, RangesFile, Scope};

#[derive(Parser, Debug)]
struct Args {
    /// Runs per input in each wave's design (8 inputs; the definitive match uses 10).
    #[arg(long, default_value_t = 3)]
    per_input: usize,
    /// Most waves (the match also ends when the space empties or stops shrinking).
    #[arg(long, default_value_t = 1)]
    waves: usize,
    /// Points of the uniform pool that measures the space (a power of two).
    #[arg(long, default_value_t = 1 << 13)]
    pool: usize,
    /// Also the ensemble claims (Figures 12, 14 and 15) with this many records per level (the
    /// figures use 32); each run then costs tens of 10 s records.
    #[arg(long)]
    ensemble_records: Option<usize>,
    /// `p1`, `p2` or `both`.
    #[arg(long, default_value = "both")]
    prototype: String,
    /// Rerun even when the inputs are unchanged.
    #[arg(long)]
    force: bool,
}

fn main() {
    common::run_main("deviations", run);
}

fn run() -> Result<()> {
    let args = Args::parse();
    let job = &common::pipeline::jobs::DEVIATIONS;
    let key = common::pipeline::freshness::key(job)?;
    if !args.force && common::pipeline::freshness::is_fresh(job, &key) {
        eprintln!(
            "[deviations] skipped: inputs unchanged since its last run (use --force to rerun)"
        );
        return Ok(());
    }
    let protos: Vec<Prototype> = match args.prototype.as_str() {
        "p1" => vec![Prototype::P1],
        "p2" => vec![Prototype::P2],
        "both" => Prototype::BOTH.to_vec(),
        other => anyhow::bail!("--prototype {other}: must be p1, p2 or both"),
    };
    let mut exp = Experiment::start("deviations");
    let p1 = exp.load_published("prototype1")?;
    let p2 = exp.load_published("prototype2")?;
    let claims = Claims::bundled()?;
    let ranges = RangesFile::bundled()?;
    let scope = Scope {
        ensemble_records: args.ensemble_records,
    };
    let settings = HistorySettings {
        per_input: args.per_input,
        max_waves: args.waves,
        pool: args.pool,
        seed: deviations::STUDY_SEED,
        ..HistorySettings::default()
    };
    let sobol = EmulatedSobol {
        seed: deviations::STUDY_SEED,
        ..EmulatedSobol::default()
    };
    let mut runs = Vec::new();
    for proto in protos {
        let (r, dev) = match proto {
            Prototype::P1 => (&ranges.prototype1, &p1.device),
            Prototype::P2 => (&ranges.prototype2, &p2.device),
        };
        let (t0, cpu0) = (std::time::Instant::now(), common::cpu_time_s());
        let most = settings.per_input * r.len() * settings.max_waves;
        let h = common::with_progress(most, &format!("history match {}", proto.key()), |tick| {
            deviations::history_match(proto, r, dev, &claims, scope, settings, tick)
        })?;
        let cost = Cost {
            seconds: t0.elapsed().as_secs_f64(),
            cpu_s: cpu0.zip(common::cpu_time_s()).map(|(c0, c1)| c1 - c0),
        };
        deviations_io::record_match(&mut exp, &h, &cost);
        runs.push(h);
    }
    let sobols = runs
        .iter()
        .map(|h| Ok((h, h.sobol(sobol)?)))
        .collect::<Result<Vec<_>>>()?;
    let run_settings = RunSettings {
        per_input: args.per_input,
        waves: args.waves,
        ensemble_records: args.ensemble_records,
    };
    deviations_io::write(exp, run_settings, &runs, &sobols)?;
    common::pipeline::freshness::mark_done(job, &key)?;
    Ok(())
}
