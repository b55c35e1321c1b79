//! Figure 8's outputs (the figure itself is `endstop::paper::figures::fig08`): the numbers of
//! the summary, the per-step sweeps, the convergence and the b_im fits as Parquet, the book's
//! tables (calibration, claims, every sweep, the paper's procedure for b_im, convergence,
//! tension-free contact) and the plot of each parameter set.

use anyhow::Result;
use endstop::paper::calibration::{CalibrationRecord, BIM_FIT_TOL_HZ, CALIBRATION_TOL_HZ};
use endstop::paper::claims::{Claims, Value};
use endstop::paper::curves::{law_key, CONV_FREQ_REL, CONV_RMS_REL};
use endstop::paper::figures::fig08::{self, Fig08, Fig8Curve, SetRun, BIM_FITS};
use endstop::paper::measured::{P1_MEASURED_JUMP_HZ, P1_MEASURED_ONSET_HZ};
use endstop::paper::setups::{endstop, ParamSet};
use endstop::paper::Figure;
use endstop::study::sweep::BranchEndKind;

use crate::io::frame::frame;
use crate::io::md::{self, Table};
use crate::io::plot::{LegendPos, LinePlot, Series, Style, PALETTE};
use crate::reports::sweep_io::{
    claims_table_both_sets, convergence_cells, curve_rows, hz, pct, CONVERGENCE_COLUMNS,
};
use crate::{fmt_sig, row, Experiment};

/// Writes everything of one run of Figure 8 with its claim `values`: the numbers of the
/// summary, the Parquet tables, the book's tables and the plots.
pub fn write(
    mut exp: Experiment,
    cal: &CalibrationRecord,
    run: &fig08::Run,
    values: &[Value],
    claims: &Claims,
) -> Result<()> {
    record_numbers(&mut exp, cal, run);
    write_parquet(&exp, run)?;
    exp.write_numbers_md(&numbers_md(cal, run, values, claims))?;
    for r in &run.sets {
        let plot = sweep_plot(r);
        match r.set {
            ParamSet::Published => exp.write_plot(&plot)?,
            ParamSet::Calibrated => exp.write_extra_plot("fig08_calibrated", &plot)?,
        }
    }
    exp.finish()
}

fn record_numbers(exp: &mut Experiment, cal: &CalibrationRecord, run: &fig08::Run) {
    exp.number("calibrated_gap_m", cal.fitted_gap_m);
    exp.number("published_gap_m", cal.published_gap_m);
    exp.number("calibration_target_onset_hz", cal.target_onset_hz);
    exp.number("calibration_achieved_onset_hz", cal.achieved_onset_hz);
    exp.number("calibration_evaluations", cal.evaluations as f64);
    for r in &run.sets {
        for c in &r.sweeps.curves {
            let k = format!("{}_{}", r.set.label(), c.spec.key());
            if let Some(t) = c.report.onset {
                exp.number(&format!("{k}_onset_hz"), t.value());
            }
            if let Some(e) = c.report.branch_end() {
                let is_jump = e.kind == BranchEndKind::Jump;
                exp.number(&format!("{k}_branch_end_hz"), e.transition.value());
                exp.number(
                    &format!("{k}_branch_end_is_jump"),
                    f64::from(u8::from(is_jump)),
                );
            }
            exp.number(&format!("{k}_max_v1_rms_v"), c.report.max_v1_rms_v());
        }
        for f in &r.fits {
            let k = format!("{}_bim_fit_{}", r.set.label(), law_key(f.stiffness));
            // No number when no b_im reaches the target (summary.json holds no NaN).
            if let Some(b) = f.bim_n_s_per_m {
                exp.number(&format!("{k}_n_s_per_m"), b);
            }
            if let Some(e) = f.at_zero {
                exp.number(&format!("{k}_end_at_bim0_hz"), e.transition.value());
            }
        }
    }
}

