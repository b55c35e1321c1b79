//! The whole response curve at the edge: the rows and the plot of a continued branch with its
//! sweeps, shared by the `response` experiment and the `endstop response` command.

use endstop::paper::response::phase_lag_deg;
use endstop::study::continuation::{Branch, EventKind};
use endstop::study::orbit::Orbit;

use crate::frame::Row;
use crate::plot::{LegendPos, LinePlot, Panels, Series, Style, PALETTE};
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

/// A quantity of the branch's orbits against frequency: solid where the orbits are stable,
/// dashed where they are not (neighbouring segments share their end point), each kind
/// labelled once; orbits where `value` is `None` are left out.
fn branch_series(branch: &Branch, value: impl Fn(&Orbit) -> Option<f64>) -> Vec<Series> {
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
        let Some(y) = value(o) else { continue };
        if stable.is_some_and(|s| s != o.is_stable()) {
            let last = seg.last().copied();
            flush(&mut seg, stable.unwrap_or(true), &mut series);
            seg.extend(last);
        }
        stable = Some(o.is_stable());
        seg.push((o.forcing.freq_hz, y));
    }
    flush(&mut seg, stable.unwrap_or(true), &mut series);
    series
}

/// The branch's folds and grazing points, each kind with its own symbol, at `value` of their
/// orbits.
fn event_series(branch: &Branch, value: impl Fn(&Orbit) -> Option<f64>) -> Vec<Series> {
    let marks = |kind: EventKind| -> Vec<(f64, f64)> {
        branch
            .events
            .iter()
            .filter(|e| e.kind == kind)
            .filter_map(|e| value(&e.orbit).map(|y| (e.param, y)))
            .collect()
    };
    let mut out = Vec::new();
    for (kind, label, color, style) in [
        (EventKind::Fold, "folds", PALETTE[3], Style::Triangles),
        (EventKind::Grazing, "grazing", PALETTE[4], Style::Circles),
    ] {
        let pts = marks(kind);
        if !pts.is_empty() {
            out.push(Series::new(label, pts, color, style));
        }
    }
    out
}

/// The whole response of a continued branch with the sweeps over it, in two panels that share
/// the frequency axis `x_hz`: the RMS voltage of load 1 (the orbits solid where stable and
/// dashed where not, the sweeps' steps as small dots, folds and grazing points marked), and
/// the phase of the displacement against the drive ([`phase_lag_deg`]), which separates the
/// upper and the unstable branch where the stops hold their voltages together. `up` and
/// `down` are the sweeps' steps as (frequency in Hz, RMS voltage of load 1 in V).
pub fn response_figure(
    title: &str,
    branch: &Branch,
    up: Vec<(f64, f64)>,
    down: Vec<(f64, f64)>,
    x_hz: (f64, f64),
) -> Panels {
    let v1 = |o: &Orbit| Some(o.summary.v1_rms_v);
    let mut rms = branch_series(branch, v1);
    rms.push(Series::new("up-sweep", up, PALETTE[1], Style::Dots));
    rms.push(Series::new("down-sweep", down, PALETTE[2], Style::Dots));
    rms.extend(event_series(branch, v1));
    let mut phase = branch_series(branch, phase_lag_deg);
    phase.extend(event_series(branch, phase_lag_deg));
    let (lo, hi) = (x_hz.0.min(x_hz.1), x_hz.0.max(x_hz.1));
    Panels::new(vec![
        LinePlot::new(title, "frequency [Hz]", "RMS output voltage V1 [V]", rms)
            .x(lo, hi)
            .legend(LegendPos::UpperLeft),
        LinePlot::new(
            "Phase of the displacement behind the drive (periodic orbits)",
            "frequency [Hz]",
            "phase lag [deg]",
            phase,
        )
        .x(lo, hi)
        .legend(LegendPos::UpperLeft),
    ])
}
