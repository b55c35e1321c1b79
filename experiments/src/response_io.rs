//! The whole response curve at the edge: rows and plot series of a continued branch, shared
//! by the `response` experiment and the `endstop response` command.

use endstop::study::continuation::Branch;

use crate::frame::Row;
use crate::plot::{Series, Style, PALETTE};
use crate::row;

/// One row per orbit of `branch`, labelled `case`; `branch` numbers the segments of equal
/// stability (a new segment starts wherever the stability changes).
pub fn continuation_rows(case: &str, branch: &Branch) -> Vec<Row> {
    let mut segment = 0u32;
    let mut prev: Option<bool> = None;
    branch
        .points
        .iter()
        .map(|p| {
            let o = &p.orbit;
            if prev.is_some_and(|s| s != o.is_stable()) {
                segment += 1;
            }
            prev = Some(o.is_stable());
            row![
                "case" => case,
                "freq_hz" => o.forcing.freq_hz,
                "accel_rms_g" => o.forcing.accel_rms_g,
                "v1_rms_v" => o.summary.v1_rms_v,
                "x_max_m" => o.summary.x_max_m,
                "stable" => o.is_stable(),
                "multiplier_max_abs" => o.max_multiplier_abs(),
                "branch" => segment,
            ]
        })
        .collect()
}

/// The branch's RMS voltage of load 1 against frequency: solid where the orbits are stable,
/// dashed where they are not (neighbouring segments share their end point), each kind
/// labelled once.
pub fn branch_series(branch: &Branch) -> Vec<Series> {
    let mut series = Vec::new();
    let mut seg: Vec<(f64, f64)> = Vec::new();
    let mut stable = None;
    let mut labelled = [false, false];
    let mut flush = |seg: &mut Vec<(f64, f64)>, st: bool, series: &mut Vec<Series>| {
        if seg.len() >= 2 {
            let k = usize::from(st);
            let label = match (labelled[k], st) {
                (true, _) => "",
                (false, true) => "periodic orbits, stable",
                (false, false) => "periodic orbits, unstable",
            };
            labelled[k] = true;
            let style = if st { Style::Line } else { Style::Dashed };
            series.push(Series::new(label, std::mem::take(seg), PALETTE[0], style));
        }
        seg.clear();
    };
    for p in &branch.points {
        let o = &p.orbit;
        if stable.is_some_and(|s| s != o.is_stable()) {
            let last = seg.last().copied();
            flush(&mut seg, stable.unwrap_or(true), &mut series);
            seg.extend(last);
        }
        stable = Some(o.is_stable());
        seg.push((o.forcing.freq_hz, o.summary.v1_rms_v));
    }
    flush(&mut seg, stable.unwrap_or(true), &mut series);
    series
}
