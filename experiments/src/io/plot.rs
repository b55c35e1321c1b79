//! Plots with plotters: every figure is drawn once into an SVG string and once into a PNG,
//! with the bundled DejaVu Sans font so that no system font library is needed.

use anyhow::{anyhow, Result};
use image::codecs::png::{CompressionType, FilterType, PngEncoder};
use image::ImageEncoder;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::sync::Once;

use super::decimate::min_max_per_column;

static FONT: &[u8] = include_bytes!("../../../assets/fonts/DejaVuSans.ttf");

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        for style in [FontStyle::Normal, FontStyle::Bold, FontStyle::Italic] {
            plotters::style::register_font("sans-serif", style, FONT)
                .unwrap_or_else(|_| panic!("bundled font is valid"));
        }
    });
}

/// A chart: something that draws itself on any plotters backend (one plot, or panels of them).
pub trait Chart {
    /// Pixel size (width, height).
    fn size(&self) -> (u32, u32) {
        (960, 640)
    }
    /// Title, used as the image's alternative text in the book.
    fn title(&self) -> String {
        String::new()
    }
    /// Draws on a drawing area.
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static;
}

/// Renders a figure to (SVG text, PNG bytes).
pub fn render<F: Chart>(fig: &F) -> Result<(String, Vec<u8>)> {
    register_font();
    let (w, h) = fig.size();
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area();
        fig.draw(&root)?;
        root.present().map_err(|e| anyhow!("svg: {e}"))?;
    }
    let mut rgb = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        fig.draw(&root)?;
        root.present().map_err(|e| anyhow!("png: {e}"))?;
    }
    // Fast compression with the Paeth filter on every row: a plot's pixels come out the same
    // as with the adaptive choice of filter per row, in about half the time (0.87 against
    // 1.75 ms for a 1440 x 600 figure of two panels) and 3 % more bytes.
    let mut png = Vec::new();
    PngEncoder::new_with_quality(&mut png, CompressionType::Fast, FilterType::Paeth).write_image(
        &rgb,
        w,
        h,
        image::ColorType::Rgb8,
    )?;
    Ok((svg, png))
}

/// How a series is drawn; the legend shows the same glyph (a marker alone for [`Style::Points`],
/// so that the paper's values stand apart from simulated curves).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Style {
    /// Solid line.
    Line,
    /// Dashed line.
    Dashed,
    /// Crosses only, no line (the paper's values: no simulated curve is drawn so).
    Points,
    /// Solid line with small markers.
    LinePoints,
    /// Small filled dots, no line (many simulated points that must not hide the curves
    /// beneath them).
    Dots,
    /// Filled triangles, no line (marked events, e.g. folds).
    Triangles,
    /// Open circles, no line (marked events of another kind, e.g. grazing points).
    Circles,
}

/// Points per pixel column of the plotting area above which a [`Style::Line`] is thinned to
/// each column's extremes (which keep at most four).
const DENSE_POINTS_PER_COLUMN: usize = 4;
/// Half-size of a [`Style::Points`] cross (pixels).
const POINT_RADIUS: i32 = 7;
/// Radius of a [`Style::LinePoints`] marker (pixels).
const LINE_POINT_RADIUS: i32 = 3;
/// Radius of a [`Style::Dots`] dot (pixels).
const DOT_RADIUS: i32 = 2;
/// Size of a [`Style::Triangles`] or [`Style::Circles`] marker (pixels).
const MARK_SIZE: i32 = 6;

/// One labelled curve.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend label (empty: not in the legend).
    pub label: String,
    /// (x, y) points.
    pub points: Vec<(f64, f64)>,
    /// Colour.
    pub color: RGBColor,
    /// Drawing style.
    pub style: Style,
}

impl Series {
    /// A series.
    pub fn new(label: &str, points: Vec<(f64, f64)>, color: RGBColor, style: Style) -> Self {
        Self {
            label: label.to_string(),
            points,
            color,
            style,
        }
    }
}

/// Vertical error bars: one unlabelled segment (x, y - e) to (x, y + e) per (x, y, e).
pub fn error_bars(
    points: impl IntoIterator<Item = (f64, f64, f64)>,
    color: RGBColor,
) -> Vec<Series> {
    points
        .into_iter()
        .map(|(x, y, e)| Series::new("", vec![(x, y - e), (x, y + e)], color, Style::Line))
        .collect()
}

/// A palette that reads well in print and for colour-blind readers (Okabe-Ito).
pub const PALETTE: [RGBColor; 8] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(230, 159, 0),
    RGBColor(86, 180, 233),
    RGBColor(0, 0, 0),
    RGBColor(240, 228, 66),
];

