//! The recorded definitive history match (`data/recorded/history/`, written by
//! `python/examples/study_dask.py --history`) in the book, by default: the chapter "Why the
//! paper deviates" opens with its answer, generated from the record's `run.json`, then shows
//! its report (`report.md`, the waves' and claims' tables) and the projections of its first and
//! last wave of each prototype, drawn from `history_projections.parquet`. The `deviations`
//! experiment (this build's reduced match) is an option with its own section.

use std::collections::BTreeMap;
use std::path::Path;

use anyhow::{anyhow, Context, Result};
use endstop::num::history::Projection;
use polars::prelude::{DataFrame, ParquetReader, SerReader};
use serde::Deserialize;

use crate::reports::history_io::ProjectionPlot;
use crate::{fmt_sig, write_atomic};

/// The record's directory, relative to the project root.
pub const RECORDED_DIR: &str = "data/recorded/history";

/// The book's directory for the record's snippets and plots (under `book/src/generated/`).
pub const BOOK_DIR: &str = "history_recorded";

/// The cut on the implausibility the record used (the history match's default,
/// `endstop::num::history`); the record's `run.json` does not store it.
const CUT: f64 = 3.0;

/// The part of `run.json` the answer reads.
#[derive(Debug, Deserialize)]
struct Run {
    date: String,
    commit: String,
    per_input: usize,
    ensemble_records: Option<usize>,
    prototypes: BTreeMap<String, PrototypeRun>,
}

#[derive(Debug, Deserialize)]
struct PrototypeRun {
    answer: Answer,
}

/// One prototype's answer as the record states it.
#[derive(Debug, Deserialize)]
struct Answer {
    stop: Option<String>,
    waves: usize,
    runs: usize,
    fraction: f64,
    fraction_all: f64,
    pool: usize,
    runs_meeting_all: usize,
    none_reproduces: bool,
}

/// Writes `answer.md`, `report.md` and the projection plots with their captions into the
/// book's `generated/history_recorded/`; where the record is missing, notes in their place say
/// so (the chapter's includes never go missing).
pub fn publish(root: &Path, book_generated: &Path) -> Result<()> {
    let src = root.join(RECORDED_DIR);
    let dst = book_generated.join(BOOK_DIR);
    let run = match std::fs::read_to_string(src.join("run.json")) {
        Ok(s) => serde_json::from_str::<Run>(&s).context("reading the record's run.json")?,
        Err(_) => {
            let note = format!(
                "*No definitive history match is recorded (`{RECORDED_DIR}/` is missing): \
                 only this build's reduced match ([below](#this-builds-reduced-match)) \
                 answers, provisionally.*\n"
            );
            write_atomic(&dst.join("answer.md"), note.as_bytes())?;
            write_atomic(&dst.join("report.md"), b"*(no record)*\n")?;
            write_atomic(&dst.join("projections.md"), b"*(no record)*\n")?;
            return Ok(());
        }
    };
    write_atomic(&dst.join("answer.md"), answer_md(&run).as_bytes())?;
    let report = std::fs::read_to_string(src.join("report.md"))
        .with_context(|| format!("reading {RECORDED_DIR}/report.md"))?;
    write_atomic(&dst.join("report.md"), report.as_bytes())?;
    let cells = read_parquet(&src.join("history_projections.parquet"))?;
    let mut md = String::new();
    for key in run.prototypes.keys() {
        let waves = waves_of(&cells, key)?;
        let (Some(first), Some(last)) = (waves.first(), waves.last()) else {
            continue;
        };
        let shown: Vec<usize> = if first == last {
            vec![*first]
        } else {
            vec![*first, *last]
        };
        for wave in shown {
            let stem = format!("history_{key}_wave{wave}");
            let plot = projection_plot(&cells, key, wave)?;
            let (svg, png) = crate::io::plot::render(&plot)?;
            write_atomic(&dst.join(format!("{stem}.svg")), svg.as_bytes())?;
            write_atomic(&dst.join(format!("{stem}.png")), &png)?;
            md.push_str(&format!(
                "![{title}](generated/{BOOK_DIR}/{stem}.svg)\n\n*{title}. Drawn by `reproduce` \
                 ([`experiments/src/pipeline/recorded_history.rs`](../../experiments/src/pipeline/recorded_history.rs)) \
                 from the record's [`history_projections.parquet`](../../{RECORDED_DIR}/history_projections.parquet).*\n\n",
                title = plot.title,
            ));
        }
    }
    write_atomic(&dst.join("projections.md"), md.as_bytes())
}

