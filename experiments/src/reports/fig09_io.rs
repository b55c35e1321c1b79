//! Figure 9's outputs (the figure itself is `endstop::paper::figures::fig09`): the numbers of
//! the summary, the continuations as Parquet, the book's tables (claims under both readings of
//! "output power", every curve, convergence) and the plot of one run.

use anyhow::Result;
use endstop::paper::calibration::CalibrationRecord;
use endstop::paper::claims::{keys, Claims, Value};
use endstop::paper::figures::fig09::{
    self, Fig09, PowerReading, CONV_ONSET_G, CONV_RMS_REL, DEFAULT_READING,
};
use endstop::paper::measured::P1_RESONANCE_HZ;
use endstop::paper::setups::endstop;
use endstop::paper::setups::{prototype1_setup, ParamSet};
use endstop::paper::Figure;

use crate::io::frame::frame;
use crate::io::md::Table;
use crate::io::plot::{LegendPos, LinePlot, Series, Style, PALETTE};
use crate::reports::sweep_io::{claims_table_both_sets, measurement_cells};
use crate::{fmt_sig, row, Experiment};

/// Writes everything of one run of Figure 9 with its claim `values` (under the figure's
/// reading of "output power") and `both_loads` (under the other reading): the numbers of the
/// summary, the Parquet table, the book's tables and the plot.
pub fn write(
    mut exp: Experiment,
    cal: &CalibrationRecord,
    run: &fig09::Run,
    values: &[Value],
    both_loads: &[Value],
    claims: &Claims,
) -> Result<()> {
    for r in &run.sets {
        for c in &r.curves {
            let k = format!("{}_{}v", r.set.label(), c.bias.volts());
            if let Some(t) = c.report.onset {
                exp.number(&format!("{k}_onset_g"), t.value());
            }
            let m = c.report.at_stop();
            exp.number(&format!("{k}_p1_at_5p5g_w"), m.p1_w);
            exp.number(&format!("{k}_p_both_at_5p5g_w"), m.p_total_w());
        }
    }
    exp.number("calibrated_gap_m", cal.fitted_gap_m);
    write_parquet(&exp, run)?;
    let tol = claims.require_class("amplitude_threshold")?.tol_abs;
    exp.write_numbers_md(&numbers_md(run, values, both_loads, claims, tol))?;
    exp.write_plot(&power_plot(run))?;
    exp.finish()
}

/// The end-stop damping of the continuations (N s/m; Hertz contact).
fn bim(r: &fig09::SetRun) -> f64 {
    endstop(&prototype1_setup(&r.device)).damping_n_s_per_m
}

fn write_parquet(exp: &Experiment, run: &fig09::Run) -> Result<()> {
    let rows = run.sets.iter().flat_map(|r| {
        r.curves.iter().flat_map(move |c| {
            let beyond_from = c.report.extended_from.unwrap_or(usize::MAX);
            let series = format!("Vb={} V, Hertz, b_im={}", c.bias.volts(), bim(r));
            c.report
                .sweep
                .steps
                .iter()
                .enumerate()
                .map(move |(i, s)| {
                    let m = &s.measurement;
                    [
                        row![
                            "accel_rms_g" => m.accel_rms_g,
                            "freq_hz" => m.freq_hz,
                            "bias_v" => c.bias.volts(),
                        ],
                        measurement_cells(m),
                        row![
                            "beyond_paper_range" => i >= beyond_from,
                            "series" => series.as_str(),
                            "params" => r.set.label(),
                            "endstop_gap_m" => endstop(&r.device).gap_m,
                        ],
                    ]
                    .concat()
                })
                .collect::<Vec<_>>()
        })
    });
    exp.write_parquet("fig09", &mut frame(rows)?, ParamSet::BOTH_LABEL)?;
    Ok(())
}

