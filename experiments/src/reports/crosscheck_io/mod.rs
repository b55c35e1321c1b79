//! The cross-check with ngspice (the program `crosscheck`): [`run`] compares every case and
//! setting (see `run.rs`); this module holds its report: one row per case and ngspice setting,
//! the book's table of them, their Parquet frame and the plot of the book's case.

use anyhow::Result;
use endstop::num::compare::Verdict;
use endstop::paper::crosscheck::{
    verdict_label, Setting, OUTPUT_STEPS_PER_PERIOD, TOL_FREE, TOL_IMPACTING,
};
use endstop::paper::setups::ParamSet;
use polars::prelude::*;

use crate::fmt_sig;
use crate::io::plot::{LegendPos, LinePlot, Series};

mod run;

pub use run::run;

/// One row of the table.
pub struct Row {
    pub case: String,
    pub case_label: String,
    pub device: String,
    pub stiffness: String,
    pub bim: f64,
    pub bias_v: f64,
    pub accel_rms_g: f64,
    pub freq_hz: f64,
    pub start: String,
    pub setting: String,
    pub setting_kind: Setting,
    pub setting_label: String,
    pub documented: bool,
    pub settings_text: String,
    pub span_s: f64,
    pub window_s: f64,
    pub v1_ours: f64,
    pub v2_ours: f64,
    pub v1_spice: f64,
    pub v2_spice: f64,
    pub rel_diff_v1: f64,
    pub rel_diff_v2: f64,
    pub rel_diff: f64,
    pub x_peak_ours_m: f64,
    pub x_peak_spice_m: f64,
    pub cf_ours: f64,
    pub cf_spice: f64,
    pub v1_ours_from_rest: f64,
    pub ours_s: f64,
    pub ours_steps: u64,
    pub spice_s: f64,
    pub spice_recorded: bool,
    pub spice_points: usize,
    pub tolerance: f64,
    pub impacting: bool,
    pub verdict: Verdict,
    /// Why ngspice gave no result (with [`Verdict::NotYet`]).
    pub failure: Option<String>,
}

impl Row {
    /// The verdict as the tables write it.
    pub fn verdict_label(&self) -> String {
        verdict_label(self.verdict, self.failure.as_deref())
    }
}

/// The book case's V1 over the last period: ours and ngspice's.
pub fn waveform_plot(series: Vec<Series>) -> LinePlot {
    let (lo, hi) = series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.1))
        .fold((f64::MAX, f64::MIN), |(a, b), y| (a.min(y), b.max(y)));
    let pad = 0.08 * (hi - lo).max(1e-9);
    LinePlot::new(
        "Cross-check: P1, 30 V, 7 g, 1350 Hz (Hertz), V1 over the last period",
        "time in the last period [periods]",
        "V1 [V]",
        series,
    )
    .x(0.0, 1.0)
    .y(lo - pad, hi + 3.0 * pad)
    .legend(LegendPos::UpperRight)
}

