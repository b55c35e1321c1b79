//! The deviations experiment's outputs (the study itself is `endstop::paper::deviations`):
//! the numbers of each prototype's history match, the values of its best run under the keys
//! the scorecard reads, the heat map of the emulators' total Sobol indices and the book's
//! numbers (the match's settings, answers, tables and the indices). The match's own files and plots are
//! [`crate::reports::history_io`]'s.

use anyhow::Result;
use endstop::num::history::Termination;
use endstop::paper::claims::Kind;
use endstop::paper::deviations::{self, ClaimIndices, HistoryRun};
use plotters::coord::Shift;
use plotters::prelude::*;

use crate::io::md::Table;
use crate::io::plot::Chart;
use crate::reports::history_io::{
    answer_md, observation_md, tables_md, write_history, write_sobol,
};
use crate::{fmt_sig, Experiment};

/// The cost of one prototype's history match: its wall time, and its processor time where
/// that is known.
pub struct Cost {
    /// Wall time of the match (s).
    pub seconds: f64,
    /// Processor time of the match (s).
    pub cpu_s: Option<f64>,
}

/// Records the numbers of one prototype's history match `h` (its waves, runs, the fraction of
/// the space left, and the values of its best run) and its `cost`.
pub fn record_match(exp: &mut Experiment, h: &HistoryRun, cost: &Cost) {
    let k = h.prototype.key();
    let a = h.answer().expect("at least one wave");
    exp.number(&format!("history_{k}_seconds"), cost.seconds);
    if let Some(cpu) = cost.cpu_s {
        exp.number(&format!("history_{k}_cpu_s_per_run"), cpu / a.runs as f64);
    }
    exp.number(&format!("history_{k}_waves"), a.waves as f64);
    exp.number(&format!("history_{k}_runs"), a.runs as f64);
    exp.number(&format!("history_{k}_fraction"), a.fraction);
    exp.number(&format!("history_{k}_fraction_all"), a.fraction_all);
    exp.number(
        &format!("history_{k}_empty"),
        f64::from(u8::from(a.stop == Some(Termination::Empty))),
    );
    exp.number(
        &format!("history_{k}_runs_meeting_all"),
        a.runs_meeting_all as f64,
    );
    best_run_numbers(exp, h);
}

/// The settings of a run of the experiment, as its command line gave them.
#[derive(Debug, Clone, Copy)]
pub struct RunSettings {
    /// Runs per input in each wave's design.
    pub per_input: usize,
    /// Most waves.
    pub waves: usize,
    /// Records per level of the ensemble claims, if they were evaluated.
    pub ensemble_records: Option<usize>,
}

/// Writes everything after the matches: the settings' numbers, the match's files, the Sobol
/// indices and their heat map and the book's numbers, then the summary. The chapter's answer is
/// the recorded definitive match's ([`crate::pipeline::recorded_history`]).
pub fn write(
    mut exp: Experiment,
    settings: RunSettings,
    runs: &[HistoryRun],
    sobols: &[(&HistoryRun, ClaimIndices)],
) -> Result<()> {
    let ensemble_records = settings.ensemble_records;
    exp.number(
        "ensemble_records",
        ensemble_records.map_or(0.0, |r| r as f64),
    );
    exp.number("history_per_input", settings.per_input as f64);
    exp.number("history_max_waves", settings.waves as f64);
    write_history(&exp, runs)?;
    write_sobol(&exp, sobols)?;
    exp.write_plot(&HeatMap::of(sobols))?;
    exp.write_numbers_md(&numbers_md(ensemble_records, runs, sobols))?;
    exp.finish()
}

/// The run of the match with the smallest worst |normalised deviation| over its quantitative
/// claims: its values under the keys the scorecard reads for "best under calibration"
/// ([`deviations::best_value_key`]).
fn best_run_numbers(exp: &mut Experiment, h: &HistoryRun) {
    let worst = |e: &[deviations::Evaluation]| {
        e.iter()
            .filter(|e| e.kind == Kind::Quantitative)
            .fold(0.0f64, |m, e| m.max(e.deviation.abs()))
    };
    let Some(best) = h
        .evaluations
        .iter()
        .min_by(|a, b| worst(a).total_cmp(&worst(b)))
    else {
        return;
    };
    exp.number(
        &format!("history_{}_best_run_worst", h.prototype.key()),
        worst(best),
    );
    for e in best {
        if let (Some(key), Some(v)) = (
            deviations::best_value_key(e.quantity.claim, e.quantity.quantity),
            e.outcome.value(),
        ) {
            exp.number(&key, v);
        }
    }
}