/// The chapter's opening: the verdict over all prototypes, then one line per prototype, each
/// number from the record.
fn answer_md(run: &Run) -> String {
    let n = run.prototypes.len();
    let none = run
        .prototypes
        .values()
        .all(|p| p.answer.none_reproduces && p.answer.runs_meeting_all == 0);
    let which = match n {
        1 => "for the prototype".to_string(),
        2 => "for either prototype".to_string(),
        _ => format!("for any of the {n} prototypes"),
    };
    let mut md = if none {
        format!(
            "**No parameter set within the ranges meets every claim, {which}.** The deviations \
             are not the printed parameters' alone: no change of the uncertain inputs within \
             their ranges reproduces every claim. The definitive history match (recorded {}, {} runs per input per wave, ensemble \
             claims {}) leaves no set consistent with all the quantitative claims at once, \
             and none of its runs meets every claim it evaluates directly.\n\n",
            run.date,
            run.per_input,
            run.ensemble_records
                .map_or("not evaluated".to_string(), |r| format!("by {r} records per level")),
        )
    } else {
        format!(
            "**Some parameter sets within the ranges remain consistent with the claims** (the \
             definitive history match, recorded {}): the paper's deviations may be the printed \
             parameters', not the model's.\n\n",
            run.date
        )
    };
    md.push_str(
        "| Prototype | Waves | Runs | Runs meeting all | Left, one may miss | Left, all within the cut | Ended |\n|---|---|---|---|---|---|---|\n",
    );
    for (key, p) in &run.prototypes {
        let a = &p.answer;
        let share = |f: f64| {
            if f == 0.0 {
                format!("none of {} pool points", a.pool)
            } else {
                format!("{} %", fmt_sig(100.0 * f, 2))
            }
        };
        md.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} |\n",
            key.trim_start_matches('p'),
            a.waves,
            a.runs,
            a.runs_meeting_all,
            share(a.fraction),
            share(a.fraction_all),
            a.stop.as_deref().unwrap_or("-"),
        ));
    }
    md.push_str(&format!(
        "\n*From the recorded definitive match (`{RECORDED_DIR}/run.json`, commit `{}`): its \
         report, tables and projections are [below](#the-recorded-definitive-match); the cut is \
         {} on the implausibility.*\n",
        run.commit,
        fmt_sig(CUT, 1)
    ));
    md
}

fn read_parquet(path: &Path) -> Result<DataFrame> {
    let f = std::fs::File::open(path).with_context(|| format!("opening {}", path.display()))?;
    ParquetReader::new(f)
        .finish()
        .with_context(|| format!("reading {}", path.display()))
}

/// The waves of prototype `key` that have projections, in order.
fn waves_of(cells: &DataFrame, key: &str) -> Result<Vec<usize>> {
    let protos = cells.column("prototype")?.str()?;
    let waves = cells
        .column("wave")?
        .cast(&polars::prelude::DataType::UInt64)?;
    let waves = waves.u64()?;
    let mut out: Vec<usize> = protos
        .into_iter()
        .zip(waves)
        .filter(|(p, _)| *p == Some(key))
        .filter_map(|(_, w)| w.map(|w| w as usize))
        .collect();
    out.sort_unstable();
    out.dedup();
    Ok(out)
}

