//! The basin map shared by the response experiment and `endstop basins`: every cell of the
//! grid drawn at its initial state in its attractor's colour, with each attractor's share in
//! the legend, and the attractors' own states at drive phase zero marked.

use endstop::study::basins::Basins;

use crate::io::legend::placed_clear;
use crate::io::plot::{LegendPos, LinePlot, Series, Style, PALETTE};

/// The basin map of `b` titled `title` (x in um, v in mm/s); `marks` are (label, x, v) of the
/// attractors at drive phase zero (none to mark nothing).
pub fn basin_map(title: &str, b: &Basins, marks: &[(String, f64, f64)]) -> LinePlot {
    let shares = b.shares();
    let mut series: Vec<Series> = shares
        .iter()
        .enumerate()
        .filter(|(_, (_, s))| *s > 0.0)
        .map(|(k, (label, share))| {
            let pts = b
                .cells
                .iter()
                .enumerate()
                .filter(|(i, _)| b.label(*i) == label)
                .map(|(_, &(x, v))| (x * 1e6, v * 1e3))
                .collect();
            Series::new(
                &format!("{label} ({:.1} %)", 100.0 * share),
                pts,
                PALETTE[(k + 1) % PALETTE.len()],
                Style::Points,
            )
        })
        .collect();
    if !marks.is_empty() {
        series.push(Series::new(
            "attractors at drive phase 0",
            marks.iter().map(|(_, x, v)| (x * 1e6, v * 1e3)).collect(),
            PALETTE[0],
            Style::Circles,
        ));
    }
    // The grid fills the plot: the legend goes into room made above it.
    placed_clear(
        LinePlot::new(title, "Initial x [um]", "Initial v [mm/s]", series)
            .legend(LegendPos::UpperRight),
    )
}
