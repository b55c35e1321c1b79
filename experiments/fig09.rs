//! Figure 9: prototype 1 at 1220 Hz, output power against RMS acceleration (0.5-5.5 g) for
//! bias voltages 20, 30 and 40 V (claims F9-a, F9-b), under the published and the calibrated
//! parameters, with both readings of "output power" (one load, both loads) and a convergence
//! check (half the amplitude step, integrator tolerance, steady-state tolerance and bracket).

use endstop_experiments as common;

use endstop_experiments::sweep_table::claim_cells;

use anyhow::Result;
use common::plot::{LegendPos, LinePlot, Series, Style, PALETTE};
use common::{fmt_sig, load_device, Experiment};
use endstop::device::Device;
use endstop::paper::claims::Claim;
use endstop::paper::claims::ClaimValue;
use endstop::paper::claims::Claims;
use endstop::paper::fig09::figure9_claims;
use endstop::paper::fig09::run_figure9;
use endstop::paper::fig09::AmplitudeCurve;
use endstop::paper::fig09::PowerReading;
use endstop::paper::fig09::FIG9_BIASES_V;
use endstop::paper::fig09::FIG9_BIM_N_S_PER_M;
use endstop::paper::fig09::ONSET_SAME_TOL_G;
use endstop::paper::measured::P1_RESONANCE_HZ;
use endstop::study::amplitude::compare_amplitude;
use polars::prelude::*;

/// The reading of "output power" our verdicts use (see the chapter: the paper's own numbers
/// support one load).
const DEFAULT_READING: PowerReading = PowerReading::OneLoad;
/// Convergence limits, applied to the onset (g) and the powers.
const CONV_ONSET_G: f64 = 0.01;
const CONV_RMS_REL: f64 = 0.01;

fn main() {
    common::run_main("fig09", run);
}

struct SetRun {
    set: &'static str,
    device: Device,
    curves: Vec<AmplitudeCurve>,
    halved: Vec<AmplitudeCurve>,
    claims: Vec<ClaimValue>,
    claims_both: Vec<ClaimValue>,
}

fn run() -> Result<()> {
    let mut exp = Experiment::start("fig09");
    let p1 = load_device("prototype1")?;
    exp.uses(&p1, "published");
    let (cal_loaded, cal) = common::calibrated_prototype1(&p1)?;
    exp.uses(&cal_loaded, "calibrated");
    let claims_file = Claims::bundled()?.claims;

    let settings = endstop::paper::fig09::amplitude_settings(&p1.device);
    let fine = settings.halved();
    let sets: Vec<(&'static str, Device)> = vec![
        ("published", p1.device.clone()),
        ("calibrated", cal.device.clone()),
    ];
    let total =
        sets.len() * FIG9_BIASES_V.len() * (settings.accels_rms_g.len() + fine.accels_rms_g.len());
    let pb = common::progress(total as u64, "fig09");
    let tick = || pb.inc(1);
    let runs: Vec<SetRun> = sets
        .into_iter()
        .map(|(set, device)| -> Result<SetRun> {
            let (curves, halved) = rayon::join(
                || run_figure9(&device, &FIG9_BIASES_V, &settings, &tick),
                || run_figure9(&device, &FIG9_BIASES_V, &fine, &tick),
            );
            let curves = curves?;
            Ok(SetRun {
                set,
                device,
                claims: figure9_claims(&curves, DEFAULT_READING),
                claims_both: figure9_claims(&curves, PowerReading::BothLoads),
                curves,
                halved: halved?,
            })
        })
        .collect::<Result<_>>()?;
    pb.finish_and_clear();

    for r in &runs {
        for c in &r.claims {
            exp.claim_with_uncertainty(c.id, c.quantity, r.set, c.value, c.uncertainty);
        }
        for c in &r.curves {
            let k = format!("{}_{}v", r.set, c.bias_v);
            if let Some(t) = c.report.onset {
                exp.number(&format!("{k}_onset_g"), t.value());
            }
            let m = c.report.at_stop();
            exp.number(&format!("{k}_p1_at_5p5g_w"), m.p1_w);
            exp.number(&format!("{k}_p_both_at_5p5g_w"), m.p_total_w());
        }
    }
    exp.number("calibrated_gap_m", cal.fitted_gap_m);
    write_parquet(&exp, &runs)?;
    exp.write_numbers_md(&numbers_md(&runs, &claims_file))?;
    exp.write_plot(&power_plot(&runs))?;
    exp.finish()
}

