//! The response experiment's outputs (the study itself is `endstop::paper::response`): the
//! continued orbits, the sweeps and the basins as Parquet, the book's tables and sentences on
//! the jumps, folds, grazing points, the steady-state criterion past the fold, the Floquet
//! multipliers, the basins and the cost, and the plots of each case.

use anyhow::Result;
use endstop::paper::response::{self, Case, CaseRun};
use endstop::paper::setups::ParamSet;
use endstop::study::steady::FOLD_BLOCK_PERIODS;
use endstop::study::sweep::DownEndKind;

use crate::io::frame::frame;
use crate::io::legend::placed_clear;
use crate::io::md::Table;
use crate::io::plot::{LinePlot, Panels};
use crate::reports::branch_io::{continuation_rows, response_figure};
use crate::{fmt_sig, row, Experiment};

/// Writes everything of one run: the numbers of the summary, the Parquet tables, the book's
/// tables and sentences, and the plots. `fine_shift` is each case's largest change of a basin
/// share on a grid twice as fine; `claim_folds` the upper folds beside the jump claims of
/// Figure 8 (`response::claim_folds`).
pub fn write(
    mut exp: Experiment,
    run: &response::Run,
    fine_shift: &[(Case, f64)],
    claim_folds: &[(String, f64)],
) -> Result<()> {
    for (case, shift) in fine_shift {
        exp.number(
            &format!("{}_basin_share_change_fine_grid", case.key()),
            *shift,
        );
    }
    for c in &run.cases {
        for (k, v) in c.numbers() {
            exp.number(&k, v);
        }
    }
    for (k, v) in claim_folds {
        exp.number(k, *v);
    }
    write_tables(&exp, run)?;
    let mut md = numbers_md(run, fine_shift);
    md.push_str(&folds_md(claim_folds));
    exp.write_numbers_md(&md)?;
    for c in &run.cases {
        exp.write_extra_plot(&format!("response_{}", c.setup.case.key()), &curve_plot(c))?;
        if c.basins.is_some() {
            exp.write_extra_plot(&format!("basins_{}", c.setup.case.key()), &basin_plot(c))?;
        }
    }
    exp.write_plot(&curve_plot(run.case(Case::Fig13P2)))?;
    exp.finish()
}

/// The table of the upper folds beside the jump claims of Figure 8.
fn folds_md(claim_folds: &[(String, f64)]) -> String {
    let mut md = String::from("\n### Folds beside the jump claims of Figure 8\n\n");
    let mut t = Table::new(["claim", "quantity", "set", "upper fold (Hz)"]);
    for (claim, _, _) in response::FOLD_CLAIMS {
        for set in ParamSet::BOTH {
            let key = response::fold_key(claim.id, claim.quantity, set).expect("a jump claim");
            let v = claim_folds.iter().find(|(k, _)| *k == key).map(|x| x.1);
            t.row([
                claim.id.to_string(),
                format!("`{}`", claim.quantity),
                set.to_string(),
                hz(v),
            ]);
        }
    }
    md.push_str(&t.render());
    md
}

fn write_tables(exp: &Experiment, run: &response::Run) -> Result<()> {
    let rows: Vec<_> = run
        .cases
        .iter()
        .flat_map(|c| continuation_rows(c.setup.case.key(), &c.branch))
        .collect();
    exp.write_parquet(
        "continuation",
        &mut frame(rows)?,
        "published and calibrated",
    )?;
    let mut rows = Vec::new();
    for c in &run.cases {
        let case = c.setup.case.key();
        let up = c.up.measurements().map(|m| ("up", m));
        let down = c.down.measurements().map(|m| ("down", m));
        for (dir, m) in up.chain(down) {
            rows.push(row![
                "case" => case,
                "direction" => dir,
                "freq_hz" => m.freq_hz,
                "accel_rms_g" => m.accel_rms_g,
                "v1_rms_v" => m.v1_rms_v,
                "x_max_m" => m.x_peak_m,
                "contact_fraction" => m.contact_fraction,
                "converged" => m.converged,
            ]);
        }
    }
    exp.write_parquet("sweeps", &mut frame(rows)?, "published and calibrated")?;
    let mut rows = Vec::new();
    for c in &run.cases {
        let Some(b) = &c.basins else { continue };
        let f = c.setup.case.basin_freq_hz().expect("basin frequency");
        for (i, &(x, v)) in b.cells.iter().enumerate() {
            rows.push(row![
                "case" => c.setup.case.key(),
                "freq_hz" => f,
                "x0_m" => x,
                "v0_m_per_s" => v,
                "attractor" => b.label(i),
                "periods" => b.periods[i],
            ]);
        }
    }
    exp.write_parquet("basins", &mut frame(rows)?, "published and calibrated")?;
    Ok(())
}

