//! The history match's files and plots (the `deviations` experiment): every run's evaluations,
//! each wave's summary and its claims' diagnostics, the 2-D projections (Parquet), the
//! projection plots, and the Markdown of the answer.

use anyhow::Result;
use endstop::num::history::Projection;
use endstop::paper::deviations::{ClaimIndices, HistoryRun, TOLERANCE_SIGMAS};
use plotters::coord::Shift;
use plotters::prelude::*;

use crate::io::frame::{frame, Cell};
use crate::io::md::Table;
use crate::io::plot::Chart;
use crate::{fmt_sig, row, Experiment};

/// Label of a prototype (`1`, `2`).
fn label(h: &HistoryRun) -> &'static str {
    &h.prototype.key()[1..]
}

/// `history_runs.parquet` (every run: its wave, its point, each quantity), `history_waves`
/// (each wave's shares and stop), `history_claims` (each wave's claims: the share they rule
/// out, the leave-one-out errors within +-2 and +-3), `history_projections` (each cell).
pub fn write_history(exp: &Experiment, runs: &[HistoryRun]) -> Result<()> {
    let mut rows = Vec::new();
    for h in runs {
        let columns = column_names(&h.factors);
        for (r, ((wave, run), evals)) in h.matcher.runs.iter().zip(&h.evaluations).enumerate() {
            for e in evals {
                let mut row = row![
                    "prototype" => h.prototype.key(),
                    "run" => r as u64,
                    "wave" => *wave as u64,
                    "claim" => e.quantity.claim,
                    "quantity" => e.quantity.quantity,
                    "outcome" => e.outcome.label(),
                    "value" => e.value,
                    "deviation" => e.deviation,
                    "ci95" => e.ci95,
                    "meets" => e.meets,
                ];
                for (f, u) in columns.iter().zip(&run.point) {
                    row.push((f, Cell::from(*u)));
                }
                rows.push(row);
            }
        }
    }
    exp.write_parquet("history_runs", &mut frame(rows)?, "within the ranges")?;
    let mut waves = Vec::new();
    let mut claims = Vec::new();
    let mut cells = Vec::new();
    for h in runs {
        let outputs = h.outputs();
        for s in &h.matcher.summaries {
            waves.push(row![
                "prototype" => h.prototype.key(),
                "wave" => s.wave as u64,
                "new_runs" => s.new_runs as u64,
                "training_runs" => s.training_runs as u64,
                "pool" => s.pool as u64,
                "non_implausible_fraction" => s.fraction(),
                "all_within_cut_fraction" => s.fraction_all(),
                "stop" => s.stop.map_or("", |s| s.label()),
            ]);
            for (j, q) in outputs.iter().enumerate() {
                let (n, w2, w3) = loo_shares(&s.loo[j]);
                claims.push(row![
                    "prototype" => h.prototype.key(),
                    "wave" => s.wave as u64,
                    "claim" => q.claim,
                    "quantity" => q.quantity,
                    "ruled_out" => s.ruled_out[j],
                    "loo_points" => n as u64,
                    "loo_within_2" => w2,
                    "loo_within_3" => w3,
                ]);
            }
            for p in &s.projections {
                for (c, (m, d)) in p
                    .min_implausibility
                    .iter()
                    .zip(&p.optical_depth)
                    .enumerate()
                {
                    let n = h.matcher.settings.cells;
                    cells.push(row![
                        "prototype" => h.prototype.key(),
                        "wave" => s.wave as u64,
                        "factor_x" => h.factors[p.i].as_str(),
                        "factor_y" => h.factors[p.j].as_str(),
                        "cell_x" => (c / n) as u64,
                        "cell_y" => (c % n) as u64,
                        "min_implausibility" => if m.is_finite() { Some(*m) } else { None },
                        "optical_depth" => if d.is_finite() { Some(*d) } else { None },
                    ]);
                }
            }
        }
    }
    exp.write_parquet("history_waves", &mut frame(waves)?, "within the ranges")?;
    exp.write_parquet("history_claims", &mut frame(claims)?, "within the ranges")?;
    exp.write_parquet(
        "history_projections",
        &mut frame(cells)?,
        "within the ranges",
    )?;
    for h in runs {
        for s in &h.matcher.summaries {
            exp.write_extra_plot(
                &format!("deviations_history_{}_wave{}", h.prototype.key(), s.wave),
                &ProjectionPlot {
                    title: format!(
                        "Prototype {}, after wave {}: least implausibility (lower left) and \
                         optical depth (upper right) over each pair of inputs",
                        label(h),
                        s.wave
                    ),
                    projections: s.projections.clone(),
                    factors: h.factors.clone(),
                    cells: h.matcher.settings.cells,
                    cut: h.matcher.settings.cut,
                },
            )?;
        }
    }
    Ok(())
}