fn write_parquet(exp: &Experiment, run: &fig08::Run) -> Result<()> {
    let sets = ParamSet::BOTH_LABEL;
    let rows = run
        .sets
        .iter()
        .flat_map(|r| curve_rows(&r.device, &r.sweeps.curves));
    exp.write_parquet("fig08", &mut frame(rows)?, sets)?;

    // Convergence: one row per set and curve (NaN where a run has no such transition).
    let rows = run.sets.iter().flat_map(|r| {
        r.sweeps
            .curves
            .iter()
            .zip(r.sweeps.convergence())
            .map(move |(c, v)| {
                let cmp = v.comparison;
                row![
                    "params" => r.set.label(),
                    "series" => c.spec.label(),
                    "onset_rel_change" => cmp.onset_rel.unwrap_or(f64::NAN),
                    "branch_end_rel_change" => cmp.end_rel.unwrap_or(f64::NAN),
                    "same_branch_end_kind" => cmp.same_end_kind,
                    "max_v1_rms_rel_change" => cmp.max_v1_rel,
                    "max_v2_rms_rel_change" => cmp.max_v2_rel,
                    "frequencies_compared" => cmp.compared as u32,
                    "frequencies_excluded" => cmp.excluded as u32,
                    "onset_refined_run_hz" => v.fine_onset_hz.unwrap_or(f64::NAN),
                    "branch_end_refined_run_hz" => v.fine_branch_end_hz.unwrap_or(f64::NAN),
                ]
            })
    });
    exp.write_parquet("fig08_convergence", &mut frame(rows)?, sets)?;

    // b_im fits: one row per evaluation.
    let rows = run.sets.iter().flat_map(|r| {
        r.fits.iter().flat_map(move |f| {
            f.samples.iter().map(move |s| {
                row![
                    "params" => r.set.label(),
                    "stiffness" => law_key(f.stiffness),
                    "bim_n_s_per_m" => s.bim_n_s_per_m,
                    "branch_end_hz" => s.end.map_or(f64::NAN, |e| e.transition.value()),
                    "branch_end_kind" => s.end.map_or("none", |e| e.kind.label()),
                ]
            })
        })
    });
    exp.write_parquet("fig08_bim_fits", &mut frame(rows)?, sets)?;
    Ok(())
}

/// The chapter's generated numbers: the calibration, the claims, every sweep, the paper's
/// b_im procedure, the convergence and the tension-free sensitivity, one section each.
fn numbers_md(
    cal: &CalibrationRecord,
    run: &fig08::Run,
    values: &[Value],
    claims: &Claims,
) -> String {
    let mut md = calibration_md(cal);
    md.push_str(
        "\n### Claims\n\nOur value, what it is, and the verdict with the claims file's \
         tolerance. Where a sweep has no jump, the value given for a jump claim is the frequency \
         at which the impacting branch ends by a gradual loss of contact, and it says so.\n\n",
    );
    md.push_str(&claims_table_both_sets(claims.of_experiment(Fig08::NAME), values, 5).render());
    md.push_str(&sweeps_md(run));
    md.push_str(&bim_md(run));
    md.push_str(&convergence_md(run));
    md.push_str(&tension_free_md(run));
    md
}

/// The calibration of the gap, read from its artefact.
fn calibration_md(cal: &CalibrationRecord) -> String {
    let mut md = format!(
        "### Calibration\n\nOne parameter, the end-stop gap xmax, fitted so that the 5.5 g, 30 V \
         up-sweep first touches a stop at the paper's measured kink ({P1_MEASURED_ONSET_HZ} Hz): \
         a root find on xmax, each evaluation a sweep plus a refined onset, stopped when the \
         onset is within {CALIBRATION_TOL_HZ} Hz of the target. Read from the calibration \
         artefact (`data/results/calibration/`).\n\n"
    );
    let mut t = Table::new([
        "published xmax (um)",
        "calibrated xmax (um)",
        "ratio",
        "target onset (Hz)",
        "achieved onset (Hz)",
        "onset bracket (Hz)",
        "evaluations",
    ]);
    t.row([
        fmt_sig(cal.published_gap_m * 1e6, 4),
        fmt_sig(cal.fitted_gap_m * 1e6, 5),
        fmt_sig(cal.fitted_gap_m / cal.published_gap_m, 4),
        cal.target_onset_hz.to_string(),
        fmt_sig(cal.achieved_onset_hz, 6),
        format!(
            "{} .. {}",
            fmt_sig(cal.onset_bracket.before, 6),
            fmt_sig(cal.onset_bracket.after, 6)
        ),
        cal.evaluations.to_string(),
    ]);
    md.push_str(&t.render());
    md
}