fn hz(v: Option<f64>) -> String {
    v.map_or("-".into(), |x| format!("{x:.2}"))
}

/// The chapter's generated numbers: the transitions, the ghost past the fold, the events,
/// the coexisting orbits, the basins and the cost, one section each.
fn numbers_md(run: &response::Run, fine_shift: &[(Case, f64)]) -> String {
    let mut md = String::from("### Jumps, folds and grazing points\n\n");
    md.push_str(&transitions_table(run));
    md.push_str(
        "\nThe sweeps' transitions are refined to brackets of 0.1 Hz (the midpoint is shown). \
         The upper fold and the grazing points are located on the continued branch to 1e-4 Hz.\n",
    );
    md.push_str(&ghost_md(run));
    md.push_str("\n### In words\n\n");
    for c in &run.cases {
        md.push_str(&in_words(c));
    }
    md.push_str(&events_md(run));
    md.push_str(&multipliers_md(run));
    md.push_str(&basins_md(run, fine_shift));
    md.push_str(&cost_md(run));
    md
}

/// Where each sweep leaves its branch, against the fold, the lower end and the grazing points.
fn transitions_table(run: &response::Run) -> String {
    let mut t = Table::new([
        "case",
        "up-sweep leaves the upper branch (Hz)",
        "how",
        "upper fold (Hz)",
        "sweep - fold (Hz)",
        "down-sweep leaves the lower branch (Hz)",
        "how",
        "lower branch end (Hz)",
        "sweep - end (Hz)",
        "grazing low (Hz)",
        "grazing high (Hz)",
        "hysteresis width (Hz)",
    ]);
    for c in &run.cases {
        let g = c.grazing_hz();
        let up_how = c.up.branch_end().map_or("-".to_string(), |e| {
            let r =
                c.up.jump_power_ratio
                    .map_or(String::new(), |r| format!(" (power x {})", fmt_sig(r, 3)));
            format!("{}{r}", e.kind.label())
        });
        let down_how = c.down.branch_end().map_or("-".to_string(), |e| {
            let r = match e.0 {
                DownEndKind::Jump => c.down.jump_power_ratio,
                DownEndKind::ContactOnset => c.down.contact_power_ratio,
            };
            format!(
                "{}{}",
                e.0.label(),
                r.map_or(String::new(), |r| format!(" (power x {})", fmt_sig(r, 3)))
            )
        });
        t.row([
            c.setup.case.label().to_string(),
            hz(c.up_end_hz()),
            up_how,
            hz(c.fold_hz()),
            hz(c.up_end_hz().zip(c.fold_hz()).map(|(a, b)| a - b)),
            hz(c.down_end_hz()),
            down_how,
            hz(c.lower_end_hz()),
            hz(c.down_end_hz().zip(c.lower_end_hz()).map(|(a, b)| a - b)),
            hz(g.map(|g| g.0)),
            hz(g.map(|g| g.1)),
            hz(c.band_hz().map(|(a, b)| b - a)),
        ]);
    }
    t.render()
}

