//! Line plots side by side in one figure (the `endstop random` tool's response and drive
//! spectra), each panel drawn as a [`LinePlot`] of its own.

use anyhow::Result;
use plotters::coord::Shift;
use plotters::prelude::*;

use crate::plot::{Figure, LinePlot};

/// Panels in a row, left to right; the figure's title is the first panel's.
#[derive(Debug, Clone)]
pub struct Panels {
    /// The panels.
    pub panels: Vec<LinePlot>,
    /// Size of the whole figure in pixels.
    pub size: (u32, u32),
}

impl Panels {
    /// Panels in a row, each about as large as a single plot's width share.
    pub fn row(panels: Vec<LinePlot>) -> Self {
        let n = panels.len().max(1) as u32;
        Self {
            panels,
            size: (720 * n, 600),
        }
    }
}

impl Figure for Panels {
    fn size(&self) -> (u32, u32) {
        self.size
    }

    fn title(&self) -> String {
        self.panels
            .iter()
            .map(|p| p.title.as_str())
            .collect::<Vec<_>>()
            .join("; ")
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        let areas = root.split_evenly((1, self.panels.len().max(1)));
        for (panel, area) in self.panels.iter().zip(&areas) {
            panel.draw(area)?;
        }
        Ok(())
    }
}