fn numbers_md(
    ensemble_records: Option<usize>,
    runs: &[HistoryRun],
    sobols: &[(&HistoryRun, ClaimIndices)],
) -> String {
    let s = runs.first().map(|h| h.matcher.settings).unwrap_or_default();
    let mut md = format!(
        "History match of this build: {} runs per input per wave ({} per wave), at most {} \
         wave{}, cut {} on the {} implausibility, a pool of {} points; {}; ensemble claims \
         (Figures 12, 14, 15): {}.\n\n",
        s.per_input,
        s.per_input * runs.first().map_or(0, |h| h.factors.len()),
        s.max_waves,
        if s.max_waves == 1 { "" } else { "s" },
        fmt_sig(s.cut, 1),
        if s.rank == 2 {
            "second-largest".to_string()
        } else {
            format!("{}-th largest", s.rank)
        },
        s.pool,
        observation_md(),
        match ensemble_records {
            Some(r) => format!("{r} records per level"),
            None => "not evaluated in this run (`--ensemble-records`)".into(),
        }
    );
    for h in runs {
        md.push_str(&answer_md(h));
        md.push('\n');
    }
    for h in runs {
        md.push_str(&tables_md(h));
        for w in &h.matcher.summaries {
            md.push_str(&format!(
                "{{{{#include deviations_history_{}_wave{}.figure.md}}}}\n\n",
                h.prototype.key(),
                w.wave
            ));
        }
    }
    for (h, qs) in sobols {
        md.push_str(&format!(
            "### Total Sobol indices from the emulators, prototype {}\n\nThe indices of the \
             first wave's emulator mean (a Saltelli design of 4096 base rows), and the 95 % \
             interval of the indices of its posterior draws: what the runs leave unknown.\n\n",
            &h.prototype.key()[1..]
        ));
        let mut t = Table::new([
            "claim",
            "quantity",
            "largest total index (factor)",
            "its 95 % interval",
            "second largest (factor)",
        ]);
        for (q, ix) in qs {
            let (big, ci, second) = match ix {
                Some(ix) => {
                    let mut order: Vec<usize> = (0..h.factors.len()).collect();
                    order.sort_by(|&a, &b| ix.total[b].value.total_cmp(&ix.total[a].value));
                    let (i, j) = (order[0], order[1]);
                    (
                        format!("{} ({})", fmt_sig(ix.total[i].value, 2), h.factors[i]),
                        format!(
                            "{} to {}",
                            fmt_sig(ix.total[i].lo, 2),
                            fmt_sig(ix.total[i].hi, 2)
                        ),
                        format!("{} ({})", fmt_sig(ix.total[j].value, 2), h.factors[j]),
                    )
                }
                None => ("constant over the runs".into(), "-".into(), "-".into()),
            };
            t.row([
                q.claim.to_string(),
                format!("`{}`", q.quantity),
                big,
                ci,
                second,
            ]);
        }
        md.push_str(&t.render());
        md.push('\n');
    }
    md
}

/// Claims x factors, total Sobol index as a grey level (white 0, black 1).
struct HeatMap {
    factors: Vec<String>,
    rows: Vec<String>,
    cells: Vec<Vec<Option<f64>>>,
}

impl HeatMap {
    fn of(runs: &[(&HistoryRun, ClaimIndices)]) -> Self {
        let mut rows = Vec::new();
        let mut cells = Vec::new();
        for (h, qs) in runs {
            for (q, ix) in qs {
                rows.push(format!("{} {} {}", h.prototype.key(), q.claim, q.quantity));
                cells.push(match ix {
                    Some(ix) => ix.total.iter().map(|t| Some(t.value)).collect(),
                    None => vec![None; h.factors.len()],
                });
            }
        }
        let factors = runs.first().map_or(Vec::new(), |(h, _)| h.factors.clone());
        Self {
            factors,
            rows,
            cells,
        }
    }
}

impl Chart for HeatMap {
    fn size(&self) -> (u32, u32) {
        (1100, 120 + 34 * self.rows.len() as u32)
    }

    fn title(&self) -> String {
        "Total Sobol index of each claim quantity (rows) for each factor (columns), from the emulators".into()
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        root.fill(&WHITE)?;
        let (left, top, cw, ch) = (380i32, 90i32, 88i32, 34i32);
        let font = ("sans-serif", 15).into_font();
        for (j, f) in self.factors.iter().enumerate() {
            let x = left + j as i32 * cw + 4;
            root.draw(&Text::new(
                f.replace('_', " "),
                (x, top - 22 - 14 * (j as i32 % 2)),
                font.clone(),
            ))?;
        }
        for (i, (label, row)) in self.rows.iter().zip(&self.cells).enumerate() {
            let y = top + i as i32 * ch;
            root.draw(&Text::new(label.clone(), (8, y + 9), font.clone()))?;
            for (j, v) in row.iter().enumerate() {
                let x = left + j as i32 * cw;
                let fill = match v {
                    Some(t) => {
                        let g = (255.0 * (1.0 - t.clamp(0.0, 1.0))).round() as u8;
                        RGBColor(g, g, 255u8.saturating_sub((255 - g) / 3))
                    }
                    None => RGBColor(230, 230, 230),
                };
                root.draw(&Rectangle::new(
                    [(x, y), (x + cw - 2, y + ch - 2)],
                    fill.filled(),
                ))?;
                let text = v.map_or("-".to_string(), |t| format!("{t:.2}"));
                let colour = if v.is_some_and(|t| t > 0.55) {
                    WHITE
                } else {
                    BLACK
                };
                root.draw(&Text::new(
                    text,
                    (x + 24, y + 9),
                    font.clone().color(&colour),
                ))?;
            }
        }
        Ok(())
    }
}
