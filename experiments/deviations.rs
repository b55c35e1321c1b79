//! Why the paper deviates (the edge; the study itself is `endstop::paper::deviations`): Sobol
//! first-order and total indices of every claim quantity the fast paths evaluate, per
//! prototype, over the ranges of `data/sensitivity.toml`, and the multi-claim calibration of
//! each prototype (the set inside the ranges that minimises the worst normalised deviation).
//! Writes `sobol.parquet`, `calibration.parquet`, the heat map and `summary.json` under
//! `data/results/deviations/`, and the book's numbers. Not part of `reproduce` (run `just deviations`);
//! skipped when its inputs are unchanged since its last run, unless `--force`.

use endstop_experiments as common;

use anyhow::Result;
use clap::Parser;
use common::md::Table;
use common::plot::{Figure, LinePlot, Series, Style, PALETTE};
use common::{fmt_sig, frame::frame, row, Experiment};
use endstop::num::minimax::MinimaxSettings;
use endstop::paper::claims::{Claims, Kind};
use endstop::paper::deviations::{
    self, MultiClaimCalibration, Pareto, Prototype, Scope, SobolDesign, SobolRun,
};
use endstop::paper::deviations::{Factor, RangesFile};
use plotters::coord::Shift;
use plotters::prelude::*;

/// Sobol indices and the multi-claim calibration of both prototypes.
#[derive(Parser, Debug)]
struct Args {
    /// Base rows of the Saltelli design (a power of two): N (d + 2) = 10 N evaluations each.
    #[arg(long, default_value_t = 8)]
    base: usize,
    /// Starts of the minimax calibration.
    #[arg(long, default_value_t = 2)]
    starts: usize,
    /// Nelder-Mead iterations per start.
    #[arg(long, default_value_t = 40)]
    iters: u64,
    /// Also evaluate the ensemble claims (Figures 12, 14 and 15) with this many records per
    /// level (the figures use 32); each point then costs tens of 10 s records, beyond the
    /// default's ten minutes on 2 cores.
    #[arg(long)]
    ensemble_records: Option<usize>,
    /// Rerun even when the inputs are unchanged.
    #[arg(long)]
    force: bool,
}

fn main() {
    common::run_main("deviations", run);
}

