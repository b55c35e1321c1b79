//! Figure 8: prototype 1 at 30 V, stepped-sine up-sweeps 900-1600 Hz at 4.1 and 5.5 g rms with
//! several end-stop models (claims F8-a..F8-f), under the published parameters and under the
//! calibrated set (end-stop gap fitted to the measured impact onset, see
//! `endstop::paper::calibration::calibrate_prototype1`). Also: the paper's own fit of b_im to the
//! measured jump, the tension-free contact as a sensitivity, and a convergence study (half the
//! frequency step, integrator tolerance, steady-state tolerance and refinement bracket).

use endstop_experiments as common;

use endstop_experiments::sweep_table::{claim_cells, SweepTable};

use anyhow::Result;
use common::plot::{LegendPos, LinePlot, Series, Style, PALETTE};
use common::{fmt_sig, load_device, Experiment};
use endstop::device::Device;
use endstop::device::StiffnessModel;
use endstop::paper::calibration::fit_bim_for_jump;
use endstop::paper::calibration::BimFit;
use endstop::paper::calibration::Calibration;
use endstop::paper::calibration::BIM_FIT_TOL_HZ;
use endstop::paper::claims::Claim;
use endstop::paper::claims::ClaimValue;
use endstop::paper::claims::Claims;
use endstop::paper::curves::run_curves;
use endstop::paper::curves::Curve;
use endstop::paper::fig08::figure8_claims;
use endstop::paper::fig08::figure8_curves;
use endstop::paper::fig08::P1_HIGH_ACCEL_RMS_G;
use endstop::paper::fig08::P1_SWEEP_STOP_HZ;
use endstop::paper::measured::P1_MEASURED_JUMP_HZ;
use endstop::paper::measured::P1_MEASURED_ONSET_HZ;
use endstop::paper::setups::P1_BIAS_V;
use endstop::study::sweep::compare_sweeps;
use endstop::study::sweep::SweepComparison;
use polars::prelude::*;

/// Convergence thresholds: transitions 0.5 %, RMS voltages 1 %.
const CONV_FREQ_REL: f64 = 0.005;
const CONV_RMS_REL: f64 = 0.01;

fn main() {
    common::run_main("fig08", run);
}

/// One parameter set's results.
struct SetRun {
    set: &'static str,
    device: Device,
    curves: Vec<Curve>,
    halved: Vec<Curve>,
    claims: Vec<ClaimValue>,
    fits: Vec<BimFit>,
}

fn run() -> Result<()> {
    let mut exp = Experiment::start("fig08");
    let p1 = load_device("prototype1")?;
    exp.uses(&p1, "published");
    let (cal_loaded, cal) = common::calibrated_prototype1(&p1)?;
    exp.uses(&cal_loaded, "calibrated");
    let claims_file = Claims::bundled()?.claims;

    let specs = figure8_curves();
    let sets: Vec<(&'static str, Device)> = vec![
        ("published", p1.device.with_bias(P1_BIAS_V)),
        ("calibrated", cal.device.with_bias(P1_BIAS_V)),
    ];
    let settings = endstop::paper::fig08::sweep_settings(&p1.device);
    let fine = settings.halved();
    let total = sets.len() * specs.len() * (settings.freqs_hz.len() + fine.freqs_hz.len());
    let pb = common::progress(total as u64, "fig08");
    let tick = || pb.inc(1);
    let runs: Vec<SetRun> = sets
        .into_iter()
        .map(|(set, device)| -> Result<SetRun> {
            let ((curves, halved), fits) = rayon::join(
                || {
                    rayon::join(
                        || run_curves(&device, &specs, &settings, &tick),
                        || run_curves(&device, &specs, &fine, &tick),
                    )
                },
                || {
                    use rayon::prelude::*;
                    [(StiffnessModel::Hertz, 1.5), (StiffnessModel::Linear, 2.0)]
                        .par_iter()
                        .map(|&(law, b)| {
                            fit_bim_for_jump(
                                &device.with_endstop(law, b),
                                P1_MEASURED_JUMP_HZ,
                                P1_HIGH_ACCEL_RMS_G,
                                &settings,
                                BIM_FIT_TOL_HZ,
                            )
                        })
                        .collect::<Result<Vec<_>, _>>()
                },
            );
            let curves = curves?;
            let claims = figure8_claims(&curves, P1_SWEEP_STOP_HZ);
            Ok(SetRun {
                set,
                device,
                curves,
                halved: halved?,
                claims,
                fits: fits?,
            })
        })
        .collect::<Result<_>>()?;
    pb.finish_and_clear();

    for r in &runs {
        for c in &r.claims {
            exp.claim_with_uncertainty(c.id, c.quantity, r.set, c.value, c.uncertainty);
        }
    }
    record_numbers(&mut exp, &cal, &runs);
    write_parquet(&exp, &runs)?;
    exp.write_numbers_md(&numbers_md(&cal, &runs, &claims_file))?;
    for r in &runs {
        let plot = sweep_plot(r);
        if r.set == "published" {
            exp.write_plot(&plot)?;
        } else {
            exp.write_extra_plot(&format!("fig08_{}", r.set), &plot)?;
        }
    }
    exp.finish()
}

