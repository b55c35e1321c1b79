//! The scorecard: `data/claims.toml` joined with every scored experiment's summary, with the
//! fold beside each jump claim and the best calibrated value beside each claim the deviations
//! study evaluates, written as `data/results/scorecard.json` and the book's table; and the
//! readers of the experiments' summaries the pipeline shares.

use anyhow::Result;
use endstop::paper::claims::{score, Claims, Row, Value, Verdict};
use endstop::paper::setups::ParamSet;
use serde::Deserialize;

use crate::pipeline::jobs::{experiment_dir, Job, JOBS};

/// What the pipeline reads of an experiment's `summary.json`.
#[derive(Deserialize)]
pub(crate) struct SummaryIn {
    /// Its claim values.
    #[serde(default)]
    pub(crate) values: Vec<Value>,
    /// The commit it ran at.
    #[serde(default)]
    pub(crate) commit: String,
    /// Its seed, if it draws random numbers.
    #[serde(default)]
    pub(crate) seed: Option<u64>,
    /// The parameter files it read, each with its set's label.
    #[serde(default)]
    pub(crate) params: Vec<(String, String)>,
    /// A number that is not finite (a reduced chi-square without a noise level) is `null`.
    #[serde(default)]
    pub(crate) numbers: std::collections::BTreeMap<String, Option<f64>>,
}

fn read_summary(job: &Job) -> Option<SummaryIn> {
    read_json(&job.dir().join("summary.json"))
}

/// The summary of an experiment that a job writes besides its own.
fn read_experiment_summary(name: &str) -> Option<SummaryIn> {
    read_json(&experiment_dir(name).join("summary.json"))
}

/// A JSON file's contents; None when it is missing or does not parse (a job that has not run).
pub(crate) fn read_json<T: serde::de::DeserializeOwned>(path: &std::path::Path) -> Option<T> {
    serde_json::from_str(&std::fs::read_to_string(path).ok()?).ok()
}

/// Joins `data/claims.toml` with every experiment's summary.
pub fn write_scorecard() -> Result<Vec<Row>> {
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
    let folds = crate::pipeline::jobs::job("response")
        .and_then(read_summary)
        .map(|s| s.numbers)
        .unwrap_or_default();
    for r in &mut rows {
        r.fold_hz = endstop::paper::response::fold_key(&r.claim, &r.quantity, r.set)
            .and_then(|k| folds.get(&k).copied().flatten());
    }
    // Beside each claim the history match evaluates, its value at the match's best run (the
    // smallest worst normalised deviation over the prototype's quantitative claims): of the
    // recorded definitive match, else of this build's reduced match if `just deviations` ran.
    let recorded = crate::pipeline::recorded_history::best_runs(&crate::root())?;
    let (best, best_source) = if recorded.is_empty() {
        (
            read_summary(&crate::pipeline::jobs::DEVIATIONS)
                .map(|s| s.numbers)
                .unwrap_or_default(),
            BestSource::Reduced,
        )
    } else {
        (
            recorded
                .iter()
                .flat_map(|b| b.values.iter().map(|(k, v)| (k.clone(), Some(*v))))
                .collect(),
            BestSource::Recorded(recorded),
        )
    };
    for r in rows.iter_mut().filter(|r| r.set == ParamSet::Published) {
        r.best_calibrated = endstop::paper::deviations::best_value_key(&r.claim, &r.quantity)
            .and_then(|k| best.get(&k).copied().flatten());
    }
    crate::write_atomic(
        &crate::results_root().join("scorecard.json"),
        serde_json::to_string_pretty(&rows)?.as_bytes(),
    )?;
    // The tally opens the chapter (its own snippet); the table's source note precedes it.
    crate::write_atomic(
        &crate::book_generated_root().join("scorecard_tally.md"),
        tally_md(&rows).as_bytes(),
    )?;
    let mut md = best_source.md();
    md.push_str(
        "| claim | quantity | set | paper | ours | ± | unit | tolerance | verdict | fold (Hz) | best under calibration | note |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in &rows {
        let ours = r
            .ours
            .map(|v| crate::fmt_sig(v.to_f64(), 4))
            .unwrap_or_else(|| "-".into());
        let unc = r
            .uncertainty
            .map(|v| crate::fmt_sig(v, 2))
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
            .map(|v| crate::fmt_sig(v, 4))
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
            crate::fmt_sig(r.tolerance, 2),
            verdict,
            fold,
            best,
            r.note
        ));
    }
    crate::write_atomic(
        &crate::book_generated_root().join("scorecard.md"),
        md.as_bytes(),
    )?;
    Ok(rows)
}

/// Where the column "best under calibration" comes from.
enum BestSource {
    /// The recorded definitive history match's best runs.
    Recorded(Vec<crate::pipeline::recorded_history::BestRun>),
    /// This build's reduced match (`just deviations`), if it ran.
    Reduced,
}

impl BestSource {
    /// A paragraph saying so, before the table.
    fn md(&self) -> String {
        match self {
            BestSource::Recorded(best) => {
                let runs: Vec<String> = best
                    .iter()
                    .map(|b| {
                        format!(
                            "prototype {}: run {}, whose worst claim misses by {} tolerances",
                            b.prototype.trim_start_matches('p'),
                            b.run,
                            crate::fmt_sig(b.worst, 2)
                        )
                    })
                    .collect();
                format!(
                    "The column \"best under calibration\" gives, for each claim the history match \
                     evaluates, its value at the best run of the [recorded definitive \
                     match](why_deviates.md#the-recorded-definitive-match): the run with the \
                     smallest worst normalised deviation over the prototype's quantitative \
                     claims ({}). Empty: a claim the match does not evaluate, or a quantity that \
                     does not exist at that run (no fold, no grazing).\n\n",
                    runs.join("; ")
                )
            }
            BestSource::Reduced => "The column \"best under calibration\" gives the value at the \
                 best run of this build's reduced history match, where `just deviations` has \
                 run (no definitive match is recorded); empty otherwise.\n\n"
                .to_string(),
        }
    }
}

/// The tally line: the verdicts' counts for each parameter set.
pub fn tally_md(rows: &[Row]) -> String {
    let mut sets: Vec<ParamSet> = Vec::new();
    for r in rows {
        if !sets.contains(&r.set) {
            sets.push(r.set);
        }
    }
    let parts: Vec<String> = sets
        .iter()
        .map(|set| {
            let of = |v: Verdict| {
                rows.iter()
                    .filter(|r| r.set == *set && r.verdict == v)
                    .count()
            };
            let n = rows.iter().filter(|r| r.set == *set).count();
            let mut s = format!(
                "**{set}** set: {} of {n} rows reproduced, {} deviate",
                of(Verdict::Reproduced),
                of(Verdict::Deviates)
            );
            for (v, label) in [
                (Verdict::NotYet, "not yet"),
                (Verdict::Open, "open questions"),
            ] {
                if of(v) > 0 {
                    s.push_str(&format!(", {} {label}", of(v)));
                }
            }
            s
        })
        .collect();
    format!("{}.\n\n", parts.join("; "))
}

/// Prints the count of each verdict to standard error.
pub fn eprint_counts(rows: &[Row]) {
    let count = |v: Verdict| rows.iter().filter(|r| r.verdict == v).count();
    eprintln!(
        "\nscorecard: {} reproduced, {} deviates, {} not yet ({} rows) -> data/results/scorecard.json",
        count(Verdict::Reproduced),
        count(Verdict::Deviates),
        count(Verdict::NotYet),
        rows.len()
    );
}