fn run() -> Result<()> {
    let args = Args::parse();
    let job = &common::jobs::DEVIATIONS;
    let key = common::freshness::key(job)?;
    if !args.force && common::freshness::is_fresh(job, &key) {
        eprintln!(
            "[deviations] skipped: inputs unchanged since its last run (use --force to rerun)"
        );
        return Ok(());
    }
    let mut exp = Experiment::start("deviations");
    let p1 = exp.load_published("prototype1")?;
    let p2 = exp.load_published("prototype2")?;
    let claims = Claims::bundled()?;
    let ranges = RangesFile::bundled()?;
    let boot = deviations::STUDY_BOOTSTRAP;
    let minimax = MinimaxSettings {
        starts: args.starts,
        max_iters: args.iters,
        seed: deviations::STUDY_SEED,
        ..MinimaxSettings::default()
    };
    let cases = [
        (Prototype::P1, &ranges.prototype1, &p1.device),
        (Prototype::P2, &ranges.prototype2, &p2.device),
    ];
    let scope = Scope {
        ensemble_records: args.ensemble_records,
    };
    let mut sobols = Vec::new();
    let mut cals = Vec::new();
    for (proto, r, dev) in cases {
        let t0 = std::time::Instant::now();
        let points = args.base * (Factor::ALL.len() + 2);
        let s = common::with_progress(points, &format!("sobol {}", proto.key()), |tick| {
            let design = SobolDesign {
                base_rows: args.base,
                seed: deviations::STUDY_SEED,
                bootstrap: boot,
                scope,
            };
            deviations::sobol(proto, r, dev, design, &claims, tick)
        })?;
        let sobol_s = t0.elapsed().as_secs_f64();
        let t0 = std::time::Instant::now();
        let evals = ((args.starts as u64 + 1) * (args.iters + 10)) as usize;
        let c = common::with_progress(evals, &format!("calibrate {}", proto.key()), |tick| {
            deviations::calibrate(proto, r, dev, minimax, &claims, scope, tick)
        })?;
        let cal_s = t0.elapsed().as_secs_f64();
        let k = proto.key();
        exp.number(&format!("sobol_{k}_points"), points as f64);
        exp.number(&format!("sobol_{k}_seconds"), sobol_s);
        exp.number(&format!("calibration_{k}_seconds"), cal_s);
        exp.number(&format!("calibration_{k}_worst"), c.worst());
        exp.number(
            &format!("calibration_{k}_meets_all"),
            f64::from(u8::from(c.meets_all())),
        );
        exp.number(
            &format!("calibration_{k}_met"),
            c.best.iter().filter(|e| e.meets).count() as f64,
        );
        exp.number(&format!("calibration_{k}_claims"), c.best.len() as f64);
        exp.number(
            &format!("calibration_{k}_failures"),
            c.fits.iter().map(|f| f.failures).sum::<usize>() as f64,
        );
        for (f, u) in Factor::ALL.iter().zip(&c.fits[0].point) {
            exp.number(&format!("calibration_{k}_{}_unit", f.key()), *u);
        }
        for e in &c.best {
            exp.number(
                &format!(
                    "calibration_{k}_{}_{}_deviation",
                    e.quantity.claim, e.quantity.quantity
                ),
                e.deviation,
            );
            if let (Some(key), Some(v)) = (
                deviations::best_value_key(e.quantity.claim, e.quantity.quantity),
                e.outcome.value(),
            ) {
                exp.number(&key, v);
            }
        }
        sobols.push(s);
        cals.push(c);
    }
    let paretos: Vec<Pareto> = sobols
        .iter()
        .filter_map(deviations::most_conflicting)
        .collect();
    for p in &paretos {
        let k = p.prototype.key();
        exp.number(&format!("pareto_{k}_conflict"), p.conflict);
        exp.number(&format!("pareto_{k}_front_points"), p.front.len() as f64);
    }
    exp.number(
        "ensemble_records",
        args.ensemble_records.map_or(0.0, |r| r as f64),
    );
    exp.number("sobol_base_rows", args.base as f64);
    exp.number("calibration_starts", args.starts as f64);
    exp.number("calibration_max_iters", args.iters as f64);
    write_sobol(&exp, &sobols)?;
    write_calibration(&exp, &cals)?;
    write_pareto(&exp, &sobols, &paretos)?;
    exp.write_plot(&HeatMap::of(&sobols))?;
    exp.write_numbers_md(&numbers_md(&args, &sobols, &cals, &paretos, &claims))?;
    exp.finish()?;
    common::freshness::mark_done(job, &key)?;
    Ok(())
}

fn write_sobol(exp: &Experiment, runs: &[SobolRun]) -> Result<()> {
    let mut rows = Vec::new();
    for r in runs {
        for q in &r.quantities {
            for (i, f) in Factor::ALL.iter().enumerate() {
                let (fi, ti) = match &q.indices {
                    Some(ix) => (ix.first[i], ix.total[i]),
                    None => continue,
                };
                rows.push(row![
                    "prototype" => r.prototype.key(),
                    "claim" => q.quantity.claim,
                    "quantity" => q.quantity.quantity,
                    "factor" => f.key(),
                    "first" => fi.value,
                    "first_lo" => fi.lo,
                    "first_hi" => fi.hi,
                    "total" => ti.value,
                    "total_lo" => ti.lo,
                    "total_hi" => ti.hi,
                    "absent_share" => q.absent_share,
                    "no_fold_share" => q.no_fold_share,
                    "no_grazing_share" => q.no_grazing_share,
                    "failed_share" => q.failed_share,
                ]);
            }
        }
    }
    exp.write_parquet("sobol", &mut frame(rows)?, "published ranges")?;
    Ok(())
}

