//! An enlarged detail of a plot: [`LinePlot::zoomed`] keeps the part of each series over an x
//! range, its lines cut at the range's edges, with the y range fitted to what is kept (e.g. a
//! hysteresis band too narrow to see at the scale of a whole sweep).

use plotters::style::RGBColor;

use super::plot::{LinePlot, Series, Style};

impl LinePlot {
    /// The part of this plot over the x values `lo..=hi`, titled `title` (an enlarged detail):
    /// a line is cut where it crosses `lo` or `hi` (so that it runs to the panel's edge, and a
    /// line that leaves the range and comes back is two lines), a marker kept where it lies
    /// inside; a series left with nothing is dropped, and its label passes to the first kept
    /// series of the same colour and style; the y range is fitted to what is kept.
    pub fn zoomed(&self, title: &str, lo: f64, hi: f64) -> LinePlot {
        let mut pending: Vec<(RGBColor, Style, String)> = Vec::new();
        let mut series = Vec::new();
        for s in &self.series {
            let pieces = match s.style {
                Style::Line | Style::Dashed | Style::LinePoints => clip_x(&s.points, lo, hi),
                _ => {
                    let inside: Vec<(f64, f64)> = s
                        .points
                        .iter()
                        .copied()
                        .filter(|&(x, _)| (lo..=hi).contains(&x))
                        .collect();
                    if inside.is_empty() {
                        Vec::new()
                    } else {
                        vec![inside]
                    }
                }
            };
            let mut label = s.label.clone();
            if pieces.is_empty() {
                if !label.is_empty() {
                    pending.push((s.color, s.style, label));
                }
                continue;
            }
            if label.is_empty() {
                if let Some(i) = pending
                    .iter()
                    .position(|(c, st, _)| *c == s.color && *st == s.style)
                {
                    label = pending.remove(i).2;
                }
            }
            for points in pieces {
                series.push(Series::new(&label, points, s.color, s.style));
                label.clear();
            }
        }
        LinePlot::new(title, &self.x_label, &self.y_label, series)
            .x(lo, hi)
            .legend(self.legend)
    }
}

/// The parts of the polyline `points` with `lo <= x <= hi`, each a polyline of its own, cut
/// where a segment crosses `lo` or `hi` at the point interpolated there; a single point is kept
/// if it lies inside.
fn clip_x(points: &[(f64, f64)], lo: f64, hi: f64) -> Vec<Vec<(f64, f64)>> {
    let inside = |x: f64| (lo..=hi).contains(&x);
    if let [p] = points {
        return if inside(p.0) {
            vec![vec![*p]]
        } else {
            Vec::new()
        };
    }
    let mut pieces = Vec::new();
    let mut piece: Vec<(f64, f64)> = Vec::new();
    for w in points.windows(2) {
        let ((x0, y0), (x1, y1)) = (w[0], w[1]);
        let dx = x1 - x0;
        // The segment's part inside, as parameters t0 <= t1 along it (0 at w[0], 1 at w[1]).
        let (t0, t1) = if dx == 0.0 {
            if inside(x0) {
                (0.0, 1.0)
            } else {
                (1.0, 0.0)
            }
        } else {
            let (ta, tb) = ((lo - x0) / dx, (hi - x0) / dx);
            (ta.min(tb).max(0.0), ta.max(tb).min(1.0))
        };
        // A NaN coordinate leaves the segment out.
        if t0 > t1 || t0.is_nan() || t1.is_nan() {
            if !piece.is_empty() {
                pieces.push(std::mem::take(&mut piece));
            }
            continue;
        }
        // The segment's own ends exactly, so that neighbouring segments join.
        let at = |t: f64| {
            if t == 0.0 {
                (x0, y0)
            } else if t == 1.0 {
                (x1, y1)
            } else {
                (x0 + t * dx, y0 + t * (y1 - y0))
            }
        };
        if piece.is_empty() {
            piece.push(at(t0));
        }
        piece.push(at(t1));
        if t1 < 1.0 {
            pieces.push(std::mem::take(&mut piece));
        }
    }
    if !piece.is_empty() {
        pieces.push(piece);
    }
    pieces
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::plot::PALETTE;

    #[test]
    fn a_zoomed_plot_cuts_its_lines_at_the_edges_and_fits_y_to_them() {
        let line = |label: &str, pts: Vec<(f64, f64)>, style: Style| {
            Series::new(label, pts, PALETTE[0], style)
        };
        let plot = LinePlot::new(
            "whole",
            "f [Hz]",
            "V [V]",
            vec![
                line("stable", vec![(0.0, 0.0), (1.0, 10.0)], Style::Line),
                line(
                    "",
                    vec![(2.0, 1.0), (4.0, 2.0), (5.0, 3.0), (9.0, 20.0)],
                    Style::Line,
                ),
                line(
                    "unstable",
                    vec![(4.0, 5.0), (8.0, 5.0), (5.0, 6.0)],
                    Style::Dashed,
                ),
                Series::new("marks", vec![(8.0, 1.0)], PALETTE[1], Style::Triangles),
            ],
        );
        let z = plot.zoomed("detail", 3.0, 6.0);
        assert_eq!(z.title, "detail");
        assert_eq!(z.x_range, (3.0, 6.0));
        let labels: Vec<&str> = z.series.iter().map(|s| s.label.as_str()).collect();
        // The first series lies outside: its label passes to the second; the dashed line
        // leaves at 6 and comes back: two lines, labelled once; the marker at 8 is dropped.
        assert_eq!(labels, ["stable", "unstable", ""]);
        assert_eq!(
            z.series[0].points,
            [(3.0, 1.5), (4.0, 2.0), (5.0, 3.0), (6.0, 7.25)],
            "cut at the edges where the segments cross them"
        );
        assert_eq!(z.series[1].points, [(4.0, 5.0), (6.0, 5.0)]);
        let back = &z.series[2].points;
        // Interpolated at t = 2/3 of the segment: exact to a few ulps.
        assert_eq!(back.len(), 2);
        assert!((back[0].0 - 6.0).abs() < 1e-12 && (back[0].1 - 17.0 / 3.0).abs() < 1e-12);
        assert_eq!(back[1], (5.0, 6.0));
        // LinePlot::new's margins over the kept 1.5..7.25: 5 % of the span below, 8 % above
        // (to rounding).
        let (y0, y1) = z.y_range;
        assert!(
            (y0 - 1.2125).abs() < 1e-12 && (y1 - 7.71).abs() < 1e-12,
            "{y0} {y1}"
        );
    }
}
