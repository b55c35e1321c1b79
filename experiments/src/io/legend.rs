//! The legend placed clear of the data: a plot whose curves change from run to run (a device
//! file's response, a sweep over a user's range) has no corner that is always free, so the
//! corner is chosen from the data the plot draws, and a plot the data fill gets room for its
//! legend above them.

use super::plot::{LegendPos, LinePlot, Style};

/// Height of one legend row at the legend's 15 px font, with its spacing (pixels).
const ROW_PX: f64 = 20.0;
/// Width of one character of a label at that font (pixels).
const CHAR_PX: f64 = 8.0;
/// The legend's glyph, its padding and its distance from the plot's corner (pixels).
const FRAME_PX: f64 = 60.0;
/// The axes, title and labels around the plotting area (pixels): what a plot's size holds
/// beside the area its legend sits in.
const AXES_PX: (f64, f64) = (110.0, 90.0);
/// The tallest a panel is drawn (pixels): a plot stacked in panels is shorter than its own
/// size, so its legend covers more of it; the estimate takes the shorter height.
const PANEL_PX: f64 = 430.0;
/// Points placed along each segment of a drawn line, so that a line crossing the legend's
/// box between two of its points counts as covered.
const LINE_SAMPLES: usize = 8;

/// The plot with its legend where it hides no data: in the corner whose legend box (estimated
/// from the labels) covers none of the plot's drawn points, lines sampled along their
/// segments (the plot's own corner first, then upper right, upper left, lower right, lower
/// left), else in an upper corner of a y range widened above the data by the legend's height
/// (a plot the data fill, such as a basin map).
pub fn placed_clear(plot: LinePlot) -> LinePlot {
    let (pos, covered) = best_corner(&plot);
    if covered == 0 {
        return plot.legend(pos);
    }
    let Some((_, box_h)) = legend_box(&plot) else {
        return plot;
    };
    let upper = match plot.legend {
        LegendPos::UpperRight | LegendPos::UpperLeft => plot.legend,
        LegendPos::LowerRight => LegendPos::UpperRight,
        LegendPos::LowerLeft => LegendPos::UpperLeft,
    };
    // The new top puts the old one a box height (and a little) below it: in the axis's own
    // scale, hi' - hi = f (hi' - lo) with f the box's fraction of the plot.
    let f = (box_h + 0.03).min(0.6);
    let (lo, hi) = plot.y_range;
    let top = if plot.log_y && lo > 0.0 && hi > 0.0 {
        10f64.powf((hi.log10() - f * lo.log10()) / (1.0 - f))
    } else {
        (hi - f * lo) / (1.0 - f)
    };
    plot.y(lo, top).legend(upper)
}

/// The legend box's width and height as fractions of the plotting area, with the plot drawn
/// [`PANEL_PX`] tall at most; `None` for a plot without labels.
fn legend_box(plot: &LinePlot) -> Option<(f64, f64)> {
    let labels: Vec<&str> = plot
        .series
        .iter()
        .map(|s| s.label.as_str())
        .filter(|l| !l.is_empty())
        .collect();
    if labels.is_empty() {
        return None;
    }
    let chars = labels.iter().map(|l| l.chars().count()).max().unwrap_or(0) as f64;
    let width_px = (f64::from(plot.size.0) - AXES_PX.0).max(1.0);
    let height_px = (f64::from(plot.size.1).min(PANEL_PX) - AXES_PX.1).max(1.0);
    Some((
        ((CHAR_PX * chars + FRAME_PX) / width_px).min(1.0),
        ((ROW_PX * labels.len() as f64 + FRAME_PX / 2.0) / height_px).min(1.0),
    ))
}