fn law(s: StiffnessModel) -> &'static str {
    match s {
        StiffnessModel::Hertz => "hertz",
        StiffnessModel::Linear => "linear",
    }
}

/// A key fragment for a curve, e.g. `5p5g_hertz_bim1p5_tf`.
fn key(c: &Curve) -> String {
    let s = &c.spec;
    format!(
        "{}g_{}_bim{}{}",
        s.accel_rms_g,
        law(s.stiffness),
        s.bim_n_s_per_m,
        if s.tension_free { "_tf" } else { "" }
    )
    .replace('.', "p")
}

fn record_numbers(exp: &mut Experiment, cal: &Calibration, runs: &[SetRun]) {
    exp.number("calibrated_gap_m", cal.fitted_gap_m);
    exp.number("published_gap_m", cal.published_gap_m);
    exp.number("calibration_target_onset_hz", cal.target_onset_hz);
    exp.number("calibration_achieved_onset_hz", cal.achieved_onset_hz);
    exp.number("calibration_evaluations", cal.iterations as f64);
    for r in runs {
        for c in &r.curves {
            let k = format!("{}_{}", r.set, key(c));
            if let Some(t) = c.report.onset {
                exp.number(&format!("{k}_onset_hz"), t.value());
            }
            if let Some(e) = c.report.branch_end() {
                exp.number(&format!("{k}_branch_end_hz"), e.transition.value());
                exp.number(
                    &format!("{k}_branch_end_is_jump"),
                    f64::from(u8::from(
                        e.kind == endstop::study::sweep::BranchEndKind::Jump,
                    )),
                );
            }
            exp.number(&format!("{k}_max_v1_rms_v"), c.report.max_v1_rms_v());
        }
        for f in &r.fits {
            let k = format!("{}_bim_fit_{}", r.set, law(f.stiffness));
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

fn write_parquet(exp: &Experiment, runs: &[SetRun]) -> Result<()> {
    let mut table = SweepTable::default();
    for r in runs {
        table.push_curves(&r.device, &r.curves);
    }
    let mut df = table.frame()?;
    exp.write_parquet("fig08", &mut df, "published+calibrated")?;

    // Convergence: one row per set and curve.
    let mut conv = ConvCols::default();
    for r in runs {
        for (c, f) in r.curves.iter().zip(&r.halved) {
            conv.push(r.set, c, compare_sweeps(&c.report, &f.report), f);
        }
    }
    let mut df = conv.frame()?;
    exp.write_parquet("fig08_convergence", &mut df, "published+calibrated")?;

    // b_im fits: one row per evaluation.
    let (mut set, mut st, mut b, mut end, mut kind) = (vec![], vec![], vec![], vec![], vec![]);
    for r in runs {
        for f in &r.fits {
            for s in &f.samples {
                set.push(r.set.to_string());
                st.push(law(f.stiffness).to_string());
                b.push(s.bim_n_s_per_m);
                end.push(s.end.map(|e| e.transition.value()).unwrap_or(f64::NAN));
                kind.push(s.end.map(|e| e.kind.label()).unwrap_or("none").to_string());
            }
        }
    }
    let mut df = df!(
        "params" => set,
        "stiffness" => st,
        "bim_n_s_per_m" => b,
        "branch_end_hz" => end,
        "branch_end_kind" => kind,
    )?;
    exp.write_parquet("fig08_bim_fits", &mut df, "published+calibrated")?;
    Ok(())
}

#[derive(Default)]
struct ConvCols {
    set: Vec<String>,
    series: Vec<String>,
    onset_rel: Vec<f64>,
    end_rel: Vec<f64>,
    same_kind: Vec<bool>,
    v1_rel: Vec<f64>,
    v2_rel: Vec<f64>,
    compared: Vec<u32>,
    excluded: Vec<u32>,
    onset_fine: Vec<f64>,
    end_fine: Vec<f64>,
}

impl ConvCols {
    fn push(&mut self, set: &str, c: &Curve, cmp: SweepComparison, fine: &Curve) {
        self.set.push(set.to_string());
        self.series.push(c.spec.label());
        self.onset_rel.push(cmp.onset_rel.unwrap_or(f64::NAN));
        self.end_rel.push(cmp.end_rel.unwrap_or(f64::NAN));
        self.same_kind.push(cmp.same_end_kind);
        self.v1_rel.push(cmp.max_v1_rel);
        self.v2_rel.push(cmp.max_v2_rel);
        self.compared.push(cmp.compared as u32);
        self.excluded.push(cmp.excluded as u32);
        self.onset_fine
            .push(fine.report.onset.map(|t| t.value()).unwrap_or(f64::NAN));
        self.end_fine.push(
            fine.report
                .branch_end()
                .map(|e| e.transition.value())
                .unwrap_or(f64::NAN),
        );
    }

    fn frame(self) -> Result<DataFrame> {
        Ok(df!(
            "params" => self.set,
            "series" => self.series,
            "onset_rel_change" => self.onset_rel,
            "branch_end_rel_change" => self.end_rel,
            "same_branch_end_kind" => self.same_kind,
            "max_v1_rms_rel_change" => self.v1_rel,
            "max_v2_rms_rel_change" => self.v2_rel,
            "frequencies_compared" => self.compared,
            "frequencies_excluded" => self.excluded,
            "onset_refined_run_hz" => self.onset_fine,
            "branch_end_refined_run_hz" => self.end_fine,
        )?)
    }
}

fn pct(x: Option<f64>) -> String {
    match x {
        Some(v) if v.is_finite() => format!("{} %", fmt_sig(100.0 * v, 2)),
        _ => "n/a".into(),
    }
}

fn hz(x: Option<f64>) -> String {
    x.map(|v| fmt_sig(v, 5)).unwrap_or_else(|| "none".into())
}

fn numbers_md(cal: &Calibration, runs: &[SetRun], claims: &[Claim]) -> String {
    let mut md = String::new();
    md.push_str(&format!(
        "### Calibration\n\nOne parameter, the end-stop gap xmax, fitted so that the 5.5 g, 30 V \
         up-sweep first touches a stop at the paper's measured kink ({} Hz): a root find on xmax, \
         each evaluation a sweep plus a refined onset.\n\n\
         | published xmax (um) | calibrated xmax (um) | ratio | target onset (Hz) | achieved onset (Hz) | onset bracket (Hz) | evaluations |\n|---|---|---|---|---|---|---|\n\
         | {} | {} | {} | {} | {} | {} .. {} | {} |\n",
        P1_MEASURED_ONSET_HZ,
        fmt_sig(cal.published_gap_m * 1e6, 4),
        fmt_sig(cal.fitted_gap_m * 1e6, 5),
        fmt_sig(cal.fitted_gap_m / cal.published_gap_m, 4),
        cal.target_onset_hz,
        fmt_sig(cal.achieved_onset_hz, 6),
        fmt_sig(cal.onset_bracket.before, 6),
        fmt_sig(cal.onset_bracket.after, 6),
        cal.iterations
    ));

    md.push_str(
        "\n### Claims\n\nOur value, what it is, and the verdict with the claims file's \
         tolerance. Where a sweep has no jump, the value given for a jump claim is the frequency \
         at which the impacting branch ends by a gradual loss of contact, and it says so.\n\n\
         | claim | quantity | paper | published: ours | what | verdict | calibrated: ours | what | verdict |\n\
         |---|---|---|---|---|---|---|---|---|\n",
    );
    let pubr = &runs[0];
    let calr = &runs[1];
    for c in claims.iter().filter(|c| c.experiment == "fig08") {
        let cell = |r: &SetRun| claim_cells(c, &r.claims, 5);
        let (a, b, v) = cell(pubr);
        let (d, e, w) = cell(calr);
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

    md.push_str(
        "\n### Every sweep\n\nOnset and branch end are refined to brackets of 0.1 Hz (midpoints \
         shown). The jump power ratio is the total output power just after over just before the \
         refined jump. Steps beyond 1600 Hz exist only where the impacting branch outlived the \
         paper's range and the sweep was continued to find its end.\n\n\
         | set | curve | onset (Hz) | branch end (Hz) | how it ends | jump power ratio | max V1 rms (V) | max (V2-V1) rms (V) | max penetration (nm) | steps beyond 1600 Hz | steps converged | integrator steps |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in runs {
        for c in &r.curves {
            let rep = &c.report;
            let end = rep.branch_end();
            let n = rep.sweep.steps.len();
            let beyond = rep.extended_from.map(|k| n - k).unwrap_or(0);
            let conv = rep.measurements().filter(|m| m.converged).count();
            let vd = rep
                .measurements_in_range()
                .map(|m| m.vdiff_rms_v)
                .fold(0.0, f64::max);
            let st = rep.total_stats();
            let pen = rep
                .measurements()
                .map(|m| m.x_peak_m - r.device.geometry.endstop_gap_m)
                .fold(0.0, f64::max);
            md.push_str(&format!(
                "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {}/{} | {} |\n",
                r.set,
                c.spec.label(),
                hz(rep.onset.map(|t| t.value())),
                hz(end.map(|e| e.transition.value())),
                end.map(|e| e.kind.label()).unwrap_or(if rep.any_contact() {
                    "contact to the end"
                } else {
                    "no contact"
                }),
                rep.jump_power_ratio
                    .map(|x| fmt_sig(x, 3))
                    .unwrap_or_else(|| "-".into()),
                fmt_sig(rep.max_v1_rms_v(), 4),
                fmt_sig(vd, 4),
                fmt_sig(pen * 1e9, 2),
                beyond,
                conv,
                n,
                st.accepted + st.rejected,
            ));
        }
    }

    md.push_str(&format!(
        "\n### The paper's procedure for b_im\n\nThe end-stop damping for which the 5.5 g \
         up-sweep's impacting branch ends at the measured {} Hz (Illinois root find on b_im, \
         branch end within {} Hz). The paper's values are 1.5 N s/m (Hertz) and 2 N s/m \
         (linear, eq 19).\n\n\
         | set | stiffness | fitted b_im (N s/m) | paper's b_im (N s/m) | branch end at the fit (Hz) | how it ends | branch end at b_im = 0 (Hz) | how it ends | evaluations |\n\
         |---|---|---|---|---|---|---|---|---|\n",
        P1_MEASURED_JUMP_HZ, BIM_FIT_TOL_HZ
    ));
    for r in runs {
        for f in &r.fits {
            let paper = match f.stiffness {
                StiffnessModel::Hertz => "1.5",
                StiffnessModel::Linear => "2",
            };
            md.push_str(&format!(
                "| {} | {} | {} | {paper} | {} | {} | {} | {} | {} |\n",
                r.set,
                law(f.stiffness),
                f.bim_n_s_per_m
                    .map(|b| fmt_sig(b, 3))
                    .unwrap_or_else(|| "none: even b_im = 0 ends below the target".into()),
                hz(f.achieved.map(|e| e.transition.value())),
                f.achieved.map(|e| e.kind.label()).unwrap_or("-"),
                hz(f.at_zero.map(|e| e.transition.value())),
                f.at_zero.map(|e| e.kind.label()).unwrap_or("-"),
                f.samples.len()
            ));
        }
    }

    md.push_str(&format!(
        "\n### Convergence\n\nEach sweep repeated with half the frequency step, half the \
         integrator tolerance, half the steady-state tolerance and half the refinement bracket. \
         Required: onset and branch end move by less than {} %, RMS voltages by less than {} % \
         (at the frequencies both runs visit, except those between the two runs' branch ends, \
         where they are legitimately on different branches).\n\n\
         | set | curve | onset change | branch end change | same kind of end | max V1 change | max V2 change | frequencies compared / excluded | within limits |\n\
         |---|---|---|---|---|---|---|---|---|\n",
        100.0 * CONV_FREQ_REL,
        100.0 * CONV_RMS_REL
    ));
    let mut worst: (f64, f64, f64) = (0.0, 0.0, 0.0);
    for r in runs {
        for (c, f) in r.curves.iter().zip(&r.halved) {
            let cmp = compare_sweeps(&c.report, &f.report);
            let ok = cmp.onset_rel.unwrap_or(0.0) < CONV_FREQ_REL
                && cmp.end_rel.unwrap_or(0.0) < CONV_FREQ_REL
                && cmp.same_end_kind
                && cmp.max_v1_rel.max(cmp.max_v2_rel) < CONV_RMS_REL;
            worst.0 = worst.0.max(cmp.onset_rel.unwrap_or(0.0));
            worst.1 = worst.1.max(cmp.end_rel.unwrap_or(0.0));
            worst.2 = worst.2.max(cmp.max_v1_rel.max(cmp.max_v2_rel));
            md.push_str(&format!(
                "| {} | {} | {} | {} | {} | {} | {} | {} / {} | {} |\n",
                r.set,
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
    }
    md.push_str(&format!(
        "\nLargest changes over all sweeps: onset {}, branch end {}, RMS voltage {}.\n",
        pct(Some(worst.0)),
        pct(Some(worst.1)),
        pct(Some(worst.2))
    ));

    md.push_str(
        "\n### Tension-free contact (sensitivity)\n\n5.5 g, Hertz, b_im = 1.5 N s/m, with eq 1 \
         as written and with the contact force clipped at zero.\n\n\
         | set | contact | onset (Hz) | branch end (Hz) | how it ends | max V1 rms (V) |\n|---|---|---|---|---|---|\n",
    );
    for r in runs {
        for c in r.curves.iter().filter(|c| {
            c.spec.accel_rms_g == P1_HIGH_ACCEL_RMS_G
                && c.spec.stiffness == StiffnessModel::Hertz
                && c.spec.bim_n_s_per_m == 1.5
        }) {
            let end = c.report.branch_end();
            md.push_str(&format!(
                "| {} | {} | {} | {} | {} | {} |\n",
                r.set,
                if c.spec.tension_free {
                    "tension-free"
                } else {
                    "eq 1 as written"
                },
                hz(c.report.onset.map(|t| t.value())),
                hz(end.map(|e| e.transition.value())),
                end.map(|e| e.kind.label()).unwrap_or("-"),
                fmt_sig(c.report.max_v1_rms_v(), 4)
            ));
        }
    }
    md
}

fn sweep_plot(r: &SetRun) -> LinePlot {
    let mut series = Vec::new();
    let mut color = 0;
    for c in &r.curves {
        let pts: Vec<(f64, f64)> = c
            .report
            .measurements_in_range()
            .map(|m| (m.freq_hz, m.v1_rms_v))
            .collect();
        let (col, style) = if c.spec.tension_free {
            (PALETTE[2], Style::Dashed)
        } else {
            let col = PALETTE[[0, 1, 2, 3, 4][color % 5]];
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
            r.set,
            fmt_sig(r.device.geometry.endstop_gap_m * 1e6, 4)
        ),
        "Frequency [Hz]",
        "RMS output voltage V1 [V]",
        series,
    )
    .x(900.0, 1600.0)
    .y(0.0, ymax)
    .legend(LegendPos::UpperRight)
}