/// The factors' names as column names of a frame (`&'static str`): leaked once per write of
/// a history, a handful of short strings, so that the columns follow the ranges file.
fn column_names(factors: &[String]) -> Vec<&'static str> {
    factors
        .iter()
        .map(|f| &*Box::leak(f.clone().into_boxed_str()))
        .collect()
}

/// (points, share within +-2, share within +-3) of leave-one-out standardised errors.
pub fn loo_shares(e: &[f64]) -> (usize, f64, f64) {
    let n = e.len();
    let within = |b: f64| e.iter().filter(|x| x.abs() <= b).count() as f64 / n.max(1) as f64;
    (n, within(2.0), within(3.0))
}

/// `sobol.parquet`: the emulated indices of every claim quantity and factor.
pub fn write_sobol(exp: &Experiment, sobols: &[(&HistoryRun, ClaimIndices)]) -> Result<()> {
    let mut rows = Vec::new();
    for (h, qs) in sobols {
        for (q, ix) in qs {
            let Some(ix) = ix else { continue };
            for (i, f) in h.factors.iter().enumerate() {
                let (fi, ti) = (ix.first[i], ix.total[i]);
                rows.push(row![
                    "prototype" => h.prototype.key(),
                    "claim" => q.claim,
                    "quantity" => q.quantity,
                    "factor" => f.as_str(),
                    "first" => fi.value,
                    "first_lo" => fi.lo,
                    "first_hi" => fi.hi,
                    "total" => ti.value,
                    "total_lo" => ti.lo,
                    "total_hi" => ti.hi,
                ]);
            }
        }
    }
    exp.write_parquet("sobol", &mut frame(rows)?, "within the ranges")?;
    Ok(())
}

/// The answer of one prototype's match, one paragraph (every number from the run).
pub fn answer_md(h: &HistoryRun) -> String {
    let Some(a) = h.answer() else {
        return String::new();
    };
    let outputs = h.outputs();
    let first = &h.matcher.summaries[0];
    let last = h.matcher.summaries.last().expect("a wave");
    // The claims that rule out most of the cube at the first wave (the whole cube).
    let mut order: Vec<usize> = (0..outputs.len()).collect();
    order.sort_by(|&a, &b| first.ruled_out[b].total_cmp(&first.ruled_out[a]));
    let top: Vec<String> = order
        .iter()
        .take(3)
        .map(|&j| {
            format!(
                "{} `{}` ({} of the cube)",
                outputs[j].claim,
                outputs[j].quantity,
                pct(first.ruled_out[j])
            )
        })
        .collect();
    let bound = 3.0 / a.pool as f64;
    let share = |f: f64| {
        if f == 0.0 {
            format!("none of the {} pool points (below {})", a.pool, pct(bound))
        } else {
            pct(f)
        }
    };
    let cut = fmt_sig(h.matcher.settings.cut, 1);
    let verdict = if a.stop == Some(endstop::num::history::Termination::Empty) {
        "**no set within the ranges is consistent with its quantitative claims**: the \
         non-implausible space emptied"
            .to_string()
    } else if a.stop == Some(endstop::num::history::Termination::TooFewRuns) {
        format!(
            "**the waves shrank the non-implausible space below what a design placed in it \
             resolves**: {} of the cube with one claim allowed to miss, {} with every claim's \
             implausibility at most {cut}; the searches around the survivors found {} points \
             with every claim within the cut, fewer than the next wave's emulators need, so \
             the match ends there",
            share(a.fraction),
            share(a.fraction_all),
            a.kept_all
        )
    } else if a.none_reproduces() {
        format!(
            "**no set within the ranges was found consistent with all its quantitative claims \
             at once**: allowing one claim to miss (the second-largest implausibility at most \
             {cut}), {} of the cube remains, but with every claim's implausibility at most {cut} \
             {}, no point found near the survivors and no run",
            share(a.fraction),
            share(a.fraction_all)
        )
    } else {
        format!(
            "**sets within the ranges remain consistent with its quantitative claims**: {} of \
             the cube ({} of the non-implausible points found, the pool's and those near them) \
             has every claim's implausibility at most {cut}; {} with one claim allowed to miss",
            share(a.fraction_all),
            a.kept_all,
            share(a.fraction),
        )
    };
    format!(
        "**Prototype {}** ({} wave{}, {} runs, {}): {}. The claims that rule out most of the \
         cube at the first wave: {}. After the last wave {} of the cube is non-implausible \
         (second-largest implausibility at most {}); {} of the {} runs meet every claim they \
         evaluate directly.\n",
        label(h),
        a.waves,
        if a.waves == 1 { "" } else { "s" },
        a.runs,
        match h.scope.ensemble_records {
            Some(r) => format!("ensemble claims by {r} records per level"),
            None => "without the ensemble claims".into(),
        },
        verdict,
        top.join(", "),
        share(last.fraction()),
        fmt_sig(h.matcher.settings.cut, 1),
        a.runs_meeting_all,
        a.runs
    )
}

