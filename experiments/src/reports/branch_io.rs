//! The whole response curve at the edge: the rows and the plot of a continued branch with its
//! sweeps, shared by the `response` experiment and the `endstop response` command.

use endstop::paper::response::phase_lag_deg;
use endstop::study::continuation::impacting::Closure;
use endstop::study::continuation::{
    Branch, BranchEnd, BranchKind, Diagram, DiagramBranch, DiagramEventKind, DiagramPoint, EndKind,
    EventKind,
};
use endstop::study::orbit::Orbit;

use crate::io::frame::Row;
use crate::io::legend::placed_clear;
use crate::io::md::Table;
use crate::io::plot::{LegendPos, LinePlot, Panels, Series, Style, PALETTE};
use crate::row;

/// The index of each point's stretch of equal stability along a branch, from the points'
/// stability in order (a new stretch starts wherever the stability changes).
pub fn stability_segments(stable: impl IntoIterator<Item = bool>) -> Vec<u32> {
    let mut segment = 0u32;
    let mut prev: Option<bool> = None;
    stable
        .into_iter()
        .map(|s| {
            if prev.is_some_and(|p| p != s) {
                segment += 1;
            }
            prev = Some(s);
            segment
        })
        .collect()
}

/// One row per orbit of `branch`, labelled `case`; `branch` numbers the segments of equal
/// stability ([`stability_segments`]).
pub fn continuation_rows(case: &str, branch: &Branch) -> Vec<Row> {
    let segments = stability_segments(branch.points.iter().map(|p| p.orbit.is_stable()));
    branch
        .points
        .iter()
        .zip(segments)
        .map(|(p, segment)| {
            let o = &p.orbit;
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
    stability_series(
        branch.points.iter().filter_map(|p| {
            let o = &p.orbit;
            value(o).map(|y| (o.forcing.freq_hz, y, o.is_stable()))
        }),
        ["periodic orbits, stable", "periodic orbits, unstable"],
    )
}

/// A branch's points `(x, y, stable)` in order along it as lines: solid where stable and
/// dashed where not (neighbouring stretches share their end point), each kind labelled once
/// with `labels` = [stable, unstable].
pub fn stability_series(
    points: impl IntoIterator<Item = (f64, f64, bool)>,
    labels: [&str; 2],
) -> Vec<Series> {
    let mut series = Vec::new();
    let mut seg: Vec<(f64, f64)> = Vec::new();
    let mut stable = None;
    let mut labelled = [false, false];
    let mut flush = |seg: &mut Vec<(f64, f64)>, st: bool, series: &mut Vec<Series>| {
        if seg.len() >= 2 {
            let k = usize::from(!st);
            let label = if labelled[k] { "" } else { labels[k] };
            labelled[k] = true;
            let style = if st { Style::Line } else { Style::Dashed };
            series.push(Series::new(label, std::mem::take(seg), PALETTE[0], style));
        }
        seg.clear();
    };
    for (x, y, st) in points {
        if stable.is_some_and(|s| s != st) {
            let last = seg.last().copied();
            flush(&mut seg, stable.unwrap_or(true), &mut series);
            seg.extend(last);
        }
        stable = Some(st);
        seg.push((x, y));
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
    marked([
        (
            marks(EventKind::Fold),
            "folds",
            PALETTE[3],
            Style::Triangles,
        ),
        (
            marks(EventKind::Grazing),
            "grazing",
            PALETTE[4],
            Style::Circles,
        ),
    ])
}

/// A series for each group of event marks that has any: a kind of event absent from a branch
/// gets no legend entry.
fn marked<'a>(
    groups: impl IntoIterator<Item = (Vec<(f64, f64)>, &'a str, plotters::style::RGBColor, Style)>,
) -> Vec<Series> {
    groups
        .into_iter()
        .filter(|(pts, ..)| !pts.is_empty())
        .map(|(pts, label, color, style)| Series::new(label, pts, color, style))
        .collect()
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
    Panels::new(voltage_and_phase(title, rms, phase, x_hz, LegendPos::UpperLeft).into())
}

/// The two panels of a response over the frequencies `x_hz`: the RMS voltage of load 1 and
/// the phase lag, each with its legend in the corner `corner` if that hides no data, else
/// where [`placed_clear`] puts it.
fn voltage_and_phase(
    title: &str,
    rms: Vec<Series>,
    phase: Vec<Series>,
    x_hz: (f64, f64),
    corner: LegendPos,
) -> [LinePlot; 2] {
    let (lo, hi) = (x_hz.0.min(x_hz.1), x_hz.0.max(x_hz.1));
    [
        placed_clear(
            LinePlot::new(title, "frequency [Hz]", "RMS output voltage V1 [V]", rms)
                .x(lo, hi)
                .legend(corner),
        ),
        placed_clear(
            LinePlot::new(
                "Phase of the displacement behind the drive (periodic orbits)",
                "frequency [Hz]",
                "phase lag [deg]",
                phase,
            )
            .x(lo, hi)
            .legend(corner),
        ),
    ]
}

/// One row per orbit of every branch of a diagram, labelled `case`: the columns of
/// [`continuation_rows`] with `branch` the branch's index in the diagram, and beside them the
/// branch's label, the segment of equal stability (numbered over the whole diagram), whether
/// the orbit is symmetric, its periods and impacts, its smallest impact speed (null without
/// impacts), the largest modulus of its half-period map's multipliers (null for an orbit that
/// is not symmetric) and the phase of its displacement behind the drive.
pub fn diagram_rows(case: &str, d: &Diagram) -> Vec<Row> {
    let mut rows = Vec::new();
    let mut segment = 0u32;
    for (i, b) in d.branches.iter().enumerate() {
        let mut prev: Option<bool> = None;
        // A point past the end of a branch where no stable orbit is found is measured, not
        // continued: it has no multipliers (NaN in their columns, unstable in `stable`).
        let continued = b.kind != BranchKind::Stepped;
        for p in &b.points {
            if prev.is_some_and(|s| s != p.is_stable()) {
                segment += 1;
            }
            prev = Some(p.is_stable());
            let speed = p
                .impact_speeds_m_s
                .iter()
                .copied()
                .fold(None, |m: Option<f64>, s| Some(m.map_or(s, |m| m.min(s))));
            rows.push(row![
                "case" => case,
                "freq_hz" => p.forcing.freq_hz,
                "accel_rms_g" => p.forcing.accel_rms_g,
                "v1_rms_v" => p.summary.v1_rms_v,
                "x_max_m" => p.summary.x_max_m,
                "stable" => continued && p.is_stable(),
                "multiplier_max_abs" => if continued { p.max_multiplier_abs() } else { f64::NAN },
                "branch" => i as u32,
                "branch_label" => b.label.as_str(),
                "segment" => segment,
                "symmetric" => p.symmetric,
                "periods" => p.periods,
                "impacts" => p.summary.impacts,
                "min_impact_speed_m_s" => speed,
                "half_multiplier_max_abs" => p.half_multiplier_max_abs(),
                "phase_lag_deg" => p.phase_lag_deg(),
                "continued" => continued,
            ]);
        }
        segment += 1;
    }
    rows
}

/// A quantity of a diagram's orbits against frequency: each branch in its own colour, solid
/// where its orbits are stable and dashed where they are not (neighbouring pieces share their
/// end point), labelled once per branch.
fn diagram_series(d: &Diagram, value: impl Fn(&DiagramPoint) -> Option<f64>) -> Vec<Series> {
    let mut series = Vec::new();
    let mut shown: Vec<&str> = Vec::new();
    for b in &d.branches {
        let color = branch_color(b);
        let mut labelled = shown.contains(&b.label.as_str());
        shown.push(&b.label);
        let mut seg: Vec<(f64, f64)> = Vec::new();
        let mut stable = None;
        let mut flush = |seg: &mut Vec<(f64, f64)>, st: bool, series: &mut Vec<Series>| {
            if seg.len() >= 2 {
                let label = if labelled {
                    String::new()
                } else {
                    b.label.clone()
                };
                labelled = true;
                let style = if b.kind == BranchKind::Stepped {
                    Style::Points
                } else if st {
                    Style::Line
                } else {
                    Style::Dashed
                };
                series.push(Series::new(&label, std::mem::take(seg), color, style));
            }
            seg.clear();
        };
        for p in &b.points {
            let Some(y) = value(p) else { continue };
            // A grazing orbit of a rigid stop has no finite multipliers: drawn with its
            // neighbour's style.
            let st = if p.max_multiplier_abs().is_finite() {
                p.is_stable()
            } else {
                stable.unwrap_or(false)
            };
            if stable.is_some_and(|s| s != st) {
                let last = seg.last().copied();
                flush(&mut seg, stable.unwrap_or(true), &mut series);
                seg.extend(last);
            }
            stable = Some(st);
            seg.push((p.forcing.freq_hz, y));
        }
        flush(&mut seg, stable.unwrap_or(true), &mut series);
    }
    series
}

/// A branch's colour by its kind: non-impacting (or one continued branch), symmetric,
/// one impact a period, other period-one impacting orbits, and longer periods.
fn branch_color(b: &DiagramBranch) -> plotters::style::RGBColor {
    match &b.kind {
        BranchKind::NonImpacting | BranchKind::Continued => PALETTE[0],
        BranchKind::Stepped => PALETTE[7],
        BranchKind::Impacting(q) => match (q.closure, q.impacts()) {
            (Closure::Mirror, _) => PALETTE[5],
            (Closure::Periodic(1), 1) => PALETTE[3],
            (Closure::Periodic(1), _) => PALETTE[4],
            _ => PALETTE[6],
        },
    }
}

/// The events of a diagram, each kind with its own symbol.
fn diagram_event_series(d: &Diagram, value: impl Fn(&DiagramPoint) -> Option<f64>) -> Vec<Series> {
    let marks = |kinds: &[DiagramEventKind]| -> Vec<(f64, f64)> {
        d.events
            .iter()
            .filter(|e| kinds.contains(&e.kind))
            .filter_map(|e| value(&e.point).map(|y| (e.param, y)))
            .collect()
    };
    marked([
        (
            marks(&[DiagramEventKind::Fold]),
            "folds",
            PALETTE[3],
            Style::Triangles,
        ),
        (
            marks(&[DiagramEventKind::Grazing]),
            "grazing",
            PALETTE[4],
            Style::Circles,
        ),
        (
            marks(&[
                DiagramEventKind::SymmetryBreaking,
                DiagramEventKind::BranchPoint,
                DiagramEventKind::PeriodDoubling,
                DiagramEventKind::Torus,
            ]),
            "pitchfork, branch point, period doubling, torus",
            PALETTE[6],
            Style::Points,
        ),
    ])
}

/// The whole response of a diagram with the sweeps over it, in two panels that share the
/// frequency axis `x_hz`: the RMS voltage of load 1 (each branch in its colour, solid where
/// stable and dashed where not; the sweeps' steps as small dots; events marked) and the phase
/// of the displacement behind the drive. `up` and `down` are the sweeps' steps as (frequency
/// in Hz, RMS voltage of load 1 in V).
pub fn diagram_figure(
    title: &str,
    d: &Diagram,
    up: Vec<(f64, f64)>,
    down: Vec<(f64, f64)>,
    x_hz: (f64, f64),
) -> Panels {
    let v1 = |p: &DiagramPoint| Some(p.summary.v1_rms_v);
    let lag = |p: &DiagramPoint| p.phase_lag_deg();
    let mut rms = diagram_series(d, v1);
    rms.push(Series::new("up-sweep", up, PALETTE[1], Style::Dots));
    rms.push(Series::new("down-sweep", down, PALETTE[2], Style::Dots));
    rms.extend(diagram_event_series(d, v1));
    let mut phase = diagram_series(d, lag);
    phase.extend(diagram_event_series(d, lag));
    let mut panels: Vec<LinePlot> =
        voltage_and_phase(title, rms, phase, x_hz, LegendPos::LowerRight).into();
    // Where branches of impacting orbits meet at grazings, they crowd a narrow band: the
    // phase again, zoomed on the grazings.
    let grazings: Vec<f64> = d
        .events_of(DiagramEventKind::Grazing)
        .map(|e| e.param)
        .collect();
    let impacting = d
        .branches
        .iter()
        .filter(|b| matches!(b.kind, BranchKind::Impacting(_)))
        .count();
    if grazings.len() >= 2 && impacting >= 2 {
        let a = grazings.iter().copied().fold(f64::INFINITY, f64::min);
        let b = grazings.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let m = 0.1 * (b - a);
        let (za, zb) = (a - m, b + m);
        let inside = |s: Series| {
            let pts: Vec<(f64, f64)> = s
                .points
                .iter()
                .copied()
                .filter(|p| p.0 >= za && p.0 <= zb)
                .collect();
            Series { points: pts, ..s }
        };
        let mut zoom: Vec<Series> = diagram_series(d, lag).into_iter().map(inside).collect();
        zoom.extend(diagram_event_series(d, lag).into_iter().map(inside));
        zoom.retain(|s| !s.points.is_empty());
        panels.push(placed_clear(
            LinePlot::new(
                "The same, between the grazings",
                "frequency [Hz]",
                "phase lag [deg]",
                zoom,
            )
            .x(za, zb)
            .legend(LegendPos::LowerRight),
        ));
    }
    Panels::new(panels)
}

/// The branches and events of a diagram in words and tables (markdown): each branch with its
/// frequency span, where its orbits are stable, and how each of its ends is reached (with the
/// residual of the end's condition and the branches met there); each event with its branches
/// and the stability beside it.
pub fn diagram_words(d: &Diagram) -> String {
    let param = d.parameter;
    let name = |i: usize| {
        d.branches
            .get(i)
            .map_or("?".to_string(), |b| b.label.clone())
    };
    let mut md = String::from("\n### Branches of periodic orbits\n\n");
    let mut t = Table::new([
        "branch",
        "orbits",
        "from (Hz)",
        "to (Hz)",
        "stable (Hz)",
        "first end",
        "last end",
    ]);
    let end = |e: &BranchEnd| {
        let mut s = format!("{} at {:.4} Hz", e.kind.label(), e.param);
        match e.kind {
            EndKind::Grazing => s.push_str(&format!(", impact speed {:.1e} m/s", e.residual)),
            EndKind::NewContact => {
                s.push_str(&format!(", excursion past the stop {:.1e} m", e.residual))
            }
            EndKind::Symmetric => s.push_str(&format!(", asymmetry {:.1e} m/s", e.residual)),
            _ => {}
        }
        if !e.meets.is_empty() {
            let m: Vec<String> = e.meets.iter().map(|&i| name(i)).collect();
            s.push_str(&format!("; meets {}", m.join(", ")));
        }
        s
    };
    for b in &d.branches {
        let f: Vec<f64> = b.points.iter().map(|p| p.forcing.get(param)).collect();
        let lo = f.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = f.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        // The stretches of consecutive stable orbits.
        let mut stretches = Vec::new();
        let mut run: Option<(f64, f64)> = None;
        for p in &b.points {
            let x = p.forcing.get(param);
            if p.is_stable() {
                run = Some(run.map_or((x, x), |(a, c)| (a.min(x), c.max(x))));
            } else if let Some((a, c)) = run.take() {
                stretches.push(format!("{a:.4}-{c:.4}"));
            }
        }
        if let Some((a, c)) = run {
            stretches.push(format!("{a:.4}-{c:.4}"));
        }
        t.row([
            b.label.clone(),
            b.points.len().to_string(),
            format!("{lo:.4}"),
            format!("{hi:.4}"),
            if b.kind == BranchKind::Stepped {
                "not continued: no stable orbit of up to 4 periods".into()
            } else if stretches.is_empty() {
                "none".into()
            } else {
                stretches.join(", ")
            },
            end(&b.start),
            end(&b.end),
        ]);
    }
    md.push_str(&t.render());
    md.push_str("\n### Events\n\n");
    if d.events.is_empty() {
        md.push_str("No fold, bifurcation or grazing in this range.\n");
        return md;
    }
    let mut t = Table::new(["event", "frequency (Hz)", "branches", "stability beside it"]);
    for e in &d.events {
        let kind = e.label();
        let st = |s: bool| if s { "stable" } else { "unstable" };
        let by_branch = matches!(
            e.kind,
            DiagramEventKind::Grazing | DiagramEventKind::BranchFound
        );
        let stability = if by_branch {
            e.branches
                .iter()
                .zip(&e.stable)
                .map(|(&i, &s)| format!("{}: {}", name(i), st(s)))
                .collect::<Vec<_>>()
                .join("; ")
        } else {
            format!(
                "{} before, {} after",
                st(e.stable.first().copied().unwrap_or(false)),
                st(e.stable.get(1).copied().unwrap_or(false))
            )
        };
        t.row([
            kind,
            format!("{:.4}", e.param),
            e.branches
                .iter()
                .map(|&i| name(i))
                .collect::<Vec<_>>()
                .join(", "),
            stability,
        ]);
    }
    md.push_str(&t.render());
    md
}