/// The corner covering the fewest drawn points, and how many it covers.
fn best_corner(plot: &LinePlot) -> (LegendPos, usize) {
    let Some((box_w, box_h)) = legend_box(plot) else {
        return (plot.legend, 0);
    };
    let to_unit = |v: f64, (lo, hi): (f64, f64), log: bool| -> Option<f64> {
        let (v, lo, hi) = if log {
            if v <= 0.0 || lo <= 0.0 || hi <= 0.0 {
                return None;
            }
            (v.log10(), lo.log10(), hi.log10())
        } else {
            (v, lo, hi)
        };
        let u = (v - lo) / (hi - lo);
        (u.is_finite() && (0.0..=1.0).contains(&u)).then_some(u)
    };
    let mut drawn: Vec<(f64, f64)> = Vec::new();
    for s in &plot.series {
        let lined = matches!(s.style, Style::Line | Style::Dashed | Style::LinePoints);
        let mut push = |x: f64, y: f64| {
            if let (Some(u), Some(w)) = (
                to_unit(x, plot.x_range, plot.log_x),
                to_unit(y, plot.y_range, plot.log_y),
            ) {
                drawn.push((u, w));
            }
        };
        for (i, &(x, y)) in s.points.iter().enumerate() {
            push(x, y);
            if lined && i + 1 < s.points.len() {
                let (x1, y1) = s.points[i + 1];
                for k in 1..LINE_SAMPLES {
                    let t = k as f64 / LINE_SAMPLES as f64;
                    push(x + t * (x1 - x), y + t * (y1 - y));
                }
            }
        }
    }
    let covered = |pos: LegendPos| -> usize {
        let (right, upper) = match pos {
            LegendPos::UpperRight => (true, true),
            LegendPos::UpperLeft => (false, true),
            LegendPos::LowerRight => (true, false),
            LegendPos::LowerLeft => (false, false),
        };
        drawn
            .iter()
            .filter(|&&(u, w)| {
                let in_x = if right { u >= 1.0 - box_w } else { u <= box_w };
                let in_y = if upper { w >= 1.0 - box_h } else { w <= box_h };
                in_x && in_y
            })
            .count()
    };
    [
        plot.legend,
        LegendPos::UpperRight,
        LegendPos::UpperLeft,
        LegendPos::LowerRight,
        LegendPos::LowerLeft,
    ]
    .into_iter()
    .map(|p| (p, covered(p)))
    .min_by_key(|&(_, n)| n)
    .unwrap_or((plot.legend, 0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::plot::{Series, PALETTE};

    fn plot_of(points: Vec<(f64, f64)>, legend: LegendPos) -> LinePlot {
        LinePlot::new(
            "t",
            "x",
            "y",
            vec![Series::new("data", points, PALETTE[0], Style::Dots)],
        )
        .x(0.0, 1.0)
        .y(0.0, 1.0)
        .legend(legend)
    }

    #[test]
    fn the_legend_leaves_the_corner_the_data_fill() {
        // Dots crowded in the lower right, where the plot's legend was asked to go.
        let pts: Vec<(f64, f64)> = (0..50)
            .map(|i| (0.9 + 0.002 * i as f64, 0.02 + 0.001 * i as f64))
            .collect();
        let placed = placed_clear(plot_of(pts, LegendPos::LowerRight));
        assert_ne!(placed.legend, LegendPos::LowerRight);
        assert_eq!(placed.y_range, (0.0, 1.0), "a free corner needs no room");
    }

    #[test]
    fn a_free_corner_asked_for_is_kept() {
        let pts = vec![(0.5, 0.5), (0.95, 0.95)];
        assert_eq!(
            placed_clear(plot_of(pts, LegendPos::LowerLeft)).legend,
            LegendPos::LowerLeft
        );
    }

    #[test]
    fn a_plot_the_data_fill_gets_room_above_them() {
        // A grid of dots over the whole plot: no corner is free.
        let pts: Vec<(f64, f64)> = (0..=20)
            .flat_map(|i| (0..=20).map(move |j| (i as f64 / 20.0, j as f64 / 20.0)))
            .collect();
        let placed = placed_clear(plot_of(pts, LegendPos::LowerRight));
        assert_eq!(placed.legend, LegendPos::UpperRight);
        assert!(placed.y_range.1 > 1.0, "{:?}", placed.y_range);
        let (_, covered) = best_corner(&placed);
        assert_eq!(covered, 0, "the widened range leaves the legend's box free");
    }

    #[test]
    fn a_line_crossing_the_box_between_its_points_counts() {
        // Two points outside the upper-left box, joined by a line that crosses it.
        let line = Series::new(
            "line",
            vec![(0.0, 0.8), (0.2, 1.0)],
            PALETTE[0],
            Style::Line,
        );
        let plot = LinePlot::new("t", "x", "y", vec![line])
            .x(0.0, 1.0)
            .y(0.0, 1.0)
            .legend(LegendPos::UpperLeft);
        assert_ne!(placed_clear(plot).legend, LegendPos::UpperLeft);
    }
}