/// The projection plot of one prototype's wave, rebuilt from the record's cells. The inputs'
/// order is the order in which they first appear as the first of a pair (the match writes the
/// pairs (i, j), i < j, in order).
fn projection_plot(cells: &DataFrame, key: &str, wave: usize) -> Result<ProjectionPlot> {
    let col_str = |name: &str| -> Result<Vec<Option<String>>> {
        Ok(cells
            .column(name)?
            .str()?
            .into_iter()
            .map(|s| s.map(str::to_string))
            .collect())
    };
    let col_u = |name: &str| -> Result<Vec<Option<u64>>> {
        let c = cells
            .column(name)?
            .cast(&polars::prelude::DataType::UInt64)?;
        Ok(c.u64()?.into_iter().collect())
    };
    let col_f = |name: &str| -> Result<Vec<Option<f64>>> {
        let c = cells
            .column(name)?
            .cast(&polars::prelude::DataType::Float64)?;
        Ok(c.f64()?.into_iter().collect())
    };
    let (protos, waves) = (col_str("prototype")?, col_u("wave")?);
    let (fx, fy) = (col_str("factor_x")?, col_str("factor_y")?);
    let (cx, cy) = (col_u("cell_x")?, col_u("cell_y")?);
    let (mi, od) = (col_f("min_implausibility")?, col_f("optical_depth")?);
    let rows: Vec<usize> = (0..cells.height())
        .filter(|&r| protos[r].as_deref() == Some(key) && waves[r] == Some(wave as u64))
        .collect();
    let mut factors: Vec<String> = Vec::new();
    for &r in &rows {
        for f in [&fx[r], &fy[r]].into_iter().flatten() {
            if !factors.contains(f) {
                factors.push(f.clone());
            }
        }
    }
    let n = rows
        .iter()
        .filter_map(|&r| cx[r].zip(cy[r]).map(|(a, b)| a.max(b) as usize + 1))
        .max()
        .ok_or_else(|| anyhow!("no projection cells for {key}, wave {wave}"))?;
    let index = |f: &Option<String>| -> Result<usize> {
        f.as_ref()
            .and_then(|f| factors.iter().position(|g| g == f))
            .ok_or_else(|| anyhow!("a projection cell without its inputs"))
    };
    let mut pairs: BTreeMap<(usize, usize), Projection> = BTreeMap::new();
    for &r in &rows {
        let (i, j) = (index(&fx[r])?, index(&fy[r])?);
        let p = pairs.entry((i, j)).or_insert_with(|| Projection {
            i,
            j,
            min_implausibility: vec![f64::INFINITY; n * n],
            optical_depth: vec![f64::NAN; n * n],
        });
        let (Some(a), Some(b)) = (cx[r], cy[r]) else {
            continue;
        };
        let c = a as usize * n + b as usize;
        // A missing value is an empty cell (the record writes it as null or NaN).
        p.min_implausibility[c] = mi[r].filter(|m| m.is_finite()).unwrap_or(f64::INFINITY);
        p.optical_depth[c] = od[r].unwrap_or(f64::NAN);
    }
    Ok(ProjectionPlot {
        title: format!(
            "Recorded definitive match, prototype {}, after wave {wave}: least implausibility \
             (lower left) and optical depth (upper right) over each pair of inputs",
            key.trim_start_matches('p')
        ),
        projections: pairs.into_values().collect(),
        factors,
        cells: n,
        cut: CUT,
    })
}

/// The best run of the recorded match for each prototype: the run with the smallest worst
/// |normalised deviation| over its quantitative claims.
#[derive(Debug, Clone)]
pub struct BestRun {
    /// Prototype key (`p1`, `p2`).
    pub prototype: String,
    /// Its index in the record's runs.
    pub run: u64,
    /// Its worst |normalised deviation| (in tolerances).
    pub worst: f64,
    /// Its values under the scorecard's keys
    /// ([`endstop::paper::deviations::best_value_key`]), where the quantity exists.
    pub values: BTreeMap<String, f64>,
}