/// The stepped sweep's steady-state criterion past the upper fold, and the fold rule's
/// convergence.
fn ghost_md(run: &response::Run) -> String {
    let mut md = String::new();
    md.push_str("\n### The stepped sweep's steady-state criterion past the upper fold\n\n");
    md.push_str(&format!(
        "One step of the sweep's steady-state criterion from the stable impacting orbit 1 Hz \
         below the upper fold, at frequencies above the fold where no impacting orbit exists; \
         beside it, how many periods the same start keeps touching the stops (the life of the \
         saddle-node's ghost). The sweep's blocks follow the fold rule (at least {} periods); \
         where the ring-up time alone gives shorter blocks, the criterion with those blocks \
         (without the rule) is shown too.\n\n",
        FOLD_BLOCK_PERIODS
    ));
    let mut t = Table::new([
        "case",
        "blocks (periods)",
        "above the fold (Hz)",
        "criterion accepts an impacting state",
        "periods the criterion simulated",
        "last period with contact",
    ]);
    for c in &run.cases {
        for rows in [&c.ghost, &c.ghost_ring_up] {
            for g in rows {
                t.row([
                    c.setup.case.key().to_string(),
                    g.block_periods.to_string(),
                    format!("{}", g.offset_hz),
                    if g.accepted_in_contact { "yes" } else { "no" }.to_string(),
                    g.periods_simulated.to_string(),
                    g.last_contact_period.to_string(),
                ]);
            }
        }
    }
    md.push_str(&t.render());
    md.push_str(
        "\nThe convergence of the fold rule: the same up-sweeps with half the sweep's blocks.\n\n",
    );
    let mut t = Table::new([
        "case",
        "half blocks (periods)",
        "up-sweep leaves the upper branch (Hz)",
        "how",
        "sweep - fold (Hz)",
        "change from the sweep's (Hz)",
    ]);
    for c in &run.cases {
        let Some(r) = &c.up_half_blocks else { continue };
        let end = r.branch_end().map(|e| e.transition.value());
        t.row([
            c.setup.case.key().to_string(),
            (c.setup.sweep.cfg.block_periods / 2).to_string(),
            hz(end),
            r.branch_end()
                .map_or("-".into(), |e| e.kind.label().to_string()),
            hz(end.zip(c.fold_hz()).map(|(a, b)| a - b)),
            hz(end.zip(c.up_end_hz()).map(|(a, b)| a - b)),
        ]);
    }
    md.push_str(&t.render());
    md
}

/// Every event on the continued branches.
fn events_md(run: &response::Run) -> String {
    let mut md = String::new();
    md.push_str("\n### Every event on the branches\n\n");
    let mut t = Table::new([
        "case",
        "event",
        "frequency (Hz)",
        "stable before",
        "stable after",
    ]);
    for c in &run.cases {
        for e in &c.named_events {
            let kind = e.label();
            t.row([
                c.setup.case.key().to_string(),
                kind,
                format!("{:.4}", e.param),
                e.stable.first().copied().unwrap_or(false).to_string(),
                e.stable.get(1).copied().unwrap_or(false).to_string(),
            ]);
        }
    }
    md.push_str(&t.render());
    md
}

/// The Floquet multipliers of the coexisting orbits in the hysteresis band.
fn multipliers_md(run: &response::Run) -> String {
    let mut md = String::new();
    md.push_str("\n### Floquet multipliers of the coexisting orbits in the hysteresis band\n\n");
    let mut t = Table::new([
        "case",
        "frequency (Hz)",
        "orbit",
        "V1 rms (V)",
        "max |x| (um)",
        "multipliers",
        "stable",
    ]);
    for c in &run.cases {
        let Some(p) = &c.probe else { continue };
        for o in &p.orbits {
            let mu = o
                .multipliers
                .iter()
                .map(|m| {
                    if m.im.abs() > 1e-12 {
                        format!(
                            "{} {} {}i",
                            fmt_sig(m.re, 4),
                            if m.im < 0.0 { "-" } else { "+" },
                            fmt_sig(m.im.abs(), 4)
                        )
                    } else {
                        fmt_sig(m.re, 4)
                    }
                })
                .collect::<Vec<_>>()
                .join(", ");
            let kind = response::Probe::orbit_label(o);
            t.row([
                c.setup.case.key().to_string(),
                format!("{:.2}", p.freq_hz),
                kind.to_string(),
                fmt_sig(o.summary.v1_rms_v, 4),
                fmt_sig(o.summary.x_max_m * 1e6, 5),
                mu,
                o.is_stable().to_string(),
            ]);
        }
    }
    md.push_str(&t.render());
    md
}