/// The Pareto front of each prototype's most conflicting pair: every design point with its
/// two |deviations| and whether it is on the front (`pareto.parquet`), and a plot of both.
fn write_pareto(exp: &Experiment, runs: &[SobolRun], paretos: &[Pareto]) -> Result<()> {
    let mut rows = Vec::new();
    for p in paretos {
        let run = runs
            .iter()
            .find(|r| r.prototype == p.prototype)
            .expect("a Pareto front comes from a run");
        for (i, &(a, b)) in p.points.iter().enumerate() {
            let mut r = row![
                "prototype" => p.prototype.key(),
                "claim_a" => p.pair.0.claim,
                "quantity_a" => p.pair.0.quantity,
                "claim_b" => p.pair.1.claim,
                "quantity_b" => p.pair.1.quantity,
                "abs_deviation_a" => a,
                "abs_deviation_b" => b,
                "on_front" => p.front.contains(&i),
            ];
            // One column per factor, named by its key: the point's unit-cube coordinate.
            for (f, u) in Factor::ALL.iter().zip(&run.design.points()[i]) {
                r.push((f.key(), (*u).into()));
            }
            rows.push(r);
        }
    }
    exp.write_parquet("pareto", &mut frame(rows)?, "published ranges")?;
    for p in paretos {
        let front: Vec<(f64, f64)> = p.front.iter().map(|&i| p.points[i]).collect();
        let label = |q: &deviations::Quantity| format!("{} {}", q.claim, q.quantity);
        let plot = LinePlot::new(
            &format!(
                "Prototype {}: the most conflicting pair of claims over the design \
                 (deviations above 10 on the edge)",
                &p.prototype.key()[1..]
            ),
            &format!("|deviation| / tolerance, {}", label(&p.pair.0)),
            &format!("|deviation| / tolerance, {}", label(&p.pair.1)),
            vec![
                Series::new("design points", p.points.clone(), PALETTE[0], Style::Points),
                Series::new("Pareto front", front, PALETTE[3], Style::LinePoints),
                Series::new(
                    "tolerance (|deviation| = 1)",
                    vec![(1.0, 0.0), (1.0, 1.0), (0.0, 1.0)],
                    PALETTE[2],
                    Style::Line,
                ),
            ],
        )
        .x(0.0, 10.0)
        .y(0.0, 10.0);
        exp.write_extra_plot(&format!("deviations_pareto_{}", p.prototype.key()), &plot)?;
    }
    Ok(())
}

fn write_calibration(exp: &Experiment, cals: &[MultiClaimCalibration]) -> Result<()> {
    let mut rows = Vec::new();
    for c in cals {
        for e in &c.best {
            rows.push(row![
                "prototype" => c.prototype.key(),
                "claim" => e.quantity.claim,
                "quantity" => e.quantity.quantity,
                "outcome" => e.outcome.label(),
                "ours" => e.value,
                "deviation" => e.deviation,
                "meets" => e.meets,
                "fitted" => e.kind == Kind::Quantitative,
            ]);
        }
    }
    exp.write_parquet(
        "calibration",
        &mut frame(rows)?,
        "calibrated within the ranges",
    )?;
    Ok(())
}