/// Every sweep's onset, branch end and cost.
fn sweeps_md(run: &fig08::Run) -> String {
    let mut md = String::new();
    md.push_str(
        "\n### Every sweep\n\nOnset and branch end are refined to brackets of 0.1 Hz (midpoints \
         shown). The jump power ratio is the total output power just after over just before the \
         refined jump. Steps beyond 1600 Hz exist only where the impacting branch outlived the \
         paper's range and the sweep was continued to find its end. The integrator steps count \
         the coarse steps and every trial of the refinements.\n\n",
    );
    let mut t = Table::new([
        "set",
        "curve",
        "onset (Hz)",
        "branch end (Hz)",
        "how it ends",
        "jump power ratio",
        "max V1 rms (V)",
        "max (V2-V1) rms (V)",
        "max penetration (nm)",
        "steps beyond 1600 Hz",
        "steps converged",
        "integrator steps",
    ]);
    let cfg = &run.protocol.settings.cfg;
    for r in &run.sets {
        for c in &r.sweeps.curves {
            let s = c.summary(&r.device, cfg);
            let how = match s.branch_end {
                Some(e) => e.kind.label(),
                None if s.any_contact => "contact to the end",
                None => "no contact",
            };
            t.row([
                r.set.label().into(),
                c.spec.label(),
                hz(s.onset_hz),
                hz(s.branch_end.map(|e| e.transition.value())),
                how.into(),
                s.jump_power_ratio.map_or("-".into(), |x| fmt_sig(x, 3)),
                fmt_sig(s.max_v1_rms_v, 4),
                fmt_sig(s.max_vdiff_rms_v, 4),
                fmt_sig(s.max_penetration_m * 1e9, 2),
                s.steps_beyond.to_string(),
                format!("{}/{}", s.steps_converged, s.steps),
                s.integrator_steps.to_string(),
            ]);
        }
    }
    md.push_str(&t.render());
    md
}

/// The paper's procedure for b_im, with our fits.
fn bim_md(run: &fig08::Run) -> String {
    let mut md = String::new();
    md.push_str(&format!(
        "\n### The paper's procedure for b_im\n\nThe end-stop damping for which the 5.5 g \
         up-sweep's impacting branch ends at the measured {P1_MEASURED_JUMP_HZ} Hz (Illinois \
         root find on b_im, branch end within {BIM_FIT_TOL_HZ} Hz). The paper's values are \
         {} N s/m (Hertz) and {} N s/m (linear, eq 19).\n\n",
        BIM_FITS[0].spec().bim_n_s_per_m,
        BIM_FITS[1].spec().bim_n_s_per_m,
    ));
    let mut t = Table::new([
        "set",
        "stiffness",
        "fitted b_im (N s/m)",
        "paper's b_im (N s/m)",
        "branch end at the fit (Hz)",
        "how it ends",
        "branch end at b_im = 0 (Hz)",
        "how it ends",
        "evaluations",
    ]);
    for r in &run.sets {
        for (f, from) in r.fits.iter().zip(BIM_FITS) {
            t.row([
                r.set.label().into(),
                law_key(f.stiffness).into(),
                f.bim_n_s_per_m.map_or_else(
                    || "none: even b_im = 0 ends below the target".into(),
                    |b| fmt_sig(b, 3),
                ),
                from.spec().bim_n_s_per_m.to_string(),
                hz(f.achieved.map(|e| e.transition.value())),
                f.achieved.map_or("-", |e| e.kind.label()).into(),
                hz(f.at_zero.map(|e| e.transition.value())),
                f.at_zero.map_or("-", |e| e.kind.label()).into(),
                f.samples.len().to_string(),
            ]);
        }
    }
    md.push_str(&t.render());
    md
}