/// Where the legend goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LegendPos {
    /// Upper right corner.
    UpperRight,
    /// Upper left corner.
    UpperLeft,
    /// Lower right corner.
    LowerRight,
    /// Lower left corner.
    LowerLeft,
}

impl LegendPos {
    fn to_plotters(self) -> SeriesLabelPosition {
        match self {
            LegendPos::UpperRight => SeriesLabelPosition::UpperRight,
            LegendPos::UpperLeft => SeriesLabelPosition::UpperLeft,
            LegendPos::LowerRight => SeriesLabelPosition::LowerRight,
            LegendPos::LowerLeft => SeriesLabelPosition::LowerLeft,
        }
    }
}

/// A single-panel x-y plot with optional log axes.
#[derive(Debug, Clone)]
pub struct LinePlot {
    /// Title (top).
    pub title: String,
    /// x-axis label with unit.
    pub x_label: String,
    /// y-axis label with unit.
    pub y_label: String,
    /// x range.
    pub x_range: (f64, f64),
    /// y range.
    pub y_range: (f64, f64),
    /// Logarithmic x axis.
    pub log_x: bool,
    /// Logarithmic y axis.
    pub log_y: bool,
    /// The curves.
    pub series: Vec<Series>,
    /// Legend position.
    pub legend: LegendPos,
    /// Size in pixels.
    pub size: (u32, u32),
}

impl LinePlot {
    /// A linear-axes plot; ranges are fitted to the data with a margin.
    pub fn new(title: &str, x_label: &str, y_label: &str, series: Vec<Series>) -> Self {
        let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for s in &series {
            for &(x, y) in &s.points {
                if x.is_finite() && y.is_finite() {
                    x0 = x0.min(x);
                    x1 = x1.max(x);
                    y0 = y0.min(y);
                    y1 = y1.max(y);
                }
            }
        }
        if x0 > x1 {
            (x0, x1, y0, y1) = (0.0, 1.0, 0.0, 1.0);
        }
        let dy = (y1 - y0).max(1e-300);
        Self {
            title: title.to_string(),
            x_label: x_label.to_string(),
            y_label: y_label.to_string(),
            x_range: (x0, x1),
            y_range: (y0.min(0.0).max(y0 - 0.05 * dy), y1 + 0.08 * dy),
            log_x: false,
            log_y: false,
            series,
            legend: LegendPos::UpperRight,
            size: (960, 640),
        }
    }

    /// Sets the x range.
    pub fn x(mut self, lo: f64, hi: f64) -> Self {
        self.x_range = (lo, hi);
        self
    }

    /// Sets the y range.
    pub fn y(mut self, lo: f64, hi: f64) -> Self {
        self.y_range = (lo, hi);
        self
    }

    /// Log axes.
    pub fn log(mut self, log_x: bool, log_y: bool) -> Self {
        self.log_x = log_x;
        self.log_y = log_y;
        self
    }

    /// Legend position.
    pub fn legend(mut self, pos: LegendPos) -> Self {
        self.legend = pos;
        self
    }
}

/// Tick label on a linear axis: the shortest decimal that reads back to the tick rounded to 10
/// significant digits (`900`, `0.3`, `-2.5`), or `2.5e-7` outside 1e-3..1e6.
fn linear_tick_label(v: &f64) -> String {
    let v = *v;
    if v == 0.0 || !v.is_finite() {
        return if v == 0.0 { "0".into() } else { format!("{v}") };
    }
    let rounded: f64 = format!("{v:.9e}").parse().unwrap_or(v);
    let a = rounded.abs();
    if (1e-3..1e6).contains(&a) {
        format!("{rounded}")
    } else {
        let e = a.log10().floor() as i32;
        let m: f64 = format!("{:.9e}", rounded / 10f64.powi(e))
            .parse()
            .unwrap_or(rounded);
        format!("{m}e{e}")
    }
}

/// Tick label on a logarithmic axis: `1e-5`, `2e-5`, or plain decimals between 0.01 and 1000.
fn log_tick_label(v: &f64) -> String {
    let v = *v;
    if !(v.is_finite() && v > 0.0) {
        return format!("{v}");
    }
    let mut e = v.log10().floor() as i32;
    let mut m = (v / 10f64.powi(e) * 100.0).round() / 100.0;
    if m >= 10.0 {
        m /= 10.0;
        e += 1;
    }
    if (-2..=3).contains(&e) {
        let x = m * 10f64.powi(e);
        let decimals = (-e).max(0) as usize + usize::from(m.fract() != 0.0);
        format!("{x:.decimals$}")
    } else {
        format!("{m}e{e}")
    }
}

