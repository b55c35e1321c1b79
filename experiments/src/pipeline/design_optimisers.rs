//! The Design chapter's choice of optimiser, read from the recorded comparison of the kept
//! search against CMA-ES (`data/recorded/design-optimisers/runs.csv`, written by the library's
//! example `design_optimisers`): per problem and optimiser, how many seeds reach a feasible
//! design within 1 % of the brute-force grid's best, the median evaluations and wall time to
//! get there with their range over the seeds, and the sentence that states the choice, every
//! number from the recording. Nothing is run here.

use std::path::Path;

use anyhow::{bail, Context, Result};

use crate::io::md::Table;
use crate::{fmt_sig, write_atomic};

/// The recording, relative to the repository's root.
pub const RECORDED: &str = "data/recorded/design-optimisers/runs.csv";
/// The file the chapter includes, in the book's `generated/own_device/`.
pub const STEM: &str = "design_optimisers";
/// The kept search's name in the recording.
const KEPT: &str = "sobol_nelder_mead";

/// One run of the recording.
#[derive(Debug, Clone, PartialEq)]
pub struct Run {
    /// The problem.
    pub case: String,
    /// The optimiser.
    pub optimiser: String,
    /// Evaluations and wall time (s) to the target, `None` where the run never reached it.
    pub to_target: Option<(usize, f64)>,
    /// Evaluations in all.
    pub evals: usize,
    /// The run's best feasible power over the grid's best (NaN where it found none).
    pub best_over_grid: f64,
}

/// The recording's runs and its comment lines (`#`, the command that made it and where).
pub fn parse(text: &str) -> Result<(Vec<Run>, Vec<String>)> {
    let mut runs = Vec::new();
    let mut comments = Vec::new();
    let mut header = false;
    for line in text.lines().map(str::trim).filter(|l| !l.is_empty()) {
        if let Some(c) = line.strip_prefix('#') {
            comments.push(c.trim().to_string());
            continue;
        }
        if !header {
            header = true;
            continue;
        }
        let f: Vec<&str> = line.split(',').collect();
        if f.len() != 9 {
            bail!(
                "{RECORDED}: a row of {} fields, 9 expected: {line}",
                f.len()
            );
        }
        let to_target = match (f[3], f[4]) {
            ("", _) | (_, "") => None,
            (n, t) => Some((n.parse()?, t.parse()?)),
        };
        runs.push(Run {
            case: f[0].to_string(),
            optimiser: f[1].to_string(),
            to_target,
            evals: f[5].parse()?,
            best_over_grid: f[7].parse::<f64>()? / f[8].parse::<f64>()?,
        });
    }
    Ok((runs, comments))
}

/// The median of `v` (the lower of the middle two) with the smallest and largest; `None`
/// where any run missed the target past the middle (the median run did not reach it).
fn median_range<T: Copy + PartialOrd>(v: &[Option<T>]) -> Option<(T, T, T)> {
    let mut got: Vec<T> = v.iter().flatten().copied().collect();
    got.sort_by(|a, b| a.partial_cmp(b).unwrap_or(std::cmp::Ordering::Equal));
    let mid = (v.len().max(1) - 1) / 2;
    Some((*got.get(mid)?, *got.first()?, *got.last()?))
}

