//! Figure 13's outputs (the figure itself is `endstop::paper::figures::fig13`): the numbers of
//! the summary, the per-step sweeps as Parquet, the book's tables (claims, every sweep,
//! convergence) and the plot of one run.

use anyhow::Result;
use endstop::device::StiffnessModel;
use endstop::paper::claims::{Claims, Value};
use endstop::paper::curves::{CONV_FREQ_REL, CONV_RMS_REL};
use endstop::paper::figures::fig13::{self, Fig13};
use endstop::paper::setups::{ParamSet, FIG13_BIAS_V};
use endstop::paper::Figure;

use crate::io::frame::frame;
use crate::io::md::{self, Table};
use crate::io::plot::{LegendPos, LinePlot, Series, Style, PALETTE};
use crate::reports::sweep_io::{
    claim_cells, convergence_cells, curve_rows, hz, CONVERGENCE_COLUMNS,
};
use crate::{fmt_sig, Experiment};

/// Writes everything of one run of Figure 13 with its claim `values`: the numbers of the
/// summary, the Parquet table, the book's tables and the plot.
pub fn write(
    mut exp: Experiment,
    run: &fig13::Run,
    values: &[Value],
    claims: &Claims,
) -> Result<()> {
    for c in &run.sweeps.curves {
        let k = c.spec.key();
        if let Some(t) = c.report.onset {
            exp.number(&format!("{k}_onset_hz"), t.value());
        }
        if let Some(t) = c.report.jump {
            exp.number(&format!("{k}_jump_hz"), t.value());
        }
        exp.number(&format!("{k}_max_v1_rms_v"), c.report.max_v1_rms_v());
    }
    let jump_difference = run.jump_difference_rel();
    if let Some(rel) = jump_difference {
        exp.number("jump_hertz_minus_linear_rel", rel);
    }
    exp.write_parquet(
        "fig13",
        &mut frame(curve_rows(&run.device, &run.sweeps.curves))?,
        ParamSet::Published.label(),
    )?;

    let mut md = String::from("### Claims\n\n");
    let mut t = Table::new(["claim", "quantity", "paper", "ours", "what", "verdict"]);
    for c in claims.of_experiment(Fig13::NAME) {
        let [ours, what, verdict] = claim_cells(c, values, ParamSet::Published, 5);
        t.row([
            c.id.clone(),
            format!("`{}`", c.quantity),
            "yes".into(),
            ours,
            what,
            verdict,
        ]);
    }
    md.push_str(&t.render());
    let s = &run.settings;
    md.push_str(&format!(
        "\n### Every sweep\n\n{} Hz to {} Hz in {} Hz steps, Vb = {FIG13_BIAS_V} V. Steady state: \
         blocks of {} periods (about the ring-up time 2m/b), one block to settle, then blocks \
         until the RMS voltages change by less than {} between two blocks. Onset and jump \
         refined to brackets of {} Hz (midpoints shown). The integrator steps and contact events \
         count the coarse steps and every trial of the refinements.\n\n",
        s.freqs_hz[0],
        s.freqs_hz[s.freqs_hz.len() - 1],
        s.freqs_hz[1] - s.freqs_hz[0],
        s.cfg.block_periods,
        s.cfg.rel_change_tol,
        s.refine_tol_hz,
    ));
    let mut t = Table::new([
        "curve",
        "onset (Hz)",
        "jump (Hz)",
        "jump power ratio",
        "loss of contact (Hz)",
        "max V1 rms (V)",
        "max (V2-V1) rms (V)",
        "mean blocks per step",
        "simulated periods",
        "integrator steps",
        "contact events",
    ]);
    for c in &run.sweeps.curves {
        let m = c.summary(&run.device, &s.cfg);
        t.row([
            c.spec.label(),
            hz(m.onset_hz),
            hz(m.jump_hz),
            m.jump_power_ratio.map_or("-".into(), |x| fmt_sig(x, 3)),
            hz(m.contact_lost_hz),
            fmt_sig(m.max_v1_rms_v, 4),
            fmt_sig(m.max_vdiff_rms_v, 4),
            fmt_sig(m.mean_blocks, 3),
            m.simulated_periods.to_string(),
            m.integrator_steps.to_string(),
            m.contact_events.to_string(),
        ]);
    }
    md.push_str(&t.render());
    if let Some(rel) = jump_difference {
        let class = claims.require_class("frequency")?;
        md.push_str(&format!(
            "\nJump with the Hertz law relative to the linear law: {} % (agreement means \
             within {} %, the claims file's frequency class).\n",
            fmt_sig(100.0 * rel, 2),
            100.0 * class.tol_rel
        ));
    }
    md.push_str(&format!(
        "\n### Convergence\n\nEach sweep repeated with half the frequency step, half the \
         integrator tolerance, half the steady-state tolerance and half the refinement bracket. \
         Required: onset and branch end move by less than {} %, RMS voltages by less than {} %.\n\n",
        100.0 * CONV_FREQ_REL,
        100.0 * CONV_RMS_REL
    ));
    let mut t: Table<8> = Table::new(md::join(["curve"], CONVERGENCE_COLUMNS));
    for (c, v) in run.sweeps.curves.iter().zip(run.sweeps.convergence()) {
        t.row(md::join([c.spec.label()], convergence_cells(&v)));
    }
    md.push_str(&t.render());
    exp.write_numbers_md(&md)?;
    exp.write_plot(&plot(run))?;
    exp.finish()
}

fn plot(run: &fig13::Run) -> LinePlot {
    let series = run
        .sweeps
        .curves
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let pts = c
                .report
                .measurements_in_range()
                .map(|m| (m.freq_hz, m.v1_rms_v))
                .collect();
            let style = match c.spec.stiffness {
                StiffnessModel::Hertz => Style::Dashed,
                StiffnessModel::Linear => Style::LinePoints,
            };
            Series::new(
                &format!("simulation: {}", c.spec.label()),
                pts,
                PALETTE[i],
                style,
            )
        })
        .collect();
    LinePlot::new(
        &format!("Figure 13: prototype 2, {FIG13_BIAS_V} V, up-sweeps (published parameters)"),
        "Frequency [Hz]",
        "RMS output voltage V1 [V]",
        series,
    )
    .x(600.0, 850.0)
    .legend(LegendPos::UpperRight)
}