macro_rules! draw_chart {
    ($self:ident, $root:ident, $xr:expr, $yr:expr) => {{
        let mut chart = ChartBuilder::on($root)
            .caption(&$self.title, ("sans-serif", 22))
            .margin(18)
            .x_label_area_size(48)
            .y_label_area_size(84)
            .build_cartesian_2d($xr, $yr)
            .map_err(|e| anyhow!("chart: {e}"))?;
        let mut mesh = chart.configure_mesh();
        mesh.x_desc(&$self.x_label)
            .y_desc(&$self.y_label)
            .label_style(("sans-serif", 15))
            .axis_desc_style(("sans-serif", 17))
            .light_line_style(RGBColor(235, 235, 235))
            .bold_line_style(RGBColor(210, 210, 210));
        // Log axes: tick labels such as 1e-5 instead of plotters' 9.999999999e-6; linear
        // axes: 900 instead of 900.0.
        if $self.log_x {
            mesh.x_label_formatter(&log_tick_label);
        } else {
            mesh.x_label_formatter(&linear_tick_label);
        }
        if $self.log_y {
            mesh.y_label_formatter(&log_tick_label);
        } else {
            mesh.y_label_formatter(&linear_tick_label);
        }
        mesh.draw().map_err(|e| anyhow!("mesh: {e}"))?;
        let mut any_label = false;
        for s in &$self.series {
            let color = s.color;
            let pts: Vec<(f64, f64)> = s
                .points
                .iter()
                .copied()
                .filter(|&(x, y)| {
                    x.is_finite()
                        && y.is_finite()
                        && (!$self.log_x || x > 0.0)
                        && (!$self.log_y || y > 0.0)
                })
                .collect();
            let line = ShapeStyle::from(&color).stroke_width(2);
            let anno = match s.style {
                Style::Line => {
                    // A solid line of more points than its pixel columns can show is drawn
                    // through the extremes of each column (see `decimate`).
                    let width = chart.plotting_area().dim_in_pixel().0 as usize;
                    let drawn = if pts.len() > DENSE_POINTS_PER_COLUMN * width {
                        min_max_per_column(&pts, |p| chart.backend_coord(&p).0)
                    } else {
                        pts.clone()
                    };
                    chart
                        .draw_series(LineSeries::new(drawn, line))
                        .map_err(|e| anyhow!("series: {e}"))?
                }
                Style::Dashed => chart
                    .draw_series(DashedLineSeries::new(pts.clone(), 8, 5, line))
                    .map_err(|e| anyhow!("series: {e}"))?,
                Style::Points => chart
                    .draw_series(
                        pts.iter()
                            .map(|&p| Cross::new(p, POINT_RADIUS, color.stroke_width(3))),
                    )
                    .map_err(|e| anyhow!("series: {e}"))?,
                Style::LinePoints => {
                    chart
                        .draw_series(LineSeries::new(pts.clone(), line))
                        .map_err(|e| anyhow!("series: {e}"))?;
                    chart
                        .draw_series(
                            pts.iter()
                                .map(|&p| Circle::new(p, LINE_POINT_RADIUS, color.filled())),
                        )
                        .map_err(|e| anyhow!("series: {e}"))?
                }
                Style::Dots => chart
                    .draw_series(
                        pts.iter()
                            .map(|&p| Circle::new(p, DOT_RADIUS, color.filled())),
                    )
                    .map_err(|e| anyhow!("series: {e}"))?,
                Style::Triangles => chart
                    .draw_series(
                        pts.iter()
                            .map(|&p| TriangleMarker::new(p, MARK_SIZE, color.filled())),
                    )
                    .map_err(|e| anyhow!("series: {e}"))?,
                Style::Circles => chart
                    .draw_series(
                        pts.iter()
                            .map(|&p| Circle::new(p, MARK_SIZE, color.stroke_width(2))),
                    )
                    .map_err(|e| anyhow!("series: {e}"))?,
            };
            if !s.label.is_empty() {
                any_label = true;
                // The legend glyph is drawn as the series is: a marker alone, a dashed or a
                // solid segment, or a segment with a marker.
                let seg = color.stroke_width(3);
                let anno = anno.label(s.label.clone());
                match s.style {
                    Style::Line => {
                        anno.legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 22, y)], seg));
                    }
                    Style::Dashed => {
                        anno.legend(move |(x, y)| {
                            EmptyElement::at((x, y))
                                + PathElement::new(vec![(0, 0), (8, 0)], seg)
                                + PathElement::new(vec![(14, 0), (22, 0)], seg)
                        });
                    }
                    Style::Points => {
                        anno.legend(move |(x, y)| {
                            Cross::new((x + 11, y), POINT_RADIUS, color.stroke_width(3))
                        });
                    }
                    Style::LinePoints => {
                        anno.legend(move |(x, y)| {
                            EmptyElement::at((x, y))
                                + PathElement::new(vec![(0, 0), (22, 0)], seg)
                                + Circle::new((11, 0), LINE_POINT_RADIUS + 1, color.filled())
                        });
                    }
                    Style::Dots => {
                        anno.legend(move |(x, y)| {
                            Circle::new((x + 11, y), DOT_RADIUS + 1, color.filled())
                        });
                    }
                    Style::Triangles => {
                        anno.legend(move |(x, y)| {
                            TriangleMarker::new((x + 11, y), MARK_SIZE, color.filled())
                        });
                    }
                    Style::Circles => {
                        anno.legend(move |(x, y)| {
                            Circle::new((x + 11, y), MARK_SIZE, color.stroke_width(2))
                        });
                    }
                }
            }
        }
        if any_label {
            chart
                .configure_series_labels()
                .position($self.legend.to_plotters())
                .label_font(("sans-serif", 15))
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .draw()
                .map_err(|e| anyhow!("legend: {e}"))?;
        }
    }};
}