/// The sweeps' convergence under halved steps and tolerances.
fn convergence_md(run: &fig08::Run) -> String {
    let mut md = String::new();
    md.push_str(&format!(
        "\n### Convergence\n\nEach sweep repeated with half the frequency step, half the \
         integrator tolerance, half the steady-state tolerance and half the refinement bracket. \
         Required: onset and branch end move by less than {} %, RMS voltages by less than {} % \
         (at the frequencies both runs visit, except those between the two runs' branch ends, \
         where they are legitimately on different branches).\n\n",
        100.0 * CONV_FREQ_REL,
        100.0 * CONV_RMS_REL
    ));
    let mut t: Table<9> = Table::new(md::join(["set", "curve"], CONVERGENCE_COLUMNS));
    for r in &run.sets {
        for (c, v) in r.sweeps.curves.iter().zip(r.sweeps.convergence()) {
            let lead = [r.set.label().into(), c.spec.label()];
            t.row(md::join(lead, convergence_cells(&v)));
        }
    }
    md.push_str(&t.render());
    let worst = run.largest_changes();
    md.push_str(&format!(
        "\nLargest changes over all sweeps: onset {}, branch end {}, RMS voltage {}.\n",
        pct(Some(worst.0)),
        pct(Some(worst.1)),
        pct(Some(worst.2))
    ));
    md
}

/// The tension-free contact's sensitivity.
fn tension_free_md(run: &fig08::Run) -> String {
    let mut md = String::new();
    md.push_str(
        "\n### Tension-free contact (sensitivity)\n\n5.5 g, Hertz, b_im = 1.5 N s/m, with eq 1 \
         as written and with the contact force clipped at zero.\n\n",
    );
    let mut t = Table::new([
        "set",
        "contact",
        "onset (Hz)",
        "branch end (Hz)",
        "how it ends",
        "max V1 rms (V)",
    ]);
    for r in &run.sets {
        for (which, contact) in [
            (Fig8Curve::Hertz1p5, "eq 1 as written"),
            (Fig8Curve::Hertz1p5TensionFree, "tension-free"),
        ] {
            let rep = &r.sweeps.curve(which).report;
            let end = rep.branch_end();
            t.row([
                r.set.label().into(),
                contact.into(),
                hz(rep.onset.map(|t| t.value())),
                hz(end.map(|e| e.transition.value())),
                end.map_or("-", |e| e.kind.label()).into(),
                fmt_sig(rep.max_v1_rms_v(), 4),
            ]);
        }
    }
    md.push_str(&t.render());
    md
}

fn sweep_plot(r: &SetRun) -> LinePlot {
    let mut series = Vec::new();
    let mut color = 0;
    for c in &r.sweeps.curves {
        let pts: Vec<(f64, f64)> = c
            .report
            .measurements_in_range()
            .map(|m| (m.freq_hz, m.v1_rms_v))
            .collect();
        let (col, style) = if c.spec.tension_free {
            (PALETTE[2], Style::Dashed)
        } else {
            let col = PALETTE[color % 5];
            color += 1;
            (col, Style::LinePoints)
        };
        series.push(Series::new(
            &format!("simulation: {}", c.spec.label()),
            pts,
            col,
            style,
        ));
    }
    // Room above the curves for the legend.
    let ymax = 1.0;
    for (f, what) in [
        (P1_MEASURED_ONSET_HZ, "paper: kink"),
        (P1_MEASURED_JUMP_HZ, "paper: jump"),
    ] {
        series.push(Series::new(
            &format!("{what} at {f} Hz"),
            vec![(f, 0.0), (f, ymax)],
            PALETTE[6],
            Style::Dashed,
        ));
    }
    LinePlot::new(
        &format!(
            "Figure 8: prototype 1, 30 V, up-sweeps ({} parameters, xmax = {} um)",
            r.set.label(),
            fmt_sig(endstop(&r.device).gap_m * 1e6, 4)
        ),
        "Frequency [Hz]",
        "RMS output voltage V1 [V]",
        series,
    )
    .x(900.0, 1600.0)
    .y(0.0, ymax)
    .legend(LegendPos::UpperRight)
}