fn write_parquet(exp: &Experiment, runs: &[SetRun]) -> Result<()> {
    let (mut a, mut f, mut vb, mut v1, mut v2, mut vd) =
        (vec![], vec![], vec![], vec![], vec![], vec![]);
    let (mut p1, mut p2, mut x, mut cf, mut imp) = (vec![], vec![], vec![], vec![], vec![]);
    let (mut blocks, mut conv, mut beyond, mut series, mut params, mut gap) =
        (vec![], vec![], vec![], vec![], vec![], vec![]);
    for r in runs {
        for c in &r.curves {
            let ext = c.report.extended_from.unwrap_or(usize::MAX);
            for (i, s) in c.report.sweep.steps.iter().enumerate() {
                let m = &s.measurement;
                a.push(m.accel_rms_g);
                f.push(m.freq_hz);
                vb.push(c.bias_v);
                v1.push(m.v1_rms_v);
                v2.push(m.v2_rms_v);
                vd.push(m.vdiff_rms_v);
                p1.push(m.p1_w);
                p2.push(m.p2_w);
                x.push(m.x_peak_m);
                cf.push(m.contact_fraction);
                imp.push(m.impacts_per_period);
                blocks.push(m.blocks as u32);
                conv.push(m.converged);
                beyond.push(i >= ext);
                series.push(format!(
                    "Vb={} V, Hertz, b_im={FIG9_BIM_N_S_PER_M}",
                    c.bias_v
                ));
                params.push(r.set.to_string());
                gap.push(r.device.geometry.endstop_gap_m);
            }
        }
    }
    let mut df = df!(
        "accel_rms_g" => a,
        "freq_hz" => f,
        "bias_v" => vb,
        "v1_rms_v" => v1,
        "v2_rms_v" => v2,
        "vdiff_rms_v" => vd,
        "p1_w" => p1,
        "p2_w" => p2,
        "x_peak_m" => x,
        "contact_fraction" => cf,
        "impacts_per_period" => imp,
        "blocks" => blocks,
        "converged" => conv,
        "beyond_paper_range" => beyond,
        "series" => series,
        "params" => params,
        "endstop_gap_m" => gap,
    )?;
    exp.write_parquet("fig09", &mut df, "published+calibrated")?;
    Ok(())
}

fn claims_table(md: &mut String, runs: &[SetRun], claims: &[Claim], both: bool) {
    md.push_str(
        "| claim | quantity | paper | published: ours | what | verdict | calibrated: ours | what | verdict |\n\
         |---|---|---|---|---|---|---|---|---|\n",
    );
    for c in claims.iter().filter(|c| c.experiment == "fig09") {
        if both && c.id != "F9-b" {
            continue;
        }
        let cell = |r: &SetRun| claim_cells(c, if both { &r.claims_both } else { &r.claims }, 4);
        let (a, b, v) = cell(&runs[0]);
        let (d, e, w) = cell(&runs[1]);
        let paper = if c.unit == "bool" {
            "yes".to_string()
        } else {
            format!("{} {}", c.paper, c.unit)
        };
        md.push_str(&format!(
            "| {} | `{}` | {paper} | {a} | {b} | **{v}** | {d} | {e} | **{w}** |\n",
            c.id, c.quantity
        ));
    }
}