impl Chart for LinePlot {
    fn size(&self) -> (u32, u32) {
        self.size
    }

    fn title(&self) -> String {
        self.title.clone()
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        root.fill(&WHITE).map_err(|e| anyhow!("fill: {e}"))?;
        let (x0, x1) = self.x_range;
        let (y0, y1) = self.y_range;
        match (self.log_x, self.log_y) {
            (false, false) => draw_chart!(self, root, x0..x1, y0..y1),
            (true, false) => draw_chart!(self, root, (x0..x1).log_scale(), y0..y1),
            (false, true) => draw_chart!(self, root, x0..x1, (y0..y1).log_scale()),
            (true, true) => draw_chart!(self, root, (x0..x1).log_scale(), (y0..y1).log_scale()),
        }
        Ok(())
    }
}

/// How [`Panels`] are laid out.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Arrangement {
    /// Top to bottom, each with its own axes and legend (one curve against two coordinates
    /// that share the x axis); the figure's title is the first panel's.
    Stacked,
    /// Left to right (e.g. a response spectrum beside its drive's); the figure's title joins
    /// the panels' titles.
    SideBySide,
}

/// Several plots in one figure, each with its own axes and legend.
#[derive(Debug, Clone)]
pub struct Panels {
    /// The panels, top first or left first.
    pub plots: Vec<LinePlot>,
    /// Size in pixels.
    pub size: (u32, u32),
    /// Their layout.
    pub arrangement: Arrangement,
}

impl Panels {
    /// Panels stacked at the usual width, each as tall as two thirds of a single plot.
    pub fn new(plots: Vec<LinePlot>) -> Self {
        let height = 430 * plots.len().max(1) as u32;
        Self {
            plots,
            size: (960, height),
            arrangement: Arrangement::Stacked,
        }
    }

    /// Panels in a row, each about as large as a single plot's width share.
    pub fn row(plots: Vec<LinePlot>) -> Self {
        let n = plots.len().max(1) as u32;
        Self {
            plots,
            size: (720 * n, 600),
            arrangement: Arrangement::SideBySide,
        }
    }
}

impl Chart for Panels {
    fn size(&self) -> (u32, u32) {
        self.size
    }

    fn title(&self) -> String {
        match self.arrangement {
            Arrangement::Stacked => self
                .plots
                .first()
                .map(|p| p.title.clone())
                .unwrap_or_default(),
            Arrangement::SideBySide => self
                .plots
                .iter()
                .map(|p| p.title.as_str())
                .collect::<Vec<_>>()
                .join("; "),
        }
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        let n = self.plots.len().max(1);
        let grid = match self.arrangement {
            Arrangement::Stacked => (n, 1),
            Arrangement::SideBySide => (1, n),
        };
        for (p, area) in self.plots.iter().zip(&root.split_evenly(grid)) {
            p.draw(area)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_tick_labels_have_no_trailing_zeros_or_float_noise() {
        assert_eq!(linear_tick_label(&900.0), "900");
        assert_eq!(linear_tick_label(&1000.0), "1000");
        assert_eq!(linear_tick_label(&0.0), "0");
        assert_eq!(linear_tick_label(&(0.1 + 0.2)), "0.3");
        assert_eq!(linear_tick_label(&-2.5), "-2.5");
        assert_eq!(linear_tick_label(&2.5e-7), "2.5e-7");
        assert_eq!(linear_tick_label(&1e6), "1e6");
    }
}