/// The book's table of the rows, ngspice named by `version`.
pub fn numbers_md(rows: &[Row], version: &str) -> String {
    let mut md = format!(
        "Simulator: {version}. Relative difference = (ngspice - ours)/ours of the RMS voltage \
         over the comparison window, the larger of V1 and V2. Tolerance: {} % without impacts, \
         {} % with impacts, applied to the documented settings. Settings marked * \
         are ngspice's defaults; T is the drive period; the output step of `.tran` is \
         T/{OUTPUT_STEPS_PER_PERIOD}. The verdict applies the tolerance to every row; only the \
         documented settings (in bold) are required to meet it. Run times are wall-clock seconds \
         (ngspice's include starting the process and writing its output); {}.\n\n",
        TOL_FREE * 100.0,
        TOL_IMPACTING * 100.0,
        if rows.iter().all(|r| r.spice_recorded) {
            "ours were measured on the machine that generated this page, ngspice's where its \
             runs were recorded"
        } else if rows.iter().any(|r| r.spice_recorded) {
            "ours were measured on the machine that generated this page, ngspice's there or, \
             for runs taken from the recording, where they were recorded"
        } else {
            "both were measured on the machine that generated this page"
        },
    );
    let mut last_case = String::new();
    for r in rows {
        if r.case != last_case {
            last_case = r.case.clone();
            md.push_str(&format!(
                "\n**{}** (`{}`). Start: {}. Span {} periods, window {} periods. Ours: V1 = {} V, \
                 V2 = {} V, peak abs(x) = {} um, time in contact {} %, {} steps in {} s.{}\n\n\
                 | ngspice setting | V1 ngspice (V) | V2 ngspice (V) | rel. diff | peak abs(x) (um) | time in contact (%) | points in window | ngspice (s) | verdict |\n\
                 |---|---|---|---|---|---|---|---|---|\n",
                r.case_label,
                r.case,
                r.start,
                (r.span_s * r.freq_hz).round(),
                (r.window_s * r.freq_hz).round(),
                fmt_sig(r.v1_ours, 7),
                fmt_sig(r.v2_ours, 7),
                fmt_sig(r.x_peak_ours_m * 1e6, 6),
                fmt_sig(r.cf_ours * 100.0, 3),
                r.ours_steps,
                fmt_sig(r.ours_s, 2),
                if r.impacting {
                    format!(
                        " Ours from rest at the same drive (the lower branch where the drive is \
                         bistable): V1 = {} V.",
                        fmt_sig(r.v1_ours_from_rest, 4)
                    )
                } else {
                    String::new()
                },
            ));
        }
        let verdict = if r.documented {
            format!("**{}**", r.verdict_label())
        } else {
            r.verdict_label()
        };
        md.push_str(&format!(
            "| {}: `{}` | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            r.setting_label,
            r.settings_text,
            fmt_sig(r.v1_spice, 7),
            fmt_sig(r.v2_spice, 7),
            sci(r.rel_diff),
            fmt_sig(r.x_peak_spice_m * 1e6, 6),
            fmt_sig(r.cf_spice * 100.0, 3),
            r.spice_points,
            fmt_sig(r.spice_s, 2),
            verdict,
        ));
    }
    // Speed: ngspice at the documented settings against ours over the same span (ngspice's
    // time includes starting the process and writing its output).
    let mut ratios: Vec<f64> = rows
        .iter()
        .filter(|r| r.documented && r.spice_s.is_finite() && r.ours_s > 0.0)
        .map(|r| r.spice_s / r.ours_s)
        .collect();
    ratios.sort_by(f64::total_cmp);
    if let (Some(lo), Some(hi)) = (ratios.first(), ratios.last()) {
        md.push_str(&format!(
            "\n**Speed.** Over the same span, ngspice at the documented settings took {} times \
             as long as ours (median of the {} cases; from {} to {}).\n",
            fmt_sig(ratios[ratios.len() / 2], 3),
            ratios.len(),
            fmt_sig(*lo, 3),
            fmt_sig(*hi, 3),
        ));
    }
    md
}

fn sci(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.1e}")
    } else {
        "-".into()
    }
}

/// The rows as a Parquet frame.
pub fn rows_df(rows: &[Row]) -> Result<DataFrame> {
    let s = |f: fn(&Row) -> String| rows.iter().map(f).collect::<Vec<String>>();
    let x = |f: fn(&Row) -> f64| rows.iter().map(f).collect::<Vec<f64>>();
    Ok(df!(
        "case" => s(|r| r.case.clone()),
        "case_label" => s(|r| r.case_label.clone()),
        "device" => s(|r| r.device.clone()),
        "stiffness" => s(|r| r.stiffness.clone()),
        "bim_n_s_per_m" => x(|r| r.bim),
        "bias_v" => x(|r| r.bias_v),
        "accel_rms_g" => x(|r| r.accel_rms_g),
        "freq_hz" => x(|r| r.freq_hz),
        "start" => s(|r| r.start.clone()),
        "setting" => s(|r| r.setting.clone()),
        "setting_label" => s(|r| r.setting_label.clone()),
        "documented" => rows.iter().map(|r| r.documented).collect::<Vec<bool>>(),
        "ngspice_options" => s(|r| r.settings_text.clone()),
        "span_s" => x(|r| r.span_s),
        "window_s" => x(|r| r.window_s),
        "v1_rms_ours_v" => x(|r| r.v1_ours),
        "v2_rms_ours_v" => x(|r| r.v2_ours),
        "v1_rms_spice_v" => x(|r| r.v1_spice),
        "v2_rms_spice_v" => x(|r| r.v2_spice),
        "rel_diff_v1" => x(|r| r.rel_diff_v1),
        "rel_diff_v2" => x(|r| r.rel_diff_v2),
        "rel_diff" => x(|r| r.rel_diff),
        "x_peak_ours_m" => x(|r| r.x_peak_ours_m),
        "x_peak_spice_m" => x(|r| r.x_peak_spice_m),
        "contact_fraction_ours" => x(|r| r.cf_ours),
        "contact_fraction_spice" => x(|r| r.cf_spice),
        "v1_rms_ours_from_rest_v" => x(|r| r.v1_ours_from_rest),
        "ours_s" => x(|r| r.ours_s),
        "ours_steps" => rows.iter().map(|r| r.ours_steps).collect::<Vec<u64>>(),
        "spice_s" => x(|r| r.spice_s),
        "spice_points_in_window" => rows.iter().map(|r| r.spice_points as u64).collect::<Vec<u64>>(),
        "tolerance" => x(|r| r.tolerance),
        "status" => s(|r| r.verdict_label()),
        "params" => s(|_| ParamSet::Published.label().to_string()),
    )?)
}