/// The basins' shares, with their change on a grid twice as fine.
fn basins_md(run: &response::Run, fine_shift: &[(Case, f64)]) -> String {
    let mut md = String::new();
    md.push_str("\n### Basins of attraction\n\n");
    let mut t = Table::new([
        "case",
        "frequency (Hz)",
        "attractor",
        "share",
        "largest change on a grid twice as fine",
    ]);
    for c in &run.cases {
        let Some(b) = &c.basins else { continue };
        let shift = fine_shift
            .iter()
            .find(|(k, _)| *k == c.setup.case)
            .map_or("-".into(), |s| format!("{:.2} points", 100.0 * s.1));
        for (label, share) in b.shares() {
            t.row([
                c.setup.case.key().to_string(),
                format!("{:.1}", c.setup.case.basin_freq_hz().unwrap_or(f64::NAN)),
                label,
                format!("{:.3}", share),
                shift.clone(),
            ]);
        }
    }
    md.push_str(&t.render());
    md
}

/// The continuation's and the sweeps' cost.
fn cost_md(run: &response::Run) -> String {
    let mut md = String::new();
    md.push_str("\n### Cost\n\n");
    let mut t = Table::new([
        "case",
        "continuation points",
        "rejected steps",
        "largest residual",
        "continuation wall time (s)",
        "integrator steps (continuation)",
        "integrator steps (up-sweep)",
        "integrator steps (down-sweep)",
    ]);
    for c in &run.cases {
        t.row([
            c.setup.case.key().to_string(),
            c.branch.points.len().to_string(),
            c.branch.rejected_steps().to_string(),
            format!("{:.1e}", c.branch.max_residual()),
            format!("{:.2}", c.continuation_s),
            c.branch.stats.accepted.to_string(),
            c.up.total_stats().accepted.to_string(),
            c.down.total_stats().accepted.to_string(),
        ]);
    }
    md.push_str(&t.render());
    md
}

/// Generated sentences on a case: where the sweeps leave the branches relative to the fold and
/// the lower end, and what the steady-state criterion does with the ghost past the fold.
fn in_words(c: &CaseRun) -> String {
    let name = c.setup.case.label();
    let mut out = format!("- **{name}.** ");
    match (c.up.branch_end(), c.fold_hz()) {
        (Some(e), Some(fold)) => {
            let d = e.transition.value() - fold;
            out.push_str(&format!(
                "The up-sweep leaves the upper branch ({}) at {:.2} Hz, {:.2} Hz {} the upper \
                 fold at {:.2} Hz (the sweep's bracket is {} Hz wide). ",
                e.kind.label(),
                e.transition.value(),
                d.abs(),
                if d >= 0.0 { "above" } else { "below" },
                fold,
                c.setup.sweep.refine_tol_hz
            ));
        }
        _ => out.push_str("The branch has no upper fold in the range. "),
    }
    if let (Some((kind, t)), Some(end)) = (c.down.branch_end(), c.lower_end_hz()) {
        out.push_str(&format!(
            "The down-sweep leaves the lower branch ({}) at {:.2} Hz, {:.2} Hz from its end at \
             {:.2} Hz. ",
            kind.label(),
            t.value(),
            (t.value() - end).abs(),
            end
        ));
    }
    out.push_str(&ghost_words(&c.ghost, "the sweep's steady-state criterion"));
    if !c.ghost_ring_up.is_empty() {
        out.push_str(&ghost_words(
            &c.ghost_ring_up,
            "the same criterion with blocks of the ring-up time alone",
        ));
    }
    if let Some(b) = &c.basins {
        let shares = b
            .shares()
            .iter()
            .map(|(l, s)| format!("{l} {:.1} %", 100.0 * s))
            .collect::<Vec<_>>()
            .join(", ");
        out.push_str(&format!(
            "Basins at {} Hz ({} initial states): {shares}.",
            c.setup.case.basin_freq_hz().unwrap_or(f64::NAN),
            b.cells.len()
        ));
    }
    out.truncate(out.trim_end().len());
    out.push('\n');
    out
}

