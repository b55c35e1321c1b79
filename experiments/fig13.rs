//! Figure 13: prototype 2 at 10 V, stepped-sine up-sweeps 600-850 Hz at 0.12 and 0.31 g rms
//! with the linear end-stop law (eq 19, b_im = 0.4 N s/m) and the Hertz law (b_im = 0.34 N s/m)
//! (claim F13), published parameters, with a convergence check and the cost of the sweeps
//! (prototype 2 rings up over hundreds of periods).

use endstop_experiments as common;

use endstop_experiments::sweep_table::{claim_cells, SweepTable};

use anyhow::Result;
use common::plot::{LegendPos, LinePlot, Series, Style, PALETTE};
use common::{fmt_sig, load_device, Experiment};
use endstop::device::StiffnessModel;
use endstop::paper::claims::ClaimValue;
use endstop::paper::claims::Claims;
use endstop::paper::curves::run_curves;
use endstop::paper::curves::Curve;
use endstop::paper::fig13::figure13_claims;
use endstop::paper::fig13::figure13_curves;
use endstop::paper::setups::FIG13_BIAS_V;
use endstop::study::sweep::compare_sweeps;

const CONV_FREQ_REL: f64 = 0.005;
const CONV_RMS_REL: f64 = 0.01;

fn main() {
    common::run_main("fig13", run);
}

fn law(s: StiffnessModel) -> &'static str {
    match s {
        StiffnessModel::Hertz => "hertz",
        StiffnessModel::Linear => "linear",
    }
}