fn pct(f: f64) -> String {
    format!("{} %", fmt_sig(100.0 * f, 2))
}

/// The tables of one prototype's match: waves, claims per wave, yes/no claims at the runs.
pub fn tables_md(h: &HistoryRun) -> String {
    let mut md = format!("#### Prototype {}: waves\n\n", label(h));
    let mut t = Table::new([
        "wave",
        "new runs",
        "emulators fitted to",
        "non-implausible share",
        "every claim within the cut",
        "ended",
    ]);
    for s in &h.matcher.summaries {
        t.row([
            s.wave.to_string(),
            s.new_runs.to_string(),
            format!("{} runs", s.training_runs),
            pct(s.fraction()),
            pct(s.fraction_all()),
            s.stop.map_or("-", |s| s.label()).to_string(),
        ]);
    }
    md.push_str(&t.render());
    md.push_str(&format!(
        "\n#### Prototype {}: each claim at each wave\n\nRuled out: the share of the space left \
         before the wave whose implausibility for the claim exceeds {}. Leave-one-out: the \
         share of the wave's training runs whose standardised error lies within +-2 and +-3 \
         (a right emulator has about 95 % and 99.7 %).\n\n",
        label(h),
        fmt_sig(h.matcher.settings.cut, 1)
    ));
    let mut t = Table::new([
        "wave",
        "claim",
        "quantity",
        "ruled out",
        "LOO within +-2",
        "LOO within +-3",
    ]);
    for s in &h.matcher.summaries {
        for (j, q) in h.outputs().iter().enumerate() {
            let (n, w2, w3) = loo_shares(&s.loo[j]);
            let (w2, w3) = if n == 0 {
                ("constant".to_string(), "-".to_string())
            } else {
                (pct(w2), pct(w3))
            };
            t.row([
                s.wave.to_string(),
                q.claim.to_string(),
                format!("`{}`", q.quantity),
                pct(s.ruled_out[j]),
                w2,
                w3,
            ]);
        }
    }
    md.push_str(&t.render());
    let yes_no: Vec<usize> = (0..h.quantities.len())
        .filter(|k| !h.emulated.contains(k))
        .collect();
    if !yes_no.is_empty() {
        md.push_str(&format!(
            "\n#### Prototype {}: the yes/no claims at the runs\n\nEvaluated directly at every \
             run (not emulated); a wave after the first runs inside the space its predecessors \
             left.\n\n",
            label(h)
        ));
        let mut t = Table::new(["wave", "runs", "claim", "quantity", "runs meeting it"]);
        for s in &h.matcher.summaries {
            let met = h.met_in_wave(s.wave);
            for &k in &yes_no {
                let q = h.quantities[k];
                t.row([
                    s.wave.to_string(),
                    s.new_runs.to_string(),
                    q.claim.to_string(),
                    format!("`{}`", q.quantity),
                    met[k].to_string(),
                ]);
            }
        }
        md.push_str(&t.render());
    }
    md.push('\n');
    md
}

/// The observation's variance in words (for the chapter's first line).
pub fn observation_md() -> String {
    format!(
        "each claim's tolerance counts as {} standard deviations of its observation",
        fmt_sig(TOLERANCE_SIGMAS, 1)
    )
}