/// The table and the choice, as markdown.
pub fn render(runs: &[Run], comments: &[String]) -> Result<String> {
    let mut cases: Vec<&str> = Vec::new();
    for r in runs {
        if !cases.contains(&r.case.as_str()) {
            cases.push(&r.case);
        }
    }
    if cases.is_empty() {
        bail!("{RECORDED}: no runs");
    }
    let mut table = Table::new([
        "problem",
        "optimiser",
        "seeds reaching 1 %",
        "evaluations to 1 %: median (range)",
        "wall time to 1 % [s]: median (range)",
        "evaluations in all: median",
        "its best over the grid's: median (range)",
    ]);
    let mut kept_wins = Vec::new();
    let mut cmaes_wins = Vec::new();
    // The median evaluations in all per problem, the kept search's then CMA-ES's.
    let mut totals: Vec<(usize, usize)> = Vec::new();
    for case in &cases {
        let mut medians = Vec::new();
        let mut total = Vec::new();
        for opt in [KEPT, "cmaes"] {
            let of: Vec<&Run> = runs
                .iter()
                .filter(|r| r.case == *case && r.optimiser == opt)
                .collect();
            if of.is_empty() {
                bail!("{RECORDED}: no `{opt}` runs of `{case}`");
            }
            let n: Vec<Option<usize>> = of.iter().map(|r| r.to_target.map(|x| x.0)).collect();
            let t: Vec<Option<f64>> = of.iter().map(|r| r.to_target.map(|x| x.1)).collect();
            let all: Vec<Option<usize>> = of.iter().map(|r| Some(r.evals)).collect();
            let ratio: Vec<Option<f64>> = of
                .iter()
                .map(|r| Some(r.best_over_grid).filter(|x| x.is_finite()))
                .collect();
            let reached = n.iter().flatten().count();
            let n_med = median_range(&n);
            medians.push(n_med.map(|m| m.0));
            total.push(median_range(&all).map_or(0, |m| m.0));
            table.row([
                format!("`{case}`"),
                if opt == KEPT {
                    "Sobol + Nelder-Mead (kept)".to_string()
                } else {
                    "CMA-ES".to_string()
                },
                format!("{reached} of {}", of.len()),
                n_med.map_or("not reached".into(), |(m, a, b)| {
                    format!("{m} ({a} to {b})")
                }),
                median_range(&t).map_or("not reached".into(), |(m, a, b)| {
                    format!("{} ({} to {})", fmt_sig(m, 2), fmt_sig(a, 2), fmt_sig(b, 2))
                }),
                median_range(&all).map_or("-".into(), |m| m.0.to_string()),
                median_range(&ratio)
                    .map_or("-".into(), |(m, a, b)| format!("{m:.4} ({a:.4} to {b:.4})")),
            ]);
        }
        totals.push((total[0], total[1]));
        match (medians[0], medians[1]) {
            (Some(k), Some(c)) if k <= c => kept_wins.push(*case),
            (Some(_), None) => kept_wins.push(*case),
            (_, Some(_)) => cmaes_wins.push(*case),
            _ => {}
        }
    }
    let names = |v: &[&str]| {
        v.iter()
            .map(|c| format!("`{c}`"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let span = |f: fn(&(usize, usize)) -> usize| {
        let lo = totals.iter().map(f).min().unwrap_or(0);
        let hi = totals.iter().map(f).max().unwrap_or(0);
        if lo == hi {
            lo.to_string()
        } else {
            format!("{lo} to {hi}")
        }
    };
    let ends = format!(
        "To its end the kept search takes {} evaluations (median per problem), CMA-ES {}.",
        span(|t| t.0),
        span(|t| t.1)
    );
    let choice = if cmaes_wins.is_empty() {
        format!(
            "The kept search reaches the target in no more evaluations than CMA-ES (median over \
             the seeds) on every problem measured ({}), so it stays the library's search, and \
             CMA-ES stays out of its dependencies. {ends}",
            names(&kept_wins)
        )
    } else if kept_wins.is_empty() {
        format!(
            "CMA-ES reaches the target in fewer evaluations (median over the seeds) on every \
             problem measured ({}): the measurement favours it over the kept search. {ends}",
            names(&cmaes_wins)
        )
    } else {
        format!(
            "Neither wins everywhere: the kept search reaches the target in no more evaluations \
             (median over the seeds) on {}, CMA-ES in fewer on {}. {ends} With no clear gain in \
             reaching the target, and a search that ends sooner, the kept search stays the \
             library's, and CMA-ES stays out of its dependencies (the last column compares \
             where each ends).",
            names(&kept_wins),
            names(&cmaes_wins)
        )
    };
    let mut md = format!("{}\n{choice}\n", table.render());
    if !comments.is_empty() {
        md.push_str(&format!(
            "\n*Recorded in [`{RECORDED}`](../../{RECORDED}): {}*\n",
            comments.join("; ")
        ));
    }
    Ok(md)
}

/// Writes `generated/own_device/design_optimisers.md` under `dst` from the recording under
/// `root`.
pub fn publish(root: &Path, dst: &Path) -> Result<()> {
    let path = root.join(RECORDED);
    let text = std::fs::read_to_string(&path).with_context(|| format!("{}", path.display()))?;
    let (runs, comments) = parse(&text)?;
    write_atomic(
        &dst.join(format!("{STEM}.md")),
        render(&runs, &comments)?.as_bytes(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = "# made by: a command\n\
        case,optimiser,seed,evals_to_target,wall_s_to_target,evals,wall_s,best_feasible_w,grid_best_w\n\
        a,sobol_nelder_mead,0,30,1.0,100,3.0,1e-3,1e-3\n\
        a,sobol_nelder_mead,1,50,2.0,100,3.0,1e-3,1e-3\n\
        a,cmaes,1,60,2.0,60,2.0,1e-3,1e-3\n\
        a,cmaes,2,,,358,9.0,9e-4,1e-3\n";

    #[test]
    fn a_run_that_never_reached_the_target_counts_as_unreached() {
        let (runs, comments) = parse(TEXT).unwrap();
        assert_eq!(comments, vec!["made by: a command".to_string()]);
        assert_eq!(runs.len(), 4);
        assert_eq!(runs[3].to_target, None);
        let md = render(&runs, &comments).unwrap();
        assert!(md.contains("| 1 of 2 |"), "{md}");
        // The kept search's median is 30 (the lower middle), CMA-ES's 60: the kept one wins.
        assert!(md.contains("30 (30 to 50)"), "{md}");
        assert!(md.contains("stays the library's search"), "{md}");
    }
}