/// The best run of each prototype of the recorded match (`history_runs.parquet`); empty where
/// there is no record.
pub fn best_runs(root: &Path) -> Result<Vec<BestRun>> {
    let path = root.join(RECORDED_DIR).join("history_runs.parquet");
    if !path.exists() {
        return Ok(Vec::new());
    }
    let df = read_parquet(&path)?;
    let s = |n: &str| -> Result<Vec<String>> {
        Ok(df
            .column(n)?
            .str()?
            .into_iter()
            .map(|v| v.unwrap_or_default().to_string())
            .collect())
    };
    let (proto, claim, quantity, kind, outcome) = (
        s("prototype")?,
        s("claim")?,
        s("quantity")?,
        s("kind")?,
        s("outcome")?,
    );
    let run: Vec<u64> = df
        .column("run")?
        .cast(&polars::prelude::DataType::UInt64)?
        .u64()?
        .into_iter()
        .map(|v| v.unwrap_or(u64::MAX))
        .collect();
    let f = |n: &str| -> Result<Vec<f64>> {
        Ok(df
            .column(n)?
            .cast(&polars::prelude::DataType::Float64)?
            .f64()?
            .into_iter()
            .map(|v| v.unwrap_or(f64::NAN))
            .collect())
    };
    let (value, deviation) = (f("value")?, f("deviation")?);
    // The worst |deviation| over the quantitative claims of each (prototype, run); a NaN
    // deviation (a quantity that does not exist) makes the run's worst NaN, never the best.
    let mut worst: BTreeMap<(String, u64), f64> = BTreeMap::new();
    for r in 0..df.height() {
        if kind[r] != "quantitative" {
            continue;
        }
        let w = worst.entry((proto[r].clone(), run[r])).or_insert(0.0);
        let d = deviation[r].abs();
        *w = if d.is_nan() || w.is_nan() {
            f64::NAN
        } else {
            w.max(d)
        };
    }
    let mut best: BTreeMap<String, (u64, f64)> = BTreeMap::new();
    for ((p, r), w) in &worst {
        if w.is_nan() {
            continue;
        }
        let e = best.entry(p.clone()).or_insert((*r, *w));
        if *w < e.1 {
            *e = (*r, *w);
        }
    }
    Ok(best
        .into_iter()
        .map(|(p, (r, w))| {
            let values = (0..df.height())
                .filter(|&i| proto[i] == p && run[i] == r && outcome[i] == "value")
                .filter_map(|i| {
                    endstop::paper::deviations::best_value_key(&claim[i], &quantity[i])
                        .map(|k| (k, value[i]))
                })
                .collect();
            BestRun {
                prototype: p,
                run: r,
                worst: w,
                values,
            }
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_recorded_match_answers_for_both_prototypes() {
        let dir = std::env::temp_dir().join(format!("recorded-history-{}", std::process::id()));
        publish(&crate::root(), &dir).unwrap();
        let answer = std::fs::read_to_string(dir.join(BOOK_DIR).join("answer.md")).unwrap();
        // The record's run.json says no prototype has a set meeting every claim.
        assert!(
            answer.starts_with(
                "**No parameter set within the ranges meets every claim, for either prototype.**"
            ),
            "{answer}"
        );
        let plots = std::fs::read_to_string(dir.join(BOOK_DIR).join("projections.md")).unwrap();
        assert!(plots.contains("history_p1_wave1.svg"), "{plots}");
        assert!(plots.contains("history_p2_wave3.svg"), "{plots}");
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn the_best_recorded_runs_are_the_least_deviating() {
        let best = best_runs(&crate::root()).unwrap();
        let keys: Vec<&str> = best.iter().map(|b| b.prototype.as_str()).collect();
        assert_eq!(keys, ["p1", "p2"]);
        for b in &best {
            assert!(b.worst.is_finite() && b.worst > 0.0, "{b:?}");
            // Its values are its own prototype's claims, under the scorecard's keys.
            let own = format!("calibration_{}_", b.prototype);
            assert!(!b.values.is_empty(), "{b:?}");
            assert!(b.values.keys().all(|k| k.starts_with(&own)), "{b:?}");
        }
    }
}