fn numbers_md(runs: &[SetRun], claims: &[Claim]) -> String {
    let mut md = String::new();
    md.push_str(&format!(
        "### Claims (power of {}, the default reading)\n\nThe onsets are the same for all bias \
         voltages when their spread is at most {ONSET_SAME_TOL_G} g, the claims file's tolerance \
         for amplitude thresholds.\n\n",
        DEFAULT_READING.label()
    ));
    claims_table(&mut md, runs, claims, false);
    md.push_str(&format!(
        "\n### The other reading: power of {}\n\nThe same simulations, with the power of both \
         loads compared with the paper's numbers (not used for the scorecard).\n\n",
        PowerReading::BothLoads.label()
    ));
    claims_table(&mut md, runs, claims, true);

    md.push_str(&format!(
        "\n### Every continuation\n\n{P1_RESONANCE_HZ} Hz, Hertz contact, b_im = \
         {FIG9_BIM_N_S_PER_M} N s/m; onset refined to a bracket of 0.005 g (midpoint shown). A \
         continuation that has not touched a stop by 5.5 g is continued in the same steps until \
         it does.\n\n\
         | set | xmax (um) | Vb (V) | onset (g rms) | beyond 5.5 g | P one load at 5.5 g (nW) | P both loads at 5.5 g (nW) | V1 rms at 5.5 g (V) | peak x at 5.5 g (um) | contact fraction at 5.5 g |\n\
         |---|---|---|---|---|---|---|---|---|---|\n"
    ));
    for r in runs {
        for c in &r.curves {
            let m = c.report.at_stop();
            md.push_str(&format!(
                "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
                r.set,
                fmt_sig(r.device.geometry.endstop_gap_m * 1e6, 4),
                c.bias_v,
                c.report
                    .onset
                    .map(|t| fmt_sig(t.value(), 4))
                    .unwrap_or_else(|| "none".into()),
                if c.report.extended_from.is_some() {
                    "yes"
                } else {
                    "no"
                },
                fmt_sig(m.p1_w * 1e9, 4),
                fmt_sig(m.p_total_w() * 1e9, 4),
                fmt_sig(m.v1_rms_v, 4),
                fmt_sig(m.x_peak_m * 1e6, 4),
                fmt_sig(m.contact_fraction, 3),
            ));
        }
    }

    md.push_str(&format!(
        "\n### Convergence\n\nEach continuation repeated with half the amplitude step, half the \
         integrator tolerance, half the steady-state tolerance and half the onset bracket. \
         Required: onset moves by less than {CONV_ONSET_G} g, powers and RMS voltages by less \
         than {} %.\n\n\
         | set | Vb (V) | onset change (g) | power change at 5.5 g | max V1 change | within limits |\n|---|---|---|---|---|---|\n",
        100.0 * CONV_RMS_REL
    ));
    for r in runs {
        for (c, f) in r.curves.iter().zip(&r.halved) {
            let cmp = compare_amplitude(&c.report, &f.report);
            let ok = cmp.onset_abs_g.unwrap_or(0.0) < CONV_ONSET_G
                && cmp.p_rel < CONV_RMS_REL
                && cmp.max_v1_rel < CONV_RMS_REL;
            md.push_str(&format!(
                "| {} | {} | {} | {} % | {} % | {} |\n",
                r.set,
                c.bias_v,
                cmp.onset_abs_g
                    .map(|x| fmt_sig(x, 2))
                    .unwrap_or_else(|| "n/a".into()),
                fmt_sig(100.0 * cmp.p_rel, 2),
                fmt_sig(100.0 * cmp.max_v1_rel, 2),
                if ok { "yes" } else { "**no**" }
            ));
        }
    }
    md
}

fn power_plot(runs: &[SetRun]) -> LinePlot {
    let mut series = Vec::new();
    for r in runs.iter().rev() {
        for (i, c) in r.curves.iter().enumerate() {
            let pts: Vec<(f64, f64)> = c
                .report
                .measurements_in_range()
                .map(|m| (m.accel_rms_g, DEFAULT_READING.of(m) * 1e9))
                .collect();
            let style = if r.set == "published" {
                Style::Dashed
            } else {
                Style::LinePoints
            };
            series.push(Series::new(
                &format!("simulation ({}): Vb = {} V", r.set, c.bias_v),
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
