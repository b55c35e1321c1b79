//! The plot of `endstop design`: the Pareto front of power against impact speed over the
//! designs evaluated, and the power maps (over a single range, the power against it).

use endstop::design::{Evaluated, Problem, Study};
use endstop::num::pareto::pareto_front;
use endstop_experiments::fmt_sig;
use endstop_experiments::io::legend::placed_clear;
use endstop_experiments::io::plot::{LegendPos, LinePlot, Panels, Series, Style, PALETTE};

/// The Pareto front of power against impact speed over every evaluated design (those within
/// the limits apart from those beyond one, the answer marked, the impact speed's limit drawn
/// where there is one; against the largest displacement and its limit under a noise or a
/// record, which measure no impact speed), and the power map of each interface over the first
/// two ranges (a curve per value of the second); over a single range, every design's power
/// against it, per interface.
pub(crate) fn plots(p: &Problem, study: &Study, maps: &[(usize, Vec<Evaluated>)]) -> Panels {
    let done: Vec<&Evaluated> = study
        .evaluations
        .iter()
        .filter(|e| e.result.is_ok())
        .collect();
    let speed = p.measures_impacts();
    let perf = |e: &Evaluated| {
        e.result
            .as_ref()
            .map(|q| {
                let x = if speed {
                    q.impact_speed_m_s
                } else {
                    q.displacement_m * 1e6
                };
                (x, q.power_w)
            })
            .unwrap_or_default()
    };
    let pts: Vec<(f64, f64)> = done
        .iter()
        .map(|e| {
            let (v, w) = perf(e);
            (v, -w)
        })
        .collect();
    let front: Vec<(f64, f64)> = pareto_front(&pts)
        .into_iter()
        .map(|k| (pts[k].0, -pts[k].1 * 1e6))
        .collect();
    let dots = |feasible: bool| -> Vec<(f64, f64)> {
        done.iter()
            .filter(|e| e.feasible() == feasible)
            .map(|e| {
                let (v, w) = perf(e);
                (v, w * 1e6)
            })
            .collect()
    };
    let top_uw = done.iter().map(|e| perf(e).1 * 1e6).fold(0.0, f64::max);
    let (v, w) = perf(&study.answer.design);
    let mut series = vec![
        Series::new(
            "designs within the limits",
            dots(true),
            PALETTE[2],
            Style::Dots,
        ),
        Series::new(
            "designs beyond a limit",
            dots(false),
            PALETTE[1],
            Style::Dots,
        ),
        Series::new("Pareto front", front, PALETTE[0], Style::LinePoints),
        Series::new(
            // A design whose orbit touches no stop has no impact speed: its point sits at
            // zero, which the label says rather than leaving it to read as a missing value.
            if speed && v == 0.0 {
                "the answer (touches no stop)"
            } else {
                "the answer"
            },
            vec![(v, w * 1e6)],
            PALETTE[4],
            Style::Circles,
        ),
    ];
    let limit = if speed {
        p.limits
            .impact_speed_m_s
            .map(|l| (l, format!("impact speed limit, {} m/s", fmt_sig(l, 3))))
    } else {
        p.limits.displacement_m.map(|l| {
            (
                l * 1e6,
                format!("displacement limit, {} um", fmt_sig(l * 1e6, 3)),
            )
        })
    };
    if let Some((l, label)) = limit {
        series.push(Series::new(
            &label,
            vec![(l, 0.0), (l, top_uw)],
            PALETTE[6],
            Style::Dashed,
        ));
    }
    series.retain(|s| !s.points.is_empty());
    // The designs that touch no stop sit at zero impact speed, on the y axis: the x range is
    // not padded below zero, whose ticks would then carry the float noise of the tick steps
    // (8.7e-19 for 0); the answer's label says when it touches no stop.
    let pareto = placed_clear(LinePlot::new(
        if speed {
            "Power against impact speed"
        } else {
            "Power against displacement"
        },
        if speed {
            "largest impact speed [m/s]"
        } else {
            "largest displacement [um]"
        },
        "DC power [uW]",
        series,
    ));
    let mut panels = vec![pareto];
    if p.ranges.len() == 1 {
        panels.push(over_the_range(p, &done));
    }
    for (i, grid) in maps {
        let n = (grid.len() as f64).sqrt().round() as usize;
        let series = (0..n)
            .step_by((n / 5).max(1))
            .enumerate()
            .map(|(c, j)| {
                let pts = (0..n)
                    .filter_map(|k| {
                        let e = &grid[k * n + j];
                        e.result
                            .as_ref()
                            .ok()
                            .map(|q| (e.values[0], q.power_w * 1e6))
                    })
                    .collect();
                let label = format!("{} = {}", p.ranges[1].path, fmt_sig(grid[j].values[1], 3));
                Series::new(&label, pts, PALETTE[c % PALETTE.len()], Style::LinePoints)
            })
            .collect();
        // The legend goes where it hides no curve, or above them: a fixed corner covers the
        // curves of whichever value of the second range peaks there.
        panels.push(placed_clear(
            LinePlot::new(
                &format!("Power map, {} interface", p.interfaces[*i].key()),
                &p.ranges[0].path,
                "DC power [uW]",
                series,
            )
            .log(p.ranges[0].spacing == endstop::device::Spacing::Log, false)
            .legend(LegendPos::UpperLeft),
        ));
    }
    Panels::new(panels)
}

/// Every evaluated design's power against the single range's value, a series per interface:
/// the curve a designer reads the choice off (a device without stops has every design at
/// zero impact speed, where the Pareto panel shows the powers but not what gives them).
fn over_the_range(p: &Problem, done: &[&Evaluated]) -> LinePlot {
    let range = &p.ranges[0];
    let series = p
        .interfaces
        .iter()
        .enumerate()
        .map(|(i, iface)| {
            let mut pts: Vec<(f64, f64)> = done
                .iter()
                .filter(|e| e.interface == i)
                .filter_map(|e| Some((e.values[0], e.result.as_ref().ok()?.power_w * 1e6)))
                .collect();
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            Series::new(
                &format!("{} interface", iface.key()),
                pts,
                PALETTE[i % PALETTE.len()],
                Style::Dots,
            )
        })
        .filter(|s| !s.points.is_empty())
        .collect();
    placed_clear(
        LinePlot::new(
            &format!("Power against {}", range.path),
            &range.path,
            "DC power [uW]",
            series,
        )
        .log(range.spacing == endstop::device::Spacing::Log, false),
    )
}
