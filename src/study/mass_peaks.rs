//! Each mass's largest displacement and speed over a run: the per-mass measures of a device of
//! several masses ([`crate::device::masses`]), beside the first mass's `x_peak_m` that every
//! study reports.
//!
//! The masses are the model's ([`Layout::masses`]: the indices of each mass's position and
//! velocity), in the layout's order; their column names come from the layout's components
//! (`x_driver` gives `x_driver_peak_m`, `v_driver` gives `v_driver_peak_m_per_s`), so a column
//! names its mass as the device file does. A one-mass model has one mass and the studies add no
//! column for it (its `x_peak_m` is the output contract's).

use crate::model::Layout;

/// Most masses measured (the device file's bound).
pub const MAX_MEASURED: usize = crate::device::masses::MAX_MASSES;

/// The largest |x| (m) and |v| (m/s) of each mass seen so far.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MassPeaks {
    /// How many masses are measured (the first `len` entries).
    pub len: usize,
    /// Largest |x| of each mass (m).
    pub x_m: [f64; MAX_MEASURED],
    /// Largest |v| of each mass (m/s).
    pub v_m_per_s: [f64; MAX_MEASURED],
}

impl Default for MassPeaks {
    fn default() -> Self {
        Self::none()
    }
}

impl MassPeaks {
    /// Nothing seen, for no mass.
    pub fn none() -> Self {
        Self {
            len: 0,
            x_m: [0.0; MAX_MEASURED],
            v_m_per_s: [0.0; MAX_MEASURED],
        }
    }

    /// Nothing seen yet, for the masses of `layout` (at most [`MAX_MEASURED`]); for a model
    /// of one mass, for none (the study's `x_peak_m` is its measure, and it costs nothing).
    pub fn of(layout: &Layout) -> Self {
        let n = layout.masses.len();
        Self {
            len: if n < 2 { 0 } else { n.min(MAX_MEASURED) },
            ..Self::none()
        }
    }

    /// Takes the state `y` (laid out as `layout`) into the peaks.
    #[inline(always)]
    pub fn see(&mut self, layout: &Layout, y: &[f64]) {
        for (i, &(ix, iv)) in layout.masses.iter().take(self.len).enumerate() {
            self.x_m[i] = self.x_m[i].max(y[ix].abs());
            self.v_m_per_s[i] = self.v_m_per_s[i].max(y[iv].abs());
        }
    }

    /// The larger of each peak of `self` and `other` (two runs of one model).
    #[must_use]
    pub fn max(mut self, other: &Self) -> Self {
        self.len = self.len.max(other.len);
        for i in 0..self.len {
            self.x_m[i] = self.x_m[i].max(other.x_m[i]);
            self.v_m_per_s[i] = self.v_m_per_s[i].max(other.v_m_per_s[i]);
        }
        self
    }

    /// The peaks' column names for the masses of `layout`: for each mass its displacement's
    /// (`<x component>_peak_m`) then its velocity's (`<v component>_peak_m_per_s`); none for a
    /// model of one mass (see the module docs). [`MassPeaks::values`] are in this order.
    pub fn column_names(layout: &Layout) -> Vec<String> {
        if layout.masses.len() < 2 {
            return Vec::new();
        }
        let name = |ix: usize| layout.components[ix].name.as_str();
        layout
            .masses
            .iter()
            .take(MAX_MEASURED)
            .flat_map(|&(ix, iv)| {
                [
                    format!("{}_peak_m", name(ix)),
                    format!("{}_peak_m_per_s", name(iv)),
                ]
            })
            .collect()
    }

    /// The peaks in the order of [`MassPeaks::column_names`]: each mass's |x| then |v|.
    pub fn values(&self) -> Vec<f64> {
        (0..self.len)
            .flat_map(|i| [self.x_m[i], self.v_m_per_s[i]])
            .collect()
    }
}