/// The pairwise projections of one wave: a `d x d` matrix of panels, the least implausibility
/// below the diagonal (white at 0, dark red at twice the cut and beyond, a black frame on cells
/// at most the cut), the optical depth above it (grey level, white 0, black the largest share
/// of any cell).
pub struct ProjectionPlot {
    /// Title.
    pub title: String,
    /// The projections.
    pub projections: Vec<Projection>,
    /// The factors' names, in the order of the inputs.
    pub factors: Vec<String>,
    /// Cells per axis.
    pub cells: usize,
    /// The cut.
    pub cut: f64,
}

impl Chart for ProjectionPlot {
    fn size(&self) -> (u32, u32) {
        (1160, 1140)
    }

    fn title(&self) -> String {
        self.title.clone()
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        root.fill(&WHITE)?;
        let (left, top, panel) = (180i32, 90i32, 120i32);
        let font = ("sans-serif", 14).into_font();
        root.draw(&Text::new(self.title.clone(), (10, 10), font.clone()))?;
        // The optical depth's grey scale runs to the largest share of any cell (a thin space
        // would be white at a scale to 1).
        let depth_max = self
            .projections
            .iter()
            .flat_map(|p| p.optical_depth.iter())
            .filter(|d| d.is_finite())
            .fold(0.0f64, |m, d| m.max(*d))
            .max(1e-12);
        // With no non-implausible set anywhere the upper panels are white: say so rather than
        // quote the scale's floor.
        let depth = if depth_max > 1e-12 {
            format!(
                "share non-implausible (black: {} %, the largest of any cell)",
                fmt_sig(100.0 * depth_max, 2)
            )
        } else {
            "share non-implausible (none in any cell: all white)".to_string()
        };
        root.draw(&Text::new(
            format!(
                "below the diagonal: least implausibility (red from {} up; framed: at most {}); \
                 above: {depth}",
                fmt_sig(self.cut, 1),
                fmt_sig(self.cut, 1),
            ),
            (10, 32),
            font.clone(),
        ))?;
        for (k, f) in self.factors.iter().enumerate() {
            let name = f.replace('_', " ");
            let k = k as i32;
            root.draw(&Text::new(
                name.clone(),
                (left + k * panel + 4, top - 20 - 14 * (k % 2)),
                font.clone(),
            ))?;
            root.draw(&Text::new(
                name,
                (4, top + k * panel + panel / 2),
                font.clone(),
            ))?;
        }
        let n = self.cells as i32;
        let cw = (panel - 6) / n;
        for p in &self.projections {
            // Lower triangle: row j, column i (x = factor i, y = factor j); upper: transposed.
            for (lower, (row, col)) in [(true, (p.j, p.i)), (false, (p.i, p.j))] {
                let (x0, y0) = (left + col as i32 * panel, top + row as i32 * panel);
                for c in 0..self.cells * self.cells {
                    let (ci, cj) = ((c / self.cells) as i32, (c % self.cells) as i32);
                    // x follows the column's factor, y (upwards) the row's.
                    let (cx, cy) = if lower { (ci, cj) } else { (cj, ci) };
                    let (px, py) = (x0 + cx * cw, y0 + (n - 1 - cy) * cw);
                    let fill = if lower {
                        let m = p.min_implausibility[c];
                        if !m.is_finite() {
                            RGBColor(230, 230, 230)
                        } else {
                            let t = (m / (2.0 * self.cut)).clamp(0.0, 1.0);
                            let g = (255.0 * (1.0 - t)) as u8;
                            RGBColor(255u8.saturating_sub((100.0 * t) as u8), g, g)
                        }
                    } else {
                        let o = p.optical_depth[c];
                        if !o.is_finite() {
                            RGBColor(230, 230, 230)
                        } else {
                            let g = (255.0 * (1.0 - (o / depth_max).clamp(0.0, 1.0))) as u8;
                            RGBColor(g, g, g)
                        }
                    };
                    root.draw(&Rectangle::new(
                        [(px, py), (px + cw, py + cw)],
                        fill.filled(),
                    ))?;
                    if lower && p.min_implausibility[c] <= self.cut {
                        root.draw(&Rectangle::new([(px, py), (px + cw, py + cw)], BLACK))?;
                    }
                }
            }
        }
        Ok(())
    }
}