fn numbers_md(
    run: &fig09::Run,
    values: &[Value],
    both_loads: &[Value],
    claims: &Claims,
    onset_tol_g: f64,
) -> String {
    let mut md = format!(
        "### Claims (power of {}, the default reading)\n\nThe onsets are the same for all bias \
         voltages when their spread is at most {onset_tol_g} g, the claims file's tolerance \
         for amplitude thresholds.\n\n",
        DEFAULT_READING.label()
    );
    md.push_str(&claims_table_both_sets(claims.of_experiment(Fig09::NAME), values, 4).render());
    md.push_str(&format!(
        "\n### The other reading: power of {}\n\nThe same simulations, with the power of both \
         loads compared with the paper's numbers (not used for the scorecard).\n\n",
        PowerReading::BothLoads.label()
    ));
    let power_claims = claims
        .of_experiment(Fig09::NAME)
        .filter(|c| c.id == keys::F9B_P_SAT_20V.id);
    md.push_str(&claims_table_both_sets(power_claims, both_loads, 4).render());

    let s = &run.protocol.settings;
    md.push_str(&format!(
        "\n### Every continuation\n\n{P1_RESONANCE_HZ} Hz, Hertz contact, b_im = {} N s/m; onset \
         refined to a bracket of {} g (midpoint shown). A continuation that has not touched a \
         stop by 5.5 g is continued in the same steps until it does.\n\n",
        bim(&run.sets[0]),
        s.refine_tol_g,
    ));
    let mut t = Table::new([
        "set",
        "xmax (um)",
        "Vb (V)",
        "onset (g rms)",
        "beyond 5.5 g",
        "P one load at 5.5 g (nW)",
        "P both loads at 5.5 g (nW)",
        "V1 rms at 5.5 g (V)",
        "peak x at 5.5 g (um)",
        "contact fraction at 5.5 g",
    ]);
    for r in &run.sets {
        for c in &r.curves {
            let m = c.report.at_stop();
            t.row([
                r.set.label().into(),
                fmt_sig(endstop(&r.device).gap_m * 1e6, 4),
                c.bias.volts().to_string(),
                c.report
                    .onset
                    .map_or("none".into(), |t| fmt_sig(t.value(), 4)),
                if c.report.extended_from.is_some() {
                    "yes"
                } else {
                    "no"
                }
                .into(),
                fmt_sig(m.p1_w * 1e9, 4),
                fmt_sig(m.p_total_w() * 1e9, 4),
                fmt_sig(m.v1_rms_v, 4),
                fmt_sig(m.x_peak_m * 1e6, 4),
                fmt_sig(m.contact_fraction, 3),
            ]);
        }
    }
    md.push_str(&t.render());

    md.push_str(&format!(
        "\n### Convergence\n\nEach continuation repeated with half the amplitude step, half the \
         integrator tolerance, half the steady-state tolerance and half the onset bracket. \
         Required: onset moves by less than {CONV_ONSET_G} g, powers and RMS voltages by less \
         than {} %.\n\n",
        100.0 * CONV_RMS_REL
    ));
    let mut t = Table::new([
        "set",
        "Vb (V)",
        "onset change (g)",
        "power change at 5.5 g",
        "max V1 change",
        "within limits",
    ]);
    for r in &run.sets {
        for (c, v) in r.curves.iter().zip(r.convergence()) {
            let cmp = v.comparison;
            t.row([
                r.set.label().into(),
                c.bias.volts().to_string(),
                cmp.onset_abs_g.map_or("n/a".into(), |x| fmt_sig(x, 2)),
                format!("{} %", fmt_sig(100.0 * cmp.p_rel, 2)),
                format!("{} %", fmt_sig(100.0 * cmp.max_v1_rel, 2)),
                if v.within_limits { "yes" } else { "**no**" }.into(),
            ]);
        }
    }
    md.push_str(&t.render());
    md
}

fn power_plot(run: &fig09::Run) -> LinePlot {
    let mut series = Vec::new();
    for r in run.sets.iter().rev() {
        for (i, c) in r.curves.iter().enumerate() {
            let pts: Vec<(f64, f64)> = c
                .report
                .measurements_in_range()
                .map(|m| (m.accel_rms_g, DEFAULT_READING.of(m) * 1e9))
                .collect();
            let style = match r.set {
                ParamSet::Published => Style::Dashed,
                ParamSet::Calibrated => Style::LinePoints,
            };
            series.push(Series::new(
                &format!("simulation ({}): Vb = {} V", r.set.label(), c.bias.volts()),
                pts,
                PALETTE[i],
                style,
            ));
        }
    }
    series.push(Series::new(
        "paper: 31 and 125 nW at 5.5 g (20, 40 V)",
        vec![(5.5, 31.0), (5.5, 125.0)],
        PALETTE[6],
        Style::Points,
    ));
    series.push(Series::new(
        "paper: impacts begin at 4.5 g",
        vec![(4.5, 0.0), (4.5, 200.0)],
        PALETTE[6],
        Style::Dashed,
    ));
    LinePlot::new(
        &format!(
            "Figure 9: prototype 1 at {P1_RESONANCE_HZ} Hz (solid: calibrated, dashed: published)"
        ),
        "RMS acceleration [g]",
        &format!("Output power, {} [nW]", DEFAULT_READING.label()),
        series,
    )
    .x(0.5, 5.5)
    .y(0.0, 200.0)
    .legend(LegendPos::UpperLeft)
}