fn run() -> Result<()> {
    let mut exp = Experiment::start("fig13");
    let p2 = load_device("prototype2")?;
    exp.uses(&p2, "published");
    let claims_file = Claims::bundled()?.claims;
    let device = p2.device.with_bias(FIG13_BIAS_V);
    let specs = figure13_curves();
    let settings = endstop::paper::fig13::sweep_settings(&device);
    let fine = settings.halved();
    let total = specs.len() * (settings.freqs_hz.len() + fine.freqs_hz.len());
    let pb = common::progress(total as u64, "fig13");
    let tick = || pb.inc(1);
    let (curves, halved) = rayon::join(
        || run_curves(&device, &specs, &settings, &tick),
        || run_curves(&device, &specs, &fine, &tick),
    );
    let (curves, halved) = (curves?, halved?);
    pb.finish_and_clear();
    let claims: Vec<ClaimValue> = figure13_claims(&curves);
    for c in &claims {
        exp.claim_with_uncertainty(c.id, c.quantity, "published", c.value, c.uncertainty);
    }
    for c in &curves {
        let k = format!(
            "{}g_{}_bim{}",
            c.spec.accel_rms_g,
            law(c.spec.stiffness),
            c.spec.bim_n_s_per_m
        )
        .replace('.', "p");
        if let Some(t) = c.report.onset {
            exp.number(&format!("{k}_onset_hz"), t.value());
        }
        if let Some(t) = c.report.jump {
            exp.number(&format!("{k}_jump_hz"), t.value());
        }
        exp.number(&format!("{k}_max_v1_rms_v"), c.report.max_v1_rms_v());
    }

    // Per-step Parquet.
    let mut table = SweepTable::default();
    table.push_curves(&device, &curves);
    let mut df = table.frame()?;
    exp.write_parquet("fig13", &mut df, "published")?;

    // numbers.md
    let mut md = String::from(
        "### Claims\n\n| claim | quantity | paper | ours | what | verdict |\n|---|---|---|---|---|---|\n",
    );
    for c in claims_file.iter().filter(|c| c.experiment == "fig13") {
        let (ours, what, verdict) = claim_cells(c, &claims, 5);
        md.push_str(&format!(
            "| {} | `{}` | yes | {ours} | {what} | **{verdict}** |\n",
            c.id, c.quantity
        ));
    }
    let block = settings.cfg.block_periods;
    md.push_str(&format!(
        "\n### Every sweep\n\n{} Hz to {} Hz in {} Hz steps, Vb = {FIG13_BIAS_V} V. Steady state: \
         blocks of {block} periods (about the ring-up time 2m/b), one block to settle, then \
         blocks until the RMS voltages change by less than {} between two blocks. Onset and jump \
         refined to brackets of {} Hz (midpoints shown).\n\n\
         | curve | onset (Hz) | jump (Hz) | jump power ratio | loss of contact (Hz) | max V1 rms (V) | max (V2-V1) rms (V) | mean blocks per step | simulated periods | integrator steps | contact events |\n\
         |---|---|---|---|---|---|---|---|---|---|---|\n",
        settings.freqs_hz[0],
        settings.freqs_hz[settings.freqs_hz.len() - 1],
        settings.freqs_hz[1] - settings.freqs_hz[0],
        settings.cfg.rel_change_tol,
        settings.refine_tol_hz,
    ));
    let hz = |x: Option<f64>| x.map(|v| fmt_sig(v, 5)).unwrap_or_else(|| "none".into());
    for c in &curves {
        let r = &c.report;
        let st = r.total_stats();
        let n = r.sweep.steps.len();
        let blocks: usize = r.measurements().map(|m| m.blocks).sum();
        let periods = blocks_to_periods(r, block, settings.cfg.settle_blocks);
        let vd = r
            .measurements_in_range()
            .map(|m| m.vdiff_rms_v)
            .fold(0.0, f64::max);
        md.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            c.spec.label(),
            hz(r.onset.map(|t| t.value())),
            hz(r.jump.map(|t| t.value())),
            r.jump_power_ratio
                .map(|x| fmt_sig(x, 3))
                .unwrap_or_else(|| "-".into()),
            hz(r.contact_lost.map(|t| t.value())),
            fmt_sig(r.max_v1_rms_v(), 4),
            fmt_sig(vd, 4),
            fmt_sig(blocks as f64 / n as f64, 3),
            periods,
            st.accepted + st.rejected,
            st.events
        ));
    }
    let lin = curves
        .iter()
        .find(|c| c.spec.accel_rms_g == 0.31 && c.spec.stiffness == StiffnessModel::Linear);
    let her = curves
        .iter()
        .find(|c| c.spec.accel_rms_g == 0.31 && c.spec.stiffness == StiffnessModel::Hertz);
    if let (Some(l), Some(h)) = (lin, her) {
        if let (Some(jl), Some(jh)) = (l.report.jump, h.report.jump) {
            let rel = (jh.value() - jl.value()) / jl.value();
            exp.number("jump_hertz_minus_linear_rel", rel);
            md.push_str(&format!(
                "\nJump with the Hertz law (b_im = 0.34) relative to the linear law (b_im = 0.4): \
                 {} % (agreement means within 3 %).\n",
                fmt_sig(100.0 * rel, 2)
            ));
        }
    }
    md.push_str(&format!(
        "\n### Convergence\n\nEach sweep repeated with half the frequency step, half the \
         integrator tolerance, half the steady-state tolerance and half the refinement bracket. \
         Required: onset and branch end move by less than {} %, RMS voltages by less than {} %.\n\n\
         | curve | onset change | branch end change | same kind of end | max V1 change | max V2 change | frequencies compared / excluded | within limits |\n\
         |---|---|---|---|---|---|---|---|\n",
        100.0 * CONV_FREQ_REL,
        100.0 * CONV_RMS_REL
    ));
    let pct = |x: Option<f64>| {
        x.map(|v| format!("{} %", fmt_sig(100.0 * v, 2)))
            .unwrap_or_else(|| "n/a".into())
    };
    for (c, f) in curves.iter().zip(&halved) {
        let cmp = compare_sweeps(&c.report, &f.report);
        let ok = cmp.onset_rel.unwrap_or(0.0) < CONV_FREQ_REL
            && cmp.end_rel.unwrap_or(0.0) < CONV_FREQ_REL
            && cmp.same_end_kind
            && cmp.max_v1_rel.max(cmp.max_v2_rel) < CONV_RMS_REL;
        md.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} / {} | {} |\n",
            c.spec.label(),
            pct(cmp.onset_rel),
            pct(cmp.end_rel),
            if cmp.same_end_kind { "yes" } else { "no" },
            pct(Some(cmp.max_v1_rel)),
            pct(Some(cmp.max_v2_rel)),
            cmp.compared,
            cmp.excluded,
            if ok { "yes" } else { "**no**" }
        ));
    }
    exp.write_numbers_md(&md)?;
    exp.write_plot(&plot(&curves))?;
    exp.finish()
}

/// Simulated periods of a sweep's coarse steps: (settle + measured blocks) x block length.
fn blocks_to_periods(r: &endstop::study::sweep::SweepReport, block: usize, settle: usize) -> usize {
    r.measurements().map(|m| (m.blocks + settle) * block).sum()
}

fn plot(curves: &[Curve]) -> LinePlot {
    let series = curves
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let pts = c
                .report
                .measurements_in_range()
                .map(|m| (m.freq_hz, m.v1_rms_v))
                .collect();
            let style = if c.spec.stiffness == StiffnessModel::Hertz {
                Style::Dashed
            } else {
                Style::LinePoints
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