fn numbers_md(
    args: &Args,
    sobols: &[SobolRun],
    cals: &[MultiClaimCalibration],
    paretos: &[Pareto],
    claims: &Claims,
) -> String {
    let mut md = format!(
        "Saltelli design of N = {} base rows ({} evaluations per prototype), seed {}, \
         {} bootstrap resamples (95 % intervals); calibration: the published set and \
         {} more starts, at most {} Nelder-Mead iterations each. Ensemble claims (Figures 12, \
         14, 15): {}.\n\n",
        args.base,
        args.base * (Factor::ALL.len() + 2),
        deviations::STUDY_SEED,
        deviations::STUDY_RESAMPLES,
        args.starts,
        args.iters,
        match args.ensemble_records {
            Some(r) => format!("{r} records per level"),
            None => "not evaluated in this run (`--ensemble-records`)".into(),
        }
    );
    md.push_str("### In short\n\n");
    for c in cals {
        let k = &c.prototype.key()[1..];
        md.push_str(&format!(
            "- Prototype {k}: the best set found has a worst normalised deviation of {} over \
             its quantitative claims ({} at the published set); it meets {} of the {} claims \
             evaluated here, so within the ranges {} every one of them.\n",
            fmt_sig(c.worst(), 3),
            fmt_sig(c.published_worst(), 3),
            c.best.iter().filter(|e| e.meets).count(),
            c.best.len(),
            if c.meets_all() {
                "this search found a set that meets"
            } else {
                "this search found no set that meets"
            }
        ));
    }
    for p in paretos {
        md.push_str(&format!(
            "- Prototype {}: the most conflicting pair is {} `{}` against {} `{}`: the best \
             design point for both has a worst |deviation| {} above the larger of the two best \
             single ones ({} points on the front).\n",
            &p.prototype.key()[1..],
            p.pair.0.claim,
            p.pair.0.quantity,
            p.pair.1.claim,
            p.pair.1.quantity,
            fmt_sig(p.conflict, 3),
            p.front.len()
        ));
    }
    md.push('\n');
    for s in sobols {
        md.push_str(&format!(
            "### Total Sobol indices, prototype {}\n\n",
            &s.prototype.key()[1..]
        ));
        let mut t = Table::new([
            "claim",
            "quantity",
            "absent share (no fold / no grazing / failed)",
            "largest total index (factor)",
            "its 95 % interval",
        ]);
        for q in &s.quantities {
            let (big, ci) = match &q.indices {
                Some(ix) => {
                    let (i, ti) = ix
                        .total
                        .iter()
                        .enumerate()
                        .max_by(|a, b| a.1.value.total_cmp(&b.1.value))
                        .expect("factors");
                    (
                        format!("{} ({})", fmt_sig(ti.value, 2), Factor::ALL[i].key()),
                        format!("{} to {}", fmt_sig(ti.lo, 2), fmt_sig(ti.hi, 2)),
                    )
                }
                None => ("constant over the design".into(), "-".into()),
            };
            t.row([
                q.quantity.claim.to_string(),
                format!("`{}`", q.quantity.quantity),
                format!(
                    "{} ({} / {} / {})",
                    fmt_sig(q.absent_share, 2),
                    fmt_sig(q.no_fold_share, 2),
                    fmt_sig(q.no_grazing_share, 2),
                    fmt_sig(q.failed_share, 2)
                ),
                big,
                ci,
            ]);
        }
        md.push_str(&t.render());
        md.push('\n');
    }
    for c in cals {
        md.push_str(&format!(
            "### Best set of prototype {} within the ranges\n\nWorst normalised deviation over \
             its quantitative claims: {}; it meets {} of the {} claims evaluated here \
             (every one: {}).\n\n",
            &c.prototype.key()[1..],
            fmt_sig(c.worst(), 3),
            c.best.iter().filter(|e| e.meets).count(),
            c.best.len(),
            if c.meets_all() { "yes" } else { "no" }
        ));
        let mut t = Table::new([
            "claim",
            "quantity",
            "paper",
            "published set (deviation)",
            "best set",
            "deviation",
            "meets",
        ]);
        for (e, p) in c.best.iter().zip(&c.published) {
            let paper = claims
                .get(e.quantity.claim, e.quantity.quantity)
                .map_or(f64::NAN, |c| c.paper.to_f64());
            t.row([
                e.quantity.claim.to_string(),
                format!("`{}`", e.quantity.quantity),
                fmt_sig(paper, 4),
                format!("{} ({})", fmt_sig(p.value, 4), fmt_sig(p.deviation, 3)),
                match e.outcome.value() {
                    Some(v) => fmt_sig(v, 4),
                    None => format!("{} ({})", e.outcome.label(), fmt_sig(e.value, 4)),
                },
                fmt_sig(e.deviation, 3),
                if e.meets { "yes" } else { "no" }.to_string(),
            ]);
        }
        md.push_str(&t.render());
        md.push('\n');
        let mut t = Table::new(["factor", "unit-cube coordinate"]);
        for (f, u) in Factor::ALL.iter().zip(&c.fits[0].point) {
            t.row([format!("`{}`", f.key()), fmt_sig(*u, 3)]);
        }
        md.push_str(&t.render());
        md.push('\n');
    }
    md
}

/// Claims x factors, total Sobol index as a grey level (white 0, black 1).
struct HeatMap {
    rows: Vec<String>,
    cells: Vec<Vec<Option<f64>>>,
}

impl HeatMap {
    fn of(runs: &[SobolRun]) -> Self {
        let mut rows = Vec::new();
        let mut cells = Vec::new();
        for r in runs {
            for q in &r.quantities {
                rows.push(format!(
                    "{} {} {}",
                    r.prototype.key(),
                    q.quantity.claim,
                    q.quantity.quantity
                ));
                cells.push(match &q.indices {
                    Some(ix) => ix.total.iter().map(|t| Some(t.value)).collect(),
                    None => vec![None; Factor::ALL.len()],
                });
            }
        }
        Self { rows, cells }
    }
}

impl Figure for HeatMap {
    fn size(&self) -> (u32, u32) {
        (1100, 120 + 34 * self.rows.len() as u32)
    }

    fn title(&self) -> String {
        "Total Sobol index of each claim quantity (rows) for each factor (columns)".into()
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        root.fill(&WHITE)?;
        let (left, top, cw, ch) = (380i32, 90i32, 88i32, 34i32);
        let font = ("sans-serif", 15).into_font();
        for (j, f) in Factor::ALL.iter().enumerate() {
            let x = left + j as i32 * cw + 4;
            root.draw(&Text::new(
                f.key().replace('_', " "),
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