/// A sentence on what a criterion (`who`) does with the ghost past the fold.
fn ghost_words(ghost: &[response::GhostRow], who: &str) -> String {
    let accepted: Vec<_> = ghost.iter().filter(|g| g.accepted_in_contact).collect();
    if let Some(worst) = accepted
        .iter()
        .max_by(|a, b| a.offset_hz.total_cmp(&b.offset_hz))
    {
        format!(
            "Past the fold {who} ({} periods a block) accepts the dying impacting state as \
             steady at {} of {} offsets, up to {} Hz above the fold: there it stops after {} \
             periods, while the state keeps touching the stops for {} periods. ",
            worst.block_periods,
            accepted.len(),
            ghost.len(),
            worst.offset_hz,
            worst.periods_simulated,
            worst.last_contact_period
        )
    } else if let Some(first) = ghost.first() {
        format!(
            "Past the fold {who} ({} periods a block) never accepts the dying impacting \
             state: at {} Hz above the fold it simulates {} periods, longer than the {} \
             periods the state keeps touching the stops. ",
            first.block_periods,
            first.offset_hz,
            first.periods_simulated,
            first.last_contact_period
        )
    } else {
        String::new()
    }
}

/// A hysteresis band narrower than this share of the plotted frequencies gets a panel of its
/// own: at the whole response's scale its two branches are drawn on top of each other.
const NARROW_BAND_SHARE: f64 = 0.05;

/// The whole response of a case: its branch with both sweeps, RMS voltage and phase, and, for
/// a hysteresis band too narrow to see at that scale, a third panel with the RMS voltage over
/// the band and half its width on either side, its scale stated in its title.
fn curve_plot(c: &CaseRun) -> Panels {
    let steps = |ms: Vec<&endstop::study::steady::Measurement>| -> Vec<(f64, f64)> {
        ms.into_iter().map(|m| (m.freq_hz, m.v1_rms_v)).collect()
    };
    let s = &c.setup.continuation;
    let mut fig = response_figure(
        &format!("Whole response: {}", c.setup.case.label()),
        &c.branch,
        steps(c.up.measurements().collect()),
        steps(c.down.measurements().collect()),
        (s.start, s.stop),
    );
    let span_hz = (s.stop - s.start).abs();
    if let Some((a, b)) = c.band_hz() {
        let width = b - a;
        if width < NARROW_BAND_SHARE * span_hz {
            let (lo, hi) = (a - 0.5 * width, b + 0.5 * width);
            let title = format!(
                "Hysteresis band, {} to {} Hz, enlarged {}x in frequency",
                fmt_sig(a, 6),
                fmt_sig(b, 6),
                fmt_sig(span_hz / (hi - lo), 2),
            );
            let zoom = placed_clear(fig.plots[0].zoomed(&title, lo, hi));
            let mut plots = fig.plots;
            plots.push(zoom);
            fig = Panels::new(plots);
        }
    }
    fig
}

fn basin_plot(c: &CaseRun) -> LinePlot {
    let b = c.basins.as_ref().expect("basins");
    let title = format!(
        "Basins at {} Hz: {}",
        c.setup.case.basin_freq_hz().unwrap_or(f64::NAN),
        c.setup.case.label()
    );
    crate::reports::basins_io::basin_map(&title, b, &[])
}
